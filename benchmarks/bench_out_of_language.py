"""``design.estimator(strict=False)`` out of its language: exact bound / information limit on the two-cart plant
(figures, not tests).

    python benchmarks/bench_out_of_language.py [--steps 400] [--seeds 3] [--loss 0.4]

Issue 32 §2 asks that, out of the language, the estimator's exact worst-case error be at most 2× the information
limit at p95 (it was 18× at the median and 39× at p95 when the estimator coasted on the model to the block's
end).  Plant :func:`eqrec.two_mass`; a class-engine design for delays ``0..3`` with at most one loss per block of
``T = 20`` (``delay_classes(max_delay=3, horizon=20, max_lost=1)``, ``μ1`` free); Bernoulli losses at
``--loss``, each delivered packet delayed uniformly by 0..3 steps.  Printed: the share of steps out of the
language and, in and out of it, the bound / limit per step pooled over the seeds (median, p95, max), where the
bound is the estimator's own (``strict=False``: the exact worst case of its error given the arrivals) and the
limit :func:`eqrec.information_limit` (max over states), both for the initial box of radius ``μ1``; also the
violations of ``|x − x̂|∞ <= bound`` with noise at random box corners, counted as ``eqrec compare`` counts them
(:func:`eqrec.compare.families.count_violations`: above the bound by more than a relative ``1e-9``, the rounding
of the run's arithmetic; must be 0), and the largest error / bound of any step (the designed levels are certified
in exact arithmetic, so a run's own rounding may exceed one by an ulp or two at the box corners).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.bounds.information import information_limit
from eqrec.compare.families import count_violations
from eqrec.design.delay.design import design_delay_global
from eqrec.design.delay.languages import delay_classes
from eqrec.simulate.loop import closed_loop
from eqrec.systems.examples import two_mass

MAX_DELAY, HORIZON = 3, 20


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=400)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--loss", type=float, default=0.4)
    args = ap.parse_args(argv)
    system = two_mass()
    t0 = time.perf_counter()
    design = design_delay_global(system, delay_classes(max_delay=MAX_DELAY, horizon=HORIZON, max_lost=1)).design
    print(f"two carts, design delays 0..{MAX_DELAY}, <= 1 of {HORIZON} lost, mu1 = {design.mu1:.4g} "
          f"({time.perf_counter() - t0:.1f} s); loss {args.loss}, {args.steps} steps x {args.seeds} seeds")
    inside, outside, viol, out_share, worst = [], [], 0, [], 0.0
    for seed in range(args.seeds):
        rng = np.random.default_rng(seed)
        trace = with_uniform_delays(rng, bernoulli_trace(rng, args.steps, args.loss), MAX_DELAY)
        N = trace.steps
        w = system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw))
        v = system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv))
        xi0 = design.mu1 * rng.choice([-1.0, 1.0], system.n)
        est = design.estimator(strict=False)
        flags = []
        out = closed_loop(system, est, trace, np.zeros(system.n), xi0, w, v,
                          after_step=lambda k: flags.append(est.in_design))
        limit = information_limit(system, trace, design.mu1).max(axis=1)
        ratio = out.bound / limit
        flags = np.array(flags)
        inside.append(ratio[flags])
        outside.append(ratio[~flags])
        out_share.append(np.mean(~flags))
        err = np.abs(out.error[1:]).max(axis=1)
        viol += count_violations(err, out.bound)
        worst = max(worst, float(np.max(err / out.bound)))
    print(f"out of the language on {100 * np.mean(out_share):.0f} % of the steps; violations {viol}; "
          f"largest error / bound {worst:.17g}")
    print(f"{'':12s} {'steps':>6s} {'median':>7s} {'p95':>6s} {'max':>6s}")
    for name, parts in (("in design", inside), ("out of it", outside)):
        r = np.concatenate(parts)
        if r.size:
            print(f"{name:12s} {r.size:6d} {np.median(r):7.3f} {np.percentile(r, 95):6.3f} {r.max():6.3f}")


if __name__ == "__main__":
    main()
