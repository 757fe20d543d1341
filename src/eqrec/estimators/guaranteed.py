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
assume the arrivals stay in the language; a real network does not.  With
``strict=False`` the estimator carries the *exact* error set of its estimate,
a zonotope (:mod:`eqrec.bounds.zonotope`), and returns its worst case: the
bound is never inf or NaN for finite data, it is at least the information
limit (:func:`eqrec.bounds.information.information_limit`: no estimator can
guarantee less) and at least the error for every noise in the box, and it
never exceeds the designed level while the arrivals stay in the language.

* *In the design* (the period started with an error set inside the ``μ1``
  box and its data have stayed in the language): the class step of the
  design, whose error is :math:`\xi(s+d) = G^{\xi_0}_{d,S}\xi(s) +
  G^{w,v}_{d,S}\operatorname{diag}(r)\varepsilon`
  (:mod:`eqrec.estimators.error_maps`), applied to the zonotope of
  :math:`\xi(s)`: no box reset at the period's start, so what earlier periods
  told is kept.  Its bound :math:`b^{\mathrm d}_i` is the smaller of that exact
  worst case and the designed level (both are guarantees; in exact arithmetic
  the first never exceeds the second, since the zonotope lies in the ``μ1`` box).
* *Tight* (``tight=True``, the default): per state, the tighter of two
  estimates is reported, the designed one above and the set-membership one
  (:class:`~eqrec.estimators.zonotope.ZonotopeEstimator`, which runs beside the
  designed gains for the fallback anyway), each with its exact bound:
  :math:`\hat x_i = \hat x^{\mathrm{sm}}_i` and :math:`b_i = b^{\mathrm{sm}}_i`
  where :math:`b^{\mathrm{sm}}_i < b^{\mathrm d}_i`, else the designed pair.
  (Restarting the designed gains at each period start from the set-membership
  set, so that they use what earlier periods told, was measured and changed no
  reported bound on the two-cart plant of ``benchmarks/bench_tight.py``: where
  the designed estimate wins, it wins on its own history; so it is not done.)

  *Proof that the reported bound is the exact worst case of the reported
  estimate, and never above the designed level.*  Given the arrivals, both
  estimates are linear in the initial error and the noise, and both bounds are
  functions of the arrivals only (the class maps and levels, and the
  set-membership generators and window weights, none of which reads a measured
  value).  So the choice of state ``i`` is fixed by the arrivals, the reported
  :math:`\hat x_i` is one of two linear estimates, and its error is bounded by
  the bound of the one chosen, :math:`|x_i - \hat x_i| \le \min(b^{\mathrm
  d}_i, b^{\mathrm{sm}}_i)`; each bound is attained by its own estimate (at
  the vertex of the noise box given by the signs of its error row), so the
  minimum is the exact worst case of what is reported.  Since
  :math:`\min(b^{\mathrm d}_i, b^{\mathrm{sm}}_i) \le b^{\mathrm d}_i \le`
  the designed level, the a priori levels ``μ1``, ``μ2`` remain guarantees.
  With ``tight=False`` the designed estimate is
  reported alone (as before this option; the cost is the same, since the
  set-membership estimator runs for the fallback either way, but its bound is
  looser in the design: on the two-cart plant of ``benchmarks/bench_tight.py``
  about 2× the information limit at the median and 220× at p95 (right after a
  period start the designed bound is the ``μ1`` box), against 1.12× and 1.26× tight).
  ``tight=True`` is the default because the reported bound is never larger,
  the levels are kept, and the estimate stays linear in the noise given the
  arrivals (so :func:`eqrec.estimators.exact.exact_bound` and the worst-case
  playback apply unchanged); ``tight=False`` is for reproducing the papers'
  estimator exactly.
* *Out of the design* (a step whose data has no class: one loss too many, a
  packet later than designed): the estimator reports the set-membership
  estimator :class:`eqrec.estimators.zonotope.ZonotopeEstimator`, which runs
  beside the designed gains on every step from :meth:`reset` (the same packets
  and inputs), so that at the fallback it holds every packet that has arrived.
