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
    second = g.get("status_second", pd.Series("", index=g.index)).map(lambda x: x if isinstance(x, str) else "")
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
            cm, cm_at = ok["certified_mu2"].to_numpy(float), at_min["certified_mu2"]
            out.update(certified_min=float(np.nanmin(cm)), certified_max=float(np.nanmax(cm)),
                       certified_at_min=[float(np.nanmin(cm_at)), float(np.nanmax(cm_at))],
                       certified_terminal_min=float(np.nanmin(ok["certified_terminal"].to_numpy(float))))
    return out


def _rel(a: float, b: float) -> float:
    return abs(a - b) / max(abs(a), abs(b), 1e-300)


def _solver_spread(per_solver: dict) -> float:
    """Relative spread over the solvers of the ``upper`` bound of
    :func:`eqrec.design.augmented.guarantee.best_guarantee_among_optima` (one result per solver)."""
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
    for rt, per in ao["runtimes"].items():
        picked = per[solver]["certified"]
        runtimes[rt] = {"value": per[solver]["upper"], "by_solver": {k: e["upper"] for k, e in per.items()},
                        "lower": {k: e["lower"] for k, e in per.items()}, "solver_spread": _solver_spread(per),
                        "certify_difference": max(_rel(e["certified"]["mu2"], e["upper"]) for e in per.values()),
                        "design_optimal": all(e["design_check"]["mu2"] <= e["optimum_bound"] * (1 + rtol)
                                              and e["design_check"]["terminal"] <= mu1 * (1 + rtol)
                                              for e in per.values()),
                        "exact": all(e["exact"] for e in per.values()),
                        "worst_time": picked["worst_time"], "terminal": picked["terminal"]}
    ok = all(r["exact"] and r["design_optimal"] and r["solver_spread"] <= rtol and r["certify_difference"] <= rtol
             for r in runtimes.values())
    term, rec = ao["terminal_theorem2"], ao["recover_theorem2"]
    return {"value": runtimes["hold"]["value"], "runtimes": runtimes, "agree": ok,
            "agree_until": next(iter(ao["runtimes"]["hold"].values()))["agree_until"], "rel_tol": ao["rel_tol"],
            "abs_tol": ao["abs_tol"],
            "terminal_theorem2": {"value": term[solver]["upper"], "solver_spread": _solver_spread(term),
                                  "exact": all(e["exact"] for e in term.values())},
            "recover_theorem2": {"value": rec[solver]["upper"], "solver_spread": _solver_spread(rec),
                                 "terminal": rec[solver]["certified"]["terminal"]}}


def _relation(a: float, b: float, tol: float, equal_tol: float) -> str:
    """``"larger"`` when ``a`` exceeds ``b`` by more than ``tol``, ``"equal"`` within ``equal_tol``, else smaller."""
    return "larger" if a > b + tol else "equal" if abs(a - b) <= equal_tol else "smaller"


