"""Benchmark of the P4 Monte Carlo: 10^4 runs of 100 steps for one example.

Goal (issue 4): <= 10 s on this machine for simulation + both estimators.

    python benchmarks/bench_p4.py [--runs 10000] [--steps 100]
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from eqrec.lmv.monte_carlo import run_mc, simulate_plant
from eqrec.studies.p4.steps import load_config, plant_of

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--runs", type=int, default=10_000)
    ap.add_argument("--steps", type=int, default=100)
    a = ap.parse_args()
    cfg = load_config(ROOT / "config" / "p4.yaml")  # validated, schema defaults filled in
    for ex in cfg["examples"]:
        plant = plant_of(cfg, ex)
        rng = np.random.default_rng(1)
        t0 = time.perf_counter()
        sim = simulate_plant(plant, 0.8, a.steps, a.runs, rng)
        t1 = time.perf_counter()
        for mech in ("zero-input", "hold-input"):
            run_mc(plant, 0.8, mech, a.steps, a.runs, 2, rng, sim=sim)
        t2 = time.perf_counter()
        total = t2 - t0
        print(f"{ex}: {a.runs} runs x {a.steps} steps: simulate {t1 - t0:.2f} s, both estimators "
              f"{t2 - t1:.2f} s, total {total:.2f} s; ratio to the 10 s goal {total / 10:.2f}")


if __name__ == "__main__":
    main()
