"""P4 values: our value of every P4 claim with its evidence (``values.json``) and ``summary.csv``.

Step ``values`` of :mod:`eqrec.studies.p4.steps` reads the tracking run, the Monte
Carlo files of each example and the merged sweeps, and compares the two
compensation mechanisms (steady state and the ``Q_lambda`` threshold from
:mod:`eqrec.lmv.steady`).  Two variances within :data:`TIE_RTOL` count as a tie.
"""

from __future__ import annotations

from pathlib import Path
from typing import Sequence

import numpy as np
import pandas as pd

from eqrec.errors import InputError
from eqrec.lmv.model import MECHANISMS
from eqrec.lmv.plant import plant_of
from eqrec.lmv.steady import qlam_threshold, steady_variances
from eqrec.studies.pipeline.outputs import read_json, write_csv, write_json

#: Relative tolerance under which two variances count as equal (a tie, e.g. at eta_bar = 1 where no packet is
#: lost and both compensations are the same filter): counts must not depend on last-digit rounding.
TIE_RTOL = 1e-9

#: The verdicts of :func:`_ranking` the evidence counts, in its order.
RANKS = ("hold-input", "zero-input", "tie")

#: The rows of ``summary.csv``, in order: the key of ``values.json`` and the target of TARGETS.md it answers.
SUMMARY_TARGETS = {"ordering": "P4-F4", "eta_trend": "P4-F5", "q_trend": "P4-F6", "better_ex1": "P4-F7",
                   "better_ex2": "P4-F8", "theory_vs_mc": "P4-THEORY", "eq9_as_printed": "P4-THEORY"}


def _ranking(zero: np.ndarray, hold: np.ndarray, rtol: float = TIE_RTOL) -> np.ndarray:
    """Per point (last axis = components): ``zero-input`` / ``hold-input`` if lower in every component by more
    than ``rtol`` (relative), ``tie`` if equal within ``rtol`` in every component, else ``mixed``."""
    zero, hold = np.asarray(zero, float), np.asarray(hold, float)
    gap = rtol * np.maximum(np.abs(zero), np.abs(hold))
    out = np.full(zero.shape[:-1], "mixed", dtype=object)
    out[np.all(np.abs(zero - hold) <= gap, axis=-1)] = "tie"
    out[np.all(zero < hold - gap, axis=-1)] = "zero-input"
    out[np.all(hold < zero - gap, axis=-1)] = "hold-input"
    return out


def _from_t(d, mech: str, T: int) -> str:
    """First t of 1..T from which ``mech`` has the lower theoretical filter variance in every component until T
    (``never`` if not at T)."""
    z, h = d["zero/theory_filt"][1: T + 1], d["hold/theory_filt"][1: T + 1]
    better = np.all((z < h) if mech == "zero-input" else (h < z), axis=1)
    if not better[-1]:
        return "never"
    bad = np.flatnonzero(~better)
    return str(1 if len(bad) == 0 else int(bad[-1]) + 2)


def _grid_set(vals: np.ndarray) -> dict:
    return {"count": int(len(vals)), "min": float(vals.min()) if len(vals) else None,
            "max": float(vals.max()) if len(vals) else None}


