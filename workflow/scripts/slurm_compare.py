#!/usr/bin/env python3
"""Compare two ``results/`` trees written by the same workflow (local run vs SLURM run).

Usage::

    python workflow/scripts/slurm_compare.py LOCAL/results SLURM/results [--rtol 1e-9] [--atol 1e-12]

Both trees must hold the same files. Numbers must agree within
``|a - b| <= atol + rtol * |b|`` (defaults 1e-9 and 1e-12: the two runs use the
same code and inputs on the same kind of machine, so they are expected to agree
to the last digits); everything else must be equal, except

* timing and memory fields: JSON keys and CSV columns ``time``, ``solve_time``,
  ``build_time``, ``tree_time``, ``classes_time``, ``wall_time``, ``*_s`` (``build_s``,
  ``solve_s``, ``elapsed_s``, ...), ``*_seconds``, ``peak_mb``; numbers followed
  by a unit ``s`` or ``ms`` in text ("build 4.0 ms", "0.48 s"); Markdown table
  columns whose header names a unit ``[s]`` or ``[MB]`` (the scale table's
  measurements); the ``our_value`` of claims whose quantity is measured in
  seconds (``... [s]``);
* figures (``.pdf``, ``.png``, ``.svg``): only their presence is compared (their
  bytes hold creation dates).

``.json``, ``.csv``, ``.md``/``.txt``, ``.npz`` files are compared by content,
any other file byte for byte. Exit status 0 if the trees agree, 1 otherwise
(each difference is printed, at most 50).
"""

from __future__ import annotations

import argparse
import csv
import json
import math
import re
import sys
from pathlib import Path

TIMING_KEY = re.compile(r"^(time|(solve|build|tree|classes|wall)_time|elapsed|seconds|.*_s|.*_seconds|peak_mb)$")
TIMING_HEADER = re.compile(r"\[(s|ms|MB)\]")  # a Markdown table column of measurements
FIGURES = {".pdf", ".png", ".svg"}
# a number, optionally followed by a time unit (then it is a timing and ignored)
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?(?P<unit>\s?(?:ms|s)\b)?")


class Diff(Exception):
    pass


def close(a: float, b: float, rtol: float, atol: float) -> bool:
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    if math.isinf(a) or math.isinf(b):
        return a == b
    return abs(a - b) <= atol + rtol * abs(b)


def compare_text(a: str, b: str, where: str, rtol: float, atol: float) -> None:
    """Equal text with numbers within tolerance; numbers with a time unit ignored."""
    na, nb = list(NUMBER.finditer(a)), list(NUMBER.finditer(b))
    if NUMBER.sub("#", a) != NUMBER.sub("#", b) or len(na) != len(nb):
        raise Diff(f"{where}: text differs: {a[:200]!r} vs {b[:200]!r}")
    for ma, mb in zip(na, nb):
        if ma.group("unit") or mb.group("unit"):
            continue
        x = float(ma.group(0))
        y = float(mb.group(0))
        if not close(x, y, rtol, atol):
            raise Diff(f"{where}: {ma.group(0)} vs {mb.group(0)}")


def compare_value(a, b, where: str, rtol: float, atol: float) -> None:
    if isinstance(a, bool) or isinstance(b, bool) or a is None or b is None:
        if a != b:
            raise Diff(f"{where}: {a!r} vs {b!r}")
    elif isinstance(a, (int, float)) and isinstance(b, (int, float)):
        if not close(float(a), float(b), rtol, atol):
            raise Diff(f"{where}: {a!r} vs {b!r}")
    elif isinstance(a, str) and isinstance(b, str):
        compare_text(a, b, where, rtol, atol)
    elif isinstance(a, list) and isinstance(b, list):
        if len(a) != len(b):
            raise Diff(f"{where}: lengths {len(a)} vs {len(b)}")
        for i, (x, y) in enumerate(zip(a, b)):
            compare_value(x, y, f"{where}[{i}]", rtol, atol)
    elif isinstance(a, dict) and isinstance(b, dict):
        if set(a) != set(b):
            raise Diff(f"{where}: keys differ: {sorted(set(a) ^ set(b))}")
        for k in a:
            if TIMING_KEY.match(str(k)):
                continue
            compare_value(a[k], b[k], f"{where}.{k}", rtol, atol)
    else:
        raise Diff(f"{where}: {type(a).__name__} vs {type(b).__name__}")


def compare_csv(pa: Path, pb: Path, where: str, rtol: float, atol: float) -> None:
    ra = list(csv.reader(pa.open(newline="")))
    rb = list(csv.reader(pb.open(newline="")))
    if not ra or not rb or ra[0] != rb[0] or len(ra) != len(rb):
        raise Diff(f"{where}: header or row count differs ({len(ra)} vs {len(rb)} rows)")
    header = ra[0]
    skip = {j for j, h in enumerate(header) if TIMING_KEY.match(h)}
    quantity = header.index("quantity") if "quantity" in header else None
    for i, (xa, xb) in enumerate(zip(ra[1:], rb[1:]), start=2):
        if len(xa) != len(xb):
            raise Diff(f"{where}:{i}: column count differs")
        seconds_row = quantity is not None and xa[quantity].rstrip().endswith("[s]")
        for j, (ca, cb) in enumerate(zip(xa, xb)):
            if j in skip or (seconds_row and header[j] == "our_value"):
                continue
            compare_text(ca, cb, f"{where}:{i}:{header[j]}", rtol, atol)


