"""The packet intake and the period clock shared by the causal estimators of :mod:`eqrec.estimators.causal`.

:class:`_StampedEstimator` keeps the observed arrivals of the current period,
a reference state per period time and the residuals of the packets received;
a step is opened aside (:class:`_Opened`, every input checked, nothing
changed), the estimator computes its estimate from it, and only then is it
committed, so a step that raises leaves the estimator as it was.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.arrivals.packets import Stamped, _is_stamp, as_packets, check_estimate, check_input
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


@dataclass
class _Opened:
    """The state of a step under way, not yet committed (module docstring of :class:`_StampedEstimator`)."""

    k: int  # absolute time of the step
    t: int  # its period time
    start: int  # absolute time of the period's start
    arrivals: list  # per period time: arrival time (period time) or None
    history: list  # reference states at the period times 0..t
    yxi: dict  # period time -> residual
    restarted: bool  # a new period starts at this step
    u: np.ndarray  # the checked input
    dropped: int = 0  # packets stamped before the period: not used (counted in dropped_packets)


class _StampedEstimator:
    """Packet intake shared by :class:`RecoveryEstimator` and :class:`ClassEstimator`.

    Keeps the period clock, the observed arrivals of the current period, a
    *reference* state per period time (the state whose predicted output a
    measurement is compared with) and the residuals
    ``y(τ) − C(τ) ref(τ)`` of the packets received in the period.

    A step is all-or-nothing: :meth:`_open` checks everything and builds the
    new state aside (:class:`_Opened`), the subclass computes the estimate
    from it, and only then :meth:`_commit` installs it; a step that raises
    leaves the estimator exactly as it was.

    Time convention: the model's time-varying matrices are read at the
    *period time* ``t = k − period_start`` (the time of the design, whose
    time 0 is the period's start), so a time-varying model describes one
    period of a ``T``-periodic plant, as the design assumes.

    A packet stamped before the current period (or before ``t0``) is not
    refused, with ``strict=True`` as with ``strict=False``: its period's
    gains are no longer in use, and the language counts it as missing there
    (a delay past the period's end means missing), so dropping it keeps the
    guarantee.  It is counted in :attr:`dropped_packets` (since the start,
    as :attr:`eqrec.estimators.zonotope.ZonotopeEstimator.dropped_packets`).
    """

    T: int

    def __init__(self, system: AffineSystem, horizon: int, xhat0: np.ndarray, periodic: bool, t0: int):
        if not _is_stamp(t0):
            raise InputError(f"the start time must be an integer, got {t0!r}", field="t0")
        self.system = system
        self.T = int(horizon)
        self.periodic = bool(periodic)
        system.check_horizon(self.T)
        self.xhat = check_estimate(xhat0, system.n)
        self._t = 0  # time since the start of the current period
        self._k = int(t0)  # absolute time
        self._start = int(t0)  # absolute time of the current period's start
        self._arrivals: list[int | None] = []  # per period time τ: arrival time (period time) or None
        self._history: list[np.ndarray] = []  # reference state at the period times 0..t
        self._yxi: dict[int, np.ndarray] = {}  # period time τ -> y(τ) - C ref(τ)
        self.dropped_packets = 0  # packets stamped before their step's period: not used (class docstring)

    @property
    def observed_prefix(self) -> ArrivalPattern:
        """The arrival prefix observed so far in the current period (events ``0..t-1``)."""
        return ArrivalPattern(tuple(self._arrivals))

    @property
    def time(self) -> int:
        """The absolute time of the next step (the estimate ``x̂`` is of this time)."""
        return self._k

    @property
    def period_time(self) -> int:
        """Steps taken in the current period (``0..T``; ``T`` once the period is over)."""
        return self._t

    @property
    def period_start(self) -> int:
        """Absolute time of the current period's first step."""
        return self._start

    def _packets(self, y) -> list[Stamped]:
        return as_packets(y, self._k, self.system.p)

    def _reference(self, restarted: bool) -> np.ndarray:
        """The state of the current time whose predicted output the measurements of this time are compared with."""
        raise NotImplementedError

    def _open(self, y, u, restart_at_now: bool = False) -> _Opened:
        """Check what arrived at the current time and ``u``, and build the step's state aside (nothing changes).

        Raises :class:`InputError` when the horizon is over (not periodic),
        for malformed packets (:func:`as_packets`), a packet whose stamp
        was already received in this period, or a malformed input.  Packets
        stamped before the current period are dropped and counted in
        :attr:`dropped_packets` when the step commits.
        """
        sys = self.system
        packets = self._packets(y)
        u = check_input(u, sys.m)
        restarted = restart_at_now or self._t == self.T
        if self._t == self.T and not self.periodic and not restart_at_now:
            raise InputError(f"the estimator's horizon T = {self.T} is over (use periodic=True to restart)")
        k = self._k
        if restarted:
            t, start, arrivals, history, yxi = 0, k, [], [], {}
        else:
            t, start = self._t, self._start
            arrivals, history, yxi = list(self._arrivals), list(self._history), dict(self._yxi)
        history.append(self._reference(restarted).copy())
        arrivals.append(None)
        dropped = 0
        for pk in packets:
            tau = pk.time - start
            if tau < 0:
                dropped += 1  # stamped before this period: its gains are no longer in use (counted, not used)
                continue
            if arrivals[tau] is not None:
                raise InputError(f"a second packet stamped {pk.time} received at time {k}", field="y")
            arrivals[tau] = t
            yxi[tau] = pk.y - sys.C_at(tau) @ history[tau]
        return _Opened(k, t, start, arrivals, history, yxi, restarted, u, dropped)

    def _commit(self, step: _Opened) -> None:
        """Install the state of a step that succeeded."""
        self._t, self._start, self._k = step.t + 1, step.start, step.k + 1
        self._arrivals, self._history, self._yxi = step.arrivals, step.history, step.yxi
        self.dropped_packets += step.dropped
