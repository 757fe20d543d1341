r"""P3-IMPL and the P3 scale table: steps of the delayed/missing-data study (P3).

P3-IMPL is Section III-B3 of the delayed-data paper ("Implementation
Strategy"), run as long simulations:

* **periodic reuse** (step ``strategy``): the gains of one design are reused
  every ``T`` steps (:func:`eqrec.core.simulate.long_run_periodic`), a delay
  word drawn uniformly from the design language for every period, noise and
  ``ξ(0)`` drawn in the box (uniform and at vertices).  Two designs: the
  batch reactor of Section IV-A (full language ``{0..τ̄}^T``, ``T = 5``,
  ``τ̄ = 2``, ``μ1 = 0.33``, sum cost) and the ACC of Section IV-B (the
  missing-data language ``{060000, 006000, 000600, 000060}``, ``μ1 = 1``).
  At every time the error must stay within the level of the node of the
  observed prefix (``μ1`` at period boundaries).  A packet whose delay
  reaches past the period's end is delivered in the next period, where the
  estimator drops it (stamped before the period); the language counts it
  as missing.  :func:`eqrec.core.simulate.periodic_model_gap` checks that
  every period follows the design model of its word exactly.
* **switching** (also step ``strategy``): the equalized-performance
  estimator (equalized recovery with period 1: ``‖ξ(t)‖ <= μ1`` implies
  ``‖ξ(t+1)‖ <= μ1`` when ``y(t)`` is on time) until a measurement is late,
  then the recovery estimator for ``T`` steps, designed on the words of
  ``{0..τ̄}^T`` whose first delay is at least 1, then back
  (:class:`eqrec.core.switching.SwitchingEstimator`,
  :func:`eqrec.core.simulate.long_run_switching`); i.i.d. delays.  On the
  batch reactor a period-1 design is infeasible at ``μ1 = 0.33`` (2 outputs,
  4 states: no one-step contraction of the ∞-norm box): the step records the
  LP's status there, the certified smallest period-1 level
  (:func:`eqrec.design.delay.min_recovery_level`), the smallest on-time period
  that recovers at ``μ1``, and runs the scheme at the smallest period-1
  level rounded up (``switching.mu1``).

The batch reactor is open-loop unstable: the runs apply ``u = −K x̂`` (LQR,
``Q = I``, ``R = I``) so that the states stay bounded over ``10⁴`` steps;
the estimator knows ``u``, so the error does not depend on it.  The ACC runs
with the constant input ``input_force``.

The scale table (steps ``scale_size`` per ``(T, τ̄)`` and engine, ``scale_table``): the
batch reactor's full-language design (sum cost, ``μ1`` fixed) solved by one
HiGHS method in a fresh process with time and memory limits
(:func:`eqrec.design.scale_sweep.run_size`), by two engines side by side:
the tree LP (node per event prefix, the language enumerated) and the class
engine (one LP per (time, available data) class and state row, the classes
from the window rule, no word enumerated; :mod:`eqrec.design.classes`).  The
default run writes ``results/p3/scale_table.{csv,md}`` from
``scale.tree_sizes`` (the tree LP where it takes seconds) and
``scale.class_sizes``; the target ``p3_scale`` (outside the default run)
writes ``results/p3/scale_table_full.{csv,md}``, adding the tree LP at
``scale.tree_slow_sizes`` (minutes and up to the memory limit each).  Per-size
JSONs: ``results/p3/scale/T{T}_tau{τ̄}.json`` (tree) and
``results/p3/scale/classes_T{T}_tau{τ̄}.json``.

Configuration (``cfg`` is the ``p3`` section; defaults are the schema's)
------------------------------------------------------------------------
``strategy``:

=========================  ===========================  ==================================================
key                        default                      meaning
=========================  ===========================  ==================================================
``steps``                  ``10000``                    length of every long run (steps)
``seed``                   ``3``                        seed of the random draws (one stream per run)
``noise``                  ``[uniform, vertex]``        noise kinds, one run of each
``cost``                   ``sum``                      cost of the designs (``sum`` or ``max``)
``reactor.horizon``        ``5``                        ``T`` of the batch-reactor designs
``reactor.max_delay``      ``2``                        ``τ̄``
``reactor.mu1``            ``0.33``                     ``μ1`` of the periodic design (the paper's)
``reactor.x0``             ``[1, 1, 1, 1]``             initial state
``acc.words``              ``[060000, ..., 000060]``    the ACC language (delay words; 6 = missing)
``acc.mu1``                ``1.0``                      ``μ1`` of the ACC design
``acc.x0``                 ``[20, 40, 20]``             initial state [m/s, m, m/s]
``acc.input_force``        ``206.4``                    constant input [N]
``switching.mu1``          ``null``                     common level; ``null``: the reactor's ``μ1`` if a
                                                        period-1 design is feasible there, else the
                                                        smallest period-1 level rounded up to ``decimals``
``switching.decimals``     ``2``                        rounding of the automatic level
``switching.p_on_time``    ``0.8``                      probability that a measurement is on time (else
                                                        delay uniform on ``1..τ̄``)
``switching.max_period``   ``5``                        longest on-time period tried at ``reactor.mu1``
``figure.window``          ``60``                       steps shown in the figure
=========================  ===========================  ==================================================

``scale``:

=========================  ======================================  ========================================
key                        default                                 meaning
=========================  ======================================  ========================================
``tree_sizes``             ``[[5,2],[6,2]]``                       ``(T, τ̄)`` of the tree LP in the default
                                                                   run (seconds each)
``tree_slow_sizes``        ``[[7,2],[8,2],[8,3]]``                 ``(T, τ̄)`` of the tree LP in the
                                                                   ``p3_scale`` target only
``class_sizes``            ``[[5,2],[6,2],[7,2],[8,2],[8,3],``     ``(T, τ̄)`` of the class engine (default
                           ``[20,4],[30,4],[40,4],[30,5]]``        run)
``method``                 ``simplex``                             HiGHS method (``scale_sweep.METHODS``),
                                                                   both engines
``builder``                ``core``                                tree LP builder (``core``)
``mu1``                    ``0.5``                                 fixed ``μ1``
``time_limit``             ``600``                                 HiGHS time limit per size [s]
``mem_limit_gb``           ``16``                                  address-space limit per size [GB]
=========================  ======================================  ========================================
"""

