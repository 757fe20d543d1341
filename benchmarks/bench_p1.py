"""Benchmark of the P1 designs: build, solve and total times, and modelling overhead.

Goals (issue 2): prefix-based L1 design <= 30 ms end to end on the 2-core
machine (the paper reports 0.11 s with YALMIP + Gurobi); modelling overhead
(everything but the solver call) <= 50 % of the solver time.

    python benchmarks/bench_p1.py [--repeats 20]

Prints the best and median of each phase over the repeats, measured in one run.
"""

from __future__ import annotations

import argparse
import statistics
import time

from eqrec.core.certify import certify_design
from eqrec.design.prefix import Design, build_prefix_lp, read_schedule
from eqrec.core.patterns import worst_case_word
from eqrec.core.lp import solve_lp
from eqrec.core.systems import acc_system

L1 = ["101111", "110111", "111011", "111101"]


def one(system, words, solver, method):
    t0 = time.perf_counter()
    model = build_prefix_lp(system, words, 1.0)
    t1 = time.perf_counter()
    sol = solve_lp(model.lp, solver).require_optimal()
    t2 = time.perf_counter()
    sched = read_schedule(model, sol, time_based=(method == "time"))
    design = Design(method=method, system=system, words=model.tree.words, T=6, M1=1.0, mu2=float(sol.x[model.mu2_col]),
                    schedule=sched, solution=sol, build_time=t1 - t0)
    certify_design(design)
    t3 = time.perf_counter()
    return {"build": t1 - t0, "solve": t2 - t1, "recover+certify": t3 - t2, "total": t3 - t0,
            "iterations": sol.iterations, "shape": model.lp.shape}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=20)
    a = ap.parse_args()
    system = acc_system()
    cases = [("prefix", L1), ("time", [worst_case_word(L1)])]
    print(f"{'design':8} {'solver':9} {'rows x cols':>12} {'iters':>6} {'build':>8} {'solve':>8} {'rec+cert':>9} "
          f"{'total':>8} {'overhead/solve':>15}   (ms, best | median of {a.repeats})")
    for method, words in cases:
        for solver in ("highs", "clarabel"):
            one(system, words, solver, method)  # warm-up (imports, caches)
            runs = [one(system, words, solver, method) for _ in range(a.repeats)]
            best = {k: min(r[k] for r in runs) for k in ("build", "solve", "recover+certify", "total")}
            med = {k: statistics.median(r[k] for r in runs) for k in best}
            overhead = (med["total"] - med["solve"]) / med["solve"]
            shape = "x".join(map(str, runs[0]["shape"]))
            print(f"{method:8} {solver:9} {shape:>12} {runs[0]['iterations']:>6} "
                  f"{1e3 * best['build']:8.1f} {1e3 * best['solve']:8.1f} {1e3 * best['recover+certify']:9.1f} "
                  f"{1e3 * best['total']:8.1f} {100 * overhead:14.0f}%   median total {1e3 * med['total']:.1f}")
    print("goals: prefix total <= 30 ms; overhead <= 50 % of solve time")


if __name__ == "__main__":
    main()
