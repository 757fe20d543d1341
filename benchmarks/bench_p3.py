"""Benchmark of the P3 (delayed-data) designs on the batch reactor, measured in one run.

    python benchmarks/bench_p3.py                      # parts 1 and 2, scale table up to (6, 2)
    python benchmarks/bench_p3.py --sizes 5,2 6,2 7,2 8,2 8,3 --time-limit 600 --mem-limit-gb 16
    python benchmarks/bench_p3.py --only scale --sizes 7,2 --methods ipm
    python benchmarks/bench_p3.py --only scale --engines classes --sizes 20,4 30,4 --methods simplex

1. ``μ1`` fixed, all 243 words (162 event sequences), sum cost: the tree LP's
   build, solve, recover, certify (goal: <= 1.5 s end to end on 2 cores), and
   the class engine's ``design_delay`` end to end beside it.
2. ``μ1`` free with its global certificate: ``design_delay_global`` (the
   smallest feasible ``μ1`` by one Charnes–Cooper LP, certified; the μ1-free
   theorem of :mod:`eqrec.design.classes.engine`; goal <= 20 s) and the paper's
   route (``design_delay_ipopt``: IPOPT on problem (10) from the LP at ``μ1 = 1``).
3. Scale table for the full language ``{0..τ̄}^T`` (``--engines tree classes``):
   words, reduced sequences, prefix-tree nodes, classes, LP rows / columns /
   nonzeros, build and
   solve time and peak memory, one fresh process per (size, method) so the
   peak memory is that size's (``ru_maxrss`` of the worker).  Methods:
   ``simplex`` (HiGHS dual simplex), ``ipm`` (HiGHS interior point with
   crossover off), ``ipm-x`` (interior point + crossover), ``pdlp`` (HiGHS's
   first-order PDLP: matrix-vector products only); ``-np``: presolve off.  A worker that
   exceeds ``--time-limit`` (HiGHS time limit, plus a wall-clock kill) or
   ``--mem-limit-gb`` (address-space limit) is reported as such.
   ``--engines classes`` measures the class engine
   (``benchmarks/bench_classes.py`` has its targets).  The worker is
   :func:`eqrec.studies.p3.size_run.run_size` (shared with the P3 scale steps
   of the pipeline).
"""

from __future__ import annotations

import argparse
import statistics
import time

from eqrec.studies.p3.size_run import ENGINES, METHODS, run_size
from eqrec.systems.examples import batch_reactor


def part_fixed(repeats: int) -> None:
    from eqrec.bounds.certify import certify_design
    from eqrec.lp.solvers import solve_lp
    from eqrec.design.delay.design import design_from_solution, delay_language, design_delay
    from eqrec.design.prefix.tree_lp import build_prefix_lp
    from eqrec.arrivals.prefix_tree import PrefixTree
    from eqrec.systems.examples import batch_reactor

    system = batch_reactor()
    design_delay(system, delay_language(max_delay=2, horizon=5), 0.33)  # warm-up (imports, caches)
    rows = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        tree = PrefixTree(delay_language(max_delay=2, horizon=5))
        model = build_prefix_lp(system, tree, 0.33, levels="sum")
        t1 = time.perf_counter()
        sol = solve_lp(model.lp, "highs").require_optimal()
        t2 = time.perf_counter()
        d = design_from_solution(model, tree, sol.x, 0.33, "sum", sol, certify=False)
        t3 = time.perf_counter()
        certify_design(d)
        t4 = time.perf_counter()
        rows.append({"build": t1 - t0, "solve": t2 - t1, "recover": t3 - t2, "certify": t4 - t3, "total": t4 - t0})
    keys = ("build", "solve", "recover", "certify", "total")
    print(f"\n1. mu1 = 0.33 fixed, 243 words -> {len(tree.patterns)} sequences, {len(tree)} nodes, "
          f"LP {model.lp.shape[0]} x {model.lp.shape[1]}, nnz {model.lp.A.nnz}; max mu2 = {d.mu2:.6f}")
    print("   " + "  ".join(f"{k:>8}" for k in keys) + f"   (s; best | median of {repeats})")
    print("   " + "  ".join(f"{min(r[k] for r in rows):8.3f}" for k in keys) + "   best")
    print("   " + "  ".join(f"{statistics.median(r[k] for r in rows):8.3f}" for k in keys) + "   median")
    print(f"   goal <= 1.5 s end to end: {'met' if statistics.median(r['total'] for r in rows) <= 1.5 else 'NOT met'}")
    words = delay_language(max_delay=2, horizon=5)
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        dc = design_delay(system, words, 0.33, engine="classes")
        times.append(time.perf_counter() - t0)
    print(f"   class engine, design_delay end to end (classes, LPs, node gains, certificate): "
          f"{statistics.median(times):.3f} s median, {min(times):.3f} s best; max mu2 = {dc.mu2:.6f} "
          f"(tree {d.mu2:.6f})")


