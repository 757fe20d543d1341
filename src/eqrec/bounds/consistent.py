r"""The exact set of states consistent with the measured data: its interval hull, filtered and predicted.

Setting
-------
The plant and the arrivals of :mod:`eqrec.bounds.information` (eq. (3) of the prefix-based paper with the noise
gains of its Remark 1):

.. math::
    x(k+1) = A(k)x(k) + B(k)u(k) + f + E(k)w(k), \qquad y(\tau) = C(\tau)x(\tau) + V(\tau)v(\tau),

:math:`\|w\|_\infty \le \eta_w`, :math:`\|v\|_\infty \le \eta_v`, :math:`|x(0) - c_0| \le \rho` (``x0_centre``,
``x0_radius``).  At step ``t`` the data delivered so far are the measurements :math:`y(\tau)`,
:math:`\tau \in \mathcal D_t = \{\tau : \tau + d(\tau) \le t\}` (:class:`~eqrec.arrivals.traces.ArrivalTrace`).
The **consistent set** is every state the plant could be in given those data:

.. math::
    \mathcal X(s \mid t) = \{x(s) : \text{some } x(0), w, v \text{ in their boxes give } y(\tau)\
        (\tau \in \mathcal D_t)\},

a polytope (the projection of one).  :func:`consistent_set` returns its interval hull at every step, *filtered*
(:math:`s = t`: what a set-based toolbox reports, the set of :math:`x(t)` given the data up to ``t``) and
*predicted* (:math:`s = t + 1`: what an estimator's ``step`` returns at ``t``, the papers' convention).

Computation
-----------
The data enter linearly.  With the noise-free run :math:`\bar x(k+1) = A\bar x(k) + Bu(k) + f`,
:math:`\bar x(0) = c_0`, the deviation :math:`\delta x = x - \bar x` follows the zero-data plant of
:func:`eqrec.bounds.information.trace_lp` and a delivered measurement reads
:math:`C(\tau)\delta x(\tau) + V(\tau)v(\tau) = y(\tau) - C(\tau)\bar x(\tau)` (its *residual*).  So the trace's
LP of the information limit serves unchanged: the same variables, rows and warm-started HiGHS models
(:func:`eqrec.bounds.information.solve_range`), with each delivered row fixed to its residual instead of 0.
Two LPs per state and kind (maximum and minimum of :math:`\delta x_i(t)`, and of :math:`\delta x_i(t+1)`), so
``4 n`` per step, each started from the previous one's optimal basis; the bounds are :math:`\bar x_i` plus the
optima.  The order matters: the maxima of a step, then its minima in reverse, reversed again on the next step
(a maximum and the minimum of the same state share no optimal vertex; a state and its neighbour in that order
share most of it): 5-6 times less time than state by state, max then min (tanks, n = 4 and 10), about 4 times
the limit's LPs on the same trace.  The values are LP optima to HiGHS's tolerances (1e-9 absolute on the rows,
:data:`eqrec.bounds.information.HIGHS_OPTIONS`): like the limit, a ruler, not a guarantee.

Data
----
``data`` holds the measurements by time stamp, as :func:`eqrec.simulate.loop.closed_loop` records them
(``LoopRun.y``, shape ``(N, p)``: every ``y(τ)`` sent, whether it arrives or not).  Only the rows the trace
delivers within its ``N`` steps are read; the others may hold anything, NaN included (a lost packet has no
value).  A dict ``{τ: y(τ)}`` of the delivered packets alone is accepted too.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import partial

import numpy as np

from eqrec.arrivals.traces import ArrivalTrace
from eqrec.bounds.information import (MAX_ESTIMATED_SECONDS, MAX_X0_RADIUS, PROGRESS_SECONDS, SEGMENT, TraceLP,
                                      check_x0_radius, delivery_steps, estimate_seconds, solve_range, trace_lp)
from eqrec.checks import instance
from eqrec.errors import InfeasibleDesign, InputError
from eqrec.lp.parallel import Progress
from eqrec.lp.solvers import solver_info
from eqrec.systems.affine import AffineSystem

#: The hulls :func:`consistent_set` computes: of x(t) and of x(t+1) given the data up to t.
HULL_KINDS = ("filtered", "predicted")


@dataclass(frozen=True)
class ConsistentSet:
    """The interval hulls of the states consistent with the data, at every step (module docstring).

    Parameters
    ----------
    filtered_lower, filtered_upper : numpy.ndarray, shape (steps, n)
        Row ``t``: the hull of :math:`x(t)` given the data delivered at steps ``<= t``.
    predicted_lower, predicted_upper : numpy.ndarray, shape (steps, n)
        Row ``t``: the hull of :math:`x(t+1)` given the data delivered at steps ``<= t`` (what an estimator's
        ``step`` at ``t`` bounds).
    """

    filtered_lower: np.ndarray
    filtered_upper: np.ndarray
    predicted_lower: np.ndarray
    predicted_upper: np.ndarray

    @property
    def filtered_centre(self) -> np.ndarray:
        """Centre of the filtered hull, shape ``(steps, n)``."""
        return 0.5 * (self.filtered_lower + self.filtered_upper)

    @property
    def filtered_radius(self) -> np.ndarray:
        """Half-width of the filtered hull, shape ``(steps, n)``."""
        return 0.5 * (self.filtered_upper - self.filtered_lower)

    @property
    def predicted_centre(self) -> np.ndarray:
        """Centre of the predicted hull, shape ``(steps, n)``."""
        return 0.5 * (self.predicted_lower + self.predicted_upper)

    @property
    def predicted_radius(self) -> np.ndarray:
        """Half-width of the predicted hull, shape ``(steps, n)``: at most :func:`eqrec.information_limit`."""
        return 0.5 * (self.predicted_upper - self.predicted_lower)

    @property
    def steps(self) -> int:
        """Number of steps (rows)."""
        return int(self.filtered_lower.shape[0])


def _measurements(data, trace: ArrivalTrace, delivered_at: np.ndarray, p: int) -> dict[int, np.ndarray]:
    """The delivered measurements ``{τ: y(τ)}`` (finite, shape ``(p,)``) read from ``data``."""
    N = trace.steps
    wanted = [int(tau) for tau in np.flatnonzero(delivered_at < N)]
    out: dict[int, np.ndarray] = {}
    if isinstance(data, dict):
        missing = [tau for tau in wanted if tau not in data]
        if missing:
            raise InputError(f"the trace delivers y({missing[0]}) but data has no entry for it "
                             f"({len(missing)} missing)", field="data")
        rows = {tau: data[tau] for tau in wanted}
    else:
        try:
            arr = np.asarray(data, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"measurements by time stamp, shape ({N}, {p}), got {type(data).__name__}",
                             field="data") from None
        if arr.ndim == 1 and p == 1:
            arr = arr[:, None]
        if arr.ndim != 2 or arr.shape[0] < N or arr.shape[1] != p:
            raise InputError(f"measurements by time stamp need shape ({N}, {p}) (rows y(0..N-1)), got {arr.shape}",
                             field="data")
        rows = {tau: arr[tau] for tau in wanted}
    for tau, y in rows.items():
        try:
            y = np.asarray(y, dtype=float).reshape(-1)
        except (TypeError, ValueError):
            raise InputError(f"y({tau}) is not a vector of numbers", field="data") from None
        if y.shape != (p,) or not np.all(np.isfinite(y)):
            raise InputError(f"y({tau}) is delivered, so it needs {p} finite numbers, got {y!r:.80}", field="data")
        out[tau] = y
    return out


def _inputs(inputs, N: int, m: int) -> np.ndarray:
    if inputs is None:
        return np.zeros((N, m))
    try:
        u = np.asarray(inputs, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"inputs need shape ({N}, {m}), got {type(inputs).__name__}", field="inputs") from None
    if u.ndim == 1 and m == 1:
        u = u[:, None]
    if u.ndim != 2 or u.shape[0] < N or u.shape[1] != m or not np.all(np.isfinite(u[:N])):
        raise InputError(f"inputs need {N} finite rows of {m} (u(0..N-1)), got shape {u.shape}", field="inputs")
    return u


def _hull_order(t: int, n: int, kinds: int = 2) -> np.ndarray:
    """The order of step ``t``'s ``2 kinds n`` objectives, as indices into (kind, state, max/min) flattened: the
    maxima of the filtered then the predicted states (or of the one kind asked), then the minima in reverse, and
    the reverse of that on odd steps (a warm solve starts from the previous objective's optimum: neighbouring
    objectives share most of their optimal vertex, a maximum and the minimum of the same state share none)."""
    idx = np.arange(2 * kinds * n).reshape(kinds, n, 2)  # (kind, state, max/min)
    maxima = idx[:, :, 0].ravel()
    order = np.concatenate([maxima, idx[:, :, 1].ravel()[::-1]])
    return order if t % 2 == 0 else order[::-1]


def _hull_targets(tlp: TraceLP, t: int,
                  kinds: tuple[str, ...] = HULL_KINDS) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """Per step ``t``: max and min of every :math:`\\delta x_i(t)` (filtered) and :math:`\\delta x_i(t+1)`
    (predicted), of the ``kinds`` asked, in the order of :func:`_hull_order`."""
    out = []
    for kind in kinds:
        k = t + (kind == "predicted")
        cols, M = tlp.xmap[k]
        for i in range(tlp.n):
            nz = M[i] != 0
            out.append((cols[nz], M[i][nz], f"{kind} x{i} max"))
            out.append((cols[nz], -M[i][nz], f"{kind} x{i} min"))
    return [out[j] for j in _hull_order(t, tlp.n, len(kinds))]


def consistent_set(system: AffineSystem, trace: ArrivalTrace, data, x0_radius, x0_centre=None, *,
                   inputs=None, solver: str = "highs", solver_options: dict | None = None,
                   force: bool = False, kinds: tuple[str, ...] = HULL_KINDS) -> ConsistentSet:
    r"""The exact interval hull of the states consistent with the measured data, filtered and predicted.

    Row ``t`` of the result: the hull of :math:`x(t)` and of :math:`x(t+1)` over every initial state, process
    noise and measurement noise in their boxes that reproduce the measurements delivered at steps ``<= t``
    (module docstring).  Four LPs per state and step, through :mod:`eqrec.lp` (HiGHS warm-started along the
    trace, the trace LP of :func:`eqrec.information_limit` with the data's residuals).  The data's counterpart
    of :func:`eqrec.information_limit`: the limit is the worst case over all data, this is the set on the data
    measured.

    Parameters
    ----------
    system : AffineSystem
        The plant; matrices read at absolute time (the trace starts at time 0).
    trace : ArrivalTrace
        The arrivals: ``y(τ)`` with delay ``d`` is delivered at step ``τ + d``; ``NEVER``: lost.
    data : array_like, shape (N, p), or dict of int to array_like
        The measurements by time stamp, ``data[τ] = y(τ)`` (``LoopRun.y`` of :func:`eqrec.simulate.loop.closed_loop`);
        only the delivered ones are read (module docstring, Data).
    x0_radius : float or array_like, shape (n,)
        Radius of the box of :math:`x(0)` around ``x0_centre``.
    x0_centre : array_like, shape (n,), optional
        Centre of that box (default 0): the ``x̂(0)`` an estimator is reset with.
    inputs : array_like, shape (N, m), optional
        The known inputs ``u(0..N-1)`` (default zero).
    solver : str, optional
        LP solver (:data:`eqrec.lp.solvers.SOLVER_NAMES`; default ``"highs"``, warm-started).
    solver_options : dict or None, optional
        Passed to the solver.
    force : bool, optional
        Run even when estimated past :data:`eqrec.bounds.information.MAX_ESTIMATED_SECONDS` (four times the
        limit's LPs); default ``False``: refuse.
    kinds : tuple of str, optional
        The hulls to compute: ``("filtered", "predicted")`` (default) or one of them, at half the cost (the
        other's arrays are then NaN). A warm solve starts from the previous objective's optimum, so the values
        of one kind alone may differ from those of both in the last digits (within the solver's tolerance).

    Returns
    -------
    ConsistentSet
        ``filtered_lower/upper`` and ``predicted_lower/upper``, shape ``(N, n)``, with centres and radii.

    Raises
    ------
    InputError
        A malformed ``system``, ``trace``, ``x0_radius`` (as :func:`eqrec.information_limit`), ``x0_centre`` (field
        ``x0_centre``), ``inputs`` (field ``inputs``), ``solver``; ``data`` of the wrong shape or with a
        delivered measurement missing or not finite (field ``data``); data no state is consistent with (field
        ``data``: the step at which the set became empty; the plant, the noise bounds or the initial box is
        wrong for these data); an estimated cost past the limit without ``force`` (field ``trace``).
    SolverFailure
        An LP without an answer (a solver fault).

    Notes
    -----
    **Theorem 1 (the limit bounds the hull's half-width).**  *For every step and state, the predicted
    half-width is at most the information limit's row* ``t`` *of* :func:`eqrec.information_limit` *(same plant,
    trace and* ``x0_radius``\ *), whatever the data.*

    *Proof.* Write the uncertainty :math:`\delta = (x(0) - c_0, w, v)`, a box :math:`\mathcal B`, symmetric and
    convex; the delivered data are :math:`\bar y + Z\delta` and :math:`x(t+1) = \bar x + G\delta`.  The
    consistent set is :math:`\bar x + G S_r`, :math:`S_r = \{\delta \in \mathcal B : Z\delta = r\}` with the
    residual ``r``.  Its half-width in state ``i`` is :math:`\tfrac12 (G_i\delta_1 - G_i\delta_2)` for some
    :math:`\delta_1, \delta_2 \in S_r`.  Then :math:`\delta = \tfrac12(\delta_1 - \delta_2)` lies in
    :math:`\mathcal B` (symmetric, convex) and :math:`Z\delta = 0`: it is feasible for the limit's LP (the same
    LP with zero data), so :math:`\tfrac12 G_i(\delta_1 - \delta_2) = G_i\delta \le r_i(t+1)`.  ∎  The zero
    data are the worst case: for :math:`r = 0` the set :math:`S_0` is symmetric and its half-width is the
    limit itself.  The same argument bounds the filtered half-width by the limit of :math:`x(t)` given
    :math:`\mathcal D_t`.

    **Theorem 2 (every sound estimator's set contains it).**  *Let an estimator report at step* ``t`` *a set*
    :math:`\hat{\mathcal X}` *that contains* :math:`x(t+1)` *for every uncertainty in* :math:`\mathcal B`
    *giving the data it saw (a sound, guaranteed set: e.g.* :class:`eqrec.ZonotopeEstimator`\ *'s*
    ``x̂ ± state_bounds``\ *).  Then* :math:`\hat{\mathcal X}` *contains the consistent set, so its interval
    hull contains the predicted hull.*

    *Proof.* The estimator's input is the delivered data (and ``c_0``, the inputs): every
    :math:`\delta \in S_r` produces exactly these data, so the estimator runs identically and reports the same
    :math:`\hat{\mathcal X}`, which, being sound, contains the state :math:`\bar x + G\delta` of that
    :math:`\delta`.  So :math:`\hat{\mathcal X} \supseteq \bar x + G S_r`, the consistent set, and an interval
    containing a set contains its hull.  ∎  The same holds for filtered sets, with :math:`x(t)`.  So the hull is
    the smallest set any guaranteed estimator can report on these data; :func:`eqrec.information_limit` is the
    smallest *guarantee*, the worst case over the data.

    Examples
    --------
    A scalar random walk measured directly, ``y(1)`` lost:

    >>> import numpy as np
    >>> import eqrec
    >>> walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    >>> trace = eqrec.ArrivalTrace([0, eqrec.arrivals.traces.NEVER, 0])
    >>> hull = eqrec.consistent_set(walk, trace, [[0.3], [np.nan], [0.2]], x0_radius=1.0)
    >>> hull.filtered_lower.ravel().round(3).tolist(), hull.filtered_upper.ravel().round(3).tolist()
    ([-0.2, -0.3, -0.3], [0.8, 0.9, 0.7])
    >>> bool(np.all(hull.predicted_radius <= eqrec.information_limit(walk, trace, 1.0) + 1e-12))
    True
    """
    instance(system, AffineSystem, "system")
    instance(trace, ArrivalTrace, "trace", "an ArrivalTrace (eqrec.ArrivalTrace)")
    n, N = system.n, trace.steps
    r0 = check_x0_radius(x0_radius, n)
    c0 = np.zeros(n) if x0_centre is None else np.asarray(x0_centre, dtype=float)
    if c0.shape != (n,) or not np.all(np.isfinite(c0)):
        raise InputError(f"needs {n} finite numbers, got {x0_centre!r:.80}", field="x0_centre")
    solver_info(solver)
    if solver_options is not None:
        instance(solver_options, dict, "solver_options")
    if not isinstance(force, (bool, np.bool_)):  # a string such as "no" would read as true
        raise InputError(f"must be True or False, got {force!r}", field="force")
    lim = system.horizon_limit
    if lim is not None and lim < N:
        raise InputError(f"the time-varying system covers {lim} steps, the trace has {N}", field="trace")
    delivered_at = delivery_steps(trace)
    ys = _measurements(data, trace, delivered_at, system.p)
    u = _inputs(inputs, N, system.m)
    empty = np.zeros((N, n))
    if N == 0:
        return ConsistentSet(empty, empty.copy(), empty.copy(), empty.copy())
    if not isinstance(kinds, tuple) or not kinds or len(set(kinds)) != len(kinds) or \
            not set(kinds) <= set(HULL_KINDS):
        raise InputError(f"kinds is a tuple of distinct names among {HULL_KINDS}, got {kinds!r}", field="kinds")
    kinds = tuple(k for k in HULL_KINDS if k in kinds)  # (filtered first: the order of the LPs is fixed)
    seconds = 2 * len(kinds) * estimate_seconds(system, N, primal=True)  # the primal simplex path at every n
    if seconds > MAX_ESTIMATED_SECONDS and not force:
        raise InputError(f"refused: the consistent set of {N} steps at n = {n} would take about {seconds:.0f} s "
                         f"(documented limit {MAX_ESTIMATED_SECONDS:.0f} s; the cost grows as the square of the "
                         "length); pass force=True to run it anyway, or a shorter trace", field="trace")
    # the noise-free run from the centre, and each delivered measurement's residual
    xbar = np.empty((N + 1, n))
    xbar[0] = c0
    f = np.zeros(n) if system.f is None else system.f
    for k in range(N):
        xbar[k + 1] = system.A_at(k) @ xbar[k] + system.B_at(k) @ u[k] + f
    if not np.all(np.isfinite(xbar)):
        raise InputError("the noise-free run from x0_centre overflows", field="x0_centre")
    tlp = trace_lp(system, trace, r0, SEGMENT)
    rhs: dict[int, float] = {}
    for tau, rows in tlp.meas.items():
        res = ys[tau] - system.C_at(tau) @ xbar[tau]
        rhs.update(zip(rows.tolist(), res.tolist()))
    if rhs and max(abs(v) for v in rhs.values()) > MAX_X0_RADIUS:
        # the LP solver reads 1e20 as infinite (a residual of 1e20 made inconsistent data "consistent"), and past
        # about 1e15 the rows lose the noise bounds' digits: refuse, as information_limit refuses such a radius
        raise InputError(f"a measurement's residual against the noise-free run from x0_centre exceeds "
                         f"{MAX_X0_RADIUS:.0e} (the LP would read it as infinite or lose the noise bounds' digits): "
                         "centre the box near the data, or rescale the plant's units", field="x0_centre")
    try:
        progress = Progress(N, "consistent set: steps") if seconds >= PROGRESS_SECONDS else None
        solved = solve_range(tlp, 0, list(range(N)), delivered_at, None, solver, solver_options,
                             targets=partial(_hull_targets, kinds=kinds), rhs=rhs, what="consistent set",
                             progress=progress)
    except InfeasibleDesign as exc:
        step = str(exc).split("step ")[1].split(",")[0] if "step " in str(exc) else "?"
        raise InputError(f"no state is consistent with the data delivered by step {step} ({exc}): the plant, "
                         "its noise bounds, x0_radius or x0_centre do not describe these measurements",
                         field="data") from exc
    vals = np.full((N, 2, n, 2), np.nan)  # (step, kind, state, max/min)
    asked = [HULL_KINDS.index(k) for k in kinds]
    for t in range(N):
        row = np.empty(2 * len(kinds) * n)
        row[_hull_order(t, n, len(kinds))] = solved[t]
        vals[t, asked] = row.reshape(len(kinds), n, 2)
    return ConsistentSet(filtered_lower=xbar[:N] - vals[:, 0, :, 1], filtered_upper=xbar[:N] + vals[:, 0, :, 0],
                         predicted_lower=xbar[1:] - vals[:, 1, :, 1], predicted_upper=xbar[1:] + vals[:, 1, :, 0])
