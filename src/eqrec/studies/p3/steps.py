r"""P3 study: the delayed/missing-data paper (Hassaan, Shen, Yong; targets P3-* of TARGETS.md).

Pipeline steps (``step_<name>``; one per rule of ``workflow/rules/p3.smk``, run by
:mod:`eqrec.studies.pipeline.harness`), each ``step(cfg, inputs, outputs, wildcards)``
with ``cfg`` the validated ``p3`` section:

``languages``   P3-LANG: Examples 1-5 (delay words -> event sequences, eqs. (2)-(3) -> reduced language
                ``L^{E'}``, prefixes (Definition 6), event matrices ``E_α``, zero patterns (7) of ``M^α``,
                ``L^α``) and the counts ``|L|``, ``|L^{E'}|``, prefix-tree nodes per depth of ``{0..τ̄}^T``
                (``languages.json``, ``examples.csv``, ``examples.md``, ``counts.csv``).
``reactor_model``    P3-BR: ZOH discretisation of the batch reactor (``reactor_model.json``).
``reactor_designs``  P3-BR: Theorem 1 / Proposition 1 with ``μ1`` free (certified global route and the
                paper's IPOPT route on (10)) and at the configured readings of ``μ1``; certificates per node,
                worst-case vertices; the bound ``max μ2 >= ‖A²‖∞ μ1`` (``reactor_designs.json``).
``augmented``   the augmented form (4) with fixed ``L^α``, ``s0``: optimum against pole placements and ``s0``
                (``augmented.json``).
``kalman``      P3-F1: proposed estimator vs the Kalman-type filters of :mod:`eqrec.estimators.kalman` on the true
                pattern, exact worst cases and sampled runs (``kalman.json``, ``kalman.npz``).
``acc``         P3-ACC: the ACC language with ``μ1 = 1`` (sum and max costs) vs P1's prefix design on the
                missing-data language, and ``μ1`` free (footnote 1) (``acc.json``).
``acc_simulate``  P3-F2: true pattern ``060000``, proposed vs P1 prefix-based estimator, same draws (``acc.npz``).
``figure1``, ``figure2``, ``strategy_figure``  figures (:mod:`eqrec.studies.p3.figures`).
``values``      our value of every published P3 number with its evidence (:mod:`eqrec.studies.p3.values`).

No mathematics here: the designs are :mod:`eqrec.design.delay.design` and
:mod:`eqrec.design.augmented.word_lp`, the languages :mod:`eqrec.arrivals.patterns`,
the filters :mod:`eqrec.estimators.kalman` (worst cases: :mod:`eqrec.simulate.filter_runs`).
"""

from __future__ import annotations

import json

import numpy as np

from eqrec.bounds.certify import certify_schedule, no_data_growth
from eqrec.arrivals.patterns import event_indices, event_matrix, event_sequence_label, gain_zero_pattern, pattern_text
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import full_delay_language, parse_delay_word
from eqrec.simulate.loop import sample_uncertainty, simulate_run
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.systems.affine import AffineSystem
from eqrec.design.cost import cost_weights
from eqrec.design.delay.design import FreeMu1Result, delay_language, design_delay, design_delay_global
from eqrec.design.report import level_table, path_levels, word_certificate
from eqrec.design.delay.ipopt import compare_free_routes, design_delay_ipopt
from eqrec.design.augmented.tree_lp import solve_augmented_delay
from eqrec.design.augmented.runtime import augmented_to_prefix
from eqrec.design.observers import place_observer
from eqrec.design.prefix.design import design_prefix
from eqrec.design.result import Design
from eqrec.estimators.kalman import GaussianDesign, make_filter
from eqrec.simulate.filter_runs import compare_with_bounds, error_maps, truncated_normal_deltas
from eqrec.systems.examples import BATCH_REACTOR_AC, BATCH_REACTOR_BC, acc_system, batch_reactor, batch_reactor_matrices
from eqrec.studies.pipeline.logs import Progress, get_logger
from eqrec.studies.pipeline.outputs import write_csv, write_json, write_npz, write_text

log = get_logger("p3")


# --------------------------------------------------------------------------- configuration


def reactor_from_config(cfg: dict) -> AffineSystem:
    """The batch reactor of Section IV-A (ZOH at ``Ts``, ``ηv``) from the config."""
    br = cfg["batch_reactor"]
    return batch_reactor(Ts=float(br["Ts"]), eta_v=float(br["eta_v"]))


