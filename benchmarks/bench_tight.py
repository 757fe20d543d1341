"""The papers' estimator made tight (issue 40): bound / information limit in and out of the design, and µs per step
side by side with the set-membership estimator (figures, not tests).

    python benchmarks/bench_tight.py [--steps 120] [--seeds 2] [--loss 0.4] [--repeats 3]
    python benchmarks/bench_tight.py --part cost [--losses 0,0.2,0.4] [--cost-steps 120,120,60] [--plants ...]

Plants: two carts and a spring (:func:`eqrec.two_mass`, ``n = 4``, one position measured), a cart-pole (``n = 4``,
one unstable mode, two outputs) and a chain of five carts (``n = 10``, every position
measured, ``p = 5``).  Each is designed by the class engine for delays
``0..2``, at most one loss per block of ``T = 6`` (``delay_classes(max_delay=2, horizon=6, max_lost=1)``, ``μ1``
free), and run on Bernoulli losses at ``--loss`` with uniform delays ``0..2``, noise at random box corners.

Printed, per plant:

* bound / information limit per step (median, p95, max; the limit :func:`eqrec.information_limit`, max over
  states, for the initial box of radius ``μ1``) on the steps in the design and out of it, for
  ``design.estimator(strict=False)`` (tight, the default), ``strict=False, tight=False`` (the designed estimate
  alone), the zonotope estimator alone (:class:`eqrec.ZonotopeEstimator`, ``max_delay = T``, the one
  ``strict=False`` runs beside the gains) and the prefix-based paper's estimator (:func:`eqrec.design_prefix` for
  at most one of ``T`` lost, ``μ1`` free, ``strict=False``, fed the on-time packets only: a late packet counts as
  lost, as in the compare study), and the largest error / bound of any step (must be <= 1).  "In the design" is
  the class design's (the steps where ``strict=False`` runs its designed gains), for every row;
* µs per step, measured side by side in one run (CPU time of the process, the best of ``--repeats`` runs, each estimator in turn on the
  same data): ``strict=True`` (a trace without losses, in the language), ``strict=False`` in the design (the
  same trace), ``strict=False`` out of it (its out-of-design steps on the lossy trace) and the zonotope estimator
  alone on each trace, and the ratios ``strict=False`` / zonotope on the same trace (issue 40's target: <= 1.2);
* the cost table (issue 40 §3, ``--part cost``): per plant and loss rate (Bernoulli, delays ``0..2`` uniform), the
  CPU µs of ``step()`` alone (the simulation outside the clock), per step the least of ``--repeats`` runs after one
  warm-up run, the estimators in lockstep on the same arrivals (at each time each takes its step in turn, the order
  rotated from run to run, so that both sides of a ratio meet the same load of a shared machine): ``strict=True`` (its steps in the language; a refused
  step resets it there, untimed), ``strict=False`` on its steps in the design and on those out of it, and the
  zonotope estimator alone on the same steps; the ratios ``strict=False`` / zonotope, and the designed side
  (``strict=False`` in the design minus the zonotope on those steps, and its share of a zonotope step).
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.bounds.information import information_limit
from eqrec.design.delay.design import design_delay_global
from eqrec.design.delay.languages import delay_classes
from eqrec.design.inputs import missing_words_at_most
from eqrec.design.prefix.design import design_prefix
from eqrec.estimators.zonotope import ZonotopeEstimator
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure
from eqrec.estimators.protocol import OnTimeOnly
from eqrec.simulate.loop import closed_loop, what_arrived
from eqrec.systems.affine import AffineSystem
from eqrec.systems.examples import two_mass, zoh

MAX_DELAY, HORIZON, MAX_LOST = 2, 6, 1


def cart_chain(carts: int = 5, k: float = 1.0, c: float = 0.02, Ts: float = 0.1) -> AffineSystem:
    """``carts`` unit masses in a row joined by lightly damped springs; force on the first, every position
    measured (``n = 2 · carts``, ``p = carts``)."""
    n = 2 * carts
    Ac = np.zeros((n, n))
    for i in range(carts):
        Ac[2 * i, 2 * i + 1] = 1.0
        for j in (i - 1, i + 1):
            if 0 <= j < carts:
                Ac[2 * i + 1, 2 * i] -= k
                Ac[2 * i + 1, 2 * j] += k
                Ac[2 * i + 1, 2 * i + 1] -= c
                Ac[2 * i + 1, 2 * j + 1] += c
    Bc = np.zeros((n, 1))
    Bc[1, 0] = 1.0
    A, B = zoh(Ac, Bc, Ts)
    E = np.zeros((n, carts))
    E[1::2, :] = np.eye(carts)
    C = np.zeros((carts, n))
    C[np.arange(carts), 2 * np.arange(carts)] = 1.0
    return AffineSystem(A=A, B=B, C=C, E=E, eta_w=0.01, eta_v=0.05, name=f"chain of {carts} carts", dt=Ts)


def cart_pole(Ts: float = 0.05) -> AffineSystem:
    """A cart-pole linearised about the upright pole (one unstable mode, signed ``A``), the cart's position and the
    pole's angle measured (``n = 4``, ``p = 2``; the plant of ``tests/test_rounding.py``)."""
    from scipy.linalg import expm

    Ac = np.array([[0, 1, 0, 0], [0, -0.1, -1.0, 0], [0, 0, 0, 1], [0, 0.2, 9.81 / 0.5 * 0.3, -0.01]])
    return AffineSystem(A=expm(Ac * Ts), C=[[1.0, 0, 0, 0], [0, 0, 1.0, 0]], E=0.01 * np.eye(4), eta_w=0.1,
                        eta_v=0.01, name="cart-pole", dt=Ts)


