"""The claims table: published numbers next to ours, with wording tied to the evidence.

The papers' values and all wording live in one file, ``config/claims.yaml``
(a list of entries)::

    - id: P1-M2:prefix-L1                    # starts with the target ID of TARGETS.md
      quantity: optimal M2, prefix-based estimator on L1 (M1 = 1)
      paper_value: "1.1490"
      source: prefix-based paper, Sec. VI
      compare: {kind: number}                 # number / interval / array / text / none (with why:)
      value: p1/values.json#prefix_L1_mu2     # where our value and its evidence are, under results/
      shown_as: "..."                         # optional: template for our value in the table
      note:                                   # the evidence, in words: templates, each shown
        - "LP optimum {mu2:.6f} ..."          #   always, or only while its `when` holds
        - {when: "all_are(probe_status, 'infeasible')", text: "...", else: "..."}
      explanation:                            # why it differs: shown only while `when` holds;
        when: "paper < value - probe_gap"     #   otherwise the table says it was withdrawn
        text: "..."

The pipeline's ``values`` steps write ``values.json`` files mapping keys to
``{"value": v, "evidence": {...numbers, statuses, words...}}`` and no prose.
Templates and conditions see the evidence's keys plus ``value`` (ours),
``paper`` (the published value, a number where it reads as one) and ``tol``
(the comparison tolerance of ``number`` claims).

Templates: ``{expression}`` or ``{expression:format}`` (Python format spec),
``{{``/``}}`` for braces.  Conditions and template fields use a small
expression language (a subset of Python syntax, evaluated here without
``eval``): literals, evidence names, ``a.b`` / ``a['b']`` / ``a[0]`` lookups,
``+ - * /``, comparisons, ``and``/``or``/``not``, ``x if c else y`` and the
functions of :data:`FUNCTIONS`.  A condition that names evidence which is
missing is false.

The table ``results/claims.csv`` has the columns ``id, quantity,
paper_value, our_value, status, reason``; ``results/REPRODUCTION.md``
renders it for reading.  Comparison kinds:

``number``    reproduced if ``|ours - paper| <= atol + rtol |paper|``; the default ``atol`` is
              half a unit of the last printed digit of the paper's value.
``interval``  ``[lo, hi]`` compared endpoint-wise.
``array``     nested lists compared entry-wise with ``atol``.
``text``      exact (case-insensitive) match, e.g. "hold-input".
``none``      not comparable (e.g. solve times on other hardware); ``why`` says why.

A claim whose ``value`` starts with ``timings/`` (a measured time, under
``results/timings/``) changes from run to run: ``claims.csv`` and
``REPRODUCTION.md`` give, in its place, where it is, and the row in full goes
to ``results/timings/claims.csv``.
"""

from __future__ import annotations

import ast
import copy
import functools
import json
import math
import operator
from decimal import Decimal
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Mapping, Sequence

import numpy as np
import yaml

from eqrec.errors import InputError
from eqrec.studies.logs import get_logger
from eqrec.studies.outputs import write_csv, write_text

if TYPE_CHECKING:
    import pandas as pd

log = get_logger("claims")

STATUSES = ("reproduced", "differs", "not comparable")
COLUMNS = ["id", "quantity", "paper_value", "our_value", "status", "reason"]
KINDS = ("number", "interval", "array", "text", "none")


# --------------------------------------------------------------------------- the expression language

class MissingEvidence(KeyError):
    """An expression names evidence that the values file does not have."""


class ExpressionError(InputError):
    """An expression or template outside the language."""


def _fmt_list(xs, spec: str = ".4g") -> str:
    """``[a, b, c]`` with every number formatted by ``spec`` (nested lists too)."""
    if isinstance(xs, (list, tuple)):
        return "[" + ", ".join(_fmt_list(x, spec) for x in xs) + "]"
    if isinstance(xs, (int, float)) and not isinstance(xs, bool):
        return format(xs, spec)
    return str(xs)


def _fmt_complex(pairs, spec: str = ".3f") -> str:
    """``{a+bj, c}`` from ``[[re, im], ...]`` (the imaginary part shown only when nonzero)."""
    return "{" + ", ".join(format(a, spec) + (format(b, "+" + spec) + "j" if abs(b) > 1e-9 else "")
                           for a, b in pairs) + "}"


def _join(x, sep: str = ", ") -> str:
    """A mapping as ``k: v, k: v``; a list as ``a, b``."""
    if isinstance(x, Mapping):
        return sep.join(f"{k}: {v}" for k, v in x.items())
    return sep.join(str(v) for v in x)


