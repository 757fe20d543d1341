"""Sweeps in chunk jobs: which grid points a chunk computes, and the merge that checks the chunks cover the grid.

A sweep over ``num`` grid points runs as ``chunks`` Snakemake jobs (the count
comes from the configuration: a laptop runs few, the SLURM profile more);
chunk ``k`` computes :func:`chunk_indices`, and the merging step checks with
:func:`check_coverage` that the chunk files it was given hold every point
exactly once, so that no chunk count leaves a trace in the merged result.
Used by the P2 heat map (:mod:`eqrec.studies.p2_sweeps`, CSV chunks) and the
P4 steady-state sweeps (:mod:`eqrec.studies.p4`, NPZ chunks).
"""

from __future__ import annotations

from pathlib import Path
from typing import Iterable, Sequence

import numpy as np
import pandas as pd

from eqrec.errors import InputError
from eqrec.studies.outputs import write_npz


def chunk_indices(num: int, chunks: int, k: int, field: str = "chunks") -> np.ndarray:
    """Indices of the grid points of chunk ``k`` (0-based): ``num`` points split into ``chunks`` near-equal,
    contiguous parts.

    Parameters
    ----------
    num : int
        Number of grid points.
    chunks : int
        Number of chunks.
    k : int
        The chunk, ``0 <= k < chunks``.
    field : str
        Configuration field of the chunk count, named in the error.

    Returns
    -------
    numpy.ndarray
        Increasing integer indices into the grid.
    """
    if not 0 <= k < chunks:
        raise InputError(f"chunk {k} requested, the configuration splits the grid into chunks 0..{chunks - 1}",
                         field=field)
    return np.array_split(np.arange(num), chunks)[k]


def check_coverage(idx: np.ndarray, num: int, field: str = "chunks", what: str = "",
                   source: str | None = None) -> None:
    """Raise :class:`~eqrec.errors.InputError` unless the merged chunks hold every grid point exactly once.

    Parameters
    ----------
    idx : numpy.ndarray
        Grid index of every merged row (integers).
    num : int
        Number of grid points.
    field : str
        Configuration field of the chunk count, named in the error.
    what : str
        Prefix of the message (e.g. the variant of a heat map).
    source : str or None
        The merged file, named in the error.
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
    """Merge NPZ chunk files: every array concatenated along its first axis in grid order, written to ``out_npz``.

    Each chunk holds ``idx`` (its grid indices, :func:`chunk_indices`) and
    ``num`` (the number of grid points it was made for), both checked against
    ``num``; the arrays named in ``shared`` are the same in every chunk and
    taken from the first.  ``num`` is not written.

    Parameters
    ----------
    files : sequence of str or pathlib.Path
        The chunk files, in any order.
    num : int
        Number of grid points of the configuration.
    out_npz : str or pathlib.Path
        The merged file.
    shared : iterable of str
        Names of arrays common to all chunks (e.g. the second axis of a 2-D grid).

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
    keep = set(shared) | {"num"}
    merged = {key: parts[0][key] if key in keep else np.concatenate([p[key] for p in parts], axis=0)
              for key in parts[0]}
    check_coverage(merged["idx"], num, source=str(out_npz))
    if not np.array_equal(merged["idx"], np.arange(num)):  # each once, yet out of order: chunks that interleave
        raise InputError("chunks interleave: merged grid indices are not increasing", str(out_npz), "chunks")
    merged.pop("num", None)
    write_npz(out_npz, **merged)
    return merged


def read_csv_chunks(files: Sequence[str | Path]) -> pd.DataFrame:
    """The rows of CSV chunk files, one frame in the order of ``files`` (``nan``/``NaN`` read as missing, an empty
    field as the empty string).

    Parameters
    ----------
    files : sequence of str or pathlib.Path
        The chunk files.

    Returns
    -------
    pandas.DataFrame
        Their rows, with a fresh index.
    """
    return pd.concat([pd.read_csv(p, keep_default_na=False, na_values=["nan", "NaN"]) for p in files],
                     ignore_index=True)