def _runs(system, design, trace, seed):
    rng = np.random.default_rng(seed)
    N = trace.steps
    w = system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw))
    v = system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv))
    xi0 = design.mu1 * rng.choice([-1.0, 1.0], system.n)
    return w, v, xi0


def _row(name: str, r: np.ndarray) -> str:
    if r.size == 0:
        return f"{name:28s} {0:6d} {'-':>7s} {'-':>6s} {'-':>6s}"
    return f"{name:28s} {r.size:6d} {np.median(r):7.3f} {np.percentile(r, 95):6.3f} {r.max():6.3f}"


def tightness(system, design, args) -> None:
    makers = {"strict=False (tight)": lambda: design.estimator(strict=False),
              "strict=False, tight=False": lambda: design.estimator(strict=False, tight=False),
              "zonotope alone": lambda: ZonotopeEstimator(system, x0_radius=design.mu1, max_delay=HORIZON)}
    radius = dict.fromkeys(makers, design.mu1)  # the initial box each estimator assumes (its limit's too)
    try:  # the prefix-based paper's estimator: on-time packets only, at most MAX_LOST of HORIZON lost
        prefix = design_prefix(system, missing_words_at_most(HORIZON, MAX_LOST), "free")
        makers["prefix (P1), on time only"] = lambda: OnTimeOnly(prefix.estimator(strict=False), system.p)
        radius["prefix (P1), on time only"] = prefix.mu1
        print(f"  prefix (P1): mu1 = {prefix.mu1:.4g}; the initial error is drawn in the smaller box, each bound is "
              "divided by the limit for its own initial box")
    except (InfeasibleDesign, SolverFailure) as err:
        print(f"  prefix (P1): no design ({type(err).__name__}: {err})")
    ratios = {name: ([], []) for name in makers}
    worst = 0.0
    for seed in range(args.seeds):
        rng = np.random.default_rng(seed)
        trace = with_uniform_delays(rng, bernoulli_trace(rng, args.steps, args.loss), MAX_DELAY)
        w, v, xi0 = _runs(system, design, trace, seed + 100)
        xi0 = xi0 * (min(radius.values()) / design.mu1)  # inside every estimator's initial box
        limits = {r: information_limit(system, trace, r).max(axis=1) for r in set(radius.values())}
        flags = []
        tight = design.estimator(strict=False)
        closed_loop(system, tight, trace, np.zeros(system.n), xi0, w, v,
                    after_step=lambda k: flags.append(tight.in_design))
        flags = np.array(flags)
        for name, make in makers.items():
            out = closed_loop(system, make(), trace, np.zeros(system.n), xi0, w, v)
            r = np.asarray(out.bound) / limits[radius[name]]
            ratios[name][0].append(r[flags])
            ratios[name][1].append(r[~flags])
            err = np.abs(out.error[1:]).max(axis=1)
            worst = max(worst, float(np.max(err / np.asarray(out.bound))))
    print(f"bound / information limit per step ({args.seeds} seeds x {args.steps} steps, loss {args.loss}); "
          f"largest error / bound {worst:.17g}")
    print(f"{'':28s} {'steps':>6s} {'median':>7s} {'p95':>6s} {'max':>6s}")
    for where, k in (("in the design", 0), ("out of it", 1)):
        print(f"  {where}:")
        for name in makers:
            print("  " + _row(name, np.concatenate(ratios[name][k])))