from __future__ import annotations

import math
import time
from functools import partial

import numpy as np
import pandas as pd
import scipy.linalg as sla

from eqrec.core.patterns import full_delay_language
from eqrec.core.simulate import LongRun, long_run_periodic, long_run_switching, periodic_model_gap
from eqrec.core.systems import ACC_CONSTANTS, AffineSystem, acc_system
from eqrec.design.delay import design_delay, design_lp_status, level_table, min_recovery_level, node_level, path_levels
from eqrec.design.result import Design
from eqrec.design.scale_sweep import ENGINES, FIELDS, class_count, run_size
from eqrec.models import BATCH_REACTOR_TS, batch_reactor
from eqrec.studies.logs import get_logger
from eqrec.studies.outputs import TIMING_KEYS, read_json, save_figure, write_csv, write_json, write_npz, write_text
from eqrec.studies.plotting import STATE_LABELS_ACC, paper_style, pyplot

log = get_logger("p3")

#: Tolerance of "inside the guarantees": error / guarantee <= 1 + RATIO_TOL.
RATIO_TOL = 1e-9


# --------------------------------------------------------------------------- helpers

def lqr_gain(system: AffineSystem) -> np.ndarray:
    """State-feedback gain ``K`` of the discrete LQR with ``Q = I``, ``R = I`` (``u = −K x``)."""
    A, B = system.A, system.B
    P = sla.solve_discrete_are(A, B, np.eye(system.n), np.eye(system.m))
    return np.linalg.solve(np.eye(system.m) + B.T @ P @ B, B.T @ P @ A)


def certificate_excess(design: Design) -> float:
    """Largest certified worst case minus the designed level over the nodes (``<= 0`` up to rounding)."""
    return float(max(r["certified"] - r["level"] for r in level_table(design)))


def _ratio_evidence(runs: dict[str, LongRun], T: int | None) -> dict:
    ev: dict = {}
    for kind, r in runs.items():
        ev[f"max_ratio_{kind}"] = r.max_ratio
        ev[f"max_ratio_after_start_{kind}"] = float(r.ratio[1:].max())
        if T:
            ev[f"max_ratio_boundary_{kind}"] = float(r.ratio[::T].max())
    ev["max_ratio"] = max(r.max_ratio for r in runs.values())
    ev["steps"] = int(min(r.delays.size for r in runs.values()))
    ev["ratio_tol"] = RATIO_TOL
    return ev


def _within(ratio: float) -> str:
    return "inside" if ratio <= 1.0 + RATIO_TOL else "outside"


