r"""The exact run-time bound of any linear estimator of the protocol: :func:`exact_bound`.

Given the arrivals, every estimator of the package is affine in the initial
estimate, the inputs and the measurements, so its error
:math:`\xi(t) = x(t) - \hat x(t)` is affine in the uncertainty
:math:`\delta = (\xi(t_0), w, v)`:

.. math:: \xi(t) = c(t) + G(t)\,\delta, \qquad
    \max_{|\delta| \le r} |\xi_i(t)| = |c_i(t)| + \sum_j |G_{ij}(t)|\, r_j .

:func:`exact_bound` wraps an estimator and returns, with each estimate, that
worst case (the infinity norm over the states, and :attr:`ExactBound.state_bounds`),
in one of two ways:

* **Error maps** (estimators that say their error: ``linear_error_model()``,
  or ``error_map()`` for the class form
  :class:`eqrec.estimators.causal.ClassEstimator`): after each step the
  estimator gives either how its error depends on an earlier error and the
  noise since (:class:`eqrec.bounds.zonotope.ErrorMap`), and
  :class:`eqrec.bounds.zonotope.ErrorSet` carries the zonotope, reduced to
  ``order · n`` generators if ``order`` is given (outer, so still a
  guarantee); or the generators of the error set of the current estimate
  itself, which become the carried set (a set-membership estimator's:
  :meth:`eqrec.estimators.zonotope.ZonotopeEstimator.linear_error_model`, and
  :meth:`eqrec.estimators.guaranteed.GuaranteedEstimator.linear_error_model`
  outside the design with ``strict=False``; a return to the design anchors
  the next maps at the period start, where that set was the last one given).
  That is the whole interface (an estimator with
  ``has_linear_error_model = False``, the node-gain
  ``GuaranteedEstimator``, is run as copies).  ``c = 0``: these estimators are
  unbiased.  On a set-membership estimator the bound is its own (its initial
  box is its own ``x0_radius``): at least the worst case measured by unit
  perturbations at every step, and within ``4e-14 .. 4e-10`` relative of it
  while the filters keep every generator (measured on the cart-pole of
  ``tests/test_exact_bound_total.py`` at 20-40 % loss, in and out of the
  design with ``strict=False``); an outer reduction of the filters' sets
  (small ``order``) makes it larger than the estimator's exact worst case
  (up to 1.7 times with window 5 and order 3).  Running such an estimator as
  copies (earlier versions) was off by up to ``6.5e-6`` relative, below and
  above: its window weights depend on the data through the filters'
  rounding generators (sized by the data), and its discrete choices (the
  extra solves, the filter picked per state, the reduction's order) amplify
  that, so the copies' differences are not the responses of one linear map.
* **Columns** (the filters of :mod:`eqrec.estimators.kalman`, whose ``reset``
  takes an ``(n, K)`` estimate and a ``one`` vector): the wrapper runs the
  estimator once on *affine data*, arrays whose columns are, in order, the
  data actually received, the nominal data (no noise, ``x(t0) = x̂(t0)``) and
  the coefficient of each entry of ``δ`` (``steps`` steps of ``w`` and ``v``
  allocated at :meth:`ExactBound.reset`); it simulates the same columns of
  the true state.  Column 0 is the estimate; the nominal column gives ``c``
  (a filter that reads a late packet as a measurement of the present is
  biased: ``c ≠ 0``); the others give ``G``.  Exact, with no reduction: the
  cost of a step grows with the number of steps allocated.
* **Copies** (any other estimator of the protocol: the node-gain
  :class:`eqrec.estimators.causal.RecoveryEstimator`, the
  :class:`eqrec.estimators.switching.SwitchingEstimator`, the
  :class:`eqrec.estimators.augmented.AugmentedEstimator`): the same columns,
  each run on its own copy of the estimator with ordinary data.  Copy 0 gets
  the data received, copy 1 the nominal data, copy ``j >= 2`` the nominal
  data plus the coefficients of entry ``j`` of ``δ``; since the estimator is
  affine, ``x̂_j − x̂_1`` is the response to that entry alone (the inputs and
  ``f`` cancel).  Copy 0 steps first, so a step it refuses changes nothing.
  The cost of a step is that of the estimator times the number of columns.

All three are exact: the bound equals the largest error of the wrapped estimator
over every noise in the box and every initial error within ``x0_radius``,
given the arrivals (up to the reduction), rounded outward in floating point.

**Floating point** (:mod:`eqrec.bounds.rounding`).  The bound covers the
rounding of the estimate and of a simulated true state: the wrapped
estimator's own allowance (``rounding_vector``: the causal estimators of
:mod:`eqrec.estimators.intake`, told the error's size through
``error_radius``) is added to the exact worst case; in a column or copy run,
the rounding of the true columns (propagated with ``|A|``, so it grows with
the steps allocated) and, for copies, every copy's allowance (a column is a
difference of two copies).  The filters run on columns
(:mod:`eqrec.estimators.kalman`, the LMV filters of :mod:`eqrec.lmv.estimator`)
are given the formula at ``reset(..., allowance=)`` and carry the rounding of
their own arithmetic, summed over the columns (``rounding_vector``: each
column's products and sums within the standard bound of their magnitudes,
carried to the current estimate by the filter's later maps: the Kalman filters
by the absolute value of their product since each rounding, the LMV filters by
``|A − L C|`` step by step); a column is one affine coefficient of ``δ``, so the
sum bounds the rounding of the estimate and of the map ``c + G δ`` at once.
Measured on the plants of ``tests/test_rounding_filters.py`` (three tanks, a
cart-pole; a state about 30 times the noise): ``5e-14 .. 1.5e-12`` of the
bound plus the estimate's size, ``2e-13 .. 1.4e-10`` of the bound alone; on
the compare study's batch reactor at most ``1.5e-11`` of the bound (carrying
the Kalman filters' bound by ``|A|`` and ``|I − K C|`` step by step instead
gave up to ``3.4e-4`` there: the absolute values ignore the cancellations of
an unstable, signed plant).  A refused step or reset changes nothing (the size given to the
estimator is restored).
"""