def speed(system, design, args) -> None:
    rng = np.random.default_rng(7)
    steps = args.steps
    clean = with_uniform_delays(rng, bernoulli_trace(rng, steps, 0.0), MAX_DELAY)  # delays <= 2, no loss
    lossy = with_uniform_delays(rng, bernoulli_trace(rng, steps, args.loss), MAX_DELAY)
    w, v, xi0 = _runs(system, design, lossy, 5)
    x0 = np.zeros(system.n)

    def timed(make, trace):
        est = make()
        stamps, flags = [time.process_time()], []

        def after(k):
            stamps.append(time.process_time())
            flags.append(getattr(est, "in_design", True))

        closed_loop(system, est, trace, x0, xi0, w, v, after_step=after)
        return np.diff(stamps), np.array(flags)  # the first interval holds the reset and the first step

    best = {}
    cases = {"strict=True": (lambda: design.estimator(), clean, True),
             "strict=False, in design": (lambda: design.estimator(strict=False), clean, True),
             "strict=False, out of it": (lambda: design.estimator(strict=False), lossy, False),
             "zonotope alone, same trace": (lambda: ZonotopeEstimator(system, x0_radius=design.mu1,
                                                                       max_delay=HORIZON), clean, None),
             "zonotope alone, lossy trace": (lambda: ZonotopeEstimator(system, x0_radius=design.mu1,
                                                                         max_delay=HORIZON), lossy, None)}
    for _ in range(args.repeats):
        for name, (make, trace, inside) in cases.items():
            dt, flags = timed(make, trace)
            pick = dt[1:] if inside is None else dt[1:][flags[1:] == inside]
            if pick.size:
                best[name] = min(best.get(name, np.inf), float(np.mean(pick)) * 1e6)
    print("us per step (CPU time, best of %d, side by side): " % args.repeats
          + ", ".join(f"{k} {v:.0f}" for k, v in best.items())
          + f"; strict=False / zonotope on the same trace: in design "
            f"{best['strict=False, in design'] / best['zonotope alone, same trace']:.2f}, "
            f"out of it {best.get('strict=False, out of it', np.nan) / best['zonotope alone, lossy trace']:.2f}")


def _arrivals(system, design, trace, seed):
    """What reaches an estimator at each step of ``trace`` (the protocol's form), from one simulated run."""
    w, v, xi0 = _runs(system, design, trace, seed)
    x0 = np.zeros(system.n)
    run = closed_loop(system, ZonotopeEstimator(system, x0_radius=design.mu1, max_delay=HORIZON), trace, x0, xi0,
                      w, v)
    schedule = trace.schedule()
    return [what_arrived(schedule[k], k, run.y) for k in range(trace.steps)], x0 - xi0


def _lockstep_times(makes: list, arrived, xhat0, stricts: list, rotate: int) -> tuple[np.ndarray, np.ndarray]:
    """CPU time of each ``step`` call of several estimators run in lockstep on the same arrivals (at each time every
    estimator takes its step in turn, the order rotated by ``rotate``, so that each side of a ratio meets the same
    load of a shared machine), and whether each was in the design after it.  ``strict=True`` refuses a step outside
    the language (nothing changes): it is then reset at that time from its estimate and the step taken again,
    untimed (``nan``), so its times are those of the steps in the language."""
    ests = [make().reset(xhat0) for make in makes]
    times = np.full((len(ests), len(arrived)), np.nan)
    flags = np.zeros((len(ests), len(arrived)), bool)
    clock = time.process_time
    order = list(range(len(ests)))
    order = order[rotate % len(order):] + order[:rotate % len(order)]
    for k, y in enumerate(arrived):
        for j in order:
            est = ests[j]
            try:
                t0 = clock()
                est.step(y)
                times[j, k] = clock() - t0
            except InputError:
                if not stricts[j]:
                    raise
                est.reset(est.x, t0=est.time)
                est.step(y)
            flags[j, k] = getattr(est, "in_design", True)
    return times, flags


