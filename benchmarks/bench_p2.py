"""P2-F3a heat-map timing: per point (placement, L update, LP solve), total, and ratio to the 60 s goal.

    python benchmarks/bench_p2.py [--n 31] [--variant theorem2] [--jobs 2]

The LP is built once per job; each grid point only rewrites the L-dependent
matrix values (eqrec.design.augmented.word_lp.AugmentedLP.set_L, as eqrec.design.augmented.sweep.fixed_L_sweep does) and re-solves.
With --jobs 2 the θ-chunks run in two processes, as two Snakemake jobs would.
"""
from __future__ import annotations

import argparse
import time
from concurrent.futures import ProcessPoolExecutor

import numpy as np

from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.observers import place_observer
from eqrec.studies.p2.readings import heatmap_poles, variant_word
from eqrec.systems.examples import acc_system

GOAL = 60.0


def run_chunk(args):
    thetas, r_grid, variant = args
    system = acc_system()
    mode, word = variant_word("100111", variant)
    t_place = t_set = t_solve = 0.0
    model, n, fails = None, 0, 0
    t_build = 0.0
    for th in thetas:
        for r in r_grid:
            t0 = time.perf_counter()
            pp = place_observer(system.A, system.C, heatmap_poles(r, th))
            t1 = time.perf_counter()
            t_place += t1 - t0
            n += 1
            if not pp.ok:
                fails += 1
                continue
            if model is None:
                model = AugmentedLP(system, word, 1.0, pp.L, mode=mode)
                t_build = time.perf_counter() - t1
            else:
                model.set_L(pp.L)
            t2 = time.perf_counter()
            t_set += t2 - t1
            model.solve("highs")
            t_solve += time.perf_counter() - t2
    return n, fails, t_place, t_set, t_solve, t_build


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=31)
    ap.add_argument("--variant", default="theorem2")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    place_observer(np.eye(2), np.eye(2), [0.1, 0.2])  # warm the scipy.signal import
    r_grid = np.linspace(0, 1.5, a.n)
    thetas = np.linspace(0, np.pi, a.n)
    chunks = [(c, r_grid, a.variant) for c in np.array_split(thetas, a.jobs)]
    t0 = time.perf_counter()
    if a.jobs > 1:
        with ProcessPoolExecutor(a.jobs) as ex:
            res = list(ex.map(run_chunk, chunks))
    else:
        res = [run_chunk(c) for c in chunks]
    wall = time.perf_counter() - t0
    n = sum(r[0] for r in res)
    fails = sum(r[1] for r in res)
    tp, ts, tv, tb = (sum(r[i] for r in res) for i in (2, 3, 4, 5))
    print(f"variant {a.variant}: {a.n}x{a.n} = {n} points ({fails} placement failures), {a.jobs} process(es)")
    print(f"per point: placement {1e3 * tp / n:.2f} ms, L update {1e3 * ts / n:.2f} ms, "
          f"LP solve {1e3 * tv / n:.2f} ms, total {1e3 * (tp + ts + tv) / n:.2f} ms (CPU time)")
    print(f"one-time LP build per job: {1e3 * tb / a.jobs:.1f} ms")
    print(f"wall time {wall:.2f} s; goal {GOAL:.0f} s on 2 cores; ratio {wall / GOAL:.3f}")


if __name__ == "__main__":
    main()
