"""Resuming an interrupted workflow run: what a hard kill leaves behind, and how to get past it.

A ``kill -9`` of Snakemake and its jobs (or a lost session) can leave two things:

* the temporary file of a write it cut short: every step writes through
  :func:`eqrec.io.atomic_path` (a ``.<name>.<8 random characters>.tmp`` file in
  the output's folder, moved onto the output when complete), and a killed process
  cannot remove it.  The job runs again on resume (its output is missing or marked
  incomplete) and :func:`remove_stale_temporaries`, called by
  ``workflow/scripts/run_step.py`` before the step, removes it.  Snakemake holds the
  lock of the job's outputs then, so no other run can be writing them;
* Snakemake's lock (``.snakemake/locks/``): the next run of the same command stops
  with ``LockException``.  :func:`lock_advice`, installed by the Snakefile
  (:func:`explain_lock_errors`), adds to that error whether a Snakemake process
  still runs in the directory on this machine and, when none does, the one command
  that resumes: ``snakemake --unlock && <the same command>``.

Snakemake's ``temp()`` files (the sweep chunks) live outside ``results/``
(``intermediate/``, see ``workflow/rules/p2.smk``): a kill between a merge job's end
and Snakemake's removal of its chunks leaves them there, never in ``results/``.
"""

from __future__ import annotations

import logging
import os
import re
import shlex
import socket
import sys
from pathlib import Path
from typing import Iterable, Sequence

#: Where Snakemake's file backend keeps its locks, relative to the working directory.
LOCK_DIR = Path(".snakemake") / "locks"

#: The random part of a :func:`tempfile.mkstemp` name (``tempfile._RandomNameSequence``: 8 characters of
#: ``a-z0-9_``), as :func:`eqrec.io.atomic_path` names its temporary file ``.<name>.<random>.tmp``.
_RANDOM_PART = r"[a-z0-9_]{8}"

#: Options of the command line that say where the workflow is: ``snakemake --unlock`` needs them too.
_LOCATION_OPTIONS = ("-d", "--directory", "-s", "--snakefile")


def remove_stale_temporaries(outputs: Iterable[str | os.PathLike]) -> list[Path]:
    """Remove the temporary files that killed writes of ``outputs`` left (:func:`eqrec.io.atomic_path`).

    Only files named as :func:`eqrec.io.atomic_path` names the temporary file of one of these outputs
    (``.<output name>.<8 characters>.tmp`` in the output's folder) are removed.  Call it only while holding
    the outputs' lock (a Snakemake job before its step runs): a running write of the same output would lose
    its temporary file.

    Parameters
    ----------
    outputs : iterable of str or path-like
        The files a job is about to write.

    Returns
    -------
    list of Path
        The files removed.
    """
    removed = []
    by_folder: dict[Path, set[str]] = {}
    for output in outputs:
        path = Path(output)
        by_folder.setdefault(path.parent, set()).add(path.name)
    for folder, names in by_folder.items():
        if not folder.is_dir():
            continue
        pattern = re.compile(rf"\.(?:{'|'.join(map(re.escape, sorted(names)))})\.{_RANDOM_PART}\.tmp")
        for entry in folder.iterdir():
            if pattern.fullmatch(entry.name) and entry.is_file():
                entry.unlink(missing_ok=True)
                removed.append(entry)
    return sorted(removed)


def lock_files(workdir: str | os.PathLike) -> list[Path]:
    """The lock files Snakemake's file backend holds in ``workdir`` (empty when unlocked).

    Parameters
    ----------
    workdir : str or path-like
        The workflow's working directory.

    Returns
    -------
    list of Path
        The ``.snakemake/locks/<n>.{input,output}.lock`` files.
    """
    folder = Path(workdir) / LOCK_DIR
    return sorted(folder.glob("*.lock")) if folder.is_dir() else []


def _ancestors() -> set[int]:
    """This process and its ancestors (a wrapper such as ``timeout snakemake ...`` is not another run)."""
    pids, pid = {os.getpid()}, os.getppid()
    while pid > 1 and pid not in pids:
        pids.add(pid)
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except OSError:
            break
        pid = int(stat.rpartition(")")[2].split()[1])  # the field after the state: the parent's id
    return pids


def snakemake_processes(workdir: str | os.PathLike, proc: str | os.PathLike = "/proc") -> list[int] | None:
    """Processes on this machine, other than this one and its ancestors, that run Snakemake in ``workdir``.

    A process counts when a word of its command line contains ``snakemake`` (the ``snakemake`` command,
    ``python -m snakemake``, and a job's script, run from ``.snakemake/scripts/``) and its working
    directory is ``workdir`` or a folder in it.  A process whose working directory cannot be read (another
    user's) counts too: it cannot be ruled out.

    Parameters
    ----------
    workdir : str or path-like
        The workflow's working directory.
    proc : str or path-like
        The process table (Linux's ``/proc``).

    Returns
    -------
    list of int or None
        Their process ids; ``None`` when this machine has no readable process table (not Linux).
    """
    table = Path(proc)
    if not (table / "self" / "cmdline").is_file():
        return None
    target = os.path.realpath(workdir)
    skip = _ancestors()
    found = []
    for entry in table.iterdir():
        if not entry.name.isdigit() or int(entry.name) in skip:
            continue
        try:
            argv = (entry / "cmdline").read_bytes()
        except OSError:  # gone meanwhile
            continue
        if b"snakemake" not in argv:  # zombies (a killed process not yet reaped) have an empty command line
            continue
        try:
            cwd = os.readlink(entry / "cwd")
        except PermissionError:
            found.append(int(entry.name))
            continue
        except OSError:
            continue
        if cwd == target or cwd.startswith(target.rstrip(os.sep) + os.sep):
            found.append(int(entry.name))
    return sorted(found)


