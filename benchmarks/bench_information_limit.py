"""Cost per step of the information limit (:func:`eqrec.information_limit`), its window and its cache (figures,
not tests).

    python benchmarks/bench_information_limit.py [--lengths 40,100,400] [--losses 0.1,0.3] [--runs 3]

Rows: ACC (n = 3) and the batch reactor (n = 4), delays 0..1 with Bernoulli losses, one trace per run; each
figure is the median over ``--runs`` traces of the time per step, exact (cache cleared before each trace) and with
``window=20`` (with the largest ratio windowed / exact: the window errs upward).  ``ms/step`` is wall-clock,
``cpu`` the process time (HiGHS threads included; the machine is shared, so the CPU figure is the steadier).
Then the cache: ``--runs`` distinct traces each asked three times (as three families of one comparison run
would), its hit rate and the cost per asked step.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.bounds.information import cache_info, clear_cache, information_limit
from eqrec.systems.examples import acc_system, batch_reactor


def _trace(N: int, loss: float, seed: int) -> ArrivalTrace:
    rng = np.random.default_rng(seed)
    return ArrivalTrace(np.where(rng.random(N) < loss, NEVER, rng.integers(0, 2, N)))


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
    args = ap.parse_args(argv)
    lengths = [int(v) for v in args.lengths.split(",")]
    losses = [float(v) for v in args.losses.split(",")]
    plants = {"ACC": (acc_system(), 0.5), "batch reactor": (batch_reactor(), 1.0)}
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
