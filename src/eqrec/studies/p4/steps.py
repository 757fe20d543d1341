"""P4 study: the LMV companion paper (zero- vs hold-input compensation of packet dropouts; targets P4-*).

Pipeline steps (``step_<name>``; one per rule of ``workflow/rules/p4.smk``, run by
:mod:`eqrec.studies.pipeline.harness`), each ``step(cfg, inputs, outputs, wildcards)``
with ``cfg`` the validated ``p4`` section:

``tracking``         Figs. 1-3: one realisation of the tracking example.
``mc``               P4-THEORY: theory against Monte Carlo for one example (``wildcards.example``), both
                     mechanisms on the same draws; also Theorem 1 eq. (9) as printed.
``sweep_eta_chunk``, ``sweep_q_chunk``   steady-state sweeps, one chunk (``wildcards.scatteritem``, ``i-of-n``) each.
``fig4``, ``fig5``, ``fig6``, ``compare``   figures (:mod:`eqrec.studies.p4.figures`); ``fig5``/``fig6``
                     first merge the sweep chunks (checking that they cover the configured grid exactly once).
``values``           our value of every P4 claim with its evidence (``values.json``) and ``summary.csv``
                     (:mod:`eqrec.studies.p4.values`).

The mathematics is in :mod:`eqrec.lmv` (the plant, the two compensated systems, the recursion,
the steady state); the chunks of the sweeps in :mod:`eqrec.studies.pipeline.chunks`.

Initial conditions (symbolic in the paper): ``x(0) ~ N(0, I)`` (``sigma0 = 0``,
``Sigma0 = I``) for both examples, ``y_h(-1) = 0`` for the hold-input
mechanism; set in ``config/p4.yaml``.
"""

from __future__ import annotations

import math
import time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from eqrec.lmv.model import MECHANISM_KEYS, MECHANISMS, ms_spectral_radius
from eqrec.lmv.plant import plant_of
from eqrec.lmv.estimator import apply_estimator
from eqrec.lmv.recursion import LMVResult, suboptimal_error_cov, theorem1_as_printed
from eqrec.lmv.steady import steady_variances
from eqrec.lmv.monte_carlo import compare_moments, fourth_moment_radius, run_mc, simulate_plant
from eqrec.studies.pipeline import configuration
from eqrec.studies.p4 import figures as p4_figures
from eqrec.studies.pipeline.chunks import scatter_indices
from eqrec.studies.pipeline.logs import Progress, get_logger
from eqrec.studies.pipeline.outputs import write_json, write_npz

log = get_logger("p4")

# --------------------------------------------------------------------------- configuration


def load_config(*files: str | Path, overrides=None) -> dict:
    """The validated ``p4`` section (default ``config/p4.yaml``); see :func:`eqrec.studies.pipeline.configuration.load_config`."""
    return configuration.load_config("p4", *files, overrides=overrides)


def _diag(P: np.ndarray) -> np.ndarray:
    return np.einsum("...ii->...i", P)


# --------------------------------------------------------------------------- steps

def step_tracking(cfg, inputs, outputs, wildcards) -> None:
    """Figs. 1-3: one realisation of the tracking example (zero-input, eta_bar of the config)."""
    ex = cfg["tracking"]["example"]
    plant = plant_of(cfg, ex)
    eta, T, N = float(cfg["eta_bar"]), int(cfg["T"]), int(cfg["smoother_lag"])
    rng = np.random.default_rng(int(cfg["tracking"]["seed"]))
    sim = simulate_plant(plant, eta, T, 1, rng, mult_dist=cfg["examples"][ex]["mc_mult_dist"])
    mc = run_mc(plant, eta, "zero-input", T, 1, N, rng, sim=sim, pred_steps=int(cfg["pred_steps"]))
    x = sim["x"][0]
    est = {"filt": mc.est["smooth"][0, :, 0], "pred": mc.est["pred"][0, : T + 1], "smooth": mc.est["smooth"][0, :, N]}
    write_npz(outputs.npz, x=x, **est, eta=sim["eta"][0], y=sim["y_zero"][0], N=N, eta_bar=eta)
    log.info("tracking %s: %d/%d packets arrived", ex, int(sim["eta"][0].sum()), T + 1)
    labels = [("filter", r"$\hat{{x}}_{i}(t|t)$"), ("one-step predictor", r"$\hat{{x}}_{i}(t|t-1)$"),
              (f"{N}-step smoother", r"$\hat{{x}}_{i}(t|t+" + str(N) + ")$")]
    for num, ((title, sym), e) in enumerate(zip(labels, est.values()), start=1):  # Figs. 1-3
        p4_figures.fig_tracking(x, e, title, sym, eta, outputs[f"f{num}"], outputs[f"f{num}png"],
                                arrived=sim["eta"][0])


