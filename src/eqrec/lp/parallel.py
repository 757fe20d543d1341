"""Independent tasks on every core, or on a Dask cluster, through joblib; results in task order.

The class engine (:mod:`eqrec.design.classes.blocks`) cuts a design into independent LPs, one per
(time, available data) class, and hands them out in batches.  This module runs the batches:

* ``n_jobs`` (:func:`check_jobs`): worker processes on this machine (joblib's ``loky`` backend);
  ``None`` or ``-1`` means every core, ``1`` runs in this process without a pool;
* ``scheduler`` (:func:`check_scheduler`): a Dask scheduler address (``"tcp://host:8786"``) or a
  ``dask.distributed.Client``: the same tasks go through joblib's Dask backend to the cluster's
  workers (``n_jobs`` is then ignored: the cluster decides).

Every task is a pure function of its arguments and the results come back in task order, so what a
caller computes from them does not depend on the number of workers, the batching or the backend.
:class:`Progress` prints ``done / total`` on stderr while the tasks run, only when stderr is a
terminal.
"""

from __future__ import annotations

import contextlib
import os
import sys
import time
from typing import Callable, Iterator, Sequence

from eqrec.errors import InputError

#: URL schemes of a Dask scheduler address.
SCHEDULER_SCHEMES = ("tcp://", "tls://", "inproc://", "ucx://", "ws://", "wss://")
#: Seconds to wait for a Dask scheduler to answer.
CONNECT_TIMEOUT = 30.0


def check_jobs(n_jobs) -> int:
    """The number of worker processes: ``n_jobs``, or every core for ``None`` and ``-1``.

    Parameters
    ----------
    n_jobs : int or None
        A positive number of workers, ``-1`` or ``None`` (every core of the machine).

    Returns
    -------
    int
        At least 1.

    Raises
    ------
    InputError
        For anything else (field ``n_jobs``).
    """
    if n_jobs is None or (isinstance(n_jobs, int) and not isinstance(n_jobs, bool) and n_jobs == -1):
        return max(1, cpu_count())
    if isinstance(n_jobs, bool) or not isinstance(n_jobs, int) or n_jobs < 1:
        raise InputError(f"must be a positive number of worker processes, -1 or None (every core), got {n_jobs!r}",
                         field="n_jobs")
    return int(n_jobs)


def cpu_count() -> int:
    """Cores this process may use (its CPU affinity, else the machine's count).

    Returns
    -------
    int
    """
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def check_scheduler(scheduler):
    """``None``, a Dask scheduler address (``tcp://host:port``) or a ``dask.distributed.Client``.

    Parameters
    ----------
    scheduler : str, distributed.Client or None

    Returns
    -------
    str, distributed.Client or None
        The address stripped, or the client itself.

    Raises
    ------
    InputError
        For another type, an address without a scheme of :data:`SCHEDULER_SCHEMES` (field ``scheduler``), or
        when ``dask.distributed`` is not installed (``pip install "eqrec[dask]"``).
    """
    if scheduler is None:
        return None
    if isinstance(scheduler, str):
        address = scheduler.strip()
        if not address.startswith(SCHEDULER_SCHEMES) or len(address) <= address.index("://") + 3:
            raise InputError(f"must be a Dask scheduler address such as tcp://host:8786, got {scheduler!r}",
                             field="scheduler")
        _distributed()
        return address
    distributed = _distributed()
    if isinstance(scheduler, distributed.Client):
        return scheduler
    raise InputError(f"must be a Dask scheduler address (str) or a dask.distributed.Client, got "
                     f"{type(scheduler).__name__}", field="scheduler")


def _distributed():
    try:
        import distributed
    except ImportError:
        raise InputError("a Dask scheduler needs dask.distributed: pip install 'eqrec[dask]'",
                         field="scheduler") from None
    return distributed