def _all_are(x, value) -> bool:
    """Every entry (of a list, or value of a mapping) equals ``value``; false if empty."""
    items = list(x.values()) if isinstance(x, Mapping) else list(x)
    return bool(items) and all(i == value for i in items)


def _count(x, value) -> int:
    items = list(x.values()) if isinstance(x, Mapping) else list(x)
    return sum(1 for i in items if i == value)


def _each(x, template: str, sep: str = "; ") -> str:
    """Render ``template`` for every item: mapping items see the item's keys (if a mapping), ``key`` and ``item``."""
    parts = []
    pairs = x.items() if isinstance(x, Mapping) else enumerate(x)
    for k, v in pairs:
        ctx = {**(v if isinstance(v, Mapping) else {}), "key": k, "item": v}
        parts.append(render(template, ctx))
    return sep.join(parts)


#: Functions available in conditions and templates.
FUNCTIONS: dict[str, Callable] = {
    "abs": abs, "min": min, "max": max, "len": len, "round": round, "sum": sum, "any": any, "all": all,
    "sorted": sorted, "keys": lambda d: list(d.keys()), "values": lambda d: list(d.values()),
    "all_are": _all_are, "count": _count, "join": _join, "fmtlist": _fmt_list, "fmtcomplex": _fmt_complex, "each": _each,
    "percent": lambda x: 100.0 * x, "fmt": format,
    "sub": lambda template, context: render(template, context),
}

_BINOPS = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv}
_CMPOPS = {ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le,
           ast.Gt: operator.gt, ast.GtE: operator.ge, ast.In: lambda a, b: a in b,
           ast.NotIn: lambda a, b: a not in b, ast.Is: operator.is_, ast.IsNot: operator.is_not}


def _parse(expr: str) -> ast.Expression:
    try:
        tree = ast.parse(expr.strip(), mode="eval")
    except SyntaxError as exc:
        raise ExpressionError(f"cannot parse {expr!r}: {exc.msg}") from None
    for node in ast.walk(tree):
        ok = isinstance(node, (ast.Expression, ast.BoolOp, ast.And, ast.Or, ast.UnaryOp, ast.Not, ast.USub,
                               ast.UAdd, ast.BinOp, ast.Compare, ast.Constant, ast.Name, ast.Load,
                               ast.Attribute, ast.Subscript, ast.List, ast.Tuple, ast.Call, ast.IfExp,
                               *_BINOPS, *_CMPOPS))
        if isinstance(node, ast.Call) and not (isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS
                                               and not node.keywords):
            ok = False
        if isinstance(node, ast.Attribute) and node.attr.startswith("_"):
            ok = False
        if not ok:
            raise ExpressionError(f"{expr!r}: {type(node).__name__} is not part of the claims expression language")
    return tree


def _lookup(container: Any, key: Any, expr: str) -> Any:
    try:
        if isinstance(container, Mapping):
            return container[key]
        if isinstance(container, (list, tuple)) and isinstance(key, int):
            return container[key]
    except (KeyError, IndexError):
        pass
    raise MissingEvidence(f"{expr!r}: no evidence {key!r}")


def _eval(node: ast.AST, ctx: Mapping[str, Any], expr: str) -> Any:
    if isinstance(node, ast.Expression):
        return _eval(node.body, ctx, expr)
    if isinstance(node, ast.Constant):
        return node.value
    if isinstance(node, ast.Name):
        if node.id in ctx:
            return ctx[node.id]
        raise MissingEvidence(f"{expr!r}: no evidence {node.id!r}")
    if isinstance(node, ast.Attribute):
        return _lookup(_eval(node.value, ctx, expr), node.attr, expr)
    if isinstance(node, ast.Subscript):
        return _lookup(_eval(node.value, ctx, expr), _eval(node.slice, ctx, expr), expr)
    if isinstance(node, (ast.List, ast.Tuple)):
        return [_eval(e, ctx, expr) for e in node.elts]
    if isinstance(node, ast.BoolOp):
        if isinstance(node.op, ast.And):
            return all(_eval(v, ctx, expr) for v in node.values)
        return any(_eval(v, ctx, expr) for v in node.values)
    if isinstance(node, ast.UnaryOp):
        v = _eval(node.operand, ctx, expr)
        return (not v) if isinstance(node.op, ast.Not) else (-v if isinstance(node.op, ast.USub) else +v)
    if isinstance(node, ast.BinOp):
        return _BINOPS[type(node.op)](_eval(node.left, ctx, expr), _eval(node.right, ctx, expr))
    if isinstance(node, ast.Compare):
        left = _eval(node.left, ctx, expr)
        for op, comp in zip(node.ops, node.comparators):
            right = _eval(comp, ctx, expr)
            if not _CMPOPS[type(op)](left, right):
                return False
            left = right
        return True
    if isinstance(node, ast.IfExp):
        return _eval(node.body if _eval(node.test, ctx, expr) else node.orelse, ctx, expr)
    if isinstance(node, ast.Call):
        return FUNCTIONS[node.func.id](*(_eval(a, ctx, expr) for a in node.args))
    raise ExpressionError(f"{expr!r}: unsupported {type(node).__name__}")  # pragma: no cover (parse checks)


