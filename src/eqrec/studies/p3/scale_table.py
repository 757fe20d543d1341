r"""The P3 scale table: steps of the delayed/missing-data study (P3).

The scale table (steps ``scale_size`` per ``(T, τ̄)`` of the tree LP, ``scale_sizes`` for every size of the class
engine in one job, ``scale_table``): the
batch reactor's full-language design (sum cost, ``μ1`` fixed) solved by one
HiGHS method in a fresh process with time and memory limits
(:func:`eqrec.studies.p3.size_run.run_size`), by two engines side by side:
the tree LP (node per event prefix, the language enumerated) and the class
engine (one LP per (time, available data) class and state row, the classes
from the window rule, no word enumerated; :mod:`eqrec.design.classes.engine`).  The
default run writes ``results/p3/scale_table.{csv,md}`` from
``scale.tree_sizes`` (the tree LP where it takes seconds) and
``scale.class_sizes``; the target ``p3_scale`` (outside the default run)
writes ``results/p3/scale_table_full.{csv,md}``, adding the tree LP at
``scale.tree_slow_sizes`` (minutes and up to the memory limit each).  Per-size
JSONs: ``results/p3/scale/T{T}_tau{τ̄}.json`` (tree) and
``results/p3/scale/classes_T{T}_tau{τ̄}.json``.

Configuration (``cfg`` is the ``p3`` section; defaults are the schema's)
------------------------------------------------------------------------
``scale``:

=========================  ======================================  ========================================
key                        default                                 meaning
=========================  ======================================  ========================================
``tree_sizes``             ``[[5,2],[6,2]]``                       ``(T, τ̄)`` of the tree LP in the default
                                                                   run (seconds each)
``tree_slow_sizes``        ``[[7,2],[8,2],[8,3]]``                 ``(T, τ̄)`` of the tree LP in the
                                                                   ``p3_scale`` target only
``class_sizes``            ``[[5,2],[6,2],[7,2],[8,2],[8,3],``     ``(T, τ̄)`` of the class engine (default
                           ``[20,4],[30,4],[40,4],[30,5]]``        run)
``method``                 ``simplex``                             HiGHS method (``scale_sweep.METHODS``),
                                                                   both engines
``builder``                ``core``                                tree LP builder (``core``)
``mu1``                    ``0.5``                                 fixed ``μ1``
``time_limit``             ``600``                                 HiGHS time limit per size [s]
``mem_limit_gb``           ``16``                                  address-space limit per size [GB]
=========================  ======================================  ========================================
"""

from __future__ import annotations

import math
import re
from typing import TYPE_CHECKING

from eqrec.errors import InputError

from eqrec.studies.p3.size_run import ENGINES, FIELDS, class_count, run_size, tree_J
from eqrec.systems.examples import batch_reactor
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import TIMING_KEYS, read_json, write_csv, write_json, write_text

if TYPE_CHECKING:
    import pandas as pd

log = get_logger("p3")


def step_scale_size(cfg, inputs, outputs, wildcards) -> dict:
    """One row of the scale table: the full language ``{0..τ̄}^T`` (wildcards ``T``, ``tau``) in a fresh process.

    The wildcard ``engine`` (``tree`` when absent) picks the tree LP or the
    class engine (:data:`eqrec.studies.p3.size_run.ENGINES`).  A size that hits
    the time or memory limit is recorded with that status (the step succeeds).
    """
    return _one_size(cfg, int(wildcards.T), int(wildcards.tau), wildcards.get("engine", "tree"), outputs.json,
                     outputs.timings)


#: A per-size JSON of the class engine's rows of the scale table: ``classes_T<T>_tau<τ̄>.json``.
_CLASS_SIZE_FILE = re.compile(r"classes_T(\d+)_tau(\d+)\.json")


