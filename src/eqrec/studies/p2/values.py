"""P2 values: our value of every P2 claim with the evidence behind it (step ``values``).

Numbers, statuses and words only; ``config/claims.yaml`` words them, each
explanation tied to a condition on this evidence.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from eqrec.studies.pipeline.outputs import write_json
from eqrec.studies.p2.grids import constant_interval


#: Classes of a sweep point; every point has exactly one (the counts add up to the grid size).
CLASSES = ("optimal", "infeasible", "solver_failed", "placement_failed")


def class_counts(g: pd.DataFrame) -> dict:
    """Points per class, how many the second solver decided and how many got a nilpotent ``L``.

    Raises if a status is outside :data:`CLASSES` (the counts must add up to the grid size).
    """
    unknown = sorted(set(g["status"]) - set(CLASSES))
    if unknown:
        raise ValueError(f"sweep points with statuses {unknown} outside {CLASSES}")
    out = {c: int((g["status"] == c).sum()) for c in CLASSES}
    out["points"] = int(len(g))
    second = (g["status_second"].map(lambda x: x if isinstance(x, str) else "") if "status_second" in g
              else pd.Series([""] * len(g), index=g.index))
    out["second_solver_decided"] = int(((second != "") & g["status"].isin(["optimal", "infeasible"])).sum())
    out["second_solver_tried"] = int((second != "").sum())
    out["deadbeat"] = int((g["observer"] == "deadbeat").sum()) if "observer" in g else 0
    return out


def _mu2_range(g: pd.DataFrame, tol: float) -> dict:
    ok = g[g["status"] == "optimal"]
    mu = ok["mu2"].to_numpy(float)
    out = {"word": str(g["word"].iloc[0]), "min": float(mu.min()) if len(mu) else None,
           "max": float(mu.max()) if len(mu) else None, **class_counts(g)}
    if len(mu):
        at_min = ok[mu <= mu.min() + tol]  # ties at the minimum counted with the tolerance, not by last digits
        out["at_min"] = int(len(at_min))
        out["at_min_r_max"] = float(at_min["r"].max()) if "r" in at_min else None
        if "certified_mu2" in ok:
            cm = ok["certified_mu2"].to_numpy(float)
            out["certified_min"] = float(np.nanmin(cm))
            out["certified_max"] = float(np.nanmax(cm))
            out["certified_at_min"] = [float(np.nanmin(at_min["certified_mu2"])),
                                       float(np.nanmax(at_min["certified_mu2"]))]
            out["certified_terminal_min"] = float(np.nanmin(ok["certified_terminal"].to_numpy(float)))
    return out


def _rel(a: float, b: float) -> float:
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def _solver_spread(per_solver: dict) -> float:
    """Relative spread over the solvers of the ``upper`` bound of
    :func:`eqrec.studies.p2.guarantee.best_guarantee_among_optima` (one result per solver)."""
    values = [e["upper"] for e in per_solver.values()]
    return _rel(max(values), min(values))


def among_optima_summary(ao: dict, solver: str, mu1: float, rtol: float = 1e-6) -> dict:
    """The best guarantee among the masked_gain optima (``printed.json``), per runtime, with its checks.

    ``value`` is the ``"hold"`` runtime's (constant ``L`` kept at missing steps) from ``solver``;
    ``agree``: every runtime exact (lower = upper) with every solver, solvers within ``rtol``
    relative, certify() of the LP's own gains within ``rtol`` of the LP value, and those gains
    optimal for the design LP (design worst case at most the optimum bound, ``M1`` at the end).
    ``agree_until``: the last time at which the two runtimes' errors coincide for every gain.
    """
    runtimes = {}
    ok = True
    for rt, per in ao["runtimes"].items():
        spread = _solver_spread(per)
        cert_diff = max(_rel(e["certified"]["mu2"], e["upper"]) for e in per.values())
        design_ok = all(e["design_check"]["mu2"] <= e["optimum_bound"] * (1 + rtol)
                        and e["design_check"]["terminal"] <= mu1 * (1 + rtol) for e in per.values())
        exact = all(e["exact"] for e in per.values())
        runtimes[rt] = {"value": per[solver]["upper"], "by_solver": {k: e["upper"] for k, e in per.items()},
                        "lower": {k: e["lower"] for k, e in per.items()}, "solver_spread": spread,
                        "certify_difference": cert_diff, "design_optimal": design_ok, "exact": exact,
                        "worst_time": per[solver]["certified"]["worst_time"],
                        "terminal": per[solver]["certified"]["terminal"]}
        ok = ok and exact and design_ok and spread <= rtol and cert_diff <= rtol
    term, rec = ao["terminal_theorem2"], ao["recover_theorem2"]
    return {"value": runtimes["hold"]["value"], "runtimes": runtimes, "agree": bool(ok),
            "agree_until": next(iter(ao["runtimes"]["hold"].values()))["agree_until"], "rel_tol": ao["rel_tol"], "abs_tol": ao["abs_tol"],
            "terminal_theorem2": {"value": term[solver]["upper"], "solver_spread": _solver_spread(term),
                                  "exact": all(e["exact"] for e in term.values())},
            "recover_theorem2": {"value": rec[solver]["upper"], "solver_spread": _solver_spread(rec),
                                 "terminal": rec[solver]["certified"]["terminal"]}}


def step_values(cfg, inputs, outputs, wildcards) -> dict:
    """``values.json``: ``{key: {"value": v, "evidence": {...}}}`` for every P2 claim."""
    tol = float(cfg["mu2_tol"])
    d = json.loads(Path(inputs.designs).read_text())
    sim = np.load(inputs.simulation)
    hm = pd.read_csv(inputs.heatmap)
    ra = pd.read_csv(inputs.realaxis)
    ck = json.loads(Path(inputs.checks).read_text())
    pr = json.loads(Path(inputs.printed).read_text())
    among = among_optima_summary(pr["masked_gain"]["among_optima"], pr["masked_gain"]["solver"],
                                 float(cfg["mu1"]))
    masked = {"mu2": pr["masked_gain"]["mu2"], "hold": pr["masked_gain"]["certified_hold"]["mu2"],
              "best": among["value"], "best_agree": among["agree"]}
    f1, f2 = d["f1"], d["f2"]
    a1, a2 = f1["augmented_free"], f2["augmented_free"]
    ob, leak = f2["one_based"], f2["leak"]
    wc = f2["worst_case_word"]
    v: dict[str, Any] = {}

    # heat map (P2-F3a), needed as evidence by the F1/F2 rows too
    main = hm[hm["variant"] == "theorem2"]
    mu = main[main["status"] == "optimal"]["mu2"].to_numpy(float)
    spread = float(np.ptp(mu))
    s0 = ck["s0"]

    v["f1_mu2_augmented"] = {"value": a1["certified_mu2"], "evidence": {
        "init_poles": cfg["init_poles"], "ipopt_status": a1["ipopt_status"], "iterations": a1["iterations"],
        "time_mu2": f1["time"]["certified_mu2"]}}
    v["f1_mu2_time"] = {"value": f1["time"]["certified_mu2"], "evidence": {"solver": "highs"}}
    v["f1_L"] = {"value": a1["L"], "evidence": {"eig": a1["eig_A_minus_LC"], "heatmap_spread": spread,
                                                 "mu2_tol": tol}}
    v["f1_s0"] = {"value": a1["s0"], "evidence": {"s0_mu2_spread": s0["mu2_spread"], "mu2_tol": tol}}
    v["f1_strictly_causal_mu2"] = {"value": f1["strictly_causal_mu2"], "evidence": {}}
    v["f1_process_noise_identity_mu2"] = {"value": f1["process_noise_identity_mu2"], "evidence": {}}

    one_based = {"word": ob["word"], "missing": [i for i, c in enumerate(ob["word"]) if c == "0"],
                 "augmented_mu2": ob["augmented_free"]["certified_mu2"], "time_mu2": ob["time_mu2"],
                 "on_true_word": ob["certified_on_true_words"][wc]}
    leak_ev = {k: ({"design_mu2": e["design_mu2"], "certified_mu2": e["certified_mu2"]} if "design_mu2" in e
                   else {"status": e["status"]}) for k, e in leak.items()}
    v["f2_mu2_augmented"] = {"value": a2["certified_mu2"], "evidence": {
        "time_mu2": f2["time"]["certified_mu2"], "worst_case_word": wc, "one_based": one_based, "leak": leak_ev,
        "masked_gain": masked, "mu2_tol": tol}}
    v["f2_mu2_time"] = {"value": f2["time"]["certified_mu2"], "evidence": {"solver": "highs"}}
    v["f2_mu2_one_based_augmented"] = {"value": one_based["augmented_mu2"], "evidence": {}}
    v["f2_mu2_one_based_time"] = {"value": one_based["time_mu2"], "evidence": {}}
    t2, aug2 = f2["time"]["certified_mu2"], a2["certified_mu2"]
    rel = "larger" if t2 > aug2 + tol else "equal" if abs(t2 - aug2) <= 1e-5 else "smaller"
    v["f2_time_vs_augmented"] = {"value": rel, "evidence": {
        "time_mu2": t2, "augmented_mu2": aug2, "worst_case_word": wc, "one_based": one_based,
        "masked_gain": masked, "mu2_tol": tol}}
    v["f2_L"] = {"value": a2["L"], "evidence": {"eig": a2["eig_A_minus_LC"], "heatmap_spread": spread,
                                                 "mu2_tol": tol}}

    variants = {var: _mu2_range(g, tol) for var, g in hm.groupby("variant")}  # class_counts: the classes add up
    grid = int(cfg["heatmap"]["n_r"]) * int(cfg["heatmap"]["n_theta"])
    v["f3a_mu2_region"] = {"value": float(np.min(mu)), "evidence": {
        "points": grid, "r_max": cfg["heatmap"]["r_max"], "spread": spread, "variants": variants,
        "time_mu2": t2, "worst_case_word": wc, "mu2_tol": tol}}
    v["f3a_mu2_spread"] = {"value": spread, "evidence": {}}
    v["f3a_placement_failures"] = {"value": variants["theorem2"]["placement_failed"], "evidence": {}}
    r0 = [r["masked_gain"] for r in pr["r0_deadbeat"] if isinstance(r.get("masked_gain"), float)]
    r0_ev = {"seeds": [r["seed"] for r in pr["r0_deadbeat"]], "min": float(min(r0)) if r0 else None,
             "max": float(max(r0)) if r0 else None}
    if "masked_gain" in variants:
        mgv = variants["masked_gain"]
        v["f3a_mu2_region_masked_gain"] = {"value": mgv["min"], "evidence": {
            **mgv, "r_max": cfg["heatmap"]["r_max"], "grid": grid, "time_mu2": t2, "r0_deadbeat": r0_ev,
            "mu2_tol": tol}}

    # Fig. 2 at the paper's printed L: the masked_gain reading, and its gains as the estimator that runs
    mgp, thp = pr["masked_gain"], pr["theorem2"]
    picks = {k: {"hold": b["certified_hold"]["mu2"], "hold_terminal": b["certified_hold"]["terminal"],
                 "theorem2_runtime": b["certified_theorem2"]["mu2"], "mu2": b["mu2"]}
             for k, b in mgp["by_solver"].items()}
    best = min(picks, key=lambda k: picks[k]["hold"])
    printed_ev = {"solver": mgp["solver"], "by_solver": picks, "best_solver": best, "word": pr["word"], "eig": pr["eig_A_minus_LC"], "theorem2_mu2": thp["mu2"], "time_mu2": t2,
                  "masked_gain_mu2": mgp["mu2"], "hold": mgp["certified_hold"]["mu2"],
                  "hold_terminal": mgp["certified_hold"]["terminal"],
                  "theorem2_runtime": mgp["certified_theorem2"]["mu2"],
                  "theorem2_runtime_terminal": mgp["certified_theorem2"]["terminal"], "words": pr["words"],
                  "M1": float(cfg["mu1"]), "mu2_tol": tol}
    v["f2_mu2_masked_gain"] = {"value": mgp["mu2"], "evidence": printed_ev}
    # the LP's optimal gains are not unique: the value is the best guarantee any of them gives as run (an LP over
    # the optima, solver-independent); the optima the solvers happen to return are secondary evidence
    v["f2_masked_gain_certified"] = {"value": among["value"], "evidence": {
        **printed_ev, "among_optima": among, "picks_max": max(b["hold"] for b in picks.values()), "heatmap": {k: variants["masked_gain"].get(k) for k in
                                  ("certified_min", "certified_max", "certified_at_min", "certified_terminal_min",
                                   "at_min", "optimal")} if "masked_gain" in variants else {}}}
    rel_mg = "larger" if t2 > mgp["mu2"] + tol else "equal" if abs(t2 - mgp["mu2"]) <= tol else "smaller"
    v["f2_time_vs_masked_gain"] = {"value": rel_mg, "evidence": printed_ev}

    # real axis (P2-F3b): the interval over place_poles points; lambda = 0 (nilpotent L) reported apart
    axis: dict[str, dict] = {}
    den = cfg["realaxis"]["grid_denominator"]
    for var, g in ra.groupby("variant"):
        g = g.sort_values("lam")
        lam_all = g["lam"].to_numpy(float)
        mu2 = np.where(g["status"] == "optimal", g["mu2"].to_numpy(float), np.nan)
        placed = (g["observer"] == "place_poles").to_numpy() & (g["status"] != "placement_failed").to_numpy()
        on_grid = placed & (np.abs(lam_all * den - np.round(lam_all * den)) < 1e-9) if den else placed
        zero = g[g["observer"] == "deadbeat"]
        axis[var] = {"interval": constant_interval(lam_all[placed], mu2[placed], tol),
                     "grid_interval": constant_interval(lam_all[on_grid], mu2[on_grid], tol),
                     "min_mu2": float(np.nanmin(mu2)), "counts": class_counts(g),
                     "at_zero": float(zero["mu2"].iloc[0]) if len(zero) and zero["status"].iloc[0] == "optimal"
                     else (str(zero["status"].iloc[0]) if len(zero) else None)}
    if "masked_gain" in axis:
        a = axis["masked_gain"]
        v["f3b_interval_masked_gain"] = {"value": a["grid_interval"], "evidence": {
            "grid_denominator": den, "min_mu2": a["min_mu2"], "at_zero": a["at_zero"], "r0_deadbeat": r0_ev}}
        v["f3b_interval_masked_gain_fine"] = {"value": a["interval"], "evidence": {
            "placed": int(a["counts"]["points"] - a["counts"]["deadbeat"]), "grid_denominator": den,
            "min_mu2": a["min_mu2"], "step": 2 * float(cfg["realaxis"]["lam_max"]) / (int(cfg["realaxis"]["n"]) - 1),
            "grid_interval": a["grid_interval"]}}
    g = ra[ra["variant"] == "theorem2"]
    okg = g[g["status"] == "optimal"]
    ra_spread = float(np.ptp(okg["mu2"]))
    whole = [float(g["lam"].min()), float(g["lam"].max())] if (ra_spread <= tol and len(okg) == len(g)) \
        else axis["theorem2"]["interval"]
    v["f3b_interval"] = {"value": whole, "evidence": {
        "n": int(len(g)), "min_mu2": float(okg["mu2"].min()), "spread": ra_spread, "variants": axis,
        "all_solved": bool(len(okg) == len(g)), "mu2_tol": tol,
        "masked_gain_interval": axis.get("masked_gain", {}).get("grid_interval")}}

    # P2-S0
    v["s0_mu2_unchanged"] = {"value": "unchanged" if s0["mu2_spread"] <= tol else "changed", "evidence": {
        "s0": [r["s0"] for r in s0["rows"]], "mu2": [r["mu2"] for r in s0["rows"]],
        "mu2_s0_zero": s0["mu2_s0_zero"], "spread": s0["mu2_spread"], "mu2_tol": tol}}
    exact = max(r["mapped_solution_F_difference"] for r in s0["rows"])
    v["s0_error_unchanged"] = {"value": "unchanged" if exact <= 1e-9 else "changed", "evidence": {
        "mapped_difference": exact,
        "solver_pick_difference": max(r["max_error_difference_solver_pick"] for r in s0["rows"])}}
    # P2-SOLVER
    sv = ck["solver"]
    keep = ("mu2", "certified_mu2", "max_abs_error", "rms_error", "M_difference_to_first", "F_difference_to_first")
    solvers = {k: {f: r[f] for f in keep} for k, r in sv.items()}
    v["solver_mu2_same"] = {"value": "same" if np.ptp([r["mu2"] for r in sv.values()]) <= 1e-6 else "different",
                            "evidence": {"solvers": solvers}}
    max_dF = max(r["F_difference_to_first"] for r in sv.values())
    v["solver_gains_differ"] = {"value": "different" if max_dF > 1e-4 else "same",
                                "evidence": {"max_F_difference": max_dF, "reference": next(iter(sv))}}
    v["runtime_equivalence"] = {"value": float(max(sim["f1/runtime_max_diff"], sim["f2/runtime_max_diff"])),
                                "evidence": {"runs": 20}}
    write_json(outputs.json, v)
    return v