def part_free() -> None:
    from eqrec.arrivals.words import full_delay_language
    from eqrec.design.delay.design import design_delay_global
    from eqrec.design.delay.ipopt import compare_free_routes, design_delay_ipopt
    from eqrec.systems.examples import batch_reactor

    system = batch_reactor()
    words = full_delay_language(5, 2)
    print("\n2. mu1 free, sum cost, 243 words")
    g = design_delay_global(system, words, cost="sum")
    ip = design_delay_ipopt(system, words, cost="sum", start_mu1=1.0)
    mm = g.mu1_min
    print(f"   {'global':13} mu1 = {g.mu1:.8f} (certified smallest in ({mm.lower:.8f}, {mm.upper:.8f}]), "
          f"J = {g.J:.6f} >= {g.lower_bound:.6f} (gap {g.gap:.1e}), max mu2 = {g.mu2:.6f}, "
          f"{g.lps} LPs ({mm.lps} for mu1_min), {g.time:.3f} s")
    pol = (ip.ipopt.polished or {})
    print(f"   {'ipopt (10)':13} mu1 = {ip.mu1:.8f} (its gains reach {ip.ipopt.mu1_of_gains:.8f}), "
          f"J = {ip.J:.6f}, max mu2 = {ip.mu2:.6f}, {ip.ipopt.iterations} iterations, "
          f"IPOPT {ip.ipopt.ipopt_time:.2f} s, total {ip.time:.2f} s; LP polish at its mu1: J = {pol.get('J'):.6f}")
    cmp = compare_free_routes(g, ip)
    print(f"   better: {cmp['better']} (tolerance {cmp['tolerance']:.1e}); IPOPT consistent with the global bound: "
          f"{cmp['ipopt_consistent_with_bound']}; goal <= 20 s: {'met' if g.time <= 20 else 'NOT met'}")


def part_scale(sizes, methods, mu1: float, limit: float, mem_gb: float, builders=("core",),
               engines=("tree",)) -> None:
    print(f"\n3. scale table, full language {{0..tau}}^T, batch reactor, sum cost, mu1 = {mu1}, split robust form; "
          f"one process per row; time limit {limit:g} s, memory limit {mem_gb:g} GB")
    hdr = (f"   {'T':>2} {'tau':>3} {'words':>9} {'seqs':>9} {'nodes':>9} {'classes':>7} {'engine':>7} {'builder':>9} "
           f"{'rows':>9} {'cols':>9} {'nnz':>10} {'build s':>8} {'method':>7} {'solve s':>8} {'iters':>7} "
           f"{'peak MB':>8} {'J':>14}  status")
    print(hdr)
    runs = [(e, bd) for e in engines for bd in (builders if e == "tree" else ("core",))]
    for T, tb in sizes:
        for (engine, builder), method in [(eb, m) for eb in runs for m in methods]:
            if engine == "classes" and method == "none":
                continue
            r = run_size(batch_reactor(), T, tb, method, mu1, limit, mem_gb, builder, engine=engine)
            g = r.get
            big = lambda k: f"{g(k):.3g}" if isinstance(g(k), int) and g(k) >= 10**9 else g(k, "")  # noqa: E731
            print(f"   {T:>2} {tb:>3} {big('words'):>9} {big('sequences'):>9} {big('nodes'):>9} {g('classes', ''):>7} "
                  f"{engine:>7} {g('builder', ''):>9} {g('rows', ''):>9} {g('cols', ''):>9} {g('nnz', ''):>10} "
                  f"{g('build_time', float('nan')):8.2f} {method:>7} {g('solve_time', float('nan')):8.2f} "
                  f"{g('iterations', ''):>7} {g('peak_mb', float('nan')):8.0f} {g('J', float('nan')):14.6g}  "
                  f"{g('status', '')}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", choices=["fixed", "free", "scale"], action="append")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--sizes", nargs="+", default=["5,2", "6,2"], help="T,tau pairs for the scale table")
    ap.add_argument("--methods", nargs="+", default=["simplex", "ipm"], choices=list(METHODS))
    ap.add_argument("--builders", nargs="+", default=["core"], choices=["core"],
                    help="core: eqrec.design.prefix.tree_lp.build_prefix_lp")
    ap.add_argument("--engines", nargs="+", default=["tree", "classes"], choices=list(ENGINES),
                    help="tree: the node-per-prefix LP; classes: the class engine")
    ap.add_argument("--mu1", type=float, default=0.5)
    ap.add_argument("--time-limit", type=float, default=600.0)
    ap.add_argument("--mem-limit-gb", type=float, default=16.0)
    a = ap.parse_args()
    parts = a.only or ["fixed", "free", "scale"]
    if "fixed" in parts:
        part_fixed(a.repeats)
    if "free" in parts:
        part_free()
    if "scale" in parts:
        sizes = [tuple(int(v) for v in s.split(",")) for s in a.sizes]
        part_scale(sizes, a.methods, a.mu1, a.time_limit, a.mem_limit_gb, a.builders, tuple(a.engines))


if __name__ == "__main__":
    main()
