"""Comparison of published numbers (claims) with the pipeline's results.

The papers' values live in one file, ``config/claims.yaml``: a list of entries::

    - id: P1-M2:prefix-L1          # starts with the target ID of TARGETS.md
      quantity: optimal M2, prefix-based estimator on L1 (M1 = 1)
      paper_value: 1.1490
      source: prefix-based paper, Sec. VI
      compare: {kind: number, atol: 5.0e-5}   # or kind: text / kind: none
      value: p1/values.json#prefix_L1_mu2      # where our value is, under results/
      explanation: >-                          # optional: what we found, shown if it differs
        ...

Each analysis step of the pipeline writes a ``values.json`` mapping keys to
``{"value": ..., "note": "..."}``; the note carries the computed evidence
(bounds, alternative readings) and becomes part of the reason.  The table
``results/claims.csv`` has the columns ``id, quantity, paper_value,
our_value, status, reason`` with status ``reproduced``, ``differs`` or
``not comparable``; ``results/REPRODUCTION.md`` renders it for reading.

Comparison kinds
----------------
``number``
    Reproduced if ``|ours - paper| <= atol + rtol |paper|``.  The default
    ``atol`` is half a unit of the last printed digit of the paper's value.
``interval``
    ``paper_value`` and ours are ``[lo, hi]``; compared endpoint-wise.
``array``
    Nested lists (matrices) compared entry-wise with ``atol``.
``text``
    Exact (case-insensitive) match of strings, e.g. "hold-input".
``none``
    Not comparable (e.g. solve times on other hardware); both values shown.
"""

from __future__ import annotations

import json
import math
from decimal import Decimal
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import yaml

from eqrec.errors import InputError

STATUSES = ("reproduced", "differs", "not comparable")
COLUMNS = ["id", "quantity", "paper_value", "our_value", "status", "reason"]


def default_atol(paper_value: Any) -> float:
    """Half a unit in the last printed digit of a published number."""
    d = Decimal(str(paper_value))
    exponent = d.as_tuple().exponent
    return 0.5 * 10.0 ** int(exponent) if isinstance(exponent, int) else 0.0


def load_claims(path: str | Path) -> list[dict]:
    """Read and check the claims file."""
    path = Path(path)
    data = yaml.safe_load(path.read_text())
    if not isinstance(data, list):
        raise InputError("must be a list of claim entries", str(path))
    seen = set()
    for i, entry in enumerate(data):
        for key in ("id", "quantity", "paper_value", "source", "compare", "value"):
            if key not in entry:
                raise InputError(f"entry {i} ({entry.get('id', '?')}) lacks '{key}'", str(path), key)
        if entry["id"] in seen:
            raise InputError(f"duplicate claim id {entry['id']}", str(path), "id")
        seen.add(entry["id"])
        kind = entry["compare"].get("kind")
        if kind not in ("number", "interval", "array", "text", "none"):
            raise InputError(f"claim {entry['id']}: unknown compare kind {kind!r}", str(path), "compare")
    return data


def _lookup(results_dir: Path, ref: str, cache: dict) -> tuple[Any, str]:
    file, _, key = ref.partition("#")
    fpath = results_dir / file
    if fpath not in cache:
        if not fpath.is_file():
            raise FileNotFoundError(f"results file {fpath} needed by a claim does not exist")
        cache[fpath] = json.loads(fpath.read_text())
    values = cache[fpath]
    if key not in values:
        raise KeyError(f"{fpath} has no value '{key}'")
    item = values[key]
    if isinstance(item, dict) and "value" in item:
        return item["value"], item.get("note", "")
    return item, ""