def _periodic(system: AffineSystem, design: Design, words, st: dict, seed_offset: int, x0, **drive) -> dict:
    T = design.T
    periods = math.ceil(int(st["steps"]) / T)
    runs: dict[str, LongRun] = {}
    gaps, dropped, timing = [], 0, []
    for j, kind in enumerate(st["noise"]):
        rng = np.random.default_rng([int(st["seed"]), seed_offset, j])
        t0 = time.perf_counter()
        r = long_run_periodic(system, design.schedule, list(words), periods, rng, mu1=design.mu1,
                              path_levels=partial(path_levels, design), kind=kind, x0=x0, **drive)
        timing.append(time.perf_counter() - t0)
        gaps.append(periodic_model_gap(r, system, design.schedule))
        dropped += len(r.dropped)
        runs[kind] = r
        log.info("periodic %s, %s noise: %d steps in %.2f s, max error/guarantee %.6f, %d packets dropped "
                 "after their period", system.name, kind, r.delays.size, timing[-1], r.max_ratio, len(r.dropped))
    ev = _ratio_evidence(runs, T)
    ev.update(T=T, periods=periods, mu1=design.mu1, max_mu2=design.mu2, words=len(words),
              sequences=len(design.patterns), model_gap=max(gaps), dropped_late=dropped,
              certificate_excess=certificate_excess(design), run_time_s=max(timing))
    return {"runs": runs, "evidence": ev}


# --------------------------------------------------------------------------- P3-IMPL