def cost_table(plants, args) -> None:
    """Issue 40 §3: µs per step of ``strict=True``, ``strict=False`` in the design and out of it, and the zonotope
    estimator alone, side by side in one run, at each loss rate (module docstring): the three run in lockstep, and
    each step's time is the least over ``--repeats`` runs."""
    losses = [float(x) for x in args.losses.split(",")]
    print(f"\nus per step (CPU time of step() alone, per step the least of {args.repeats} runs; the estimators run in "
          f"lockstep on the same arrivals, each step in turn, order rotated per run; delays 0..{MAX_DELAY} uniform, "
          "Bernoulli loss; the zonotope on the same steps)")
    head = (f"{'plant':22s} {'loss':>5s} {'in/out':>7s} {'strict=True':>11s} {'False in':>9s} {'zono in':>8s} "
            f"{'ratio':>6s} {'False out':>9s} {'zono out':>8s} {'ratio':>6s} {'designed side':>14s}")
    print(head)
    for system, design, steps in plants:
        for loss in losses:
            rng = np.random.default_rng(11)
            trace = with_uniform_delays(rng, bernoulli_trace(rng, steps, loss), MAX_DELAY)
            arrived, xhat0 = _arrivals(system, design, trace, 3)
            names = ["true", "false", "zono"]
            makes = [lambda: design.estimator(), lambda: design.estimator(strict=False),
                     lambda: ZonotopeEstimator(system, x0_radius=design.mu1, max_delay=HORIZON)]
            best = None
            for rep in range(args.repeats + 1):  # the first run warms the caches (compiled code, class maps)
                dt, fl = _lockstep_times(makes, arrived, xhat0, [True, False, False], rep)
                if rep:
                    best = dt if best is None else np.fmin(best, dt)
            flags = fl[1]
            us = {name: best[j] * 1e6 for j, name in enumerate(names)}
            inside, outside = flags.copy(), ~flags
            inside[0] = outside[0] = False  # the first step holds the estimators' first-use work

            def mean(name, where):
                sel = us[name][where]
                sel = sel[np.isfinite(sel)]
                return float(np.mean(sel)) if sel.size else np.nan

            f_in, z_in, f_out, z_out = mean("false", inside), mean("zono", inside), mean("false", outside), \
                mean("zono", outside)
            side = f_in - z_in
            print(f"{system.name[:22]:22s} {loss:5.0%} {int(inside.sum()):3d}/{int(outside.sum()):<3d} "
                  f"{mean('true', np.isfinite(us['true'])):11.0f} {f_in:9.0f} {z_in:8.0f} {f_in / z_in:6.2f} "
                  f"{f_out:9.0f} {z_out:8.0f} {f_out / z_out:6.2f} {side:7.0f} ({side / z_in:4.0%})")


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=120)
    ap.add_argument("--seeds", type=int, default=2)
    ap.add_argument("--loss", type=float, default=0.4)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--part", choices=("all", "tightness", "cost"), default="all",
                    help="tightness and speed per plant, the cost table (issue 40 §3), or both (default)")
    ap.add_argument("--losses", default="0,0.2,0.4", help="loss rates of the cost table (comma-separated)")
    ap.add_argument("--cost-steps", default="120,120,60",
                    help="steps of the cost table per plant: two carts, cart-pole, chain of five carts")
    ap.add_argument("--plants", default="carts,cart-pole,chain",
                    help="plants to run (comma-separated): carts (two carts), cart-pole, chain (five carts)")
    args = ap.parse_args(argv)
    plants = []
    chosen = args.plants.split(",")
    for key, system, steps in zip(("carts", "cart-pole", "chain"), (two_mass(), cart_pole(), cart_chain(5)),
                                  (int(x) for x in args.cost_steps.split(","))):
        if key not in chosen:
            continue
        t0 = time.perf_counter()
        try:
            design = design_delay_global(system, delay_classes(max_delay=MAX_DELAY, horizon=HORIZON,
                                                               max_lost=MAX_LOST)).design
        except Exception as err:  # a plant the language cannot be designed for: say so, go on
            print(f"{system.name}: no design ({type(err).__name__}: {err})")
            continue
        plants.append((system, design, steps))
        if args.part in ("all", "tightness"):
            print(f"\n{system.name} (n = {system.n}, p = {system.p}): delays 0..{MAX_DELAY}, <= {MAX_LOST} of "
                  f"{HORIZON} lost, mu1 = {design.mu1:.4g} ({time.perf_counter() - t0:.1f} s)")
            tightness(system, design, args)
            speed(system, design, args)
    if args.part in ("all", "cost"):
        cost_table(plants, args)


if __name__ == "__main__":
    main()
