"""The switching implementation strategy of the delayed-data paper (Section III-B3).

Equalized performance (a period-1 design) runs while measurements arrive on
time; when one is late or missing, an equalized-recovery estimator takes over
for ``T`` steps, then performance resumes.  Built on the estimators of
:mod:`eqrec.estimators.causal`.
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from eqrec.bounds.data_classes import ClassGains
from eqrec.estimators.causal import Packet, _has_class, make_estimator
from eqrec.bounds.gains import GainSchedule
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


class SwitchingEstimator:
    r"""Equalized performance until a measurement is late or missing, then equalized recovery for ``T`` steps.

    The implementation strategy of Section III-B3 of the delayed-data paper.

    * *Performance mode*: the equalized-performance estimator, i.e. an
      equalized-recovery design of period 1 on the one-letter language
      "``y(t)`` arrives on time": ``‖ξ(t)‖ <= μ1`` implies ``‖ξ(t+1)‖ <= μ1``.
      It runs as a :class:`~eqrec.estimators.causal.RecoveryEstimator` (node gains) or a
      :class:`~eqrec.estimators.causal.ClassEstimator` (class gains) with ``periodic=True`` and
      ``T = 1`` (packets stamped before the current step are dropped).
    * At a time ``k`` at which ``y(k)`` has not arrived (late or missing), the
      estimator switches: an estimator on the ``recovery`` gains
      (:func:`make_estimator`) starts at ``k`` from the current estimate (``‖ξ(k)‖ <= μ1``).
      Its language has words whose first measurement is delayed or missing,
      so its first event, "``y(0)`` not (yet) arrived", is what was observed.
    * After ``T`` steps (``‖ξ(k+T)‖ <= μ1``) it reverts to performance mode;
      if ``y(k+T)`` is late too it switches again at once.

    Packets stamped before the current phase (a recovery phase's
    measurements that arrive after it ended) are dropped, as in the
    language where a delay past the horizon means missing.

    Parameters
    ----------
    system : AffineSystem
        The model used by both estimators.
    performance : GainSchedule or ClassGains
        Gains of the period-1 design: a schedule of horizon 1 with the row of
        the on-time prefix, or class gains of horizon 1 with the on-time
        class ``(1, (0,))``.
    recovery : GainSchedule or ClassGains
        Gains of the recovery design (horizon ``T``, ``.horizon``) on a
        language whose words all have their first measurement late or
        missing: a schedule, or class gains without the class ``(1, (0,))``.
    xhat0 : ndarray, shape (n,)
        Initial estimate (``‖ξ(t0)‖ <= μ1`` for the guarantees to hold).
    t0 : int, optional
        Absolute time of the first step (default 0).

    Attributes
    ----------
    mode
        ``"performance"`` or ``"recovery"`` (the mode of the last step).
    switch_times, revert_times
        Absolute times at which recovery phases started, and at which
        performance mode resumed.
    """

    def __init__(self, system: AffineSystem, performance: "GainSchedule | ClassGains",
                 recovery: "GainSchedule | ClassGains", xhat0: np.ndarray, t0: int = 0):
        for name, g in (("performance", performance), ("recovery", recovery)):
            if not isinstance(g, (GainSchedule, ClassGains)):
                raise TypeError(f"the {name} gains must be a GainSchedule or ClassGains, got {type(g).__name__}")
        on_time = ArrivalPattern((0,))
        perf_msg = (f"the equalized-performance gains must have horizon 1 (got {performance.horizon}) "
                    "and be designed for an on-time measurement")
        if isinstance(performance, GainSchedule):
            if performance.horizon != 1 or performance.time_based and performance.designed[0] != on_time:
                raise InputError(perf_msg)
            performance.row(on_time)  # raises if there is no on-time row
        elif performance.horizon != 1 or not _has_class(performance, 1, (0,)):
            raise InputError(perf_msg + " (the class (1, (0,)))")
        if isinstance(recovery, GainSchedule):
            bad = [p.label for p in recovery.designed if p.arrivals[0] == 0]
            if bad:
                raise InputError(f"the recovery language must have its first measurement late or missing; "
                                 f"words {bad[:5]} have it on time")
        elif _has_class(recovery, 1, (0,)):
            raise InputError("the recovery language must have its first measurement late or missing; its "
                             "classes include (1, (0,)): y(0) on time")
        self.system = system
        self.performance = performance
        self.recovery = recovery
        self.T = recovery.horizon
        self.mode = "performance"
        self.switch_times: list[int] = []
        self.revert_times: list[int] = []
        self._est = make_estimator(system, performance, xhat0, periodic=True, t0=t0)

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

        Parameters
        ----------
        y : ndarray, Packet, iterable of Packet, or None
            ``None`` (nothing arrives), an array (``y(k)`` on time) or packets
            stamped with their absolute times ``τ <= k``.
        u : ndarray, shape (m,), or None, optional
            The input ``u(k)`` (``None``: zero).

        Returns
        -------
        ndarray, shape (n,)
            The prediction ``x̂(k+1)``.
        """
        est, mode = self._est, self.mode
        k = est.time
        packets = est._packets(y)  # checked before anything changes
        switched, reverted = False, False
        if mode == "recovery" and est.period_time == self.T:
            mode, reverted = "performance", True
            est = make_estimator(self.system, self.performance, est.xhat, periodic=True, t0=k)
        if mode == "performance" and not any(int(pk.time) == k for pk in packets):
            mode, switched = "recovery", True
            est = make_estimator(self.system, self.recovery, est.xhat, periodic=False, t0=k)
        xhat = est.step(packets, u)  # all-or-nothing; a new estimator is dropped if it raises
        self._est, self.mode = est, mode
        if reverted:
            self.revert_times.append(k)
        if switched:
            self.switch_times.append(k)
        return xhat