def check_reachable(scheduler, timeout: float = 5.0) -> None:
    """Raise now if a ``tcp://`` scheduler address does not accept connections (a design may not need it later).

    A small language is solved in this process whatever ``scheduler`` says, so an address that is
    never contacted would go unnoticed; a caller that was given one (``eqrec design --scheduler``)
    checks it up front.  Only ``tcp://host:port`` is probed (a TCP connection, closed at once);
    other schemes and clients are left to Dask.

    Parameters
    ----------
    scheduler : str, distributed.Client or None
        As :func:`check_scheduler` (``None``: nothing to check).
    timeout : float, optional
        Seconds to wait for the connection.

    Raises
    ------
    InputError
        The address cannot be reached (field ``scheduler``).
    """
    if not isinstance(scheduler, str) or not scheduler.strip().startswith("tcp://"):
        return
    import socket

    address = scheduler.strip()
    host, _, port = address[len("tcp://"):].rpartition(":")
    try:
        with socket.create_connection((host.strip("[]"), int(port)), timeout=timeout):
            pass
    except (OSError, ValueError) as exc:
        raise InputError(f"cannot reach the Dask scheduler {address} ({exc})", field="scheduler") from None


@contextlib.contextmanager
def connected(scheduler) -> Iterator:
    """A ``dask.distributed.Client`` for ``scheduler`` while the block runs (``None`` stays ``None``).

    An address is connected here and closed on exit; a client is passed through (the caller owns it).

    Parameters
    ----------
    scheduler : str, distributed.Client or None
        As :func:`check_scheduler`.

    Yields
    ------
    distributed.Client or None
    """
    scheduler = check_scheduler(scheduler)
    if not isinstance(scheduler, str):
        yield scheduler
        return
    distributed = _distributed()
    try:
        client = distributed.Client(scheduler, set_as_default=False, timeout=CONNECT_TIMEOUT)
    except OSError as exc:
        raise InputError(f"cannot reach the Dask scheduler {scheduler} ({exc})", field="scheduler") from None
    try:
        yield client
    finally:
        client.close()


class Progress:
    """Progress of a long stage on stderr: a bar rewritten in place on a terminal, else one line at its start and
    one at its end.

    Parameters
    ----------
    total : int
        Units of work (e.g. classes).
    label : str
        What is counted.
    enabled : bool or None, optional
        ``None`` (default): a bar when ``sys.stderr`` is a terminal, the two lines otherwise; ``True``: the bar;
        ``False``: nothing.
    """

    WIDTH = 24  # characters of the bar

    def __init__(self, total: int, label: str, enabled: bool | None = None):
        self.total, self.label, self.done = int(total), label, 0
        self.enabled = _isatty(sys.stderr) if enabled is None else bool(enabled)
        self.lines = enabled is None and not self.enabled
        self._last = 0.0
        self._start = time.monotonic()
        if self.lines:
            sys.stderr.write(f"{self.label}: 0 / {self.total} ...\n")
            sys.stderr.flush()

    def advance(self, units: int) -> None:
        """Count ``units`` more done (the bar redrawn at most 10 times a second, and at the end).

        Parameters
        ----------
        units : int
        """
        self.done += int(units)
        now = time.monotonic()
        end = self.done >= self.total
        if self.lines and end:
            sys.stderr.write(f"{self.label}: {self.done} / {self.total} in {now - self._start:.1f} s\n")
            sys.stderr.flush()
        if self.enabled and (now - self._last > 0.1 or end):
            self._last = now
            frac = self.done / max(1, self.total)
            bar = "#" * int(frac * self.WIDTH)
            elapsed = now - self._start
            eta = f", {elapsed * (1 - frac) / frac:.0f} s left" if 0 < frac < 1 else ""
            sys.stderr.write(f"\r{self.label}: {self.done} / {self.total} [{bar:<{self.WIDTH}}] {frac:4.0%}"
                             f" ({elapsed:.0f} s{eta})")
            if end:
                sys.stderr.write("\n")
            sys.stderr.flush()


def _isatty(stream) -> bool:
    try:
        return bool(stream.isatty())
    except (AttributeError, ValueError):
        return False


#: Warm-up tasks of a pool started ahead (:func:`prestart`), consumed by :func:`settle`.
_WARMING: list = []
#: The local pool last seen running: its size and when (``time.monotonic()``).
_POOL = {"workers": 0, "seen": -1e9}
#: Seconds a pool is taken to be still running after its last use (joblib's loky pool stops after 300 s idle).
POOL_ALIVE_S = 200.0