def evaluate(expr: str, context: Mapping[str, Any]) -> Any:
    """Value of an expression of the claims language on ``context`` (no ``eval``)."""
    return _eval(_parse(expr), context, expr)


def holds(condition: str, context: Mapping[str, Any]) -> bool:
    """Truth of a condition; false when it names missing evidence."""
    try:
        return bool(evaluate(condition, context))
    except MissingEvidence:
        return False


def _fields(template: str) -> list[tuple[str, str, str]]:
    """Split a template into ``(literal, expression, format_spec)`` triples (expression empty at the end)."""
    out, lit, i, n = [], [], 0, len(template)
    while i < n:
        c = template[i]
        if c in "{}" and i + 1 < n and template[i + 1] == c:
            lit.append(c)
            i += 2
            continue
        if c == "}":
            raise ExpressionError(f"template {template!r}: single '}}' (write '}}}}')")
        if c != "{":
            lit.append(c)
            i += 1
            continue
        depth, quote, j, colon = 0, None, i + 1, None
        while j < n:
            ch = template[j]
            if quote:
                if ch == quote:
                    quote = None
            elif ch in "'\"":
                quote = ch
            elif ch in "([{":
                depth += 1
            elif ch in ")]":
                depth -= 1
            elif ch == "}":
                if depth == 0:
                    break
                depth -= 1
            elif ch == ":" and depth == 0:
                colon = j
            j += 1
        if j >= n:
            raise ExpressionError(f"template {template!r}: unclosed '{{'")
        body = template[i + 1:j]
        expr, spec = (body[: colon - i - 1], body[colon - i:]) if colon is not None else (body, "")
        out.append(("".join(lit), expr, spec))
        lit = []
        i = j + 1
    out.append(("".join(lit), "", ""))
    return out


def render(template: str, context: Mapping[str, Any]) -> str:
    """Fill a template's ``{expression:format}`` fields from ``context``."""
    parts = []
    for lit, expr, spec in _fields(template):
        parts.append(lit)
        if expr:
            parts.append(format(evaluate(expr, context), spec))
    return "".join(parts)


def check_template(template: str) -> None:
    """Parse every field of a template (raises :class:`ExpressionError`)."""
    for _, expr, _ in _fields(template):
        if expr:
            _parse(expr)


# --------------------------------------------------------------------------- claims file

def _pieces(spec: Any) -> list[dict]:
    """A note or explanation as a list of ``{text, when?, else?}``."""
    if spec is None:
        return []
    items = spec if isinstance(spec, list) else [spec]
    out: list[dict] = []
    for it in items:
        if isinstance(it, list):  # a YAML alias of a shared list of pieces
            out += _pieces(it)
        else:
            out.append({"text": it} if isinstance(it, str) else dict(it))
    return out


def load_claims(path: str | Path) -> list[dict]:
    """Read and check the claims file (keys, kinds, and the syntax of every template and condition)."""
    path = Path(path)
    data = yaml.safe_load(path.read_text())
    if not isinstance(data, list):
        raise InputError("must be a list of claim entries", str(path))
    seen = set()
    for i, entry in enumerate(data):
        cid = entry.get("id", f"entry {i}")
        for key in ("id", "quantity", "paper_value", "source", "compare", "value"):
            if key not in entry:
                raise InputError(f"{cid} lacks '{key}'", str(path), key)
        if entry["id"] in seen:
            raise InputError(f"duplicate claim id {entry['id']}", str(path), "id")
        seen.add(entry["id"])
        kind = entry["compare"].get("kind")
        if kind not in KINDS:
            raise InputError(f"claim {cid}: unknown compare kind {kind!r}", str(path), "compare")
        for key in ("note", "explanation"):
            for piece in _pieces(entry.get(key)):
                if "text" not in piece or set(piece) - {"text", "when", "else"}:
                    raise InputError(f"claim {cid}: each {key} is a text or {{when, text, else}}", str(path), key)
                try:
                    for t in (piece["text"], piece.get("else")):
                        if t is not None:
                            check_template(str(t))
                    if "when" in piece:
                        _parse(str(piece["when"]))
                except ExpressionError as exc:
                    raise InputError(f"claim {cid}: {exc}", str(path), key) from None
        if any("when" not in p for p in _pieces(entry.get("explanation"))):
            raise InputError(f"claim {cid}: an explanation needs the evidence it rests on ('when')",
                             str(path), "explanation")
    return data