def step_strategy(cfg, inputs, outputs, wildcards) -> dict:
    """P3-IMPL: periodic reuse (batch reactor, ACC) and the switching scheme, long runs inside the guarantees.

    Writes ``outputs.npz`` (errors, guarantees and switching instants of
    every run) and ``outputs.values`` (claims format: numbers and statuses).
    """
    st = cfg["strategy"]
    rc, ac, sw = st["reactor"], st["acc"], st["switching"]
    cost = st["cost"]
    t_start = time.perf_counter()
    arrays: dict = {}
    values: dict = {}

    # --- batch reactor, periodic reuse
    reactor = batch_reactor()
    K = lqr_gain(reactor)
    T, tb, mu1 = int(rc["horizon"]), int(rc["max_delay"]), float(rc["mu1"])
    words = full_delay_language(T, tb)
    log.info("batch reactor: design on {0..%d}^%d (%d words) at mu1 = %g", tb, T, len(words), mu1)
    d_r = design_delay(reactor, words, mu1, cost=cost)
    x0_r = np.asarray(rc["x0"], float)
    controller = lambda xh: -K @ xh  # noqa: E731
    per_r = _periodic(reactor, d_r, words, st, 0, x0_r, controller=controller)

    # --- ACC, periodic reuse (missing-data language as delay words)
    acc = acc_system()
    d_a = design_delay(acc, list(ac["words"]), float(ac["mu1"]), cost=cost)
    log.info("ACC: design on %s at mu1 = %g, max mu2 = %.6f", list(ac["words"]), float(ac["mu1"]), d_a.mu2)
    per_a = _periodic(acc, d_a, ac["words"], st, 1, np.asarray(ac["x0"], float),
                      inputs=np.array([float(ac["input_force"])]))

    # --- switching scheme: is a period-1 (equalized-performance) design feasible at the reactor's μ1?
    on_time = ["0"]
    status_at_mu1 = design_lp_status(reactor, on_time, mu1, cost)
    mm = min_recovery_level(reactor, on_time)
    periods_min = []
    for P in range(1, int(sw["max_period"]) + 1):
        periods_min.append(min_recovery_level(reactor, ["0" * P]).upper)
    smallest_period = next((P for P, m in enumerate(periods_min, 1) if m <= mu1), None)
    if sw["mu1"] is not None:
        mu1_s, rule = float(sw["mu1"]), "configured"
    elif status_at_mu1 == "optimal":
        mu1_s, rule = mu1, "reactor mu1"
    else:
        scale = 10.0 ** int(sw["decimals"])
        mu1_s, rule = math.ceil(mm.upper * scale - 1e-9) / scale, "smallest period-1 level rounded up"
    log.info("period-1 design at mu1 = %g: %s; smallest period-1 level %.6f (certified > %.6f); smallest on-time "
             "period recovering to %g: %s; switching at mu1 = %g", mu1, status_at_mu1, mm.upper, mm.lower, mu1,
             smallest_period, mu1_s)
    d_p = design_delay(reactor, on_time, mu1_s, cost=cost)
    rec_words = [w for w in words if w[0] != "0"]
    d_s = design_delay(reactor, rec_words, mu1_s, cost=cost)
    sw_runs: dict[str, LongRun] = {}
    timing = []
    for j, kind in enumerate(st["noise"]):
        rng = np.random.default_rng([int(st["seed"]), 2, j])
        t0 = time.perf_counter()
        r = long_run_switching(reactor, d_p.schedule, d_s.schedule, int(st["steps"]), rng, mu1=mu1_s,
                               recovery_level=partial(node_level, d_s), max_delay=tb,
                               p_on_time=float(sw["p_on_time"]), kind=kind, x0=x0_r, controller=controller)
        timing.append(time.perf_counter() - t0)
        sw_runs[kind] = r
        log.info("switching, %s noise: %d steps in %.2f s, %d switches, max error/guarantee %.6f", kind,
                 r.delays.size, timing[-1], len(r.switch_times), r.max_ratio)
    sw_ev = _ratio_evidence(sw_runs, None)
    perf = [float(r.ratio[1:][~r.recovering].max()) for r in sw_runs.values() if (~r.recovering).any()]
    rec = [float(r.ratio[1:][r.recovering].max()) for r in sw_runs.values() if r.recovering.any()]
    sw_ev.update(mu1=mu1_s, performance_mu2=d_p.mu2, recovery_max_mu2=d_s.mu2, recovery_words=len(rec_words),
                 recovery_sequences=len(d_s.patterns), T=T, p_on_time=float(sw["p_on_time"]),
                 switches=int(sum(len(r.switch_times) for r in sw_runs.values())),
                 reverts=int(sum(len(r.revert_times) for r in sw_runs.values())),
                 recovery_fraction=float(np.mean([r.recovering.mean() for r in sw_runs.values()])),
                 max_ratio_performance=max(perf, default=0.0), max_ratio_recovery=max(rec, default=0.0),
                 dropped_late=int(sum(len(r.dropped) for r in sw_runs.values())),
                 certificate_excess=max(certificate_excess(d_s), float(d_p.certificate.terminal - mu1_s)),
                 run_time_s=max(timing))

    # --- values
    ev_r, ev_a = per_r["evidence"], per_a["evidence"]
    values["periodic_reactor_within"] = {"value": _within(ev_r["max_ratio"]), "evidence": ev_r}
    values["periodic_reactor_max_ratio"] = {"value": ev_r["max_ratio"], "evidence": {
        k: ev_r[k] for k in ("steps", "ratio_tol", "max_ratio_after_start_uniform", "model_gap") if k in ev_r}}
    values["periodic_acc_within"] = {"value": _within(ev_a["max_ratio"]), "evidence": ev_a}
    values["periodic_acc_max_ratio"] = {"value": ev_a["max_ratio"], "evidence": {
        k: ev_a[k] for k in ("steps", "ratio_tol", "model_gap") if k in ev_a}}
    values["switching_within"] = {"value": _within(sw_ev["max_ratio"]), "evidence": sw_ev}
    values["switching_max_ratio"] = {"value": sw_ev["max_ratio"], "evidence": {
        k: sw_ev[k] for k in ("steps", "ratio_tol", "max_ratio_performance", "max_ratio_recovery")}}
    values["performance_period1_status"] = {"value": status_at_mu1, "evidence": {
        "mu1": mu1, "lp_status": status_at_mu1, "mu1_min": mm.upper, "mu1_min_lower": mm.lower,
        "smallest_period": smallest_period, "max_period": int(sw["max_period"]), "period_mu1_min": periods_min,
        "switching_mu1": mu1_s}}
    values["switching_mu1"] = {"value": mu1_s, "evidence": {
        "rule": rule, "mu1_min": mm.upper, "mu1_min_lower": mm.lower, "decimals": int(sw["decimals"]),
        "lp_status": design_lp_status(reactor, on_time, mu1_s, cost), "reactor_mu1": mu1,
        "status_at_reactor_mu1": status_at_mu1}}
    values["strategy_time_s"] = {"value": time.perf_counter() - t_start, "evidence": {"steps": int(st["steps"])}}

    # --- arrays for the figure
    for label, runs, Ts, T_ in (("reactor_periodic", per_r["runs"], BATCH_REACTOR_TS, T),
                                ("acc_periodic", per_a["runs"], float(ACC_CONSTANTS["Ts"]), d_a.T),
                                ("reactor_switching", sw_runs, BATCH_REACTOR_TS, T)):
        for kind, r in runs.items():
            key = f"{label}_{kind}"
            arrays[f"{key}_error"] = r.error
            arrays[f"{key}_level"] = r.level
            arrays[f"{key}_recovering"] = r.recovering
            arrays[f"{key}_switch"] = np.asarray(r.switch_times, int)
            arrays[f"{key}_revert"] = np.asarray(r.revert_times, int)
        arrays[f"{label}_T"] = T_
        arrays[f"{label}_Ts"] = Ts
    write_npz(outputs.npz, compressed=True, noise=np.array(list(st["noise"])), reactor_mu1=mu1, acc_mu1=d_a.mu1,
              switching_mu1=mu1_s, **arrays)
    write_json(outputs.values, values, timings=outputs.timings)
    log.info("P3-IMPL done in %.1f s", time.perf_counter() - t_start)
    return values


