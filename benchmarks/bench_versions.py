"""µs per step of two versions of the package side by side in one process (issue 40 §3: old vs new, back to back).

    python benchmarks/bench_versions.py --old /path/to/old/src [--plants carts,cart-pole,chain] [--losses 0,0.2,0.4]

The package is imported twice, from ``--old`` and from this tree's ``src`` (each keeps its own modules), and the
cost table of ``benchmarks/bench_tight.py --part cost`` is measured for both in one lockstep: at each time the eight
estimators (``strict=True``, ``strict=False`` and the zonotope alone, of each version) take their step in turn on
the same arrivals (each version's own packets, the same numbers), the order rotated from run to run, so that every
column meets the same load of a shared machine.  Per step the least of ``--repeats`` runs after one warm-up; CPU µs
of ``step()`` alone.  Printed per plant and loss: ``strict=True``, ``strict=False`` in the design and out of it, the
zonotope alone on the same steps, and the ratios, for old and new.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def _ours(name: str) -> bool:
    return name == "eqrec" or name.startswith("eqrec.") or name == "bench_tight"


def _install(modules: dict) -> None:
    """Make one version's modules the imported ones (a function importing at call time gets its own version)."""
    for name in [m for m in sys.modules if _ours(m)]:
        del sys.modules[name]
    sys.modules.update(modules)


def _load(src: str):
    """The package and the bench helpers imported from ``src``, and that version's modules."""
    for name in [m for m in sys.modules if _ours(m)]:
        del sys.modules[name]
    sys.path.insert(0, src)
    sys.path.insert(0, str(HERE))
    try:
        bt = importlib.import_module("bench_tight")
        eq = importlib.import_module("eqrec")
        assert Path(eq.__file__).resolve().is_relative_to(Path(src).resolve()), eq.__file__
    finally:
        sys.path.remove(src)
        sys.path.remove(str(HERE))
    return bt, {m: mod for m, mod in sys.modules.items() if _ours(m)}


def _setup(version, key, loss, steps):
    bt, modules = version
    _install(modules)
    system = {"carts": bt.two_mass, "cart-pole": bt.cart_pole, "chain": lambda: bt.cart_chain(5)}[key]()
    design = bt.design_delay_global(system, bt.delay_classes(max_delay=bt.MAX_DELAY, horizon=bt.HORIZON,
                                                             max_lost=bt.MAX_LOST)).design
    rng = np.random.default_rng(11)
    trace = bt.with_uniform_delays(rng, bt.bernoulli_trace(rng, steps, loss), bt.MAX_DELAY)
    arrived, xhat0 = bt._arrivals(system, design, trace, 3)
    makes = [lambda: design.estimator(), lambda: design.estimator(strict=False),
             lambda: bt.ZonotopeEstimator(system, x0_radius=design.mu1, max_delay=bt.HORIZON)]
    return makes, arrived, xhat0, bt.InputError, modules


def _lockstep(groups, rotate):
    """``groups``: per version (makes, arrived, xhat0, InputError); the CPU time of each step of each estimator."""
    ests, ins, errs = [], [], []
    for makes, arrived, xhat0, err, modules in groups:
        _install(modules)
        for j, mk in enumerate(makes):
            ests.append((mk().reset(xhat0), arrived, j == 0, err, modules))
    N = len(groups[0][1])
    times = np.full((len(ests), N), np.nan)
    flags = np.zeros((len(ests), N), bool)
    order = list(range(len(ests)))
    order = order[rotate % len(order):] + order[:rotate % len(order)]
    clock = time.process_time
    for k in range(N):
        for j in order:
            est, arrived, strict, err, modules = ests[j]
            _install(modules)  # outside the clock
            y = arrived[k]
            try:
                t0 = clock()
                est.step(y)
                times[j, k] = clock() - t0
            except err:
                if not strict:
                    raise
                est.reset(est.x, t0=est.time)
                est.step(y)
            flags[j, k] = getattr(est, "in_design", True)
    return times, flags


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--old", required=True, help="the src folder of the old version")
    ap.add_argument("--plants", default="carts,cart-pole,chain")
    ap.add_argument("--losses", default="0,0.2,0.4")
    ap.add_argument("--steps", default="120,120,60", help="steps per plant: carts, cart-pole, chain")
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args(argv)
    versions = {"old": _load(args.old), "new": _load(str(HERE.parent / "src"))}
    steps = dict(zip(("carts", "cart-pole", "chain"), (int(s) for s in args.steps.split(","))))
    print(f"CPU us per step, per step the least of {args.repeats} runs, old and new in one lockstep")
    print(f"{'plant':10s} {'loss':>5s} {'ver':>4s} {'in/out':>7s} {'strict=True':>11s} {'False in':>9s} "
          f"{'zono in':>8s} {'ratio':>6s} {'False out':>9s} {'zono out':>8s} {'ratio':>6s}")
    for key in args.plants.split(","):
        for loss in (float(x) for x in args.losses.split(",")):
            groups = [_setup(version, key, loss, steps[key]) for version in versions.values()]
            best = None
            for rep in range(args.repeats + 1):
                dt, fl = _lockstep(groups, rep)
                if rep:
                    best = dt if best is None else np.fmin(best, dt)
            for v, name in enumerate(versions):
                us = best[3 * v:3 * v + 3] * 1e6
                flags = fl[3 * v + 1]
                inside, outside = flags.copy(), ~flags
                inside[0] = outside[0] = False

                def mean(j, where):
                    sel = us[j][where]
                    sel = sel[np.isfinite(sel)]
                    return float(np.mean(sel)) if sel.size else np.nan

                t_true = mean(0, np.isfinite(us[0]))
                f_in, z_in, f_out, z_out = mean(1, inside), mean(2, inside), mean(1, outside), mean(2, outside)
                print(f"{key:10s} {loss:5.0%} {name:>4s} {int(inside.sum()):3d}/{int(outside.sum()):<3d} "
                      f"{t_true:11.0f} {f_in:9.0f} {z_in:8.0f} {f_in / z_in:6.2f} {f_out:9.0f} {z_out:8.0f} "
                      f"{f_out / z_out:6.2f}", flush=True)


if __name__ == "__main__":
    main()