def resume_command(argv: Sequence[str] | None) -> str:
    """The one shell command that removes a stale lock and runs the interrupted command again.

    Parameters
    ----------
    argv : sequence of str or None
        The interrupted command's arguments after the program name (``sys.argv[1:]`` of the
        ``snakemake`` command); ``None`` when unknown.

    Returns
    -------
    str
        ``snakemake --unlock && snakemake <argv>`` (the unlock with the ``--directory`` and ``--snakefile``
        options of ``argv``); with ``argv`` unknown, the unlock followed by a placeholder.

    Examples
    --------
    >>> resume_command(["--cores", "2", "--forceall"])
    'snakemake --unlock && snakemake --cores 2 --forceall'
    >>> resume_command(["-d", "my run", "p1"])
    "snakemake -d 'my run' --unlock && snakemake -d 'my run' p1"
    """
    if argv is None:
        return "snakemake --unlock && <the same snakemake command as before>"
    location: list[str] = []
    for k, arg in enumerate(argv):
        if arg in _LOCATION_OPTIONS and k + 1 < len(argv):
            location += [arg, argv[k + 1]]
        elif arg.startswith(tuple(f"{o}=" for o in _LOCATION_OPTIONS if o.startswith("--"))):
            location.append(arg)
    unlock = shlex.join(["snakemake", *location, "--unlock"])
    return f"{unlock} && {shlex.join(['snakemake', *argv])}"


def lock_advice(workdir: str | os.PathLike, argv: Sequence[str] | None) -> str | None:
    """What to do about the lock that stopped a run in ``workdir``.

    Parameters
    ----------
    workdir : str or path-like
        The workflow's working directory.
    argv : sequence of str or None
        The command's arguments (:func:`resume_command`).

    Returns
    -------
    str or None
        When no other Snakemake process runs in ``workdir`` on this machine: that the lock is stale and the
        command that resumes.  When one does: its process ids, and to wait for it.  ``None`` when there is
        no lock file (another persistence backend) or no way to tell (no process table).
    """
    if not lock_files(workdir):
        return None
    pids = snakemake_processes(workdir)
    if pids is None:
        return None
    where = os.path.realpath(workdir)
    if pids:
        listed = ", ".join(map(str, pids))
        return (f"The lock is held: a Snakemake process still runs in {where} (process {listed}). "
                "Wait for it to end; do not unlock a directory a run is using.")
    return (f"The lock is stale: no Snakemake process runs in {where} on this machine "
            f"({socket.gethostname()}); an interrupted run (a kill, a lost session) left it. "
            "If no run on another machine uses this directory, resume with\n"
            f"    {resume_command(argv)}\n"
            "(--unlock only removes the lock; the run then re-does the jobs the interruption cut short).")


def cli_arguments() -> list[str] | None:
    """The arguments of this process's ``snakemake`` command line (``sys.argv[1:]``), ``None`` when this
    process is not the ``snakemake`` command (``python -m snakemake`` counts) but, say, a program using
    Snakemake's API."""
    program = Path(sys.argv[0]) if sys.argv and sys.argv[0] else Path()
    if program.name == "snakemake" or (program.name == "__main__.py" and program.parent.name == "snakemake"):
        return list(sys.argv[1:])
    return None


class LockAdvice(logging.Handler):
    """A log handler that follows Snakemake's lock error with :func:`lock_advice` (once, on stderr).

    Parameters
    ----------
    workdir : str or path-like
        The workflow's working directory.
    argv : sequence of str or None
        The command's arguments (:func:`resume_command`).
    """

    def __init__(self, workdir: str | os.PathLike, argv: Sequence[str] | None):
        super().__init__(level=logging.INFO)
        self.workdir, self.argv, self.done = Path(workdir), argv, False

    def emit(self, record: logging.LogRecord) -> None:
        """Print the advice after the first record of a lock error.

        Parameters
        ----------
        record : logging.LogRecord
            A record of Snakemake's logger: its ``LockException``, or the line of a dry run that finds the
            directory locked.
        """
        if self.done:
            return
        lock_error = getattr(record, "exception", None) == "LockException"
        if not lock_error and "Directory cannot be locked" not in str(record.msg):
            return
        self.done = True
        try:
            advice = lock_advice(self.workdir, self.argv)
        except Exception:  # advice must never turn into an error of its own
            return
        if advice:
            print(advice, file=sys.stderr, flush=True)


def explain_lock_errors(logger: logging.Logger, workdir: str | os.PathLike,
                        argv: Sequence[str] | None) -> LockAdvice:
    """Install :class:`LockAdvice` on Snakemake's logger (once per logger).

    Parameters
    ----------
    logger : logging.Logger
        Snakemake's logger (``logging.getLogger("snakemake.logging")``).
    workdir : str or path-like
        The workflow's working directory.
    argv : sequence of str or None
        The command's arguments (:func:`resume_command`).

    Returns
    -------
    LockAdvice
        The handler installed (the one already there, if any).
    """
    for handler in logger.handlers:
        if isinstance(handler, LockAdvice):
            return handler
    handler = LockAdvice(workdir, argv)
    logger.addHandler(handler)
    return handler