def step_strategy_figure(cfg, inputs, outputs, wildcards) -> None:
    """P3-IMPL figure: errors per state with the per-time guarantees over a window of each long run.

    Columns: periodic reuse on the batch reactor, on the ACC, and the
    switching scheme on the batch reactor (recovery phases shaded, switching
    instants marked).  The run with the first noise kind is shown.
    """
    paper_style()
    plt = pyplot()
    data = np.load(inputs.npz)
    kind = str(data["noise"][0])
    window = int(cfg["strategy"]["figure"]["window"])
    reactor_labels = [rf"$\xi_{i}$ [–]" for i in range(1, 5)]  # the linearised reactor's states are dimensionless
    cols = (("reactor_periodic", "Batch reactor, gains reused every T", reactor_labels),
            ("acc_periodic", "ACC, gains reused every T", list(STATE_LABELS_ACC)),
            ("reactor_switching", "Batch reactor, switching scheme", reactor_labels))
    fig, axes = plt.subplots(4, 3, figsize=(10.0, 8.2), sharex="col")
    # one scale per reactor state across the two reactor columns (the same quantity)
    reactor_lim = {}
    for label in ("reactor_periodic", "reactor_switching"):
        key = f"{label}_{kind}"
        N = min(window, data[f"{key}_error"].shape[0] - 1)
        for i in range(data[f"{key}_error"].shape[1]):
            reactor_lim[i] = max(reactor_lim.get(i, 0.0), 1.15 * max(float(data[f"{key}_level"][: N + 1].max()),
                                                                  float(np.abs(data[f"{key}_error"][: N + 1, i]).max())))
    for c, (label, title, ylabels) in enumerate(cols):
        key = f"{label}_{kind}"
        err, lev = data[f"{key}_error"], data[f"{key}_level"]
        T, Ts = int(data[f"{label}_T"]), float(data[f"{label}_Ts"])
        N = min(window, err.shape[0] - 1)
        t = np.arange(N + 1)
        n = err.shape[1]
        for i in range(4):
            ax = axes[i, c]
            if i >= n:
                ax.axis("off")
                continue
            ax.fill_between(t, -lev[: N + 1], lev[: N + 1], step="mid", color="0.85", label="guarantee")
            ax.plot(t, err[: N + 1, i], "C0.-", ms=2.5, label="estimation error")
            if label == "reactor_switching":
                sw, rv = data[f"{key}_switch"], data[f"{key}_revert"]
                for j, s in enumerate(sw[sw <= N]):
                    ax.axvline(s, color="C3", ls="--", lw=0.7, label="switch to recovery" if j == 0 else None)
                for j, s in enumerate(rv[rv <= N]):
                    ax.axvline(s, color="C2", ls=":", lw=0.9, label="back to performance" if j == 0 else None)
            else:
                for j, s in enumerate(range(T, N + 1, T)):
                    ax.axvline(s, color="0.5", ls=":", lw=0.6, label="period boundary" if j == 0 else None)
            ax.set_ylabel(ylabels[i])
            lim = reactor_lim[i] if label.startswith("reactor") else (
                1.15 * max(float(lev[: N + 1].max()), float(np.abs(err[: N + 1, i]).max())))
            ax.set_ylim(-lim, lim)
            if i == 0:
                ax.set_title(title)
        last = axes[min(n, 4) - 1, c]
        last.set_xlabel(f"time step k (Ts = {Ts:g} s)")
        last.tick_params(labelbottom=True)
    # one legend under the figure (inside an axis it covers the bands)
    seen: dict[str, object] = {}
    for ax in axes[0]:
        for h, lab in zip(*ax.get_legend_handles_labels()):
            seen.setdefault(lab, h)
    fig.legend(list(seen.values()), list(seen), loc="lower center", ncol=len(seen), bbox_to_anchor=(0.5, 0.0))
    fig.suptitle(f"P3 implementation strategy: estimation errors and per-time guarantees ({kind} noise, first "
                 f"{window} steps; $\\mu_1$ = {float(data['reactor_mu1']):g} / {float(data['acc_mu1']):g} / "
                 f"{float(data['switching_mu1']):g})")
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    save_figure(fig, outputs.pdf, outputs.png)