def step_values(cfg, inputs, outputs, wildcards) -> dict:
    """``values.json``: ``{key: {"value": v, "evidence": {...}}}`` for every P2 claim."""
    tol = float(cfg["mu2_tol"])
    d, ck, pr = (json.loads(Path(p).read_text()) for p in (inputs.designs, inputs.checks, inputs.printed))
    sim = np.load(inputs.simulation)
    hm, ra = pd.read_csv(inputs.heatmap), pd.read_csv(inputs.realaxis)
    mgp = pr["masked_gain"]
    among = among_optima_summary(mgp["among_optima"], mgp["solver"], float(cfg["mu1"]))
    masked = {"mu2": mgp["mu2"], "hold": mgp["certified_hold"]["mu2"], "best": among["value"],
              "best_agree": among["agree"]}
    f1, f2 = d["f1"], d["f2"]
    a1, a2 = f1["augmented_free"], f2["augmented_free"]
    ob, wc = f2["one_based"], f2["worst_case_word"]
    t2, aug2 = f2["time"]["certified_mu2"], a2["certified_mu2"]
    v: dict[str, Any] = {}

    def put(key: str, value: Any, **evidence: Any) -> None:
        v[key] = {"value": value, "evidence": evidence}

    # heat map (P2-F3a), needed as evidence by the F1/F2 rows too
    main = hm[hm["variant"] == "theorem2"]
    mu = main[main["status"] == "optimal"]["mu2"].to_numpy(float)
    spread = float(np.ptp(mu))
    s0 = ck["s0"]

    put("f1_mu2_augmented", a1["certified_mu2"], init_poles=cfg["init_poles"], ipopt_status=a1["ipopt_status"],
        iterations=a1["iterations"], time_mu2=f1["time"]["certified_mu2"])
    put("f1_mu2_time", f1["time"]["certified_mu2"], solver="highs")
    put("f1_L", a1["L"], eig=a1["eig_A_minus_LC"], heatmap_spread=spread, mu2_tol=tol)
    put("f1_s0", a1["s0"], s0_mu2_spread=s0["mu2_spread"], mu2_tol=tol)
    put("f1_strictly_causal_mu2", f1["strictly_causal_mu2"])
    put("f1_process_noise_identity_mu2", f1["process_noise_identity_mu2"])

    one_based = {"word": ob["word"], "missing": [i for i, c in enumerate(ob["word"]) if c == "0"],
                 "augmented_mu2": ob["augmented_free"]["certified_mu2"], "time_mu2": ob["time_mu2"],
                 "on_true_word": ob["certified_on_true_words"][wc]}
    leak = {k: ({"design_mu2": e["design_mu2"], "certified_mu2": e["certified_mu2"]} if "design_mu2" in e
                else {"status": e["status"]}) for k, e in f2["leak"].items()}
    put("f2_mu2_augmented", aug2, time_mu2=t2, worst_case_word=wc, one_based=one_based, leak=leak, masked_gain=masked,
        mu2_tol=tol)
    put("f2_mu2_time", t2, solver="highs")
    put("f2_mu2_one_based_augmented", one_based["augmented_mu2"])
    put("f2_mu2_one_based_time", one_based["time_mu2"])
    put("f2_time_vs_augmented", _relation(t2, aug2, tol, 1e-5), time_mu2=t2, augmented_mu2=aug2, worst_case_word=wc,
        one_based=one_based, masked_gain=masked, mu2_tol=tol)
    put("f2_L", a2["L"], eig=a2["eig_A_minus_LC"], heatmap_spread=spread, mu2_tol=tol)

    variants = {var: _mu2_range(g, tol) for var, g in hm.groupby("variant")}  # class_counts: the classes add up
    grid = int(cfg["heatmap"]["n_r"]) * int(cfg["heatmap"]["n_theta"])
    r_max = cfg["heatmap"]["r_max"]
    put("f3a_mu2_region", float(np.min(mu)), points=grid, r_max=r_max, spread=spread, variants=variants, time_mu2=t2,
        worst_case_word=wc, mu2_tol=tol)
    put("f3a_mu2_spread", spread)
    put("f3a_placement_failures", variants["theorem2"]["placement_failed"])
    r0 = [r["masked_gain"] for r in pr["r0_deadbeat"] if isinstance(r.get("masked_gain"), float)]
    r0_ev = {"seeds": [r["seed"] for r in pr["r0_deadbeat"]], "min": float(min(r0)) if r0 else None,
             "max": float(max(r0)) if r0 else None}
    mgv = variants.get("masked_gain")
    if mgv:
        put("f3a_mu2_region_masked_gain", mgv["min"], **mgv, r_max=r_max, grid=grid, time_mu2=t2, r0_deadbeat=r0_ev,
            mu2_tol=tol)

    # Fig. 2 at the paper's printed L: the masked_gain reading, and its gains as the estimator that runs
    picks = {k: {"hold": b["certified_hold"]["mu2"], "hold_terminal": b["certified_hold"]["terminal"],
                 "theorem2_runtime": b["certified_theorem2"]["mu2"], "mu2": b["mu2"]}
             for k, b in mgp["by_solver"].items()}
    best = min(picks, key=lambda k: picks[k]["hold"])
    hold, th2 = mgp["certified_hold"], mgp["certified_theorem2"]
    printed_ev = {"solver": mgp["solver"], "by_solver": picks, "best_solver": best, "word": pr["word"],
                  "eig": pr["eig_A_minus_LC"], "theorem2_mu2": pr["theorem2"]["mu2"], "time_mu2": t2,
                  "masked_gain_mu2": mgp["mu2"], "hold": hold["mu2"], "hold_terminal": hold["terminal"],
                  "theorem2_runtime": th2["mu2"], "theorem2_runtime_terminal": th2["terminal"], "words": pr["words"],
                  "M1": float(cfg["mu1"]), "mu2_tol": tol}
    put("f2_mu2_masked_gain", mgp["mu2"], **printed_ev)
    # the LP's optimal gains are not unique: the value is the best guarantee any of them gives as run (an LP over
    # the optima, solver-independent); the optima the solvers happen to return are secondary evidence
    heat = ("certified_min", "certified_max", "certified_at_min", "certified_terminal_min", "at_min", "optimal")
    put("f2_masked_gain_certified", among["value"], **printed_ev, among_optima=among,
        picks_max=max(b["hold"] for b in picks.values()), heatmap={k: mgv.get(k) for k in heat} if mgv else {})
    put("f2_time_vs_masked_gain", _relation(t2, mgp["mu2"], tol, tol), **printed_ev)

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
                     "at_zero": (float(zero["mu2"].iloc[0]) if zero["status"].iloc[0] == "optimal"
                                 else str(zero["status"].iloc[0])) if len(zero) else None}
    if "masked_gain" in axis:
        a = axis["masked_gain"]
        put("f3b_interval_masked_gain", a["grid_interval"], grid_denominator=den, min_mu2=a["min_mu2"],
            at_zero=a["at_zero"], r0_deadbeat=r0_ev)
        put("f3b_interval_masked_gain_fine", a["interval"],
            placed=int(a["counts"]["points"] - a["counts"]["deadbeat"]), grid_denominator=den, min_mu2=a["min_mu2"],
            step=2 * float(cfg["realaxis"]["lam_max"]) / (int(cfg["realaxis"]["n"]) - 1),
            grid_interval=a["grid_interval"])
    g = ra[ra["variant"] == "theorem2"]
    okg = g[g["status"] == "optimal"]
    ra_spread = float(np.ptp(okg["mu2"]))
    all_solved = len(okg) == len(g)
    whole = [float(g["lam"].min()), float(g["lam"].max())] if ra_spread <= tol and all_solved \
        else axis["theorem2"]["interval"]
    put("f3b_interval", whole, n=int(len(g)), min_mu2=float(okg["mu2"].min()), spread=ra_spread, variants=axis,
        all_solved=bool(all_solved), mu2_tol=tol,
        masked_gain_interval=axis.get("masked_gain", {}).get("grid_interval"))

    # P2-S0
    rows = s0["rows"]
    put("s0_mu2_unchanged", "unchanged" if s0["mu2_spread"] <= tol else "changed", s0=[r["s0"] for r in rows],
        mu2=[r["mu2"] for r in rows], mu2_s0_zero=s0["mu2_s0_zero"], spread=s0["mu2_spread"], mu2_tol=tol)
    exact = max(r["mapped_solution_F_difference"] for r in rows)
    put("s0_error_unchanged", "unchanged" if exact <= 1e-9 else "changed", mapped_difference=exact,
        solver_pick_difference=max(r["max_error_difference_solver_pick"] for r in rows))
    # P2-SOLVER
    sv = ck["solver"]
    keep = ("mu2", "certified_mu2", "max_abs_error", "rms_error", "M_difference_to_first", "F_difference_to_first")
    put("solver_mu2_same", "same" if np.ptp([r["mu2"] for r in sv.values()]) <= 1e-6 else "different",
        solvers={k: {f: r[f] for f in keep} for k, r in sv.items()})
    max_dF = max(r["F_difference_to_first"] for r in sv.values())
    put("solver_gains_differ", "different" if max_dF > 1e-4 else "same", max_F_difference=max_dF,
        reference=next(iter(sv)))
    put("runtime_equivalence", float(max(sim["f1/runtime_max_diff"], sim["f2/runtime_max_diff"])), runs=20)
    write_json(outputs.json, v)
    return v