from __future__ import annotations

import copy
import inspect
from typing import Any, NamedTuple

import numpy as np

from eqrec.arrivals.packets import Packet, as_packets, check_estimate, check_input, checked_columns, in_scale_array
from eqrec.bounds.rounding import UNIT_ROUNDOFF, rounding_allowance
from eqrec.bounds.zonotope import ErrorMap, ErrorSet, check_order, outer_row_sums
from eqrec.checks import check_allocation, integer, radii
from eqrec.errors import InputError
from eqrec.systems.affine import AffineSystem


def _allowance(bound: Any, terms: float, magnitude: Any) -> Any:
    """:func:`eqrec.bounds.rounding.rounding_allowance`, the same numbers with two operations fewer for the float
    ``bound = 0.0`` of the allowance alone (a magnitude is a sum of absolute values, at least ``+0``, so adding
    ``0.0`` to it or to its multiple changes no bit)."""
    if type(bound) is float and bound == 0.0:
        return np.nextafter(4.0 * terms * UNIT_ROUNDOFF * magnitude, np.inf)
    return rounding_allowance(bound, terms, magnitude)


class _TrueStep(NamedTuple):
    """One step of the true columns of a column or copy run (:meth:`ExactBound._simulate_truth`)."""

    u: bytes  #: the input of the step, as bytes (a trail is followed while the inputs are the same)
    sent: np.ndarray  #: the columns of ``y(t)`` sent at ``t``
    in_scale: bool  #: whether they are in scale (:func:`eqrec.arrivals.packets.in_scale_array`)
    truth: np.ndarray  #: the columns of ``x(t+1)``
    truth_dev: np.ndarray  #: the rounding of the true columns, summed over them