def step_scale_sizes(cfg, inputs, outputs, wildcards) -> list[dict]:
    """The class engine's rows of the scale table in one job: each size of the outputs ``json`` (one file per size
    of ``scale.class_sizes``, each once, named ``classes_T<T>_tau<τ̄>.json``, with its ``timings`` file in the same
    order), one after the other, each in a fresh worker process (:func:`step_scale_size`'s row, the same files).

    Seconds a size: a job per size spent more CPU on starting than on the size.
    """
    files, timings = ([paths] if isinstance(paths, str) else list(paths) for paths in (outputs.json, outputs.timings))
    found = [_CLASS_SIZE_FILE.fullmatch(path.rsplit("/", 1)[-1]) for path in files]
    sizes = [(int(m[1]), int(m[2])) for m in found if m]
    if len(sizes) != len(files) or len(timings) != len(files) \
            or sorted(sizes) != sorted(map(tuple, cfg["scale"]["class_sizes"])):
        raise InputError(f"the rule's outputs {files} are not one per size", field="scale.class_sizes")
    return [_one_size(cfg, T, tau, "classes", *paths) for (T, tau), *paths in zip(sizes, files, timings)]


def _one_size(cfg: dict, T: int, tau: int, engine: str, json_path: str, timings_path: str) -> dict:
    """One size in a fresh process (:func:`eqrec.studies.p3.size_run.run_size`), logged and written."""
    sc = cfg["scale"]
    log.info("scale (T, tau) = (%d, %d), %s engine: %s, builder %s, mu1 = %g, limits %g s / %g GB", T, tau, engine,
             sc["method"], sc["builder"], float(sc["mu1"]), float(sc["time_limit"]), float(sc["mem_limit_gb"]))
    r = run_size(batch_reactor(), T, tau, sc["method"], float(sc["mu1"]), float(sc["time_limit"]),
                 float(sc["mem_limit_gb"]), sc["builder"], engine=engine)
    log.info("scale (%d, %d), %s: %s; %s classes, %s columns, build %.2f s, solve %.2f s, peak %.0f MB, J = %s", T,
             tau, engine, r.get("status"), r.get("classes"), r.get("cols"), r.get("build_time", float("nan")),
             r.get("solve_time", float("nan")), r.get("peak_mb", float("nan")), r.get("J"))
    write_json(json_path, r, timings=timings_path)
    return r


def scale_frame(rows: list[dict]) -> pd.DataFrame:
    """The scale table as a frame (columns :data:`eqrec.studies.p3.size_run.FIELDS`), sorted by ``(T, τ̄)``, the
    tree LP before the class engine.

    Rows written before the engine dimension (the tracked tree sizes) read as
    ``engine = "tree"``; their ``classes`` (closed form) and ``J`` (the LP's
    objective plus the constant ``(1 + 2|L^{E'}|) μ1`` it leaves out) are
    filled in.
    """
    rows = [{"engine": "tree", **r} for r in rows]
    for r in rows:
        if r.get("classes") is None and "T" in r and "tau" in r:
            r["classes"] = class_count(r["T"], r["tau"])
        if (r["engine"] == "tree" and r.get("J") is None and r.get("status") == "optimal"
                and r.get("objective") is not None and r.get("sequences") is not None):
            r["J"] = tree_J(r["objective"], r["sequences"], r["mu1"])
    # imported here: only the table step needs pandas, not the eleven size jobs (saves ~0.5 s CPU per size job)
    import pandas as pd

    frame = pd.DataFrame(rows).reindex(columns=list(FIELDS))
    order = frame["engine"].map({e: i for i, e in enumerate(ENGINES)}).fillna(len(ENGINES))  # then unknown engines
    frame = frame.assign(_e=order).sort_values(["T", "tau", "_e", "method"], kind="stable")
    return frame.drop(columns="_e").reset_index(drop=True)


def _md_cell(v, col: str = "") -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return ""
    if isinstance(v, int):  # a bool too: str
        return f"{v:.3e}" if abs(v) >= 10**10 else str(v)  # (τ̄+1)^T: 9.313e+20 words at (30, 4)
    if isinstance(v, float):
        if col in ("max_level", "terminal_level"):
            return f"{v:.6f}"
        if col == "J":
            return f"{v:.6g}" if abs(v) >= 1e6 else f"{v:.4f}"
        if col == "peak_mb" or v.is_integer():
            return f"{v:.0f}" if abs(v) < 1e10 else f"{v:.3e}"
        return f"{v:.2f}" if abs(v) < 1e6 else f"{v:.4g}"
    return str(v)