# --------------------------------------------------------------------------- scale table

def step_scale_size(cfg, inputs, outputs, wildcards) -> dict:
    """One row of the scale table: the full language ``{0..τ̄}^T`` (wildcards ``T``, ``tau``) in a fresh process.

    The wildcard ``engine`` (``tree`` when absent) picks the tree LP or the
    class engine (:data:`eqrec.design.scale_sweep.ENGINES`).  A size that hits
    the time or memory limit is recorded with that status (the step succeeds).
    """
    sc = cfg["scale"]
    T, tau = int(wildcards.T), int(wildcards.tau)
    engine = wildcards.get("engine", "tree")
    log.info("scale (T, tau) = (%d, %d), %s engine: %s, builder %s, mu1 = %g, limits %g s / %g GB", T, tau, engine,
             sc["method"], sc["builder"], float(sc["mu1"]), float(sc["time_limit"]), float(sc["mem_limit_gb"]))
    r = run_size(batch_reactor(), T, tau, sc["method"], float(sc["mu1"]), float(sc["time_limit"]),
                 float(sc["mem_limit_gb"]), sc["builder"], engine=engine)
    log.info("scale (%d, %d), %s: %s; %s classes, %s columns, build %.2f s, solve %.2f s, peak %.0f MB, J = %s", T,
             tau, engine, r.get("status"), r.get("classes"), r.get("cols"), r.get("build_time", float("nan")),
             r.get("solve_time", float("nan")), r.get("peak_mb", float("nan")), r.get("J"))
    write_json(outputs.json, r, timings=outputs.timings)
    return r


def scale_frame(rows: list[dict]) -> pd.DataFrame:
    """The scale table as a frame (columns :data:`eqrec.design.scale_sweep.FIELDS`), sorted by ``(T, τ̄)``, the
    tree LP before the class engine.

    Rows written before the engine dimension (the tracked tree sizes) read as
    ``engine = "tree"``; their ``classes`` (closed form) and ``J`` (the LP's
    objective plus the constant ``(1 + 2|L^{E'}|) μ1`` it leaves out) are
    filled in.
    """
    rows = [dict(r) for r in rows]
    for r in rows:
        r.setdefault("engine", "tree")
        if r.get("classes") is None and "T" in r and "tau" in r:
            r["classes"] = class_count(r["T"], r["tau"])
        if (r["engine"] == "tree" and r.get("J") is None and r.get("status") == "optimal"
                and r.get("objective") is not None and r.get("sequences") is not None):
            r["J"] = float(r["objective"]) + (1.0 + 2.0 * int(r["sequences"])) * float(r["mu1"])
    frame = pd.DataFrame(rows).reindex(columns=list(FIELDS))
    order = {e: i for i, e in enumerate(ENGINES)}
    frame = frame.assign(_e=frame["engine"].map(order).fillna(len(order)))
    frame = frame.sort_values(["T", "tau", "_e", "method"], kind="stable").drop(columns="_e")
    return frame.reset_index(drop=True)


def _md_cell(v, col: str = "") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    if isinstance(v, bool):
        return str(v)
    if isinstance(v, int):
        return f"{v:.3e}" if abs(v) >= 10**10 else str(v)  # (τ̄+1)^T: 9.313e+20 words at (30, 4)
    if isinstance(v, float):
        if col in ("max_level", "terminal_level"):
            return f"{v:.6f}"
        if col == "J":
            return f"{v:.6g}" if abs(v) >= 1e6 else f"{v:.4f}"
        if col == "peak_mb" or v.is_integer():
            return f"{v:.0f}" if abs(v) < 1e10 else f"{v:.3e}"
        return f"{v:.2f}" if abs(v) < 1e6 else f"{v:.4g}"
    return str(v)


def _value(v):
    return v.item() if hasattr(v, "item") else v