def reactor_language(cfg: dict) -> tuple[str, ...]:
    """All ``(τ̄+1)^T`` delay words of the batch-reactor example."""
    br = cfg["batch_reactor"]
    return full_delay_language(int(br["horizon"]), int(br["max_delay"]))


# --------------------------------------------------------------------------- P3-LANG

def language_examples(T: int, max_delay: int) -> dict:
    """Examples 1-5 for the full delay language ``{0..τ̄}^T``: per word and per reduced sequence."""
    words = full_delay_language(T, max_delay)
    pats = [parse_delay_word(w) for w in words]
    reduced = list(delay_language(words, max_delay=max_delay))
    alpha_of = {p: k + 1 for k, p in enumerate(reduced)}
    word_rows = [{"word": w, "arrivals": list(p.arrivals), "events": list(p.events()),
                  "event_indices": list(event_indices(p)), "event_sequence": event_sequence_label(p),
                  "alpha": alpha_of[p]} for w, p in zip(words, pats)]
    seq_rows = [{"alpha": k + 1, "event_sequence": event_sequence_label(p), "event_indices": list(event_indices(p)),
                 "words": [w for w, q in zip(words, pats) if q == p],
                 "prefixes": [event_sequence_label(p, i) for i in range(1, T + 1)],
                 "event_matrix": event_matrix(p).tolist(), "M_pattern": gain_zero_pattern(p, "M"),
                 "L_pattern": gain_zero_pattern(p, "L")} for k, p in enumerate(reduced)]
    # constraint (6): sequences sharing a prefix share the gain blocks of that prefix
    tree = PrefixTree(reduced)
    shared = []
    for node in tree:
        through = [alpha_of[q] for q in reduced if node.depth <= q.T and q.prefix(node.depth) == node.prefix]
        if len(through) > 1:
            shared.append({"prefix": event_sequence_label(node.prefix), "length": node.depth, "alphas": through})
    return {"T": T, "max_delay": max_delay, "words": word_rows, "reduced": seq_rows, "shared_prefixes": shared,
            "sizes": {"L": len(words), "LE": len(pats), "LE_reduced": len(reduced),
                      "nodes_per_depth": tree.nodes_per_depth()}}


def language_counts(T: int, max_delay: int) -> dict:
    """``|L|``, ``|L^{E'}|`` and prefix-tree nodes per depth for the full language ``{0..τ̄}^T``."""
    tree = PrefixTree(delay_language(max_delay=max_delay, horizon=T))
    return {"T": T, "max_delay": max_delay, "words": (max_delay + 1) ** T, "sequences": len(tree.patterns),
            "nodes": len(tree), "nodes_per_depth": tree.nodes_per_depth()}


def _examples_markdown(ex: dict) -> str:
    lines = [f"# P3-LANG: Examples 1-5 (T = {ex['T']}, max delay = {ex['max_delay']})", "",
             f"{ex['sizes']['L']} delay words -> {ex['sizes']['LE']} event sequences (eqs. (2)-(3)) -> "
             f"{ex['sizes']['LE_reduced']} distinct sequences (the reduced language L^E').", "",
             "## Words (Examples 1 and 3)", "", "| word | arrival times | events d_0..d_k | j_k (eq. (2)) | "
             "event sequence | alpha |", "|---|---|---|---|---|---|"]
    for r in ex["words"]:
        arr = ", ".join("never" if a is None else str(a) for a in r["arrivals"])
        lines.append(f"| {r['word']} | {arr} | {' '.join(r['events'])} | {r['event_indices']} | "
                     f"{r['event_sequence']} | {r['alpha']} |")
    lines += ["", "## Reduced language L^E' (Examples 3-5)", "",
              "| alpha | event sequence | words | prefixes (Def. 6) | E_alpha | zero pattern of M | "
              "zero pattern of L |", "|---|---|---|---|---|---|---|"]
    for r in ex["reduced"]:
        E = "[" + "; ".join(" ".join(map(str, row)) for row in r["event_matrix"]) + "]"
        lines.append(f"| {r['alpha']} | {r['event_sequence']} | {', '.join(r['words'])} | {', '.join(r['prefixes'])} | "
                     f"{E} | {pattern_text(r['M_pattern'])} | {pattern_text(r['L_pattern'])} |")
    lines += ["", "## Shared prefixes (constraint (6))", "", "| prefix | length | sequences alpha |", "|---|---|---|"]
    for r in ex["shared_prefixes"]:
        lines.append(f"| {r['prefix']} | {r['length']} | {r['alphas']} |")
    return "\n".join(lines) + "\n"