def pool_ready(n_jobs=None) -> bool:
    """Whether a local pool of ``n_jobs`` workers ran recently (:data:`POOL_ALIVE_S`): tasks start at once there.

    Parameters
    ----------
    n_jobs : int or None, optional
        Worker processes (:func:`check_jobs`).

    Returns
    -------
    bool
    """
    workers = check_jobs(n_jobs)
    return workers > 1 and _POOL["workers"] == workers and time.monotonic() - _POOL["seen"] < POOL_ALIVE_S


def _pool_seen(workers: int) -> None:
    _POOL.update(workers=workers, seen=time.monotonic())


def prestart(fn: Callable, n_jobs=None) -> None:
    """Start the local worker processes now, in the background, each loading ``fn``'s module.

    The next :func:`run_tasks` on this machine finds them ready (joblib reuses its pool): a caller that has other
    work first (μ1 free: the Charnes–Cooper LPs) hides their start (0.3-1 s) behind it.  Call :func:`settle`
    when done, whatever happens.

    Parameters
    ----------
    fn : callable
        A module-level function (the task function to come).
    n_jobs : int or None, optional
        Worker processes (:func:`check_jobs`); nothing is started for one.
    """
    workers = check_jobs(n_jobs)
    if workers <= 1:
        return
    import joblib

    with joblib.parallel_config(backend="loky", n_jobs=workers):
        _WARMING.append(joblib.Parallel(n_jobs=workers, return_as="generator_unordered", batch_size=1,
                                        pre_dispatch="all")(joblib.delayed(_touch)(fn) for _ in range(workers)))


def settle() -> None:
    """Wait for the warm-up tasks of :func:`prestart` (if any) and drop them."""
    while _WARMING:
        workers = len([_ for _ in _WARMING.pop()])
        _pool_seen(workers)


def _touch(fn: Callable) -> int:
    return os.getpid()


def run_tasks(fn: Callable, tasks: Sequence[tuple], *, n_jobs=None, scheduler=None,
              progress: Progress | None = None, units: Sequence[int] | None = None) -> list:
    """``[fn(*task) for task in tasks]``, on worker processes or a Dask cluster, in task order.

    Parameters
    ----------
    fn : callable
        A module-level function (pickled to the workers).
    tasks : sequence of tuple
        The arguments of each call.
    n_jobs : int or None, optional
        Worker processes on this machine (:func:`check_jobs`; default every core).  One worker or one
        task: the calls run in this process.
    scheduler : str, distributed.Client or None, optional
        A Dask scheduler (:func:`check_scheduler`): the calls run on its workers through joblib's Dask
        backend.
    progress : Progress or None, optional
        Advanced by ``units[i]`` when task ``i`` is done.
    units : sequence of int, optional
        Work units of each task for ``progress`` (default 1 each).

    Returns
    -------
    list
        ``fn``'s results, in the order of ``tasks`` whatever the order they finished in.
    """
    workers = check_jobs(n_jobs)
    units = [1] * len(tasks) if units is None else list(units)
    if scheduler is None and (workers == 1 or len(tasks) <= 1):
        out = []
        for task, u in zip(tasks, units):
            out.append(fn(*task))
            if progress is not None:
                progress.advance(u)
        return out
    import joblib

    out: list = [None] * len(tasks)
    settle()
    with connected(scheduler) as client:
        config = (joblib.parallel_config(backend="dask", client=client) if client is not None
                  else joblib.parallel_config(backend="loky", n_jobs=workers))
        with config:  # loky: the pool of `workers` processes is joblib's reusable one (started ahead or not)
            par = joblib.Parallel(n_jobs=-1 if client is not None else workers,
                                  return_as="generator_unordered", batch_size=1, pre_dispatch="all")
            for i, result in par(joblib.delayed(_indexed)(fn, i, task) for i, task in enumerate(tasks)):
                out[i] = result
                if progress is not None:
                    progress.advance(units[i])
        if client is None:
            _pool_seen(workers)
    return out


def _indexed(fn: Callable, i: int, task: tuple) -> tuple:
    return i, fn(*task)