def _check_record(c) -> dict:
    return {"passed": c.passed, "max_abs_z": c.max_abs_z, "z_crit": c.z_crit, "max_mean_z": c.mean_z,
            "entries": c.k, "max_rel_err_var": c.max_rel_err, "summary": c.summary()}


def step_mc(cfg, inputs, outputs, wildcards) -> dict:
    """Monte Carlo validation (P4-THEORY) and the error-variance curves of Figs. 4, 7, 8.

    Both mechanisms are run on the same realisations.  The standard errors of the Monte Carlo variances
    (``outputs.se``: ``{mechanism}/se_{estimator}`` and ``runs``) give the figures their uncertainty bands.  Also measures
    Theorem 1 *as printed* (eq. (9)) against the same Monte Carlo.
    """
    example = wildcards["example"]
    plant = plant_of(cfg, example)
    eta, T, N, Np = float(cfg["eta_bar"]), int(cfg["T"]), int(cfg["smoother_lag"]), int(cfg["pred_steps"])
    runs, alpha = int(cfg["mc"]["runs"]), float(cfg["mc"]["alpha"])
    dist = cfg["examples"][example]["mc_mult_dist"]
    seed = int(cfg["mc"]["seed"]) + sum(map(ord, example))
    rng = np.random.default_rng(seed)
    t0 = time.perf_counter()
    sim = simulate_plant(plant, eta, T, runs, rng, mult_dist=dist)
    log.info("%s: simulated %d runs x %d steps (%s multiplicative noise) in %.2f s", example, runs, T + 1, dist,
             time.perf_counter() - t0)
    arrays: dict[str, np.ndarray] = {"t": np.arange(T + 1)}
    errors: dict[str, np.ndarray] = {"t": np.arange(T + 1), "runs": np.array(runs)}  # standard errors (figures)
    report: dict[str, Any] = {"example": example, "runs": runs, "T": T, "eta_bar": eta, "alpha": alpha,
                              "mult_dist": dist, "seed": seed, "smoother_lag": N, "pred_steps": Np,
                              "fourth_moment_radius": {d: fourth_moment_radius(plant, d)
                                                       for d in ("gaussian", "two-point")},
                              "checks": {}}
    mcs = {}
    for mech in MECHANISMS:
        t1 = time.perf_counter()
        mc = mcs[mech] = run_mc(plant, eta, mech, T, runs, N, rng, sim=sim, pred_steps=Np)
        k = MECHANISM_KEYS[mech]
        report[f"ms_radius_{k}"] = ms_spectral_radius(mc.sys)
        checks = {"pred1": compare_moments(mc.err_pred, mc.P_pred, alpha),
                  f"pred{Np}": compare_moments(mc.err_npred, mc.P_npred, alpha)}
        for name, P, c in (("pred", mc.P_pred, checks["pred1"]), ("npred", mc.P_npred, checks[f"pred{Np}"])):
            arrays[f"{k}/theory_{name}"], arrays[f"{k}/mc_{name}"] = _diag(P), _diag(c.emp)
        errors[f"{k}/se_pred"] = _diag(checks["pred1"].se)
        for j in range(N + 1):  # the j-step smoother (j = 0: the filter) has values up to t = T - j; NaN after
            name, valid = "filt" if j == 0 else f"smooth{j}", np.arange(T + 1 - j)
            c = checks[name] = compare_moments(mc.err_smooth[:, valid, j], mc.P_smooth[valid, j], alpha)
            for store, key, moment in ((arrays, "theory", c.theory), (arrays, "mc", c.emp), (errors, "se", c.se)):
                store[f"{k}/{key}_{name}"] = np.full((T + 1, plant.n), np.nan)
                store[f"{k}/{key}_{name}"][valid] = _diag(moment)
        for name, c in checks.items():
            report["checks"][f"{k}/{name}"] = _check_record(c)
            log.info("%s %s %s: %s", example, mech, name, c.summary())
        log.info("%s %s: estimation and comparison %.2f s", example, mech, time.perf_counter() - t1)
    # Theorem 1 as printed versus the same Monte Carlo (zero-input, predictor).
    printed = theorem1_as_printed(plant, eta, T)
    zsys, zres = mcs["zero-input"].sys, mcs["zero-input"].res
    P_true_printed_gain = suboptimal_error_cov(zsys, printed["L"], zres.q)
    est_p = apply_estimator(LMVResult(zsys, zres.q, printed["P"], printed["L"], printed["Qe"]), sim["y_zero"])
    err_p = sim["x"] - est_p["pred"][:, : T + 1]
    c_printed = compare_moments(err_p, printed["P"][: T + 1], alpha)
    c_true = compare_moments(err_p, P_true_printed_gain[: T + 1], alpha)
    report["checks"]["printed_eq9/pred1"] = _check_record(c_printed)
    report["printed_eq9"] = {
        "P_printed_T": _diag(printed["P"][T]).tolist(),
        "P_corrected_T": _diag(zres.P_pred[T]).tolist(),
        "P_true_with_printed_gains_T": _diag(P_true_printed_gain[T]).tolist(),
        "mc_T": _diag(c_printed.emp[T]).tolist(),
        "se_T": _diag(c_printed.se[T]).tolist(),
        "joseph_check": {"passed": c_true.passed, "max_abs_z": c_true.max_abs_z, "summary": c_true.summary()},
    }
    log.info("%s Theorem 1 as printed: %s", example, c_printed.summary())
    arrays["printed/theory_pred"] = _diag(printed["P"][: T + 1])
    arrays["printed/true_pred"] = _diag(P_true_printed_gain[: T + 1])
    arrays["printed/mc_pred"] = _diag(c_printed.emp)
    write_npz(outputs.npz, **arrays)
    write_npz(outputs.se, **errors)
    write_json(outputs.json, report)
    return report