def published_value(claims_path: str | Path, claim_id: str) -> Any:
    """The paper's value of one claim of ``config/claims.yaml`` (the only place published numbers live)."""
    path = Path(claims_path)
    for entry in _loaded_claims(path, path.stat().st_mtime_ns):
        if entry["id"] == claim_id:
            return copy.deepcopy(entry["paper_value"])
    raise InputError(f"{claims_path} has no claim {claim_id!r}", field="printed")


@functools.lru_cache(maxsize=4)
def _loaded_claims(path: Path, mtime_ns: int) -> list[dict]:
    return load_claims(path)


def default_atol(paper_value: Any) -> float:
    """Half a unit in the last printed digit of a published number."""
    d = Decimal(str(paper_value))
    exponent = d.as_tuple().exponent
    return 0.5 * 10.0 ** int(exponent) if isinstance(exponent, int) else 0.0


def _tolerance(entry: dict) -> float | None:
    """The comparison tolerance (``number``: ``atol + rtol |paper|``; ``interval``: per endpoint)."""
    cmp, paper = entry["compare"], entry["paper_value"]
    if cmp["kind"] == "number":
        return float(cmp.get("atol", default_atol(paper))) + float(cmp.get("rtol", 0.0)) * abs(float(paper))
    if cmp["kind"] == "interval":
        return float(cmp.get("atol", max(default_atol(paper[0]), default_atol(paper[1]))))
    return None


def compare_one(entry: dict, ours: Any) -> tuple[str, str]:
    """Status and the tolerance wording of one claim."""
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


def _format(value: Any) -> str:
    if isinstance(value, float):
        return f"{value:.6g}"
    if isinstance(value, (list, tuple)):
        return "[" + ", ".join(_format(v) for v in value) + "]"
    return str(value)


def _number(x: Any) -> Any:
    try:
        return float(x) if isinstance(x, str) else x
    except ValueError:
        return x


def _render_pieces(pieces: list[dict], ctx: Mapping[str, Any], cid: str) -> str:
    out = []
    for p in pieces:
        text = p["text"] if "when" not in p or holds(str(p["when"]), ctx) else p.get("else")
        if text is None:
            continue
        try:
            out.append(render(str(text), ctx).strip())
        except MissingEvidence as exc:
            raise InputError(f"claim {cid}: template names evidence the values file lacks: {exc.args[0]}") from None
    return _join_pieces(out)


def _join_pieces(texts: list[str]) -> str:
    """Pieces separated by a space, except before a piece that starts with punctuation."""
    joined = ""
    for t in texts:
        if not t:
            continue
        joined += t if (not joined or t[0] in ",;:.)") else " " + t
    return joined


def explain(entry: dict, ctx: Mapping[str, Any]) -> str:
    """The explanation while its evidence holds; otherwise a line saying it was withdrawn and why."""
    shown, withdrawn = [], []
    for p in _pieces(entry.get("explanation")):
        (shown if holds(str(p["when"]), ctx) else withdrawn).append(p)
    text = _render_pieces(shown, ctx, entry["id"])
    if withdrawn:
        conds = "; ".join(str(p["when"]) for p in withdrawn)
        text = (text + " " if text else "") + (f"[explanation withdrawn: its evidence no longer holds ({conds})]")
    return text


def _values_file(values: Mapping[str, str | Path] | str | Path, ref_file: str) -> Path:
    """The declared values file a claim refers to (``p1/values.json`` -> ``.../p1/values.json``)."""
    if isinstance(values, (str, Path)):
        path = Path(values) / ref_file
        if not path.is_file():
            raise FileNotFoundError(f"results file {path} needed by a claim does not exist")
        return path
    for p in values:  # ``p1/values.json`` is results/p1/values.json, not results/timings/p1/values.json
        pos = Path(p).as_posix()
        if pos == ref_file or (pos.endswith("/" + ref_file)
                               and not pos[: -len(ref_file)].endswith("/" + TIMINGS_PREFIX)):
            return Path(p)
    raise FileNotFoundError(f"values file {ref_file} needed by a claim is not among the inputs {list(values)}")


