r"""The causal equalized-recovery estimator running on a stream of time-stamped packets.

Eqs. (5)-(7) of the prefix-based paper, with delayed packets as in the
delayed-data paper:

.. math::
    \hat x(t+1) = A\hat x(t) + Bu(t) - u_e(t) + f, \qquad
    u_e(t) = u_0(t, P_t) + \sum_{\tau \in \mathcal A(t)} F(t, \tau, P_t)\, y_\xi(\tau),

where :math:`\mathcal A(t)` is the set of measurement times whose packets
have arrived by ``t``, :math:`P_t` the observed arrival prefix (the events
``0..t``), and :math:`y_\xi(\tau) = y(\tau) - C(\tau)\hat x(\tau)` is formed
with the estimate of the packet's *own* time: the estimator keeps its history
``x̂(0..t)`` so that a late ``y(τ)`` enters as ``y(τ) − C x̂(τ)``.  The gains
are looked up by ``P_t`` (prefix-based) or by ``t`` alone (time-based).

With ``periodic=True`` the estimator restarts its horizon every ``T`` steps
(Section V of the prefix-based paper, Section III-D of the augmented paper):
the error is back below ``M1`` at the end of each period, so the same gains
apply again.  A packet stamped before the current period is dropped.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from eqrec.core.gains import GainSchedule
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.systems import AffineSystem
from eqrec.errors import InputError


@dataclass(frozen=True)
class Packet:
    """A measurement ``y`` of time ``time`` (its time stamp)."""

    time: int
    y: np.ndarray


class RecoveryEstimator:
    """Causal estimator of eqs. (5)-(7) on time-stamped packets.

    Parameters
    ----------
    system
        The model (``A, B, C, f``) used by the estimator.
    schedule
        Prefix-based or time-based gains.
    xhat0
        Initial estimate ``x̂(0)``.
    periodic
        Restart the horizon every ``T`` steps instead of stopping.
    """

    def __init__(self, system: AffineSystem, schedule: GainSchedule, xhat0: np.ndarray, periodic: bool = False):
        self.system = system
        self.schedule = schedule
        self.T = schedule.horizon
        self.periodic = periodic
        self.xhat = np.asarray(xhat0, float).reshape(system.n).copy()
        self._t = 0  # time since the start of the current period
        self._k = 0  # absolute time (for time-varying models)
        self._start = 0  # absolute time of the current period's start
        self._arrivals: list[int | None] = []  # per period time τ: arrival time (period time) or None
        self._history: list[np.ndarray] = []  # x̂ at the period times 0..t
        self._yxi: dict[int, np.ndarray] = {}  # period time τ -> y(τ) - C x̂(τ)

    @property
    def observed_prefix(self) -> ArrivalPattern:
        """The arrival prefix observed so far in the current period (events ``0..t-1``)."""
        return ArrivalPattern(tuple(self._arrivals))

    def _packets(self, y) -> list[Packet]:
        if y is None:
            return []
        if isinstance(y, Packet):
            return [y]
        if isinstance(y, np.ndarray) or (isinstance(y, (list, tuple)) and y and not isinstance(y[0], Packet)):
            return [Packet(self._k, np.asarray(y, float))]
        return list(y)

    def step(self, y: "np.ndarray | Packet | Iterable[Packet] | None", u: np.ndarray | None = None) -> np.ndarray:
        """Process time ``t``: the packets arriving at ``t`` and the input ``u(t)``.

        ``y`` is ``None`` (nothing arrives), an array (``y(t)`` arriving on
        time) or :class:`Packet` objects stamped with their own (absolute)
        times ``τ <= t``.  Returns the prediction ``x̂(t+1)``.
        """
        sys = self.system
        if self._t == self.T:
            if not self.periodic:
                raise InputError(f"the estimator's horizon T = {self.T} is over (use periodic=True to restart)")
            self._t, self._start, self._arrivals, self._history, self._yxi = 0, self._k, [], [], {}
        k, t = self._k, self._t
        self._history.append(self.xhat.copy())
        self._arrivals.append(None)
        for pk in self._packets(y):
            tau_abs = int(pk.time)
            if tau_abs > k:
                raise InputError(f"packet stamped {tau_abs} received at time {k}: a packet cannot come from the future")
            tau = tau_abs - self._start
            if tau < 0:
                continue  # stamped before this period: its gains are no longer in use
            if self._arrivals[tau] is not None:
                raise InputError(f"a second packet stamped {tau_abs} received at time {k}")
            yv = np.asarray(pk.y, float).reshape(-1)
            if yv.shape != (sys.p,):
                raise InputError(f"measurement of time {tau_abs} has {yv.size} entries, expected p = {sys.p}")
            self._arrivals[tau] = t
            self._yxi[tau] = yv - sys.C_at(tau_abs) @ self._history[tau]
        gain = self.schedule.row(self.observed_prefix)
        yxi = np.zeros((t + 1, sys.p))
        for tau, v in self._yxi.items():
            yxi[tau] = v
        ue = gain.u0 + gain.F @ yxi.reshape(-1)
        u = np.zeros(sys.m) if u is None else np.asarray(u, float).reshape(-1)
        self.xhat = sys.A_at(k) @ self.xhat + sys.B_at(k) @ u - ue + sys.f
        self._t += 1
        self._k += 1
        return self.xhat.copy()