class ExactBound:
    r"""A linear estimator with its exact worst-case bound at every step (module docstring).

    Parameters
    ----------
    estimator : object
        An estimator of the protocol: with ``error_map()``, one that runs on columns
        (``reset(xhat0, t0, one=...)`` with ``(n, K)`` estimates), or any other (run as copies).
    system : AffineSystem
        The true system (its noise bounds are the box).
    x0_radius : float or array_like
        Bound on the initial error, one number or one per state.
    order : float or None, optional
        Reduction order of the error set (error-map estimators only; ``None``: exact).
    steps : int or None, optional
        Steps allocated for a column or copy run (required unless the estimator has ``error_map()``).
    truths : dict or None, optional
        Shared by the column or copy runs that simulate the same true columns (:func:`exact_bound`): each step of
        the true columns is computed once per start (system, ``x̂(t0)``, ``t0``, columns, ``x0_radius``) and
        inputs, and read back by the other runs (the same numbers).  ``None``: computed here.

    Attributes
    ----------
    kind : str
        ``"guaranteed"``.
    name : str
        The wrapped estimator's name with ``", exact bound"``.
    bound : float
        The bound of the current estimate.
    """

    kind = "guaranteed"

    def __init__(self, estimator: Any, system: AffineSystem, x0_radius: Any, order: "float | None" = None,
                 steps: "int | None" = None, truths: "dict | None" = None):
        if not isinstance(system, AffineSystem):
            raise InputError(f"expected an AffineSystem, got {type(system).__name__}", field="system")
        self.estimator, self.system = estimator, system
        self.x0_radius = radii(x0_radius, system.n)
        self.order = check_order(order)
        self.name = f"{getattr(estimator, 'name', type(estimator).__name__)}, exact bound"
        if callable(self._model_hook()) and getattr(estimator, "has_linear_error_model", True):
            self.mode = "maps"
        elif not callable(getattr(estimator, "reset", None)) or not callable(getattr(estimator, "step", None)):
            raise InputError("the estimator follows no protocol: it has neither error_map() nor reset() and "
                             "step()", field="estimator")
        else:
            self.mode = "columns" if "one" in inspect.signature(estimator.reset).parameters else "copies"
        if self.mode != "maps":
            if steps is None:
                raise InputError("a column or copy run needs the number of steps to allocate (an integer >= 1)",
                                 field="steps")
            integer(steps, "steps", low=1)
            # a column run holds n x (2 + n + steps (nw + nv)) numbers per column set: refused past the memory
            K = 2 + system.n + int(steps) * (system.nw + system.nv)
            check_allocation(8.0 * K * (system.n + 4), "steps", f"an exact-bound run of {int(steps)} steps")
        self.steps = None if steps is None else int(steps)
        self.truths = truths
        self._trail: "list[_TrueStep] | None" = None
        self.bound = np.nan
        self._bounds = np.full(system.n, np.nan)
        self._set: ErrorSet | None = None

    # -- protocol ---------------------------------------------------------------------------------------------
    def reset(self, xhat0: Any, t0: int = 0) -> "ExactBound":
        """Start the wrapped estimator at ``x̂(t0) = xhat0``; the initial error is within ``x0_radius``.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            Initial estimate.
        t0 : int, optional
            Absolute time of the first step.

        Returns
        -------
        ExactBound
            ``self``.

        Raises
        ------
        InputError
            What the wrapped estimator refuses.
        """
        self.bound = float(self.x0_radius.max())  # a raw causal estimator's allowance: the initial error's size
        try:
            return self._sized(lambda: self._reset(xhat0, t0), [self.estimator])
        except Exception:
            self.bound = float(self._bounds.max()) if np.all(np.isfinite(self._bounds)) else np.nan
            raise

    def _reset(self, xhat0: Any, t0: int) -> "ExactBound":
        n, sysm = self.system.n, self.system
        if self.mode == "maps":
            self.estimator.reset(xhat0, t0)
            self._set = ErrorSet.box(self.x0_radius, n, int(t0), self.order)
        else:
            x = check_estimate(xhat0, n)
            K = 2 + n + self.steps * (sysm.nw + sysm.nv)
            one = np.zeros(K)
            one[:2] = 1.0
            if self.mode == "columns":
                X = np.zeros((n, K))
                X[:, 0] = X[:, 1] = x
                if "allowance" in inspect.signature(self.estimator.reset).parameters:  # it carries its rounding
                    self.estimator.reset(X, t0, one=one, allowance=_allowance)
                else:
                    self.estimator.reset(X, t0, one=one)
            else:  # copy 0 is the estimator itself; every copy starts at x̂(t0) (the nominal start)
                self.estimator.reset(x, t0)
                self._copies = [copy.deepcopy(self.estimator) for _ in range(K - 1)]
            truth = np.zeros((n, K))  # the true state's columns (column 0 unknown: left at zero, never read)
            truth[:, 1] = x
            truth[:, 2:2 + n] = np.diag(self.x0_radius)
            self._truth, self._one, self._K, self._t0 = truth, one, K, int(t0)
            self._one_sum = np.abs(one).sum()
            self._truth_dev = np.zeros(n)  # the rounding of the true columns, summed over them (module docstring)
            self._sent: dict[int, np.ndarray] = {}
            self._scaled: dict[int, bool] = {}
            self._trail = self._shared_trail(x, int(t0), K)
        self._bounds = self.x0_radius.copy()
        self.bound = float(self._bounds.max())
        return self

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        return self.estimator.time

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate."""
        x = self.estimator.x
        return x[:, 0].copy() if x.ndim == 2 else x

    @property
    def state_bounds(self) -> np.ndarray:
        """Per-state exact worst case of the current estimate's error."""
        return self._bounds.copy()

    def step(self, y: Any = None, u: Any = None) -> tuple[np.ndarray, float]:
        """Step the wrapped estimator; return its estimate and the exact worst case of its error.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            What arrived (any protocol form).
        u : array_like or None, optional
            The input.

        Returns
        -------
        xhat : ndarray, shape (n,)
            The wrapped estimator's estimate.
        bound : float
            ``max_i`` of :attr:`state_bounds`.

        Raises
        ------
        InputError
            What the wrapped estimator refuses; a column run past its allocated steps.
        """
        if self.mode == "maps":
            xhat = self._map_step(y, u)
        elif self.mode == "copies":
            xhat = self._sized(lambda: self._column_step(y, u), [self.estimator] + self._copies)
        else:
            xhat = self._column_step(y, u)
        self.bound = float(self._bounds.max())
        return xhat, self.bound

    def _sized(self, run: Any, estimators: list) -> Any:
        """``run()`` with each raw causal estimator told the error's size (its allowance's magnitudes; restored
        if ``run`` raises, so a refused step changes nothing)."""
        sized = [e for e in estimators if hasattr(e, "error_radius")]
        kept = [e.error_radius for e in sized]
        for e in sized:
            e.error_radius = self.bound
        try:
            return run()
        except Exception:
            for e, r in zip(sized, kept):
                e.error_radius = r
            raise

    def _model_hook(self) -> Any:
        """The estimator's ``linear_error_model`` (or, for the class form, ``error_map``), if any."""
        hook = getattr(self.estimator, "linear_error_model", None)
        return hook if callable(hook) else getattr(self.estimator, "error_map", None)

    def _map_step(self, y: Any, u: Any) -> np.ndarray:
        """A step of an estimator that says its error (module docstring): an anchored map advances the carried
        set, generators replace it; the estimator's rounding allowance is added, and the sum rounded up."""
        est = self.estimator
        xhat, _ = self._sized(lambda: est.step(y, u), [est])
        model = self._model_hook()()
        if isinstance(model, ErrorMap):
            bounds = self._set.advance(model)
        else:  # the error set of the current estimate itself (a set-membership estimator's)
            G = np.asarray(model, dtype=float)
            bounds = outer_row_sums(G)
            self._set = ErrorSet(G, est.time, self.order)
        rho = getattr(est, "rounding_vector", None)
        self._bounds = bounds if rho is None else np.nextafter(bounds + rho, np.inf)
        return xhat

    def _noise_blocks(self, t: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """``V(t) diag(η_v)``, ``E(t) diag(η_w)``, the row sums of ``|E(t) diag(η_w)|`` (``None`` past two noise
        entries) and ``|A(t)|``: the nonzero blocks of the noise columns of a step, made once on a time-invariant
        system.

        Each entry of ``V(t) @ v_cols`` (``v_cols`` zero but its block ``diag(η_v)``) is one product plus exact
        zeros, so the block alone gives the same numbers (the sign of a zero aside, which no bound or estimate
        reads: the columns enter through absolute values and column-wise maps only).  A row sum of ``|E w_cols|``
        with at most two nonzero terms is the same float in any order of summation.
        """
        cached = getattr(self, "_blocks", None)
        if cached is not None:
            return cached
        sysm = self.system
        eye_v, eye_w = sysm.eta_v * np.eye(sysm.nv), sysm.eta_w * np.eye(sysm.nw)
        Ew = sysm.E_at(t) @ eye_w
        blocks = (sysm.V_at(t) @ eye_v, Ew, np.abs(Ew).sum(axis=1) if sysm.nw <= 2 else None,
                  np.abs(sysm.A_at(t)))
        if not sysm.is_time_varying:
            self._blocks = blocks
        return blocks

    def _shared_trail(self, xhat0: np.ndarray, t0: int, K: int) -> "list[_TrueStep] | None":
        """The steps of the true columns already simulated from this start by a run sharing :attr:`truths` (the
        list this run extends), or ``None`` without ``truths``."""
        if self.truths is None:
            return None
        key = (id(self.system), xhat0.tobytes(), t0, K, self.x0_radius.tobytes())
        entry = self.truths.setdefault(key, (self.system, []))  # the system kept alive: its id stays its own
        return entry[1]

    def _true_step(self, t: int, k: int, u: np.ndarray) -> "_TrueStep":
        """Step ``k`` (time ``t``, input ``u``) of the true columns: from the shared trail where a run with the same
        start and the same inputs simulated it already, else simulated here (and added to the trail)."""
        trail, key = self._trail, u.tobytes()
        if trail is not None and len(trail) > k:
            if trail[k].u == key:
                return trail[k]
            self._trail = trail = None  # other inputs: this run's true columns are its own from here on
        found = self._simulate_truth(t, k, u, key)
        if trail is not None and len(trail) == k:
            trail.append(found)
        return found

    def _simulate_truth(self, t: int, k: int, u: np.ndarray, key: bytes) -> "_TrueStep":
        """The columns of ``y(t) = C x(t) + V v(t)`` sent at ``t``, whether they are in scale, and the true columns
        of ``x(t+1)`` with their rounding (module docstring)."""
        sysm = self.system
        nw, nv, n = sysm.nw, sysm.nv, sysm.n
        base = 2 + n + k * (nw + nv)
        v_block, w_block, w_sums, absA = self._noise_blocks(t)
        sent_t = sysm.C_at(t) @ self._truth
        sent_t[:, base + nw: base + nw + nv] += v_block  # V v(t): its block
        drive = sysm.B_at(t) @ u + sysm.f
        truth = sysm.A_at(t) @ self._truth + np.outer(drive, self._one)
        truth[:, base: base + nw] += w_block  # + E w(t): its block
        if w_sums is None:  # more than two noise entries: the row sums of |E w_cols| in the order of the full row
            w_cols = np.zeros((n, self._K))
            w_cols[:, base: base + nw] = w_block
            w_sums = np.abs(w_cols).sum(axis=1)
        fresh = absA @ np.abs(self._truth[:, 1:]).sum(axis=1) + np.abs(drive) * self._one_sum + w_sums
        truth_dev = absA @ self._truth_dev + _allowance(0.0, n + sysm.nw + sysm.m + 2, fresh)
        for array in (sent_t, truth, truth_dev):  # shared by the runs of a trail: read only
            array.flags.writeable = False
        return _TrueStep(key, sent_t, in_scale_array(sent_t), truth, truth_dev)

    def _column_step(self, y: Any, u: Any) -> np.ndarray:
        sysm, t = self.system, self.time
        k = t - self._t0
        if k >= self.steps:
            raise InputError(f"the column run was allocated {self.steps} steps (exact_bound(..., steps=))",
                             field="steps")
        packets = as_packets(y, t, sysm.p)
        u = check_input(u, sysm.m)
        true = self._true_step(t, k, u)
        # the columns of y(t) = C x(t) + V v(t), sent now and read when its packet arrives
        sent = dict(self._sent)
        sent[t] = true.sent
        scaled = dict(self._scaled)  # the stamps whose columns are in scale (the reader's checks, made once)
        if true.in_scale:
            scaled[t] = True
        cols = []
        for pk in packets:
            if pk.time not in sent:
                raise InputError(f"a packet stamped {pk.time} before the run started at {self._t0}", field="y")
            Y = sent[pk.time].copy()
            Y[:, 0] = pk.y
            cols.append(Packet(pk.time, Y))
        if all(pk.time in scaled for pk in cols):  # column 0 read above: marked as checked (else the reader refuses)
            cols = checked_columns([(pk.time, pk.y) for pk in cols], t, (sysm.p, self._K))
        if self.mode == "columns":
            xhat_cols, _ = self.estimator.step(cols, u)
        else:
            xhat_cols = self._copies_step(cols, u)
        err = true.truth[:, 1:] - xhat_cols[:, 1:]
        # the rounding of the columns: the true ones' (propagated with |A|), the copies' own allowances
        self._truth, self._sent, self._truth_dev, self._scaled = true.truth, sent, true.truth_dev, scaled
        slack = true.truth_dev + _allowance(0.0, 1, np.abs(err).sum(axis=1)) + self._copies_rounding() \
            + self._columns_rounding()
        self._bounds = np.nextafter(outer_row_sums(err) + slack, np.inf)
        return xhat_cols[:, 0].copy()

    def _columns_rounding(self) -> np.ndarray:
        """A column run's own rounding, summed over the columns (the filter's ``rounding_vector``; zero for a
        column estimator that carries none, and for copies)."""
        rho = getattr(self.estimator, "rounding_vector", None) if self.mode == "columns" else None
        return np.zeros(self.system.n) if rho is None else rho

    def _copies_rounding(self) -> np.ndarray:
        """Copy 0's allowance, plus for each other copy its own and copy 1's (its column is a difference)."""
        n = self.system.n
        if self.mode != "copies":
            return np.zeros(n)
        rho = [getattr(e, "rounding_vector", None) for e in [self.estimator] + self._copies]
        if any(r is None for r in rho):
            return np.zeros(n)
        return rho[0] + sum(rho[2:], np.zeros(n)) + (len(rho) - 1) * rho[1]

    def _copies_step(self, cols: list, u: np.ndarray) -> np.ndarray:
        """The columns of the estimate from the copies (module docstring): ``(n, K)``, column 1 nominal."""
        x0, _ = self.estimator.step([Packet(pk.time, pk.y[:, 0]) for pk in cols], u)  # raises first, if at all
        out = np.empty((self.system.n, self._K))
        out[:, 0] = x0
        for j, est in enumerate(self._copies, start=1):
            data = [Packet(pk.time, pk.y[:, j] + (pk.y[:, 1] if j > 1 else 0.0)) for pk in cols]
            out[:, j] = est.step(data, u)[0]
        out[:, 2:] -= out[:, 1:2]  # the response to entry j alone (the estimator is affine)
        return out


def exact_bound(estimator: Any, system: AffineSystem, x0_radius: Any, order: "float | None" = None,
                steps: "int | None" = None, truths: "dict | None" = None) -> ExactBound:
    r"""Give a linear estimator of the protocol its exact worst-case bound at every step (module docstring).

    Parameters
    ----------
    estimator : object
        The estimator (not yet reset): one with ``error_map()`` (the class form), one that runs on
        columns (the Kalman-type filters of :mod:`eqrec.estimators.kalman`), or any other linear estimator of
        the protocol (run as copies: the node-gain, switching and augmented estimators).
    system : AffineSystem
        The true system; its noise box and ``x0_radius`` are the uncertainty.
    x0_radius : float or array_like
        Bound on ``|ξ(t0)|``, one number or one per state.
    order : float or None, optional
        Outer reduction of the error set to ``order · n`` generators (error-map estimators).
    steps : int or None, optional
        Steps to allocate for a column or copy run.
    truths : dict or None, optional
        One dict given to the column or copy runs of several estimators on the same uncertainty (the same system,
        ``x0_radius``, steps, start and inputs): the true columns they all simulate are simulated once
        (:class:`ExactBound`); the bounds are the same numbers.  ``None``: each run simulates its own.

    Returns
    -------
    ExactBound
        A protocol estimator: ``reset``, then ``step -> (x̂, exact bound)``.

    Raises
    ------
    InputError
        A bad ``system``, ``x0_radius``, ``order`` or ``steps``, or an estimator that offers neither way.

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> from eqrec.estimators.kalman import DelayUnawareKalman
    >>> from eqrec.systems.noise import GaussianNoise
    >>> acc = eqrec.acc_system()
    >>> noise = GaussianNoise(Qw=np.eye(1) * 0.01, Qv=np.eye(2) * 0.001, x0_cov=np.eye(3) * 0.04)
    >>> est = eqrec.exact_bound(DelayUnawareKalman(acc, noise.design(acc)), acc, 0.5, steps=10).reset(np.zeros(3))
    >>> xhat, bound = est.step(np.array([0.1, 0.2]))
    >>> bool(np.isfinite(bound)) and bound > 0
    True
    """
    return ExactBound(estimator, system, x0_radius, order=order, steps=steps, truths=truths)
