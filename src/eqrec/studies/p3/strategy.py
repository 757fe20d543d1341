r"""P3-IMPL: the implementation strategy steps of the delayed/missing-data study (P3).

P3-IMPL is Section III-B3 of the delayed-data paper ("Implementation
Strategy"), run as long simulations:

* **periodic reuse** (step ``strategy``): the gains of one design are reused
  every ``T`` steps (:func:`eqrec.simulate.long_runs.long_run_periodic`), a delay
  word drawn uniformly from the design language for every period, noise and
  ``ξ(0)`` drawn in the box (uniform and at vertices).  Two designs: the
  batch reactor of Section IV-A (full language ``{0..τ̄}^T``, ``T = 5``,
  ``τ̄ = 2``, ``μ1 = 0.33``, sum cost) and the ACC of Section IV-B (the
  missing-data language ``{060000, 006000, 000600, 000060}``, ``μ1 = 1``).
  At every time the error must stay within the level of the node of the
  observed prefix (``μ1`` at period boundaries).  A packet whose delay
  reaches past the period's end is delivered in the next period, where the
  estimator drops it (stamped before the period); the language counts it
  as missing.  :func:`eqrec.simulate.long_runs.periodic_model_gap` checks that
  every period follows the design model of its word exactly.
* **switching** (also step ``strategy``): the equalized-performance
  estimator (equalized recovery with period 1: ``‖ξ(t)‖ <= μ1`` implies
  ``‖ξ(t+1)‖ <= μ1`` when ``y(t)`` is on time) until a measurement is late,
  then the recovery estimator for ``T`` steps, designed on the words of
  ``{0..τ̄}^T`` whose first delay is at least 1, then back
  (:class:`eqrec.estimators.switching.SwitchingEstimator`,
  :func:`eqrec.simulate.long_runs.long_run_switching`); i.i.d. delays.  On the
  batch reactor a period-1 design is infeasible at ``μ1 = 0.33`` (2 outputs,
  4 states: no one-step contraction of the ∞-norm box): the step records the
  LP's status there, the certified smallest period-1 level
  (:func:`eqrec.design.delay.design.min_recovery_level`), the smallest on-time period
  that recovers at ``μ1``, and runs the scheme at the smallest period-1
  level rounded up (``switching.mu1``).

The batch reactor is open-loop unstable: the runs apply ``u = −K x̂`` (LQR,
``Q = I``, ``R = I``) so that the states stay bounded over ``10⁴`` steps;
the estimator knows ``u``, so the error does not depend on it.  The ACC runs
with the constant input ``input_force``.

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

The figure is drawn by :func:`eqrec.studies.p3.figures.step_strategy_figure`; the scale table is
:mod:`eqrec.studies.p3.scale_table`.
"""

from __future__ import annotations

import math
import time
from functools import partial

import numpy as np
import scipy.linalg as sla

from eqrec.arrivals.words import full_delay_language
from eqrec.simulate.long_runs import LongRun, long_run_periodic, long_run_switching, periodic_model_gap
from eqrec.systems.examples import ACC_CONSTANTS, acc_system
from eqrec.systems.affine import AffineSystem
from eqrec.design.delay.design import design_delay, design_lp_status, min_recovery_level
from eqrec.design.report import level_table, node_level, path_levels
from eqrec.design.result import Design
from eqrec.systems.examples import BATCH_REACTOR_TS, batch_reactor
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import write_json, write_npz

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
    return {**ev, "max_ratio": max(r.max_ratio for r in runs.values()),
            "steps": int(min(r.delays.size for r in runs.values())), "ratio_tol": RATIO_TOL}


def _long_runs(st: dict, seed_offset: int, what: str, run) -> tuple[dict[str, LongRun], float]:
    """One long run ``run(rng, kind=kind)`` per noise kind of ``st["noise"]`` (its own random stream) and the longest
    run time."""
    runs: dict[str, LongRun] = {}
    timing = []
    for j, kind in enumerate(st["noise"]):
        rng = np.random.default_rng([int(st["seed"]), seed_offset, j])
        t0 = time.perf_counter()
        r = runs[kind] = run(rng, kind=kind)
        timing.append(time.perf_counter() - t0)
        log.info("%s, %s noise: %d steps in %.2f s, max error/guarantee %.6f, %d switches, %d packets dropped late",
                 what, kind, r.delays.size, timing[-1], r.max_ratio, len(r.switch_times), len(r.dropped))
    return runs, max(timing)


