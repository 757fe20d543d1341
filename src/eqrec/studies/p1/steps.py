"""P1 study: the prefix-based paper (Rutledge, Yong, Ozay, ACC 2019; targets P1-* of TARGETS.md).

Pipeline steps (``step_<name>``; one per rule of ``workflow/rules/p1.smk``, run by
:mod:`eqrec.studies.pipeline.harness`), each ``step(cfg, inputs, outputs, wildcards)``
with ``cfg`` the validated ``p1`` section:

``model``       P1-T1: ACC matrices from the Table I constants (``model.json``).
``designs``     P1-M2 / P1-TIME: prefix- and time-based designs on L1, certified, timed, probed (``designs.json``).
``simulate``    P1-F1: Monte Carlo errors of both estimators on the same draws, worst-vertex checks (``simulation.npz``).
``extensions``  P1-EXT: M2*(M1), smallest M1, a finite-length language, minimum T (``extensions.json``).
``figure1``, ``figure_ext``  figures (:mod:`eqrec.studies.p1.figures`).
``values``      our value of every published P1 number with its evidence (``values.json``; the wording
                lives in ``config/claims.yaml``).
"""

from __future__ import annotations

import itertools
import time
from typing import TYPE_CHECKING, Callable

import numpy as np

from eqrec.arrivals.words import worst_case_word
from eqrec.systems.examples import ACC_CONSTANTS, acc_system
from eqrec.systems.affine import AffineSystem
from eqrec.studies.pipeline.logs import Progress, get_logger
from eqrec.studies.pipeline.outputs import read_json, write_json, write_npz

if TYPE_CHECKING:
    from eqrec.design.result import Design

log = get_logger("p1")


def design_methods() -> dict[str, Callable[..., Design]]:
    """The two designs of P1 by name: ``prefix`` (:func:`~eqrec.design.prefix.design.design_prefix`) and ``time``
    (:func:`~eqrec.design.prefix.time_based.design_time_based`).

    Returns
    -------
    dict of str to callable
        ``fn(system, language, mu1) -> Design`` per method name.
    """
    # The design, simulation and search modules are imported in the steps that use them: the model and values
    # steps design nothing (saves ~0.6 s CPU of imports, numba and the LP layer, per job).
    from eqrec.design.prefix import design, time_based

    return {"prefix": design.design_prefix, "time": time_based.design_time_based}


def system_from_config(cfg: dict) -> AffineSystem:
    """The ACC model from the Table I constants, with the config's ``acc_constants`` overrides."""
    return acc_system(**{**ACC_CONSTANTS, **cfg["acc_constants"]})


# --------------------------------------------------------------------------- P1-T1

def step_model(cfg, inputs, outputs, wildcards) -> dict:
    """P1-T1: discretise the ACC model and store its matrices."""
    sys_ = system_from_config(cfg)
    data = {"constants": {**ACC_CONSTANTS, **cfg["acc_constants"]}, **sys_.to_dict(),
            "B": sys_.B.tolist(), "eig_A": sorted(np.linalg.eigvals(sys_.A).real.tolist())}
    write_json(outputs.json, data)
    return data


# --------------------------------------------------------------------------- P1-M2 and P1-TIME

def _timed_design(fn, repeats: int) -> tuple[Design, dict]:
    """Run a design ``repeats`` times; report the best build/solve/total times."""
    runs = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        d = fn()
        runs.append((d.build_time, d.solve_time, time.perf_counter() - t0))
    build, solve, total = map(min, zip(*runs))
    return d, {"build_s": build, "solve_s": solve, "total_s": total,
               "iterations": d.solution.iterations, "solver": d.solution.solver, "repeats": repeats}


def _certified(d: Design) -> dict:
    """The design's optimal M2 and what its certificate gives (largest level, terminal error)."""
    return {"mu2": d.mu2, "certified_mu2": d.certificate.mu2, "certified_terminal": d.certificate.terminal}


