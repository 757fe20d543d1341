r"""An exact set-membership estimator: the interval hull of the states consistent with the measured data.

The zonotope estimator (:mod:`eqrec.estimators.zonotope`) chooses its weights without looking at the measured
values: its set's shape, and so its bound, is the same for every data of an arrival trace, never below the
information limit (the worst case over the data).  For the data actually measured the consistent set can be
smaller.  :class:`ExactSetEstimator` intersects with the measured strips: at each step it solves the window of
the last :math:`L` steps **with its data** as linear programs (:mod:`eqrec.bounds.window_lp`): the set of
:math:`x(t+1)` consistent with

* the zonotope filter's set of :math:`x(s_0)` at the window's start (the filter of
  :class:`~eqrec.estimators.zonotope.ZonotopeEstimator`, a guaranteed outer set, reduced to ``order · n``
  generators),
* and every packet of times :math:`s_0..t` received so far, each a strip
  :math:`|y(s) - C(s)x(s)| \le \eta_v|V(s)|\mathbf 1` in its exact form,

is a constrained zonotope (Scott, Raimondo, Marseglia, Braatz, Automatica 69, 2016); its interval hull is two LPs
per state (:func:`eqrec.lp.box_simplex.box_lp_multipliers`: a compiled dense dual simplex up to 64 rows, and for
equality rows up to 40,000 entries, HiGHS beyond; warm-started from one objective to the next), each end bounded
by weak
duality from the LP's duals with a rounding allowance, so every reported end is a guarantee in floating point
whatever the LP's accuracy (:mod:`eqrec.bounds.window_lp`).

What "exact" means here
-----------------------
The set is exact given its prior at :math:`s_0`: the states of the window and every measurement in it enter
without approximation.  The prior is an outer set (the filter's reduced zonotope), so the hull can exceed the
exact hull of the whole trace; the window's data shrink the prior's excess with every measured step (the
documented approximation, in place of a constrained zonotope's order reduction).  A longer ``window`` is
tighter and costs more.  Measured against the full-horizon LP on the two-cart plant (lightly damped, a double
integrator: the slowest to forget its prior), 30 % loss, delays 0..2, 150 steps: window 20 ends at 1.35 times
the exact hull (1.59 at worst), window 30 at 1.13 (1.19), window 40 at 1.001 (1.06)
(``tests/test_exact_set.py``, ``benchmarks/bench_zonotope.py``).  The ratio depends on the trace: on the
benchmark's two-cart trace window 40 ends at 1.0122 (1.0288 at worst) and window 50 (the default) at 1.0076
(1.011); on the 60-step runs of ``tests/test_exact_set.py`` (filtered hull over the exact hull, last step / worst)
window 50 gives 1.0000 / 1.0000 on the oscillator and the six-state plant, 1.0001 / 1.0039 on the two carts and
1.0003 / 1.0003 on the tank chain n = 4, against 1.0000 / 1.0000, 1.0000 / 1.0000, 1.0003 / 1.0235 and 1.0015 /
1.0030 at window 40.  Window 50 became the default once the rounding allowance of the window's rows followed the
true products (:mod:`eqrec.bounds.window_lp`, *Soundness*): the earlier allowance propagated magnitudes through
:math:`|A|` step by step, grew like :math:`\rho(|A|)^L` (above 1 on the six-state plant, although
:math:`\rho(A) = 0.9`) and took the last of its 60 steps to 1.33 times the exact hull at window 50 (1.0041 at
window 40); the new one is at most :math:`1.2\cdot 10^{-10}` of the bound there.  Carrying the constrained zonotope itself
(Scott et al.'s measurement and prediction are exact) needs a reduction of its constraints and generators; with
their variable elimination and the lifted Girard reduction the set drifted on that plant, so the window is used.

The prior: the filter's zonotope, or the earlier hull (``prior=``)
------------------------------------------------------------------
``prior="zonotope"`` (default) is the above.  The estimator's own earlier answer is a second outer set of
:math:`x(s_0)`: the hull it reported at step :math:`s_0 - 1` (its prediction, given the data before :math:`s_0`,
itself from the window before, and so on: a moving-horizon estimate whose arrival cost is that box).

* ``"zonotope+box"``: the filter's zonotope within that box,
  :math:`\{c_0 + G_0\varepsilon : \underline x(s_0) - c_0 \le G_0\varepsilon \le \overline x(s_0) - c_0\}`, ``n``
  ranged rows more per LP (:func:`eqrec.bounds.window_lp.window_set`, ``prior_rows``; the ends rounded outward);
* ``"box"``: the box alone, centre and radius rounded outward (:func:`_centre_radius`): ``n`` columns instead of
  the zonotope's ``order · n``, no rows.

Each contains :math:`x(s_0)`, so every end stays a guarantee (``tests/test_exact_set.py`` plays the noise back at
box corners with a window of 4 steps, where the box binds at every step).  The box pays where the filter's reduced
zonotope is far from the consistent set and the window is short; it loses the zonotope's correlations, which the
data of a long window recover.  Measured (``benchmarks/bench_zonotope.py``, process time on a loaded 2-core
machine; predicted hull over the exact hull of the whole horizon): tank chain n = 30, p = 5, 60 steps, at steps
29 / 59: ``"zonotope"`` window 50 (default) 1.00 / 1.19 at about 1 s per step, window 40 1.00 / 1.51 at 650-730 ms,
window 10 6.2 at step 59;
``"zonotope+box"`` window 10 1.20 / 1.10 (475 ms: 65 rows, HiGHS), window 15 1.07 / 1.05; ``"box"`` window 10
1.20 / 1.10 at 11.9 ms per step (35 rows, the dense solver), window 5 1.38 / 1.26 at 2.2 ms.  Again on an idle
machine (2026-11-30, one run, ``--exact-scale-priors box:10 box:15 box:20 zonotope+box:10``): the default 583 ms
per step (1.00 / 1.19), ``"box"`` window 10 6.9 ms (1.20 / 1.10), 15 84 ms (1.07 / 1.05), 20 103 ms (1.08 / 1.03),
``"zonotope+box"`` window 10 284 ms (1.20 / 1.10).  The box's LPs take many more pivots as the window grows (about
13 per LP at window 10, 87 at 15, 80 at 20: degenerate vertices), so ``prior="box", window=10`` is the setting for
large plants (issue 45 §4's 20 ms per step at n = 30).  On the n <= 6 plants at window 40 the box changes the
ratios in the third decimal or not at all (tanks n = 4, 150 steps: ``"zonotope+box"`` 1.0007 against 1.0011 at
the last step; two carts 1.0122 both), for ``n`` more rows per LP.

The default by size
-------------------
``prior=None`` (default) takes the zonotope (with :data:`EXACT_WINDOW` = 50 steps) below
:data:`EXACT_BOX_STATES` = 20 states and the box (with :data:`EXACT_WINDOW_BOX` = 10 steps) from 20 states on.
Measured on the tank chains (``benchmarks/bench_zonotope.py --part exact --exact-scale-n ... --exact-scale-priors
zonotope:50 box:15``, 60 steps, one run per size, 2026-11-30; ms per step, and the predicted hull over the exact
hull of the whole horizon at step 59; at step 29 the zonotope's window still reaches back to the exact initial box
and ends at 1.00 everywhere, the box's at 1.06-1.26):

======  ===  ===================  ===================  ===================
 n       p   zonotope, window 50  box, window 10       box, window 15
======  ===  ===================  ===================  ===================
 10      2   5.2 ms, 1.008        0.43 ms, 1.20        0.69 ms, 1.09
 14      2   11 ms, 1.052         0.46 ms, 1.20        -
 16      2   15 ms, 1.079         0.53 ms, 1.18        0.81 ms, 1.09
 18      3   52 ms, 1.079         1.1 ms, 1.16         2.3 ms, 1.070
 20      4   167 ms, 1.063        2.4 ms, 1.064        7.1 ms, 1.036
 24      4   233 ms, 1.134        3.3 ms, 1.139        11.6 ms, 1.065
 30      5   583-641 ms, 1.19     6.9-9.5 ms, 1.10     84 ms, 1.05
======  ===  ===================  ===================  ===================

Below 20 states the zonotope is the tighter once the window slides, at up to 52 ms per step; from 20 on the box
of window 10 is as tight (n = 20, 24) or tighter (n = 30) at 1/70 to 1/85 of the cost, which the zonotope's cost
(its ``4n`` columns per LP and their pivots) makes prohibitive (issue 45 §4: 20 ms per step at n = 30).  A window
of 15 for the box is tighter still from 16 states on, and cheap up to 24 (12 ms), but its LPs take many more pivots
at n = 30 (84 ms); pass ``window=15`` there where the cost allows.  The compare study's plants are small, so their
results are those of the zonotope prior.

Warm start across steps (``warm_start=``)
-----------------------------------------
Consecutive windows share most of their LP: the rows of the measurements of the common times and the columns of
their noises; only the prior's generators (the filter's reduced zonotope at the new window start) and the newest
and oldest times change.  With ``warm_start=True`` (default) the last basis of a step's ``2n`` LPs is kept with
the labels of its columns and rows (:func:`eqrec.bounds.window_lp.window_labels`); the next window's first LP
starts from it (:func:`eqrec.bounds.window_lp.carry_basis`: a noise column or measured row of a common time keeps
its status, the prior's columns and rows take the status of the previous prior's in the same place (a different
vector, but the filter's reduction keeps a similar order), a new row's slack is basic; the solver completes that to a
nonsingular basis, or falls back to the slack basis), and the order of the objectives alternates from one step to
the next (maxima first, then minima first) so that the first objective of a window is the last of the previous
one.  With boxed variables any nonsingular basis is dual feasible once each nonbasic variable sits at the bound
its reduced cost asks for, so any start is valid and a poor one costs pivots only; the ends stay the weak-duality
bounds of the multipliers found (``tests/test_exact_set.py`` replaces the carried basis by a random one at every
step).  The carried basis is part of the estimator's state (pickled with it, dropped by :meth:`reset`, set only
by a step that completes).  The ends differ from the slack-basis start's only where the optimum is degenerate or
within the solver's tolerances (measured against the code before it, window 40, 150 steps of the
benchmark's plants: at most 3e-10 of the hull's width on the two carts, 8e-9 on tanks n = 4, 1.3e-7 on tanks
n = 6).  :attr:`lp_pivots` counts the pivots.

Estimate, bound, and what that means for ``exact_bound``
--------------------------------------------------------
The estimate :math:`\hat x(t+1)` is the centre of the hull, per state the midpoint of its two ends.  The ends
are LP optima in the measured values, so the estimate is **not linear in the data**: it is piecewise linear,
the pieces chosen by the LPs' optimal bases.  Its bound (the hull's half-width, per state) is a set-membership
guarantee: for every initial state in the box and every noise in the box the true state lies in the consistent
set, so inside the hull, so within the half-width of the centre.  It depends on the data (it can be below the
information limit, which is the worst case over all data).  :func:`eqrec.exact_bound`, which carries a *linear*
estimator's error zonotope and plays back the sign vertex of its error map, does not apply: the exact estimator
has no error map, and its worst case over the noise is not at a known vertex.  Its own bound is already the
guarantee ``exact_bound`` would give a linear estimator, and is checked by playing back the noise at random box
corners (every run must satisfy ``error <= bound``).

Delays and losses follow :class:`~eqrec.estimators.zonotope.ZonotopeEstimator`: a packet up to ``max_delay``
steps late is used at its own time (the window has at least ``max_delay + 1`` steps), an older one is dropped
and counted; a step that raises changes nothing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from eqrec.bounds.window_lp import carry_basis, lp_hull_solve, window_labels, window_set
from eqrec.errors import InputError
from eqrec.estimators.protocol import StateSet
from eqrec.estimators.zonotope import ZonotopeEstimator
from eqrec.systems.affine import AffineSystem

#: Default window of :class:`ExactSetEstimator` in steps with the filter's zonotope as its prior (at least
#: ``max_delay + 1`` are used).
EXACT_WINDOW = 50

#: The size (states) from which the default prior is the box (module docstring, *The default by size*).
EXACT_BOX_STATES = 20

#: Default window with the box prior (``prior="box"``; module docstring, *The prior*): the box pays where the
#: window is short, and the LPs of longer windows of the box take many more pivots.
EXACT_WINDOW_BOX = 10

#: The window's priors of :class:`ExactSetEstimator` (module docstring, *The prior*).
EXACT_PRIORS = ("zonotope", "zonotope+box", "box")

#: Default order of the filter's zonotope at the window's start (generators per state).
EXACT_ORDER = 4


class ExactSetEstimator(ZonotopeEstimator):
    r"""Set-membership estimator reporting the interval hull of the set consistent with the data (module docstring).

    Follows the estimator protocol (:mod:`eqrec.estimators.protocol`): :meth:`reset`, then one :meth:`step` per
    time with what arrived and the input, returning the hull's centre :math:`\hat x(t+1)` and the largest
    half-width; :attr:`state_bounds` per state, :attr:`predicted` and :attr:`filtered` as
    :class:`~eqrec.estimators.protocol.StateSet` (their ``generators`` are ``None``: the set is a constrained
    zonotope, reported by its hull).

    Parameters
    ----------
    system : AffineSystem
        The plant.
    x0_radius : float or array_like, shape (n,)
        Radius of the initial box around ``xhat0``.
    max_delay : int, optional
        ``D >= 0``: packets up to ``D`` steps late are used at their own time; older ones are dropped.
    order : float, optional
        Generators per state kept by the filter whose zonotope is the window's prior (default
        :data:`EXACT_ORDER`).
    window : int or None, optional
        Steps of the window solved with its data (at least ``max_delay + 1`` are used); default ``None``:
        :data:`EXACT_WINDOW` = 50 with the zonotope prior, :data:`EXACT_WINDOW_BOX` = 10 with the box alone.
    gain : str, optional
        The filter's gain (``"reweighted"``, default, or ``"fradius"``; one filter).
    reduction : {"pca", "girard"}, optional
        The filter's order reduction.
    prior : {"zonotope", "zonotope+box", "box"} or None, optional
        The window's prior (module docstring, *The prior*): the filter's zonotope, the zonotope within the box of
        the hull this estimator reported for the window's start, or that box alone.  Default ``None``, by the
        plant's size: ``"zonotope"`` below :data:`EXACT_BOX_STATES` = 20 states, ``"box"`` from 20 on (module
        docstring, *The default by size*).  The values used are the attributes ``prior``
        and ``window``.
    warm_start : bool, optional
        Start each window's LPs from the last basis of the previous window's, carried over by label (module
        docstring, *Warm start across steps*; default ``True``); ``False``: from the slack basis at every step.

    Attributes
    ----------
    kind : str
        ``"guaranteed"``.
    name : str
        ``"set-membership, exact"``.
    lp_fallbacks : int
        Hull LPs since :meth:`reset` that ended without an optimum (their end was the bound of the multipliers the
        solve ended with, still a guarantee).
    lp_pivots : int
        Simplex pivots (and HiGHS iterations) of the hull LPs since :meth:`reset`, the filtered set's included.
    lp_warm_starts : int
        Steps since :meth:`reset` whose LPs started from the previous window's basis (the others: from the slack
        basis, the first step, or a carried basis that was singular).

    Raises
    ------
    InputError
        As :class:`~eqrec.estimators.zonotope.ZonotopeEstimator` (the field is named); several gains; a
        ``prior`` not in :data:`EXACT_PRIORS`.

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> carts = eqrec.two_mass()
    >>> est = eqrec.ExactSetEstimator(carts, x0_radius=0.5, max_delay=2).reset(np.zeros(4))
    >>> xhat, bound = est.step(np.array([0.1]))
    >>> xhat, bound = est.step(None)
    >>> bool(np.all(est.filtered.lower <= est.filtered.upper)), est.predicted.time, est.filtered.time
    (True, 2, 1)
    """

    kind = "guaranteed"
    name = "set-membership, exact"

    def __init__(self, system: AffineSystem, x0_radius: Any = 1.0, max_delay: int = 0, order: float = EXACT_ORDER,
                 window: "int | None" = None, gain: str = "reweighted", reduction: str = "pca",
                 prior: "str | None" = None, warm_start: bool = True):
        if order is None:
            raise InputError("the exact estimator needs a reduction order (a number >= 1), got None", field="order")
        if not isinstance(gain, str):
            raise InputError(f"the exact estimator runs one filter: gain is one name, got {gain!r}", field="gain")
        if prior is None:  # by the plant's size (module docstring, *The default by size*)
            n = system.n if isinstance(system, AffineSystem) else 0  # (a bad system is refused below)
            prior = "zonotope" if n < EXACT_BOX_STATES else "box"
        if not isinstance(prior, str) or prior not in EXACT_PRIORS:
            raise InputError(f"the window's prior is None (by the plant's size) or one of {', '.join(EXACT_PRIORS)}, "
                             f"got {prior!r}", field="prior")
        if window is None:
            window = EXACT_WINDOW_BOX if prior == "box" else EXACT_WINDOW
        super().__init__(system, x0_radius, max_delay, order=order, gain=gain, reduction=reduction, window=window)
        self.prior = prior
        self.warm_start = bool(warm_start)
        self._lp_carry = None
        self.lp_fallbacks = self.lp_pivots = self.lp_warm_starts = 0

    def start_from(self, xhat0: Any, generators: Any, t0: int = 0) -> "ExactSetEstimator":
        """Start a run from a given set (:meth:`ZonotopeEstimator.start_from`).

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            Centre.
        generators : array_like, shape (n, q)
            Generators of the initial error set.
        t0 : int, optional
            Absolute time of the first step.

        Returns
        -------
        ExactSetEstimator
            ``self``.
        """
        super().start_from(xhat0, generators, t0)
        self._drive_mag = np.zeros((0, self.system.n))  # |B||u| + |f| of the window's times (_intake)
        self._ws = None
        start = StateSet.around(self.time, self._xhat, self._beta)
        self._lower, self._upper = start.lower, start.upper
        self._boxes = {}
        self._lp_carry = None
        self.lp_fallbacks = self.lp_pivots = self.lp_warm_starts = 0
        return self

    def _intake(self, packets: list, u: np.ndarray) -> dict:
        """:meth:`ZonotopeEstimator._intake`, with the magnitudes :math:`|B||u| + |f|` of the window's drives: the
        drive :math:`Bu + f` is computed in floating point, and its rounding is bounded by these, not by the drive
        (:mod:`eqrec.bounds.window_lp`, *Soundness*); nothing changed."""
        intake = super()._intake(packets, u)
        sysm = self.system
        mag = np.abs(sysm.B_at(self._model_time(intake["t"]))) @ np.abs(u) + np.abs(sysm.f)
        intake["drive_mag"] = np.concatenate([self._drive_mag, mag[None]])[-intake["drive"].shape[0]:]
        return intake

    def _estimate(self, intake: dict) -> tuple[np.ndarray, np.ndarray, dict]:
        """The window's hull of ``x(t+1)`` with the data (module docstring); nothing changed."""
        first, drive = intake["first"], intake["drive"]
        A, C, E, V = self._window_model(first, drive.shape[0])
        sets = intake["carried"]
        c0, G0 = sets["c"][0], sets["G"][0]
        box = self._boxes.get(first) if self.prior != "zonotope" else None
        rows = None
        if box is not None and self.prior == "box":  # the box alone: centre and radius rounded outward
            c0, radius = _centre_radius(*box)
            G0 = np.diag(radius)
        elif box is not None:  # the filter's zonotope within the box: G0 ε in [lower - c0, upper - c0]
            rows = (G0, np.nextafter(box[0] - c0, -np.inf), np.nextafter(box[1] - c0, np.inf))
        ws = window_set(A, C, E, V, drive, intake["known"], intake["ys"], c0, G0, rows,
                        drive_magnitude=intake["drive_mag"], drive_terms=self.system.m + 1)
        start, minima_first, labels = None, False, None
        if self.warm_start:  # the last basis of the previous window's LPs, carried over by label (module docstring)
            sysm = self.system
            labels = window_labels(first, intake["known"], sysm.p, sysm.nw, sysm.nv, G0.shape[1],
                                   0 if rows is None else rows[0].shape[0])
            if self._lp_carry is not None:
                old_labels, old_basis, old_minima_first = self._lp_carry
                start = carry_basis(old_labels, old_basis, labels)
                minima_first = not old_minima_first  # the first objective is the previous window's last
        hull = lp_hull_solve(ws, "pred", start=start, minima_first=minima_first)
        lower, upper = hull.lower, hull.upper
        xhat, beta = _centre_radius(lower, upper)
        carry = None if hull.basis is None or not self.warm_start else (labels, hull.basis, hull.minima_first)
        extra = {"_ws": ws, "_lower": lower, "_upper": upper, "lp_fallbacks": self.lp_fallbacks + hull.fallbacks,
                 "lp_pivots": self.lp_pivots + hull.pivots, "lp_warm_starts": self.lp_warm_starts + hull.warm,
                 "_lp_carry": carry, "_drive_mag": intake["drive_mag"]}
        if self.prior != "zonotope":  # the hulls of the times still to start a window (a new dict: the step stays atomic)
            boxes = {s: b for s, b in self._boxes.items() if s > first}
            boxes[intake["t"] + 1] = (lower, upper)
            extra["_boxes"] = boxes
        return xhat, beta, extra

    @property
    def carried_set(self) -> tuple[np.ndarray, np.ndarray]:
        """The hull as a zonotope: centre :attr:`x` and ``diag(state_bounds)`` (copies).

        Returns
        -------
        tuple of numpy.ndarray
            ``(x̂, diag(β))``.
        """
        self.time  # noqa: B018 - raises before reset
        return self._xhat.copy(), np.diag(self._beta)

    @property
    def predicted(self) -> StateSet:
        """The hull of ``x(t+1)`` given the data up to ``t`` (right after :meth:`reset`: the initial box).

        Returns
        -------
        StateSet
            Centre, bounds; ``generators`` ``None``.
        """
        t1 = self.time
        return StateSet(t1, self._xhat.copy(), self._lower.copy(), self._upper.copy(), None)

    @property
    def filtered(self) -> StateSet:
        """The hull of ``x(t)`` given the data up to ``t``: the last window's LPs for ``x(t)`` (computed on the
        first request after a step, then kept).

        Returns
        -------
        StateSet
            Centre, bounds; ``generators`` ``None``.

        Raises
        ------
        InputError
            Before :meth:`reset`, or right after it (no data yet).
        """
        t1 = self.time
        if self._ws is None:
            raise InputError("no step since reset: the filtered set needs the data of one step", field="filtered")
        if self._filtered is None:
            start, minima_first = None, False
            if self._lp_carry is not None:  # the same LP as the step's: start from its last basis
                _, start, step_minima_first = self._lp_carry
                minima_first = not step_minima_first
            hull = lp_hull_solve(self._ws, "filt", start=start, minima_first=minima_first)
            lower, upper = hull.lower, hull.upper
            self.lp_fallbacks += hull.fallbacks
            self.lp_pivots += hull.pivots
            centre, _ = _centre_radius(lower, upper)
            self._filtered = StateSet(t1 - 1, centre, lower, upper, None)
        return self._filtered


def _centre_radius(lower: np.ndarray, upper: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The midpoint of ``[lower, upper]`` and a radius ``>=`` both distances to the ends (rounded upward)."""
    centre = 0.5 * lower + 0.5 * upper
    # an empty hull (lower > upper: data inconsistent with the model) gets radius 0 at its midpoint
    radius = np.nextafter(np.maximum(np.maximum(upper - centre, centre - lower), 0.0), np.inf)
    radius = np.nextafter(radius + 2 * np.finfo(float).eps * (np.abs(upper) + np.abs(lower)), np.inf)
    return centre, radius