def step_values(cfg, inputs, outputs, wildcards) -> dict:
    """``values.json`` (our value of every P4 claim, with its evidence) and ``summary.csv``."""
    eta, N, T = float(cfg["eta_bar"]), int(cfg["smoother_lag"]), int(cfg["T"])
    tol, max_iter = float(cfg["steady"]["tol"]), int(cfg["steady"]["max_iter"])
    ex0 = cfg["tracking"]["example"]
    mc_npz = {ex: _example_file(inputs.mc_npz, f"mc_{ex}") for ex in cfg["examples"]}
    reports = {ex: read_json(_example_file(inputs.mc_json, f"mc_{ex}")) for ex in cfg["examples"]}
    values: dict[str, dict] = {}

    # P4-F1..F3: tracking, one realisation
    tr = np.load(inputs.tracking)
    x = tr["x"]
    rms_x = np.sqrt(np.mean(x ** 2, axis=0))
    ok = ~np.isnan(tr["smooth"][:, 0])      # the N-step smoother ends N steps before T
    values["tracking"] = {
        "value": {name: {"rel_rms": (np.sqrt(np.mean((x[ok] - tr[name][ok]) ** 2, axis=0)) / rms_x).tolist(),
                         "corr": [float(np.corrcoef(x[ok, i], tr[name][ok, i])[0, 1]) for i in range(x.shape[1])]}
                  for name in ("filt", "pred", "smooth")},
        "evidence": {"example": ex0, "eta_bar": eta, "t_last": int(np.flatnonzero(ok)[-1]),
                     "seed": cfg["tracking"]["seed"]}}

    # P4-F4: ordering (whole horizon, theory and MC)
    d = np.load(mc_npz[ex0])
    estimators = {"predictor": "pred", "filter": "filt", "smoother": f"smooth{N}"}
    curves = {src: {est: d[f"zero/{src}_{key}"] for est, key in estimators.items()} for src in ("theory", "mc")}
    valid = slice(1, T + 1 - N)
    strict = {src: bool(np.all(c["smoother"][valid] < c["filter"][valid])
                        and np.all(c["filter"][valid] < c["predictor"][valid])) for src, c in curves.items()}
    tlast = T - N
    th = curves["theory"]
    order_str = " < ".join(sorted(th, key=lambda k: float(np.sum(th[k][tlast]))))
    values["ordering"] = {
        "value": order_str if strict["theory"] else f"{order_str} (not at every t)",
        "evidence": {"example": ex0, "eta_bar": eta, "N": N, "t": tlast,
                     **{src: {k: v[tlast].tolist() for k, v in c.items()} for src, c in curves.items()},
                     "strict_theory": strict["theory"], "strict_mc": strict["mc"]}}

    # P4-F5: trend in eta_bar
    e = np.load(inputs.eta)
    etas = e["eta"]
    decreasing = {est: bool(np.all(np.diff(e[f"{ex0}/zero/{est}"], axis=0) < 0)) for est in ("pred", "filt", "smooth")}
    at = {"lo": 0, "mid": int(np.argmin(np.abs(etas - eta))), "hi": -1}  # the ends of the grid and the nearest to eta
    values["eta_trend"] = {
        "value": "decreasing" if all(decreasing.values()) else
        "not monotone (" + ", ".join(k for k, ok_ in decreasing.items() if not ok_) + ")",
        "evidence": {"example": ex0, **{f"eta_{k}": float(etas[i]) for k, i in at.items()}, "points": int(len(etas)),
                     "decreasing": decreasing,
                     **{f"filt_{k}": e[f"{ex0}/zero/filt"][i].tolist() for k, i in at.items()}}}

    # P4-F6: trend in Q_xi, Q_lambda
    q = np.load(inputs.q)
    F = q[f"{ex0}/zero/filt"]        # (qxi, qlam, n)
    inc_xi = bool(np.all(np.diff(F, axis=0) > 0))
    inc_lam = bool(np.all(np.diff(F, axis=1) > 0))
    values["q_trend"] = {
        "value": "increasing" if inc_xi and inc_lam else f"not monotone (Q_xi: {inc_xi}, Q_lambda: {inc_lam})",
        "evidence": {"example": ex0, "eta_bar": eta, "n_xi": int(len(q["qxi"])), "n_lam": int(len(q["qlam"])),
                     "q_lo": float(q["qxi"][0]), "q_hi": float(q["qxi"][-1]), "q_lam_hi": float(q["qlam"][-1]),
                     "increasing_xi": inc_xi, "increasing_lam": inc_lam, "filt_lo": F[0, 0].tolist(),
                     "filt_hi": F[-1, -1].tolist(), "all_stable": bool(np.all(q[f"{ex0}/zero/stable"]))}}

    # P4-THEORY: the corrected recursion and Theorem 1 as printed (eq. (9)) vs Monte Carlo, per example
    theory, printed = {}, {}
    for ex, rep in reports.items():
        corrected = {n: c for n, c in rep["checks"].items() if not n.startswith("printed")}
        theory[ex] = {"runs": rep["runs"], "steps": rep["T"] + 1, "mult_dist": rep["mult_dist"],
                      "checks": len(corrected), "z_crit": rep["checks"]["zero/filt"]["z_crit"],
                      "max_abs_z": max(c["max_abs_z"] for c in corrected.values()),
                      "passed": all(bool(c["passed"]) for c in corrected.values())}
        pe, cp = rep["printed_eq9"], rep["checks"]["printed_eq9/pred1"]
        printed[ex] = {"P_printed_T": pe["P_printed_T"], "P_corrected_T": pe["P_corrected_T"],
                       "P_true_T": pe["P_true_with_printed_gains_T"], "mc_T": pe["mc_T"], "se_T": pe["se_T"],
                       "max_abs_z": cp["max_abs_z"], "z_crit": cp["z_crit"], "passed": bool(cp["passed"])}

    # P4-F7 / P4-F8: zero vs hold
    for ex, key in (("ex1", "better_ex1"), ("ex2", "better_ex2")):
        if ex not in mc_npz:
            continue
        d = np.load(mc_npz[ex])
        plant = plant_of(cfg, ex)
        ssz, ssh = (steady_variances(plant, mech, eta, N, tol, max_iter)["filt"] for mech in MECHANISMS)
        # per point of the eta and Q grids; ties (eta_bar = 1: the same filter) kept apart
        rank_eta, rank_q = (_ranking(g[f"{ex}/zero/filt"], g[f"{ex}/hold/filt"]) for g in (e, q))
        values[key] = {"value": str(_ranking(ssz, ssh)[()]), "evidence": {  # the steady states: one point
            "example": ex, "eta_bar": eta, "T": T, "runs": reports[ex]["runs"],
            "steady_zero": ssz.tolist(), "steady_hold": ssh.tolist(),
            "trace_zero": float(ssz.sum()), "trace_hold": float(ssh.sum()),
            **{f"{src}_{m}_T": d[f"{m}/{src}_filt"][T].tolist() for src in ("theory", "mc") for m in ("zero", "hold")},
            "from_t": {m: _from_t(d, m, T) for m in MECHANISMS},
            "qlam_threshold": qlam_threshold(plant, eta, N, tol, max_iter),
            "eta_lo": float(etas[0]), "eta_hi": float(etas[-1]),
            **{f"{k}_eta": _grid_set(etas[rank_eta == r])
               for k, r in zip(("hold_better", "zero_better", "tie"), RANKS)},
            "tie_rtol": TIE_RTOL, "q_lo": float(q["qxi"][0]), "q_hi": float(q["qxi"][-1]),
            **{f"frac_{k}": float(np.mean(rank_q == r)) for k, r in zip(("hold", "zero", "tie"), RANKS)},
            "theory_checks_passed": theory[ex]["passed"]}}

    all_pass = all(t["passed"] for t in theory.values())
    values["theory_vs_mc"] = {"value": "agrees" if all_pass else "disagrees",
                              "evidence": {"alpha": cfg["mc"]["alpha"], "examples": theory, "all_passed": all_pass}}
    printed_ok = all(p["passed"] for p in printed.values())
    values["eq9_as_printed"] = {"value": "agrees" if printed_ok else "disagrees",
                                "evidence": {"examples": printed, "printed_passed": printed_ok,
                                             "corrected_passed": all_pass}}
    write_json(outputs.values, values)
    rows = [(target, key, values[key]["value"]) for key, target in SUMMARY_TARGETS.items() if key in values]
    write_csv(outputs.table, pd.DataFrame(rows, columns=["target", "key", "value"]))
    return values


def _example_file(files: Sequence[str], stem: str) -> str:
    """The declared input of one example (``.../mc_ex1.json`` for stem ``mc_ex1``)."""
    hits = [f for f in files if Path(f).stem == stem]
    if len(hits) != 1:
        raise InputError(f"expected one input named {stem}.*, got {hits}", None, stem)
    return hits[0]