def _value(v):
    return v.item() if hasattr(v, "item") else v


def md_table(head: list[str], rows) -> str:
    """A Markdown table: the header cells ``head``, then a line per row of cells (``rows``; ``str`` of each)."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join(lines + ["| " + " | ".join(map(str, cells)) + " |" for cells in rows]) + "\n"


def scale_markdown(frame: pd.DataFrame, missing_tree: list | None = None, timings: bool = True) -> str:
    """The scale table in Markdown: a note (setting, why the class engine scales), one row per (size, engine),
    then the two engines side by side on the sizes both ran.

    ``missing_tree``: tree sizes left out of this table (the slow ones of the
    ``p3_scale`` target), named in the note.  ``timings=False``: without the
    measured columns (times, memory), which change from run to run; the
    table with them is written under ``results/timings/``.
    """
    columns = [("T", "T"), ("tau", "τ̄"), ("words", "words"), ("sequences", "sequences (L^E')"), ("nodes", "nodes"),
               ("classes", "classes (d, S)"), ("engine", "engine"), ("rows", "LP rows"), ("cols", "LP cols"),
               ("nnz", "nonzeros"), ("tree_time", "tree [s]"), ("classes_time", "classes [s]"),
               ("build_time", "build [s]"), ("method", "HiGHS method"), ("solve_time", "solve [s]"),
               ("iterations", "iterations"), ("J", "J"), ("max_level", "max μ2"), ("peak_mb", "peak [MB]"),
               ("status", "status")]
    columns = [(c, h) for c, h in columns if timings or c not in TIMING_KEYS]
    parts = ["# P3 scale table\n"]
    if len(frame):
        meta = frame.iloc[0]
        tree = frame[frame["engine"] == "tree"]
        builder = tree["builder"].iloc[0] if len(tree) else "core"
        parts.append(
            f"Batch reactor (Section IV-A of the delayed-data paper), full delay language {{0..τ̄}}^T, sum cost J of "
            f"Theorem 1 / Proposition 1, mu1 = {_value(meta['mu1']):g} fixed; one fresh process per size and engine, "
            f"HiGHS {meta['method']}, time limit {_value(meta['time_limit']):g} s, address-space limit "
            f"{_value(meta['mem_limit_gb']):g} GB. Engine `tree`: the node-per-prefix LP on the enumerated prefix tree "
            f"(builder {builder}); engine `classes`: one LP per (time, available data) class and state row, the "
            f"classes built by the window rule without enumerating a word (`eqrec.design.classes.engine`).\n")
        parts.append(
            "Why the class engine scales: by the separation theorem of `eqrec.design.classes.engine`, every node of a "
            "class (d, S) attains the same optimal level whatever its ancestors' gains, so the tree LP's optimum is "
            "the class levels weighted by their sequence counts and one small LP per class and state row gives it. "
            "The classes number Σ_{d=1..T} 2^min(τ̄, d) ≈ T·2^τ̄ (446 at (30, 4)), while the sequences and prefix-tree "
            "nodes the tree LP carries grow like (τ̄+1)^T (1.8e+20 sequences at (30, 4)).\n")
        if timings:
            parts.append(
                "Columns: `tree [s]` enumerates the language and builds its prefix tree, `classes [s]` builds the "
                "class set, `build [s]` assembles the LP, `solve [s]` is HiGHS (`total [s]` below: their sum); "
                "`peak [MB]` is the worker's peak resident memory (timings and memory are measurements: they change "
                "from run to run). `J` is the paper's sum cost (the same for both engines); `max μ2` the largest "
                "level (class engine: certified from the gains; tree: the LP's).\n")
        else:
            parts.append(
                "Columns: the language and LP sizes, `J` the paper's sum cost (the same for both engines) and "
                "`max μ2` the largest level (class engine: certified from the gains; tree: the LP's). The times and "
                "peak memory of each size are measurements that change from run to run: they are in "
                "`results/timings/p3/` (the same table with them, `scale_table.md` there).\n")
        if missing_tree:
            parts.append(
                f"Tree LP at {', '.join(f'({int(T)}, {int(tau)})' for T, tau in missing_tree)}: "
                f"`results/p3/scale_table_full.md` (target `p3_scale`, "
                f"outside the default run: minutes and up to the memory limit per size).\n")
    parts.append(md_table([h for _, h in columns], ([_md_cell(_value(row[c]), c) for c, _ in columns]
                                                     for _, row in frame.iterrows())))
    side = _side_by_side(frame, timings)
    if side:
        parts.append("## Side by side (sizes both engines ran)\n\n" + side)
    return "\n".join(parts)


def _side_by_side(frame: pd.DataFrame, timings: bool = True) -> str:
    """Per size run by both engines: LP sizes, total times (language + build + solve), peak memory and J of each
    (without times and memory when ``timings`` is false)."""
    by = {(int(_value(r["T"])), int(_value(r["tau"])), r["engine"]): r for _, r in frame.iterrows()}
    sizes = sorted({(T, tau) for T, tau, e in by if (T, tau, "tree") in by and (T, tau, "classes") in by})
    if not sizes:
        return ""

    def total(r):  # a size that did not solve has no total (its build time is in the table above)
        if r["status"] != "optimal":
            return None
        vals = [_value(r[c]) for c in ("tree_time", "classes_time", "build_time", "solve_time") if r.notna()[c]]
        return float(sum(vals)) if vals else float("nan")

    # (header, engine of the row, field; "total" is the sum above)
    columns = [("T", "classes", "T"), ("τ̄", "classes", "tau"), ("sequences", "classes", "sequences"),
               ("nodes", "classes", "nodes"), ("classes", "classes", "classes"), ("tree LP cols", "tree", "cols"),
               ("class LP cols", "classes", "cols"), ("tree total [s]", "tree", "total"),
               ("classes total [s]", "classes", "total"), ("tree peak [MB]", "tree", "peak_mb"),
               ("classes peak [MB]", "classes", "peak_mb"), ("tree status", "tree", "status"),
               ("classes status", "classes", "status"), ("J (tree)", "tree", "J"), ("J (classes)", "classes", "J")]
    columns = [col for col in columns if timings or col[2] not in ("total", "peak_mb")]
    rows = ([_md_cell(total(by[T, tau, e]) if f == "total" else _value(by[T, tau, e][f]), f) for _, e, f in columns]
            for T, tau in sizes)
    return md_table([h for h, *_ in columns], rows)


def step_scale_table(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """Merge the per-size JSONs (``inputs.sizes``, with their ``inputs.timings``) into the scale table: ``outputs.csv``
    and ``outputs.md`` without the measured columns, ``outputs.timings_csv`` and ``outputs.timings_md`` with them.

    The Markdown note names the ``scale.tree_slow_sizes`` whose tree row is
    not among the inputs (the default run's table leaves them to ``p3_scale``).
    """
    rows = [read_json(p, timings=t) for p, t in zip(inputs.sizes, inputs.timings, strict=True)]
    frame = scale_frame(rows)
    have = {(int(r["T"]), int(r["tau"])) for r in rows if r.get("engine", "tree") == "tree"}
    slow = cfg["scale"]["tree_slow_sizes"]  # validated config: the schema fills the default
    missing = [(int(T), int(tau)) for T, tau in slow if (int(T), int(tau)) not in have]
    write_csv(outputs.csv, frame, timings=outputs.timings_csv, keys=["engine", "T", "tau"])
    write_text(outputs.md, scale_markdown(frame, missing, timings=False))
    write_text(outputs.timings_md, scale_markdown(frame, missing, timings=True))
    log.info("scale table: %d rows (%d tree, %d classes)", len(frame), int((frame["engine"] == "tree").sum()),
             int((frame["engine"] == "classes").sum()))
    return frame
