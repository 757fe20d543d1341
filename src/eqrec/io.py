"""Atomic file writing, shared by the workflow's steps (:mod:`eqrec.studies.pipeline.harness`) and the CLI.

A file is written to a temporary file in its own folder and moved onto its
name with :func:`os.replace`, so a reader never sees half a file and a failed
write leaves nothing behind.  A killed process (SIGKILL) cannot remove its
temporary file: :func:`remove_stale_temporaries` does, before the file is
written again (``workflow/scripts/run_step.py``, for a job's outputs).
"""

from __future__ import annotations

import contextlib
import os
import re
import tempfile
from pathlib import Path
from typing import Iterable, Iterator

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


def remove_stale_temporaries(paths: Iterable[str | os.PathLike]) -> list[Path]:
    """Remove the temporary files that killed :func:`atomic_path` writes of ``paths`` left.

    Only the names :func:`atomic_path` gives (``.<name>.<8 characters of a-z0-9_>.tmp``, the random part of
    :func:`tempfile.mkstemp`) beside each path go.  Call it only where no other process may be writing these
    paths (a Snakemake job holds their lock).

    Parameters
    ----------
    paths : iterable of str or path-like
        The files about to be written.

    Returns
    -------
    list of Path
        The files removed.
    """
    names: dict[Path, set[str]] = {}
    for path in map(Path, paths):
        names.setdefault(path.parent, set()).add(re.escape(path.name))
    removed = []
    for folder, escaped in names.items():
        pattern = re.compile(rf"\.(?:{'|'.join(sorted(escaped))})\.[a-z0-9_]{{8}}\.tmp")
        for entry in folder.iterdir() if folder.is_dir() else ():
            if pattern.fullmatch(entry.name) and entry.is_file():
                entry.unlink(missing_ok=True)
                removed.append(entry)
    return sorted(removed)


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


@contextlib.contextmanager
def gc_paused() -> Iterator[None]:
    """Run the body with Python's cyclic garbage collector paused, then restore it as it was (also on an error).

    For a job's long loop over objects that stay to its end (modules, compiled kernels, designs, figures): each
    full pass of the collector scans them all again, while the loop leaves little cyclic garbage (the compare
    job: about 0.3 s of CPU less, its peak memory 3 MB higher of 320).  Reference counting still frees the rest;
    no number depends on it.

    Yields
    ------
    None
    """
    import gc

    collecting = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if collecting:
            gc.enable()


@contextlib.contextmanager
def compiled_once() -> Iterator[None]:
    """Run the body alone while the package's Numba kernels are not compiled yet; concurrently once they are.

    The kernels are compiled on their first call and cached on disk (``@numba.njit(cache=True)``: in the
    ``__pycache__`` folders of the package, or in ``NUMBA_CACHE_DIR``).  Jobs started together on a fresh clone
    would each compile them (tens of seconds of CPU each).  Here the first job holds an exclusive lock
    (:func:`fcntl.flock`) on a file of the cache folder while its body runs, then leaves a marker; a job that
    finds the marker runs at once, one that waits for the lock finds the marker when it gets the lock and loads
    the kernels from the cache.  The marker is named by a hash of the package's sources that use Numba and of
    the Numba and Python versions, so an edited kernel is compiled once again.  Where the cache folder cannot be
    written, the body runs without the lock.

    Yields
    ------
    None
    """
    import fcntl
    import hashlib
    import platform

    import numba

    package = Path(__file__).resolve().parent
    digest = hashlib.sha256(f"{numba.__version__} {platform.python_version()}".encode())
    for source in sorted(package.rglob("*.py")):
        text = source.read_bytes()
        if b"numba" in text:
            digest.update(source.relative_to(package).as_posix().encode() + b"\0" + text)
    folder = Path(numba.config.CACHE_DIR) if numba.config.CACHE_DIR else package / "__pycache__"
    marker = folder / f"eqrec-compiled-{digest.hexdigest()[:16]}"
    if marker.exists():
        yield
        return
    try:
        folder.mkdir(parents=True, exist_ok=True)
        lock = open(folder / "eqrec-compile.lock", "a")
    except OSError:  # a read-only installation: Numba caches elsewhere, or not at all
        yield
        return
    with lock:
        try:
            fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file is closed
        except OSError:  # a file system without locks (some network ones): every job compiles, as before
            lock.close()
        if lock.closed or marker.exists():  # no lock, or another job compiled while this one waited
            lock.close()
            yield
            return
        yield
        marker.touch()
