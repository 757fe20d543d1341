"""Cost of building the classes of the loss-aware delay language (delays ``0..D``, at most ``m`` lost per block)
from the window rule and its counting rule, without listing a word (figures, not tests).

    python benchmarks/bench_loss_language.py [--repeats 3] [--big] [--design]

Rows: ``(D, T, m)`` with ``m = -`` the language without losses (today's code path).  Columns: classes, words,
sequences of the reduced language, and the build time (median over ``--repeats``).  ``--big`` adds
``(4, 100, 2)`` (about 2.4 million classes); ``--design`` adds the time of ``design_delay_global`` on the batch
reactor for the smaller languages (the class LPs, every core).
"""

from __future__ import annotations

import argparse
import statistics
import time

from eqrec.bounds.data_classes import full_language_class_count
from eqrec.design.delay.design import design_delay_global
from eqrec.design.delay.languages import delay_classes
from eqrec.systems.examples import batch_reactor


def _build(D: int, T: int, m: int | None, repeats: int) -> tuple[object, float]:
    times, classes = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        classes = delay_classes(max_delay=D, horizon=T, max_lost=m)
        times.append(time.perf_counter() - start)
    return classes, statistics.median(times)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--big", action="store_true", help="add (4, 100, 2)")
    ap.add_argument("--design", action="store_true", help="add design_delay_global on the batch reactor")
    args = ap.parse_args()
    rows = [(2, 5, None), (2, 5, 1), (4, 30, None), (4, 30, 1), (4, 30, 2), (4, 100, None), (4, 100, 1)]
    if args.big:
        rows.append((4, 100, 2))
    print(f"{'D':>2} {'T':>4} {'m':>2} {'classes':>9} {'words':>10} {'sequences':>10} {'build s':>9}"
          + (f" {'design s':>9} {'mu1':>9}" if args.design else ""))
    for D, T, m in rows:
        classes, seconds = _build(D, T, m, 1 if (T, m) == (100, 2) else args.repeats)
        assert len(classes) == full_language_class_count(T, D, m)
        line = (f"{D:>2} {T:>4} {'-' if m is None else m:>2} {len(classes):>9} {float(classes.words):>10.3g} "
                f"{float(classes.sequences):>10.3g} {seconds:>9.3f}")
        if args.design and len(classes) <= 20_000:
            start = time.perf_counter()
            free = design_delay_global(batch_reactor(), classes)
            line += f" {time.perf_counter() - start:>9.2f} {free.mu1:>9.5f}"
        print(line, flush=True)


if __name__ == "__main__":
    main()
