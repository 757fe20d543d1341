r"""The packet intake, the period clock and the protocol of the causal estimators (all-or-nothing steps).

Shared by :class:`~eqrec.estimators.causal.RecoveryEstimator`,
:class:`~eqrec.estimators.causal.ClassEstimator` and
:class:`~eqrec.estimators.augmented.AugmentedEstimator`.
:class:`StampedEstimator` keeps the observed arrivals of the current period,
a reference state per period time and the residuals of the packets received;
a step is opened aside (:class:`OpenedStep`, every input checked, nothing
changed), the estimator computes its estimate from it, and only then is it
committed, so a step that raises leaves the estimator as it was.  The class
form checks a step the same way (:meth:`~eqrec.estimators.causal.ClassEstimator._take`:
the same checks and errors, nothing changed) but keeps its period in arrays
made once, which its compiled step writes only once the step can no longer
fail (the reference state of the step's time, the residuals of the new
packets, the record below); the node-gain and augmented forms keep the lists
and dictionaries of :class:`OpenedStep`.

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

**Floating point.**  The levels are exact-arithmetic worst cases; the error a
user computes, ``x − x̂`` with ``x`` a simulated state and ``x̂`` this
estimate, is rounded on both sides.  So the reported bound is the level plus
:attr:`StampedEstimator.rounding`, an a priori allowance :math:`\rho` for the
rounding of the estimate and of a simulated true state of the same size
(:mod:`eqrec.bounds.rounding`), rounded up: with the levels,
``bound = nextafter(level + ρ, +inf)``, and ``error <= bound`` holds in
floating point, not even one ulp over.

How :math:`\rho` is computed.  Each rounding of a step, of the estimator's
state update (the prediction ``x̄`` of the class form, ``x̂`` of the node
form) and of a simulated true state of the same size, acts on the error
:math:`\xi = x - \hat x` exactly as a process noise with ``E = I`` would; the
rounding of a residual and of a simulated measurement as a measurement noise
with ``V = I``.  Their per-step bounds (:func:`eqrec.bounds.rounding_kernels.injection_bound`
of the step's actual magnitudes: ``|A| (|ref| + |x̂| + bound) + 2 |B u + f| +
|E| η_w`` and ``|r| + |C| (2 |ref| + |x̂| + bound) + |V| η_v``, the true state
being within ``bound`` of the estimate) are carried to the estimate by the
estimator's own exact error map with identity noise gains, and so is the
previous period's :math:`\rho` (through the map's :math:`\xi_0` columns):
:math:`\rho = |G|\,(\iota_w, \iota_v, \rho(s))`, with ``G`` the class map
:math:`E_d - K Z_S` of the system with ``E = I``, ``V = I``
(:class:`eqrec.estimators.error_maps.RoundingMaps`) or, for node gains, the
period's map built step by step; plus the rounding of ``x̄ + K r`` itself.
So :math:`\rho` contracts with the design from one period to the next, and
stays bounded on long runs.  ``bound`` is the estimator's level, or
:attr:`StampedEstimator.error_radius` when a wrapper knows the error's size
(:func:`eqrec.exact_bound`, the switching estimator).  The augmented
estimator (one horizon, no period to carry) uses the a priori form:
:func:`eqrec.bounds.rounding.rounding_allowance` of the magnitudes
propagated with absolute values.  The map's own rounding is a relative
:math:`u` of :math:`\rho`, second order, covered by the factor 4 of the
allowance.  Measured (``tests/test_rounding.py``'s plants, class engine,
noise at box corners, in the language, 10 periods): :math:`\rho` / bound has
median ``9e-14`` (three tanks), ``3e-13`` (cart-pole) and ``2e-12``
(``n = 10``) with the state at the scale of its error (max ``2e-13``,
``3e-12``, ``1e-11``), and grows with ``‖x‖ / bound``: ``3e-12``, ``1e-9``
and ``5e-11`` at ``‖x(0)‖ ≈ 100`` (the cart-pole's unstable mode grows the
state itself); the allowance scales with the state, the bound with its
error.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from eqrec.arrivals.packets import Stamped, is_stamp, as_packets, check_estimate, check_input
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.bounds.rounding import UNIT_ROUNDOFF, rounding_allowance
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

#: Levels of observed prefixes kept per estimator (:meth:`StampedEstimator._level`; cleared when full).
_LEVELS_KEPT = 4096

_SHARED_LEVELS: "weakref.WeakKeyDictionary" = weakref.WeakKeyDictionary()


def _levels_kept(rule: "BoundRule | None") -> dict:
    """The levels looked up with ``rule``, shared by every estimator built with an equal rule while one lives
    (a rule that cannot be weakly referenced or hashed gets a dict of its own)."""
    if rule is None:
        return {}
    try:
        kept = _SHARED_LEVELS.get(rule)
        if kept is None:
            kept = _SHARED_LEVELS[rule] = {}
    except TypeError:
        return {}
    return kept


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


def _injection_bound(M, a, scale, b, c, add, terms):
    """:func:`eqrec.bounds.rounding_kernels.injection_bound`, imported at its first call (with Numba, about 0.35 s
    of CPU that a job building estimators without stepping them does not pay); the compiled kernel then takes this
    name's place in the module."""
    global _injection_bound
    from eqrec.bounds.rounding_kernels import injection_bound as compiled
    _injection_bound = compiled
    return compiled(M, a, scale, b, c, add, terms)


