"""Atomic file writing, shared by the workflow's steps (:mod:`eqrec.studies.pipeline.harness`) and the CLI.

A file is written to a temporary file in its own folder and moved onto its
name with :func:`os.replace`, so a reader never sees half a file and a failed
write leaves nothing behind.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path
from typing import Iterator

_UMASK = os.umask(0)
os.umask(_UMASK)


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success move it onto ``path``, on failure remove it.

    Parameters
    ----------
    path : str or Path
        The file to write (its folder is created if missing).

    Yields
    ------
    Path
        The temporary file to write to.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_UMASK)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


def write_text(path: str | Path, text: str) -> None:
    """Write ``text`` to ``path`` atomically (:func:`atomic_path`).

    Parameters
    ----------
    path : str or Path
        The file to write.
    text : str
        Its whole content.
    """
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def save_figure(fig, *paths: "str | Path") -> None:
    """Save a matplotlib figure to each path (format from the suffix: PDF, PNG, ...) atomically, then close it.

    PDFs carry no creation date, so an unchanged figure is byte-identical.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    *paths : str or Path
        The files to write.
    """
    import matplotlib.pyplot as plt

    try:
        for p in paths:
            fmt = Path(p).suffix.lstrip(".").lower()
            meta = {"CreationDate": None} if fmt == "pdf" else None
            with atomic_path(p) as tmp:
                fig.savefig(tmp, format=fmt, metadata=meta)
    finally:
        plt.close(fig)