def step_designs(cfg, inputs, outputs, wildcards) -> dict:
    """P1-M2 / P1-TIME: optimal M2 of the prefix- and time-based estimators on L1, per solver."""
    from eqrec.studies.searches import lower_bound_probe

    system = system_from_config(cfg)
    L1, mu1 = cfg["language"], float(cfg["mu1"])
    gap = float(cfg["probe_gap"])
    result: dict = {"language": L1, "worst_case_word": worst_case_word(L1), "M1": mu1, "designs": {}}
    for method, fn in design_methods().items():
        entry: dict = {"solvers": {}}
        for solver in cfg["solvers"]:
            log.info("%s-based design with %s", method, solver)
            # the paper-comparison rows (values, iterations, times) keep the paper's form: the tree LP
            d, timing = _timed_design(lambda: fn(system, L1, mu1, solver=solver, engine="tree"),
                                      int(cfg["timing_repeats"]) if solver == "highs" else 1)
            entry["solvers"][solver] = {**_certified(d), **timing}
            if solver == "highs":
                entry.update(**_certified(d), words=list(d.words), gains=d.schedule.to_json(), timing=timing,
                             per_time_bound=d.certificate.per_time().tolist())
                log.info("%s-based: probing M2 <= %.6f - %g", method, d.mu2, gap)
                entry["lower_bound_probe"] = {"gap": gap, "status": lower_bound_probe(
                    system, d.words, mu1, d.mu2, gap, cfg["probe_solvers"])}
                # the class engine on the same problem (eqrec.design.classes.engine): same optimum, one LP per class
                dc, timing_c = _timed_design(lambda: fn(system, L1, mu1, solver=solver), int(cfg["timing_repeats"]))
                entry["class_engine"] = {"mu2": dc.mu2, "certified_mu2": dc.certificate.mu2,
                                         "classes": dc.classes, **timing_c}
        entry["solver_spread"] = float(np.ptp([v["mu2"] for v in entry["solvers"].values()]))
        result["designs"][method] = entry
    result["variants"] = design_variants(cfg)
    write_json(outputs.json, result, timings=outputs.timings)
    return result


def design_variants(cfg: dict) -> dict:
    """Optimal M2 under readings of the paper other than ours (evidence for the claims).

    * ``rounded_matrices``: A and E as printed (4 digits) in the augmented paper, Sec. IV-A;
    * ``identity_noise_gain``: process noise on every state (``E = I``), the
      identity-gain convention of eq. (3) of the prefix-based paper.
    """
    base = system_from_config(cfg)
    L1, mu1 = cfg["language"], float(cfg["mu1"])
    rounded = AffineSystem(A=np.round(base.A, 4), C=base.C, E=np.round(base.E, 4), eta_w=base.eta_w,
                           eta_v=base.eta_v, name="ACC rounded")
    eye = AffineSystem(A=base.A, C=base.C, E=np.eye(3), eta_w=base.eta_w, eta_v=base.eta_v, name="ACC E=I")
    out, methods = {}, design_methods()
    for name, s in (("rounded_matrices", rounded), ("identity_noise_gain", eye)):
        log.info("reading %s", name)
        out[name] = {m: fn(s, L1, mu1).mu2 for m, fn in methods.items()}
    return out


# --------------------------------------------------------------------------- P1-F1

