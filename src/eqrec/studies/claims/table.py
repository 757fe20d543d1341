"""The claims table: published numbers next to ours, with wording tied to the evidence.

The papers' values and all wording live in one file, ``config/claims.yaml``
(read and checked by :mod:`eqrec.studies.claims.published`), a list of entries::

    - id: P1-M2:prefix-L1                    # starts with the target ID of TARGETS.md
      quantity: optimal M2, prefix-based estimator on L1 (M1 = 1)
      paper_value: "1.1490"
      source: prefix-based paper, Sec. VI
      compare: {kind: number}                 # number / interval / array / text / none (with why:)
      value: p1/values.json#prefix_L1_mu2     # where our value and its evidence are, under results/
      shown_as: "{value:.4g}"                 # optional: our value in the table
      note:                                   # the evidence in words: one text, or named texts
        optimum: "LP optimum {mu2:.6f} ..."   #   of which the claim's reason function picks
        proven: "So no estimator ..."         #   the ones to show, in order
        not_proven: "So the optimum ..."
      explanation:                            # why it differs: each named text shown while its
        misprint: "..."                       #   evidence holds, otherwise reported as withdrawn

Every text is a ``str.format`` template with plain named fields and a format
spec (``{mu2:.6f}``): no expressions, no conditions.  The fields are the
evidence's keys, ``value`` (ours), ``paper`` (the published value, a number
where it reads as one) and ``tol`` (the comparison tolerance), plus what the
claim's reason function adds.  The reason functions (one per claim id, or
shared by ids of one shape) are in :mod:`eqrec.studies.p1.claims` ...
:mod:`eqrec.studies.p4.claims`, registered by id in one registry (the contract is in
:mod:`eqrec.studies.claims.reasons`; :func:`load_reasons` imports those modules by name); a claim with named texts or an
explanation must have one, and a claim without one shows its single ``note``
filled from the evidence.

The pipeline's ``values`` steps write ``values.json`` files mapping keys to
``{"value": v, "evidence": {...numbers, statuses, words...}}`` and no prose.
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

import functools
import importlib.util
import json
import math
from decimal import Decimal
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterable, Mapping, Sequence

import numpy as np

from eqrec.errors import InputError
from eqrec.studies.claims import reasons as claim_reasons
from eqrec.studies.claims.reasons import Reason, fmtlist
from eqrec.studies.claims.published import named_texts, read_claims
from eqrec.studies.pipeline.configuration import CLAIMS_MODULE, SECTIONS
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import write_csv, write_text

if TYPE_CHECKING:
    import pandas as pd

log = get_logger("claims")

STATUSES = ("reproduced", "differs", "not comparable")
COLUMNS = ["id", "quantity", "paper_value", "our_value", "status", "reason"]


def load_reasons(studies: Iterable[str] = SECTIONS) -> dict[str, Callable]:
    """Every study's reason functions by claim id, from the registry :data:`eqrec.studies.claims.reasons.REASONS`.

    Each study's ``claims`` module (:data:`~eqrec.studies.pipeline.configuration.CLAIMS_MODULE`), where there is one, is
    imported by name, and its ``@reason`` decorators fill the registry: the table imports no study.

    Parameters
    ----------
    studies : Iterable[str]
        The studies' names (default: the configuration's sections).

    Returns
    -------
    dict[str, callable]
        The registry, claim id -> reason function.
    """
    for name in (CLAIMS_MODULE.format(study) for study in studies):
        if importlib.util.find_spec(name) is not None:
            importlib.import_module(name)
    return claim_reasons.REASONS


#: The reason functions of every study by claim id (see :mod:`eqrec.studies.claims.reasons`).
REASONS: dict[str, Callable] = load_reasons()


# --------------------------------------------------------------------------- claims file

def load_claims(path: str | Path, reasons: Mapping[str, Callable] | None = None) -> list[dict]:
    """Read and check the claims file, and that every claim whose wording needs a choice has its function.

    Parameters
    ----------
    path : str or Path
        ``config/claims.yaml``.
    reasons : Mapping[str, callable], optional
        Reason functions by claim id (default: :data:`REASONS`, those of the studies).

    Returns
    -------
    list of dict
        The entries, checked by :func:`~eqrec.studies.claims.published.read_claims`, and a reason function
        for every claim with named notes or an explanation.
    """
    reasons = REASONS if reasons is None else reasons
    data = read_claims(path)
    for entry in data:
        if (isinstance(entry.get("note"), Mapping) or "explanation" in entry) and entry["id"] not in reasons:
            raise InputError(f"claim {entry['id']}: named texts and explanations are chosen by a reason function, "
                             "and none is registered for this id (eqrec.studies.p*.claims)", str(path), "id")
    return data


def default_atol(paper_value: Any) -> float:
    """Half a unit in the last printed digit of a published number."""
    exponent = Decimal(str(paper_value)).as_tuple().exponent
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
    """Status and the tolerance wording of one claim (of a kind :func:`load_claims` accepts)."""
    cmp, paper = entry["compare"], entry["paper_value"]
    if cmp["kind"] == "none":
        return "not comparable", cmp.get("why", "")
    if ours is None or (isinstance(ours, float) and math.isnan(ours)):
        return "differs", "our computation produced no value"
    if cmp["kind"] == "text":
        ok = str(ours).strip().lower() == str(paper).strip().lower()
        wording = "exact match" if ok else ""
    elif cmp["kind"] == "number":
        ok = abs(float(ours) - float(paper)) <= _tolerance(entry)
        wording = f"tolerance {float(cmp.get('atol', default_atol(paper))):g} + {float(cmp.get('rtol', 0.0)):g}|paper|"
    elif cmp["kind"] == "array":
        a, b, atol = np.asarray(ours, float), np.asarray(paper, float), float(cmp.get("atol", 0.0))
        if a.shape != b.shape:
            return "differs", f"shape {a.shape} vs published {b.shape}"
        gap = float(np.max(np.abs(a - b))) if a.size else 0.0
        ok, wording = gap <= atol, f"largest entry gap {gap:.2g} (tolerance {atol:g})"
    else:  # interval
        ok = all(abs(float(a) - float(b)) <= _tolerance(entry) for a, b in zip(ours, paper))
        wording = f"endpoint tolerance {_tolerance(entry):g}"
    return ("reproduced" if ok else "differs"), wording


def _number(x: Any) -> Any:
    try:
        return float(x) if isinstance(x, str) else x
    except ValueError:
        return x


def _fill(template: str, fields: Mapping[str, Any], cid: str) -> str:
    try:
        return template.format_map(fields).strip()
    except KeyError as exc:
        raise InputError(f"claim {cid}: a text names evidence the values file lacks: {exc.args[0]!r}") from None


def _join_pieces(texts: list[str]) -> str:
    """Pieces separated by a space, except before a piece that starts with punctuation."""
    joined = ""
    for t in filter(None, texts):
        joined += t if (not joined or t[0] in ",;:.)") else " " + t
    return joined


def _reason(entry: dict, ctx: Mapping[str, Any], reasons: Mapping[str, Callable]) -> tuple[dict, str, str]:
    """The fields, the note and the explanation (or the line saying it was withdrawn) of one claim."""
    cid = entry["id"]
    notes, explanations = named_texts(entry, "note", cid), named_texts(entry, "explanation", cid)
    chosen = Reason()
    if cid in reasons:
        try:
            chosen = reasons[cid](ctx, notes)
        except KeyError as exc:
            raise InputError(f"claim {cid}: its reason function reads {exc.args[0]!r}, which neither the evidence "
                             "nor the claim's texts have") from None
    if isinstance(entry.get("note"), Mapping) and chosen.note is None:
        raise InputError(f"claim {cid}: its reason function must choose among the named notes {list(notes)}")
    names = list(notes) if chosen.note is None else chosen.note
    if set(names) - set(notes) or set(chosen.explanation) != set(explanations):
        raise InputError(f"claim {cid}: its reason function chose notes {list(names)} of {list(notes)} and "
                         f"judged explanations {list(chosen.explanation)} of {list(explanations)}")
    fields = {**ctx, **chosen.fields}
    note = _join_pieces([_fill(notes[n], fields, cid) for n in names])
    text = _join_pieces([_fill(t, fields, cid) for n, t in explanations.items() if chosen.explanation[n]])
    withdrawn = [n for n in explanations if not chosen.explanation[n]]
    if withdrawn:
        text = _join_pieces([text, f"[explanation withdrawn: its evidence no longer holds ({'; '.join(withdrawn)})]"])
    return fields, note, text


def _values_file(values: Sequence[str | Path] | str | Path, ref_file: str) -> Path:
    """The declared values file a claim refers to (``p1/values.json`` -> ``.../p1/values.json``)."""
    if isinstance(values, (str, Path)):
        path = Path(values) / ref_file
        if not path.is_file():
            raise FileNotFoundError(f"results file {path} needed by a claim does not exist")
        return path
    ref = Path(ref_file).parts
    for path in map(Path, values):  # ``p1/values.json`` is results/p1/values.json, not results/timings/p1/values.json
        if path.parts[-len(ref):] == ref and path.parts[-len(ref) - 1:-len(ref)] != ("timings",):
            return path
    raise FileNotFoundError(f"values file {ref_file} needed by a claim is not among the inputs {list(values)}")


def _lookup_value(values: Sequence[str | Path] | str | Path, ref: str,
                  read: Callable[[Path], Any]) -> tuple[Any, dict]:
    """Our value and its evidence (``ref``: ``p1/values.json#key``); ``read`` parses a values file."""
    file, _, key = ref.partition("#")
    path = _values_file(values, file)
    data = read(path)
    if key not in data:
        raise KeyError(f"{path} has no value '{key}'")
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


def build_claims_table(claims_path: str | Path, values: Sequence[str | Path] | str | Path,
                       reasons: Mapping[str, Callable] | None = None) -> pd.DataFrame:
    """Compare every claim with the pipeline's values.

    Parameters
    ----------
    claims_path : str or Path
        ``config/claims.yaml``.
    values : sequence of str or Path, or str or Path
        The ``values.json`` files (or the results folder holding ``p1/values.json`` ...).
    reasons : Mapping[str, callable], optional
        Reason functions by claim id (default: :data:`REASONS`).

    Returns
    -------
    pandas.DataFrame
        One row per claim: the columns of ``claims.csv`` plus ``source``, ``timing`` and
        ``fixed_reason``.  Raises if a referenced result is missing: a table with holes would be a
        partial result presented as whole.
    """
    import pandas as pd  # here, not at the top: the Snakefile reads published values at every start

    reasons = REASONS if reasons is None else reasons
    claims = load_claims(claims_path, reasons)
    published = {e["id"]: _number(e["paper_value"]) for e in claims}  # for a reason that cites another claim's
    read = functools.cache(lambda path: json.loads(path.read_text()))  # each values file parsed once
    rows = []
    for entry in claims:
        ours, evidence = _lookup_value(values, entry["value"], read)
        status, tol = compare_one(entry, ours)
        ctx = {**evidence, "value": ours, "paper": _number(entry["paper_value"]), "tol": _tolerance(entry),
               "published": published}
        fields, note, explanation = _reason(entry, ctx, reasons)
        if status == "differs":
            reason = " ".join(t for t in (note, explanation) if t) or "unexplained"
        elif status == "reproduced":
            reason = ("within " if tol != "exact match" else "") + tol + (f"; {note}" if note else "")
        else:
            reason = " ".join(p for p in (tol, note) if p)
        shown = _fill(entry["shown_as"], fields, entry["id"]) if entry.get("shown_as") else fmtlist(ours, ".6g")
        rows.append({"id": entry["id"], "quantity": entry["quantity"],
                     "paper_value": fmtlist(entry["paper_value"], ".6g"), "our_value": shown, "status": status,
                     "reason": reason, "source": entry["source"], "timing": is_timing_claim(entry),
                     "fixed_reason": tol})
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
             "| status | count |", "|---|---|", *(f"| {s} | {int(counts.get(s, 0))} |" for s in STATUSES), ""]
    for paper, group in table.groupby(table["id"].str.split("-").str[0], sort=True):
        lines += [f"## {paper}", "", "| id | quantity | paper | ours | status | reason | source |",
                  "|---|---|---|---|---|---|---|"]
        for cells in group.assign(status="**" + group["status"] + "**")[[*COLUMNS, "source"]].itertuples(index=False):
            lines.append("| " + " | ".join(str(c).replace("|", "\\|").replace("\n", " ") for c in cells) + " |")
        lines.append("")
    return "\n".join(lines)


def step_table(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """The claims table from ``config/claims.yaml`` and the studies' declared ``values.json`` files:
    ``claims.csv`` and ``REPRODUCTION.md`` without the measured values, the timing rows in full beside."""
    table = build_claims_table(inputs.claims, [*inputs["values"], *inputs["timings"]])
    fixed = without_timings(table)
    write_csv(outputs.csv, fixed[COLUMNS])
    write_text(outputs.md, render_markdown(fixed))
    write_csv(outputs.timings, table.loc[table["timing"].astype(bool), COLUMNS])
    for status, n in table["status"].value_counts().items():
        log.info("%s: %d", status, n)
    return table