def _size_list(sizes) -> str:
    return ", ".join(f"({int(T)}, {int(tau)})" for T, tau in sizes)


def scale_markdown(frame: pd.DataFrame, missing_tree: list | None = None, timings: bool = True) -> str:
    """The scale table in Markdown: a note (setting, why the class engine scales), one row per (size, engine),
    then the two engines side by side on the sizes both ran.

    ``missing_tree``: tree sizes left out of this table (the slow ones of the
    ``p3_scale`` target), named in the note.  ``timings=False``: without the
    measured columns (times, memory), which change from run to run; the
    table with them is written under ``results/timings/``.
    """
    columns = [("T", "T"), ("tau", "τ̄"), ("words", "words"), ("sequences", "sequences (L^E')"), ("nodes", "nodes"),
               ("classes", "classes (d, S)"), ("engine", "engine"), ("rows", "LP rows"), ("cols", "LP cols"),
               ("nnz", "nonzeros"), ("tree_time", "tree [s]"), ("classes_time", "classes [s]"),
               ("build_time", "build [s]"), ("method", "HiGHS method"), ("solve_time", "solve [s]"),
               ("iterations", "iterations"), ("J", "J"), ("max_level", "max μ2"), ("peak_mb", "peak [MB]"),
               ("status", "status")]
    columns = [(c, h) for c, h in columns if timings or c not in TIMING_KEYS]
    cols, head = [c for c, _ in columns], [h for _, h in columns]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for _, row in frame.iterrows():
        lines.append("| " + " | ".join(_md_cell(_value(row[c]), c) for c in cols) + " |")
    parts = ["# P3 scale table\n"]
    if len(frame):
        meta = frame.iloc[0]
        tree = frame[frame["engine"] == "tree"]
        builder = tree["builder"].iloc[0] if len(tree) else "core"
        parts.append(
            f"Batch reactor (Section IV-A of the delayed-data paper), full delay language {{0..τ̄}}^T, sum cost J of "
            f"Theorem 1 / Proposition 1, mu1 = {_value(meta['mu1']):g} fixed; one fresh process per size and engine, "
            f"HiGHS {meta['method']}, time limit {_value(meta['time_limit']):g} s, address-space limit "
            f"{_value(meta['mem_limit_gb']):g} GB. Engine `tree`: the node-per-prefix LP on the enumerated prefix tree "
            f"(builder {builder}); engine `classes`: one LP per (time, available data) class and state row, the "
            f"classes built by the window rule without enumerating a word (`eqrec.design.classes`).\n")
        parts.append(
            "Why the class engine scales: by the separation theorem of `eqrec.design.classes`, every node of a "
            "class (d, S) attains the same optimal level whatever its ancestors' gains, so the tree LP's optimum is "
            "the class levels weighted by their sequence counts and one small LP per class and state row gives it. "
            "The classes number Σ_{d=1..T} 2^min(τ̄, d) ≈ T·2^τ̄ (446 at (30, 4)), while the sequences and prefix-tree "
            "nodes the tree LP carries grow like (τ̄+1)^T (1.8e+20 sequences at (30, 4)).\n")
        if timings:
            parts.append(
                "Columns: `tree [s]` enumerates the language and builds its prefix tree, `classes [s]` builds the "
                "class set, `build [s]` assembles the LP, `solve [s]` is HiGHS (`total [s]` below: their sum); "
                "`peak [MB]` is the worker's peak resident memory (timings and memory are measurements: they change "
                "from run to run). `J` is the paper's sum cost (the same for both engines); `max μ2` the largest "
                "level (class engine: certified from the gains; tree: the LP's).\n")
        else:
            parts.append(
                "Columns: the language and LP sizes, `J` the paper's sum cost (the same for both engines) and "
                "`max μ2` the largest level (class engine: certified from the gains; tree: the LP's). The times and "
                "peak memory of each size are measurements that change from run to run: they are in "
                "`results/timings/p3/` (the same table with them, `scale_table.md` there).\n")
        if missing_tree:
            parts.append(
                f"Tree LP at {_size_list(missing_tree)}: `results/p3/scale_table_full.md` (target `p3_scale`, "
                f"outside the default run: minutes and up to the memory limit per size).\n")
    parts.append("\n".join(lines) + "\n")
    side = _side_by_side(frame, timings)
    if side:
        parts.append("## Side by side (sizes both engines ran)\n\n" + side)
    return "\n".join(parts)


