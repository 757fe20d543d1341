"""What a step writes: JSON, CSV, NPZ and figures, atomically, with the measured values kept apart.

Every writer goes through :func:`eqrec.io.atomic_path` (a temporary file in
the target's folder, then ``os.replace``; removed on failure).  Timing and
memory fields (:data:`TIMING_KEYS`) never go next to the results: a step
declares a ``timings`` output under ``results/timings/`` and the writer puts
them there, so that two runs give byte-identical ``results/`` outside
``results/timings/``.  A step that writes a timing without a timings output
fails (:class:`~eqrec.errors.StepError`).
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any, Iterable, Mapping, Sequence

from eqrec.errors import StepError
from eqrec.io import save_figure  # noqa: F401  (the one figure writer, re-exported for the steps)
from eqrec.io import atomic_path, write_text

def _json_default(obj: Any) -> Any:
    import numpy as np

    for types, convert in ((np.bool_, bool), (np.integer, int), (np.floating, float), (np.ndarray, np.ndarray.tolist),
                           ((set, tuple), list)):
        if isinstance(obj, types):
            return convert(obj)
    raise TypeError(f"cannot write {type(obj).__name__} as JSON")


#: Keys of the values that change from run to run (wall-clock times, memory peaks).  A step
#: writes them to its ``timings`` output (under ``results/timings/``), never next to the
#: results, so that two runs give byte-identical ``results/`` outside ``results/timings/``.
TIMING_KEYS = frozenset({
    "build_s", "solve_s", "total_s", "time_s", "global_s", "ipopt_s", "run_time_s", "elapsed_s",
    "prefix_time_s", "time_time_s", "strategy_time_s",
    "build_time", "solve_time", "tree_time", "classes_time", "wall_time", "peak_mb",
})


#: ``write_csv(..., timings=INTERMEDIATE)``: a temporary output (a sweep chunk) keeps its timing columns;
#: the step that merges the chunks splits them off.
INTERMEDIATE = "intermediate"


def timings_of(paths: Iterable[str]) -> list[str]:
    """The timings file a step writes beside each of its results files: ``results/x`` -> ``results/timings/x``."""
    return [str(p).replace("results/", "results/timings/", 1) for p in paths]


def split_timings(data: Any) -> tuple[Any, Any]:
    """Split nested JSON-like ``data`` into ``(rest, timings)``.

    A mapping entry whose key is in :data:`TIMING_KEYS` goes, whole, to
    ``timings``, at the same place in the nesting (lists keep their length,
    with ``None`` where an item has no timing).  ``timings`` is ``None`` when
    ``data`` holds none.  :func:`merge_timings` undoes the split.
    """
    if isinstance(data, Mapping):
        rest, timed = {}, {}
        for key, val in data.items():
            if key in TIMING_KEYS:
                timed[key] = val
                continue
            rest[key], sub = split_timings(val)
            if sub is not None:
                timed[key] = sub
        return rest, (timed or None)
    if isinstance(data, (list, tuple)):
        parts = [split_timings(v) for v in data]
        timed_items = [t for _, t in parts]
        return [r for r, _ in parts], (timed_items if any(t is not None for t in timed_items) else None)
    return data, None


def merge_timings(data: Any, timings: Any) -> Any:
    """Put the ``timings`` written by :func:`split_timings` back into ``data`` (in place; returns ``data``)."""
    if timings is None:
        return data
    if isinstance(timings, Mapping) and isinstance(data, dict):
        for key, val in timings.items():
            data[key] = val if key in TIMING_KEYS or key not in data else merge_timings(data[key], val)
        return data
    if isinstance(timings, list) and isinstance(data, list) and len(timings) == len(data):
        return [merge_timings(d, t) for d, t in zip(data, timings)]
    raise StepError("timings file does not match its results file (run the workflow again)")


def _json_text(data: Any) -> str:
    return json.dumps(data, indent=2, default=_json_default) + "\n"


def write_json(path: str | Path, data: Any, timings: str | Path | None = None) -> None:
    """JSON with two-space indent and a final newline; numpy scalars and arrays as numbers and lists.

    Timing and memory entries (:data:`TIMING_KEYS`) go to the file ``timings``
    (the step's ``timings`` output, under ``results/timings/``), the rest to
    ``path``; a step that records timings without declaring where is an error.
    """
    rest, timed = split_timings(data)
    if timed is not None and timings is None:
        keys = sorted(_timing_keys_in(timed))
        raise StepError(f"{path}: timing fields {keys} need a timings output (results/timings/...)")
    if timings is not None:
        write_text(timings, _json_text(timed if timed is not None else {}))
    write_text(path, _json_text(rest))


def _timing_keys_in(timed: Any) -> set[str]:
    if isinstance(timed, Mapping):
        return {k for k in timed if k in TIMING_KEYS} | {x for v in timed.values() for x in _timing_keys_in(v)}
    if isinstance(timed, list):
        return {x for v in timed for x in _timing_keys_in(v)}
    return set()


def read_json(path: str | Path, timings: str | Path | None = None) -> Any:
    """A results JSON file, with its timings (the file written by :func:`write_json`) put back when given."""
    data = json.loads(Path(path).read_text())
    if timings is not None:
        data = merge_timings(data, json.loads(Path(timings).read_text()))
    return data


def write_npz(path: str | Path, compressed: bool = False, **arrays: Any) -> None:
    import numpy as np

    with atomic_path(path) as tmp, open(tmp, "wb") as fh:
        (np.savez_compressed if compressed else np.savez)(fh, **arrays)


def write_csv(path: str | Path, frame, timings: str | Path | None = None, keys: Sequence[str] = (),
              **kwargs: Any) -> None:
    """A pandas frame as CSV (``index=False`` unless given).

    Timing and memory columns (:data:`TIMING_KEYS`) go to the CSV ``timings``
    with the ``keys`` columns that identify a row; the rest to ``path``.
    """
    kwargs.setdefault("index", False)
    timing_columns = [] if timings == INTERMEDIATE else [c for c in frame.columns if c in TIMING_KEYS]
    if timing_columns and timings is None:
        raise StepError(f"{path}: timing columns {timing_columns} need a timings output")
    if timings not in (None, INTERMEDIATE):
        write_text(timings, frame[[*keys, *timing_columns]].to_csv(**kwargs))
    write_text(path, frame.drop(columns=timing_columns).to_csv(**kwargs))