def _format(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    return str(value)


def compare_one(entry: dict, ours: Any) -> tuple[str, str]:
    """Status and default reason for one claim."""
    cmp = entry["compare"]
    kind = cmp["kind"]
    paper = entry["paper_value"]
    if kind == "none":
        return "not comparable", cmp.get("why", "")
    if ours is None or (isinstance(ours, float) and math.isnan(ours)):
        return "differs", "our computation produced no value"
    if kind == "text":
        same = str(ours).strip().lower() == str(paper).strip().lower()
        return ("reproduced" if same else "differs"), "exact match" if same else ""
    if kind == "number":
        atol = float(cmp.get("atol", default_atol(paper)))
        rtol = float(cmp.get("rtol", 0.0))
        ok = abs(float(ours) - float(paper)) <= atol + rtol * abs(float(paper))
        return ("reproduced" if ok else "differs"), f"tolerance {atol:g} + {rtol:g}|paper|"
    if kind == "array":
        a, b = np.asarray(ours, float), np.asarray(paper, float)
        atol = float(cmp.get("atol", 0.0))
        if a.shape != b.shape:
            return "differs", f"shape {a.shape} vs published {b.shape}"
        gap = float(np.max(np.abs(a - b))) if a.size else 0.0
        return ("reproduced" if gap <= atol else "differs"), f"largest entry gap {gap:.2g} (tolerance {atol:g})"
    if kind == "interval":
        atol = float(cmp.get("atol", max(default_atol(paper[0]), default_atol(paper[1]))))
        ok = all(abs(float(a) - float(b)) <= atol for a, b in zip(ours, paper))
        return ("reproduced" if ok else "differs"), f"endpoint tolerance {atol:g}"
    raise AssertionError(kind)


def build_claims_table(claims_path: str | Path, results_dir: str | Path) -> pd.DataFrame:
    """Compare every claim with the pipeline's values.

    Raises if a referenced result is missing: a table with holes would be a
    partial result presented as whole.
    """
    results_dir = Path(results_dir)
    rows = []
    cache: dict = {}
    for entry in load_claims(claims_path):
        ours, note = _lookup(results_dir, entry["value"], cache)
        status, tol = compare_one(entry, ours)
        parts = []
        if status == "differs":
            if note:
                parts.append(note)
            if entry.get("explanation"):
                parts.append(str(entry["explanation"]).strip())
            if not parts:
                parts.append("unexplained")
        elif status == "reproduced":
            parts.append(("within " if tol != "exact match" else "") + tol + (f"; {note}" if note else ""))
        else:
            parts.extend(p for p in (tol, note) if p)
        rows.append({"id": entry["id"], "quantity": entry["quantity"], "paper_value": _format(entry["paper_value"]),
                     "our_value": _format(ours), "status": status, "reason": " ".join(parts),
                     "source": entry["source"]})
    return pd.DataFrame(rows)


def write_claims(claims_path: str | Path, results_dir: str | Path, csv_out: str | Path, md_out: str | Path) -> pd.DataFrame:
    """Write ``claims.csv`` and ``REPRODUCTION.md``."""
    table = build_claims_table(claims_path, results_dir)
    table[COLUMNS].to_csv(csv_out, index=False)
    Path(md_out).write_text(render_markdown(table))
    return table


def render_markdown(table: pd.DataFrame) -> str:
    """A report readable without running Python."""
    counts = table["status"].value_counts()
    lines = ["# Reproduction report", "",
             "Every published number of the papers next to the value this pipeline computed "
             "(`results/claims.csv`). Generated by `snakemake`; do not edit by hand.", "",
             "| status | count |", "|---|---|"]
    for s in STATUSES:
        lines.append(f"| {s} | {int(counts.get(s, 0))} |")
    lines.append("")
    for paper, group in table.groupby(table["id"].str.split("-").str[0], sort=True):
        lines += [f"## {paper}", "", "| id | quantity | paper | ours | status | reason | source |",
                  "|---|---|---|---|---|---|---|"]
        for _, r in group.iterrows():
            cells = [r["id"], r["quantity"], r["paper_value"], r["our_value"], f"**{r['status']}**",
                     r["reason"], r["source"]]
            lines.append("| " + " | ".join(str(c).replace("|", "\\|").replace("\n", " ") for c in cells) + " |")
        lines.append("")
    return "\n".join(lines)


def write_values(path: str | Path, values: dict[str, Any]) -> None:
    """Write an analysis step's ``values.json`` (``{key: {"value": v, "note": s}}``)."""
    def norm(v):
        if isinstance(v, dict) and "value" in v:
            return v
        return {"value": v}
    Path(path).parent.mkdir(parents=True, exist_ok=True)
    Path(path).write_text(json.dumps({k: norm(v) for k, v in values.items()}, indent=2, default=float) + "\n")


def main(argv: list[str] | None = None) -> int:
    """``python -m eqrec.claims``: build the claims table (a Snakemake rule)."""
    import argparse

    ap = argparse.ArgumentParser(prog="python -m eqrec.claims",
                                 description="Compare published values (claims file) with the pipeline's results.")
    ap.add_argument("--claims", required=True, help="claims YAML (config/claims.yaml)")
    ap.add_argument("--results", required=True, help="results directory holding the values.json files")
    ap.add_argument("--csv", required=True, help="output CSV")
    ap.add_argument("--md", required=True, help="output Markdown report")
    a = ap.parse_args(argv)
    table = write_claims(a.claims, a.results, a.csv, a.md)
    print(table["status"].value_counts().to_string())
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
