"""Cost of one ``step()`` of the runnable estimator, strict and ``strict=False``, measured in one run (figures,
not tests).

    python benchmarks/bench_step.py [--steps 20000] [--repeats 5]

Rows: the README's plant and loss language (``000, 300, 030, 003``), class engine, the data in the language
(every mode) and, for ``strict=False``, Bernoulli losses of 40 % (the traces leave the language, the estimator
coasts); the prefix-based paper's ACC design with node gains (tree engine).  Each figure is the median over
``--repeats`` runs of the mean time per call; the ratio column is against the strict class-engine row.
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from eqrec.systems.examples import acc_system
from eqrec.systems.affine import AffineSystem
from eqrec.design.delay.design import design_delay_global
from eqrec.design.prefix.design import design_prefix


def _trace(steps: int, p: int, loss: float | None, seed: int) -> list:
    rng = np.random.default_rng(seed)
    out = []
    for k in range(steps):
        if loss is None:  # in the language: one loss per block of three, at a random place
            if k % 3 == 0:
                which = rng.integers(0, 4)
            lost = k % 3 == which
        else:
            lost = rng.random() < loss
        out.append(None if lost else rng.normal(size=p))
    return out


def _time(make, trace, u, repeats: int) -> float:
    times = []
    for _ in range(repeats):
        est = make()
        t0 = time.perf_counter()
        for y in trace:
            est.step(y, u)
        times.append((time.perf_counter() - t0) / len(trace))
    return statistics.median(times)


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=20000)
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    plant = AffineSystem(A=[[1, 0.1], [0, 1]], B=[[0.005], [0.1]], C=[[1, 0]], E=0.1 * np.eye(2), eta_w=0.1,
                         eta_v=0.05)
    design = design_delay_global(plant, ["000", "300", "030", "003"]).design
    inside = _trace(args.steps, 1, None, 1)
    outside = _trace(args.steps, 1, 0.4, 2)
    u = np.array([0.1])
    rows = [
        ("class engine, strict=True, in the language", lambda: design.estimator().reset(np.zeros(2)), inside, u),
        ("class engine, strict=False, in the language",
         lambda: design.estimator(strict=False).reset(np.zeros(2)), inside, u),
        ("class engine, strict=False, 40 % losses (outside)",
         lambda: design.estimator(strict=False).reset(np.zeros(2)), outside, u),
    ]
    acc = acc_system()
    p1 = design_prefix(acc, ["101111", "110111", "111011", "111101"], 1.0, engine="tree")
    words = [str(w) for w in np.random.default_rng(3).choice(["101111", "110111", "111011", "111101"],
                                                              args.steps // 6)]
    acc_trace = [None if c == "0" else np.ones(2) for w in words for c in w]
    rows.append(("ACC prefix design, node gains (tree), strict=True",
                 lambda: p1.estimator().reset(np.zeros(3)), acc_trace, np.zeros(1)))
    base = None
    print(f"{'estimator':55s} {'µs/step':>9s} {'ratio':>6s}")
    for name, make, trace, uu in rows:
        t = _time(make, trace, uu, args.repeats) * 1e6
        base = base or t
        print(f"{name:55s} {t:9.1f} {t / base:6.2f}")


if __name__ == "__main__":
    main()
