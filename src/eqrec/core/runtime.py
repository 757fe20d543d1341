r"""A designed estimator ready to run on a user's system: each step returns the estimate and its guarantee.

:class:`GuaranteedEstimator` wraps the causal estimators of
:mod:`eqrec.core.estimator` (the class form :class:`ClassEstimator` or the
node-gain form :class:`RecoveryEstimator`) with the guarantee of the design
they come from, in the convention of python-control's discrete-time systems
and of filterpy's filters:

* :meth:`~GuaranteedEstimator.reset` starts it from an initial estimate
  ``x̂(0)`` (the guarantee assumes :math:`\|x(0) - \hat x(0)\|_\infty \le \mu_1`);
* :meth:`~GuaranteedEstimator.step` takes what arrived at time ``t``: a
  measurement ``y(t)`` (an array), ``None`` for a lost packet (filterpy's
  ``update(None)``), or time-stamped packets ``(τ, y(τ))`` for late ones, and
  the input ``u(t)``; it returns the prediction ``x̂(t+1)`` and the bound
  ``b(t+1)`` with :math:`\|x(t+1) - \hat x(t+1)\|_\infty \le b(t+1)` for every
  noise in the design's box and every arrival pattern of its language.

The bound after a prefix is the design's guarantee for it: the certified
level of the (time, available data) class for class-engine designs
(:mod:`eqrec.design.classes`: the exact worst case of that class), the node
or common level otherwise, and ``μ1`` at the end of each period.
"""

from __future__ import annotations

from typing import Callable, Iterable

import numpy as np

from eqrec.core.classes import ClassGains
from eqrec.core.estimator import ClassEstimator, Packet, RecoveryEstimator, make_estimator
from eqrec.core.gains import GainSchedule
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.systems import AffineSystem
from eqrec.errors import InputError

#: ``bound_of(prefix)``: the guarantee on ``ξ(t+1)`` after the observed arrival prefix of length ``t + 1``.
BoundRule = Callable[[ArrivalPattern], float]