class RoundingRecord:
    """The rounding allowance's record of a period (:class:`StampedEstimator`, module docstring).

    Parameters
    ----------
    T, n, p : int
        Period, state and output dimensions.
    rho0 : numpy.ndarray, shape (n,)
        The allowance of the period's initial estimate.
    z, true : numpy.ndarray or None, optional
        Arrays to hold :attr:`z` and :attr:`true` (views of a class estimator's period buffer, whose compiled step
        writes them); ``None``: new ones.

    Attributes
    ----------
    z : numpy.ndarray, shape (T (n + p) + n,)
        ``w``, ``v`` and ``rho0`` end to end (the columns of the error maps).
    w : numpy.ndarray, shape (T, n)
        Per period time ``j``, the bound of the rounding injected into ``ξ(j+1)`` (the estimator's state update
        and the simulated state's).
    v : numpy.ndarray, shape (T, p)
        Per period time ``τ``, the bound of the rounding injected into the measurement of ``τ`` (its residual
        and the simulated ``y(τ)``).
    true : numpy.ndarray, shape (T, n)
        Per period time entered, the magnitude ``|x̂| + bound`` of the true state.
    maps : list
        What a node-gain estimator propagates (its error maps per period time).
    output_maps : dict
        A node-gain estimator's ``C(τ) G(τ)`` per period time ``τ`` received (made once, read at every later step).
    """

    def __init__(self, T: int, n: int, p: int, rho0: np.ndarray, z: "np.ndarray | None" = None,
                 true: "np.ndarray | None" = None):
        #: all the injections in the order of the error maps' columns ``(w, v, ξ0)``: one product carries them
        self.z = np.zeros(T * (n + p) + n) if z is None else z  # (given: views of a class estimator's period buffer)
        self.w, self.v = self.z[:T * n].reshape(T, n), self.z[T * n:T * (n + p)].reshape(T, p)
        self.z[T * (n + p):] = rho0
        self.true = np.zeros((T, n)) if true is None else true
        self.maps: list = []
        self.output_maps: dict = {}


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
        self._rho = np.zeros(system.n)  # the rounding allowance ρ of the current estimate, per state (module docstring)
        self._rows: "np.ndarray | None" = None  # the class form's x̄, x̂, ρ as its compiled step wrote them
        self.error_radius: "float | None" = None  # the true error's size, when a wrapper knows it (else the bound)
        self._norms: dict = {}
        self._varying = system.is_time_varying  # a frozen system: asked once (its matrices are cached by time)
        # asked once per estimator, not per step: the input and output sizes, and C when it does not vary in time
        self._n, self._m, self._p = system.n, system.m, system.p
        # the lengths of the rounding injections' dot products beyond the estimator's own (module docstring)
        self._state_terms_extra = system.nw + system.m + 3
        self._output_terms = system.n + system.nv + 2
        self._allowance_factor = 1.0 + (2 * system.n + 8) * UNIT_ROUNDOFF  # ρ's factor (:meth:`_allowance`)
        self._C_fixed = system.C if system.C.ndim == 2 else None
        self._no_input = np.zeros(self._m)  # u = None: the zero input, shared by the steps (read only)
        self._levels = _levels_kept(self.bound_of)  # observed prefix -> its level (:meth:`_level`)
        self._zeros = np.zeros(system.n)
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
        # the rounding allowance's record of the period (module docstring): ρ at its start and per period time the
        # magnitudes of the true state and of the estimator's reference, the sensitivity to the start (node gains)
        self._record: "RoundingRecord | None" = None

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
        self._restart(check_estimate(xhat0, self.system.n), int(t0))
        return self

    def _restart(self, x: np.ndarray, t0: int) -> None:
        """:meth:`reset` from an estimate already checked: ``x`` a finite float vector of ``n`` entries (kept, not
        copied: a new array of the caller's) and ``t0`` an ``int`` (the return of
        :class:`eqrec.estimators.guaranteed.GuaranteedEstimator` to the design, from the set-membership centre)."""
        self._clear(t0)
        self.xhat = x
        self._on_reset()
        self.bound = self.mu1
        # the simulated x(t0) = x̂(t0) + ξ(t0) is itself rounded: half an ulp of its size
        self._rho = rounding_allowance(0.0, 1, np.abs(x) + self._radius())
        self._rows = None  # (the class form's x̄, x̂, ρ in one array: made again from these at its next step)

    def carry_rounding(self, rounding: float, error_radius: "float | None") -> None:
        """Start the current period with the allowance of the estimate it starts from (module docstring).

        For an estimator started from another one's estimate (a switch of
        :class:`eqrec.estimators.switching.SwitchingEstimator`): the new
        estimator's :math:`\\rho` is the old one's, and the true error's size
        at the start is ``error_radius`` (``None``: this estimator's bound).

        Parameters
        ----------
        rounding : float or ndarray, shape (n,)
            The allowance :math:`\\rho` of the current estimate (one number or per state).
        error_radius : float or None
            A bound on the true error of the current estimate, for the magnitudes.

        Returns
        -------
        None
            The estimator is changed in place.
        """
        self._rho = np.broadcast_to(np.asarray(rounding, float), (self.system.n,)).copy()
        self._rows = None  # (the class form's x̄, x̂, ρ in one array: made again at its next step)
        self.error_radius = error_radius

    def _radius(self) -> float:
        """The true error's size assumed by the magnitudes: :attr:`error_radius`, else the bound (0 if unknown)."""
        if self.error_radius is not None:
            return float(self.error_radius)
        return float(self.bound) if math.isfinite(self.bound) else 0.0

    def _absolute_model(self, t: int) -> tuple[np.ndarray, ...]:
        """``|A|, |B|, |C|, |E| η_w 1, |V| η_v 1, |f|`` at period time ``t`` (cached)."""
        sysm = self.system
        key = t if self._varying else 0
        hit = self._norms.get(key)
        if hit is None:
            B = sysm.B_at(t)
            hit = self._norms[key] = (np.abs(sysm.A_at(t)), np.abs(B) if B is not None else np.zeros((sysm.n, 0)),
                                      np.abs(sysm.C_at(t)), np.abs(sysm.E_at(t)).sum(axis=1) * sysm.eta_w,
                                      np.abs(sysm.V_at(t)).sum(axis=1) * sysm.eta_v, np.abs(sysm.f))
        return hit

    def _output_model(self) -> tuple[np.ndarray, np.ndarray, int]:
        """``|C(τ)|`` and ``|V(τ)| η_v 1`` stacked over the period times ``τ = 0..T-1`` (arrays ``(T, p, n)`` and
        ``(T, p)``, made once) and the ``terms`` of an output injection (:meth:`_output_injection`)."""
        hit = self._norms.get("outputs")
        if hit is None:
            models = [self._absolute_model(tau) for tau in range(self.T)]
            hit = self._norms["outputs"] = (np.ascontiguousarray([m[2] for m in models], dtype=float),
                                            np.ascontiguousarray([m[4] for m in models], dtype=float),
                                            self._output_terms)
        return hit

    def _period_record(self, step: OpenedStep) -> "RoundingRecord":
        """The period's rounding record with period time ``t`` entered (a new one at a period's start; called once
        the step can no longer raise, so it is extended in place)."""
        sysm = self.system
        if step.t == 0:
            record = RoundingRecord(self.T, sysm.n, sysm.p, self._rho.copy())
        else:
            record = self._record
        record.true[step.t] = np.abs(self.xhat) + self._radius()  # |x(t)| <= |x̂(t)| + bound
        return record

    def _new_packets(self, step: OpenedStep) -> list[int]:
        """The period times of the packets first received at this step."""
        before = {} if step.t == 0 else self._yxi
        return [tau for tau in step.yxi if tau not in before]

    def _state_injection(self, step: OpenedStep, record: "RoundingRecord", reference: np.ndarray,
                         own: "np.ndarray | None", length: int) -> None:
        """Enter the rounding of the step's state updates, an injection into ``ξ(t+1)`` (module docstring): the
        estimator's (``own``: the magnitude of its update beyond ``|A| |reference|``, dot products of ``length``)
        and the simulated state's ``x(t+1) = A x + B u + f + E w``."""
        absA, absB, _, e, _, f = self._absolute_model(step.t)
        # without input (u = 0: |B| |u| = 0 exactly) the magnitude is e + 2 |f|, kept per time: the same numbers
        add = e + 2.0 * (absB @ np.abs(step.u) + f) if absB.shape[1] and step.u.any() else self._drift(step.t)
        if own is not None:
            add = add + own
        record.w[step.t] = _injection_bound(absA, reference, 1.0, record.true[step.t], self._zeros, add,
                                           length + self._state_terms_extra)

    def _drift(self, t: int) -> np.ndarray:
        """``|E| η_w 1 + 2 |f|`` at period time ``t`` (cached): the part of a state update's magnitude without input."""
        key = ("drift", t if self._varying else 0)
        hit = self._norms.get(key)
        if hit is None:
            _, _, _, e, _, f = self._absolute_model(t)
            hit = self._norms[key] = e + 2.0 * f
        return hit

    def _output_injection(self, record: "RoundingRecord", tau: int, residual: np.ndarray,
                          reference: np.ndarray) -> None:
        """Enter the rounding of a residual ``y(τ) − C ref(τ)`` and of the simulated ``y(τ) = C x(τ) + V v(τ)``,
        an injection into the measurement of ``τ``."""
        _, _, absC, _, v, _ = self._absolute_model(tau)
        record.v[tau] = _injection_bound(absC, reference, 2.0, record.true[tau], residual, v, self._output_terms)

    def _allowance(self, record: "RoundingRecord", maps: np.ndarray, extra: "np.ndarray | float" = 0.0) -> np.ndarray:
        """``ρ = |G| (ι_w, ι_v, ρ(s)) + extra``, rounded up (module docstring); ``maps`` is ``|G|``, the absolute
        error map of the current estimate with identity noise gains, columns ``(w, v, ξ0)``."""
        total = maps @ record.z + extra
        return np.nextafter(total * self._allowance_factor, np.inf)

    def _with_rounding(self, level: float) -> float:
        """The reported bound: the level plus the allowance, rounded up (``inf`` stays ``inf``)."""
        if not math.isfinite(level):
            return level
        return math.nextafter(level + self.rounding, math.inf)  # the IEEE nextafter, as np.nextafter

    @property
    def rounding(self) -> float:
        """The rounding allowance :math:`\\rho` of the current estimate, ``max_i ρ_i`` (module docstring)."""
        return float(self._rho.max(initial=0.0))

    @property
    def rounding_vector(self) -> np.ndarray:
        """The per-state rounding allowance of the current estimate (a copy; module docstring)."""
        return self._rho.copy()

    def _on_reset(self) -> None:
        """What a subclass starts besides the estimate (after :meth:`reset` has set it)."""

    def _level(self) -> float:
        """The bound of the current estimate (module docstring): ``μ1`` at the period's end, else the level of
        the observed prefix; ``inf`` without levels."""
        return self._level_at(self._t, self._arrivals)

    def _level_at(self, t: int, arrivals: list) -> float:
        """:meth:`_level` of the estimate reached after ``t`` steps of a period with these observed arrivals (a step
        under way: its level before it is committed)."""
        if self.bound_of is None:
            return math.inf
        if t == self.T:
            return self.mu1
        # the rule is a function of the prefix, and a period has finitely many prefixes: kept (bounded)
        key = tuple(arrivals)
        hit = self._levels.get(key)
        if hit is None:
            if len(self._levels) >= _LEVELS_KEPT:
                self._levels.clear()
            hit = self._levels[key] = float(self.bound_of(ArrivalPattern(key)))
        return hit

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
        return as_packets(y, self._k, self._p)

    def _reference(self, restarted: bool) -> np.ndarray:
        """The state of the current time whose predicted output the measurements of this time are compared with."""
        raise NotImplementedError

    def _residual(self, tau: int, y: np.ndarray, reference: np.ndarray) -> np.ndarray:
        """The residual ``y(τ) − C(τ) ref(τ)`` of a packet stamped at period time ``τ``."""
        C = self._C_fixed  # C_at(τ) is C itself for a C without a time axis: the same product
        return y - (self.system.C_at(tau) if C is None else C) @ reference

    def _place(self, packets: list, start: int, arrivals: list, t: int) -> tuple[list, list, int]:
        """Mark the packets of this step in ``arrivals`` (the period's observed arrivals, this step's entry
        appended: a new list, written here) with the period time ``t`` at which each arrived.

        Returns the period times of the new packets and their measurements, in the packets' order, and the number
        of packets stamped before the period's ``start`` (dropped: their gains are no longer in use).  Raises
        :class:`InputError` for a packet whose stamp was already received in this period.
        """
        taus, ys, dropped = [], [], 0
        for pk in packets:
            tau = pk.time - start
            if tau < 0:
                dropped += 1  # stamped before this period: its gains are no longer in use (counted, not used)
                continue
            if arrivals[tau] is not None:
                raise InputError(f"a second packet stamped {pk.time} received at time {self._k}", field="y")
            arrivals[tau] = t
            taus.append(tau)
            ys.append(pk.y)
        return taus, ys, dropped

    def _open(self, y, u, restart_at_now: bool = False) -> OpenedStep:
        """Check what arrived at the current time and ``u``, and build the step's state aside (nothing changes).

        Raises :class:`InputError` when the horizon is over (not periodic),
        for malformed packets (:func:`as_packets`), a packet whose stamp
        was already received in this period, or a malformed input.  Packets
        stamped before the current period are dropped and counted in
        :attr:`dropped_packets` when the step commits.
        """
        if self.xhat is None:
            self._running()  # raises: reset first
        packets = self._packets(y)
        u = self._no_input if u is None else check_input(u, self._m)  # (the zero input is only read, never written)
        at_end = self._t == self.T
        restarted = restart_at_now or at_end
        if at_end and not self.periodic and not restart_at_now:
            raise InputError(f"the estimator's horizon T = {self.T} is over{self._restart_hint}")
        k = self._k
        if restarted:
            t, start, arrivals, history, yxi = 0, k, [None], [], {}
        else:
            t, start = self._t, self._start
            arrivals, history, yxi = self._arrivals + [None], self._history.copy(), self._yxi.copy()
        history.append(self._reference(restarted).copy())
        taus, ys, dropped = self._place(packets, start, arrivals, t)
        for tau, y_tau in zip(taus, ys):
            yxi[tau] = self._residual(tau, y_tau, history[tau])
        return OpenedStep(k, t, start, arrivals, history, yxi, restarted, u, dropped)

    def _commit(self, step: OpenedStep, rounding: "tuple[RoundingRecord, np.ndarray] | None" = None) -> None:
        """Install the state of a step that succeeded (with the period's rounding record and ``ρ``)."""
        if rounding is not None:
            self._record, self._rho = rounding
        self._t, self._start, self._k = step.t + 1, step.start, step.k + 1
        self._arrivals, self._history, self._yxi = step.arrivals, step.history, step.yxi
        self.dropped_packets += step.dropped