def step_languages(cfg, inputs, outputs, wildcards) -> dict:
    """P3-LANG: Examples 1-5 as tables, and the language counts for a few ``(T, τ̄)``."""
    import pandas as pd  # imported here: the only step of this module writing frames (saves ~0.3-0.5 s CPU per job)

    lc = cfg["languages"]
    ex = language_examples(int(lc["example_T"]), int(lc["example_max_delay"]))
    counts = []
    prog = Progress(log, len(lc["count_sizes"]), "language counts", "sizes")
    for T, tb in lc["count_sizes"]:
        counts.append(language_counts(int(T), int(tb)))
        prog.advance()
    data = {"examples": ex, "counts": counts}
    write_json(outputs.json, data)
    rows = [{"alpha": r["alpha"], "event_sequence": r["event_sequence"], "words": " ".join(r["words"]),
             "prefixes": " ".join(r["prefixes"]), "event_matrix": json.dumps(r["event_matrix"]),
             "M_pattern": pattern_text(r["M_pattern"]), "L_pattern": pattern_text(r["L_pattern"])}
            for r in ex["reduced"]]
    write_csv(outputs.csv, pd.DataFrame(rows))
    write_text(outputs.md, _examples_markdown(ex))
    write_csv(outputs.counts, pd.DataFrame([{**c, "nodes_per_depth": " ".join(map(str, c["nodes_per_depth"]))}
                                            for c in counts]))
    return data


# --------------------------------------------------------------------------- P3-BR

def step_reactor_model(cfg, inputs, outputs, wildcards) -> dict:
    """P3-BR: the continuous batch reactor and its ZOH discretisation (scipy)."""
    br = cfg["batch_reactor"]
    A, B = batch_reactor_matrices(float(br["Ts"]))
    sys_ = reactor_from_config(cfg)
    data = {"Ts": float(br["Ts"]), "Ac": BATCH_REACTOR_AC.tolist(), "Bc": BATCH_REACTOR_BC.tolist(),
            "A": A.tolist(), "B": B.tolist(), "C": sys_.C.tolist(), "eta_v": sys_.eta_v,
            "eig_A": sorted(np.abs(np.linalg.eigvals(A)).tolist()), "A2_inf_norm": no_data_growth(sys_, 2)}
    write_json(outputs.json, data)
    return data


def vertex_attainment(system: AffineSystem, design: Design, x0: np.ndarray) -> dict:
    """Run the causal estimator at the worst-case vertex of every sequence's largest component at every time.

    Returns the largest ``| |ξ_i(t)| - bound |`` (time-stamped packet runs of
    :func:`eqrec.simulate.loop.simulate_run`) and the number of runs.
    """
    gap, runs = 0.0, 0
    for pat in design.patterns:
        wc = word_certificate(design, pat)
        for t in range(1, pat.T + 1):
            i = int(np.argmax(wc.bounds[t]))
            run = simulate_run(system, design.schedule, pat, wc.worst_vertex(t, i), x0)
            gap = max(gap, abs(abs(run.error[t, i]) - wc.bounds[t, i]))
            runs += 1
    return {"max_gap": float(gap), "runs": runs}


def _design_summary(design: Design) -> dict:
    """Levels and certificate of a design; ``argmax_*``: the event prefix whose level is the largest; the certified
    worst cases per node (from the gains alone) against the designed levels."""
    rows = level_table(design)
    inner = [r for r in rows if 0 < r["k"] < design.T]
    top = max(inner, key=lambda r: r["level"], default={"prefix": None, "k": None})
    return {"mu1": design.mu1, "mu2": design.mu2, "J": design.J, "cost": design.cost,
            "sequences": design.sequences, "nodes": len(rows) - 1, "classes": design.classes,
            "min_level": float(min(r["level"] for r in inner)) if inner else design.mu2,
            "argmax_prefix": top["prefix"], "argmax_depth": top["k"],
            "certified_mu2": design.certificate.mu2, "certified_terminal": design.certificate.terminal,
            "J_certified": design.J_certified,
            "max_certified_over_level": float(max((r["certified"] / r["level"] for r in inner), default=1.0))}


