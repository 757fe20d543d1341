"""The switching implementation strategy of the delayed-data paper (Section III-B3).

Equalized performance (a period-1 design) runs while measurements arrive on
time; when one is late or missing, an equalized-recovery estimator takes over
for ``T`` steps, then performance resumes.  Built on the estimators of
:mod:`eqrec.estimators.causal`, and like them a protocol estimator
(:mod:`eqrec.estimators.protocol`): ``reset(xhat0, t0=0)``, then
``step(y, u) -> (x̂(t+1), bound)``, the bound being the designs' level when
the estimator is built with the levels (else ``inf``,
:mod:`eqrec.estimators.intake`), plus the rounding allowance of the running
estimator, carried across the switches (the new phase's estimator starts with
the allowance of the estimate it starts from).
"""

from __future__ import annotations

import math
from typing import Any, Iterable

import numpy as np

from eqrec.bounds.data_classes import ClassGains
from eqrec.bounds.rounding import rounding_allowance
from eqrec.estimators.causal import ClassEstimator, Packet, RecoveryEstimator, has_class, make_estimator
from eqrec.estimators.intake import BoundRule, check_levels
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
    xhat0 : ndarray, shape (n,), or None, optional
        Initial estimate (``‖ξ(t0)‖ <= μ1`` for the guarantees to hold); the
        estimator is reset at once.  ``None`` (default): call :meth:`reset` first.
    t0 : int, optional
        Absolute time of the first step (default 0).
    bound_of : callable or None, optional
        ``bound_of(prefix) -> level``: the recovery design's guarantee after an
        observed recovery prefix (with ``mu1``).
    mu1 : float or None, optional
        The common level of both designs: the bound in performance mode and at
        the end of each recovery phase.

    Attributes
    ----------
    kind : str
        ``"guaranteed"``: the second value of :meth:`step` is a bound.
    name : str
        ``"switching"``.
    bound : float
        The bound of the current estimate: ``μ1`` in performance mode and at the
        end of a recovery phase, the recovery level of the observed prefix in
        between; ``inf`` without the levels.
    mode
        ``"performance"`` or ``"recovery"`` (the mode of the last step).
    switch_times, revert_times
        Absolute times at which recovery phases started, and at which
        performance mode resumed (since :meth:`reset`).
    """

    kind = "guaranteed"
    name = "switching"

    def __init__(self, system: AffineSystem, performance: "GainSchedule | ClassGains",
                 recovery: "GainSchedule | ClassGains", xhat0: "np.ndarray | None" = None, t0: int = 0, *,
                 bound_of: "BoundRule | None" = None, mu1: "float | None" = None):
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
        elif performance.horizon != 1 or not has_class(performance, 1, (0,)):
            raise InputError(perf_msg + " (the class (1, (0,)))")
        if isinstance(recovery, GainSchedule):
            bad = [p.label for p in recovery.designed if p.arrivals[0] == 0]
            if bad:
                raise InputError(f"the recovery language must have its first measurement late or missing; "
                                 f"words {bad[:5]} have it on time")
        elif has_class(recovery, 1, (0,)):
            raise InputError("the recovery language must have its first measurement late or missing; its "
                             "classes include (1, (0,)): y(0) on time")
        self.system = system
        self.performance = performance
        self.recovery = recovery
        self.T = recovery.horizon
        self.bound_of, self.mu1 = check_levels(bound_of, mu1)
        self.mode = "performance"
        self.switch_times: list[int] = []
        self.revert_times: list[int] = []
        self.bound = math.nan
        self._dropped = 0  # packets dropped by the phases that ended
        self._est: "RecoveryEstimator | ClassEstimator" = make_estimator(system, performance, None, periodic=True,
                                                                          t0=t0)
        if xhat0 is not None:
            self.reset(xhat0, t0)

    def reset(self, xhat0: Any, t0: int = 0) -> "SwitchingEstimator":
        """Start a run in performance mode from ``x̂(t0) = xhat0``, discarding any run in progress.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            The initial estimate (``‖ξ(t0)‖ <= μ1`` for the guarantees to hold).
        t0 : int, optional
            Absolute time of the first step (default 0).

        Returns
        -------
        SwitchingEstimator
            ``self``.

        Raises
        ------
        InputError
            ``xhat0`` without ``n`` finite entries, ``t0`` not an integer (nothing changes).
        """
        est = make_estimator(self.system, self.performance, xhat0, periodic=True, t0=t0)  # checked first
        radius = self.mu1 if math.isfinite(self.mu1) else None
        est.carry_rounding(rounding_allowance(0.0, 1, np.abs(est.xhat) + (radius or 0.0)), radius)
        self._est, self.mode = est, "performance"
        self.switch_times, self.revert_times = [], []
        self._dropped = 0
        self.bound = self.mu1
        return self

    @property
    def xhat(self) -> np.ndarray:
        """The current estimate (of time :attr:`time`)."""
        return self._est.xhat

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate (of time :attr:`time`)."""
        return self._est.x

    @property
    def time(self) -> int:
        """Absolute time of the next step."""
        return self._est.time

    @property
    def period_start(self) -> int:
        """Absolute time at which the current phase (a performance step or a recovery phase) started."""
        return self._est.period_start

    @property
    def dropped_packets(self) -> int:
        """Packets stamped before their step's phase, not used (since :meth:`reset`)."""
        return self._dropped + self._est.dropped_packets

    @property
    def recovery_prefix(self) -> ArrivalPattern | None:
        """In recovery mode, the arrival prefix observed since the switch (events ``0..j``); else ``None``."""
        return self._est.observed_prefix if self.mode == "recovery" else None

    @property
    def recovery_step(self) -> int | None:
        """In recovery mode, the steps taken since the switch (``1..T``); else ``None``."""
        return self._est.period_time if self.mode == "recovery" else None

    def step(self, y: "np.ndarray | Packet | Iterable[Packet] | None" = None,
             u: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        """Process time ``k``: the packets arriving at ``k`` (see :meth:`RecoveryEstimator.step`) and ``u(k)``.

        Parameters
        ----------
        y : ndarray, Packet, iterable of Packet, or None, optional
            ``None`` (nothing arrives), an array (``y(k)`` on time) or packets
            stamped with their absolute times ``τ <= k``.
        u : ndarray, shape (m,), or None, optional
            The input ``u(k)`` (``None``: zero).

        Returns
        -------
        xhat : ndarray, shape (n,)
            The prediction ``x̂(k+1)``.
        bound : float
            Its bound (:attr:`bound`).

        Raises
        ------
        InputError
            Before :meth:`reset`, or what the running estimator refuses (nothing changes).
        """
        est, mode = self._est, self.mode
        est._running()  # before reset: refused
        k = est.time
        packets = est._packets(y)  # checked before anything changes
        switched, reverted = False, False
        if mode == "recovery" and est.period_time == self.T:
            mode, reverted = "performance", True
            est = make_estimator(self.system, self.performance, est.xhat, periodic=True, t0=k)
        if mode == "performance" and not any(int(pk.time) == k for pk in packets):
            mode, switched = "recovery", True
            est = make_estimator(self.system, self.recovery, est.xhat, periodic=False, t0=k)
        radius = self.bound if math.isfinite(self.bound) else None  # the true error's size, for the allowance
        if est is not self._est:  # a new phase starts from the estimate, with its rounding allowance
            est.carry_rounding(self._est.rounding_vector, radius)
        else:
            est.error_radius = radius
        xhat, _ = est.step(packets, u)  # all-or-nothing; a new estimator is dropped if it raises
        if est is not self._est:
            self._dropped += self._est.dropped_packets  # the phase that ended
        self._est, self.mode = est, mode
        if reverted:
            self.revert_times.append(k)
        if switched:
            self.switch_times.append(k)
        self.bound = est._with_rounding(self._level())
        return xhat, self.bound

    @property
    def rounding(self) -> float:
        """The rounding allowance of the current estimate (:mod:`eqrec.estimators.intake`): the bound is the level
        plus it, rounded up; carried from phase to phase."""
        return self._est.rounding

    @property
    def rounding_vector(self) -> np.ndarray:
        """The per-state rounding allowance of the current estimate (a copy)."""
        return self._est.rounding_vector

    def _level(self) -> float:
        """The bound of the current estimate (class docstring)."""
        if self.bound_of is None:
            return math.inf
        if self.mode == "recovery" and self._est.period_time < self.T:
            return float(self.bound_of(self._est.observed_prefix))
        return self.mu1