def _periodic(system: AffineSystem, design: Design, words, st: dict, seed_offset: int, x0, **drive) -> dict:
    T = design.T
    periods = math.ceil(int(st["steps"]) / T)
    run = partial(long_run_periodic, system, design.schedule, list(words), periods, mu1=design.mu1,
                  path_levels=partial(path_levels, design), x0=x0, **drive)
    runs, run_time = _long_runs(st, seed_offset, f"periodic {system.name}", run)
    gap = max(periodic_model_gap(r, system, design.schedule) for r in runs.values())
    ev = dict(_ratio_evidence(runs, T), T=T, periods=periods, mu1=design.mu1, max_mu2=design.mu2, words=len(words),
              sequences=len(design.patterns), model_gap=gap, dropped_late=sum(len(r.dropped) for r in runs.values()),
              certificate_excess=certificate_excess(design), run_time_s=run_time)
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

    # --- batch reactor, periodic reuse
    reactor = batch_reactor()
    K = lqr_gain(reactor)
    T, tb, mu1 = int(rc["horizon"]), int(rc["max_delay"]), float(rc["mu1"])
    words = full_delay_language(T, tb)
    log.info("batch reactor: design on {0..%d}^%d (%d words) at mu1 = %g", tb, T, len(words), mu1)
    d_r = design_delay(reactor, words, mu1, kind="delay", cost=cost)
    x0_r = np.asarray(rc["x0"], float)
    controller = lambda xh: -K @ xh  # noqa: E731
    per_r = _periodic(reactor, d_r, words, st, 0, x0_r, controller=controller)

    # --- ACC, periodic reuse (missing-data language as delay words)
    acc = acc_system()
    d_a = design_delay(acc, list(ac["words"]), float(ac["mu1"]), kind="delay", cost=cost)
    log.info("ACC: design on %s at mu1 = %g, max mu2 = %.6f", list(ac["words"]), float(ac["mu1"]), d_a.mu2)
    per_a = _periodic(acc, d_a, ac["words"], st, 1, np.asarray(ac["x0"], float),
                      inputs=np.array([float(ac["input_force"])]))

    # --- switching scheme: is a period-1 (equalized-performance) design feasible at the reactor's μ1?
    on_time = ["0"]
    status_at_mu1 = design_lp_status(reactor, on_time, mu1, cost, kind="delay")
    by_period = [min_recovery_level(reactor, ["0" * P], kind="delay") for P in range(1, int(sw["max_period"]) + 1)]
    mm = by_period[0]  # period 1: the on-time word
    periods_min = [m.upper for m in by_period]
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
    d_p = design_delay(reactor, on_time, mu1_s, kind="delay", cost=cost)
    rec_words = [w for w in words if w[0] != "0"]
    d_s = design_delay(reactor, rec_words, mu1_s, kind="delay", cost=cost)
    sw_runs, sw_time = _long_runs(st, 2, "switching", partial(
        long_run_switching, reactor, d_p.schedule, d_s.schedule, int(st["steps"]), mu1=mu1_s,
        recovery_level=partial(node_level, d_s), max_delay=tb, p_on_time=float(sw["p_on_time"]), x0=x0_r,
        controller=controller))
    perf = [float(r.ratio[1:][~r.recovering].max()) for r in sw_runs.values() if (~r.recovering).any()]
    rec = [float(r.ratio[1:][r.recovering].max()) for r in sw_runs.values() if r.recovering.any()]
    sw_ev = dict(_ratio_evidence(sw_runs, None), mu1=mu1_s, performance_mu2=d_p.mu2, recovery_max_mu2=d_s.mu2,
                 recovery_words=len(rec_words), recovery_sequences=len(d_s.patterns), T=T,
                 p_on_time=float(sw["p_on_time"]), switches=int(sum(len(r.switch_times) for r in sw_runs.values())),
                 reverts=int(sum(len(r.revert_times) for r in sw_runs.values())),
                 recovery_fraction=float(np.mean([r.recovering.mean() for r in sw_runs.values()])),
                 max_ratio_performance=max(perf, default=0.0), max_ratio_recovery=max(rec, default=0.0),
                 dropped_late=int(sum(len(r.dropped) for r in sw_runs.values())),
                 certificate_excess=max(certificate_excess(d_s), float(d_p.certificate.terminal - mu1_s)),
                 run_time_s=sw_time)

    # --- values
    values: dict = {}
    for name, ev, keys in (("periodic_reactor", per_r["evidence"], ("max_ratio_after_start_uniform", "model_gap")),
                           ("periodic_acc", per_a["evidence"], ("model_gap",)),
                           ("switching", sw_ev, ("max_ratio_performance", "max_ratio_recovery"))):
        values[f"{name}_within"] = {"value": "inside" if ev["max_ratio"] <= 1.0 + RATIO_TOL else "outside",
                                    "evidence": ev}
        values[f"{name}_max_ratio"] = {"value": ev["max_ratio"], "evidence": {
            k: ev[k] for k in ("steps", "ratio_tol", *keys) if k in ev}}
    values["performance_period1_status"] = {"value": status_at_mu1, "evidence": {
        "mu1": mu1, "lp_status": status_at_mu1, "mu1_min": mm.upper, "mu1_min_lower": mm.lower,
        "smallest_period": smallest_period, "max_period": int(sw["max_period"]), "period_mu1_min": periods_min,
        "switching_mu1": mu1_s}}
    values["switching_mu1"] = {"value": mu1_s, "evidence": {
        "rule": rule, "mu1_min": mm.upper, "mu1_min_lower": mm.lower, "decimals": int(sw["decimals"]),
        "lp_status": design_lp_status(reactor, on_time, mu1_s, cost, kind="delay"), "reactor_mu1": mu1,
        "status_at_reactor_mu1": status_at_mu1}}
    values["strategy_time_s"] = {"value": time.perf_counter() - t_start, "evidence": {"steps": int(st["steps"])}}

    # --- arrays for the figure
    arrays: dict = {}
    for label, runs, Ts, T_ in (("reactor_periodic", per_r["runs"], BATCH_REACTOR_TS, T),
                                ("acc_periodic", per_a["runs"], float(ACC_CONSTANTS["Ts"]), d_a.T),
                                ("reactor_switching", sw_runs, BATCH_REACTOR_TS, T)):
        for kind, r in runs.items():
            arrays.update({f"{label}_{kind}_{name}": a for name, a in (
                ("error", r.error), ("level", r.level), ("recovering", r.recovering),
                ("switch", np.asarray(r.switch_times, int)), ("revert", np.asarray(r.revert_times, int)))})
        arrays.update({f"{label}_T": T_, f"{label}_Ts": Ts})
    write_npz(outputs.npz, compressed=True, noise=np.array(list(st["noise"])), reactor_mu1=mu1, acc_mu1=d_a.mu1,
              switching_mu1=mu1_s, **arrays)
    write_json(outputs.values, values, timings=outputs.timings)
    log.info("P3-IMPL done in %.1f s", time.perf_counter() - t_start)
    return values