class GuaranteedEstimator:
    r"""A design's causal estimator with its per-step guarantee (module docstring).

    Runs the estimator of a design (usually made by :meth:`Design.estimator`,
    not by hand) in the convention of python-control's discrete-time systems
    and of filterpy's filters: :meth:`reset` from ``x̂(0)``, then one
    :meth:`step` per time with what arrived.  Each step returns the
    prediction ``x̂(t+1)`` and its guarantee ``b(t+1)``,

    .. math:: \|x(t+1) - \hat x(t+1)\|_\infty \le b(t+1),

    valid for every noise in the design's box and every arrival pattern of
    its language provided :math:`\|x(0) - \hat x(0)\|_\infty \le \mu_1`
    (equalized recovery, Definition 2 of the prefix-based paper): the
    certified level of the observed prefix (or of its class), and ``μ1`` at
    the end of each period.

    Parameters
    ----------
    system : AffineSystem
        The model the estimator runs on (``A, B, C, f``).
    gains : GainSchedule or ClassGains
        Node gains or class gains of the design.
    bound_of : callable
        ``bound_of(prefix) -> float``, the guarantee after an observed prefix.
    mu1 : float
        The recovery level (the guarantee at ``t = 0`` and at each period end).
    periodic : bool, optional
        Restart the horizon every ``T`` steps (Section V of the prefix-based
        paper): the gains are reused for ever (default).

    Attributes
    ----------
    x : ndarray
        The current estimate (of time :attr:`time`).
    bound : float
        Its guarantee on the infinity norm of the error (``nan`` before
        :meth:`reset`).
    time : int
        Absolute time of the current estimate.

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111", "111011", "111101"], mu1=1.0)
    >>> estimator = design.estimator()
    >>> estimator.reset(np.zeros(3)).time, estimator.bound  # reset returns the estimator
    (0, 1.0)
    >>> xhat, bound = estimator.step([1.0, 2.0])  # y(0) arrives on time
    >>> estimator.time, bound
    (1, 1.05)
    >>> xhat, bound = estimator.step(None)  # y(1) is lost: the design's intermediate level
    >>> abs(bound - design.mu2) < 1e-9
    True
    """

    def __init__(self, system: AffineSystem, gains: "GainSchedule | ClassGains", bound_of: BoundRule, mu1: float,
                 periodic: bool = True):
        self.system = system
        self.gains = gains
        self.bound_of = bound_of
        self.mu1 = float(mu1)
        self.periodic = bool(periodic)
        self._est: "RecoveryEstimator | ClassEstimator | None" = None
        self.bound = np.nan

    def reset(self, xhat0, t0: int = 0) -> "GuaranteedEstimator":
        """Start from ``x̂(t0) = xhat0`` (shape ``(n,)``); the guarantee assumes its error is within ``μ1``.

        Starts a new period at ``t0`` (discarding any run in progress) and
        sets :attr:`bound` to ``μ1``.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            Initial estimate ``x̂(t0)``, with ``‖x(t0) − x̂(t0)‖∞ <= μ1``.
        t0 : int, optional
            Absolute time of the first step (the time stamp of the first
            measurement; default 0).  Packets stamped before ``t0`` are dropped.

        Returns
        -------
        GuaranteedEstimator
            ``self``, so that ``design.estimator().reset(x0)`` chains.

        Raises
        ------
        InputError
            If ``xhat0`` does not have ``n`` entries.
        """
        x0 = np.asarray(xhat0, float)
        if x0.shape != (self.system.n,):
            raise InputError(f"the initial estimate must have n = {self.system.n} entries, got shape {x0.shape}",
                             field="xhat0")
        self._est = make_estimator(self.system, self.gains, x0, periodic=self.periodic, t0=int(t0))
        self.bound = self.mu1
        return self

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate ``x̂`` (of time :attr:`time`)."""
        return self._running().xhat.copy()

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        return self._running().time

    def _running(self) -> "RecoveryEstimator | ClassEstimator":
        if self._est is None:
            raise InputError("call reset(xhat0) before running the estimator")
        return self._est

    def step(self, y: "np.ndarray | Packet | Iterable | None" = None, u=None) -> tuple[np.ndarray, float]:
        """Process time ``t``: what arrived (``y(t)``, ``None``, or packets ``(τ, y(τ))``) and ``u(t)``.

        Forms ``x̂(t+1) = A x̂(t) + B u(t) − u_e(t) + f`` with the gains of
        the observed arrival prefix (eqs. (5), (7) of the prefix-based paper)
        or of its class (:class:`ClassEstimator`), and updates :attr:`bound`.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            What arrived at time ``t``: ``y(t)`` itself (an array of ``p``
            numbers, on time); ``None`` when nothing arrived (a lost or late
            packet, filterpy's ``update(None)``); or time-stamped packets,
            a :class:`~eqrec.core.estimator.Packet` or a pair
            ``(τ, y(τ))`` with ``τ <= t`` the absolute time stamp, or a
            list of them (late measurements).
        u : array_like, shape (m,), or None, optional
            The input ``u(t)`` (``None``: zero).

        Returns
        -------
        xhat : ndarray, shape (n,)
            The prediction ``x̂(t+1)``.
        bound : float
            Its guarantee: ``‖x(t+1) − x̂(t+1)‖∞ <= bound``.

        Raises
        ------
        InputError
            Before :meth:`reset`; for a packet from the future, a second
            packet with one stamp, a measurement of the wrong length, an
            arrival prefix outside the design, or a step past the horizon of
            a non-periodic estimator.
        """
        est = self._running()
        packets = _as_packets(y, est.time)
        xhat = est.step(packets, u)
        done = est.period_time == est.T
        self.bound = self.mu1 if done else float(self.bound_of(est.observed_prefix))
        return xhat, self.bound

    def update(self, y=None, u=None) -> np.ndarray:
        """filterpy's spelling: ``update(y)``, ``update(None)`` for a lost packet; returns the new estimate.

        The same as :meth:`step` without the bound (read :attr:`bound`).

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            What arrived at the current time, as in :meth:`step`.
        u : array_like, shape (m,), or None, optional
            The input (``None``: zero).

        Returns
        -------
        ndarray, shape (n,)
            The prediction ``x̂(t+1)``.

        Raises
        ------
        InputError
            As :meth:`step`.
        """
        return self.step(y, u)[0]


def _is_pair(item) -> bool:
    return (isinstance(item, (tuple, list)) and len(item) == 2 and isinstance(item[0], (int, np.integer))
            and not np.isscalar(item[1]))


def _as_packets(y, now: int) -> list[Packet]:
    """What arrived at ``now``: ``None``; ``y(now)`` (an array, a list of numbers or a number); a
    :class:`Packet` or a pair ``(τ, y(τ))``; or a list of packets and pairs."""
    if y is None:
        return []
    if isinstance(y, Packet):
        return [y]
    if _is_pair(y):
        return [Packet(int(y[0]), np.asarray(y[1], float))]
    if np.isscalar(y) or isinstance(y, np.ndarray) or all(np.isscalar(v) for v in y):
        return [Packet(now, np.atleast_1d(np.asarray(y, float)))]
    out = []
    for item in y:
        if isinstance(item, Packet):
            out.append(item)
        elif _is_pair(item):
            out.append(Packet(int(item[0]), np.asarray(item[1], float)))
        else:
            raise InputError(f"a packet is (time stamp, y), got {item!r}", field="y")
    return out