def _lookup_value(values, ref: str, cache: dict) -> tuple[Any, dict]:
    file, _, key = ref.partition("#")
    fpath = _values_file(values, file)
    if fpath not in cache:
        cache[fpath] = json.loads(fpath.read_text())
    data = cache[fpath]
    if key not in data:
        raise KeyError(f"{fpath} has no value '{key}'")
    item = data[key]
    if isinstance(item, dict) and "value" in item:
        return item["value"], dict(item.get("evidence") or {})
    return item, {}


#: A claim whose value lives under ``results/timings/`` (``value: timings/p1/values.json#...``) is a
#: measurement that changes from run to run: ``claims.csv`` and ``REPRODUCTION.md`` name where it is,
#: and the row in full goes to ``results/timings/claims.csv``.
TIMINGS_PREFIX = "timings/"


def is_timing_claim(entry: Mapping[str, Any]) -> bool:
    """Whether the claim's value is a timing (its value file is under ``results/timings/``)."""
    return str(entry["value"]).startswith(TIMINGS_PREFIX)


def build_claims_table(claims_path: str | Path, values: Sequence[str | Path] | str | Path) -> pd.DataFrame:
    """Compare every claim with the pipeline's values.

    ``values``: the ``values.json`` files (or the results folder holding
    ``p1/values.json`` ...).  Raises if a referenced result is missing: a table
    with holes would be a partial result presented as whole.
    """
    rows = []
    cache: dict = {}
    for entry in load_claims(claims_path):
        ours, evidence = _lookup_value(values, entry["value"], cache)
        status, tol = compare_one(entry, ours)
        ctx = {**evidence, "value": ours, "paper": _number(entry["paper_value"]), "tol": _tolerance(entry)}
        note = _render_pieces(_pieces(entry.get("note")), ctx, entry["id"])
        parts = []
        if status == "differs":
            parts += [t for t in (note, explain(entry, ctx)) if t]
            if not parts:
                parts.append("unexplained")
        elif status == "reproduced":
            parts.append(("within " if tol != "exact match" else "") + tol + (f"; {note}" if note else ""))
        else:
            parts.extend(p for p in (tol, note) if p)
        shown = render(str(entry["shown_as"]), ctx) if entry.get("shown_as") else _format(ours)
        rows.append({"id": entry["id"], "quantity": entry["quantity"], "paper_value": _format(entry["paper_value"]),
                     "our_value": shown, "status": status, "reason": " ".join(parts), "source": entry["source"],
                     "timing": is_timing_claim(entry), "fixed_reason": tol})
    import pandas as pd  # here, not at the top: the Snakefile reads published values at every start

    return pd.DataFrame(rows)


def without_timings(table: pd.DataFrame) -> pd.DataFrame:
    """The table with every timing row's value and reason replaced by where they are (``results/timings/claims.csv``),
    so that the table is the same from run to run."""
    out = table.copy()
    timing = out["timing"].astype(bool)
    out.loc[timing, "our_value"] = "measured each run: results/timings/claims.csv"
    out.loc[timing, "reason"] = out.loc[timing, "fixed_reason"]  # the comparison's text, without the measured note
    return out


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


def write_claims(claims_path: str | Path, values, csv_out: str | Path, md_out: str | Path,
                 timings_out: str | Path | None = None) -> pd.DataFrame:
    """Write ``claims.csv`` and ``REPRODUCTION.md`` (atomically), and the timing rows in full to ``timings_out``."""
    table = build_claims_table(claims_path, values)
    fixed = without_timings(table)
    write_csv(csv_out, fixed[COLUMNS])
    write_text(md_out, render_markdown(fixed))
    if timings_out is not None:
        write_csv(timings_out, table.loc[table["timing"].astype(bool), COLUMNS])
    return table


def step_table(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """The claims table from ``config/claims.yaml`` and the studies' declared ``values.json`` files."""
    table = write_claims(inputs.claims, [*inputs["values"], *inputs["timings"]], outputs.csv, outputs.md,
                         outputs.timings)
    for status, n in table["status"].value_counts().items():
        log.info("%s: %d", status, n)
    return table


STEPS = {"table": step_table}
