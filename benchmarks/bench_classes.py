"""Benchmark of the class engine against the tree LP, measured side by side in one run (figures, not tests).

    python benchmarks/bench_classes.py                 # all parts
    python benchmarks/bench_classes.py --only a --repeats 50
    python benchmarks/bench_classes.py --only c --sizes 8,3 20,4 30,4 40,4 30,5
    python benchmarks/bench_classes.py --only d --free-sizes 4,60 --configs blocks-1 blocks-2

a. The prefix-based paper's design end to end (build, solve, gains,
   certificate) on the ACC language L1 (``101111, 110111, 111011, 111101``,
   ``μ1 = 1``): :func:`eqrec.design.prefix.design.design_prefix` with
   ``engine="classes"`` in class form (gains ``K``, certificate from them),
   with node gains derived and certified by the recursion, and
   ``engine="tree"``.  Targets (class form): <= 5 ms and <= 0.3x the tree.
b. The batch reactor's ``{0..2}^5`` with ``μ1`` free and its certificate:
   :func:`eqrec.design.delay.design.design_delay_global` in class form (class gains,
   class certificate, the μ1 bracket; target <= 100 ms; with node gains
   printed beside it) against
   the paper's route, IPOPT on problem (10)
   (:func:`eqrec.design.delay.ipopt.design_delay_ipopt`).  The previous global
   route (Dinkelbach + interval branch and bound on the tree LP, removed in
   commit b2da9c6) is quoted from git history, not measured: 2.5 s
   (``results/p3/reactor_designs.json``, ``global.time_s`` = 2.497 s at commit
   52958df; 1.65 to 3.0 s in the regenerated results up to 3973e51).
c. Full languages ``{0..τ̄}^T`` on the batch reactor (sum cost, ``μ1 = 0.5``
   fixed) by the class engine, one fresh process per run through
   :func:`eqrec.studies.p3.size_run.run_size` so that the peak memory is that
   size's.  The time is the design's: class set + LP build + HiGHS solve
   (+ the certificate inside ``solve_classes``), measured in the worker;
   the worker's wall time (interpreter start and imports included) is printed
   beside it.  Targets: (8, 3) <= 1 s, (20, 4) <= 5 s, (30, 4) <= 10 s and
   <= 1 GB peak.

d. Issue 27: the batch reactor's full language ``{0..τ̄}^T`` with ``μ1`` free
   (:func:`eqrec.design.delay.design.design_delay_global` on
   :func:`eqrec.design.delay.design.delay_classes`), one fresh process per size and
   configuration: the one block LP (``monolithic``: today's algorithm, forced
   through ``class_blocks.MONOLITHIC_MAX_WORK``), per class on 1 and 2 worker
   processes (``n_jobs``), and per class on a ``dask.distributed.LocalCluster``
   (2 worker processes, 1 thread each; its start not counted).  ``cold``: the
   first design in the process (the worker pool starts inside it, as for the
   CLI); ``warm``: the median of the next ``--warm-repeats`` (the pool already
   up); peak memory: the main process and the largest worker (``VmHWM``).  The
   sizes are ``(τ̄, T)``.  Targets: (4, 100) <= 20 s and <= 1 GB; (5, 60) <= 15 s;
   (4, 60) <= 5 s; (30, 4) = (τ̄, T) = (4, 30) not slower than the one block LP;
   speed-up from 1 to 2 workers >= 1.7x at (4, 60) (warm, and cold beside it).

e. Issue 41: the construction of the classes of ``{0..τ̄}^T`` alone
   (:func:`eqrec.delay_classes`, no word, no design) at ``T`` = 1,000 / 2,000
   / 4,000 / 8,000 (``--class-horizons``), ``τ̄`` = 1 and 2
   (``--class-delays``), beside the previous construction (data as tuples,
   weights as integers, quadratic in ``T``; kept in
   ``tests/test_window_classes.py``) in the same run, with the growth
   exponent of each (least squares of ``log t`` on ``log T``) and the size
   model's estimate (:meth:`eqrec.design.inputs.ClassShape.build_cost`).
   Target: exponent <= 1.2 (linear in ``T``); the same classes.

Medians over ``--repeats`` (part c: ``--size-repeats`` fresh processes per
size, peak memory the largest).  The last table lists every target with
PASS or MISS.  Timings depend on the machine's load (2 shared cores here).
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import time

ACC_L1 = ["101111", "110111", "111011", "111101"]
HISTORICAL_GLOBAL_S = 2.497  # results/p3/reactor_designs.json global.time_s at commit 52958df (old global route)

#: (label, target seconds, target peak MB or None) of part c.
SIZE_TARGETS = {(8, 3): (1.0, None), (20, 4): (5.0, None), (30, 4): (10.0, 1024.0)}
#: Part d: (τ̄, T) -> (target seconds, target peak MB) of the per-class design on 2 workers (cold).
FREE_TARGETS = {(4, 100): (20.0, 1024.0), (5, 60): (15.0, None), (4, 60): (5.0, None)}
#: Part d configurations: label -> (n_jobs, dask, monolithic).
CONFIGS = {"monolithic": (1, False, True), "blocks-1": (1, False, False), "blocks-2": (2, False, False),
           "dask-2": (2, True, False)}


def _median_time(fn, repeats: int) -> tuple[float, float, object]:
    times, out = [], None
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), out


def part_a(repeats: int, verdicts: list) -> None:
    from eqrec.systems.examples import acc_system
    from eqrec.design.prefix.design import design_prefix

    system = acc_system()
    print(f"\na. P1 prefix design end to end (build, solve, gains, certificate), ACC L1 = {ACC_L1}, mu1 = 1; "
          f"median | best of {repeats}")
    res = {}
    variants = {"classes": dict(engine="classes", node_gains=False),
                "classes+nodes": dict(engine="classes", node_gains=True), "tree": dict(engine="tree")}
    for name, kw in variants.items():
        design_prefix(system, ACC_L1, 1.0, **kw)  # warm-up (imports, caches)
        med, best, d = _median_time(lambda: design_prefix(system, ACC_L1, 1.0, **kw), repeats)
        res[name] = (med, best, d)
        what = ("class gains K + class certificate" if name == "classes" else
                "+ node gains (F, u0) and their certificate by the recursion" if name == "classes+nodes" else
                "tree LP, node gains, certificate")
        print(f"   {name:14} {1e3 * med:9.2f} ms | {1e3 * best:8.2f} ms   M2 = {d.mu2:.9f}  ({what})")
    (mc, _, dc), (mn, _, _), (mt, _, dt) = res["classes"], res["classes+nodes"], res["tree"]
    ratio = mc / mt
    print(f"   ratio classes / tree = {ratio:.3f}  ({mt / mc:.1f}x faster); with node gains {mn / mt:.3f}; "
          f"|M2 difference| = {abs(dc.mu2 - dt.mu2):.2e}")
    verdicts.append(("a", "ACC L1 design_prefix, class form", f"{1e3 * mc:.2f} ms", "<= 5 ms", mc <= 5e-3))
    verdicts.append(("a", "ACC L1 class form / tree", f"{ratio:.3f}x", "<= 0.3x", ratio <= 0.3))
    verdicts.append(("a", "ACC L1 with node gains / tree (no target)", f"{mn / mt:.3f}x", "-", True))


def part_b(repeats: int, ipopt_repeats: int, verdicts: list) -> None:
    from eqrec.arrivals.words import full_delay_language
    from eqrec.design.delay.design import design_delay_global
    from eqrec.design.delay.ipopt import compare_free_routes, design_delay_ipopt
    from eqrec.systems.examples import batch_reactor

    system = batch_reactor()
    words = full_delay_language(5, 2)
    print(f"\nb. batch reactor {{0..2}}^5 (243 words, 162 sequences), mu1 free, sum cost, with certificate; "
          f"median | best of {repeats} (IPOPT: {ipopt_repeats})")
    design_delay_global(system, words, node_gains=False)  # warm-up
    mg, bg, g = _median_time(lambda: design_delay_global(system, words, node_gains=False), repeats)
    mn, bn, _ = _median_time(lambda: design_delay_global(system, words), repeats)
    print(f"   with node gains for the 162 sequences and their certificate by the recursion: {1e3 * mn:.1f} ms | "
          f"{1e3 * bn:.1f} ms")
    mm = g.mu1_min
    print(f"   design_delay_global  {1e3 * mg:9.1f} ms | {1e3 * bg:8.1f} ms   mu1 = {g.mu1:.8f} (certified smallest "
          f"in ({mm.lower:.8f}, {mm.upper:.8f}]), J = {g.J:.6f} >= {g.lower_bound:.6f} (gap {g.gap:.1e}), "
          f"max mu2 = {g.mu2:.6f}, {g.lps} LPs")
    mi, bi, ip = _median_time(lambda: design_delay_ipopt(system, words, start_mu1=1.0), ipopt_repeats)
    print(f"   design_delay_ipopt   {1e3 * mi:9.1f} ms | {1e3 * bi:8.1f} ms   mu1 = {ip.mu1:.8f} (its gains reach "
          f"{ip.ipopt.mu1_of_gains:.8f}), J = {ip.J:.6f}, {ip.ipopt.iterations} IPOPT iterations")
    cmp = compare_free_routes(g, ip)
    print(f"   better: {cmp['better']}; IPOPT / global time = {mi / mg:.0f}x; old global route (Dinkelbach + "
          f"branch and bound, git history, not measured): {HISTORICAL_GLOBAL_S:.1f} s = "
          f"{HISTORICAL_GLOBAL_S / mg:.0f}x the new one")
    verdicts.append(("b", "reactor (5,2) mu1 free, global", f"{1e3 * mg:.1f} ms", "<= 100 ms", mg <= 0.1))


def part_c(sizes, size_repeats: int, mem_limit_gb: float, time_limit: float, verdicts: list) -> None:
    from eqrec.studies.p3.size_run import run_size
    from eqrec.systems.examples import batch_reactor

    system = batch_reactor()
    print(f"\nc. full languages {{0..tau}}^T, batch reactor, class engine, sum cost, mu1 = 0.5, HiGHS simplex; "
          f"{size_repeats} fresh process(es) per size (run_size), memory limit {mem_limit_gb:g} GB; "
          f"design = classes + build + solve (median), peak = largest")
    print(f"   {'T':>3} {'tau':>3} {'words':>10} {'sequences':>10} {'classes':>7} {'LP rows':>8} {'LP cols':>8} "
          f"{'nnz':>9} {'classes s':>9} {'build s':>8} {'solve s':>8} {'design s':>8} {'wall s':>7} {'peak MB':>8}"
          f"  {'J':>12}  status")
    for T, tau in sizes:
        runs = [run_size(system, T, tau, "simplex", 0.5, time_limit, mem_limit_gb, engine="classes", wall_margin=60)
                for _ in range(size_repeats)]
        ok = [r for r in runs if r.get("status") == "optimal"]
        r = ok[0] if ok else runs[0]
        med = lambda k: statistics.median(x.get(k, float("nan")) for x in (ok or runs))  # noqa: E731
        design = statistics.median(x.get("classes_time", 0) + x.get("build_time", 0) + x.get("solve_time", 0)
                                   for x in (ok or runs))
        peak = max(x.get("peak_mb", float("nan")) for x in runs)
        status = r.get("status") if len(ok) == len(runs) else f"{len(ok)}/{len(runs)} optimal: {runs[-1].get('status')}"
        print(f"   {T:>3} {tau:>3} {r.get('words', 0):>10.3g} {r.get('sequences', 0):>10.3g} {r.get('classes', ''):>7} "
              f"{r.get('rows', ''):>8} {r.get('cols', ''):>8} {r.get('nnz', ''):>9} {med('classes_time'):9.3f} "
              f"{med('build_time'):8.3f} {med('solve_time'):8.3f} {design:8.3f} {med('wall_time'):7.2f} {peak:8.0f}"
              f"  {r.get('J', float('nan')):12.6g}  {status}", flush=True)
        target = SIZE_TARGETS.get((T, tau))
        if target:
            limit_s, limit_mb = target
            verdicts.append(("c", f"({T},{tau}) class engine, design time", f"{design:.2f} s", f"<= {limit_s:g} s",
                             bool(ok) and design <= limit_s))
            if limit_mb:
                verdicts.append(("c", f"({T},{tau}) class engine, peak memory", f"{peak:.0f} MB",
                                 f"<= {limit_mb / 1024:g} GB", bool(ok) and peak <= limit_mb))


def _vmhwm_mb(pid: int) -> float:
    """Peak resident memory of a process (``VmHWM``), MB; 0 if unreadable."""
    try:
        with open(f"/proc/{pid}/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024
    except OSError:
        pass
    return 0.0


def free_worker(tau: int, T: int, config: str, warm_repeats: int) -> dict:
    """One configuration of part d in this (fresh) process: cold and warm times, peaks."""
    import psutil

    from eqrec.design.classes import blocks as class_blocks
    from eqrec.design.delay.design import delay_classes, design_delay_global
    from eqrec.systems.examples import batch_reactor

    n_jobs, dask, mono = CONFIGS[config]
    if mono:
        class_blocks.MONOLITHIC_MAX_WORK = float("inf")
    system = batch_reactor()
    design_delay_global(system, delay_classes(max_delay=1, horizon=3), n_jobs=1)  # imports
    cluster = client = None
    kw = {"n_jobs": n_jobs}
    if dask:
        from dask.distributed import Client, LocalCluster

        cluster = LocalCluster(n_workers=n_jobs, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
        kw = {"scheduler": client}
    times, res = [], None
    for _ in range(1 + warm_repeats):
        t0 = time.perf_counter()
        classes = delay_classes(max_delay=tau, horizon=T)
        res = design_delay_global(system, classes, **kw)
        times.append(time.perf_counter() - t0)
    workers = psutil.Process().children(recursive=True)
    out = {"tau": tau, "T": T, "config": config, "classes": len(classes), "cold": times[0],
           "warm": statistics.median(times[1:]) if warm_repeats else float("nan"),
           "main_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024,
           "worker_mb": max([_vmhwm_mb(p.pid) for p in workers], default=0.0), "mu1": res.mu1, "J": res.J,
           "mu2": res.mu2, "lower_bound": res.lower_bound}
    if client is not None:
        client.close()
        cluster.close()
    return out


def part_d(sizes, configs, warm_repeats: int, mono_max_classes: int, verdicts: list) -> None:
    from eqrec.design.delay.design import delay_classes

    print(f"\nd. reactor {{0..tau}}^T, mu1 free (design_delay_global), one fresh process per size and configuration; "
          f"cold = first design (pool start inside), warm = median of {warm_repeats} more; load average "
          f"{os.getloadavg()[0]:.2f} at the start")
    print(f"   {'tau':>3} {'T':>3} {'classes':>7} {'config':>10} {'cold s':>8} {'warm s':>8} {'main MB':>8} "
          f"{'worker MB':>9}  {'mu1':>12} {'J':>14}  load")
    rows = {}
    for tau, T in sizes:
        n_classes = len(delay_classes(max_delay=tau, horizon=T))
        for config in configs:
            if config == "monolithic" and n_classes > mono_max_classes:
                continue
            arg = json.dumps({"tau": tau, "T": T, "config": config, "warm": warm_repeats})
            proc = subprocess.run([sys.executable, __file__, "--free-worker", arg], capture_output=True, text=True)
            if proc.returncode:
                print(f"   {tau:>3} {T:>3} {config}: failed\n{proc.stderr[-2000:]}")
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            rows[(tau, T, config)] = r
            print(f"   {tau:>3} {T:>3} {r['classes']:>7} {config:>10} {r['cold']:8.2f} {r['warm']:8.2f} "
                  f"{r['main_mb']:8.0f} {r['worker_mb']:9.0f}  {r['mu1']:12.9g} {r['J']:14.9g}  "
                  f"{os.getloadavg()[0]:.2f}", flush=True)
    for (tau, T), (limit_s, limit_mb) in FREE_TARGETS.items():
        r = rows.get((tau, T, "blocks-2"))
        if r:
            verdicts.append(("d", f"({tau},{T}) mu1 free, 2 workers, cold", f"{r['cold']:.2f} s", f"<= {limit_s:g} s",
                             r["cold"] <= limit_s))
            if limit_mb:
                peak = max(r["main_mb"], r["worker_mb"])
                verdicts.append(("d", f"({tau},{T}) peak memory (main or worker)", f"{peak:.0f} MB",
                                 f"<= {limit_mb / 1024:g} GB", peak <= limit_mb))
    one, two = rows.get((4, 60, "blocks-1")), rows.get((4, 60, "blocks-2"))
    if one and two:
        for kind in ("warm", "cold"):
            ratio = one[kind] / two[kind]
            verdicts.append(("d", f"(4,60) speed-up 1 -> 2 workers, {kind}", f"{ratio:.2f}x", ">= 1.7x", ratio >= 1.7))
    mono, blocks = rows.get((4, 30, "monolithic")), rows.get((4, 30, "blocks-2"))
    if mono and blocks:
        verdicts.append(("d", "(T,tau) = (30,4): per class 2 workers vs one LP", f"{blocks['cold']:.2f} s",
                         f"<= {mono['cold']:.2f} s", blocks["cold"] <= mono["cold"]))
    for (tau, T, config), r in rows.items():
        ref = rows.get((tau, T, "blocks-1"))
        if ref and config != "blocks-1":
            same = all(r[k] == ref[k] for k in ("mu1", "J", "mu2", "lower_bound"))
            if config != "monolithic":
                verdicts.append(("d", f"({tau},{T}) {config}: same mu1, J, mu2, bound as 1 worker", str(same),
                                 "bytes", same))


def part_e(horizons, delays, repeats: int, verdicts: list) -> None:
    import importlib.util
    from pathlib import Path

    import numpy as np

    from eqrec.design.delay.languages import delay_classes
    from eqrec.design.inputs import class_shape

    spec = importlib.util.spec_from_file_location(
        "reference", Path(__file__).resolve().parents[1] / "tests" / "test_window_classes.py")
    reference = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(reference)
    print(f"\ne. the classes of {{0..tau}}^T alone (delay_classes), median | best of {repeats}, beside the previous "
          f"construction (tuples, quadratic; tests/test_window_classes.py); load average {os.getloadavg()[0]:.2f}")
    print(f"   {'tau':>3} {'T':>6} {'classes':>8} {'new s':>8} {'best':>8} {'estimate s':>10} {'previous s':>10} "
          f"{'ratio':>7}  same")
    import gc

    def timed(fn):  # each construction from a collected heap, its result dropped before the next one
        times = []
        for _ in range(repeats):
            gc.collect()
            t0 = time.perf_counter()
            out = fn()
            times.append(time.perf_counter() - t0)
            del out
        return statistics.median(times), min(times)

    for tau in delays:
        new_t, old_t = [], []
        for T in horizons:
            med, best = timed(lambda: delay_classes(max_delay=tau, horizon=T))
            old_med, _ = timed(lambda: reference.old_classes(T, tau))
            classes = delay_classes(max_delay=tau, horizon=T)
            same = [reference.fields(c) for c in classes] == reference.old_classes(T, tau)
            estimate = class_shape(tau, T).build_cost(T, tau)[0]
            new_t.append(med), old_t.append(old_med)
            print(f"   {tau:>3} {T:>6} {len(classes):>8} {med:8.3f} {best:8.3f} {estimate:10.3f} {old_med:10.3f} "
                  f"{old_med / med:6.1f}x  {same}", flush=True)
            del classes
            verdicts.append(("e", f"({tau},{T}) same classes as the previous construction", str(same), "True", same))
        logT = np.log(np.asarray(horizons, float))
        slope_new = float(np.polyfit(logT, np.log(new_t), 1)[0])
        slope_old = float(np.polyfit(logT, np.log(old_t), 1)[0])
        print(f"   tau = {tau}: growth exponent (time ~ T^k) new k = {slope_new:.2f}, previous k = {slope_old:.2f}")
        verdicts.append(("e", f"tau = {tau}: growth exponent of delay_classes", f"{slope_new:.2f}", "<= 1.2",
                         slope_new <= 1.2))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--only", choices=["a", "b", "c", "d", "e"], action="append")
    ap.add_argument("--repeats", type=int, default=20, help="repeats of parts a and b")
    ap.add_argument("--ipopt-repeats", type=int, default=3)
    ap.add_argument("--sizes", nargs="+", default=["8,3", "20,4", "30,4", "40,4", "30,5"], help="T,tau pairs (part c)")
    ap.add_argument("--size-repeats", type=int, default=3, help="fresh processes per size (part c)")
    ap.add_argument("--mem-limit-gb", type=float, default=4.0)
    ap.add_argument("--time-limit", type=float, default=300.0)
    ap.add_argument("--free-sizes", nargs="+", default=["4,30", "4,60", "5,60", "4,100"], help="tau,T pairs (d)")
    ap.add_argument("--configs", nargs="+", default=list(CONFIGS), choices=list(CONFIGS), help="part d")
    ap.add_argument("--warm-repeats", type=int, default=2, help="part d: designs after the first, per process")
    ap.add_argument("--mono-max-classes", type=int, default=1000,
                    help="part d: the one block LP only up to this many classes (it takes minutes beyond)")
    ap.add_argument("--class-horizons", type=int, nargs="+", default=[1000, 2000, 4000, 8000], help="part e: T")
    ap.add_argument("--class-delays", type=int, nargs="+", default=[1, 2], help="part e: tau")
    ap.add_argument("--class-repeats", type=int, default=3, help="part e: repeats per size")
    ap.add_argument("--free-worker", default=None, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.free_worker:
        w = json.loads(a.free_worker)
        print(json.dumps(free_worker(w["tau"], w["T"], w["config"], w["warm"])))
        return
    parts = a.only or ["a", "b", "c", "d", "e"]
    verdicts: list = []
    if "a" in parts:
        part_a(a.repeats, verdicts)
    if "b" in parts:
        part_b(a.repeats, a.ipopt_repeats, verdicts)
    if "c" in parts:
        sizes = [tuple(int(v) for v in s.split(",")) for s in a.sizes]
        part_c(sizes, a.size_repeats, a.mem_limit_gb, a.time_limit, verdicts)
    if "d" in parts:
        part_d([tuple(int(v) for v in s.split(",")) for s in a.free_sizes], a.configs, a.warm_repeats,
               a.mono_max_classes, verdicts)
    if "e" in parts:
        part_e(a.class_horizons, a.class_delays, a.class_repeats, verdicts)
    print("\nTargets")
    print(f"   {'part':4} {'case':42} {'measured':>12} {'target':>10}  verdict")
    for part, case, measured, target, ok in verdicts:
        print(f"   {part:4} {case:42} {measured:>12} {target:>10}  {'PASS' if ok else 'MISS'}")


if __name__ == "__main__":
    main()