def _cells(line: str) -> list[str]:
    return [c.strip() for c in line.strip().strip("|").split("|")]


def compare_markdown(pa: Path, pb: Path, where: str, rtol: float, atol: float) -> None:
    la, lb = pa.read_text().splitlines(), pb.read_text().splitlines()
    if len(la) != len(lb):
        raise Diff(f"{where}: {len(la)} vs {len(lb)} lines")
    skip: set[int] = set()  # measured columns of the current table
    for i, (xa, xb) in enumerate(zip(la, lb), start=1):
        if not xa.startswith("|"):
            skip = set()
        elif i < len(la) and la[i].startswith("|") and set(la[i].replace("|", "").strip()) <= {"-", ":", " "}:
            skip = {j for j, h in enumerate(_cells(xa)) if TIMING_HEADER.search(h)}  # a header row
        elif skip:
            ca, cb = _cells(xa), _cells(xb)
            xa = " | ".join(c for j, c in enumerate(ca) if j not in skip)
            xb = " | ".join(c for j, c in enumerate(cb) if j not in skip)
        if "[s] |" in xa and xa.startswith("|"):  # a table row of a quantity in seconds: drop its values
            ca, cb = xa.split(" | "), xb.split(" | ")
            xa, xb = " | ".join(ca[:2] + ca[4:]), " | ".join(cb[:2] + cb[4:])
        compare_text(xa, xb, f"{where}:{i}", rtol, atol)


def compare_npz(pa: Path, pb: Path, where: str, rtol: float, atol: float) -> None:
    import numpy as np

    with np.load(pa, allow_pickle=False) as za, np.load(pb, allow_pickle=False) as zb:
        if set(za.files) != set(zb.files):
            raise Diff(f"{where}: arrays differ: {sorted(set(za.files) ^ set(zb.files))}")
        for k in za.files:
            x, y = za[k], zb[k]
            if x.shape != y.shape or x.dtype.kind != y.dtype.kind:
                raise Diff(f"{where}[{k}]: shape/dtype {x.shape} {x.dtype} vs {y.shape} {y.dtype}")
            if x.dtype.kind in "fc":
                ok = np.isclose(x, y, rtol=rtol, atol=atol, equal_nan=True)
                if not ok.all():
                    idx = np.argwhere(~ok)[0]
                    raise Diff(f"{where}[{k}] at {tuple(idx)}: {x[tuple(idx)]} vs {y[tuple(idx)]}")
            elif not np.array_equal(x, y):
                raise Diff(f"{where}[{k}]: values differ")


def compare_trees(a: Path, b: Path, rtol: float = 1e-9, atol: float = 1e-12) -> list[str]:
    """Differences between two results trees (empty list: they agree)."""
    fa = {p.relative_to(a).as_posix() for p in a.rglob("*") if p.is_file()}
    fb = {p.relative_to(b).as_posix() for p in b.rglob("*") if p.is_file()}
    diffs = [f"only in {a}: {f}" for f in sorted(fa - fb)] + [f"only in {b}: {f}" for f in sorted(fb - fa)]
    for rel in sorted(fa & fb):
        pa, pb = a / rel, b / rel
        suffix = pa.suffix.lower()
        try:
            if suffix in FIGURES:
                continue
            if suffix == ".json":
                compare_value(json.loads(pa.read_text()), json.loads(pb.read_text()), rel, rtol, atol)
            elif suffix == ".csv":
                compare_csv(pa, pb, rel, rtol, atol)
            elif suffix in (".md", ".txt"):
                compare_markdown(pa, pb, rel, rtol, atol)
            elif suffix == ".npz":
                compare_npz(pa, pb, rel, rtol, atol)
            elif pa.read_bytes() != pb.read_bytes():
                raise Diff(f"{rel}: bytes differ")
        except Diff as exc:
            diffs.append(str(exc))
    return diffs


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("a", type=Path)
    ap.add_argument("b", type=Path)
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--atol", type=float, default=1e-12)
    args = ap.parse_args(argv)
    for d in (args.a, args.b):
        if not d.is_dir():
            print(f"slurm_compare: {d}: not a directory", file=sys.stderr)
            return 1
    diffs = compare_trees(args.a, args.b, args.rtol, args.atol)
    n = sum(1 for p in args.a.rglob("*") if p.is_file())
    if diffs:
        for d in diffs[:50]:
            print(f"DIFF {d}")
        print(f"slurm_compare: {len(diffs)} difference(s) between {args.a} and {args.b}")
        return 1
    print(f"slurm_compare: {n} files agree (rtol {args.rtol:g}, atol {args.atol:g}; "
          "timings and figure bytes ignored)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