* *The return.*  At each period start while out of the design, if the
  zonotope's interval hull lies in the ``μ1`` box (every state bound
  :math:`\le \mu_1`, exactly in floating point), the designed gains take over
  again from the set-membership centre.  Proof that the designed guarantee
  then holds: the design's certificate bounds the error of every class of the
  language for every initial error with :math:`\|\xi(s)\|_\infty \le \mu_1`,
  and the true error lies in the zonotope, hence in that box.  The
  set-membership bound tracks the information limit (within a factor close to
  one, ``benchmarks/bench_zonotope.py``), so the return comes at the first
  period start after the arrivals give enough data for a bound below ``μ1``.

:attr:`GuaranteedEstimator.in_design` says which of the two applies;
:attr:`GuaranteedEstimator.state_bounds` holds the per-state bounds.
``strict=True`` keeps the a priori guarantee of the design (the level of the
observed prefix or class) and refuses data outside the language.

**Cost.**  With ``strict=False`` the set-membership estimator runs on every
step (it must hold every packet at a fallback), so a step costs one
set-membership step plus the designed side.  The two share one intake: the
packets and the input are checked once (:func:`eqrec.arrivals.packets.as_packets`,
:meth:`ClassEstimator._take`), and the set-membership estimator takes them as
checked through its private entry (``ZonotopeEstimator._step_checked``: no
second check, no copy of its estimate; its window still refuses what only it
can see, a packet it already holds).  What the designed side needs that
depends on the arrivals alone is kept per observed prefix of a period, a
finite set (the class ``(d, S)``, its level and its arrays: the gain, its
absolute values, the rounding allowance's map and the error map's parts;
:class:`eqrec.estimators.error_maps.ClassSteps`, shared by every estimator of
the design), and found in one dictionary lookup while the packets are
checked.  The class form's period (reference states, residuals, rounding
record) lives in one buffer made once, and the model's parts the step reads
in another (:func:`eqrec.estimators.error_maps.model_buffer`).  The rest of a
step in the design is one compiled call (``_designed_step``, 24 arguments):
the residuals of the new packets and the stacked data of the class, the class
estimate, the rounding allowance of this step's own numbers (it depends on the
magnitudes of the state and the residuals, so it cannot be kept), the product
:math:`\Phi G(s)`, the exact row sums of :math:`[\Phi G(s), N]` (the set at
the period's start depends on the earlier periods) and the choice per state;
the designed set's blocks are entered into its :class:`~eqrec.bounds.zonotope.ErrorSet`
only when read (at the next period start, where the set is reduced to the
order, or by :attr:`predicted`).  Its products go through BLAS as NumPy's
``@`` does and its sums run in NumPy's order, so every number is the one of
the uncompiled step (``tests/test_class_step_cache.py``, bit for bit;
``benchmarks/hash_estimates.py``: 132 digests unchanged by this layout).
A return to the design restarts a spare class estimator (a twin of the one in
use, made at the first return) and checks the carried set's row sums in one
compiled call.
Measured side by side (``python benchmarks/bench_versions.py --old <src>``:
this version and the previous one in one lockstep on the same arrivals, the
cost table of ``python benchmarks/bench_tight.py --part cost``; CPU µs per
step, per step the least of three runs, three runs on a 2-core machine shared
with 4–6 other processes, so read the ratios; 0/20/40 % loss): in the design
``strict=False`` costs 1.11–1.18×, 1.17–1.21× and 1.19–1.25× the
set-membership estimator alone on the two carts, 1.07–1.13×, 1.10–1.17× and
1.16–1.23× on the cart-pole and 1.02–1.08× on the ``n = 10`` chain, against
1.17–1.25×, 1.21–1.29×, 1.26–1.39×; 1.09–1.13×, 1.13–1.23×, 1.19–1.28×;
1.03–1.07× for the previous version in the same runs; ``strict=True`` costs
the same as before (33–110 µs per step, as the previous version's 33–104 µs
in the same runs).  What is left of the designed side at ``n = 4`` (two carts,
40 % loss, about 45–70 µs a step in the design): the compiled call (6 µs on
its own, a third of it passing its arguments, 14–20 µs after a set-membership
step, whose work leaves the caches cold), about 15 µs of Python around it, the
Girard reduction of the designed set at each period start (about 25 µs, 4 µs
per step on average) and the returns to the design (9 of the 103 steps in the
design on that trace, each about 150–200 µs beyond a designed step: the
set-membership estimator's carried set formed by NumPy, about 70–90 µs, and
its reduction to the order, 30–40 µs; 13–16 µs per step on average).  Out of
the design a step is the set-membership step, with the return's check at each
period start (the carried set is formed only when no set-membership bound
exceeds ``μ1``).  ``tight=False`` costs the same as ``tight=True`` (the
set-membership estimator runs for the fallback either way).
"""

from __future__ import annotations

from typing import Iterable

import numba
import numpy as np

from eqrec.arrivals.packets import Packet, as_packets, check_estimate, check_input
from eqrec.bounds.data_classes import ClassGains
from eqrec.bounds.gains import GainSchedule
from eqrec.bounds.zonotope import (PARTS_LIMIT, ErrorMap, ErrorSet, check_order, hull_pad, outer_row_sums,
                                   row_sums_of_parts_compiled)
from eqrec.errors import InputError
from eqrec.estimators.causal import ClassEstimator, RecoveryEstimator, make_estimator
from eqrec.estimators.error_maps import blas_ready, class_step
from eqrec.estimators.intake import BoundRule
from eqrec.estimators.protocol import StateSet
from eqrec.estimators.zonotope import ZonotopeEstimator
from eqrec.systems.affine import AffineSystem

#: Default reduction order of the error set carried with ``strict=False`` (generators per state).
DEFAULT_ORDER = 40


@numba.njit(cache=True)
def _tighter(row_sums, rho, level, sm_bounds, sm_x, x, tight, xhat, bounds,
             use_sm):  # pragma: no cover - compiled
    r"""The reported estimate and bounds of a step in the design (module docstring), in one compiled pass.

    Per state, the designed bound :math:`b^{\mathrm d}_i = \min(\mathrm{nextafter}(\beta_i + \rho_i, +\infty),
    \mathrm{level})` (the exact worst case of the designed set plus the rounding allowance, rounded up, and the
    class's level); with ``tight``, the set-membership pair where its bound is smaller.  Elementwise IEEE operations
    only, the same as NumPy's ``nextafter``, ``minimum``, ``<`` and ``where``: the same numbers.  The reported
    estimate, the bounds and the choice are written into ``xhat``, ``bounds`` and ``use_sm`` (shape ``(n,)``).

    Returns
    -------
    float
        The largest bound (NaN if any is).
    """
    n = row_sums.shape[0]
    top = -np.inf
    for i in range(n):
        d = np.nextafter(row_sums[i] + rho[i], np.inf)
        if d > level:  # np.minimum(d, level): d unless level is smaller
            d = level
        use_sm[i] = tight and sm_bounds[i] < d
        if use_sm[i]:
            xhat[i], bounds[i] = sm_x[i], sm_bounds[i]
        else:
            xhat[i], bounds[i] = x[i], d
        top = max(top, bounds[i]) if not np.isnan(top) else top  # NaN propagates, as in np.max
        if np.isnan(bounds[i]):
            top = np.nan
    return top


def _within(G: np.ndarray, level: float) -> bool:
    """``np.all(outer_row_sums(G) <= level)``, the same decision: the row sums of :func:`outer_row_sums` are those of
    :func:`eqrec.bounds.zonotope.row_sums_of_parts_compiled` with an empty second part (the same additions in the
    same order, up to :data:`PARTS_LIMIT` columns), one compiled call (the return's check of the carried set)."""
    if G.shape[1] > PARTS_LIMIT or not G.flags.c_contiguous:
        return bool(np.all(outer_row_sums(G) <= level))
    return bool((row_sums_of_parts_compiled(G, np.zeros((G.shape[0], 0))) <= level).all())


@numba.njit(cache=True)
def _designed_step(A, B, absB, fixed, period, K, absK, S, rounding_map, state, noise, u, rows, radius, t, taus, ys,
                   level, start_set, sm_bounds, sm_x, tight, out, use_sm):  # pragma: no cover - compiled
    r"""A step in the design with ``strict=False`` in one compiled call: the class step from the packets as they
    arrived (:func:`eqrec.estimators.error_maps.class_step`, with the class's error map parts ``state`` = Φ and
    ``noise`` = N after its rounding map: the residuals, the stacked
    data, ``x̄``, the designed ``x̂`` and ``ρ`` written into ``out[:3]``), its bound ``nextafter(level + max ρ,
    +inf)``, the designed set's new blocks :math:`(\Phi G(s), N)` with their exact row sums
    (:func:`eqrec.bounds.zonotope.outer_row_sums_of_parts`, ``Φ G(s)`` by BLAS as NumPy's ``@``) and the choice
    per state (:func:`_tighter`, writing the reported estimate and bounds into ``out[3:5]`` and the choice into
    ``use_sm``).  The operations of the uncompiled step in the same order: the same numbers.

    Returns
    -------
    tuple
        ``(Φ G(s), the designed bound, the largest reported bound)``.
    """
    top = class_step(A, B, absB, fixed, period, K, absK, S, rounding_map, u, rows, radius, t, taus, ys, out)
    bound = np.nextafter(level + top, np.inf) if np.isfinite(level) else level
    P = np.dot(state, start_set)
    row_sums = row_sums_of_parts_compiled(P, noise)
    top_rep = _tighter(row_sums, out[2], bound, sm_bounds, sm_x, out[1], tight, out[3], out[4], use_sm)
    return P, bound, top_rep


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
        the estimator carries the exact error set of its estimate and returns
        its worst case, falls back to set-membership outside the language and
        says in :attr:`in_design` whether the designed gains apply (module docstring).
    name : str or None, optional
        The family in words (:mod:`eqrec.estimators.protocol`).
    order : float or None, optional
        ``strict=False``: the error set is reduced (outer, Girard) to ``order · n`` generators at each
        period start and in the fallback (default :data:`DEFAULT_ORDER`; ``None``: exact, growing).
    tight : bool, optional
        ``strict=False``: ``True`` (default) reports, per state, the tighter of the designed estimate and the
        set-membership one, each with its exact bound (never above the designed level); ``False`` the designed
        estimate alone (module docstring).

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
    >>> xhat, bound = estimator.step([1.0, 2.0])  # y(0) arrives on time: the level plus the rounding allowance
    >>> estimator.time, round(bound, 12), 0 < bound - 1.05 < 1e-12
    (1, 1.05, True)
    >>> xhat, bound = estimator.step(None)  # y(1) is lost: the design's intermediate level
    >>> abs(bound - design.mu2) < 1e-9
    True
    """

    kind = "guaranteed"

    def __init__(self, system: AffineSystem, gains: "GainSchedule | ClassGains", bound_of: BoundRule, mu1: float,
                 periodic: bool = True, strict: bool = True, name: str | None = None,
                 order: "float | None" = DEFAULT_ORDER, tight: bool = True):
        for key, flag in (("strict", strict), ("periodic", periodic), ("tight", tight)):
            if not isinstance(flag, (bool, np.bool_)):
                raise InputError(f"{key} must be True or False, got {flag!r}", field=key)
        if not strict and not isinstance(gains, ClassGains):
            raise InputError("strict=False needs class gains (a design of the class engine, engine='classes'): the "
                             "bound outside the language is computed from the class maps", field="strict")
        self.system, self.gains, self.bound_of = system, gains, bound_of
        self._n, self._p, self._m = system.n, system.p, system.m
        self.mu1 = float(mu1)
        self.periodic = bool(periodic)
        self.strict = bool(strict)
        self.tight = bool(tight)
        self.name = name or ("guaranteed, class engine" if isinstance(gains, ClassGains) else "guaranteed, node gains")
        if not strict and not periodic:
            raise InputError("strict=False runs periodically (periodic=True): the set-membership fallback returns "
                             "to the designed gains at a period start", field="periodic")
        self.order = check_order(order)
        self._est: "RecoveryEstimator | ClassEstimator | None" = None
        self.bound = np.nan
        # strict=False: the error set, the fallback (None while in the design), the period's record
        self._error_set: ErrorSet | None = None
        # the designed set's blocks of the last step not yet entered into it, (anchor, Φ G(s), N, time): entered
        # when the set is read (:attr:`_set`), so a step does not pay for the error set's bookkeeping
        self._pending: "tuple | None" = None
        self._outside = False  # out of the design: the set-membership estimator's estimate is reported
        self._sm: ZonotopeEstimator | None = None  # the set-membership estimator, run on every step
        self._t0 = 0
        self._bounds = np.full(system.n, np.nan)
        self._xhat: np.ndarray | None = None  # strict=False: the reported estimate
        self._spare: ClassEstimator | None = None  # strict=False: the class estimator not in use (returns)
        self._use_sm: np.ndarray | None = None  # tight, in the design: the states reported from the set-membership
        # strict=False: (period start, the designed set there as the compiled step takes it), kept per period
        self._anchor: "tuple[int, np.ndarray] | None" = None

    @property
    def _set(self) -> "ErrorSet | None":
        """The designed estimate's error set (:class:`eqrec.bounds.zonotope.ErrorSet`), up to date: the last step's
        blocks entered (only the last step's set and the period starts' are ever read)."""
        pending = self._pending
        if pending is not None:
            anchor, P, noise, time = pending
            self._pending = None
            self._error_set.time = time - 1  # the steps in between: no set of theirs is read
            self._error_set.enter(anchor, (P, noise))
        return self._error_set

    @_set.setter
    def _set(self, error_set: "ErrorSet | None") -> None:
        self._error_set, self._pending, self._anchor = error_set, None, None

    @property
    def in_design(self) -> bool:
        """Whether the designed gains and guarantee apply to the current estimate (always true with ``strict=True``).

        False from a step whose data leave the design's language until a
        period starts with an error set inside the ``μ1`` box (module docstring).
        """
        return not self._outside

    def error_map(self):
        """The error map of the current estimate (class gains, inside the design; :mod:`eqrec.bounds.zonotope`).

        Returns
        -------
        ErrorMap
            :meth:`eqrec.estimators.causal.ClassEstimator.error_map` of the running class estimator.

        Raises
        ------
        InputError
            Node gains, or ``strict=False`` outside the design (the set-membership fallback carries its own set).
        """
        est = self._running()
        if not isinstance(est, ClassEstimator) or self._outside:
            raise InputError("error maps are those of the class form inside the design", field="gains")
        return est.error_map()

    @property
    def has_linear_error_model(self) -> bool:
        """Whether :meth:`linear_error_model` answers at every step (class gains; node gains are run as copies
        by :func:`eqrec.exact_bound`)."""
        return isinstance(self.gains, ClassGains)

    def linear_error_model(self):
        """The error of the current estimate, as :func:`eqrec.exact_bound` reads it (class gains, every step).

        The narrow interface between an estimator and the exact run-time bound
        (:mod:`eqrec.estimators.exact`): either an
        :class:`~eqrec.bounds.zonotope.ErrorMap` anchored at an earlier estimate of
        the run (``exact_bound`` carries the error sets and advances them), or
        the generators ``(n, q)`` of the error set of the current estimate
        itself, in unit-box variables independent of the noise still to come
        (``exact_bound`` takes them as its set).  Inside the design: the class
        estimate's map (:meth:`eqrec.estimators.causal.ClassEstimator.error_map`),
        or with ``tight=True`` (``strict=False``) the reported estimate's set, row by
        row: the designed set's rows for the states reported from the designed
        estimate, the set-membership carried set's rows for the others (each row
        zero on the other's generators: an outer set whose row sums are exact);
        outside it (``strict=False``): the set-membership estimator's carried
        set (:attr:`eqrec.estimators.zonotope.ZonotopeEstimator.carried_set`, its
        rounding allowance included); a return to the design anchors the next
        maps at the period start, where that set was the last one given.

        Returns
        -------
        ErrorMap or numpy.ndarray
            The map, or the generators of the error set.

        Raises
        ------
        InputError
            Node gains (:attr:`has_linear_error_model` is false), or before the first step of a period.
        """
        est = self._running()
        if self._outside:
            return self._sm.carried_set[1]
        if not isinstance(est, ClassEstimator):
            raise InputError("node gains have no error maps: exact_bound runs them as copies", field="gains")
        if self._use_sm is not None:  # tight: the reported estimate's rows
            m = self._use_sm[:, None]
            return np.concatenate([np.where(m, 0.0, self._set.current), np.where(m, self._sm.carried_set[1], 0.0)],
                                  axis=1)
        return est.error_map()

    @property
    def rounding_vector(self) -> np.ndarray:
        """The rounding allowance of the current estimate beyond its error set (:mod:`eqrec.estimators.intake`;
        zero outside the design, where the set-membership set includes its own)."""
        if self._outside:
            return np.zeros(self.system.n)
        rho = self._running().rounding_vector
        if self._use_sm is not None:  # tight: the set-membership rows carry their own allowance
            return np.where(self._use_sm, 0.0, rho)
        return rho

    @property
    def state_bounds(self) -> np.ndarray:
        """Per-state bounds ``|x_i − x̂_i| <= state_bounds[i]`` of the current estimate.

        With ``strict=True`` the designed level of the current estimate for every state (the design bounds the
        infinity norm); with ``strict=False`` the per-state exact bounds (module docstring).
        """
        if self.strict:
            self._running()
            return np.full(self.system.n, self.bound)
        self._running()
        return self._bounds.copy()

    @property
    def predicted(self) -> StateSet:
        r"""The set of ``x(t+1)`` the estimator reports (:class:`~eqrec.estimators.protocol.StateSet`, the protocol's
        sets): centre :attr:`x`, per-state bounds :attr:`state_bounds` (rounded outward), and a zonotope.

        * ``strict=False``, in the design: the error set of the *reported* estimate, row by row as
          :meth:`linear_error_model` gives it (with ``tight=True`` the designed set's row for a state reported from
          the designed estimate, the set-membership carried set's row for a state reported from it; the designed
          set alone with ``tight=False``; right after :meth:`reset` the ``μ1`` box, right after a return to the
          design the set-membership set it starts from), each row padded on the diagonal up to its reported bound
          (the pad covers the rounding allowance :attr:`rounding_vector`); a row whose exact worst case lies above
          the designed level (the level is then the bound, a guarantee of its own) is replaced by the box of that
          level.  So the zonotope contains ``x(t+1)`` and its interval hull is the reported bounds (up to the
          rounding of its row sums).
        * ``strict=False``, out of the design: the set-membership estimator's
          (:attr:`eqrec.estimators.zonotope.ZonotopeEstimator.predicted`), whose estimate is the one reported.
        * ``strict=True``: the box of the design's level, the one guarantee it carries (generators ``bound · I``).

        Raises
        ------
        InputError
            Before :meth:`reset`.
        """
        est = self._running()
        n = self.system.n
        if self.strict:
            return StateSet.around(self.time, est.xhat, np.full(n, self.bound), self.bound * np.eye(n))
        if self._outside:
            return self._sm.predicted
        G = self.linear_error_model() if self._use_sm is not None else self._set.current
        bounds = self._bounds
        # a row whose worst case lies above its bound (the designed level): the level's box for that state
        over = np.abs(G).sum(axis=1) > bounds
        if self._use_sm is not None:  # a set-membership row is its carried set's, padded to its own bound already
            over &= ~self._use_sm
        G = np.where(over[:, None], 0.0, G)  # the other rows keep their sums: their pad as the estimator's
        pad = np.where(over, bounds, hull_pad(G, bounds))
        return StateSet.around(self.time, self._xhat, bounds, np.concatenate([G, np.diag(pad)], axis=1))

    @property
    def filtered(self) -> StateSet:
        """The set of ``x(t)`` given the data received up to ``t`` (:class:`~eqrec.estimators.protocol.StateSet`).

        With ``strict=False``: the set-membership estimator's filtered set
        (:attr:`eqrec.estimators.zonotope.ZonotopeEstimator.filtered`), in and out of the design: it runs on every
        packet, and the designed gains give a prediction of ``x(t+1)``, not an estimate of ``x(t)``.

        Raises
        ------
        InputError
            Before :meth:`reset`, right after it (no data yet), or with ``strict=True`` (the design's gains carry
            no set of ``x(t)``: ``design.estimator(strict=False)`` does).
        """
        self._running()
        if self.strict:
            raise InputError("strict=True carries no set of x(t) given the data (only the design's level of the "
                             "prediction): design.estimator(strict=False) gives the filtered set", field="filtered")
        return self._sm.filtered

    @property
    def error_box(self) -> np.ndarray:
        """The same as :attr:`state_bounds` (the name of earlier versions)."""
        return self.state_bounds

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
        self._est = make_estimator(self.system, self.gains, x0, periodic=self.periodic, t0=t0,
                                   bound_of=self.bound_of, mu1=self.mu1)
        self.bound = self.mu1
        if not self.strict:
            self._t0 = int(t0)
            self._set = ErrorSet.box(self.mu1, self.system.n, self._t0, self.order)
            self._outside = False
            self._sm = self._new_set_membership().reset(x0, self._t0)
            self._bounds = np.full(self.system.n, self.mu1)
            self._xhat = x0.copy()
            self._use_sm = None
        return self

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate ``x̂`` (of time :attr:`time`)."""
        if self._outside:
            return self._sm.x
        if self._xhat is not None:
            return self._xhat.copy()
        return self._running().xhat.copy()

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        if self._outside:
            return self._sm.time
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
        est = self._est
        if est is None:
            self._running()  # raises: reset first
        if not self.strict:  # (the time: :attr:`time`)
            return self._relaxed_step(est, as_packets(y, self._sm.time if self._outside else est._k, self._p), u)
        packets = as_packets(y, est.time, self._p)
        try:
            xhat, bound = est.step(packets, u)  # bound: μ1 at the period's end, else the observed prefix's level
        except InputError as err:
            if "outside the design" not in str(err):
                raise
            what = str(err).removeprefix("field 'y': ")
            raise InputError(f"{what}. design.estimator(strict=False) keeps running outside the language "
                             "with an exact bound; or call reset(x̂0) to start again inside it", field="y") from None
        self.bound = bound
        return xhat, self.bound

    def _relaxed_step(self, est: ClassEstimator, packets: list, u) -> tuple[np.ndarray, float]:
        """A step with ``strict=False`` (module docstring): the class step with its exact bound, or the fallback.

        The set-membership estimator runs on every step (every packet reaches it), so on leaving the language
        it is ready, with all the information of the run.  In the design, with ``tight=True``, each state is
        reported from whichever of the two has the smaller exact bound (module docstring).
        """
        if self._outside:
            sm = self._sm
            now = sm.time
            # at a period start, the return needs the carried set's row sums within μ1.  Its pad brings them up to the
            # set-membership bounds (ZonotopeEstimator._window_generators, hull_pad), up to the rounding of a sum of
            # positive terms (relative q u, far below 1e-6), so a bound above μ1 (1 + 1e-6) rules the return out
            # without forming the set: the same decision
            carried = sm.carried_set if (now - self._t0) % self.gains.horizon == 0 \
                and not (sm._beta > self.mu1 * (1.0 + 1e-6)).any() else None
            checked_u = check_input(u, self._m)  # (raises before anything changes)
            if carried is None or not _within(carried[1], self.mu1):
                sm._step_checked(packets, checked_u)
                return self._outside_bounds()
            # the return: the set-membership step first (the one step that may still refuse the data: a packet its
            # window already holds, stamped before the new period, which the class form drops), then the designed
            # gains from the carried set, which the set-membership step does not read (it was formed before)
            sm._step_checked(packets, checked_u)
            est, taken = self._return_to_design(now, packets, u, carried)  # (cannot raise: the data are checked)
        else:
            taken = est._take(packets, u)  # every input checked once, for both estimators; nothing changes
            # the set-membership estimator takes the packets and the input as checked (one intake: its private
            # entry); all-or-nothing, and nothing below can raise
            sm = self._sm
            sm._step_checked(packets, taken[5])
        # the class (t+1, S), its level and its arrays, kept per observed prefix (ClassSteps.prefixes)
        entry, level, kernel, _ = taken[7]
        if entry is None:  # out of the language (on a return: at the period's first step)
            self._outside = True  # the set-membership estimate from now on
            return self._outside_bounds()
        # the class step (its level: μ1 at the period's end, else the class's; plus the rounding allowance of its
        # arithmetic, :mod:`eqrec.estimators.intake`), the exact worst case of the designed estimate's error set
        # (the error map's blocks applied to the set of the period's start) plus that allowance, and per state the
        # smaller of two exact bounds, each a function of the arrivals only (module docstring): one compiled call
        state, noise = kernel[4:]
        start = taken[1]
        anchor = self._anchor  # the set of the period's start, as the compiled product takes it: once per period
        if anchor is not None and anchor[0] == start:
            start_set = anchor[1]
        else:
            start_set = blas_ready(self._set.at(start))  # (reduced on this first use, then kept as it is)
            self._anchor = (start, start_set)
        n = self._n
        out, use_sm = np.empty((5, n)), np.empty(n, np.bool_)
        if start_set.shape[1] + noise.shape[1] <= PARTS_LIMIT:
            P, bound, self.bound = _designed_step(*est._kernel_args(taken, kernel), level, start_set, sm._beta,
                                                  sm._xhat, self.tight, out, use_sm)
            self._pending = (start, P, noise, est._k + 1)
        else:  # rows too long for the compiled sums: the same steps, the sums by NumPy
            bound = est._plus_rounding(level, class_step(*est._kernel_args(taken, kernel[:4]), out))
            row_sums = self._set.advance(ErrorMap(start, state, noise))
            self.bound = _tighter(row_sums, out[2], bound, sm._beta, sm._xhat, out[1], self.tight, out[3], out[4],
                                  use_sm)
        est._install(taken, out, bound)
        self._bounds, xhat = out[4], out[3]
        self._use_sm = use_sm if self.tight else None
        self._xhat = xhat
        return xhat.copy(), self.bound

    def _new_set_membership(self) -> ZonotopeEstimator:
        return ZonotopeEstimator(self.system, x0_radius=self.mu1, max_delay=self.gains.horizon,
                                 order=self.order).periodic_model(self.gains.horizon, self._t0)

    def _outside_bounds(self) -> tuple[np.ndarray, float]:
        """A step out of the design: the set-membership estimate and its bounds (the largest, as its ``step``
        returns it), after its step."""
        sm = self._sm
        beta = sm._beta
        self._use_sm = None
        self._bounds = beta.copy()
        self.bound = bound = float(beta.max()) if beta.size else 0.0
        return sm._xhat.copy(), bound

    def _return_to_design(self, now: int, packets, u,
                          carried: tuple[np.ndarray, np.ndarray]) -> "tuple[ClassEstimator, tuple]":
        """The designed gains again from the set-membership centre (``carried``: its :attr:`carried_set` before this
        step's, which lies in the ``μ1`` box), and the step's packets placed on them (:meth:`ClassEstimator._take`,
        on the estimator reset here).  Called after the set-membership step has taken the packets (the one part of
        a return that may refuse them), with the packets and the input checked: it cannot raise, so a refused
        return changes nothing."""
        centre, generators = carried
        # a spare class estimator, made once and reset at each return (a twin of the one in use: making one anew
        # checks every class gain again)
        est = self._spare
        if est is None:
            est = self._est._twin()
        est._restart(centre.copy(), now)  # reset(centre, now) without its checks: the centre is checked finite
        taken = est._take(packets, u)  # (the packets and the input already checked: it cannot raise here)
        self._set = ErrorSet(generators, now, self.order)
        self._est, self._spare, self._outside = est, self._est, False
        self._use_sm = None
        self._xhat = centre
        return est, taken

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
