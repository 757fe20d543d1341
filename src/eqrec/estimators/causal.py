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

:class:`eqrec.estimators.switching.SwitchingEstimator` is the implementation strategy of Section III-B3
of the delayed-data paper: an equalized-performance estimator (equalized
recovery with period 1) while every measurement arrives on time, switching
to a recovery estimator for ``T`` steps when one is late or missing.

:class:`ClassEstimator` runs the same estimator in **class form**
(:mod:`eqrec.design.classes.engine`): one gain ``K`` per (time, available data)
class instead of one gain row per prefix-tree node,

.. math:: \hat x(d) = \bar x(d) + K_{(d, S)}\,(y_S - \bar y_S),

with :math:`\bar x` the noise-free prediction from the period's first
estimate.  Both take the same packets and raise the same errors;
:func:`make_estimator` picks one from the kind of gains.

Both follow the protocol of :mod:`eqrec.estimators.protocol`: ``reset(xhat0,
t0=0)``, then ``step(y, u) -> (x̂(t+1), bound)``.  The bound is the design's
level of the observed prefix (or class) when the estimator is built with the
levels (``bound_of``, ``mu1``), else ``inf``: a raw estimator knows its gains,
not its levels (:mod:`eqrec.estimators.intake`).  ``xhat0`` may still be given
to the constructor (then it is reset at once); without it, call
:meth:`~RecoveryEstimator.reset` first.
"""

from __future__ import annotations

import math
from typing import Iterable

import numpy as np

from eqrec.bounds.data_classes import ClassGains
from eqrec.bounds.gains import GainSchedule
from eqrec.bounds.zonotope import ErrorMap
from eqrec.estimators.error_maps import (ClassErrorMaps, ClassSteps, blas_ready, class_step, model_buffer,
                                        period_layout, period_views)
from eqrec.estimators.intake import BoundRule, OpenedStep, RoundingRecord, StampedEstimator
from eqrec.arrivals.packets import Packet, check_estimate, check_input  # noqa: F401  (re-exported: the runtime API)
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


class RecoveryEstimator(StampedEstimator):
    """Causal estimator of eqs. (5)-(7) on time-stamped packets.

    Parameters
    ----------
    system : AffineSystem
        The model (``A, B, C, f``) used by the estimator.
    schedule : GainSchedule
        Prefix-based or time-based gains.
    xhat0 : array_like, shape (n,), or None, optional
        Initial estimate ``x̂(t0)`` (then the estimator is reset at once);
        ``None`` (default): call :meth:`reset` before the first step.
    periodic : bool, optional
        Restart the horizon every ``T`` steps instead of stopping.
    t0 : int, optional
        Absolute time of the first step (the time stamp of the first
        measurement; ``0`` by default).  Packets stamped before ``t0`` are
        dropped like packets of an earlier period.
    bound_of : callable or None, optional
        ``bound_of(prefix) -> level``: the design's guarantee after an observed
        arrival prefix (with ``mu1``; :func:`eqrec.estimators.intake.check_levels`).
    mu1 : float or None, optional
        The design's recovery level: the bound at :meth:`reset` and at each period's end.

    Attributes
    ----------
    kind : str
        ``"guaranteed"``: the second value of :meth:`step` is a bound.
    name : str
        ``"causal, node gains"``.
    bound : float
        The bound of the current estimate: the level of the observed prefix
        with the levels, else ``inf`` (module docstring).
    dropped_packets : int
        Packets stamped before their step's period, not used (since :meth:`reset`).
    """

    name = "causal, node gains"

    def __init__(self, system: AffineSystem, schedule: GainSchedule, xhat0: "np.ndarray | None" = None,
                 periodic: bool = False, t0: int = 0, *, bound_of: "BoundRule | None" = None,
                 mu1: "float | None" = None):
        self.schedule = schedule
        super().__init__(system, schedule.horizon, xhat0, periodic, t0, bound_of, mu1)

    def _reference(self, restarted: bool) -> np.ndarray:
        return self.xhat  # y_ξ(τ) = y(τ) − C x̂(τ), with the estimate of the packet's own time

    def step(self, y: "np.ndarray | Packet | Iterable[Packet] | None" = None,
             u: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        """Process time ``t``: the packets arriving at ``t`` and the input ``u(t)`` (eqs. (5), (7)).

        Parameters
        ----------
        y : ndarray, Packet, iterable of Packet, or None, optional
            ``None`` (nothing arrives), an array (``y(t)`` arriving on time) or
            :class:`Packet` objects stamped with their own (absolute) times ``τ <= t``.
        u : ndarray, shape (m,), or None, optional
            The input ``u(t)`` (``None``: zero).

        Returns
        -------
        xhat : ndarray, shape (n,)
            The prediction ``x̂(t+1)`` (a copy).
        bound : float
            Its bound: the level of the observed prefix (``μ1`` at the period's
            end) with the levels, else ``inf`` (module docstring).

        Raises
        ------
        InputError
            Before :meth:`reset`; when the horizon is over (not periodic), for a
            packet from the future, a second packet with one stamp, a malformed
            measurement or input, or an observed prefix the schedule lacks (nothing changes).
        """
        sys = self.system
        step = self._open(y, u)
        t = step.t
        gain = self.schedule.row(ArrivalPattern(tuple(step.arrivals)), field="y")
        yxi = np.zeros((t + 1, sys.p))
        for tau, v in step.yxi.items():
            yxi[tau] = v
        ue = gain.u0 + gain.F @ yxi.reshape(-1)
        xhat = sys.A_at(t) @ self.xhat + sys.B_at(t) @ step.u - ue + sys.f
        self._commit(step, self._node_rounding(step, gain))
        self.xhat = xhat
        self.bound = self._with_rounding(self._level())
        return self.xhat.copy(), self.bound

    def _node_rounding(self, step: OpenedStep, gain) -> tuple[RoundingRecord, np.ndarray]:
        """The allowance of the node estimate (:mod:`eqrec.estimators.intake`): the period's error maps with
        identity noise gains, ``G(t+1) = A G(t) + I_w(t) + Σ_τ F_τ (C(τ) G(τ) + I_v(τ))`` over ``(w, v, ξ(s))``
        (``τ`` received; ``ξ`` gains ``+u_e``), carry the roundings injected into the state and the measurements."""
        sysm, t, p, n, T = self.system, step.t, self._p, self._n, self.T
        record = self._period_record(step)
        eye = self._norms.get("eye")
        if eye is None:
            eye = self._norms["eye"] = np.eye(n)
        if t == 0:
            G0 = np.zeros((n, T * (n + p) + n))
            G0[:, T * (n + p):] = eye
            record.maps = [G0]
            record.output_maps = {}
        for tau in self._new_packets(step):
            self._output_injection(record, tau, step.yxi[tau], step.history[tau])
        hit = self._norms.get(("gain", id(gain)))  # |F| and |u0| of a node's gains, made once (the row kept alive)
        if hit is None or hit[0] is not gain:
            F = np.asarray(gain.F, float)
            hit = self._norms[("gain", id(gain))] = (gain, F, np.abs(F), np.abs(gain.u0))
        _, F, absF, absu0 = hit
        yxi = np.zeros((t + 1) * p)
        for tau, v in step.yxi.items():
            yxi[tau * p:(tau + 1) * p] = np.abs(v)
        own = absu0 + absF @ yxi
        self._state_injection(step, record, self.xhat, own, n + (t + 1) * p)
        G = sysm.A_at(t) @ record.maps[t]
        G[:, t * n:(t + 1) * n] += eye
        outputs = record.output_maps  # C(τ) G(τ) per received τ: fixed once G(τ) is, made once per period
        for tau in sorted(step.yxi):
            Ft = F[:, tau * p:(tau + 1) * p]
            CG = outputs.get(tau)
            if CG is None:
                CG = outputs[tau] = sysm.C_at(tau) @ record.maps[tau]
            G += Ft @ CG
            G[:, T * n + tau * p:T * n + (tau + 1) * p] += Ft
        record.maps.append(G)
        return record, self._allowance(record, np.abs(G))


class ClassEstimator(StampedEstimator):
    r"""The equalized-recovery estimator in class form: one gain per (time, available data) class.

    The class form of the delayed-data paper's estimator (its eqs. (5)-(7)
    with the gains of Theorem 1, rewritten by the separation theorem of
    :mod:`eqrec.design.classes.engine`): at period time ``t`` the estimator has
    received the measurements of the times ``S = A(t)`` (a packet stamped
    ``τ`` of the current period that arrived at or before ``t``) and predicts

    .. math::
        \hat x(t+1) = \bar x(t+1) + K_{(t+1,\,S)}\,(y_S - \bar y_S),

    where :math:`\bar x` is the noise-free prediction from the period's first
    estimate :math:`\hat x(0)`,

    .. math::
        \bar x(0) = \hat x(0), \qquad \bar x(s+1) = A(s)\,\bar x(s) + B(s)\,u(s) + f,
        \qquad \bar y(\tau) = C(\tau)\,\bar x(\tau),

    (inputs and ``f`` included, so they cancel in the error), and
    :math:`y_S - \bar y_S` stacks :math:`y(\tau) - \bar y(\tau)` over
    :math:`\tau \in S` in increasing time (the column order of ``K``).  With
    :math:`\delta = (w, v, \xi_0)` of the period, :math:`x(d) - \bar x(d) =
    E_d\delta` and :math:`y_S - \bar y_S = Z_S\delta`
    (:func:`eqrec.bounds.data_classes.class_maps`), so the error is exactly

    .. math:: \xi(t+1) = x(t+1) - \hat x(t+1) = (E_{t+1} - K_{(t+1,S)} Z_S)\,\delta,

    whose worst case over the box is the class's certified level.  Unlike
    :class:`RecoveryEstimator` it needs no prefix tree and no history of
    estimates, only the ``K`` of the current class (looked up by
    ``(t+1, S)``); any arrival prefix whose classes are in the design gets
    their guarantees, whether or not the prefix itself is one of the design's.

    Packet handling, periodic restart and errors are those of
    :class:`RecoveryEstimator`.  With ``periodic=True`` the horizon restarts
    every ``T`` steps and :math:`\bar x` is re-anchored at the estimate reached
    at the period's end (``‖ξ‖ <= μ1`` there, so the same gains apply again);
    packets stamped before the current period are dropped (the language counts
    a delay past the period's end as a missing measurement).

    Parameters
    ----------
    system : AffineSystem
        The model (``A, B, C, f``) used by the estimator (time-varying
        matrices are read at absolute times, as in :class:`RecoveryEstimator`).
    gains : ClassGains
        One ``K`` per class (:class:`eqrec.bounds.data_classes.ClassGains`, e.g.
        ``design.class_gains`` of the class engine).
    xhat0 : array_like, shape (n,), or None, optional
        Initial estimate ``x̂(t0)`` (then the estimator is reset at once);
        ``None`` (default): call :meth:`reset` before the first step.
    periodic : bool, optional
        Restart the horizon every ``T`` steps instead of stopping (default
        ``False``).
    t0 : int, optional
        Absolute time of the first step; packets stamped before it are dropped.
    bound_of : callable or None, optional
        ``bound_of(prefix) -> level``: the design's guarantee after an observed
        arrival prefix, i.e. its class's level (with ``mu1``).
    mu1 : float or None, optional
        The design's recovery level: the bound at :meth:`reset` and at each period's end.

    Attributes
    ----------
    kind : str
        ``"guaranteed"``: the second value of :meth:`step` is a bound.
    name : str
        ``"causal, class gains"``.
    bound : float
        The bound of the current estimate: the level of its class with the
        levels, else ``inf`` (module docstring; :func:`eqrec.exact_bound` gives
        the exact worst case from :meth:`error_map`).
    dropped_packets : int
        Packets stamped before their step's period, not used (since :meth:`reset`).
    xhat : ndarray, shape (n,)
        The current estimate (of time :attr:`time`).
    time : int
        Absolute time of the next step.
    period_time : int
        Steps taken in the current period (``0..T``).
    observed_prefix : ArrivalPattern
        The arrival prefix observed so far in the current period.
    prediction : ndarray, shape (n,)
        ``x̄`` of the current time.

    Raises
    ------
    InputError
        Gains whose shapes do not fit the system; in :meth:`step`, the
        errors of :meth:`RecoveryEstimator.step`, or observed data whose class
        ``(t+1, S)`` the gains do not have.

    See Also
    --------
    GuaranteedEstimator : The same estimator with its per-step guarantee
        (what :meth:`Design.estimator` returns).

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> words = ["101111", "110111", "111011", "111101"]  # the prefix-based paper's L1
    >>> design = eqrec.design_prefix(acc, words, mu1=1.0)
    >>> estimator = eqrec.ClassEstimator(acc, design.class_gains).reset(np.zeros(3))
    >>> xhat, bound = estimator.step(np.array([1.0, 2.0]))  # y(0) arrives on time
    >>> xhat.shape, bound, estimator.time, estimator.observed_prefix.label  # no levels given: no bound
    ((3,), inf, 1, '1')
    """

    name = "causal, class gains"

    def __init__(self, system: AffineSystem, gains: ClassGains, xhat0: "np.ndarray | None" = None,
                 periodic: bool = False, t0: int = 0, *, bound_of: "BoundRule | None" = None,
                 mu1: "float | None" = None):
        if (gains.n, gains.p) != (system.n, system.p):
            raise InputError(f"class gains for n = {gains.n}, p = {gains.p} do not fit the system "
                             f"(n = {system.n}, p = {system.p})")
        for cls, K in zip(gains.classes.classes, gains.K):
            if np.shape(K) != (system.n, len(cls.available) * system.p):
                raise InputError(f"the gain of class {cls.label} has shape {np.shape(K)}, expected "
                                 f"{(system.n, len(cls.available) * system.p)}")
        self.gains = gains
        self._maps: ClassErrorMaps | None = None
        self._class_steps: ClassSteps | None = None  # per class: K, |K|, the rounding map (shared by the design)
        self._xbar: "np.ndarray | None" = None
        T, n, p = gains.horizon, system.n, system.p
        # the period's state, kept in arrays made once (:meth:`_take`, :func:`class_step`): the reference state and
        # the residual per period time, the rounding record, the period times of the data received (increasing)
        self._period_buffer = np.zeros(sum(period_layout(T, n, p)))
        refs, res, z, true = period_views(self._period_buffer, T, n, p)
        self._period = RoundingRecord(T, n, p, np.zeros(n), z, true)
        self._S: tuple = ()
        self._no_taus, self._no_ys = np.zeros(0, dtype=np.int64), np.zeros(0)
        self._one_tau = [np.array([tau], dtype=np.int64) for tau in range(T)]
        # what the compiled step takes of the model, looked up once (:meth:`_kernel_args`): the output model, and
        # the whole model of a time-invariant system
        self._outputs: "tuple | None" = None
        self._fixed_model: "tuple | None" = None
        self._prefixes: dict = {}
        super().__init__(system, gains.horizon, xhat0, periodic, t0, bound_of, mu1)
        if self.bound_of is not None:  # the levels looked up, shared by the estimators of these gains and rule
            self._levels = self._steps().levels(self.bound_of)
        self._prefixes = self._steps().prefixes((self.bound_of, self.mu1))

    def _twin(self) -> "ClassEstimator":
        """A new estimator of these gains, levels and system, not yet reset (call :meth:`_restart`): what the
        constructor would make, with its checks of the gains and its per-design lookups taken from this one (the
        spare of :class:`eqrec.estimators.guaranteed.GuaranteedEstimator`, made at its first return to the design).

        The read-only parts are shared (the gains, the design's per-class and per-prefix stores, the model's
        arrays); the period's buffer, its record and what holds them (the compiled step's model tuples) are its own.
        """
        twin = object.__new__(type(self))
        twin.__dict__.update(self.__dict__)
        T, n, p = self.T, self._n, self._p
        twin._period_buffer = np.zeros(self._period_buffer.shape[0])
        refs, res, z, true = period_views(twin._period_buffer, T, n, p)
        twin._period = RoundingRecord(T, n, p, np.zeros(n), z, true)
        # the model tuples of the compiled step end with the period buffer: made again (the model's arrays kept)
        twin._outputs = twin._fixed_model = None
        twin._norms = {key: hit for key, hit in self._norms.items() if not (type(key) is tuple and key[0] == "class")}
        twin.xhat, twin._xbar, twin._rows = None, None, None
        twin.bound = math.nan
        twin._rho = np.zeros(n)
        twin.error_radius = None
        twin._S = ()
        twin._clear(0)
        return twin

    def _on_reset(self) -> None:
        self._xbar = self.xhat.copy()  # x̄(t): noise-free prediction from the period's x̂(0)
        self._S = ()

    def error_map(self) -> ErrorMap:
        r"""How the error of the current estimate depends on the period's initial error and noise.

        :math:`\xi(s+d) = G^{\xi_0}_{d,S}\,\xi(s) + G^{w,v}_{d,S}\,\mathrm{diag}(r)\,\varepsilon`
        for the class ``(d, S)`` of the last step, anchored at the period's start ``s``
        (:mod:`eqrec.estimators.error_maps`; the maps are computed on first use and kept).

        Returns
        -------
        ErrorMap
            The map of the current estimate (:mod:`eqrec.bounds.zonotope`).

        Raises
        ------
        InputError
            Before the first step of a period (the estimate is the period's initial one).
        """
        if self._t == 0:
            raise InputError("no step of the period has been taken: the current estimate is its initial one")
        if self._maps is None:
            self._maps = ClassErrorMaps.of(self.system, self.gains)
        return self._maps.error_map(self._start, self._t, self._S)

    @property
    def prediction(self) -> np.ndarray:
        """``x̄`` of the current time: the noise-free prediction from the period's first estimate."""
        return self._xbar.copy()

    def _reference(self, restarted: bool) -> np.ndarray:
        # residuals y(τ) − C(τ) x̄(τ); a new period re-anchors x̄ at the estimate reached at the period's end
        return self.xhat if restarted else self._xbar

    def class_of(self, y, u=None) -> tuple[int, tuple[int, ...]]:
        """The class ``(t+1, S)`` a step with these packets would need (nothing changes).

        Parameters
        ----------
        y : ndarray, Packet, iterable of Packet, or None
            What would arrive at the current time (as in :meth:`step`).
        u : ndarray or None, optional
            The input (checked like :meth:`step` does).

        Returns
        -------
        tuple
            ``(depth, available)``: the period time of the predicted estimate and
            the period times of the measurements received by then.

        Raises
        ------
        InputError
            As :meth:`step`, except for a class the gains lack.
        """
        taken = self._take(self._packets(y), u)
        return taken[0] + 1, taken[7][3]

    def step(self, y: "np.ndarray | Packet | Iterable[Packet] | None" = None,
             u: np.ndarray | None = None) -> tuple[np.ndarray, float]:
        r"""Process time ``t``: the packets arriving at ``t`` and the input ``u(t)``.

        Advances the noise-free prediction
        :math:`\bar x(t+1) = A\bar x(t) + B u(t) + f` and returns
        :math:`\hat x(t+1) = \bar x(t+1) + K_{(t+1,S)}(y_S - \bar y_S)`,
        with ``S`` the measurement times of the period received so far.

        Parameters
        ----------
        y : ndarray, Packet, iterable of Packet, or None, optional
            As in :meth:`RecoveryEstimator.step`: ``None`` (nothing arrives),
            an array (``y(t)`` arriving on time) or :class:`Packet` objects
            stamped with their own (absolute) times ``τ <= t``.
        u : ndarray, shape (m,), or None, optional
            The input ``u(t)`` (``None``: zero).

        Returns
        -------
        xhat : ndarray, shape (n,)
            The prediction ``x̂(t+1)`` (a copy).
        bound : float
            Its bound: the level of its class (``μ1`` at the period's end) with
            the levels, else ``inf`` (module docstring).

        Raises
        ------
        InputError
            Before :meth:`reset`; when the horizon is over (not periodic), for a packet from the
            future, a second packet with one stamp, a measurement of the
            wrong length, or observed data whose class ``(t+1, S)`` the
            gains do not have.
        """
        return self._advance(self._take(self._packets(y), u))

    def _steps(self) -> ClassSteps:
        """The design's per-class cache (:class:`eqrec.estimators.error_maps.ClassSteps`, shared by the gains)."""
        steps = self._class_steps
        if steps is None:
            steps = self._class_steps = ClassSteps.of(self.system, self.gains)
        return steps

    def _take(self, packets: list, u) -> tuple:
        """Check a step's packets (:func:`eqrec.arrivals.packets.as_packets`'s list) and input: the step's period
        time, the period's start, the observed arrivals with this step's, the period times of the new packets and
        their measurements, the checked input, the packets dropped (stamped before the period) and the step's class
        with its level (:meth:`_lookup`).  Nothing changes.

        Raises :class:`InputError` when the horizon is over (not periodic), for a packet whose stamp was already
        received in this period, or a malformed input (the intake of
        :meth:`eqrec.estimators.intake.StampedEstimator._open`, without the residuals: the compiled step forms them).
        """
        if self.xhat is None:
            self._running()  # raises: reset first
        u = self._no_input if u is None else check_input(u, self._m)  # (the zero input is only read, never written)
        t = self._t
        if t == self.T:
            if not self.periodic:
                raise InputError(f"the estimator's horizon T = {self.T} is over{self._restart_hint}")
            t, start, arrivals = 0, self._k, [None]
        else:
            start, arrivals = self._start, self._arrivals + [None]
        taus, ys, dropped = self._place(packets, start, arrivals, t)
        # the class (t+1, S) and its level, kept per observed prefix (one lookup; :meth:`_lookup`)
        hit = self._prefixes.get(tuple(arrivals))
        if hit is None:
            hit = self._lookup(t, arrivals)
        return t, start, arrivals, taus, ys, u, dropped, hit

    def _lookup(self, t: int, arrivals: list) -> tuple:
        """The class ``(t+1, S)`` of a step with these observed arrivals and what the step needs of it: ``(entry,
        level, kernel, S)``, the :class:`~eqrec.estimators.error_maps.ClassStep` (``None`` when the design has no
        such class), its level (:meth:`_level_at`; NaN without a class), its
        :attr:`~eqrec.estimators.error_maps.ClassStep.kernel` and ``S``; kept per prefix for the design's estimators
        of this rule (:meth:`eqrec.estimators.error_maps.ClassSteps.prefixes`)."""
        key = tuple(arrivals)
        hit = self._prefixes.get(key)
        if hit is None:
            S = tuple(tau for tau, a in enumerate(arrivals) if a is not None)
            entry = self._steps().get(t + 1, S)
            if entry is None:  # not kept (a refused step changes nothing, caches included: the language is kept)
                return None, math.nan, None, S
            hit = (entry, self._level_at(t + 1, arrivals), entry.kernel, S)
            if len(self._prefixes) >= 4096:  # bounded (a period has finitely many prefixes)
                self._prefixes.clear()
            self._prefixes[key] = hit
        return hit

    def _refuse(self, taken: tuple) -> InputError:
        """The error of a step whose data the design has no class for."""
        t, start, arrivals = taken[:3]
        S = [tau for tau, a in enumerate(arrivals) if a is not None]
        return InputError(f"observed data outside the design: at time {self._k} (step {t} of the period "
                          f"started at {start}, arrival prefix {ArrivalPattern(tuple(arrivals)).label!r}) the "
                          f"measurements of times {[start + tau for tau in S]} have arrived; the gains have no class "
                          f"({t + 1}, {S})", field="y")

    def _advance(self, taken: tuple) -> tuple[np.ndarray, float]:
        """The step of :meth:`step` from its checked packets (:meth:`_take`; the class lookup may still raise, then
        nothing changes)."""
        entry, level, kernel, _ = taken[7]
        if entry is None:
            raise self._refuse(taken)
        out = np.empty((3, self._n))
        top = class_step(*self._kernel_args(taken, kernel[:4]), out)
        self._install(taken, out, self._plus_rounding(level, top))
        return self.xhat.copy(), self.bound

    @staticmethod
    def _plus_rounding(level: float, top: float) -> float:
        """The reported bound: the level plus the allowance's largest entry, rounded up (``inf`` stays ``inf``)."""
        return math.nextafter(level + top, math.inf) if math.isfinite(level) else level

    def _install(self, taken: tuple, out: np.ndarray, bound: float) -> None:
        """Install a computed class step (it can no longer fail; ``out``: ``x̄``, ``x̂`` and ``ρ`` in rows)."""
        t, start, arrivals, _, _, _, dropped, hit = taken
        self._xbar, self.xhat, self._rho = out[0], out[1], out[2]
        self._rows = out
        self._t, self._start, self._k = t + 1, start, self._k + 1
        self._arrivals, self._S = arrivals, hit[3]
        self._record = self._period
        if dropped:
            self.dropped_packets += dropped
        self.bound = bound

    def _model(self, t: int) -> tuple:
        """What the compiled class step takes of the model at period time ``t``, in its order, in one lookup (kept
        by time for a time-varying system): ``A(t), B(t)`` (:func:`eqrec.estimators.error_maps.blas_ready`),
        ``|B|``, then in one array (:func:`eqrec.estimators.error_maps.model_buffer`) ``|A|``, the rows ``f``,
        ``|E| η_w 1``, ``|f|`` and the magnitude without input (:meth:`_drift`), ``|C(τ)|``, ``|V(τ)| η_v 1`` and
        ``C(τ)`` per period time (row-major), the ``terms`` of an output and of a state injection and the
        allowance's factor, then the period buffer.

        A row-major ``C`` (the systems' own: made from nested lists) is multiplied by the BLAS kernel of NumPy's
        ``C @ ref``, so the residuals are the numbers of the uncompiled step; a column-major one is copied to
        row-major, whose product may round differently, still within the allowance (its bound holds for any order
        of the sums, :func:`eqrec.bounds.rounding_kernels.injection_bound`)."""
        key = ("class", t if self._varying else 0)
        hit = self._norms.get(key)
        if hit is None:
            absA, absB, _, e, _, f = self._absolute_model(t)
            vecs = np.ascontiguousarray([self.system.f, e, f, self._drift(t)], dtype=float)
            outputs = self._outputs
            if outputs is None:
                absC, v, output_terms = self._output_model()
                Cs = np.ascontiguousarray([self.system.C_at(tau) for tau in range(self.T)], dtype=float)
                outputs = self._outputs = (absC, v, Cs, output_terms, self._n + self._state_terms_extra,
                                           self._allowance_factor)
            hit = self._norms[key] = (blas_ready(self.system.A_at(t)), blas_ready(self.system.B_at(t)), absB,
                                      model_buffer(absA, vecs, *outputs), self._period_buffer)
        return hit

    def _kernel_args(self, taken: tuple, kernel: tuple) -> tuple:
        """The arguments of the compiled class step (:func:`eqrec.estimators.error_maps.class_step`) but ``out``:
        the model and the period buffer (:meth:`_model`), the class's ``kernel`` (the first four of
        :attr:`~eqrec.estimators.error_maps.ClassStep.kernel`, or all six for the designed step), the input, the
        estimates, the magnitudes' radius, the period time and the new packets.  The allowance of the class
        estimate (:mod:`eqrec.estimators.intake`): the roundings of ``x̄``, of the residuals and of the simulated
        state and measurements, carried by the class map with identity noise gains
        (:class:`eqrec.estimators.error_maps.RoundingMaps`), plus that of ``x̄ + K r`` itself (``r`` the stacked
        residuals of the class's data)."""
        t, _, _, taus, ys, u, _, _ = taken
        model = self._fixed_model
        if model is None:
            model = self._model(t)
            if not self._varying:
                self._fixed_model = model
        if not taus:
            taus, ys = self._no_taus, self._no_ys
        elif len(taus) == 1:
            taus, ys = self._one_tau[taus[0]], ys[0]  # (made once per period time; only read)
        else:
            taus, ys = np.array(taus, dtype=np.int64), np.concatenate(ys)
        error_radius = self.error_radius
        if error_radius is not None:  # :meth:`_radius`, inline
            radius = float(error_radius)
        else:
            radius = float(self.bound) if math.isfinite(self.bound) else 0.0
        rows = self._rows
        if rows is None:  # after a reset (or a carried allowance): made once from the estimates
            rows = self._rows = np.array([self._xbar, self.xhat, self._rho])
        return model + kernel + (u, rows, radius, t, taus, ys)


def make_estimator(system: AffineSystem, gains: "GainSchedule | ClassGains", xhat0: "np.ndarray | None" = None,
                   periodic: bool = False, t0: int = 0, *, bound_of: "BoundRule | None" = None,
                   mu1: "float | None" = None) -> "RecoveryEstimator | ClassEstimator":
    """The runtime estimator of a design's gains.

    Parameters
    ----------
    system : AffineSystem
        The model used by the estimator.
    gains : GainSchedule or ClassGains
        Node gains (:class:`eqrec.bounds.gains.GainSchedule`: a
        :class:`RecoveryEstimator`, eqs. (5)-(7)) or class gains
        (:class:`eqrec.bounds.data_classes.ClassGains`: a :class:`ClassEstimator`,
        the class form).
    xhat0 : array_like, shape (n,), or None, optional
        Initial estimate ``x̂(t0)`` (``None``: call ``reset`` before the first step).
    periodic : bool, optional
        Restart the horizon every ``T`` steps.
    t0 : int, optional
        Absolute time of the first step.
    bound_of : callable or None, optional
        The design's levels by observed prefix (with ``mu1``; module docstring).
    mu1 : float or None, optional
        The design's recovery level.

    Returns
    -------
    RecoveryEstimator or ClassEstimator
        The estimator, at time ``t0`` with estimate ``xhat0`` (if given).

    Raises
    ------
    InputError
        For gains of any other kind (field ``gains``).
    """
    if isinstance(gains, GainSchedule):
        return RecoveryEstimator(system, gains, xhat0, periodic=periodic, t0=t0, bound_of=bound_of, mu1=mu1)
    if isinstance(gains, ClassGains):
        return ClassEstimator(system, gains, xhat0, periodic=periodic, t0=t0, bound_of=bound_of, mu1=mu1)
    raise InputError(f"expected a GainSchedule or ClassGains, got {type(gains).__name__}", field="gains")


def has_class(gains: ClassGains, depth: int, available: tuple[int, ...]) -> bool:
    """Whether the design's language has the class ``(depth, available)`` (the data of a step are in it).

    Parameters
    ----------
    gains : ClassGains
        The class gains of a design.
    depth : int
        Period time of the estimate.
    available : tuple of int
        Period times of the measurements received.

    Returns
    -------
    bool
        ``True`` when the class exists.
    """
    try:
        gains.classes.index(depth, available)
    except InputError:
        return False
    return True
