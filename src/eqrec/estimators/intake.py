r"""The packet intake, the period clock and the protocol of the causal estimators (all-or-nothing steps).

Shared by :class:`~eqrec.estimators.causal.RecoveryEstimator`,
:class:`~eqrec.estimators.causal.ClassEstimator` and
:class:`~eqrec.estimators.augmented.AugmentedEstimator`.
:class:`StampedEstimator` keeps the observed arrivals of the current period,
a reference state per period time and the residuals of the packets received;
a step is opened aside (:class:`OpenedStep`, every input checked, nothing
changed), the estimator computes its estimate from it, and only then is it
committed, so a step that raises leaves the estimator as it was.

The protocol (:mod:`eqrec.estimators.protocol`): ``reset(xhat0, t0=0)``
returns the estimator, ``step(y, u)`` returns ``(x̂(t+1), bound)``.  These
raw estimators know their gains, not the levels their design certified, so
the bound is what they were told (:func:`check_levels`):

* built with the design's levels (``bound_of``, a rule ``observed prefix ->
  level``, and ``mu1``: what :class:`~eqrec.estimators.guaranteed.GuaranteedEstimator`
  gets from its design), it is the level of the observed prefix (or of its
  class), ``μ1`` at ``reset`` and at the end of each period: the a priori
  guarantee of equalized recovery, valid while the arrivals stay in the
  design's language and the initial error is within ``μ1``;
* built without them, it is ``math.inf``, on purpose and always: the
  estimator promises nothing it was not told (the trivial bound, never NaN).
  :func:`eqrec.estimators.exact.exact_bound` gives a class-form estimator its
  exact worst case for an initial radius, ``Design.estimator()`` its levels.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from eqrec.arrivals.packets import Stamped, is_stamp, as_packets, check_estimate, check_input
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

#: ``bound_of(prefix)``: the guarantee on ``ξ(t+1)`` after the observed arrival prefix of length ``t + 1``.
BoundRule = Callable[[ArrivalPattern], float]


def check_levels(bound_of: "BoundRule | None", mu1: Any) -> "tuple[BoundRule | None, float]":
    """The levels a raw estimator reports as its bound (module docstring): both given, or neither.

    Parameters
    ----------
    bound_of : callable or None
        ``bound_of(prefix) -> level``, the design's guarantee after an observed arrival prefix.
    mu1 : float or None
        The recovery level (the bound at ``reset`` and at each period's end).

    Returns
    -------
    tuple
        ``(bound_of, μ1)``, or ``(None, inf)`` when neither is given (no guarantee known).

    Raises
    ------
    InputError
        Only one of the two, a ``bound_of`` that is not callable (field ``bound_of``), or a ``mu1`` that is
        not a finite number > 0 (field ``mu1``).
    """
    if bound_of is None and mu1 is None:
        return None, math.inf
    if bound_of is None or not callable(bound_of):
        raise InputError(f"the levels are a rule prefix -> level and mu1, got bound_of = {bound_of!r:.60}",
                         field="bound_of")
    if isinstance(mu1, (bool, np.bool_, str)) or not isinstance(mu1, (int, float, np.integer, np.floating)) \
            or not math.isfinite(float(mu1)) or float(mu1) <= 0:
        raise InputError(f"mu1 must be a finite number > 0 with bound_of, got {mu1!r:.60}", field="mu1")
    return bound_of, float(mu1)


@dataclass
class OpenedStep:
    """The state of a step under way, not yet committed (module docstring of :class:`StampedEstimator`).

    Parameters
    ----------
    k : int
        Absolute time of the step.
    t : int
        Its period time.
    start : int
        Absolute time of the period's start.
    arrivals : list
        Per period time: the arrival time (period time) or ``None``.
    history : list
        Reference states at the period times ``0..t``.
    yxi : dict
        Period time -> residual of the packet received.
    restarted : bool
        A new period starts at this step.
    u : numpy.ndarray
        The checked input.
    dropped : int, optional
        Packets stamped before the period: not used (counted in ``dropped_packets``).
    """

    k: int  # absolute time of the step
    t: int  # its period time
    start: int  # absolute time of the period's start
    arrivals: list  # per period time: arrival time (period time) or None
    history: list  # reference states at the period times 0..t
    yxi: dict  # period time -> residual
    restarted: bool  # a new period starts at this step
    u: np.ndarray  # the checked input
    dropped: int = 0  # packets stamped before the period: not used (counted in dropped_packets)


class StampedEstimator:
    """Packet intake and protocol shared by the causal estimators (module docstring).

    Keeps the period clock, the observed arrivals of the current period, a
    *reference* state per period time (the state whose predicted output a
    measurement is compared with) and the residuals
    ``y(τ) − C(τ) ref(τ)`` of the packets received in the period.

    A step is all-or-nothing: :meth:`_open` checks everything and builds the
    new state aside (:class:`OpenedStep`), the subclass computes the estimate
    from it, and only then :meth:`_commit` installs it; a step that raises
    leaves the estimator exactly as it was.  :meth:`reset` (the protocol's
    ``reset``) too checks its arguments before anything changes.

    Time convention: the model's time-varying matrices are read at the
    *period time* ``t = k − period_start`` (the time of the design, whose
    time 0 is the period's start), so a time-varying model describes one
    period of a ``T``-periodic plant, as the design assumes.

    A packet stamped before the current period (or before ``t0``) is not
    refused, with ``strict=True`` as with ``strict=False``: its period's
    gains are no longer in use, and the language counts it as missing there
    (a delay past the period's end means missing), so dropping it keeps the
    guarantee.  It is counted in :attr:`dropped_packets` (since the last
    ``reset``, as :attr:`eqrec.estimators.zonotope.ZonotopeEstimator.dropped_packets`).

    Parameters
    ----------
    system : AffineSystem
        The model the estimator runs on.
    horizon : int
        ``T``, the period of the gains.
    xhat0 : numpy.ndarray or None
        Initial estimate (``None``: call ``reset`` first).
    periodic : bool
        Restart the horizon every ``T`` steps.
    t0 : int
        Absolute time of the first step.
    bound_of : callable or None, optional
        The design's level of an observed prefix (with ``mu1``; the second value of ``step``).
    mu1 : float or None, optional
        The recovery level (with ``bound_of``).
    """

    T: int
    kind = "guaranteed"
    name = "causal"
    _restart_hint = " (use periodic=True to restart)"

    def __init__(self, system: AffineSystem, horizon: int, xhat0: "np.ndarray | None", periodic: bool, t0: int,
                 bound_of: "BoundRule | None" = None, mu1: "float | None" = None):
        if not is_stamp(t0):
            raise InputError(f"the start time must be an integer, got {t0!r}", field="t0")
        self.system = system
        self.T = int(horizon)
        self.periodic = bool(periodic)
        system.check_horizon(self.T)
        self.bound_of, self.mu1 = check_levels(bound_of, mu1)
        self.xhat: "np.ndarray | None" = None  # set by reset
        self.bound = math.nan  # nan until reset (then μ1, or inf without levels)
        self._clear(int(t0))
        if xhat0 is not None:
            self.reset(xhat0, t0)

    def _clear(self, t0: int) -> None:
        self._t = 0  # time since the start of the current period
        self._k = t0  # absolute time
        self._start = t0  # absolute time of the current period's start
        self._arrivals: list[int | None] = []  # per period time τ: arrival time (period time) or None
        self._history: list = []  # reference state at the period times 0..t
        self._yxi: dict[int, np.ndarray] = {}  # period time τ -> y(τ) - C ref(τ)
        self.dropped_packets = 0  # packets stamped before their step's period: not used (class docstring)

    def reset(self, xhat0: Any, t0: int = 0) -> "StampedEstimator":
        """Start a run (a new period) from ``x̂(t0) = xhat0``, discarding any run in progress.

        The ``reset`` of the protocol, shared by the causal estimators (each
        subclass starts what it carries besides the estimate in ``_on_reset``:
        the prediction of the class form, the auxiliary state of the augmented one).

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            The initial estimate (finite).
        t0 : int, optional
            Absolute time of the first step (the time stamp of the first measurement; default 0).
            Packets stamped before it are dropped like packets of an earlier period.

        Returns
        -------
        StampedEstimator
            ``self``, so that ``est.reset(x0).step(...)`` chains; :attr:`bound` is ``μ1`` (``inf`` without levels).

        Raises
        ------
        InputError
            ``xhat0`` without ``n`` finite entries (field ``xhat0``), ``t0`` not an integer (field ``t0``);
            nothing changes.
        """
        if not is_stamp(t0):
            raise InputError(f"the start time must be an integer, got {t0!r}", field="t0")
        x = check_estimate(xhat0, self.system.n)
        self._clear(int(t0))
        self.xhat = x
        self._on_reset()
        self.bound = self.mu1
        return self

    def _on_reset(self) -> None:
        """What a subclass starts besides the estimate (after :meth:`reset` has set it)."""

    def _level(self) -> float:
        """The bound of the current estimate (module docstring): ``μ1`` at the period's end, else the level of
        the observed prefix; ``inf`` without levels."""
        if self.bound_of is None:
            return math.inf
        return self.mu1 if self._t == self.T else float(self.bound_of(self.observed_prefix))

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate (of time :attr:`time`)."""
        return self._running().copy()

    def _running(self) -> np.ndarray:
        if self.xhat is None:
            raise InputError("call reset(xhat0) before running the estimator")
        return self.xhat

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

    def _residual(self, tau: int, y: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """The residual ``y(τ) − C(τ) ref(τ)`` of a packet stamped at period time ``τ``."""
        return y - self.system.C_at(tau) @ reference

    def _open(self, y, u, restart_at_now: bool = False) -> OpenedStep:
        """Check what arrived at the current time and ``u``, and build the step's state aside (nothing changes).

        Raises :class:`InputError` when the horizon is over (not periodic),
        for malformed packets (:func:`as_packets`), a packet whose stamp
        was already received in this period, or a malformed input.  Packets
        stamped before the current period are dropped and counted in
        :attr:`dropped_packets` when the step commits.
        """
        sys = self.system
        self._running()
        packets = self._packets(y)
        u = check_input(u, sys.m)
        restarted = restart_at_now or self._t == self.T
        if self._t == self.T and not self.periodic and not restart_at_now:
            raise InputError(f"the estimator's horizon T = {self.T} is over{self._restart_hint}")
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
            yxi[tau] = self._residual(tau, pk.y, history[tau])
        return OpenedStep(k, t, start, arrivals, history, yxi, restarted, u, dropped)

    def _commit(self, step: OpenedStep) -> None:
        """Install the state of a step that succeeded."""
        self._t, self._start, self._k = step.t + 1, step.start, step.k + 1
        self._arrivals, self._history, self._yxi = step.arrivals, step.history, step.yxi
        self.dropped_packets += step.dropped
