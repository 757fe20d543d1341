"""Sweeps in chunk jobs: the grid points of a chunk, and the check that merged chunks cover the grid.

A sweep of ``num`` points runs as ``n`` jobs through Snakemake's
``scattergather`` (``n`` is the configured ``chunks`` count, or ``--set-scatter``);
the job of ``scatteritem`` ``"i-of-n"`` computes the points :func:`scatter_indices`
gives, and the merging step (its inputs ``gather.<sweep>(...)``) checks with
:func:`check_coverage` that its chunk files hold every point exactly once, so
no chunk count leaves a trace in the merged result.  Used by the P2 heat map
(CSV chunks, :mod:`eqrec.studies.p2.sweeps`) and the P4 steady-state sweeps
(NPZ chunks, :func:`merge_npz`).
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Sequence

import numpy as np

from eqrec.errors import InputError
from eqrec.studies.pipeline.outputs import write_npz


def chunk_indices(num: int, chunks: int, k: int, field: str = "chunks") -> np.ndarray:
    """Grid indices of chunk ``k`` of ``num`` points split into ``chunks`` near-equal contiguous parts.

    Parameters
    ----------
    num, chunks, k : int
        Grid points, chunks, and the chunk (``0 <= k < chunks``).
    field : str
        Configuration field of the chunk count, named in the error.

    Returns
    -------
    numpy.ndarray
        Increasing indices into the grid.
    """
    if not 0 <= k < chunks:
        raise InputError(f"chunk {k} requested, the configuration splits the grid into chunks 0..{chunks - 1}",
                         field=field)
    return np.array_split(np.arange(num), chunks)[k]


def scatter_indices(wildcards, num: int, field: str = "chunks") -> tuple[str, np.ndarray]:
    """The job's chunk (Snakemake's ``scatteritem`` wildcard, ``"i-of-n"`` with ``i`` from 1) and its grid indices
    (:func:`chunk_indices` of part ``i - 1`` of ``n``)."""
    item = wildcards["scatteritem"]
    i, _, n = item.partition("-of-")
    return item, chunk_indices(num, int(n), int(i) - 1, field)


def check_coverage(idx: np.ndarray, num: int, field: str = "chunks", what: str = "",
                   source: str | None = None) -> None:
    """Raise :class:`~eqrec.errors.InputError` unless the grid indices ``idx`` of the merged rows hold each of
    ``0..num-1`` exactly once.

    Parameters
    ----------
    idx : numpy.ndarray
        Grid index of every merged row.
    num : int
        Number of grid points.
    field, what, source : str
        Configuration field of the chunk count, prefix of the message, and the merged file (for the error).
    """
    idx = np.asarray(idx, int)
    inside = (idx >= 0) & (idx < num)
    counts = np.bincount(idx[inside], minlength=num)
    missing, twice, outside = int((counts == 0).sum()), int((counts > 1).sum()), int((~inside).sum())
    if missing or twice or outside:
        beyond = f" and hold {outside} rows outside it" if outside else ""
        raise InputError(f"{what}{': ' if what else ''}the chunks miss {missing} and repeat {twice} of the {num} "
                         f"grid points{beyond} (each must be covered exactly once)", source, field)


def merge_npz(files: Sequence[str | Path], num: int, out_npz: str | Path,
              shared: Iterable[str] = ()) -> dict[str, np.ndarray]:
    """Merge NPZ chunks (any order) into ``out_npz``: every array concatenated along its first axis in grid order.

    Each chunk holds ``idx`` (its grid indices) and ``num`` (its grid size, checked; not written); the arrays
    named in ``shared`` are common to all chunks and taken from the first.

    Parameters
    ----------
    files : sequence of str or pathlib.Path
        The chunk files.
    num : int
        Number of grid points of the configuration.
    out_npz : str or pathlib.Path
        The merged file.
    shared : iterable of str
        Arrays that are not split (e.g. the second axis of a 2-D grid).

    Returns
    -------
    dict of str to numpy.ndarray
        The merged arrays, as written.
    """
    parts = [dict(np.load(f)) for f in files]
    if not parts:
        raise InputError("no chunk files to merge", str(out_npz), "chunks")
    for f, p in zip(files, parts):
        if "num" in p and int(p["num"]) != num:
            raise InputError(f"chunk {f} is of a {int(p['num'])}-point grid, the configuration has {num} points",
                             str(f), "num")
    parts.sort(key=lambda p: int(p["idx"][0]) if len(p["idx"]) else -1)
    shared = set(shared)
    merged = {key: parts[0][key] if key in shared else np.concatenate([p[key] for p in parts])
              for key in parts[0] if key != "num"}
    check_coverage(merged["idx"], num, source=str(out_npz))
    if not np.array_equal(merged["idx"], np.arange(num)):  # each point once, yet chunks that interleave
        raise InputError("chunks interleave: the merged grid indices are not increasing", str(out_npz), "chunks")
    write_npz(out_npz, **merged)
    return merged
