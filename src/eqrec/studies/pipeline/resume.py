"""After a hard kill of the workflow: is the lock it left stale, and which one command resumes.

A ``kill -9`` of Snakemake (or a lost session) leaves its lock in
``.snakemake/locks/``, and the next run of the same command stops with
``LockException``.  The Snakefile installs :class:`LockAdvice` on Snakemake's
logger (:func:`explain_lock_errors`): it follows that error with
:func:`lock_advice`, which says whether a Snakemake process still runs in the
directory on this machine and, when none does, that the lock is stale and the
one command that resumes: ``snakemake --unlock && <the same command>``.
(The other leftovers of a kill: the temporary files of killed writes, removed by
:func:`eqrec.io.remove_stale_temporaries` when the job runs again; the sweeps'
temp() chunks, kept under ``intermediate/``, not ``results/``.)
"""

from __future__ import annotations

import logging
import os
import shlex
import socket
import sys
from pathlib import Path
from typing import Sequence

#: Where Snakemake's file backend keeps its locks, relative to the working directory.
LOCK_DIR = Path(".snakemake") / "locks"

#: Options of the command line that say where the workflow is: ``snakemake --unlock`` needs them too.
_LOCATION_OPTIONS = ("-d", "--directory", "-s", "--snakefile")


def _ancestors() -> set[int]:
    """This process and its ancestors (a wrapper such as ``timeout snakemake ...`` is not another run)."""
    pids, pid = {os.getpid()}, os.getppid()
    while pid > 1 and pid not in pids:
        pids.add(pid)
        try:  # the field after the state in /proc/<pid>/stat: the parent's id
            pid = int(Path(f"/proc/{pid}/stat").read_text().rpartition(")")[2].split()[1])
        except OSError:
            break
    return pids


def snakemake_processes(workdir: str | os.PathLike, proc: str | os.PathLike = "/proc") -> list[int] | None:
    """Processes on this machine, other than this one and its ancestors, that run Snakemake in ``workdir``.

    A process counts when its command line holds ``snakemake`` (the ``snakemake`` command, ``python -m
    snakemake``, a job's script run from ``.snakemake/scripts/``) and its working directory is ``workdir`` or
    a folder in it, or cannot be read (another user's: it cannot be ruled out).  A killed process not yet
    reaped (a zombie) has an empty command line and does not count.

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
    target, skip, found = os.path.realpath(workdir), _ancestors(), []
    for entry in table.iterdir():
        if not entry.name.isdigit() or int(entry.name) in skip:
            continue
        try:
            if b"snakemake" not in (entry / "cmdline").read_bytes():
                continue
            cwd = os.readlink(entry / "cwd")
        except PermissionError:
            cwd = target
        except OSError:  # gone meanwhile
            continue
        if cwd == target or cwd.startswith(target.rstrip(os.sep) + os.sep):
            found.append(int(entry.name))
    return sorted(found)


def resume_command(argv: Sequence[str] | None) -> str:
    """The one shell command that removes a stale lock and runs the interrupted command again.

    Parameters
    ----------
    argv : sequence of str or None
        The interrupted command's arguments after the program name (``sys.argv[1:]`` of ``snakemake``);
        ``None`` when unknown.

    Returns
    -------
    str
        ``snakemake --unlock && snakemake <argv>``, the unlock with the ``--directory`` and ``--snakefile``
        options of ``argv``.

    Examples
    --------
    >>> resume_command(["--cores", "2", "--forceall"])
    'snakemake --unlock && snakemake --cores 2 --forceall'
    >>> resume_command(["-d", "my run", "p1"])
    "snakemake -d 'my run' --unlock && snakemake -d 'my run' p1"
    """
    if argv is None:
        return "snakemake --unlock && <the same snakemake command as before>"
    location = [arg for k, arg in enumerate(argv)
                if arg.split("=")[0] in _LOCATION_OPTIONS or (k > 0 and argv[k - 1] in _LOCATION_OPTIONS)]
    return f"{shlex.join(['snakemake', *location, '--unlock'])} && {shlex.join(['snakemake', *argv])}"


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
        With no other Snakemake process in ``workdir`` on this machine: the lock is stale, and the command
        that resumes.  With one: its process ids, and to wait for it.  ``None`` without a lock file (another
        persistence backend) or a process table to tell.
    """
    pids = snakemake_processes(workdir)
    if pids is None or not any((Path(workdir) / LOCK_DIR).glob("*.lock")):
        return None
    where = os.path.realpath(workdir)
    if pids:
        return (f"The lock is held: a Snakemake process still runs in {where} (process "
                f"{', '.join(map(str, pids))}). Wait for it to end; do not unlock a directory a run is using.")
    return (f"The lock is stale: no Snakemake process runs in {where} on this machine ({socket.gethostname()}); "
            "an interrupted run (a kill, a lost session) left it. If no run on another machine uses this "
            f"directory, resume with\n    {resume_command(argv)}\n"
            "(--unlock only removes the lock; the run then re-does the jobs the interruption cut short).")


def cli_arguments() -> list[str] | None:
    """The arguments of this process's ``snakemake`` command line, if it is one.

    Returns
    -------
    list of str or None
        ``sys.argv[1:]`` when this process is the ``snakemake`` command (``python -m snakemake`` too);
        ``None`` otherwise (a program using Snakemake's API).
    """
    program = Path(sys.argv[0] if sys.argv else "")
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
        self.workdir, self.argv, self.done = workdir, argv, False

    def emit(self, record: logging.LogRecord) -> None:
        """Print the advice after the first record of a lock error.

        Parameters
        ----------
        record : logging.LogRecord
            A record of Snakemake's logger: its ``LockException``, or a dry run's line that the directory is
            locked.
        """
        if self.done or not (getattr(record, "exception", None) == "LockException"
                             or "Directory cannot be locked" in str(record.msg)):
            return
        self.done = True
        try:
            advice = lock_advice(self.workdir, self.argv)
        except Exception:  # advice must never become an error of its own
            return
        if advice:
            print(advice, file=sys.stderr, flush=True)


def explain_lock_errors(logger: logging.Logger, workdir: str | os.PathLike,
                        argv: Sequence[str] | None) -> LockAdvice:
    """Install :class:`LockAdvice` on Snakemake's logger, once.

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
        The handler installed (or the one already there).
    """
    handler = next((h for h in logger.handlers if isinstance(h, LockAdvice)), None)
    if handler is None:
        handler = LockAdvice(workdir, argv)
        logger.addHandler(handler)
    return handler