def _side_by_side(frame: pd.DataFrame, timings: bool = True) -> str:
    """Per size run by both engines: LP sizes, total times (language + build + solve), peak memory and J of each
    (without times and memory when ``timings`` is false)."""
    if not len(frame):
        return ""
    by = {(int(_value(r["T"])), int(_value(r["tau"])), r["engine"]): r for _, r in frame.iterrows()}
    sizes = sorted({(T, tau) for T, tau, e in by if (T, tau, "tree") in by and (T, tau, "classes") in by})
    if not sizes:
        return ""

    def total(r):  # a size that did not solve has no total (its build time is in the table above)
        if r["status"] != "optimal":
            return None
        vals = [_value(r[c]) for c in ("tree_time", "classes_time", "build_time", "solve_time")]
        vals = [v for v in vals if v is not None and not (isinstance(v, float) and math.isnan(v))]
        return float(sum(vals)) if vals else float("nan")

    # (header, cell of (T, τ̄, tree row, class row), format of _md_cell, a measurement?)
    columns = [
        ("T", lambda T, tau, t, c: T, "T", False),
        ("τ̄", lambda T, tau, t, c: tau, "tau", False),
        ("sequences", lambda T, tau, t, c: _value(c["sequences"]), "sequences", False),
        ("nodes", lambda T, tau, t, c: _value(c["nodes"]), "nodes", False),
        ("classes", lambda T, tau, t, c: _value(c["classes"]), "classes", False),
        ("tree LP cols", lambda T, tau, t, c: _value(t["cols"]), "cols", False),
        ("class LP cols", lambda T, tau, t, c: _value(c["cols"]), "cols", False),
        ("tree total [s]", lambda T, tau, t, c: total(t), "", True),
        ("classes total [s]", lambda T, tau, t, c: total(c), "", True),
        ("tree peak [MB]", lambda T, tau, t, c: _value(t["peak_mb"]), "peak_mb", True),
        ("classes peak [MB]", lambda T, tau, t, c: _value(c["peak_mb"]), "peak_mb", True),
        ("tree status", lambda T, tau, t, c: t["status"], "status", False),
        ("classes status", lambda T, tau, t, c: c["status"], "status", False),
        ("J (tree)", lambda T, tau, t, c: _value(t["J"]), "J", False),
        ("J (classes)", lambda T, tau, t, c: _value(c["J"]), "J", False),
    ]
    columns = [col for col in columns if timings or not col[3]]
    lines = ["| " + " | ".join(h for h, *_ in columns) + " |", "|" + "---|" * len(columns)]
    for T, tau in sizes:
        t, c = by[(T, tau, "tree")], by[(T, tau, "classes")]
        lines.append("| " + " | ".join(_md_cell(cell(T, tau, t, c), fmt) for _, cell, fmt, _ in columns) + " |")
    return "\n".join(lines) + "\n"


def step_scale_table(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """Merge the per-size JSONs (``inputs.sizes``, with their ``inputs.timings``) into the scale table: ``outputs.csv``
    and ``outputs.md`` without the measured columns, ``outputs.timings_csv`` and ``outputs.timings_md`` with them.

    The Markdown note names the ``scale.tree_slow_sizes`` whose tree row is
    not among the inputs (the default run's table leaves them to ``p3_scale``).
    """
    rows = [read_json(p, timings=t) for p, t in zip(inputs.sizes, inputs.timings, strict=True)]
    frame = scale_frame(rows)
    have = {(int(r["T"]), int(r["tau"])) for r in rows if r.get("engine", "tree") == "tree"}
    slow = cfg["scale"]["tree_slow_sizes"]  # validated config: the schema fills the default
    missing = [(int(T), int(tau)) for T, tau in slow if (int(T), int(tau)) not in have]
    write_csv(outputs.csv, frame, timings=outputs.timings_csv, keys=["engine", "T", "tau"])
    write_text(outputs.md, scale_markdown(frame, missing, timings=False))
    write_text(outputs.timings_md, scale_markdown(frame, missing, timings=True))
    log.info("scale table: %d rows (%d tree, %d classes)", len(frame), int((frame["engine"] == "tree").sum()),
             int((frame["engine"] == "classes").sum()))
    return frame


STEPS = {
    "strategy": step_strategy,
    "strategy_figure": step_strategy_figure,
    "scale_size": step_scale_size,
    "scale_class_size": step_scale_size,  # the same step; the engine comes from the output path
    "scale_table": step_scale_table,
    "scale_table_full": step_scale_table,  # the same step over more sizes
}
