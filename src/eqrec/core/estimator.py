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
apply again.  A packet stamped before the current period is dropped: its
gains are no longer in use, and the design language counts a delay that
reaches past the period's end as a missing measurement (Definition 1 of the
delayed-data paper), so dropping it is exactly what the guarantee assumes.

:class:`SwitchingEstimator` is the implementation strategy of Section III-B3
of the delayed-data paper: an equalized-performance estimator (equalized
recovery with period 1) while every measurement arrives on time, switching
to a recovery estimator for ``T`` steps when one is late or missing.
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
    t0
        Absolute time of the first step (the time stamp of the first
        measurement; ``0`` by default).  Packets stamped before ``t0`` are
        dropped like packets of an earlier period.
    """

    def __init__(self, system: AffineSystem, schedule: GainSchedule, xhat0: np.ndarray, periodic: bool = False,
                 t0: int = 0):
        self.system = system
        self.schedule = schedule
        self.T = schedule.horizon
        self.periodic = periodic
        self.xhat = np.asarray(xhat0, float).reshape(system.n).copy()
        self._t = 0  # time since the start of the current period
        self._k = int(t0)  # absolute time (for time-varying models)
        self._start = int(t0)  # absolute time of the current period's start
        self._arrivals: list[int | None] = []  # per period time τ: arrival time (period time) or None
        self._history: list[np.ndarray] = []  # x̂ at the period times 0..t
        self._yxi: dict[int, np.ndarray] = {}  # period time τ -> y(τ) - C x̂(τ)

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


class SwitchingEstimator:
    r"""Equalized performance until a measurement is late or missing, then equalized recovery for ``T`` steps.

    The implementation strategy of Section III-B3 of the delayed-data paper.

    * *Performance mode*: the equalized-performance estimator, i.e. an
      equalized-recovery design of period 1 on the one-letter language
      "``y(t)`` arrives on time": ``‖ξ(t)‖ <= μ1`` implies ``‖ξ(t+1)‖ <= μ1``.
      It runs as a :class:`RecoveryEstimator` with ``periodic=True`` and
      ``T = 1`` (packets stamped before the current step are dropped).
    * At a time ``k`` at which ``y(k)`` has not arrived (late or missing), the
      estimator switches: a :class:`RecoveryEstimator` on the ``recovery``
      gains starts at ``k`` from the current estimate (``‖ξ(k)‖ <= μ1``).
      Its language has words whose first measurement is delayed or missing,
      so its first event, "``y(0)`` not (yet) arrived", is what was observed.
    * After ``T`` steps (``‖ξ(k+T)‖ <= μ1``) it reverts to performance mode;
      if ``y(k+T)`` is late too it switches again at once.

    Packets stamped before the current phase (a recovery phase's
    measurements that arrive after it ended) are dropped, as in the
    language where a delay past the horizon means missing.

    Parameters
    ----------
    system
        The model used by both estimators.
    performance
        Gains of the period-1 design: a schedule of horizon 1 with the row of
        the on-time prefix.
    recovery
        Gains of the recovery design (horizon ``T``) on a language whose words
        all have their first measurement late or missing.
    xhat0
        Initial estimate (``‖ξ(t0)‖ <= μ1`` for the guarantees to hold).
    t0
        Absolute time of the first step.

    Attributes
    ----------
    mode
        ``"performance"`` or ``"recovery"`` (the mode of the last step).
    switch_times, revert_times
        Absolute times at which recovery phases started, and at which
        performance mode resumed.
    """

    def __init__(self, system: AffineSystem, performance: GainSchedule, recovery: GainSchedule,
                 xhat0: np.ndarray, t0: int = 0):
        on_time = ArrivalPattern((0,))
        if performance.horizon != 1 or performance.time_based and performance.designed[0] != on_time:
            raise InputError(f"the equalized-performance gains must have horizon 1 (got {performance.horizon}) "
                             "and be designed for an on-time measurement")
        performance.row(on_time)  # raises if there is no on-time row
        bad = [p.label for p in recovery.designed if p.arrivals[0] == 0]
        if bad:
            raise InputError(f"the recovery language must have its first measurement late or missing; "
                             f"words {bad[:5]} have it on time")
        self.system = system
        self.performance = performance
        self.recovery = recovery
        self.T = recovery.horizon
        self.mode = "performance"
        self.switch_times: list[int] = []
        self.revert_times: list[int] = []
        self._est = RecoveryEstimator(system, performance, xhat0, periodic=True, t0=t0)

    @property
    def xhat(self) -> np.ndarray:
        """The current estimate (of time :attr:`time`)."""
        return self._est.xhat

    @property
    def time(self) -> int:
        """Absolute time of the next step."""
        return self._est.time

    @property
    def period_start(self) -> int:
        """Absolute time at which the current phase (a performance step or a recovery phase) started."""
        return self._est.period_start

    @property
    def recovery_prefix(self) -> ArrivalPattern | None:
        """In recovery mode, the arrival prefix observed since the switch (events ``0..j``); else ``None``."""
        return self._est.observed_prefix if self.mode == "recovery" else None

    @property
    def recovery_step(self) -> int | None:
        """In recovery mode, the steps taken since the switch (``1..T``); else ``None``."""
        return self._est.period_time if self.mode == "recovery" else None

    def step(self, y: "np.ndarray | Packet | Iterable[Packet] | None", u: np.ndarray | None = None) -> np.ndarray:
        """Process time ``k``: the packets arriving at ``k`` (see :meth:`RecoveryEstimator.step`) and ``u(k)``.

        Returns the prediction ``x̂(k+1)``.
        """
        est = self._est
        k = est.time
        packets = est._packets(y)
        if self.mode == "recovery" and est.period_time == self.T:
            self.mode = "performance"
            self.revert_times.append(k)
            est = self._est = RecoveryEstimator(self.system, self.performance, est.xhat, periodic=True, t0=k)
        if self.mode == "performance" and not any(int(pk.time) == k for pk in packets):
            self.mode = "recovery"
            self.switch_times.append(k)
            est = self._est = RecoveryEstimator(self.system, self.recovery, est.xhat, periodic=False, t0=k)
        return est.step(packets, u)
