"""Benchmark of the P1 designs: build, solve and total times, and modelling overhead.

Goals (issue 2): prefix-based L1 design <= 30 ms end to end on the 2-core
machine (the paper reports 0.11 s with YALMIP + Gurobi); modelling overhead
(everything but the solver call) <= 50 % of the solver time.

    python benchmarks/bench_p1.py [--repeats 20] [--compare REV]

Prints the best and median of each phase over the repeats, measured in one run.
With ``--compare REV`` (e.g. ``00ee815``, the version before the arrival-pattern
core) it also times ``design_prefix`` end to end (build, solve, recover,
certify) in a git worktree of REV and in this tree, in interleaved rounds of
fresh interpreters, and prints the ratio of the medians (this / REV).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from eqrec.bounds.certify import certify_design
from eqrec.arrivals.words import worst_case_word
from eqrec.lp.solvers import solve_lp
from eqrec.systems.examples import acc_system
from eqrec.design.prefix.tree_lp import build_prefix_lp, read_schedule
from eqrec.design.result import Design

L1 = ["101111", "110111", "111011", "111101"]


def one(system, words, solver, method):
    t0 = time.perf_counter()
    model = build_prefix_lp(system, words, 1.0)
    t1 = time.perf_counter()
    sol = solve_lp(model.lp, solver).require_optimal()
    t2 = time.perf_counter()
    sched = read_schedule(model, sol, time_based=(method == "time"))
    design = Design(method=method, system=system, patterns=model.tree.patterns, T=6, mu1=1.0,
                    mu2=float(sol.x[model.mu2_col]),
                    schedule=sched, solution=sol, build_time=t1 - t0)
    certify_design(design)
    t3 = time.perf_counter()
    return {"build": t1 - t0, "solve": t2 - t1, "recover+certify": t3 - t2, "total": t3 - t0,
            "iterations": sol.iterations, "shape": model.lp.shape}


# Timed in a fresh interpreter of either version: design_prefix end to end on L1 (prefix and time-based).
WORKER = r"""
import json, statistics, sys, time
try:  # the layout of issue 25 (rooms and engine subpackages)
    from eqrec.design.prefix.design import design_prefix
    from eqrec.systems.examples import acc_system
except ImportError:
    try:
        from eqrec.design.prefix import design_prefix
        try:
            from eqrec.core.acc import acc_system
        except ImportError:  # layout before the core split of issue 18
            from eqrec.core.systems import acc_system
    except ImportError:  # layout before the arrival-pattern core
        from eqrec.design_prefix import design_prefix
        from eqrec.systems import acc_system
L1 = ["101111", "110111", "111011", "111101"]
acc = acc_system()
out = {}
for name, words in (("prefix", L1), ("time", ["100001"])):
    design_prefix(acc, words, 1.0)
    ts = []
    for _ in range(int(sys.argv[1])):
        t0 = time.perf_counter(); d = design_prefix(acc, words, 1.0); ts.append(time.perf_counter() - t0)
    out[name] = {"median": statistics.median(ts), "mu2": d.mu2}
print(json.dumps(out))
"""


def compare(rev: str, repeats: int, rounds: int = 5) -> None:
    """Ratio of the end-to-end design time of this tree to that of ``rev``, measured in one run."""
    root = Path(__file__).resolve().parents[1]
    with tempfile.TemporaryDirectory() as tmp:
        wt = Path(tmp) / "old"
        subprocess.run(["git", "-C", str(root), "worktree", "add", "--detach", str(wt), rev], check=True,
                       capture_output=True)
        try:
            res: dict[str, list[dict]] = {"this": [], rev: []}
            for _ in range(rounds):
                for name, src in (("this", root / "src"), (rev, wt / "src")):
                    env = {**os.environ, "PYTHONPATH": str(src)}
                    p = subprocess.run([sys.executable, "-c", WORKER, str(repeats)], env=env, check=True,
                                       capture_output=True, text=True, cwd=tmp)
                    res[name].append(json.loads(p.stdout))
        finally:
            subprocess.run(["git", "-C", str(root), "worktree", "remove", "--force", str(wt)], capture_output=True)
    print(f"\nend-to-end design_prefix (build, solve, recover, certify), median over {rounds} rounds x {repeats}:")
    for case in ("prefix", "time"):
        new = statistics.median(r[case]["median"] for r in res["this"])
        old = statistics.median(r[case]["median"] for r in res[rev])
        same = res["this"][0][case]["mu2"] == res[rev][0][case]["mu2"]
        print(f"  {case:7} this {1e3 * new:7.2f} ms   {rev} {1e3 * old:7.2f} ms   ratio this/{rev} = {new / old:.3f}"
              f"   mu2 identical: {same}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--repeats", type=int, default=20)
    ap.add_argument("--compare", metavar="REV", help="also time git revision REV and print the ratio")
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
    if a.compare:
        compare(a.compare, a.repeats)


if __name__ == "__main__":
    main()