def _sweep_chunk(cfg: dict, wildcards, sweep: str) -> tuple[str, np.ndarray, np.ndarray]:
    """One job of a sweep (``sweep_eta`` or ``sweep_q``): its chunk (``i-of-n``), the whole grid, the chunk's
    indices."""
    g = cfg[sweep]
    values = np.linspace(float(g["lo"]), float(g["hi"]), int(g["num"]))
    return *scatter_indices(wildcards, len(values), field=f"{sweep}.chunks"), values


def _sweep(cfg: dict, outputs, what: str, out: dict, points_of: Callable, keys: tuple, shape: tuple) -> dict:
    """Write one chunk of a sweep (``outputs.npz``): ``out`` (its grid) and, per example and mechanism, the
    ``keys`` of :func:`eqrec.lmv.steady.steady_variances` at the points ``(plant, eta_bar)`` that ``points_of``
    makes of the example's plant, in the grid's ``shape`` (then the components)."""
    N, tol, max_iter = int(cfg["smoother_lag"]), float(cfg["steady"]["tol"]), int(cfg["steady"]["max_iter"])
    prog = Progress(log, len(cfg["examples"]) * len(MECHANISMS) * math.prod(shape), what)
    for ex in cfg["examples"]:
        points = points_of(plant_of(cfg, ex))
        for mech in MECHANISMS:
            rows = []
            for plant, eta in points:
                rows.append(steady_variances(plant, mech, eta, N, tol, max_iter))
                prog.advance()
            for key in keys:
                v = np.array([r[key] for r in rows])
                out[f"{ex}/{MECHANISM_KEYS[mech]}/{key}"] = v.reshape(*shape, *v.shape[1:])
    write_npz(outputs.npz, **out)
    return out


def step_sweep_eta_chunk(cfg, inputs, outputs, wildcards) -> dict:
    """Steady-state variances against eta_bar (Fig. 5) for one chunk of the grid, both examples and mechanisms."""
    chunk, idx, etas = _sweep_chunk(cfg, wildcards, "sweep_eta")
    grid = {"idx": idx, "eta": etas[idx], "num": np.array(len(etas))}
    return _sweep(cfg, outputs, f"eta sweep chunk {chunk}", grid, lambda plant: [(plant, float(e)) for e in etas[idx]],
                  ("pred", "filt", "smooth", "stable"), (len(idx),))


def step_sweep_q_chunk(cfg, inputs, outputs, wildcards) -> dict:
    """Steady filter variances on the (Q_xi, Q_lambda) grid (Fig. 6): rows of Q_xi in this chunk."""
    chunk, idx, qs = _sweep_chunk(cfg, wildcards, "sweep_q")
    eta = float(cfg["eta_bar"])
    grid = {"idx": idx, "qxi": qs[idx], "qlam": qs, "num": np.array(len(qs))}
    return _sweep(cfg, outputs, f"Q sweep chunk {chunk}", grid,
                  lambda base: [(base.with_(Qxi=float(qs[i]), Qlam=float(ql)), eta) for i in idx for ql in qs],
                  ("filt", "stable"), (len(idx), len(qs)))