def _free_summary(res: FreeMu1Result) -> dict:
    out = {"route": res.route, "mu1": res.mu1, "J": res.J, "lower_bound": res.lower_bound, "gap": res.gap,
           "lps": res.lps, "time_s": res.time, **_design_summary(res.design)}
    if res.mu1_min is not None:
        out["mu1_min"] = {"upper": res.mu1_min.upper, "lower": res.mu1_min.lower,
                          "lower_margin": res.mu1_min.lower_margin, "binding": res.mu1_min.binding}
    if res.route == "ipopt":
        pol = res.ipopt.polished or {}
        out.update({key: getattr(res.ipopt, key) for key in ("status", "iterations", "mu1_of_gains", "start_mu1")},
                   polished={"mu1": pol.get("mu1"), "J": pol.get("J")})
    return out


def step_reactor_designs(cfg, inputs, outputs, wildcards) -> dict:
    """P3-BR: μ1 free (global certified route and IPOPT route), μ1 at the configured readings."""
    br = cfg["batch_reactor"]
    system = reactor_from_config(cfg)
    words = reactor_language(cfg)
    cost = br["cost"]
    x0 = np.asarray(cfg["kalman"]["x0"], float)
    log.info("batch reactor, %d words, cost %s: mu1 free, global route", len(words), cost)
    g = design_delay_global(system, words, kind="delay", cost=cost)
    log.info("global: mu1 = %.6f, J = %.6f (lower bound %.6f), max mu2 = %.6f", g.mu1, g.J, g.lower_bound, g.mu2)
    log.info("mu1 free, IPOPT route on (10) from the LP at mu1 = %g", br["ipopt_start_mu1"])
    ip = design_delay_ipopt(system, words, kind="delay", cost=cost, start_mu1=float(br["ipopt_start_mu1"]))
    log.info("ipopt: mu1 = %.6f, J = %.6f, max mu2 = %.6f", ip.mu1, ip.J, ip.mu2)
    A2_norm = no_data_growth(system, 2)
    res: dict = {"words": len(words), "cost": cost,
                 "global": {**_free_summary(g), "vertex_attainment": vertex_attainment(system, g.design, x0),
                            "levels": level_table(g.design)},
                 "ipopt": _free_summary(ip), "compare": compare_free_routes(g, ip), "A2_inf_norm": A2_norm,
                 "readings": []}
    for mu1 in br["mu1_readings"]:
        log.info("reading mu1 = %g (fixed, LP)", mu1)
        d = design_delay(system, words, float(mu1), kind="delay", cost=cost)
        res["readings"].append({"mu1": float(mu1), **_design_summary(d), "A2_bound": A2_norm * float(mu1),
                                "vertex_attainment": vertex_attainment(system, d, x0)})
    # no data at times 0 and 1 (a word starting with delays >= 2, >= 1): ξ(2) = A² ξ0 for every estimator
    res["no_data_prefix"] = {"exists": any(parse_delay_word(w).available(1) == () for w in words),
                             "bound_over_mu1": A2_norm, "global_mu2_over_mu1": g.mu2 / g.mu1}
    write_json(outputs.json, res, timings=outputs.timings)
    return res


# --------------------------------------------------------------------------- augmented form (4)

def step_augmented(cfg, inputs, outputs, wildcards) -> dict:
    """Form (4) with fixed ``L^α``, ``s0``: LP optimum for each pole placement and ``s0`` vs the prefix design."""
    ac = cfg["augmented"]
    system = reactor_from_config(cfg)
    tree = PrefixTree(reactor_language(cfg), kind="delay")
    mu1, cost = float(ac["mu1"]), cfg["batch_reactor"]["cost"]
    levels = "sum" if cost == "sum" else "common"
    ref = design_delay(system, tree, mu1, cost=cost)
    rows = []
    prog = Progress(log, len(ac["poles"]) * len(ac["s0"]), "augmented form (4)", "(L, s0) pairs")
    for poles in ac["poles"]:
        L = place_observer(system.A, system.C, poles).L
        for s0 in ac["s0"]:
            gains, sol, _ = solve_augmented_delay(system, tree, mu1, L, np.asarray(s0, float), levels=levels)
            cert = certify_schedule(system, augmented_to_prefix(system, tree, gains), tree.patterns, mu1)
            rows.append({"poles": list(poles), "s0": list(s0), "objective": float(sol.objective),
                         "certified_mu2": cert.mu2, "certified_terminal": cert.terminal,
                         "eig_A_minus_LC": sorted(np.abs(np.linalg.eigvals(system.A - L @ system.C)).tolist())})
            prog.advance()
    objs = [r["objective"] for r in rows]
    # the fixed-μ1 LP's objective: Σ_nodes w μ2,node (sum cost, J without its μ1 term) or μ2 (max cost)
    prefix_objective = ref.J - cost_weights(tree, cost)[0] * mu1 if cost == "sum" else ref.mu2
    res = {"mu1": mu1, "cost": cost, "sequences": len(tree.patterns), "prefix_objective": float(prefix_objective),
           "rows": rows, "spread": float(np.ptp(objs)),
           "max_difference_to_prefix": float(max(abs(o - prefix_objective) for o in objs))}
    write_json(outputs.json, res)
    return res


