"""Cost per step of the information limit (:func:`eqrec.information_limit`), its window and its cache, its growth
with the state dimension, and the consistent set (:func:`eqrec.consistent_set`) (figures, not tests).

    python benchmarks/bench_information_limit.py [--lengths 40,100,400] [--losses 0.1,0.3] [--runs 3]
    python benchmarks/bench_information_limit.py --only scale [--sizes 4:1,10:2,20:4,30:5] [--scale-steps 150]

Rows: ACC (n = 3) and the batch reactor (n = 4), delays 0..1 with Bernoulli losses, one trace per run; each
figure is the median over ``--runs`` traces of the time per step, exact (cache cleared before each trace) and with
``window=20`` (with the largest ratio windowed / exact: the window errs upward).  ``ms/step`` is wall-clock,
``cpu`` the process time (HiGHS threads included; the machine is shared, so the CPU figure is the steadier).
Then the cache: ``--runs`` distinct traces each asked three times (as three families of one comparison run
would), its hit rate and the cost per asked step.

Scale (issue 45 §4): chains of coupled tanks (:func:`tanks`) of ``n`` states and ``p`` level sensors, 30 % loss,
delays <= 2, ``--scale-steps`` steps, one trace each, all in one run: the exact limit's wall and process time, its
time model's estimate (:func:`eqrec.bounds.information.estimate_seconds`), and the growth exponent in ``n`` (least
squares of log process time on log ``n``); then the consistent set of the same traces on simulated data at the
sizes of ``--consistent-sizes``.

Measured 2026-11-29, second session (issue 45 §4; tank chains, 150 steps, process time, one run each, 2 cores
shared with other jobs, load 4-9): before, the primal simplex with the states in fixed order at every size: n = 4,
10, 20, 30 in 0.49, 5.58, 151, 542 s; after (from ``LIMIT_DUAL_FROM_N`` = 16 states on the dual simplex with Devex
pricing and the states in alternating order, :data:`eqrec.bounds.information.LIMIT_HIGHS_OPTIONS`): 0.54, 6.90
(n < 16: the same method, so these two differ by the load only), 129 and 459 s, growth about n^3.4.  The switch
gains 1.7 times at n = 20 over 60 steps but only 1.2 times over 150.  Tried on the way and not kept (n = 20, 60
steps unless said): the redundant box of the eliminated states (slower with the dual simplex), HiGHS's interior
point (4 times slower, no warm start), models of 16 or 64 steps (slower at 90 steps), a per-state basis carried
from step to step (no fewer iterations: about 100 per LP either way), segments of 1, 2, 16 and 32 steps (8 stays
the fastest).  The goal, 60 s at n = 30 over 150 steps, is not met: each of the 4,500 LPs holds the whole past
(about 5,000 columns at n = 30) and takes a few hundred simplex iterations, and no old block can be dropped
exactly here (an old block drops out only where the dual's adjoint is zero, and with p = 5 outputs for n = 30
states the multipliers generically cannot cancel it).

Measured 2026-11-29, third session (same tank chains and traces, 150 steps, process time, old = the dual simplex
alone from 16 states on, new = each objective 200 primal simplex iterations, then the dual simplex from where they
stopped, a state that needed the dual going to it at once from its own basis of the step before,
:data:`eqrec.bounds.information.LIMIT_PRIMAL_ITERATIONS`; the two codes back to back in one script, 2 cores shared,
load 2-6): n = 4, 10 (path unchanged, values byte-identical) 0.43 / 0.46 and 5.44 / 6.19 s; n = 20 131.6 ->
76.6 s; n = 30 426.3 -> 309.3 s (growth about n^3.3, from n = 10 to 30).  Why: from a neighbour's optimum most
states need 0-150 primal iterations (10-20 ms each at n = 30), but about a third (next to a sensor) need thousands
with either simplex, and there the primal stalls; on the last rows the LP takes 152-168 ms against 325 ms, over
the whole trace 1.4 times less.  Values: n = 20 within 7e-11 of before; n = 30 within 1e-9 but one of 4,500,
5.4e-9 below the optimum that cold solves agree on.  Tried and not kept: the sparse form, the state at every step
(``K = 1``: 1.5 times slower than ``K = 8`` with the dual simplex on the last 8 rows at n = 30, 1.3 with the
primal); steepest-edge pricing (dual: 1.4 times slower; primal: 3 times); a dual feasibility tolerance of 1e-10
in the dual phase (no closer to the cold optima).  The goal (60 s at n = 30) is still not met.

Measured 2026-11-29, fourth session (same tank chains and traces, 150 steps; old = the third session's code, new
= this one with ``n_jobs=1`` and with ``n_jobs=None`` (2 workers from n = 20 on), the three back to back in one
script; process time including the worker processes' tasks; 2 cores shared with three other helpers, load 4-7, so
the wall clock is far from an idle machine's):

====  =======================  =======================  =======================
n     old wall / cpu s         new, 1 process           new, 2 workers
====  =======================  =======================  =======================
4     0.79 / 0.36              0.63 / 0.33              0.68 / 0.34 (1 process)
10    11.44 / 5.45             17.12 / 5.20             13.79 / 5.14 (1 process)
20    279.5 / 84.2             103.0 / 59.4             101.3 / 58.7
30    557.7 / 300.6            262.6 / 167.5            293.0 / 198.8
====  =======================  =======================  =======================

n = 4 and 10: the same path, values byte-identical.  n = 20 and 30: 1 process and 2 workers byte-identical to each
other; against the old code within 1.5e-10 at n = 20; at n = 30 within 1e-9 on 4,498 of 4,500 values (median
2e-13), the other two checked against cold solves: the old code's one known miss (row 131, state 16, 5.4e-9 below
the cold optimum) is on it now (3e-16), and row 67, state 20 is now 1.5e-8 above it (relative 3.8e-8; the old
value was on it).  What was kept, and why:

* Hard states from their own basis in two phases (``_HighsModel._run_own``).  Where the time goes (rows 128-135
  at n = 30, 240 LPs, 41.5 s): the 89 LPs of more than 1,000 iterations take 36.9 s (164 µs per iteration), the
  others 10-25 ms each.  From a hard state's own optimal basis of the step before, moving only its objective by a
  step costs the dual simplex 1,931-2,349 iterations and the primal 14-109; fixing only the newly delivered rows
  (5) costs the dual 706-738 and the primal 2,390-3,928.  So: free the rows delivered since, primal simplex, fix
  them again, dual simplex: about 800-1,000 iterations instead of 2,000-2,500; rows 128-149 at n = 30: 126.7 ->
  71.0 s.
* Tasks of one chunk and one group of 8 neighbouring states on worker processes (:func:`state_groups`,
  ``n_jobs``).  In one process the groups cost 0-10 % (one cold start per group and chunk) and make the values
  independent of the number of workers; with 2 workers the process time is about the same, so the wall time
  halves only where a second core is free: here it was not (load 4-7 from other jobs), and the wall clock gained
  nothing measurable.  On the idle 2-core machine afterwards (``--only scale --sizes 30:5 --jobs auto``, the
  merged code): n = 30 in 100.9 s of wall and 199.0 s of process time, 2 workers (the goal: 60 s).

Tried and not kept:

* Row generation on the delivered measurement rows: the hypothesis fails.  At n = 30, row 149 (LP of 1,045 rows
  and 5,575 columns, 505 delivered measurement rows), the rows with a nonzero dual at a cold optimum number
  278-417 per state (55-83 %), 475 (94 %) over the 30 states; at n = 20, row 59: 57-100 of 136 per state, 118
  over all.  A working set would hold most of them and save nothing.
* Cost perturbation: HiGHS's primal bound perturbation (multiplier 0, 10, 100) and dual cost perturbation (0, 10,
  100) at n = 20, 60 steps: 6.5-9.3 s against 7.1-7.4 s (the load's noise); on rows 128-131 at n = 30 the dual
  cost perturbation off 10.6 s, default 11.7, 20 times 15.8.  Our own random cost perturbation (1e-7 relative,
  then a clean-up solve on the exact costs): more iterations (81,649 against 70,006) in the same time.

The goal (60 s at n = 30 over 150 steps) is still not met: 167.5 s of process time in one process (1.8 times
less than 300.6; growth from n = 10 to 30 about n^3.2, against n^3.7 before), so about 85-100 s of wall clock
with 2 workers on an idle 2-core machine (not measured here: no core was idle).

Measured 2026-11-29, fifth session (same tank chains and traces, 150 steps; old = the fourth session's settings,
given as ``--versus '{"simplex_scale_strategy": 2, "dual_feasibility_tolerance": 1e-9}'``, new = this code, from 16
states on both simplex phases on the LP unscaled with a dual feasibility tolerance of 1e-10,
:data:`eqrec.bounds.information.LIMIT_SHARED_OPTIONS`; all in one run, ``--only scale --sizes 4:1,10:2,20:4,30:5
--consistent-sizes "" --jobs 1,auto``; process time including the worker processes' tasks; 2 cores shared with
three other helpers, load 4-8, so the wall clock is far from an idle machine's, and worst for the 2-worker rows):

====  =======================  =======================  =======================  =======================
n     old, 1 process           old, 2 workers           new, 1 process           new, 2 workers
      wall / cpu s             wall / cpu s             wall / cpu s             wall / cpu s
====  =======================  =======================  =======================  =======================
4     0.69 / 0.46              0.64 / 0.46 (1 process)  0.68 / 0.47              0.59 / 0.45 (1 process)
10    7.79 / 6.83              10.63 / 7.12 (1 process) 7.90 / 6.88              10.15 / 6.92 (1 process)
20    116.1 / 65.3             101.0 / 61.3             61.4 / 33.3              55.2 / 30.4
30    364.3 / 198.4            433.2 / 216.8            212.0 / 102.3            188.8 / 100.4
====  =======================  =======================  =======================  =======================

n = 4 and 10: the same path (below ``LIMIT_DUAL_FROM_N`` nothing changed), values byte-identical.  n = 20: new
within 1.5e-10 of old; n = 30: at most 1.5e-8, at row 67, state 20, the old path's known drift (in the task holding
it, old 1.5e-8 above the cold optimum, new 1.7e-16 from it).  Old, 1 process and 2 workers: identical (the table
prints each row's difference to the first row of its size, the old 1 process; new 1 process and 2 workers are
byte-identical by construction, the same tasks, and ``tests/test_information_limit.py`` checks it).  Growth
of the new process time from n = 10 to 30: about n^2.5 (old: n^3.1); n = 4 to 30, n^2.65.
Process time, old / new: n = 20, 1.96 in one process and 2.02 with 2 workers; n = 30, 1.94 and 2.16.

Where the time went (rows 128-135 at n = 30, states 8-15, one task of 64 LPs): old 5.0 s, 29,975 simplex
iterations (166 µs each); the 13 LPs of more than 1,000 iterations 3.5 s, the 29 of fewer than 50 iterations
0.25 s (about 7 ms each, a run's fixed cost).  New: 2.4 s, 12,697 iterations (190 µs each), 2 LPs above 1,000
iterations and 21 of 200-1,000.  The lever was the number of iterations of the hard states, not their cost:
HiGHS's default scaling (strategy 2) made the dual simplex take 1.6-2.7 times the iterations it takes on the LP as
built (tasks of 6 rows and 8 states at rows 60, 100, 128 and 140: 17,014 -> 10,930, 23,403 -> 13,127, 17,250 ->
10,158, 60,717 -> 22,374), at the same cost per iteration.  Unscaled with the dual tolerance of before (1e-9) the
warm optima ended up to 1.9e-9 below the cold ones (32 LPs of rows 140-143, states 0-7, against the dual simplex
cold at tolerances 1e-10); at 1e-10 within 1.1e-10 (old: 1.9e-10), for 10-30 % more iterations than at 1e-9.

Tried and not kept (tasks of 6 rows and 8 states at n = 30, process time, about 15 % noise between repeats):
scaling strategies 1 and 3 (the default's iterations exactly), 4 (as off, within 5 %); a simplex update limit of 50
or 1,000 (no change); price strategies 0, 1, 2 (the same iterations, no faster); dual steepest edge
(3 % fewer iterations, the same time) and Dantzig pricing (17 % more iterations, the same time); 100 or 400 primal
iterations before the dual simplex instead of 200 (2-14 % slower); without the hard states' own bases or
without remembering which states are hard (1.2-2.3 times slower: the fourth session's two-phase start still pays
without scaling); groups of 4, 5, 6, 10 or 20 states instead of 8 (n = 20, 60 steps, one process: 4.8-6.0 s
against 4.6-5.3 s for 8; fewer, larger groups are not cheaper, so they cannot remove the 2-worker overhead
below); chunks of 16 steps instead of 32 (n = 30, 60 steps: 12.2 s against 10.8-13.3 s).  Not tried for lack of
time: the condensed form, presolve per chunk, column generation (issue 45's list).

The 2 workers' extra process time: old 216.8 against 198.4 s in one process (+9 %), new 100.4 against 102.3 s (none)
in this run; the fourth session measured 198.8 against 167.5 s in one run, so it varies with what else runs on the
machine.  It is not the groups' cold starts (the same tasks run in one process, and larger groups were not cheaper
above), so the groups stay as they were (the values independent of ``n_jobs``).  The goal, 60 s of wall at n = 30 on
2 cores, was not measured on an idle machine: here, at load 5-8, the 2-worker run took 188.8 s of wall.  Its process
time, 100.4 s, is half of before and no more than one process's, so on an idle 2-core machine about 50-60 s of wall
is expected (half the process time plus the imbalance of the last chunk's four tasks): to be confirmed there with
``--only scale --sizes 30:5 --jobs auto``.  The ``estimate s`` column of that run is the first time model's (149 and
883 s at n = 20 and 30); from 16 states on :func:`eqrec.bounds.information.estimate_seconds` now uses a model fit on
these rows (33.7 and 103.6 s), so n = 30 over 150 steps is no longer refused without ``force``.  Confirmed on the
idle 2-core machine afterwards (``--only scale --sizes 30:5 --jobs auto``, the merged code, load about 1): n = 30
over 150 steps in **51.3 s of wall** and 99.8 s of process time with 2 workers (the goal, 60 s, met); largest
limit 1.0405, the same as the one-process run's.
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np

from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.bounds.consistent import consistent_set
from eqrec.bounds.information import (cache_info, clear_cache, estimate_seconds, information_limit,
                                      last_solve_info)
from eqrec.systems.affine import AffineSystem
from eqrec.systems.examples import tank_chain
from eqrec.systems.examples import acc_system, batch_reactor


def _trace(N: int, loss: float, seed: int, max_delay: int = 1) -> ArrivalTrace:
    rng = np.random.default_rng(seed)
    return ArrivalTrace(np.where(rng.random(N) < loss, NEVER, rng.integers(0, max_delay + 1, N)))


def tanks(n: int, p: int, flow: float = 0.2, leak: float = 0.05, eta_w: float = 0.01,
          eta_v: float = 0.05) -> AffineSystem:
    """A chain of ``n`` coupled tanks (levels ``x``): the plant of :func:`eqrec.systems.examples.tank_chain`
    (neighbours exchange ``flow`` times their difference per step, the last tank leaks ``leak`` of its level,
    process noise on every level) without its input, and ``p`` level sensors spread evenly along the chain (the
    first and the last tank among them when ``p >= 2``; the first when ``p = 1``, where ``tank_chain`` takes the
    last: the figures above were measured on this placement)."""
    chain = tank_chain(n, p, flow, leak)
    sensors = np.unique(np.linspace(0, n - 1, p).round().astype(int))
    return AffineSystem(A=chain.A, C=np.eye(n)[sensors], E=np.eye(n), eta_w=eta_w, eta_v=eta_v, name=f"{n} tanks")


def scale(sizes: list[tuple[int, int]], steps: int, consistent_sizes: list[int], jobs: list,
          versus: dict | None = None) -> None:
    """The scale table (module docstring): the exact limit at every size with each ``n_jobs`` of ``jobs`` (and,
    with ``versus``, also with those ``solver_options``, the rows ``vs``: e.g. the settings of before, to time
    old and new in one run; ``max |diff|`` is then against the first row of the size), its growth exponent (of the
    first), the consistent set."""
    print(f"scale: chains of coupled tanks, 30 % loss, delays <= 2, {steps} steps, x0_radius 1 (one run)")
    print(f"{'n':>3s} {'p':>2s} {'opts':>4s} {'n_jobs':>6s} {'workers':>7s} {'wall s':>8s} {'cpu s':>8s} "
          f"{'ms/step':>8s} {'estimate s':>10s} {'max limit':>10s} {'max |diff|':>10s}")
    cpu_by_n = {}
    for n, p in sizes:
        plant = tanks(n, p)
        trace = _trace(steps, 0.3, 45 + n, max_delay=2)
        first = None
        for opts, jobs_ in [(o, j) for o in ([None] if versus is None else [versus, None]) for j in jobs]:
            clear_cache()
            limit, wall, cpu = _timed(lambda: information_limit(plant, trace, 1.0, cache=False, force=True,
                                                                n_jobs=jobs_, solver_options=opts))
            ran = last_solve_info()
            if ran["workers"] > 1:  # the tasks' process time on the worker processes
                cpu += ran["task_seconds"]
            first = limit if first is None else first
            if opts is None:
                cpu_by_n.setdefault(n, cpu)
            print(f"{n:3d} {p:2d} {'vs' if opts else '':>4s} {str(jobs_):>6s} {ran['workers']:7d} {wall:8.2f} "
                  f"{cpu:8.2f} {1e3 * wall / steps:8.1f} {estimate_seconds(plant, steps):10.2f} "
                  f"{float(limit.max()):10.4f} {float(np.abs(limit - first).max()):10.1e}", flush=True)
    if len(cpu_by_n) >= 2:
        ns = np.array(sorted(cpu_by_n), float)
        slope = np.polyfit(np.log(ns), np.log([cpu_by_n[int(v)] for v in ns]), 1)[0]
        print(f"growth of the process time in n: about n^{slope:.2f}")
    if consistent_sizes:
        print()
        print(f"consistent set on simulated data ({steps} steps; 4 n LPs per step against the limit's n)")
        print(f"{'n':>3s} {'wall s':>8s} {'cpu s':>8s} {'ms/step':>8s} {'pred. radius / limit, median':>30s}")
        for n, p in sizes:
            if n not in consistent_sizes:
                continue
            plant = tanks(n, p)
            trace = _trace(steps, 0.3, 45 + n, max_delay=2)
            rng = np.random.default_rng(n)
            x = rng.uniform(-1, 1, n)
            y = np.empty((steps, plant.p))
            for k in range(steps):
                y[k] = plant.C @ x + plant.eta_v * rng.uniform(-1, 1, plant.p)
                x = plant.A @ x + plant.eta_w * rng.uniform(-1, 1, n)
            hull, wall, cpu = _timed(lambda: consistent_set(plant, trace, y, 1.0, force=True))
            limit = information_limit(plant, trace, 1.0, force=True)
            ratio = np.median(hull.predicted_radius / np.maximum(limit, 1e-300))
            print(f"{n:3d} {wall:8.2f} {cpu:8.2f} {1e3 * wall / steps:8.1f} {ratio:30.4f}", flush=True)


def _timed(fn):
    w0, c0 = time.perf_counter(), time.process_time()
    out = fn()
    return out, time.perf_counter() - w0, time.process_time() - c0


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--lengths", default="40,100,400")
    ap.add_argument("--losses", default="0.1,0.3")
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--window", type=int, default=20)
    ap.add_argument("--only", choices=["plants", "cache", "scale"], action="append",
                    help="run only these parts (repeatable; default: all)")
    ap.add_argument("--sizes", default="4:1,10:2,20:4,30:5", help="scale: n:p pairs")
    ap.add_argument("--scale-steps", type=int, default=150)
    ap.add_argument("--consistent-sizes", default="4,10", help="scale: the n at which to time the consistent set")
    ap.add_argument("--versus", default=None, help="scale: also time every size and n_jobs with these HiGHS "
                    "solver_options (JSON), first; e.g. the settings before LIMIT_SHARED_OPTIONS: "
                    "'{\"simplex_scale_strategy\": 2, \"dual_feasibility_tolerance\": 1e-9}'")
    ap.add_argument("--jobs", default="1,auto", help="scale: the n_jobs of information_limit to time, one after the "
                    "other at every size (auto: None, every core when the estimate reaches PARALLEL_SECONDS)")
    args = ap.parse_args(argv)
    parts = set(args.only or ["plants", "cache", "scale"])
    if "scale" in parts:
        sizes = [tuple(int(v) for v in pair.split(":")) for pair in args.sizes.split(",")]
        jobs = [None if v == "auto" else int(v) for v in args.jobs.split(",")]
        scale(sizes, args.scale_steps, [int(v) for v in args.consistent_sizes.split(",") if v], jobs,
              None if args.versus is None else json.loads(args.versus))
        print()
        if parts == {"scale"}:
            return
    lengths = [int(v) for v in args.lengths.split(",")]
    losses = [float(v) for v in args.losses.split(",")]
    plants = {"ACC": (acc_system(), 0.5), "batch reactor": (batch_reactor(), 1.0)}
    if "plants" in parts:
        _plants(plants, lengths, losses, args)
    if "cache" in parts:
        _cache(plants, lengths, args)


def _plants(plants: dict, lengths: list[int], losses: list[float], args) -> None:
    print(f"{'plant':14s} {'N':>4s} {'loss':>5s} {'ms/step':>8s} {'cpu':>6s} {'W ms/step':>9s} {'W cpu':>6s} "
          f"{'W/exact max':>12s}")
    for name, (plant, radius) in plants.items():
        for N in lengths:
            for loss in losses:
                ex, exc, win, winc, ratio = [], [], [], [], 1.0
                for run in range(args.runs):
                    trace = _trace(N, loss, 1000 * run + N)
                    clear_cache()
                    exact, wall, cpu = _timed(lambda: information_limit(plant, trace, radius))
                    ex.append(wall / N)
                    exc.append(cpu / N)
                    windowed, wall, cpu = _timed(lambda: information_limit(plant, trace, radius, window=args.window,
                                                                            cache=False))
                    win.append(wall / N)
                    winc.append(cpu / N)
                    ratio = max(ratio, float(np.max(windowed / np.maximum(exact, 1e-300))))
                med = lambda v: 1e3 * statistics.median(v)  # noqa: E731
                print(f"{name:14s} {N:4d} {loss:5.2f} {med(ex):8.2f} {med(exc):6.2f} {med(win):9.2f} "
                      f"{med(winc):6.2f} {ratio:12.6f}")
    print()


def _cache(plants: dict, lengths: list[int], args) -> None:
    print("cache: distinct traces, each asked 3 times (three families of one comparison run)")
    for name, (plant, radius) in plants.items():
        for N in lengths:
            clear_cache()
            asked, total = 0, 0.0
            for run in range(args.runs):
                trace = _trace(N, 0.1, 7 + run)
                for _ in range(3):
                    _, wall, _ = _timed(lambda: information_limit(plant, trace, radius))
                    total += wall
                    asked += N
            info = cache_info()
            print(f"{name:14s} N={N:4d}: hit rate {info['hits'] / asked:6.1%} (hits across distinct traces "
                  f"{(info['hits'] - 2 * args.runs * N) / (args.runs * N):5.1%}), {1e3 * total / asked:.3f} ms "
                  f"per asked step")


if __name__ == "__main__":
    main()
