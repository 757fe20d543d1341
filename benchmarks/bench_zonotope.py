"""The zonotopic set-membership estimator on the two-cart plant: cost of ``step`` and bound / information limit
(figures, not tests).

    python benchmarks/bench_zonotope.py [--steps 300] [--seeds 3] [--timing-steps 5000] [--repeats 3]

Plant :func:`eqrec.two_mass` (lightly damped, n = 4, one output), Bernoulli losses 0.3, each delivered packet
delayed uniformly by 0..2 steps, ``max_delay = 2``, initial box of radius 0.5.  Rows: the default
(``fradius+reweighted``: the F-radius filter and the reweighted one side by side, per state the tighter), each
gain alone, and the crude reference (``fradius`` with Girard's box reduction: Combastel's Kalman-shaped gain), at
orders 20 and 40 with the PCA (default) and Girard reductions.  The last line gives the default against the
reference at order 40.  Columns: µs per ``step`` (median over ``--repeats`` timed runs on a pre-built arrival
list, no simulation in the loop), and bound / limit per step pooled over the seeds (median, p95, max), where
the limit is :func:`eqrec.bounds.information.information_limit` (max over states, per step).  The guarantee is
also counted: violations of ``|x - x̂|_∞ <= bound`` with noise at random box corners (must be 0).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.estimators.zonotope import ZonotopeEstimator
from eqrec.simulate.loop import closed_loop, what_arrived
from eqrec.systems.examples import two_mass

X0_RADIUS, LOSS, MAX_DELAY = 0.5, 0.3, 2


def _limit(system, trace):
    from eqrec.bounds.information import information_limit  # lazily: the module of the information limit

    return information_limit(system, trace, X0_RADIUS)


def _trace(seed: int, steps: int):
    rng = np.random.default_rng(seed)
    return with_uniform_delays(rng, bernoulli_trace(rng, steps, LOSS), MAX_DELAY)


def _us_per_step(system, gain, order: int, reduction: str, steps: int, repeats: int) -> float:
    rng = np.random.default_rng(100)
    trace = _trace(100, steps)
    sched = trace.schedule()
    y = 0.1 * rng.normal(size=(steps, system.p))
    arrivals = [what_arrived(sched[k], k, y) for k in range(steps)]
    u = np.zeros(system.m)
    times = []
    for _ in range(repeats):
        est = ZonotopeEstimator(system, X0_RADIUS, MAX_DELAY, order, gain=gain, reduction=reduction)
        est.reset(np.zeros(system.n))
        t0 = time.perf_counter()
        for a in arrivals:
            est.step(a, u)
        times.append((time.perf_counter() - t0) / steps)
    return statistics.median(times) * 1e6


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--timing-steps", type=int, default=5000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    system = two_mass()
    N = args.steps
    runs = []
    t0 = time.perf_counter()
    for seed in range(args.seeds):
        trace = _trace(seed, N)
        rng = np.random.default_rng(seed + 1000)
        noise = (system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw)),
                 system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv)),
                 X0_RADIUS * rng.choice([-1.0, 1.0], system.n))
        runs.append((trace, _limit(system, trace).max(axis=1), noise))
    limit_s = (time.perf_counter() - t0) / (args.seeds * N)
    gains = {"fradius+reweighted": ("fradius", "reweighted"), "fradius": "fradius", "reweighted": "reweighted"}
    rows = [(g, o, r) for r in ("pca", "girard") for g in gains for o in (20, 40)]
    print(f"two carts, loss {LOSS}, delays 0..{MAX_DELAY}, {N} steps x {args.seeds} seeds; "
          f"information limit {limit_s * 1e3:.1f} ms per step")
    print(f"{'gain':18s} {'reduction':9s} {'order':>5s} {'us/step':>8s} {'median':>7s} {'p95':>6s} {'max':>6s} "
          f"{'viol':>4s}")
    table = {}
    for name, order, reduction in rows:
        gain = gains[name]
        ratios, viol = [], 0
        for trace, lim, (w, v, xi0) in runs:
            est = ZonotopeEstimator(system, X0_RADIUS, MAX_DELAY, order, gain=gain, reduction=reduction)
            out = closed_loop(system, est, trace, np.zeros(system.n), xi0, w, v)
            ratios.append(out.bound / lim)
            viol += int(np.sum(np.abs(out.error[1:]).max(axis=1) > out.bound))
        r = np.concatenate(ratios)
        us = _us_per_step(system, gain, order, reduction, args.timing_steps, args.repeats)
        table[name, order, reduction] = (np.median(r), r.max())
        print(f"{name:18s} {reduction:9s} {order:5d} {us:8.1f} {np.median(r):7.3f} {np.percentile(r, 95):6.3f} "
              f"{r.max():6.3f} {viol:4d}")
    (dm, dx), (rm, rx) = table["fradius+reweighted", 40, "pca"], table["fradius", 40, "girard"]
    print(f"order 40: the default against the reference (fradius, girard): median {dm:.3f} vs {rm:.3f} "
          f"({100 * (1 - dm / rm):.1f} % lower), max {dx:.3f} vs {rx:.3f} ({100 * (1 - dx / rx):.1f} % lower)")


if __name__ == "__main__":
    main()