# --------------------------------------------------------------------------- P3-F1

def design_for_f1(cfg: dict, system: AffineSystem) -> Design:
    """The proposed design of Fig. 1: ``μ1`` free (global route) or the configured ``μ1``."""
    br, f1 = cfg["batch_reactor"], cfg["kalman"]
    words = reactor_language(cfg)
    if f1["mu1"] == "free":
        return design_delay_global(system, words, kind="delay", cost=br["cost"]).design
    return design_delay(system, words, float(f1["mu1"]), kind="delay", cost=br["cost"])


def step_kalman(cfg, inputs, outputs, wildcards) -> dict:
    """P3-F1: the proposed estimator and the Kalman-type filters on the true pattern, same draws.

    Each filter is affine in ``δ = (w, v, ξ0)`` on a fixed pattern: its exact
    worst case over the box (:func:`eqrec.simulate.filter_runs.error_maps`) is compared with
    the proposed estimator's guarantees along the pattern (levels ``μ2,k`` and
    per-component certified bounds), for the prediction ``x̂(t|I_{t-1})`` (the
    information the proposed ``x̂(t)`` uses) and the filtered ``x̂(t|I_t)``.
    """
    f1 = cfg["kalman"]
    system = reactor_from_config(cfg)
    design = design_for_f1(cfg, system)
    mu1 = design.mu1
    pat = parse_delay_word(f1["true_pattern"])
    x0 = np.asarray(f1["x0"], float)
    lay = UncertaintyLayout(pat.T, system.nw, system.nv, system.n)
    rng = np.random.default_rng(int(f1["seed"]))
    deltas = truncated_normal_deltas(lay, lay.radius(system.eta_w, system.eta_v, mu1), rng, int(f1["runs"]),
                                     sigmas=float(f1["sigmas"]))
    levels = path_levels(design, pat)
    wc = word_certificate(design, pat)
    proposed = np.stack([simulate_run(system, design.schedule, pat, d, x0).error for d in deltas])
    maps_err = wc.errors(deltas)
    arrays = {"proposed_errors": proposed, "levels": levels, "proposed_bounds": wc.bounds, "deltas": deltas}
    res: dict = {"mu1": mu1, "mu2": design.mu2, "true_pattern": pat.label, "runs": int(f1["runs"]),
                 "sigmas": float(f1["sigmas"]), "levels": levels.tolist(), "proposed_bounds": wc.bounds.tolist(),
                 "proposed": {"max_ratio_levels": float(np.max(np.abs(proposed).max(axis=2) / levels[None])),
                              "certified_norm": wc.bounds.max(axis=1).tolist(),
                              "runtime_vs_maps": float(np.abs(proposed - maps_err).max())},
                 "filters": {}}
    gd = GaussianDesign.from_box(system, mu1, float(f1["sigmas"]))
    for name in f1["filters"]:
        log.info("filter %s: exact worst case and %d runs", name, len(deltas))
        filt = make_filter(name, system, gd, horizon=pat.T, max_delay=int(cfg["batch_reactor"]["max_delay"]),
                           x0_mean=x0)
        maps = error_maps(filt, system, pat, x0, mu1)
        entry = res["filters"][name] = {}
        for est in ("prediction", "filtered"):
            cmp = compare_with_bounds(maps, wc.bounds, levels, deltas, estimate=est)
            errors = arrays[f"{name}_{est}_errors"] = maps.errors(deltas, est)
            n_t = cmp["worst"].shape[0]
            exceed_t = [int(t) for t in np.nonzero(cmp["exceeds_levels"])[0]]
            entry[est] = {"worst": cmp["worst"].tolist(), "worst_norm": cmp["worst_norm"].tolist(),
                          "levels": levels[:n_t].tolist(), "times_exceeding_levels": exceed_t,
                          "max_ratio_levels": cmp["max_ratio_levels"], "max_ratio_bounds": cmp["max_ratio"],
                          "sampled_exceed_levels": cmp["sampled_exceed_levels"],
                          "sampled_exceed_bounds": cmp["sampled_exceed"], "samples": cmp["samples"],
                          "sampled_max_ratio_levels": float(np.max(np.abs(errors).max(axis=2) / levels[None, :n_t])),
                          "verdict": "outside" if exceed_t else "inside"}
            # the worst-case vertex of the largest excess attains the exact bound
            t = int(np.argmax(np.asarray(cmp["worst_norm"]) / levels[:n_t]))
            i = int(np.argmax(cmp["worst"][t]))
            attained = maps.errors(maps.worst_vertex(t, i, est), est)[0, t, i]
            entry[est]["vertex"] = {"t": t, "i": i, "attain_gap": float(abs(abs(attained) - cmp["worst"][t, i]))}
            arrays[f"{name}_{est}_worst"] = cmp["worst"]
    write_json(outputs.json, res)
    write_npz(outputs.npz, compressed=True, **arrays)
    return res


