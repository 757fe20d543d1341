"""P2 study: the state-augmented estimator paper (Hassaan, Shen, Yong, ACC 2019; targets P2-*).

Pipeline steps (``step_<name>``; one per rule of ``workflow/rules/p2.smk``, run by
:mod:`eqrec.studies.pipeline.harness`), each ``step(cfg, inputs, outputs, wildcards)``
with ``cfg`` the validated ``p2`` section:

``designs``     P2-F1/F2 designs: time-based LP, augmented LP (pole-placement ``L``), augmented IPOPT
                (``L``, ``s0`` free), and the readings of the text (:mod:`eqrec.studies.p2.readings`).
``simulate``    Monte Carlo, every estimator on the same draws (core simulator).
``checks``      P2-S0 and P2-SOLVER.
``printed``     the paper's printed Fig. 2 ``L`` (read from ``config/claims.yaml``, where published numbers
                live) under ``theorem2`` and ``masked_gain``; the ``masked_gain`` gains certified as the
                estimator that runs; how ``masked_gain`` at ``r = 0`` depends on which nilpotent ``L``.
``heatmap_chunk`` / ``heatmap_merge`` / ``realaxis``   P2-F3a/F3b sweeps (:mod:`eqrec.studies.p2.sweeps`).
``values``      our value of every P2 claim with its evidence (:mod:`eqrec.studies.p2.values`).
``figure_trajectories`` / ``figure_heatmap`` / ``figure_realaxis``   figures (:mod:`eqrec.studies.p2.figures`).
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from eqrec.arrivals.draws import ArrivalTrace, uniform_words
from eqrec.bounds.certify import certify_schedule
from eqrec.bounds.gains import schedule_from_word_gains
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import validate_language, worst_case_word
from eqrec.simulate.loop import closed_loop, monte_carlo, sample_uncertainty, simulate_run
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.systems.examples import acc_system
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.design import design_augmented
from eqrec.design.augmented.guarantee import OPTIMUM_ATOL, OPTIMUM_RTOL, best_guarantee_among_optima
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.model import AugmentedGains, AugmentedStacking
from eqrec.design.augmented.runtime import augmented_to_time_based, schedule_from_augmented
from eqrec.estimators.augmented import AugmentedEstimator
from eqrec.design.augmented.nlp import solve_free_ipopt
from eqrec.design.observers import deadbeat_observer, place_observer
from eqrec.design.prefix.time_based import design_time_based
from eqrec.errors import EqrecError
from eqrec.studies.claims.published import published_value
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import write_json, write_npz
from eqrec.studies.p2.readings import one_based_word, retarget

log = get_logger("p2")


def _eig(system: AffineSystem, L: np.ndarray) -> list[list[float]]:
    ev = np.linalg.eigvals(system.A - np.asarray(L) @ system.C)
    ev = ev[np.lexsort((ev.imag, ev.real))]
    return [[float(e.real), float(e.imag)] for e in ev]


def _gains_npz(prefix: str, system: AffineSystem, g: AugmentedGains, runtime: str | None = None) -> dict:
    """The gains and their converted time-based form (``runtime`` as in ``augmented_to_time_based``)."""
    return {**{f"{prefix}/{k}": getattr(g, k) for k in ("M", "nu", "L", "s0")},
            **_schedule_npz(prefix, g.word, *augmented_to_time_based(system, g, runtime)),
            f"{prefix}/mode": np.array(g.mode)}


def _schedule_npz(prefix: str, word: str, F: np.ndarray, u0: np.ndarray) -> dict:
    """A time-based schedule ``(F, u0)`` of one word."""
    return {f"{prefix}/F": F, f"{prefix}/u0": u0, f"{prefix}/word": np.array(word)}


# --------------------------------------------------------------------------- designs

def _augmented_entry(system, d) -> dict:
    g: AugmentedGains = d.augmented.gains
    cert, x = d.certificate, d.augmented
    return {"design_mu2": d.mu2, "certified_mu2": cert.mu2, "certified_terminal": cert.terminal,
            "worst_case_word": d.worst_case_word, "mode": x.mode, "L": g.L[0].tolist(),
            "eig_A_minus_LC": _eig(system, g.L[0]), "s0": g.s0.tolist(), "solver": d.solution.solver,
            "iterations": d.solution.iterations, "solve_time": d.solution.solve_time,
            **{k: getattr(x, k) for k in ("ipopt_status", "initial_mu2", "initial_guess")},
            "poles": [[p.real, p.imag] for p in x.poles or []], "certified_words": list(cert.words)}


def step_designs(cfg, inputs, outputs, wildcards) -> dict:
    """P2-F1, P2-F2 and the readings: every design certified from its time-based form."""
    system = acc_system()
    mu1, poles = float(cfg["mu1"]), np.asarray(cfg["init_poles"], float)
    out: dict[str, Any] = {"system": system.to_dict(), "mu1": mu1, "init_poles": poles.tolist()}
    arrays: dict[str, np.ndarray] = {}
    for fig, key in (("f1", "f1_words"), ("f2", "f2_words")):
        language = validate_language(cfg[key], length=int(cfg["T"]))
        wc = worst_case_word(language)
        tb = design_time_based(system, language, mu1, engine="tree")  # the paper-comparison row: the papers' LP
        arrays.update(_schedule_npz(f"{fig}/time", wc, *tb.schedule.word_matrices(wc)))
        res: dict[str, Any] = {"language": list(language), "worst_case_word": wc, "time": {
            "mu2": tb.mu2, "certified_mu2": tb.certificate.mu2, "solve_time": tb.solve_time,
            "iterations": tb.solution.iterations}}
        for name, Lspec in (("augmented_lp", None), ("augmented_free", "free")):
            t0 = time.perf_counter()
            d = design_augmented(system, language, mu1, L=Lspec, poles=poles)
            res[name] = {**_augmented_entry(system, d), "wall_time": time.perf_counter() - t0}
            arrays.update(_gains_npz(f"{fig}/{name}", system, d.augmented.gains))
            log.info("%s %s: mu2 = %.9g (certified %.9g)", fig, name, d.mu2, d.certificate.mu2)
        if fig == "f2":
            # Reading 1: word positions read as 1-based time indices (caption: k = 2 and 3).
            w1 = one_based_word(wc)
            d1 = design_augmented(system, [w1], mu1, L="free", poles=poles)
            g1 = d1.augmented.gains
            arrays.update(_gains_npz("f2/one_based", system, g1))
            # What the 1-based design really guarantees on the true worst-case word.
            on_true = certify_schedule(system, retarget(schedule_from_augmented(system, g1), w1, wc), [wc], mu1)
            res["one_based"] = {"word": w1, "time_mu2": design_time_based(system, [w1], mu1).mu2,
                                "augmented_free": _augmented_entry(system, d1),
                                "certified_on_true_words": {wc: float(on_true.words[wc].bounds.max())}}
            # Reading 2: constant L kept at the missing steps with the measurement in the s-dynamics (leak).
            res["leak"] = {}
            for name, Lspec in (("leak_lp", None), ("leak_free", "free")):
                try:
                    dl = design_augmented(system, language, mu1, L=Lspec, poles=poles, mode="leak")
                    gl = dl.augmented.gains
                    res["leak"][name] = {**_augmented_entry(system, dl), "certified_mu2_theorem2_runtime":
                                         _certified(system, gl, [wc], mu1, "theorem2")["mu2"]}
                    arrays.update(_gains_npz(f"f2/{name}", system, gl, "hold"))
                except EqrecError as exc:
                    res["leak"][name] = {"status": f"{type(exc).__name__}: {exc}"}
        if fig == "f1":
            # Reading 3: injection without the current measurement (M(k, k) = 0).
            m = AugmentedLP(system, wc, mu1, place_observer(system.A, system.C, poles).L, strictly_causal=True)
            res["strictly_causal_mu2"] = float(m.solve().require_optimal("strictly causal augmented design").objective)
            # Reading 4: process noise entering every state (W = I_n) instead of E = [0, Ts^2/2, Ts]^T.
            sysI = AffineSystem(A=system.A, B=system.B, f=system.f, C=system.C, E=np.eye(system.n),
                                eta_w=system.eta_w, eta_v=system.eta_v, name="ACC, W = I")
            res["process_noise_identity_mu2"] = design_time_based(sysI, language, mu1).mu2
        out[fig] = res
    write_json(outputs.json, out, timings=outputs.timings)
    write_npz(outputs.npz, **arrays)
    return out


# --------------------------------------------------------------------------- simulation

def step_simulate(cfg, inputs, outputs, wildcards) -> dict:
    """P2-F1/F2 Monte Carlo: every estimator on the same draws (same seed, same words)."""
    system = acc_system()
    mu1, runs, seed = float(cfg["mu1"]), int(cfg["runs"]), int(cfg["seed"])
    x0 = np.asarray(cfg["x0"], float)
    npz = np.load(inputs.designs)
    out: dict[str, np.ndarray] = {}
    summary = {}
    for fig, key in (("f1", "f1_words"), ("f2", "f2_words")):
        language = list(validate_language(cfg[key]))
        wc = worst_case_word(language)
        names = ["time", "augmented_lp", "augmented_free"]
        if fig == "f2":
            names += [n for n in ("one_based", "leak_lp", "leak_free") if f"f2/{n}/F" in npz.files]
        for name in names:
            pre = f"{fig}/{name}"
            designed = str(npz[f"{pre}/word"])
            sch = schedule_from_word_gains(PrefixTree([designed]), {designed: (npz[f"{pre}/F"], npz[f"{pre}/u0"])},
                                           system.n, system.p, time_based=True)
            if designed != wc:  # reading variants run on the true data
                sch = retarget(sch, designed, wc)
            errs, used = monte_carlo(system, sch, language, mu1, runs, seed, kind=cfg["noise"], x0=x0)
            out[f"{fig}/{name}"] = errs
            summary[f"{fig}/{name}"] = float(np.abs(errs).max())
        out[f"{fig}/words"] = np.array(used)
        # the runtime augmented estimator reproduces the converted one on the first runs
        g = AugmentedGains(**{k: npz[f"{fig}/augmented_free/{k}"] for k in ("L", "s0", "M", "nu")},
                           word=str(npz[f"{fig}/augmented_free/word"]), mode=str(npz[f"{fig}/augmented_free/mode"]))
        out[f"{fig}/runtime_max_diff"] = np.array(_runtime_check(system, g, language, mu1, seed, cfg["noise"], x0, 20))
    write_npz(outputs.npz, **out)
    return summary


def _runtime_check(system, gains, language, mu1, seed, kind, x0, runs) -> float:
    """Largest gap between the runtime augmented estimator and its converted prefix form on the same runs.

    Both run in the one loop (:func:`eqrec.simulate.loop.closed_loop`: ``B u``, ``V`` and time variation
    included) on the same words and draws as the Monte Carlo (seed ``seed``)."""
    sch = schedule_from_augmented(system, gains)
    rng = np.random.default_rng(seed)
    lay = UncertaintyLayout(gains.T, system.nw, system.nv, system.n)
    rad = lay.radius(system.eta_w, system.eta_v, mu1)
    worst = 0.0
    for _ in range(runs):
        word = uniform_words(rng, language)
        delta = sample_uncertainty(lay, rad, rng, kind)
        tr = simulate_run(system, sch, word, delta, x0)
        w, v, xi0 = lay.split(delta)
        run = closed_loop(system, AugmentedEstimator(system, gains), ArrivalTrace.from_pattern(word), x0, xi0, w, v)
        worst = max(worst, float(np.abs(run.xhat[1:] - tr.xhat[1:]).max()))
    return worst


# --------------------------------------------------------------------------- P2-S0, P2-SOLVER

def step_checks(cfg, inputs, outputs, wildcards) -> dict:
    """P2-S0 and P2-SOLVER on the F2 worst-case word with the pole-placement ``L``."""
    system = acc_system()
    mu1 = float(cfg["mu1"])
    wc = worst_case_word(validate_language(cfg["f2_words"]))
    pp = place_observer(system.A, system.C, np.asarray(cfg["init_poles"], float))
    lay = UncertaintyLayout(len(wc), system.nw, system.nv, system.n)
    rng = np.random.default_rng(int(cfg["seed"]))
    deltas = sample_uncertainty(lay, lay.radius(system.eta_w, system.eta_v, mu1), rng, cfg["noise"],
                                size=int(cfg["runs"]))
    x0 = np.asarray(cfg["x0"], float)

    def errors(sch):
        return np.stack([simulate_run(system, sch, wc, d, x0).error for d in deltas])

    out: dict[str, Any] = {"word": wc, "L": pp.L.tolist(), "poles": cfg["init_poles"]}
    # --- P2-S0: optimal μ2 and error for several s0 (LP with HiGHS)
    base = AugmentedLP(system, wc, mu1, pp.L)
    sol0 = base.solve().require_optimal("s0 = 0")
    g0 = base.gains(sol0)
    err0 = errors(schedule_from_augmented(system, g0))
    F0 = augmented_to_time_based(system, g0)
    Zs = AugmentedStacking(system, wc, pp.L, "theorem2").Zs.reshape(-1, system.n)
    s0_rows = []
    for s0 in cfg["s0_samples"]:
        s0 = np.asarray(s0, float)
        m = AugmentedLP(system, wc, mu1, pp.L, s0=s0)
        sol = m.solve().require_optimal(f"s0 = {s0}")
        g = m.gains(sol)
        # the exact correspondence: same M, ν shifted by M (z0(0) - z0(s0)) gives the identical estimator
        gm = AugmentedGains(wc, g0.L, s0, g0.M, g0.nu - g0.M @ (Zs @ s0), "theorem2")
        Fm = augmented_to_time_based(system, gm)
        s0_rows.append({"s0": s0.tolist(), "mu2": float(sol.objective),
                        "certified_mu2": _certified(system, g, [wc], mu1)["mu2"],
                        "max_error_difference_solver_pick": float(np.abs(
                            errors(schedule_from_augmented(system, g)) - err0).max()),
                        "max_gain_difference_M": float(np.abs(g.M - g0.M).max()),
                        "mapped_solution_F_difference": float(max(np.abs(a - b).max() for a, b in zip(Fm, F0)))})
    out["s0"] = {"mu2_s0_zero": float(sol0.objective), "rows": s0_rows,
                 "mu2_spread": float(max(abs(r["mu2"] - sol0.objective) for r in s0_rows))}
    # --- P2-SOLVER: same LP (L, s0 = 0 fixed) with HiGHS, Clarabel, IPOPT
    sols = {}
    for solver in cfg["solvers"]:
        if solver == "ipopt":
            # IPOPT starts from the HiGHS optimum; also from zero gains to see where an interior method lands
            gz = AugmentedGains(wc, g0.L, g0.s0, np.zeros_like(g0.M), np.zeros_like(g0.nu), "theorem2")
            for name, start, mu2_start in (("ipopt_from_zero", gz, 10.0), (solver, g0, float(sol0.objective))):
                res = solve_free_ipopt(base, start, mu2_start, free_L=False, free_s0=False)
                sols[name] = (res.gains, res.mu2, res.iterations, res.solve_time)
        else:
            sol = base.solve(solver).require_optimal(solver)
            sols[solver] = (base.gains(sol), float(sol.objective), sol.iterations, sol.solve_time)
    out["solver"] = {}
    ref_F = None
    for name, (g, mu2, it, tt) in sols.items():
        sch = schedule_from_augmented(system, g)
        F = sch.word_matrices(wc)[0]
        ref_F = F if ref_F is None else ref_F
        err = errors(sch)
        out["solver"][name] = {"mu2": mu2, "certified_mu2": certify_schedule(system, sch, [wc], mu1).mu2,
                               "iterations": it, "solve_time": tt, "max_abs_error": float(np.abs(err).max()),
                               "rms_error": float(np.sqrt(np.mean(err ** 2))),
                               "M_difference_to_first": float(np.abs(g.M - sols[cfg["solvers"][0]][0].M).max()),
                               "F_difference_to_first": float(np.abs(F - ref_F).max())}
    write_json(outputs.json, out, timings=outputs.timings)
    return out


# --------------------------------------------------------------------------- the printed L and the masked_gain reading

def _certified(system, gains, words, mu1, runtime: str | None = None, per_time: bool = False) -> dict:
    cert = certify_schedule(system, schedule_from_augmented(system, gains, runtime), words, mu1)
    out = {"mu2": cert.mu2, "terminal": cert.terminal,
           "per_word": {w: float(c.bounds.max()) for w, c in cert.words.items()}}
    if per_time:
        pt = cert.per_time()
        out.update(per_time=[float(x) for x in pt], worst_time=int(np.argmax(pt)))
    return out


def _among_optima(system, res, words, mu1) -> dict:
    """A :func:`best_guarantee_among_optima` result with its gains certified as run and checked optimal."""
    from eqrec.lp.robust import worst_case_abs

    G, c = AugmentedStacking(system, res.gains.word, res.gains.L, res.design_mode).error_map(
        res.gains.M, res.gains.nu, res.gains.s0)
    lay = UncertaintyLayout(len(res.gains.word), system.nw, system.nv, system.n)
    design_wc = worst_case_abs(G, c, lay.radius(system.eta_w, system.eta_v, mu1)).reshape(-1, system.n).max(axis=1)
    return {"lower": res.lower, "upper": res.upper, "exact": res.exact, "agree_until": res.agree_until,
            "design_optimum": res.design_optimum, "optimum_bound": res.optimum_bound, "design_mu2": res.design_mu2,
            "design_check": {"mu2": float(design_wc[:-1].max()), "terminal": float(design_wc[-1])},
            "certified": _certified(system, res.gains, words, mu1, res.runtime, per_time=True)}


def step_printed(cfg, inputs, outputs, wildcards) -> dict:
    """The Fig. 2 design at the paper's printed ``L``: the LP of each reading and the masked_gain gains
    certified as the estimator that runs (``hold``: the constant ``L`` kept at missing steps; ``theorem2``:
    ``L`` zeroed there)."""
    system = acc_system()
    mu1 = float(cfg["mu1"])
    pc = cfg["printed"]
    language = validate_language(cfg["f2_words"], length=int(cfg["T"]))
    wc = worst_case_word(language)
    words = sorted(set(language) | {wc})
    L = np.asarray(published_value(inputs.claims, pc["L_claim"]), float)
    out: dict[str, Any] = {"word": wc, "words": words, "L_claim": pc["L_claim"], "eig_A_minus_LC": _eig(system, L),
                           "time_mu2": design_time_based(system, language, mu1).mu2}
    # the LP's optimal gains are not unique: certify the optimum each LP solver returns
    first = cfg["heatmap"]["solver"]
    lp_solvers = [first] + [s for s in cfg["solvers"] if s in ("highs", "clarabel", "scipy") and s != first]
    for mode in ("theorem2", "masked_gain"):
        m = AugmentedLP(system, wc, mu1, L, mode=mode)
        by_solver = {}
        for solver in lp_solvers:
            sol = m.solve(solver).require_optimal(f"{mode} LP at the printed L ({solver})")
            g = m.gains(sol)
            by_solver[solver] = {"mu2": float(sol.objective), **{
                f"certified_{rt}": _certified(system, g, words, mu1, rt) for rt in ("hold", "theorem2")}}
        out[mode] = {**by_solver[first], "solver": first, "by_solver": by_solver}
        log.info("printed L, %s: LP mu2 = %.9g, certified as run (hold) %s", mode, out[mode]["mu2"],
                 {k: round(b["certified_hold"]["mu2"], 6) for k, b in by_solver.items()})
    # ... so the solver-independent quantity: the best guarantee any masked_gain optimum gives as run (an LP over
    # the optima, solved by each LP solver), its gains certified; the smallest end-of-horizon bound; recovery
    def per_solver(**options) -> dict:
        return {s: _among_optima(system, best_guarantee_among_optima(system, wc, mu1, L, solver=s, **options),
                                 words, mu1) for s in lp_solvers}

    among = {"rel_tol": OPTIMUM_RTOL, "abs_tol": OPTIMUM_ATOL,
             "runtimes": {rt: per_solver(runtime=rt) for rt in ("hold", "theorem2")},
             "terminal_theorem2": per_solver(bound="terminal"), "recover_theorem2": per_solver(recover=True)}
    out["masked_gain"]["among_optima"] = among
    log.info("printed L, masked_gain: best guarantee among the optima as run %s",
             {rt: {k: round(e["upper"], 9) for k, e in per.items()} for rt, per in among["runtimes"].items()})
    # r = 0: the nilpotent L is not unique and the masked_gain value depends on which one
    out["r0_deadbeat"] = []
    for seed in pc["deadbeat_seeds"]:
        d = deadbeat_observer(system.A, system.C, seed=seed)
        row: dict[str, Any] = {"seed": int(seed), "ok": bool(d.ok)}
        if d.ok:
            for mode in ("theorem2", "masked_gain"):
                sol = AugmentedLP(system, wc, mu1, d.L, mode=mode).solve(cfg["heatmap"]["solver"])
                row[mode] = float(sol.objective) if sol.optimal else sol.status
        out["r0_deadbeat"].append(row)
    # for the figures only (not evidence): the published Fig. 3b interval, drawn on the heat map
    out["published_interval"] = [float(x) for x in published_value(inputs.claims, pc["interval_claim"])]
    write_json(outputs.json, out)
    return out
