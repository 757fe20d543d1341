r"""P2 pipeline: the state-augmented estimator paper (Hassaan, Shen, Yong, ACC 2019).

One function per Snakemake rule (``workflow/rules/p2.smk``); each reads the
``p2:`` section of ``config/p2.yaml`` and writes its declared outputs.  Run as
``python -m eqrec.studies.p2 <step> ...``.

Steps
-----
``designs``     P2-F1/F2 designs: time-based LP, augmented LP (pole-placement ``L``),
                augmented IPOPT (``L``, ``s0`` free), and the readings of the text
                (word indices read 1-based; ``L`` kept at missing steps = ``leak``;
                injection without the current measurement; process noise ``W = I``).
``simulate``    500 runs per figure, every estimator on the same draws (core simulator).
``heatmap-chunk`` / ``heatmap-merge``   P2-F3a sweep, one job per θ-chunk.
``realaxis``    P2-F3b: eigenvalues ``{0, λ, λ}``, ``λ`` real.
``checks``      P2-S0 and P2-SOLVER.
``values``      ``values.json`` for the claims table.
``figure-*``    figures.
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

from eqrec.design.augmented_model import (AugmentedEstimator, AugmentedGains, AugmentedStacking, augmented_to_time_based,
                        schedule_from_augmented)
from eqrec.core.certify import certify_schedule
from eqrec.studies.claims import write_values
from eqrec.design.augmented import design_augmented
from eqrec.design.augmented_lp import AugmentedLP
from eqrec.design.augmented_nlp import solve_free_ipopt
from eqrec.design.observers import place_observer
from eqrec.design.time_based import design_time_based
from eqrec.errors import EqrecError, InputError
from eqrec.core.gains import GainSchedule, schedule_from_word_gains
from eqrec.core.patterns import PrefixTree, validate_language, worst_case_word
from eqrec.core.simulate import monte_carlo, simulate_run, sample_uncertainty
from eqrec.core.stacking import UncertaintyLayout
from eqrec.core.systems import AffineSystem, acc_system

log = logging.getLogger("eqrec.p2")

DEFAULTS: dict[str, Any] = {
    "T": 6, "mu1": 1.0, "f1_words": ["111111"], "f2_words": ["101111", "110111"],
    "runs": 500, "seed": 2019, "noise": "uniform", "x0": [20.0, 40.0, 20.0],
    "init_poles": [0.0, 0.5, -0.5],
    "heatmap": {"word": "100111", "n_r": 31, "n_theta": 31, "r_max": 1.5, "chunks": 8,
                "variants": ["theorem2", "one_based", "leak"], "solver": "highs"},
    "realaxis": {"n": 301, "lam_max": 1.5},
    "s0_samples": [[0.5, -0.3, 0.2], [-2.0, 1.0, 3.0]],
    "solvers": ["highs", "clarabel", "ipopt"],
    "mu2_tol": 1.0e-6,
}

#: Heat-map / projection variants: name -> (mode, word reading)
VARIANTS = {"theorem2": ("theorem2", "zero_based"), "one_based": ("theorem2", "one_based"),
            "leak": ("leak", "zero_based"), "masked_gain": ("masked_gain", "zero_based")}


def load_config(path: str | Path | dict | None) -> dict:
    """The ``p2`` section (file path or mapping) merged over :data:`DEFAULTS`."""
    if path is None:
        data: dict = {}
    elif isinstance(path, dict):
        data = path.get("p2", path)
    else:
        raw = yaml.safe_load(Path(path).read_text()) or {}
        if "p2" not in raw:
            raise InputError("config lacks the top key 'p2'", str(path))
        data = raw["p2"]
    cfg = json.loads(json.dumps(DEFAULTS))
    for k, v in data.items():
        if isinstance(v, dict) and isinstance(cfg.get(k), dict):
            cfg[k].update(v)
        else:
            cfg[k] = v
    if cfg["heatmap"]["chunks"] < 1 or cfg["heatmap"]["chunks"] > cfg["heatmap"]["n_theta"]:
        raise InputError("heatmap.chunks must be between 1 and n_theta", field="p2.heatmap.chunks")
    return cfg


def heatmap_poles(r: float, theta: float) -> np.ndarray:
    """Fig. 3a: one eigenvalue at 0 and a pair at ``r e^{±jθ}``."""
    lam = r * np.exp(1j * theta)
    if abs(lam.imag) <= 1e-12 * max(r, 1.0):  # θ = 0 or π: a real double eigenvalue, not a rounding-error pair
        lam = complex(lam.real, 0.0)
    return np.array([0.0, lam, np.conj(lam)])


def one_based_word(word: str) -> str:
    """Reading check: the word's missing positions taken as 1-based time indices.

    ``100111`` misses ``k = 1, 2`` (0-based); the Fig. 2 caption says
    ``k = 2 and 3``. Read 1-based, the missing steps become ``k = 2, 3``:
    ``110011``. A missing position shifted past the horizon is dropped.
    """
    T = len(word)
    out = ["1"] * T
    for i, c in enumerate(word):
        if c == "0" and i + 1 < T:
            out[i + 1] = "0"
    return "".join(out)


def variant_word(word: str, variant: str) -> tuple[str, str]:
    """``(mode, word)`` used by a heat-map variant."""
    if variant not in VARIANTS:
        raise InputError(f"unknown variant {variant!r}; choose from {list(VARIANTS)}", field="variants")
    mode, reading = VARIANTS[variant]
    return mode, (one_based_word(word) if reading == "one_based" else word)


def _eig(system: AffineSystem, L: np.ndarray) -> list[list[float]]:
    ev = np.linalg.eigvals(system.A - np.asarray(L) @ system.C)
    ev = ev[np.lexsort((ev.imag, ev.real))]
    return [[float(e.real), float(e.imag)] for e in ev]


def _gains_npz(prefix: str, g: AugmentedGains, F: np.ndarray, u0: np.ndarray) -> dict:
    return {f"{prefix}/M": g.M, f"{prefix}/nu": g.nu, f"{prefix}/L": g.L, f"{prefix}/s0": g.s0,
            f"{prefix}/F": F, f"{prefix}/u0": u0, f"{prefix}/word": np.array(g.word),
            f"{prefix}/mode": np.array(g.mode)}


def _schedule_npz(prefix: str, word: str, F: np.ndarray, u0: np.ndarray) -> dict:
    return {f"{prefix}/F": F, f"{prefix}/u0": u0, f"{prefix}/word": np.array(word)}


def _schedule_from(npz, prefix: str, n: int, p: int) -> GainSchedule:
    word = str(npz[f"{prefix}/word"])
    return schedule_from_word_gains(PrefixTree([word]), {word: (npz[f"{prefix}/F"], npz[f"{prefix}/u0"])}, n, p,
                                    time_based=True)


def _gains_from(npz, prefix: str) -> AugmentedGains:
    return AugmentedGains(word=str(npz[f"{prefix}/word"]), L=npz[f"{prefix}/L"], s0=npz[f"{prefix}/s0"],
                          M=npz[f"{prefix}/M"], nu=npz[f"{prefix}/nu"], mode=str(npz[f"{prefix}/mode"]))


# ---------------------------------------------------------------------------
# Step: designs
# ---------------------------------------------------------------------------

def _augmented_entry(system, d, language) -> dict:
    g: AugmentedGains = d.extra["gains"]
    cert = d.certificate
    return {"design_mu2": d.mu2, "certified_mu2": cert.mu2, "certified_terminal": cert.terminal,
            "worst_case_word": d.extra["worst_case_word"], "mode": d.extra["mode"],
            "L": g.L[0].tolist(), "eig_A_minus_LC": _eig(system, g.L[0]), "s0": g.s0.tolist(),
            "solver": d.solution.solver, "iterations": d.solution.iterations, "solve_time": d.solution.solve_time,
            "ipopt_status": d.extra.get("ipopt_status"), "initial_mu2": d.extra.get("initial_mu2"),
            "initial_guess": d.extra.get("initial_guess"), "poles": [[p.real, p.imag] for p in d.extra.get("poles", [])],
            "certified_words": list(cert.words)}


def step_designs(config, out_json: str | Path, out_npz: str | Path) -> dict:
    """P2-F1, P2-F2 and the readings: every design certified from its time-based form."""
    cfg = load_config(config)
    system = acc_system()
    M1, poles = float(cfg["mu1"]), np.asarray(cfg["init_poles"], float)
    out: dict[str, Any] = {"system": system.to_dict(), "mu1": M1, "init_poles": poles.tolist()}
    arrays: dict[str, np.ndarray] = {}
    for fig, key in (("f1", "f1_words"), ("f2", "f2_words")):
        language = validate_language(cfg[key], length=int(cfg["T"]))
        wc = worst_case_word(language)
        res: dict[str, Any] = {"language": list(language), "worst_case_word": wc}
        tb = design_time_based(system, language, M1)
        F, u0 = tb.schedule.word_matrices(wc)
        arrays.update(_schedule_npz(f"{fig}/time", wc, F, u0))
        res["time"] = {"mu2": tb.mu2, "certified_mu2": tb.certificate.mu2, "solve_time": tb.solve_time,
                       "iterations": tb.solution.iterations}
        for name, kwargs in (("augmented_lp", {"L": None, "poles": poles}),
                             ("augmented_free", {"L": "free", "poles": poles})):
            t0 = time.perf_counter()
            d = design_augmented(system, language, M1, **kwargs)
            entry = _augmented_entry(system, d, language)
            entry["wall_time"] = time.perf_counter() - t0
            res[name] = entry
            g = d.extra["gains"]
            arrays.update(_gains_npz(f"{fig}/{name}", g, *augmented_to_time_based(system, g)))
            log.info("%s %s: mu2 = %.9g (certified %.9g)", fig, name, d.mu2, d.certificate.mu2)
        if fig == "f2":
            # Reading 1: word positions read as 1-based time indices (caption: k = 2 and 3).
            w1 = one_based_word(wc)
            tb1 = design_time_based(system, [w1], M1)
            d1 = design_augmented(system, [w1], M1, L="free", poles=poles)
            res["one_based"] = {"word": w1, "time_mu2": tb1.mu2, "augmented_free": _augmented_entry(system, d1, [w1])}
            g1 = d1.extra["gains"]
            arrays.update(_gains_npz("f2/one_based", g1, *augmented_to_time_based(system, g1)))
            # What the 1-based design really guarantees on the true worst-case word.
            sch1 = schedule_from_augmented(system, g1)
            F1_, u01 = sch1.word_matrices(w1)
            res["one_based"]["certified_on_true_words"] = {
                w: float(certify_schedule(system, _retarget(sch1, w1, wc), [w], M1).words[w].bounds.max())
                for w in [wc]}
            # Reading 2: constant L kept at the missing steps with the measurement in the s-dynamics (leak).
            leak = {}
            for name, Lspec in (("leak_lp", None), ("leak_free", "free")):
                try:
                    dl = design_augmented(system, language, M1, L=Lspec, poles=poles, mode="leak")
                    e = _augmented_entry(system, dl, language)
                    gl = dl.extra["gains"]
                    e["certified_mu2_theorem2_runtime"] = certify_schedule(
                        system, schedule_from_augmented(system, gl, "theorem2"), [wc], M1).mu2
                    arrays.update(_gains_npz(f"f2/{name}", gl, *augmented_to_time_based(system, gl, "hold")))
                    leak[name] = e
                except EqrecError as exc:
                    leak[name] = {"status": f"{type(exc).__name__}: {exc}"}
            # leak with an L for which the leak LP is feasible: sweep the real pole λ of {0, λ, λ}
            res["leak"] = leak
        if fig == "f1":
            # Reading 3: injection without the current measurement (M(k, k) = 0).
            pp = place_observer(system.A, system.C, poles)
            m = AugmentedLP(system, wc, M1, pp.L, strictly_causal=True)
            s = m.solve().require_optimal("strictly causal augmented design")
            res["strictly_causal_mu2"] = float(s.objective)
            # Reading 4: process noise entering every state (W = I_n) instead of E = [0, Ts^2/2, Ts]^T.
            sysI = AffineSystem(A=system.A, B=system.B, f=system.f, C=system.C, E=np.eye(system.n),
                                eta_w=system.eta_w, eta_v=system.eta_v, name="ACC, W = I")
            res["process_noise_identity_mu2"] = design_time_based(sysI, language, M1).mu2
        out[fig] = res
    Path(out_json).parent.mkdir(parents=True, exist_ok=True)
    Path(out_json).write_text(json.dumps(out, indent=2, default=float) + "\n")
    np.savez(out_npz, **arrays)
    return out


def _retarget(schedule: GainSchedule, designed: str, actual: str) -> GainSchedule:
    """Run a time-based schedule designed for ``designed`` on data following ``actual``.

    The gains on measurements that ``actual`` lacks multiply ``ỹ = 0``: zero
    those columns (what the running estimator really does).
    """
    F, u0 = schedule.word_matrices(designed)
    p = schedule.p
    q = np.repeat(np.array([int(c) for c in actual]) == 0, p)
    F = F.copy()
    F[:, q] = 0.0
    return schedule_from_word_gains(PrefixTree([actual]), {actual: (F, u0)}, schedule.n, p, time_based=True)


# ---------------------------------------------------------------------------
# Step: simulate
# ---------------------------------------------------------------------------

def step_simulate(config, designs_npz: str | Path, out_npz: str | Path) -> dict:
    """P2-F1/F2 Monte Carlo: every estimator on the same draws (same seed, same words)."""
    cfg = load_config(config)
    system = acc_system()
    M1, runs, seed = float(cfg["mu1"]), int(cfg["runs"]), int(cfg["seed"])
    x0 = np.asarray(cfg["x0"], float)
    npz = np.load(designs_npz)
    out: dict[str, np.ndarray] = {}
    summary = {}
    for fig, key in (("f1", "f1_words"), ("f2", "f2_words")):
        language = list(validate_language(cfg[key]))
        names = ["time", "augmented_lp", "augmented_free"]
        if fig == "f2":
            names += [n for n in ("one_based", "leak_lp", "leak_free") if f"f2/{n}/F" in npz.files]
        for name in names:
            sch = _schedule_from(npz, f"{fig}/{name}", system.n, system.p)
            designed = str(npz[f"{fig}/{name}/word"])
            if designed != worst_case_word(language):  # reading variants run on the true data
                sch = _retarget(sch, designed, worst_case_word(language))
            errs, used = monte_carlo(system, sch, language, M1, runs, seed, kind=cfg["noise"], x0=x0)
            out[f"{fig}/{name}"] = errs
            summary[f"{fig}/{name}"] = float(np.abs(errs).max())
        out[f"{fig}/words"] = np.array(used)
        # the runtime augmented estimator reproduces the converted one on the first runs
        g = _gains_from(npz, f"{fig}/augmented_free")
        out[f"{fig}/runtime_max_diff"] = np.array(_runtime_check(system, g, language, M1, seed, cfg["noise"], x0, 20))
    np.savez(out_npz, **out)
    return summary


def _runtime_check(system, gains, language, M1, seed, kind, x0, runs) -> float:
    sch = schedule_from_augmented(system, gains)
    rng = np.random.default_rng(seed)
    T = gains.T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    rad = lay.radius(system.eta_w, system.eta_v, M1)
    worst = 0.0
    for _ in range(runs):
        word = language[rng.integers(len(language))]
        delta = sample_uncertainty(lay, rad, rng, kind)
        tr = simulate_run(system, sch, word, delta, x0)
        w, v, xi0 = lay.split(delta)
        est = AugmentedEstimator(system, gains, x0 - xi0)
        x = x0.copy()
        for t in range(T):
            y = system.C @ x + v[t] if word[t] == "1" else None
            xh = est.step(y)
            x = system.A @ x + system.f + system.E @ w[t]
            worst = max(worst, float(np.abs(xh - tr.xhat[t + 1]).max()))
    return worst


# ---------------------------------------------------------------------------
# Steps: heat map (P2-F3a) and real axis (P2-F3b)
# ---------------------------------------------------------------------------

def heatmap_grid(cfg: dict) -> tuple[np.ndarray, np.ndarray]:
    h = cfg["heatmap"]
    return np.linspace(0.0, float(h["r_max"]), int(h["n_r"])), np.linspace(0.0, np.pi, int(h["n_theta"]))


def theta_chunk(cfg: dict, chunk: int) -> np.ndarray:
    """Indices of θ handled by job ``chunk``."""
    n_chunks = int(cfg["heatmap"]["chunks"])
    if not 0 <= chunk < n_chunks:
        raise InputError(f"chunk {chunk} outside 0..{n_chunks - 1}", field="chunk")
    return np.array_split(np.arange(int(cfg["heatmap"]["n_theta"])), n_chunks)[chunk]


def sweep_points(system: AffineSystem, word: str, M1: float, mode: str, poles_list: list[np.ndarray],
                 solver: str = "highs") -> list[dict]:
    """Optimal ``μ2`` (LP, ``s0 = 0``) for each pole set; the LP is built once and only its ``L`` values change."""
    model = None
    rows = []
    for poles in poles_list:
        t0 = time.perf_counter()
        pp = place_observer(system.A, system.C, poles)
        rec = {"status": "placement_failed", "mu2": np.nan, "message": pp.message}
        if pp.ok:
            if model is None:
                model = AugmentedLP(system, word, M1, pp.L, mode=mode)
            else:
                model.set_L(pp.L)
            sol = model.solve(solver)
            rec = {"status": sol.status if sol.status in ("optimal", "infeasible") else "solver_failed",
                   "mu2": float(sol.objective) if sol.optimal else (np.inf if sol.status == "infeasible" else np.nan),
                   "message": "" if sol.optimal else sol.status}
        rec["time"] = time.perf_counter() - t0
        rows.append(rec)
    return rows


def step_heatmap_chunk(config, variant: str, chunk: int, out_csv: str | Path) -> pd.DataFrame:
    """P2-F3a, one θ-chunk of one variant."""
    cfg = load_config(config)
    system = acc_system()
    mode, word = variant_word(cfg["heatmap"]["word"], variant)
    r_grid, th_grid = heatmap_grid(cfg)
    pts, poles = [], []
    for j in theta_chunk(cfg, chunk):
        for r in r_grid:
            pts.append((r, th_grid[j]))
            poles.append(heatmap_poles(r, th_grid[j]))
    recs = sweep_points(system, word, float(cfg["mu1"]), mode, poles, cfg["heatmap"]["solver"])
    df = pd.DataFrame([{"variant": variant, "word": word, "mode": mode, "r": r, "theta": th, **rec}
                       for (r, th), rec in zip(pts, recs)])
    Path(out_csv).parent.mkdir(parents=True, exist_ok=True)
    df.to_csv(out_csv, index=False)
    return df


def step_heatmap_merge(inputs: list[str], out_csv: str | Path) -> pd.DataFrame:
    df = pd.concat([pd.read_csv(p, keep_default_na=False, na_values=["nan", "NaN"]) for p in inputs],
                   ignore_index=True).sort_values(["variant", "theta", "r"])
    df.to_csv(out_csv, index=False)
    return df


def step_realaxis(config, out_csv: str | Path) -> pd.DataFrame:
    """P2-F3b: eigenvalues ``{0, λ, λ}`` for real ``λ`` (the heat map at θ = 0 and π, finer)."""
    cfg = load_config(config)
    system = acc_system()
    lam_max = float(cfg["realaxis"]["lam_max"])
    lam = np.linspace(-lam_max, lam_max, int(cfg["realaxis"]["n"]))
    den = cfg["realaxis"].get("grid_denominator")
    if den:  # the grid k / den as well (exact points, e.g. the paper's -10/14 and 13/14)
        k = np.arange(-int(np.floor(lam_max * den)), int(np.floor(lam_max * den)) + 1)
        lam = np.unique(np.concatenate([lam, k / den]))
    frames = []
    for variant in cfg["heatmap"]["variants"]:
        mode, word = variant_word(cfg["heatmap"]["word"], variant)
        recs = sweep_points(system, word, float(cfg["mu1"]), mode, [np.array([0.0, x, x]) for x in lam],
                            cfg["heatmap"]["solver"])
        frames.append(pd.DataFrame([{"variant": variant, "word": word, "lam": x, **rec} for x, rec in zip(lam, recs)]))
    df = pd.concat(frames, ignore_index=True)
    df.to_csv(out_csv, index=False)
    return df


def constant_interval(lam: np.ndarray, mu2: np.ndarray, tol: float) -> list[float] | None:
    """Largest interval of ``λ`` (grid points, failures breaking it) on which ``μ2`` equals its minimum."""
    finite = np.isfinite(mu2)
    if not finite.any():
        return None
    best = np.nanmin(np.where(finite, mu2, np.nan))
    at_min = finite & (np.abs(mu2 - best) <= tol)
    runs, start = [], None
    for i, ok in enumerate(at_min):
        if ok and start is None:
            start = i
        if (not ok or i == len(at_min) - 1) and start is not None:
            end = i if ok else i - 1
            runs.append((start, end))
            start = None
    s, e = max(runs, key=lambda se: lam[se[1]] - lam[se[0]])
    return [float(lam[s]), float(lam[e])]


# ---------------------------------------------------------------------------
# Step: checks (P2-S0, P2-SOLVER)
# ---------------------------------------------------------------------------

def step_checks(config, out_json: str | Path) -> dict:
    """P2-S0 and P2-SOLVER on the F2 worst-case word with the pole-placement ``L``."""
    cfg = load_config(config)
    system = acc_system()
    M1 = float(cfg["mu1"])
    wc = worst_case_word(validate_language(cfg["f2_words"]))
    pp = place_observer(system.A, system.C, np.asarray(cfg["init_poles"], float))
    lay = UncertaintyLayout(len(wc), system.nw, system.nv, system.n)
    rad = lay.radius(system.eta_w, system.eta_v, M1)
    rng = np.random.default_rng(int(cfg["seed"]))
    deltas = sample_uncertainty(lay, rad, rng, cfg["noise"], size=int(cfg["runs"]))
    x0 = np.asarray(cfg["x0"], float)

    def errors(sch):
        return np.stack([simulate_run(system, sch, wc, d, x0).error for d in deltas])

    out: dict[str, Any] = {"word": wc, "L": pp.L.tolist(), "poles": cfg["init_poles"]}
    # --- P2-S0: optimal μ2 and error for several s0 (LP with HiGHS)
    base = AugmentedLP(system, wc, M1, pp.L)
    sol0 = base.solve().require_optimal("s0 = 0")
    g0 = base.gains(sol0)
    err0 = errors(schedule_from_augmented(system, g0))
    s0_rows = []
    for s0 in cfg["s0_samples"]:
        s0 = np.asarray(s0, float)
        m = AugmentedLP(system, wc, M1, pp.L, s0=s0)
        sol = m.solve().require_optimal(f"s0 = {s0}")
        g = m.gains(sol)
        err = errors(schedule_from_augmented(system, g))
        # the exact correspondence: same M, ν shifted by M (z0(0) - z0(s0)) gives the identical estimator
        aug = AugmentedStacking(system, wc, pp.L, "theorem2")
        z0 = aug.Zs.reshape(-1, system.n) @ s0
        gm = AugmentedGains(wc, g0.L, s0, g0.M, g0.nu - g0.M @ z0, "theorem2")
        F0, u00 = augmented_to_time_based(system, g0)
        Fm, u0m = augmented_to_time_based(system, gm)
        s0_rows.append({"s0": s0.tolist(), "mu2": float(sol.objective),
                        "certified_mu2": certify_schedule(system, schedule_from_augmented(system, g), [wc], M1).mu2,
                        "max_error_difference_solver_pick": float(np.abs(err - err0).max()),
                        "max_gain_difference_M": float(np.abs(g.M - g0.M).max()),
                        "mapped_solution_F_difference": float(max(np.abs(Fm - F0).max(), np.abs(u0m - u00).max()))})
    out["s0"] = {"mu2_s0_zero": float(sol0.objective), "rows": s0_rows,
                 "mu2_spread": float(max(abs(r["mu2"] - sol0.objective) for r in s0_rows))}
    # --- P2-SOLVER: same LP (L, s0 = 0 fixed) with HiGHS, Clarabel, IPOPT
    sols = {}
    for solver in cfg["solvers"]:
        if solver == "ipopt":
            res = solve_free_ipopt(base, g0, float(sol0.objective), free_L=False, free_s0=False)
            g, mu2, it, tt = res.gains, res.mu2, res.iterations, res.solve_time
            # IPOPT starts from the HiGHS optimum; also from zero gains to see where an interior method lands
            gz = AugmentedGains(wc, g0.L, g0.s0, np.zeros_like(g0.M), np.zeros_like(g0.nu), "theorem2")
            resz = solve_free_ipopt(base, gz, 10.0, free_L=False, free_s0=False)
            sols["ipopt_from_zero"] = (resz.gains, resz.mu2, resz.iterations, resz.solve_time)
        else:
            sol = base.solve(solver).require_optimal(solver)
            g, mu2, it, tt = base.gains(sol), float(sol.objective), sol.iterations, sol.solve_time
        sols[solver] = (g, mu2, it, tt)
    rows = {}
    ref_F = None
    for name, (g, mu2, it, tt) in sols.items():
        sch = schedule_from_augmented(system, g)
        F, _ = sch.word_matrices(wc)
        err = errors(sch)
        ref_F = F if ref_F is None else ref_F
        rows[name] = {"mu2": mu2, "certified_mu2": certify_schedule(system, sch, [wc], M1).mu2,
                      "iterations": it, "solve_time": tt, "max_abs_error": float(np.abs(err).max()),
                      "rms_error": float(np.sqrt(np.mean(err ** 2))),
                      "M_difference_to_first": float(np.abs(g.M - sols[cfg["solvers"][0]][0].M).max()),
                      "F_difference_to_first": float(np.abs(F - ref_F).max())}
    out["solver"] = rows
    Path(out_json).write_text(json.dumps(out, indent=2, default=float) + "\n")
    return out


# ---------------------------------------------------------------------------
# Step: values
# ---------------------------------------------------------------------------

def step_values(config, designs_json, simulation_npz, heatmap_csv, realaxis_csv, checks_json, out_json) -> dict:
    """Our value for every P2 claim, with the evidence in the notes."""
    cfg = load_config(config)
    tol = float(cfg["mu2_tol"])
    d = json.loads(Path(designs_json).read_text())
    sim = np.load(simulation_npz)
    hm = pd.read_csv(heatmap_csv)
    ra = pd.read_csv(realaxis_csv)
    ck = json.loads(Path(checks_json).read_text())
    f1, f2 = d["f1"], d["f2"]
    v: dict[str, Any] = {}
    fmt = lambda e: "{" + ", ".join(f"{a:.3f}{b:+.3f}j" if abs(b) > 1e-9 else f"{a:.3f}" for a, b in e) + "}"  # noqa: E731
    a1 = f1["augmented_free"]
    v["f1_mu2_augmented"] = {"value": a1["certified_mu2"], "note": (
        f"IPOPT (L, s0 free) from the LP at the pole-placement L (poles {cfg['init_poles']}): "
        f"{a1['ipopt_status']}, {a1['iterations']} iterations, {a1['solve_time']:.2f} s; certified from the "
        f"converted time-based gains.")}
    v["f1_mu2_time"] = {"value": f1["time"]["certified_mu2"], "note": "time-based LP (HiGHS), certified"}
    v["f1_L"] = {"value": a1["L"], "note": f"eig(A - LC) = {fmt(a1['eig_A_minus_LC'])}; L is not unique: the "
                 f"LP optimum is the same for every L (augmented = time-based for fixed L, s0)"}
    v["f1_s0"] = {"value": a1["s0"], "note": "s0 does not affect the optimum (P2-S0), so IPOPT leaves it wherever "
                  "the initial guess and the barrier path put it"}
    v["f1_strictly_causal_mu2"] = f1["strictly_causal_mu2"]
    v["f1_process_noise_identity_mu2"] = f1["process_noise_identity_mu2"]
    a2 = f2["augmented_free"]
    ob = f2["one_based"]
    leak = f2["leak"]
    leak_txt = "; ".join(f"{k}: " + (f"design mu2 {e['design_mu2']:.6g}, certified as run (hold) {e['certified_mu2']:.6g}"
                                     if "design_mu2" in e else e["status"]) for k, e in leak.items())
    v["f2_mu2_augmented"] = {"value": a2["certified_mu2"], "note": (
        f"Lower bound: for fixed L, s0 the map (M, nu) <-> time-based (F, u0) is a bijection, so no augmented "
        f"estimator beats the time-based optimum {f2['time']['certified_mu2']:.6g} on {f2['worst_case_word']}; "
        f"IPOPT (L, s0 free) reaches it. Reading the word's missing positions as 1-based time indices "
        f"(word {ob['word']}, missing k = 2, 3 as in the Fig. 2 caption) gives augmented "
        f"{ob['augmented_free']['certified_mu2']:.6g} and time-based {ob['time_mu2']:.6g}; those "
        f"gains run on the true word {f2['worst_case_word']} guarantee only "
        f"{ob['certified_on_true_words'][f2['worst_case_word']]:.6g}. Leak reading (constant L at the missing "
        f"steps, measurement inside s): {leak_txt}.")}
    v["f2_mu2_time"] = {"value": f2["time"]["certified_mu2"], "note": "time-based LP (HiGHS), certified"}
    v["f2_mu2_one_based_augmented"] = ob["augmented_free"]["certified_mu2"]
    v["f2_mu2_one_based_time"] = ob["time_mu2"]
    rel = ("larger" if f2["time"]["certified_mu2"] > a2["certified_mu2"] + tol else
           "equal" if abs(f2["time"]["certified_mu2"] - a2["certified_mu2"]) <= 1e-5 else "smaller")
    v["f2_time_vs_augmented"] = {"value": rel, "note": (
        f"time-based {f2['time']['certified_mu2']:.6g} vs augmented {a2['certified_mu2']:.6g} on the same word; "
        f"'larger' only when the two are designed for different words (time-based {f2['worst_case_word']}, augmented "
        f"{ob['word']}: {f2['time']['certified_mu2']:.6g} vs {ob['augmented_free']['certified_mu2']:.6g})")}
    v["f2_L"] = {"value": a2["L"], "note": f"eig(A - LC) = {fmt(a2['eig_A_minus_LC'])}; not unique (any L is optimal)"}
    # heat map
    main = hm[hm["variant"] == "theorem2"]
    ok = main[main["status"] == "optimal"]
    fails = main[main["status"] == "placement_failed"]
    mu = ok["mu2"].to_numpy(float)
    parts = []
    for var, g in hm.groupby("variant"):
        okv = g[g["status"] == "optimal"]["mu2"]
        parts.append(f"{var} ({g['word'].iloc[0]}): mu2 in [{okv.min():.6g}, {okv.max():.6g}] on {len(okv)} points, "
                     f"{int((g['status'] == 'infeasible').sum())} infeasible, "
                     f"{int((g['status'] == 'placement_failed').sum())} placement failures")
    v["f3a_mu2_region"] = {"value": float(np.min(mu)), "note": (
        f"min over the {len(main)}-point grid (r in [0, {cfg['heatmap']['r_max']}], theta in [0, pi]); spread "
        f"{np.ptp(mu):.2e}: mu2 does not depend on L at all (bijection), so there is no region. "
        + "; ".join(parts) + f". Placement fails where a pole would be repeated more than rank C = 2 times "
        f"(r = 0: {len(fails)} points).")}
    v["f3a_mu2_spread"] = float(np.ptp(mu))
    v["f3a_placement_failures"] = int(len(fails))
    mg = hm[(hm["variant"] == "masked_gain") & (hm["status"] == "optimal")]
    if len(mg):
        vmin = float(mg["mu2"].min())
        at_min = int((mg["mu2"] <= vmin + tol).sum())
        v["f3a_mu2_region_masked_gain"] = {"value": vmin, "note": (
            f"'masked_gain' reading: mu2 = {vmin:.6g} on {at_min} of {len(mg)} solved grid points (a region around "
            f"the origin), up to {mg['mu2'].max():.4g} outside; "
            f"{int((hm[hm['variant'] == 'masked_gain']['status'] == 'infeasible').sum())} infeasible points")}
    # real axis
    notes = []
    interval = None
    for var, g in ra.groupby("variant"):
        g = g.sort_values("lam")
        mu2 = np.where(g["status"] == "optimal", g["mu2"].to_numpy(float), np.nan)
        iv = constant_interval(g["lam"].to_numpy(float), mu2, tol)
        failed = g[g["status"] == "placement_failed"]["lam"].tolist()
        notes.append(f"{var}: constant on {iv} (placement failed at lambda = {failed})")
        if var == "theorem2":
            interval = iv
        if var == "masked_gain":
            # λ = 0 (a triple pole) cannot be placed; it does not break the interval
            lam_all = g["lam"].to_numpy(float)
            placed = (g["status"] != "placement_failed").to_numpy()
            fine = constant_interval(lam_all[placed], mu2[placed], tol)
            den = cfg["realaxis"].get("grid_denominator")
            on_grid = placed & (np.abs(lam_all * den - np.round(lam_all * den)) < 1e-9) if den else placed
            coarse = constant_interval(lam_all[on_grid], mu2[on_grid], tol)
            v["f3b_interval_masked_gain"] = {"value": coarse, "note": (
                f"'masked_gain' reading (Appendix with Phi = A - LC at every step, measurement gain zeroed at the "
                f"missing steps), on the grid lambda = k/{den}: mu2 stays at its minimum {np.nanmin(mu2):.6g} on "
                f"{coarse}; lambda = 0 (a triple pole that cannot be placed with rank C = 2) is skipped")}
            v["f3b_interval_masked_gain_fine"] = {"value": fine, "note": (
                f"same reading on all {int(placed.sum())} placeable real eigenvalues (step "
                f"{2 * float(cfg['realaxis']['lam_max']) / (int(cfg['realaxis']['n']) - 1):g} plus the k/{den} grid): "
                f"mu2 = {np.nanmin(mu2):.6g} on {fine}, a slightly wider interval than the one the k/{den} grid "
                f"can show, so the published endpoints are the grid points next to the true edges")}
    # the interval across the single failure point λ = 0 (triple pole) is the whole axis
    g = ra[ra["variant"] == "theorem2"]
    okg = g[g["status"] == "optimal"]
    whole = [float(okg["lam"].min()), float(okg["lam"].max())] if np.ptp(okg["mu2"]) <= tol else interval
    v["f3b_interval"] = {"value": whole, "note": (
        f"{cfg['realaxis']['n']} real eigenvalue pairs {{0, lambda, lambda}}; mu2 = {okg['mu2'].min():.6g} at every "
        f"placeable lambda (spread {np.ptp(okg['mu2']):.1e}); " + "; ".join(notes) + ".")}
    # S0
    s0 = ck["s0"]
    v["s0_mu2_unchanged"] = {"value": "unchanged" if s0["mu2_spread"] <= tol else "changed", "note": (
        f"optimal mu2 for s0 in {[r['s0'] for r in s0['rows']]}: {[round(r['mu2'], 9) for r in s0['rows']]} vs "
        f"{s0['mu2_s0_zero']:.9g} at s0 = 0")}
    exact = max(r["mapped_solution_F_difference"] for r in s0["rows"])
    pick = max(r["max_error_difference_solver_pick"] for r in s0["rows"])
    v["s0_error_unchanged"] = {"value": "unchanged" if exact <= 1e-9 else "changed", "note": (
        f"(M, nu) optimal for s0 = 0 maps to (M, nu - M z0(s0)), an optimum for any s0 with the identical "
        f"estimator (time-based gains differ by {exact:.1e}); the solver's own pick at another s0 differs in its "
        f"errors by up to {pick:.3g} (another of the many optima)")}
    sv = ck["solver"]
    mus = [r["mu2"] for r in sv.values()]
    v["solver_mu2_same"] = {"value": "same" if np.ptp(mus) <= 1e-6 else "different", "note": (
        "; ".join(f"{k}: mu2 {r['mu2']:.9g} (certified {r['certified_mu2']:.9g}), max|xi| {r['max_abs_error']:.4g}, "
                  f"rms {r['rms_error']:.4g}, |dM| {r['M_difference_to_first']:.3g}" for k, r in sv.items()))}
    v["solver_gains_differ"] = {"value": "different" if max(r["F_difference_to_first"] for r in sv.values()) > 1e-4
                                else "same", "note": "largest time-based gain difference to HiGHS: "
                                f"{max(r['F_difference_to_first'] for r in sv.values()):.3g}"}
    v["runtime_equivalence"] = {"value": float(max(sim["f1/runtime_max_diff"], sim["f2/runtime_max_diff"])),
                                "note": "max |x̂ (augmented recursions) - x̂ (converted time-based)| over 20 runs"}
    write_values(out_json, v)
    return v


# ---------------------------------------------------------------------------
# Figures
# ---------------------------------------------------------------------------

def _levels(T: int, M1: float, mu2: float) -> np.ndarray:
    lev = np.full(T + 1, mu2)
    lev[0] = lev[-1] = M1
    return lev


def figure_trajectories(config, designs_json, simulation_npz, fig: str, pdf: str | Path, png: str | Path) -> None:
    """P2-F1 / P2-F2: augmented (left) vs time-based (right), same draws, certified guarantee bars.

    For F2 a third column shows the 1-based-reading design run on the true data.
    """
    import matplotlib.pyplot as plt

    from eqrec.studies.plotting import paper_style, save_figure, trajectory_panel

    cfg = load_config(config)
    paper_style()
    d = json.loads(Path(designs_json).read_text())[fig]
    sim = np.load(simulation_npz)
    M1 = float(cfg["mu1"])
    cols = [("augmented_free", f"augmented (IPOPT), $\\mu_2$ = {d['augmented_free']['certified_mu2']:.4g}",
             d["augmented_free"]["certified_mu2"], "C0"),
            ("time", f"time-based, $\\mu_2$ = {d['time']['certified_mu2']:.4g}", d["time"]["certified_mu2"], "C1")]
    if fig == "f2" and "f2/one_based" in sim.files:
        c = d["one_based"]["certified_on_true_words"][d["worst_case_word"]]
        cols.append(("one_based", f"1-based reading ({d['one_based']['word']}) on true data,\ncertified {c:.4g}",
                     c, "C3"))
    errs0 = sim[f"{fig}/time"]
    T = errs0.shape[1] - 1
    f, axes = plt.subplots(3, len(cols), figsize=(3.3 * len(cols), 6.0), sharex=True, squeeze=False,
                           layout="constrained")
    for j, (name, title, mu2, color) in enumerate(cols):
        trajectory_panel(axes[:, j], sim[f"{fig}/{name}"], _levels(T, M1, mu2), title, color=color,
                         ylabels=(j == 0))
    handles, labels = axes[0, 0].get_legend_handles_labels()
    f.legend(handles, ["estimation error", "certified guarantee"], loc="outside lower center", ncol=2)
    f.suptitle(f"{'no missing data' if fig == 'f1' else 'language ' + str(d['language'])}: "
               f"{errs0.shape[0]} runs, same draws for every estimator")
    save_figure(f, pdf, png)


def figure_heatmap(config, heatmap_csv, pdf: str | Path, png: str | Path) -> None:
    """P2-F3a: optimal μ2 over the eigenvalue pair ``r e^{±jθ}`` per variant; failures marked."""
    import matplotlib.pyplot as plt

    from eqrec.studies.plotting import paper_style, save_figure

    paper_style()
    df = pd.read_csv(heatmap_csv)
    variants = list(dict.fromkeys(df["variant"]))
    f, axes = plt.subplots(1, len(variants), figsize=(3.9 * len(variants), 3.2), squeeze=False,
                           layout="constrained")
    for ax, var in zip(axes[0], variants):
        g = df[df["variant"] == var]
        x = g["r"] * np.cos(g["theta"])
        y = g["r"] * np.sin(g["theta"])
        ok = g["status"] == "optimal"
        mu = g["mu2"].where(ok)
        vmin, vmax = np.nanmin(mu), np.nanmax(mu)
        if vmax - vmin < 1e-6:
            vmin, vmax = vmin - 0.05, vmax + 0.05
        sc = ax.scatter(x[ok], y[ok], c=mu[ok], s=9, marker="s", cmap="viridis", vmin=vmin, vmax=vmax)
        inf = g["status"] == "infeasible"
        ax.scatter(x[inf], y[inf], s=9, marker="s", color="0.8", label="LP infeasible")
        fl = g["status"] == "placement_failed"
        ax.scatter(x[fl], y[fl], s=25, marker="x", color="red", label="placement failed")
        ax.set_aspect("equal")
        ax.set_xlabel(r"Re $\lambda$")
        if ax is axes[0][0]:
            ax.set_ylabel(r"Im $\lambda$")
        ax.set_title(f"{var} (word {g['word'].iloc[0]})")
        f.colorbar(sc, ax=ax, label=r"optimal $\mu_2$", shrink=0.7, location="bottom")
    handles, labels = [], []
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            if lab not in labels:
                handles.append(h)
                labels.append(lab)
    f.legend(handles, labels, loc="outside upper center", ncol=len(labels))
    save_figure(f, pdf, png)


def figure_realaxis(config, realaxis_csv, pdf: str | Path, png: str | Path) -> None:
    """P2-F3b: optimal μ2 against a real double eigenvalue λ (third eigenvalue at 0)."""
    import matplotlib.pyplot as plt

    from eqrec.studies.plotting import paper_style, save_figure

    paper_style()
    df = pd.read_csv(realaxis_csv)
    f, ax = plt.subplots(figsize=(5, 2.8))
    for i, (var, g) in enumerate(df.groupby("variant", sort=False)):
        g = g.sort_values("lam")
        mu = np.where(g["status"] == "optimal", g["mu2"], np.nan)
        ax.plot(g["lam"], mu, marker=".", ms=2, color=f"C{i}", label=f"{var} ({g['word'].iloc[0]})")
        inf = g["status"] == "infeasible"
        if inf.any():
            ax.plot(g["lam"][inf], np.full(inf.sum(), np.nanmax(df["mu2"].replace(np.inf, np.nan)) * 1.05), "|",
                    color=f"C{i}", label=f"{var}: LP infeasible")
        fl = g["status"] == "placement_failed"
        ax.plot(g["lam"][fl], np.full(fl.sum(), 1.0), "x", color="red",
                label="placement failed" if i == 0 else None)
    ax.set_xlabel(r"real eigenvalue $\lambda$ (double), third at 0")
    ax.set_ylabel(r"optimal $\mu_2$")
    ax.legend(fontsize=6)
    save_figure(f, pdf, png)


# ---------------------------------------------------------------------------
# Command line
# ---------------------------------------------------------------------------

def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m eqrec.studies.p2", description=__doc__.split("\n")[0])
    sub = ap.add_subparsers(dest="step", required=True)

    def add(name, *args):
        p = sub.add_parser(name)
        p.add_argument("--config", required=True)
        for a in args:
            p.add_argument(a, required=True)
        return p

    add("designs", "--out", "--npz")
    add("simulate", "--designs", "--out")
    p = add("heatmap-chunk", "--variant", "--out")
    p.add_argument("--chunk", type=int, required=True)
    p = sub.add_parser("heatmap-merge")
    p.add_argument("inputs", nargs="+")
    p.add_argument("--out", required=True)
    add("realaxis", "--out")
    add("checks", "--out")
    add("values", "--designs", "--simulation", "--heatmap", "--realaxis", "--checks", "--out")
    p = add("figure-trajectories", "--designs", "--simulation", "--fig", "--pdf", "--png")
    add("figure-heatmap", "--heatmap", "--pdf", "--png")
    add("figure-realaxis", "--realaxis", "--pdf", "--png")
    a = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s %(message)s")
    t0 = time.perf_counter()
    if a.step == "designs":
        step_designs(a.config, a.out, a.npz)
    elif a.step == "simulate":
        step_simulate(a.config, a.designs, a.out)
    elif a.step == "heatmap-chunk":
        step_heatmap_chunk(a.config, a.variant, a.chunk, a.out)
    elif a.step == "heatmap-merge":
        step_heatmap_merge(a.inputs, a.out)
    elif a.step == "realaxis":
        step_realaxis(a.config, a.out)
    elif a.step == "checks":
        step_checks(a.config, a.out)
    elif a.step == "values":
        step_values(a.config, a.designs, a.simulation, a.heatmap, a.realaxis, a.checks, a.out)
    elif a.step == "figure-trajectories":
        figure_trajectories(a.config, a.designs, a.simulation, a.fig, a.pdf, a.png)
    elif a.step == "figure-heatmap":
        figure_heatmap(a.config, a.heatmap, a.pdf, a.png)
    elif a.step == "figure-realaxis":
        figure_realaxis(a.config, a.realaxis, a.pdf, a.png)
    log.info("step %s done in %.2f s", a.step, time.perf_counter() - t0)
    return 0


if __name__ == "__main__":
    sys.exit(main())