# --------------------------------------------------------------------------- P3-ACC and P3-F2

def _acc(cfg: dict) -> tuple[AffineSystem, list[str], float, list[str], Design]:
    """The ACC, its delay words, ``μ1``, the same language as missing-data words and P1's prefix design on it."""
    acc = cfg["acc"]
    system, words, mu1 = acc_system(), list(acc["language"]), float(acc["mu1"])
    missing = [p.canonical_label for p in delay_language(words)]
    return system, words, mu1, missing, design_prefix(system, missing, mu1, engine="tree")  # P1's LP's gains


def step_acc(cfg, inputs, outputs, wildcards) -> dict:
    """P3-ACC: the ACC delay language at ``μ1 = 1`` (sum and max costs) vs P1's prefix design; ``μ1`` free."""
    system, words, mu1, missing, p1 = _acc(cfg)
    log.info("ACC: delay language %s = missing-data language %s, mu1 = %g", words, missing, mu1)
    out: dict = {"language": words, "missing_data_language": missing, "mu1": mu1,
                 "p1_prefix": {"mu2": p1.mu2, "certified_mu2": p1.certificate.mu2}, "fixed": {}, "free": {}}
    for cost in ("sum", "max"):
        d = design_delay(system, words, mu1, kind="delay", cost=cost)
        at_max = [v >= d.mu2 * (1 - 1e-6) for v in (d.levels or {}).values()]
        out["fixed"][cost] = {**_design_summary(d), "levels_at_max": sum(at_max),
                              "levels_below_max": len(at_max) - sum(at_max), "difference_to_p1": abs(d.mu2 - p1.mu2)}
    for cost in cfg["acc"]["free_costs"]:
        log.info("ACC, mu1 free, cost %s (global route)", cost)
        g = design_delay_global(system, words, kind="delay", cost=cost)
        ip = design_delay_ipopt(system, words, kind="delay", cost=cost)
        out["free"][cost] = {"global": _free_summary(g), "ipopt": _free_summary(ip),
                             "compare": compare_free_routes(g, ip)}
    write_json(outputs.json, out, timings=outputs.timings)
    return out


def step_acc_simulate(cfg, inputs, outputs, wildcards) -> dict:
    """P3-F2: proposed (delay design, paper's cost) vs P1 prefix-based estimator on the true pattern, same draws."""
    system, words, mu1, _, prefix = _acc(cfg)
    ac = cfg["acc"]
    sim = ac["simulation"]
    proposed = design_delay(system, words, mu1, kind="delay", cost=ac["cost"])
    pat = parse_delay_word(ac["true_pattern"])
    T = pat.T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    rng = np.random.default_rng(int(sim["seed"]))
    deltas = sample_uncertainty(lay, lay.radius(system.eta_w, system.eta_v, mu1), rng, sim["noise"],
                                size=int(sim["runs"]))
    x0 = np.asarray(sim["x0"], float)
    u = np.full((T, system.m), float(sim["input_force"]))
    arrays = {f"{name}_errors": np.stack([simulate_run(system, d.schedule, pat, dl, x0, u).error for dl in deltas])
              for name, d in (("proposed", proposed), ("prefix", prefix))}
    arrays.update(proposed_levels=path_levels(proposed, pat),
                  prefix_levels=np.array([mu1] + [prefix.mu2] * (T - 1) + [mu1]),
                  proposed_bounds=word_certificate(proposed, pat).bounds,
                  prefix_bounds=next(iter(certify_schedule(system, prefix.schedule, [pat], mu1).words.values())).bounds,
                  mu1=mu1, proposed_mu2=proposed.mu2, prefix_mu2=prefix.mu2)
    write_npz(outputs.npz, compressed=True, **arrays)
    return arrays
