r"""A designed estimator ready to run on a user's system: each step returns the estimate and its guarantee.

:class:`GuaranteedEstimator` wraps the causal estimators of
:mod:`eqrec.estimators.causal` (the class form :class:`ClassEstimator` or the
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
(:mod:`eqrec.design.classes.engine`: the exact worst case of that class), the node
or common level otherwise, and ``μ1`` at the end of each period.

Every call is all-or-nothing: the packets, the input and the initial estimate
are checked (shapes, types, NaN/inf) before anything changes, so a call that
raises leaves the estimator exactly as it was.

**Outside the designed language** (``strict=False``, class gains): the papers
assume the arrivals stay in the language; a real network does not.  The
estimator then keeps a true bound: it tracks a box :math:`\beta(k) \in
\mathbb R^n` with :math:`|\xi_i(k)| \le \beta_i(k)` for every noise in the
box.  In a period that starts with :math:`|\xi(0)| \le \beta_0` and whose
data stay in the language, the class maps are linear in :math:`\delta =
(w, v, \xi_0)`, so the exact worst case of class ``(d, S)`` is

.. math:: \beta(d) = |G^{w,v}_{d,S}|\, r + |G^{\xi_0}_{d,S}|\, \beta_0,
    \qquad G_{d,S} = E_d - K_{d,S} Z_S,

(``r`` the noise radii), which is the designed level when :math:`\beta_0 \le
\mu_1`.  When a step's data has no class in the design (one loss too many, a
packet later than designed), the estimator *coasts* to the period's end on the
model, :math:`\hat x(k+1) = A\hat x(k) + Bu(k) + f`, with
:math:`\beta(k+1) = |A|\,\beta(k) + |E|\, r_w` (packets are not used until
the next period), and the next period starts from :math:`\beta_0 =
\beta(\text{end})`.

*When the designed guarantee returns.*  :attr:`GuaranteedEstimator.in_design`
is true exactly when the current period started with :math:`\beta_0 \le
\mu_1` (componentwise) and its data have stayed in the language; the bounds
are then the designed levels.  After an excursion, let :math:`e = \max_i
\beta_{0,i}/\mu_1 - 1 > 0`.  The certificate of every terminal class gives
:math:`c_T + M_T \mu_1 \mathbf 1 \le (\mu_1 - \varepsilon)\mathbf 1`
(:math:`c_T = |G^{w,v}_T| r`, :math:`M_T = |G^{\xi_0}_T|`,
:math:`\varepsilon \ge 0` the design's slack at the period's end), hence
:math:`\|M_T\|_\infty \le \rho := 1 - \min_i c_{T,i}/\mu_1 \le 1` and, after
one period in the language, :math:`e' \le \rho\, e - \varepsilon/\mu_1`.
So with slack (:math:`\varepsilon > 0`) the designed guarantee is back after at
most :math:`\lceil e\,\mu_1/\varepsilon \rceil` periods in the language; without
it the bounds converge to the designed levels geometrically (ratio
:math:`\rho < 1` when noise reaches every state by the period's end).
"""

from __future__ import annotations

from typing import Iterable

import numpy as np

from eqrec.bounds.data_classes import ClassGains
from eqrec.estimators.error_boxes import BoundRule, BoxState, ClassBoxes
from eqrec.estimators.causal import ClassEstimator, RecoveryEstimator, make_estimator
from eqrec.arrivals.packets import Packet, check_estimate
from eqrec.bounds.gains import GainSchedule
from eqrec.arrivals.packets import as_packets
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError



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
    strict : bool, optional
        ``True`` (default): data outside the design's language raise
        :class:`InputError` (nothing changes).  ``False`` (class gains only):
        the estimator keeps running with a true, possibly larger bound and
        says in :attr:`in_design` whether the designed guarantee applies
        (module docstring).
    name : str or None, optional
        The family in words (:mod:`eqrec.estimators.protocol`).

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

    kind = "guaranteed"

    def __init__(self, system: AffineSystem, gains: "GainSchedule | ClassGains", bound_of: BoundRule, mu1: float,
                 periodic: bool = True, strict: bool = True, name: str | None = None):
        for key, flag in (("strict", strict), ("periodic", periodic)):
            if not isinstance(flag, (bool, np.bool_)):
                raise InputError(f"{key} must be True or False, got {flag!r}", field=key)
        if not strict and not isinstance(gains, ClassGains):
            raise InputError("strict=False needs class gains (a design of the class engine, engine='classes'): the "
                             "bound outside the language is computed from the class maps", field="strict")
        self.system, self.gains, self.bound_of = system, gains, bound_of
        self.mu1 = float(mu1)
        self.periodic = bool(periodic)
        self.strict = bool(strict)
        self.name = name or ("guaranteed, class engine" if isinstance(gains, ClassGains) else "guaranteed, node gains")
        self._est: "RecoveryEstimator | ClassEstimator | None" = None
        self.bound = np.nan
        self._boxes = None if strict else ClassBoxes(system, gains, self.mu1)
        self._box = BoxState(np.zeros(0), np.zeros(0), False, True)  # strict=False: the error boxes

    @property
    def in_design(self) -> bool:
        """Whether the designed guarantee applies to the current estimate (always true with ``strict=True``).

        False from a step whose data leave the design's language until a period
        starts again with an error box within ``μ1`` (module docstring).
        """
        return self._box.in_design

    @property
    def error_box(self) -> np.ndarray:
        """``β``: per-state bounds ``|x_i − x̂_i| <= β_i`` of the current estimate (``strict=False`` only)."""
        if self.strict:
            raise InputError("the per-state error box is tracked with strict=False only", field="strict")
        return self._box.beta.copy()

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
            If ``xhat0`` does not have ``n`` finite entries, or ``t0`` is not an integer
            (nothing changes).
        """
        x0 = check_estimate(xhat0, self.system.n)
        self._est = make_estimator(self.system, self.gains, x0, periodic=self.periodic, t0=t0)
        self.bound = self.mu1
        if not self.strict:
            self._box = self._boxes.start()
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
            a :class:`~eqrec.estimators.causal.Packet` or a pair
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
        packets = as_packets(y, est.time, self.system.p)
        if not self.strict:
            return self._relaxed_step(est, packets, u)
        xhat = est.step(packets, u)
        done = est.period_time == est.T
        self.bound = self.mu1 if done else float(self.bound_of(est.observed_prefix))
        return xhat, self.bound

    def _relaxed_step(self, est: ClassEstimator, packets: list[Packet], u) -> tuple[np.ndarray, float]:
        """A step with ``strict=False`` (module docstring): the class step, or coasting with a growing box."""
        opened = est._open(packets, u)  # every input checked; nothing changes
        t, S = opened.t, tuple(sorted(opened.yxi))
        boxes, coasting = self._boxes.advance(self._box, t, S)
        xhat = est._coast(opened) if coasting else est._advance(opened)
        self._box = boxes
        self.bound = self._boxes.bound(boxes, t, S, self.bound_of, est.observed_prefix)
        return xhat, self.bound

    def update(self, y=None, u=None) -> np.ndarray:
        """The filterpy spelling: ``update(y)``, ``update(None)`` for a lost packet; returns the new estimate.

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