def step_simulate(cfg, inputs, outputs, wildcards) -> dict:
    """P1-F1: Monte Carlo error trajectories of both estimators (same draws) and worst-vertex checks."""
    from eqrec.simulate.loop import monte_carlo, simulate_run

    system = system_from_config(cfg)
    L1, mu1 = cfg["language"], float(cfg["mu1"])
    sim = cfg["simulation"]
    T = len(L1[0])
    x0 = np.asarray(sim["x0"], float)
    u = np.full((T, 1), float(sim["input_force"]))
    arrays: dict = {}
    for method, fn in design_methods().items():
        d = fn(system, L1, mu1, engine="tree")  # the gains of designs.json (the paper's LP)
        log.info("simulating %d runs of the %s-based estimator", sim["runs"], method)
        errs, words = monte_carlo(system, d.schedule, L1, mu1, int(sim["runs"]), int(sim["seed"]),
                                  kind="uniform", x0=x0, inputs=u)
        verrs, _ = monte_carlo(system, d.schedule, L1, mu1, int(sim["runs"]), int(sim["seed"]) + 1,
                               kind="vertex", x0=x0, inputs=u)
        cert = d.certificate.words
        attain = []  # worst-case vertex of every (word, t, i): the simulated error must attain the bound
        for w, t, i in itertools.product(L1, range(1, T + 1), range(system.n)):
            error = simulate_run(system, d.schedule, w, cert[w].worst_vertex(t, i), x0, u).error[t, i]
            attain.append(abs(abs(error) - cert[w].bounds[t, i]))
        arrays.update({f"{method}_{key}": value for key, value in (
            ("errors", errs), ("vertex_errors", verrs), ("bounds", np.stack([cert[w].bounds for w in words])),
            ("words", np.array(words)), ("mu2", d.mu2), ("attain_gap", float(max(attain))))})
    write_npz(outputs.npz, compressed=True, M1=mu1, **arrays)  # the stored key keeps its name
    return arrays


# --------------------------------------------------------------------------- P1-EXT

def step_extensions(cfg, inputs, outputs, wildcards) -> dict:
    """P1-EXT: M2*(M1) curve, smallest M1, a finite-length language, minimum recovery time."""
    from eqrec.studies.searches import min_feasible_mu1, min_recovery_time, mu2_curve

    system = system_from_config(cfg)
    L1 = cfg["language"]
    ext = cfg["extensions"]
    res, methods = {}, design_methods()
    log.info("smallest feasible M1 (exact: the class engine's Charnes-Cooper LP)")
    smallest = {m: min_feasible_mu1(system, L1, m) for m in methods}
    res["min_M1"] = {m: r.upper for m, r in smallest.items()}
    res["min_M1_bracket"] = {m: {"lower": r.lower, "upper": r.upper, "binding": r.binding}
                             for m, r in smallest.items()}
    grid = np.linspace(float(ext["M1_min_plot"]), float(ext["M1_max"]), int(ext["M1_points"]))
    res["curve"] = {"M1": grid.tolist()}
    for m in methods:
        prog = Progress(log, grid.size, f"M2*(M1) curve, {m}-based", "levels")
        res["curve"][m] = mu2_curve(system, L1, grid, m, on_point=lambda k, mu1: prog.advance())
    fin = ext["finite_language"]  # Section V: a finite-length language
    d = methods["prefix"](system, fin, float(cfg["mu1"]), fixed_length=False)
    res["finite_language"] = {"words": fin, **_certified(d), "per_word_terminal": {
        w: float(c.bounds[-1].max()) for w, c in d.certificate.words.items()}}
    res["min_T"] = []
    prog = Progress(log, len(ext["min_T_levels"]), "minimum recovery time", "levels")
    for mu1 in ext["min_T_levels"]:
        res["min_T"].append({"M1": float(mu1), "T": min_recovery_time(system, L1, float(mu1), int(ext["T_max"]))})
        prog.advance()
    write_json(outputs.json, res)
    return res


# --------------------------------------------------------------------------- values.json

def _design_evidence(entry: dict, mu1: float) -> dict:
    probe = entry["lower_bound_probe"]
    return {**{k: entry[k] for k in ("mu2", "certified_mu2", "certified_terminal")}, "M1": mu1,
            "solver_spread": entry["solver_spread"], "probe_gap": probe["gap"], "probe_status": probe["status"]}


def _within_value(sim, m: str) -> dict:
    """P1-F1: whether the simulated errors of the ``m``-based estimator stay inside its bounds."""
    errs, bounds = sim[f"{m}_errors"], sim[f"{m}_bounds"]
    return {"value": "inside" if np.all(np.abs(errs) <= bounds + 1e-9) else "outside", "evidence": {
        "runs": int(errs.shape[0]), "max_ratio": float(np.max(np.abs(errs) / np.maximum(bounds, 1e-300))),
        "attain_gap": float(sim[f"{m}_attain_gap"]), "vertex_runs": int(sim[f"{m}_vertex_errors"].shape[0])}}


