#!/usr/bin/env python3
"""Compare two ``results/`` trees written by the workflow (e.g. a SLURM run against the committed results).

Usage::

    python workflow/scripts/slurm_compare.py REFERENCE/results OTHER/results [--subset]

Results reproduce byte for byte: outside ``timings/`` both trees must hold the
same files with the same bytes (numbers, tables, ``.npz`` arrays, figures).
Under ``timings/`` (wall-clock times and memory peaks, which change from run
to run) only the set of files is compared.  With ``--subset`` the reference
may hold more files (targets outside the run, e.g. the committed
``p3_scale`` table): every file of OTHER must then be in REFERENCE.  Exit status 0 if the trees agree,
1 otherwise (each difference is printed, at most 50; for text files the first
differing line).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

#: The folder (relative to ``results/``) of the measured values.
TIMINGS = "timings"
TEXT = {".json", ".csv", ".md", ".txt", ".html", ".ipynb"}


def _files(root: Path) -> set[str]:
    return {p.relative_to(root).as_posix() for p in root.rglob("*") if p.is_file() and not p.name.startswith(".")}


def _first_difference(a: Path, b: Path) -> str:
    """Where two text files first differ (line number and both lines, shortened)."""
    la, lb = a.read_text(errors="replace").splitlines(), b.read_text(errors="replace").splitlines()
    for i, (x, y) in enumerate(zip(la, lb), 1):
        if x != y:
            return f"line {i}: {x[:100]!r} != {y[:100]!r}"
    return f"{len(la)} lines != {len(lb)} lines"


def compare_trees(a: Path, b: Path, subset: bool = False) -> list[str]:
    """The differences between two results trees (empty when they agree); ``subset``: ``a`` may hold more files."""
    fa, fb = _files(a), _files(b)
    diffs = [] if subset else [f"{f}: only in {a}" for f in sorted(fa - fb)]
    diffs += [f"{f}: only in {b}" for f in sorted(fb - fa)]
    for f in sorted(fa & fb):
        if f.startswith(TIMINGS + "/"):
            continue
        pa, pb = a / f, b / f
        if pa.read_bytes() != pb.read_bytes():
            detail = _first_difference(pa, pb) if pa.suffix in TEXT else "bytes differ"
            diffs.append(f"{f}: {detail}")
    return diffs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", type=Path, help="reference results/ folder")
    ap.add_argument("b", type=Path, help="results/ folder to check")
    ap.add_argument("--subset", action="store_true", help="the reference may hold files the other run did not write")
    args = ap.parse_args(argv)
    for d in (args.a, args.b):
        if not d.is_dir():
            print(f"slurm_compare: {d}: not a directory", file=sys.stderr)
            return 2
    diffs = compare_trees(args.a, args.b, args.subset)
    if diffs:
        print(f"slurm_compare: {len(diffs)} difference(s) between {args.a} and {args.b}")
        for d in diffs[:50]:
            print("  " + d)
        return 1
    n = len([f for f in _files(args.b) if not f.startswith(TIMINGS + "/")])
    print(f"slurm_compare: {n} files identical (timings/ compared by name only)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
