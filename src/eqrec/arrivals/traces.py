r"""The arrival trace: when each measurement of a run reaches the estimator (delay, or :data:`NEVER`).

The type of the one arrival model (:mod:`eqrec.arrivals.draws` draws them): per
measurement ``y(τ)`` its delay ``d(τ)`` (arrival at ``τ + d(τ)``) or
:data:`NEVER` when it is lost; read per step, the time stamps arriving at
``t``.  Re-exported by :mod:`eqrec.arrivals.draws`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence

import numpy as np

from eqrec.checks import integer
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_pattern
from eqrec.errors import InputError

#: Delay code of a measurement that is never delivered.
NEVER = -1
#: Largest delay a trace stores (steps): arrival times ``τ + d`` stay 64-bit integers for any run shorter than it.
MAX_TRACE_DELAY = 2 ** 62


@dataclass(frozen=True, eq=False)
class ArrivalTrace:
    """When each measurement of a run of ``N`` steps reaches the estimator (module docstring).

    Parameters
    ----------
    delays : array_like of int, shape (N,)
        ``delays[τ]``: the delay of ``y(τ)`` (it arrives at ``τ + delays[τ]``),
        or :data:`NEVER` (``-1``) when it is lost.  Stored as a read-only
        integer array.

    Raises
    ------
    InputError
        Not a one-dimensional array of integers ``>= 0`` or ``NEVER`` (field ``delays``), or a delay above
        :data:`MAX_TRACE_DELAY` (its arrival time would overflow; a packet that never arrives is ``NEVER``).

    Examples
    --------
    >>> from eqrec.arrivals.draws import NEVER, ArrivalTrace
    >>> trace = ArrivalTrace([0, 2, NEVER, 0])
    >>> [trace.arriving_at(t) for t in range(trace.steps)]
    [[0], [], [], [1, 3]]
    >>> ArrivalTrace.from_pattern("1011").delays.tolist()
    [0, -1, 0, 0]
    """

    delays: np.ndarray

    def __post_init__(self) -> None:
        raw = np.asarray(self.delays)
        integral = raw.dtype.kind in "iu" or (raw.dtype.kind == "f" and np.all(raw == np.round(raw)))
        if raw.ndim != 1 or (raw.size and not integral):
            raise InputError(f"delays must be a one-dimensional array of integers, got {raw.dtype} of shape "
                             f"{raw.shape}", field="delays")
        if raw.size and np.any(raw > MAX_TRACE_DELAY):  # before the cast: τ + d must stay a 64-bit integer
            raise InputError(f"a delay is at most {MAX_TRACE_DELAY} steps (2**62), got {raw.max().item()!r}; a "
                             f"packet that never arrives has the delay NEVER = {NEVER}", field="delays")
        if raw.size and np.any((raw < 0) & (raw != NEVER)):  # before the cast, which wraps a huge negative float
            bad = sorted(set(raw[(raw < 0) & (raw != NEVER)].tolist()))
            raise InputError(f"a delay is >= 0 or NEVER = {NEVER}, got {bad[:5]}", field="delays")
        d = np.array(raw, dtype=np.int64)
        d.flags.writeable = False
        object.__setattr__(self, "delays", d)

    # -- construction -------------------------------------------------------
    @classmethod
    def from_pattern(cls, pattern: "ArrivalPattern | str") -> "ArrivalTrace":
        """The trace of an arrival pattern (or a 0/1 missing-data word) of horizon ``T``.

        Parameters
        ----------
        pattern : ArrivalPattern or str
            The pattern; a measurement it never delivers within the horizon is lost.

        Returns
        -------
        ArrivalTrace
            ``T`` steps.
        """
        pat = as_pattern(pattern)
        return cls(np.array([NEVER if a is None else a - tau for tau, a in enumerate(pat.arrivals)], np.int64))

    @classmethod
    def from_arrived(cls, arrived: "np.ndarray | Sequence[bool]") -> "ArrivalTrace":
        """Each measurement on time (``True``) or lost (``False``).

        Parameters
        ----------
        arrived : array_like of bool, shape (N,)
            Whether ``y(t)`` arrives (at ``t``): ``True``/``False`` or ``1``/``0`` (anything else is refused).

        Returns
        -------
        ArrivalTrace
            Delays ``0`` or :data:`NEVER`.
        """
        a = np.asarray(arrived)
        if a.ndim != 1 or not np.isin(a, (0, 1)).all():  # a fraction, NaN or a string is not an arrival
            raise InputError(f"arrived must be a vector of 0/1 (or bool), got {arrived!r:.60}", field="arrived")
        return cls(np.where(a.astype(bool), 0, NEVER).astype(np.int64))

    @classmethod
    def from_schedule(cls, arrive: Sequence[Sequence[int]]) -> "ArrivalTrace":
        """The trace of ``arrive[t]`` lists (the stamps arriving at each step ``t < N``).

        Parameters
        ----------
        arrive : sequence of sequence of int
            ``arrive[t]``: the measurement times ``τ <= t`` whose packets arrive at ``t``;
            a stamp in no list is lost.

        Returns
        -------
        ArrivalTrace
            ``N = len(arrive)`` steps.

        Raises
        ------
        InputError
            Not a sequence of sequences, a stamp that is not an integer, outside ``0..t`` or listed twice
            (field ``arrive``).
        """
        try:
            arrive = [list(stamps) for stamps in arrive]
        except TypeError:
            raise InputError(f"arrive[t] lists the stamps arriving at step t, got {arrive!r:.60}", field="arrive") \
                from None
        N = len(arrive)
        d = np.full(N, NEVER, np.int64)
        for t, stamps in enumerate(arrive):
            for tau in stamps:
                tau = integer(tau, "arrive")
                if not 0 <= tau <= t:
                    raise InputError(f"stamp {tau} arrives at {t}: a stamp lies in 0..t", field="arrive")
                if d[tau] != NEVER:
                    raise InputError(f"stamp {tau} arrives twice", field="arrive")
                d[tau] = t - tau
        return cls(d)

    # -- reading ----------------------------------------------------------------
    @property
    def steps(self) -> int:
        """Number ``N`` of steps (measurements) of the run."""
        return int(self.delays.size)

    def arrival_times(self) -> np.ndarray:
        """Arrival time ``τ + d(τ)`` of each measurement (:data:`NEVER` when lost).

        Returns
        -------
        ndarray of int, shape (N,)
            Arrival times, possibly ``>= N`` (after the run).
        """
        tau = np.arange(self.steps)
        return np.where(self.delays == NEVER, NEVER, tau + self.delays)

    def arriving_at(self, t: int) -> list[int]:
        """The stamps whose packets arrive at step ``t``, increasing.

        Parameters
        ----------
        t : int
            Step, ``0 <= t < N``.

        Returns
        -------
        list of int
            ``{τ : τ + d(τ) = t}``.
        """
        return [int(tau) for tau in np.flatnonzero(self.arrival_times() == t)]

    def schedule(self) -> list[list[int]]:
        """``out[t]``: the stamps arriving at ``t``, for every ``t < N`` (arrivals at or after ``N`` left out).

        Returns
        -------
        list of list of int
            Length ``N``; each list increasing.
        """
        N = self.steps
        out: list[list[int]] = [[] for _ in range(N)]
        for tau, d in enumerate(self.delays.tolist()):
            if d != NEVER and tau + d < N:
                out[tau + d].append(tau)
        return out

    @property
    def lost(self) -> np.ndarray:
        """``True`` for a measurement that is never delivered (bool, shape ``(N,)``)."""
        return self.delays == NEVER

    @property
    def on_time(self) -> np.ndarray:
        """``True`` for a measurement that arrives at its own time (bool, shape ``(N,)``)."""
        return self.delays == 0

    def pattern(self) -> ArrivalPattern:
        """The trace as an arrival pattern of horizon ``N`` (a packet arriving at or after ``N`` is missing).

        Returns
        -------
        ArrivalPattern
            ``arrivals[τ] = τ + d(τ)`` when it is ``< N``, else ``None``.
        """
        N = self.steps
        return ArrivalPattern(tuple(None if (d == NEVER or tau + d >= N) else tau + d
                                    for tau, d in enumerate(self.delays.tolist())))