def _finite_language_value(fin: dict, mu1: float) -> dict:
    """P1-EXT (Section V): "yes" when the design on the finite-length language is certified from its gains alone
    (largest level within the LP's optimum, every word's terminal error within ``mu1`` at its own end)."""
    ok = (fin["certified_mu2"] <= fin["mu2"] * (1 + 1e-9)
          and fin["certified_terminal"] <= mu1 * (1 + 1e-9))
    return {"value": "yes" if ok else "no",
            "evidence": {**{k: fin[k] for k in ("words", "mu2", "certified_mu2", "certified_terminal")}, "mu1": mu1}}


def _min_T_value(min_T: list[dict], language: list[str]) -> dict:
    """P1-EXT (Section V): "yes" when the minimum recovery time was found for some level, and the longest word
    length (the paper: T "can be longer than the longest word")."""
    found = [r for r in min_T if r["T"] is not None]
    longest = max(len(w) for w in language)
    return {"value": "yes" if found else "no",
            "evidence": {"levels": min_T, "longest_word": longest,
                         "longer_than_words": sum(1 for r in found if r["T"] > longest)}}


def step_values(cfg, inputs, outputs, wildcards) -> dict:
    """Our value of every published P1 number, with the evidence behind it (numbers only)."""
    model = read_json(inputs.model)
    des = read_json(inputs.designs, timings=inputs.designs_timings)
    ext = read_json(inputs.extensions)
    sim = np.load(inputs.simulation)
    p, t = des["designs"]["prefix"], des["designs"]["time"]
    var = des["variants"]
    mu1 = float(des["M1"])
    A, B, f, E = (np.asarray(model[k]) for k in ("A", "B", "f", "E"))

    def timing(entry):
        return {k: entry["timing"][k] for k in ("iterations", "build_s", "solve_s", "total_s", "repeats", "solver")}

    values = {
        "A": {"value": A.round(4).tolist(), "evidence": {"decimals": 4}},
        "B_scaled": {"value": (B[:, 0] * 1e3).round(4).tolist(), "evidence": {"decimals": 4, "scale": 1e3}},
        "f": {"value": f.round(4).tolist(), "evidence": {"decimals": 4}},
        "E": {"value": E[:, 0].round(4).tolist(), "evidence": {"Ts": model["constants"]["Ts"]}},
        "prefix_L1_mu2": {"value": p["mu2"], "evidence": {
            **_design_evidence(p, mu1), "rounded_matrices_mu2": var["rounded_matrices"]["prefix"],
            "identity_noise_gain_mu2": var["identity_noise_gain"]["prefix"]}},
        "time_L1_mu2": {"value": t["mu2"], "evidence": _design_evidence(t, mu1)},
        "prefix_time_s": {"value": p["timing"]["total_s"], "evidence": timing(p)},
        "prefix_iterations": {"value": p["timing"]["iterations"], "evidence": {"solver": p["timing"]["solver"]}},
        "time_time_s": {"value": t["timing"]["total_s"], "evidence": timing(t)},
        "time_iterations": {"value": t["timing"]["iterations"], "evidence": {"solver": t["timing"]["solver"]}},
        "fig1_prefix_within": _within_value(sim, "prefix"),
        "fig1_time_within": _within_value(sim, "time"),
        "fig1_prefix_lower": {"value": "prefix" if p["mu2"] < t["mu2"] else "time",
                              "evidence": {"prefix_mu2": p["mu2"], "time_mu2": t["mu2"],
                                           "ratio": p["mu2"] / t["mu2"]}},
        "min_M1_prefix": {"value": ext["min_M1"]["prefix"], "evidence": ext["min_M1_bracket"]["prefix"]},
        "finite_language_mu2": {"value": ext["finite_language"]["mu2"],
                                "evidence": {"words": ext["finite_language"]["words"]}},
        "ext_finite_language": _finite_language_value(ext["finite_language"], mu1),
        "ext_min_T": _min_T_value(ext["min_T"], des["language"]),
    }
    write_json(outputs.json, values, timings=outputs.timings)
    return values
