r"""The information limit: the smallest error bound *any* estimator can guarantee on an arrival trace.

Setting
-------
The plant of :class:`eqrec.systems.affine.AffineSystem` (eq. (3) of the prefix-based paper with the noise
gains of its Remark 1),

.. math::
    x(k+1) = A(k)x(k) + B(k)u(k) + f + E(k)w(k), \qquad y(\tau) = C(\tau)x(\tau) + V(\tau)v(\tau),

with :math:`\|w(k)\|_\infty \le \eta_w`, :math:`\|v(\tau)\|_\infty \le \eta_v` and the initial error in the box
:math:`|x_i(0) - \hat x_i(0)| \le \rho_i` (``x0_radius``).  A measurement :math:`y(\tau)` with delay ``d`` is
delivered at step :math:`\tau + d` (:class:`eqrec.arrivals.traces.ArrivalTrace`, :data:`NEVER`: lost).  The
estimate an estimator's ``step`` returns at step ``t`` is :math:`\hat x(t+1)`, computed from the data delivered
at steps ``<= t``: the set :math:`\mathcal D_t = \{\tau : \tau + d(\tau) \le t\}`.

Subtracting the noise-free prediction (inputs, ``f`` and :math:`\hat x(0)` are known and enter linearly) leaves
the *zero-data* problem, one linear program per state ``i`` and step ``t``:

.. math::
    r_i(t+1) = \max\Big\{ x_i(t+1) \;:\; x(k+1) = A(k)x(k) + E(k)w(k),\
        C(\tau)x(\tau) + V(\tau)v(\tau) = 0 \ (\tau \in \mathcal D_t),\
        |x(0)| \le \rho,\ \|w\|_\infty \le \eta_w,\ \|v\|_\infty \le \eta_v \Big\},

the per-state *radius of information* (Traub, Wasilkowski, Woźniakowski) of :math:`x(t+1)` given the delivered
data.  :func:`information_limit` returns these radii, row ``t`` for step ``t``.

:func:`information_limit` proves (Notes) that no estimator, linear or not, with any memory, guarantees less
at that step, and that inside one block the limit equals the class engine's class level.

Time
----
Matrices are read at absolute time: :math:`A(k)` = ``system.A_at(k)``, and likewise ``E_at``, ``C_at``,
``V_at``; the trace starts at time 0 with the box :math:`\rho`.  A time-varying system must cover
``trace.steps`` steps.

Computation
-----------
The trace's whole LP is built once (:func:`trace_lp`), sparse and ordered by time, so the LP of the steps
``< t1`` is a leading block of its rows and columns.  The state is a variable every :data:`SEGMENT` ``= K``
steps and eliminated in between (:math:`x(k)` is linear in :math:`x(jK)` and :math:`w(jK..k-1)`): eliminating
it over the whole trace instead, as :math:`x(k)` linear in :math:`x(0), w(0..k-1)`, would give a dense
lower-triangular block of :math:`O(N^2)` entries and powers :math:`A^k` that ruin the scaling of an unstable
plant; keeping it at every step doubles the LP (``K = 8`` is 1.9 times faster than ``K = 1`` on ACC and 2.7
times on the batch reactor at 400 steps, with the same values to 4e-11).  A measurement's rows
:math:`C(\tau)x(\tau) + V(\tau)v(\tau)` are free until it is delivered and fixed to 0 from then on: going from
step ``t`` to ``t+1`` changes row bounds and the objective only.  HiGHS keeps one model per chunk of
:data:`CHUNK` steps (the LP up to the chunk's last step) and starts every solve from the previous optimal basis
(primal simplex, :data:`HIGHS_OPTIONS`; from :data:`LIMIT_DUAL_FROM_N` states on, the states in alternating
order and each objective the primal simplex for at most :data:`LIMIT_PRIMAL_ITERATIONS` iterations, then the dual
simplex of :data:`LIMIT_HIGHS_OPTIONS` from where it stopped, both on the LP unscaled with a dual feasibility
tolerance of 1e-10, :data:`LIMIT_SHARED_OPTIONS`); other solvers solve each LP from scratch.  The cost of a step
grows with ``t`` (the LP holds the whole past; ``benchmarks/bench_information_limit.py`` prints it).

From :data:`LIMIT_DUAL_FROM_N` states on, two more things.  A state that needed the dual simplex (next to a
sensor) starts on the next step from its own optimal basis, in two phases: with the rows delivered since freed
again, that basis is still primal feasible and only the objective has moved by a step, which the primal simplex
follows in tens of iterations; fixing the rows again leaves it dual feasible, and the dual simplex takes in the
new measurements (``_HighsModel._run_own``: about 800 iterations in all at n = 30, against about 2,000 for the
dual simplex alone from that basis, whose objective step is what costs it).  And the states of a row are
independent LPs: they are solved in tasks of one chunk and one group of neighbouring states
(:func:`state_groups`), each on a HiGHS model of its own, on ``n_jobs`` worker processes (by default every core
once the estimate reaches :data:`PARALLEL_SECONDS`).  Each task is a fixed sequence of solves whatever process runs
it, so the values do not depend on the number of workers (byte for byte); against one model for all the states
they move within the LP tolerance (different warm starts).
Rows are cached by (system, ``x0_radius``, solver, ``t``, :math:`\mathcal D_t`): runs whose delivered sets agree,
and repeated calls on one trace, share their LPs (:func:`cache_info`).

Size.  Before anything is read or solved, :func:`estimate_seconds` estimates the call's process time from the
trace's length and the state dimension (the sum over the rows of ``n`` LPs whose cost grows with the past they
hold: quadratic in the length); past :data:`MAX_ESTIMATED_SECONDS` the call is refused unless ``force=True``,
and the message offers a window (below) with its own estimate.  The same LP with the data's residuals as the
delivered rows' values gives the exact consistent set on the data (:func:`eqrec.bounds.consistent.consistent_set`).

Accuracy.  The values are LP optima to HiGHS's tolerances (1e-9): the identity with the class levels holds to
1e-14 relative on short blocks; on 400-step batch-reactor traces two solve orders agree to 1e-9 absolute.  On a
150-step tank chain of n = 30 the primal-then-dual fallback (below 16 states unused) and the dual simplex alone
agree to 1e-9 on 4,499 of the 4,500 values (median 6e-13); on the last the fallback's warm solve stopped 5.4e-9
(relative 1.5e-8) below the optimum that cold solves (either simplex, the interior point with crossover) agree on.
The groups and the two-phase start of hard states (below) agree with that fallback to 1e-9 on 4,498 of the 4,500
values (median 2e-13); of the other two, one is that value, now on the cold optimum (3e-16 from it), and one (row
67, state 20) is 1.5e-8 (relative 3.8e-8) above the cold optimum, which the old path was on (6e-14): warm solves
drift by that much at n = 30, either way.  Without scaling and at a dual tolerance of 1e-10
(:data:`LIMIT_SHARED_OPTIONS`) the same 4,500 values agree with that path's to 1.5e-8, and that largest difference is
the row 67, state 20 above: on the cold optimum now (1.7e-16); on 32 LPs of rows 140-143 (states 0-7) the warm
optima are within 1.1e-10 of cold ones (the scaled path: 1.9e-10); n = 20 over 150 steps moves by at most 1.5e-10.

Window (``window=W``): the rows ``kW .. (k+1)W - 1`` use the box :math:`[-r(s), r(s)]` at the start
``s = (k-1)W`` rounded down to a multiple of ``K`` (:math:`r(s)` is row ``s - 1``) and the data of times
``>= s`` only: each row keeps at least the last ``W`` steps.  Both *enlarge* the feasible set.  The past
(:math:`x(0)`, :math:`w(<s)`, :math:`v(<s)`) and the present (:math:`w(\ge s)`, :math:`v(\ge s)`) are
independent boxes linked only through :math:`x(s)`, whose set given the old data delivered by ``t`` lies in its
set given the data delivered by ``s - 1``, hence in the box of radius :math:`r(s)` (by induction over the
chunks, the windowed :math:`r(s)` is itself at least the exact one); and dropping the old measurements drops
constraints.  The windowed value is therefore **larger than or equal to** the exact limit (up to the LP
tolerance): an upper estimate, no longer a lower bound on what an estimator can guarantee.  It is the limit
of an estimator that keeps a box at ``s`` (as the class engine does at its block starts) and is exact for
``t < W``.  Where the
past matters for long (the batch reactor has no process noise: what ``x(0)`` was stays informative forever) it
is far from exact: at 100-400 steps ``W = 40`` gives up to 1.06 times the limit there and ``W = 20`` up to 1.3,
against 1 + 1e-12 on ACC (``benchmarks/bench_information_limit.py``).
"""

from __future__ import annotations

import functools
import hashlib
import time
from collections import OrderedDict
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.checks import instance, integer, radii
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure
from eqrec.lp.model import INF, LinearProgram, LPBuilder
from eqrec.lp.parallel import Progress, check_jobs, cpu_count, run_tasks
from eqrec.lp.solvers import highs_model, highs_status, solve_lp, solver_info
from eqrec.systems.affine import AffineSystem

#: Longest trace whose rows are cached: a row's key holds its delivered set, ``t/8`` bytes, so the keys of a trace
#: take ``N²/16`` bytes (600 MiB at 10^5 steps) and as long to build as a fast row takes to solve.
CACHE_MAX_STEPS = 10_000

#: Largest number of cached rows (one row: ``n`` floats and a key of ``t/8`` bytes); the oldest go first.
CACHE_SIZE = 500_000

_CACHE: "OrderedDict[tuple, np.ndarray]" = OrderedDict()
_STATS = {"hits": 0, "misses": 0}


def cache_info() -> dict[str, int]:
    """Rows served from the cache and rows solved since the last :func:`clear_cache`.

    Returns
    -------
    dict of str to int
        ``{"hits": ..., "misses": ..., "size": ...}`` (``size``: rows held).
    """
    return {**_STATS, "size": len(_CACHE)}


def clear_cache() -> None:
    """Forget every cached row and reset the counts of :func:`cache_info`.

    Returns
    -------
    None
        The cache is emptied in place.
    """
    _CACHE.clear()
    _STATS.update(hits=0, misses=0)


# ---------------------------------------------------------------------------
# Inputs
# ---------------------------------------------------------------------------

#: Largest initial radius (``x0_radius``) the limit accepts: HiGHS reads a bound of 1e20 or more as infinite (the
#: LP becomes unbounded), and its feasibility tolerance (1e-9, :data:`HIGHS_OPTIONS`) is absolute, so radii past
#: about 1e15 leave the optimum below one unit in the last place of the rows' values.  Rescale the plant's units.
MAX_X0_RADIUS = 1e15


def check_x0_radius(x0_radius, n: int) -> np.ndarray:
    """``x0_radius`` as ``n`` radii, each finite, ``>= 0`` and at most :data:`MAX_X0_RADIUS`.

    Parameters
    ----------
    x0_radius : float or array_like, shape (n,)
        The radius of the box of ``x(0)``.
    n : int
        State dimension.

    Returns
    -------
    numpy.ndarray, shape (n,)
        The radii.

    Raises
    ------
    InputError
        Negative, NaN, infinite, of the wrong length, or above :data:`MAX_X0_RADIUS` (field ``x0_radius``).
    """
    r0 = radii(x0_radius, n)
    if np.any(r0 > MAX_X0_RADIUS):
        raise InputError(f"each radius is at most {MAX_X0_RADIUS:.0e} (the LP solver reads 1e20 as infinite and "
                         f"its tolerances are absolute), got {float(r0.max()):.3g}; express the state in larger "
                         "units", field="x0_radius")
    return r0


def delivery_steps(trace: ArrivalTrace) -> np.ndarray:
    r"""The step at which each measurement is delivered, or ``trace.steps`` when not within the trace.

    Computed from the delays without forming ``τ + d`` for a delay past the trace (a delay near ``2**63`` would
    overflow :meth:`ArrivalTrace.arrival_times` to a negative time); the delivered sets
    :math:`\mathcal D_t = \{\tau : s(\tau) \le t\}` of every row, its LP and its cache key are all read from
    this one array.

    Parameters
    ----------
    trace : ArrivalTrace
        The arrivals.

    Returns
    -------
    numpy.ndarray of int64, shape (trace.steps,)
        ``τ + d(τ)`` when ``y(τ)`` arrives at a step ``< N``, else ``N``.
    """
    N = trace.steps
    d = trace.delays
    tau = np.arange(N, dtype=np.int64)
    within = (d != NEVER) & (d < N - tau)
    return np.where(within, tau + np.where(within, d, 0), N).astype(np.int64)


def _check(system, trace, x0_radius, solver: str, window, options) -> tuple[np.ndarray, int | None]:
    instance(system, AffineSystem, "system")
    instance(trace, ArrivalTrace, "trace", "an ArrivalTrace (eqrec.ArrivalTrace)")
    r0 = check_x0_radius(x0_radius, system.n)
    solver_info(solver)
    if options is not None:
        instance(options, dict, "solver_options")
    if window is not None:
        window = integer(window, "window", low=1)
    lim = system.horizon_limit
    if lim is not None and lim < trace.steps:
        raise InputError(f"the time-varying system covers {lim} steps, the trace has {trace.steps}", field="trace")
    return r0, window


def _fingerprint(system: AffineSystem, r0: np.ndarray, solver: str, options: dict | None) -> bytes:
    """What a cached row depends on besides ``(t, D_t)``: the matrices, noise bounds, radii and solver."""
    h = hashlib.sha1()
    for arr in (system.A, system.C, system.E, system.V, r0, np.array([system.eta_w, system.eta_v], float)):
        a = np.ascontiguousarray(arr, float)
        h.update(str(a.shape).encode())
        h.update(a.tobytes())
    h.update(f"{solver}|{sorted((options or {}).items())!r}".encode())
    return h.digest()


# ---------------------------------------------------------------------------
# The trace's LP, ordered by time
# ---------------------------------------------------------------------------

@dataclass
class TraceLP:
    r"""The zero-data LP of a whole trace, columns and rows ordered by time (module docstring, Computation).

    The state is a variable at the segment starts ``k = 0, K, 2K, ...`` only; inside a segment
    :math:`x(k) = \Phi(k, jK)\,x(jK) + \sum_{l} \Phi(k, l{+}1)E(l)w(l)` (:attr:`xmap`).  Block ``k`` of columns:
    ``x(k)`` (segment starts), ``w(k)``, then ``v(k)`` if ``y(k)`` arrives within the trace.  Block ``k`` of
    rows: the measurement rows :math:`C(k)x(k) + V(k)v(k)` of ``y(k)`` (if any; free here, a step fixes those
    of its delivered data to 0), then, at a segment's end, the dynamics rows linking ``x((j+1)K)``.

    Parameters
    ----------
    lp : LinearProgram
        Objective 0, ``x(0)`` in the box ``±ρ``, every measurement row free.
    xmap : list of tuple
        ``xmap[k] = (cols, M)``: :math:`x(k) = M\,z_{cols}` for ``k = 0..N``.
    meas : dict of int to ndarray
        Rows of ``y(τ)`` per measurement ``τ`` arriving within the trace.
    col_start, row_start : ndarray of int, shape (N+2,)
        First column and row of block ``k`` (entry ``N+1``: the totals).
    segment : int
        ``K``.
    n : int
        State dimension.
    """

    lp: LinearProgram
    xmap: list
    meas: dict
    col_start: np.ndarray
    row_start: np.ndarray
    segment: int
    n: int

    def window(self, start: int, stop: int) -> tuple[LinearProgram, int, int]:
        """The LP of blocks ``start .. stop-1`` (and the columns of ``x(stop)`` if ``stop`` starts a segment).

        Parameters
        ----------
        start, stop : int
            ``0 <= start <= stop <= N``; ``start`` a segment start.

        Returns
        -------
        lp : LinearProgram
            Rows of blocks ``start..stop-1`` and their columns, with the trace LP's bounds (a copy).
        col_offset, row_offset : int
            Index of its first column and row in the whole LP.
        """
        c0 = int(self.col_start[start])
        c1 = int(self.col_start[stop]) + (self.n if stop % self.segment == 0 else 0)
        r0, r1 = int(self.row_start[start]), int(self.row_start[stop])
        A = sp.csc_matrix(self.lp.A[:, c0:c1][r0:r1])  # columns first: cheap on CSC, linear in the window
        return LinearProgram(c=self.lp.c[c0:c1].copy(), A=A, row_lower=self.lp.row_lower[r0:r1].copy(),
                             row_upper=self.lp.row_upper[r0:r1].copy(), col_lower=self.lp.col_lower[c0:c1].copy(),
                             col_upper=self.lp.col_upper[c0:c1].copy()), c0, r0


def _triplets(M: np.ndarray, cols: np.ndarray, rows_offset: int = 0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Local rows, global columns and values of the nonzeros of ``M`` (columns ``cols``)."""
    r, c = np.nonzero(M)
    return r + rows_offset, cols[c], M[r, c]


def trace_lp(system: AffineSystem, trace: ArrivalTrace, x0_radius: np.ndarray, segment: int = 1) -> TraceLP:
    """Build the zero-data LP of ``trace`` (module docstring): variables ``x`` (segment starts), ``w``, ``v``.

    Parameters
    ----------
    system : AffineSystem
        The plant; matrices read at absolute time (``A_at(k)`` ...).
    trace : ArrivalTrace
        The arrivals; a measurement arriving at or after ``trace.steps`` gets no columns or rows.
    x0_radius : ndarray, shape (n,)
        Radii of the box of ``x(0)``.
    segment : int, optional
        ``K``: the state is a variable every ``K`` steps (default 1: every step).

    Returns
    -------
    TraceLP
        The LP, its column and row blocks and the maps of ``x(k)``.
    """
    N, n, K = trace.steps, system.n, int(segment)
    delivered_at = delivery_steps(trace)
    b = LPBuilder()
    xmap: list = [None] * (N + 1)
    meas: dict[int, np.ndarray] = {}
    col_start = np.zeros(N + 2, np.int64)
    row_start = np.zeros(N + 2, np.int64)
    eye = np.eye(n)
    for k in range(N + 1):
        col_start[k] = b.num_variables
        if k % K == 0:
            xk = b.add_variables(n, -x0_radius, x0_radius) if k == 0 else b.add_variables(n)
            if k > 0:  # close the segment: x(k) - M z = 0 (rows of block k-1, with the columns of x(k))
                cols, M = xmap[k]
                r, c, v = _triplets(-M, cols)
                b.add_rows(np.concatenate([np.arange(n), r]), np.concatenate([xk, c]),
                           np.concatenate([np.ones(n), v]), 0.0, 0.0, count=n)
            xmap[k] = (xk, eye)
        row_start[k] = b.num_rows
        if k == N:
            break
        cols, M = xmap[k]
        E = system.E_at(k)
        wc = b.add_variables(E.shape[1], -system.eta_w, system.eta_w)
        if delivered_at[k] < N:
            C, V = system.C_at(k), system.V_at(k)
            vc = b.add_variables(V.shape[1], -system.eta_v, system.eta_v)
            r1, c1, v1 = _triplets(C @ M, cols)
            r2, c2, v2 = _triplets(V, vc)
            meas[k] = b.add_rows(np.concatenate([r1, r2]), np.concatenate([c1, c2]), np.concatenate([v1, v2]),
                                 -INF, INF, count=C.shape[0])
        xmap[k + 1] = (np.concatenate([cols, wc]), np.hstack([system.A_at(k) @ M, E]))
    col_start[N + 1], row_start[N + 1] = b.num_variables, b.num_rows
    return TraceLP(b.build(), xmap, meas, col_start, row_start, K, n)


# ---------------------------------------------------------------------------
# Solving: a growing, warm-started HiGHS model, or one LP at a time
# ---------------------------------------------------------------------------

#: Steps per HiGHS model: the model of a chunk holds the LP up to its last step and its solves start from the
#: previous optimal basis.  Measured at 400 steps: fresh models every 32 steps beat one model grown a block at a
#: time (``addCols``/``addRows``) by 2-5x, 4-step chunks by 2x, and 16 or 64 by 0-25 %.
CHUNK = 32

#: ``K``: the state is a variable every ``K`` steps of the trace LP (:func:`trace_lp`); inside a segment it is
#: eliminated (module docstring, Computation: measured against 1, 2, 4 and 16).
SEGMENT = 8

#: HiGHS settings of the limit's LPs (the caller's ``solver_options`` override them): primal simplex, since a
#: new objective leaves the previous optimal basis primal feasible (5-13 iterations per LP against 30-40 for
#: the dual simplex on ACC and the batch reactor), and feasibility tolerances of 1e-9 (the default 1e-7 acts
#: like a process noise of that size at every step: on the batch reactor, which has none, 400-step values then
#: move by 1e-7 to 2e-5 between solve orders; at 1e-9, by 1e-9).
HIGHS_OPTIONS = {"simplex_strategy": 4, "primal_feasibility_tolerance": 1e-9, "dual_feasibility_tolerance": 1e-9}

#: The limit's own solves from :data:`LIMIT_DUAL_FROM_N` states on (the consistent set keeps the primal simplex):
#: each objective first runs the primal simplex of :data:`HIGHS_OPTIONS` from the previous optimal basis for at
#: most :data:`LIMIT_PRIMAL_ITERATIONS` iterations, and only if that does not reach the optimum it goes on from
#: where it stopped with these options, the dual simplex with Devex pricing (and no iteration limit); the states
#: in alternating order (:func:`_limit_order`).  Measured on tank chains (process time, the last rows of
#: 150 steps): most warm solves need 0-150 primal iterations (10-20 ms at n = 30), but about a third of the
#: states (those next to a sensor) need thousands of iterations with either method from their neighbour's basis,
#: where the primal simplex stalls (5,000-6,000 iterations, more than a cold solve) and the dual does not: the
#: hybrid takes 152-168 ms per LP at n = 30 and 77-81 ms at n = 20, against 325 and 138 ms with the dual simplex
#: alone (the values agree to 2e-10).  Over the whole 150 steps, back to back (process time): n = 20 131.6 ->
#: 76.6 s, n = 30 426.3 -> 309.3 s (the early rows, on smaller LPs, gain less).  Before (dual simplex alone),
#: measured on n = 20 at 60 steps: 7.3 s against 12.3 s with the primal simplex in fixed order and 11.0 s with the
#: primal simplex alternating (the values agree to 6e-11); keeping the eliminated states boxed by a data-free
#: reachable box (a redundant bound, so the same LP) made the dual simplex slower (9.0 s), and so did models of 16
#: or 64 steps instead of :data:`CHUNK`.
LIMIT_HIGHS_OPTIONS = {"simplex_strategy": 1, "simplex_dual_edge_weight_strategy": 1}

#: HiGHS settings of both phases of the limit's solves from :data:`LIMIT_DUAL_FROM_N` states on (under the caller's
#: ``solver_options``): no scaling of the LP, and a dual feasibility tolerance of 1e-10.  Measured (issue 45, fifth
#: session) on tasks of 6 rows and 8 states of the 150-step tank chain at n = 30 (rows 60-145): HiGHS's default
#: scaling (strategy 2) makes the hard states' dual simplex take 1.6-2.7 times the iterations it takes on the LP as
#: built (whose entries and bounds, ``ρ``, ``η_w``, ``η_v`` and the powers of ``A`` over one segment, are already
#: of moderate range), at the same cost per iteration: 1.5-2.7 times less process time.  Unscaled, the tolerances
#: apply to the LP as stated; at 1e-9 the unscaled warm optima ended up to 1.9e-9 below the cold ones (dual simplex,
#: tolerances 1e-10), at 1e-10 within 1.1e-10 (the scaled path at 1e-9: 1.9e-10), at 10-30 % more iterations.
#: (Scaling strategies 1 and 3 took the default's iterations, 4 about those of no scaling; a simplex update limit
#: of 50 or 1,000 instead of 5,000 changed nothing.)
LIMIT_SHARED_OPTIONS = {"simplex_scale_strategy": 0, "dual_feasibility_tolerance": 1e-10}

#: The primal simplex iterations an objective of the limit gets, from :data:`LIMIT_DUAL_FROM_N` states on, before
#: it goes on with the dual simplex (:data:`LIMIT_HIGHS_OPTIONS`): 150 and 400 took the same time at n = 30.
LIMIT_PRIMAL_ITERATIONS = 200

#: The smallest state dimension whose limit uses the fallback to :data:`LIMIT_HIGHS_OPTIONS` and the alternating
#: order of :func:`_limit_order`; below it, the primal simplex to the end with the states in increasing order, so
#: the limits of the compare study's plants (n <= 4) are those of before, byte for byte.  (On ACC, n = 3, and the
#: batch reactor, n = 4, at 400 steps the dual simplex alone took 1.0-1.5 times as long, on tank chains of n = 4
#: and 10 at 150 steps 2.0 and 1.05 times.  The primal-then-dual fallback at 150 steps: n = 6, 1.2-1.3 times as
#: long; n = 10, 0.7 times, but its values differ from the primal path's by up to 5e-9, past the 1e-9 between solve
#: orders documented here, so the threshold stays.)
LIMIT_DUAL_FROM_N = 16

#: From :data:`LIMIT_DUAL_FROM_N` states on, the states of a row are solved in contiguous groups of at most this many
#: (:func:`state_groups`), one task per group and chunk of :data:`CHUNK` steps, each on a HiGHS model of its own
#: warm-starting along its own states and steps: the tasks are independent, so they run on several processes, and
#: the values do not depend on how many (the same tasks, the same solves, whichever process runs them).
LIMIT_GROUP_STATES = 8

#: Estimated seconds (:func:`estimate_seconds`) from which :func:`information_limit` with ``n_jobs=None`` runs the
#: tasks of a plant of at least :data:`LIMIT_DUAL_FROM_N` states on every core (below: in this process; starting
#: the worker processes and sending them the trace's LP costs about a second).
PARALLEL_SECONDS = 10.0

_LAST_SOLVE = {"workers": 1, "tasks": 0, "task_seconds": 0.0}


def last_solve_info() -> dict:
    """How the last :func:`information_limit` call that solved LPs ran.

    Returns
    -------
    dict
        ``workers``: processes used (1: this one); ``tasks``: the tasks of :func:`state_groups` (0 below
        :data:`LIMIT_DUAL_FROM_N` states); ``task_seconds``: their process time, summed over the processes that ran
        them (on worker processes it is not in this process's ``time.process_time()``).
    """
    return dict(_LAST_SOLVE)


def _option(h, key: str):
    """HiGHS option ``key`` of ``h`` (highspy returns ``(status, value)``; some versions the value alone)."""
    val = h.getOptionValue(key)
    return val[1] if isinstance(val, tuple) else val


class _HighsModel:
    """One HiGHS model of a window of the trace LP; objectives and delivered rows change between warm solves.

    A warm solve that ends without an optimum (HiGHS has answered 'Unknown' once in thousands of warm primal
    solves, not reproducibly) is solved again cold by :func:`eqrec.lp.solvers.solve_lp` (with its retries), and
    the model is loaded afresh.
    """

    def __init__(self, lp: LinearProgram, col_offset: int, row_offset: int, options: dict | None,
                 fallback: dict | None = None):
        self.lp, self.c0, self.r0 = lp, col_offset, row_offset
        self.cost_cols = np.zeros(0, np.int32)
        shared = LIMIT_SHARED_OPTIONS if fallback is not None else {}  # both phases of the limit's fallback path
        self.options = {**HIGHS_OPTIONS, **shared, **(options or {})}
        # fallback: each run first stops after LIMIT_PRIMAL_ITERATIONS, then goes on with these options
        self.fallback = None if fallback is None else {**fallback, **(options or {})}
        self.h = self._load()
        self.retries = 0
        self.hard: set = set()  # objectives whose last solve needed the dual simplex (fallback only)
        self.bases: dict = {}  # their optimal bases and len(batches) then (fallback only)
        self.batches: list = []  # the deliveries so far: (local rows, values)

    def _load(self):
        h = highs_model(self.lp, self.options)
        if self.fallback is not None:  # the primal phase's settings, restored after each fallback
            self.restore = {key: _option(h, key) for key in (*self.fallback, "simplex_iteration_limit")}
            h.setOptionValue("simplex_iteration_limit", LIMIT_PRIMAL_ITERATIONS)
        return h

    def _run(self, key=None) -> str:
        """Run from the current basis.  With the fallback: the primal simplex for at most
        :data:`LIMIT_PRIMAL_ITERATIONS` iterations, then, if it has not reached the optimum, the dual simplex from
        where it stopped.  An objective ``key`` that needed the dual simplex last time (the same state at an
        earlier step of this model) starts from its own optimal basis of then instead (:meth:`_run_own`), until
        it takes fewer than :data:`LIMIT_PRIMAL_ITERATIONS` iterations there."""
        hard = self.fallback is not None and key is not None and key in self.hard
        if hard and key in self.bases:
            return self._run_own(key)
        if not hard:
            self.h.run()
            status, _ = highs_status(int(self.h.getModelStatus()))
            if self.fallback is None or status != "Iteration limit reached":
                self.hard.discard(key)
                return status
        self.hard.add(key)
        status, iterations = self._dual()
        if iterations < LIMIT_PRIMAL_ITERATIONS:  # easy this time: primal next
            self.hard.discard(key)
        elif status == "optimal":
            self.bases[key] = (self.h.getBasis(), len(self.batches))
        return status

    def _dual(self) -> tuple[str, int]:
        """The dual simplex of the fallback options, without an iteration limit, from the current basis; then the
        primal phase's settings again.  Its status and iterations."""
        for name, val in self.fallback.items():
            self.h.setOptionValue(name, val)
        self.h.setOptionValue("simplex_iteration_limit", self.restore["simplex_iteration_limit"])
        self.h.run()
        status, _ = highs_status(int(self.h.getModelStatus()))
        iterations = int(self.h.getInfo().simplex_iteration_count)
        for name, val in self.restore.items():
            self.h.setOptionValue(name, val)
        self.h.setOptionValue("simplex_iteration_limit", LIMIT_PRIMAL_ITERATIONS)
        return status, iterations

    def _run_own(self, key) -> str:
        """Solve the objective ``key`` from its own optimal basis of an earlier step, in two phases: with the rows
        delivered since then free again (as they were then) the basis stays primal feasible and only the objective
        has moved (by a step), which the primal simplex follows in a few iterations (14-109 on the hard states at
        n = 30, against about 2,000 for the dual simplex); then the rows are fixed again, which leaves that optimum
        dual feasible, and the dual simplex takes in the new measurements (about 700 iterations at n = 30, against
        2,400-3,900 for the primal simplex).  The last run solves the current LP, so the value is its optimum as
        before."""
        basis, seen = self.bases[key]
        self.h.setBasis(basis)
        since = self.batches[seen:]
        idx = np.concatenate([b[0] for b in since]) if since else np.zeros(0, np.int32)
        if idx.size:
            self.h.changeRowsBounds(idx.size, idx, np.full(idx.size, -INF), np.full(idx.size, INF))
        self.h.run()  # primal, at most LIMIT_PRIMAL_ITERATIONS
        status, _ = highs_status(int(self.h.getModelStatus()))
        iterations = int(self.h.getInfo().simplex_iteration_count)
        if idx.size:
            val = np.concatenate([b[1] for b in since])
            self.h.changeRowsBounds(idx.size, idx, val, val)
        if idx.size or status != "optimal":
            status, more = self._dual()
            iterations += more
        if status == "optimal":
            self.bases[key] = (self.h.getBasis(), len(self.batches))
        if iterations < LIMIT_PRIMAL_ITERATIONS:
            self.hard.discard(key)
        return status

    def deliver(self, rows: np.ndarray, values: np.ndarray | None = None) -> None:
        """Fix the measurement rows ``rows`` (global indices) to ``values`` (default 0: the zero-data LP)."""
        idx = (np.asarray(rows) - self.r0).astype(np.int32)
        val = np.zeros(idx.size) if values is None else np.asarray(values, float)
        self.lp.row_lower[idx] = self.lp.row_upper[idx] = val
        self.h.changeRowsBounds(idx.size, idx, val, val)
        self.batches.append((idx, val))

    def maximise(self, cols: np.ndarray, coef: np.ndarray, what: str, key=None) -> float:
        """``max coef · z[cols]`` (global columns) over the current LP (``key``: the objective's name across
        steps, for the fallback's choice of method)."""
        j = (cols - self.c0).astype(np.int32)
        if self.cost_cols.size:
            self.h.changeColsCost(self.cost_cols.size, self.cost_cols, np.zeros(self.cost_cols.size))
            self.lp.c[self.cost_cols] = 0.0
        self.h.changeColsCost(j.size, j, -coef)
        self.lp.c[j] = -coef
        self.cost_cols = j
        status = self._run(key)
        if status == "optimal":
            return -float(self.h.getInfo().objective_function_value)
        self.retries += 1
        sol = solve_lp(self.lp, "highs", self.options).require_optimal(f"{what} (warm HiGHS: {status!r})")
        self.h = self._load()
        return -float(sol.objective)


def _window_lp(tlp: TraceLP, start: int, stop: int, fixed: list, box: np.ndarray | None,
               rhs: dict | None = None) -> tuple:
    """The LP of blocks ``start..stop-1`` with the rows ``fixed`` set to their data (0, or ``rhs[row]``) and
    ``x(start)`` in ``±box``."""
    lp, c0, r0 = tlp.window(start, stop)
    n = tlp.n
    if box is not None:
        lp.col_lower[:n], lp.col_upper[:n] = -box, box
    if fixed:
        rows = np.concatenate(fixed)
        idx = rows - r0
        val = 0.0 if rhs is None else np.array([rhs[r] for r in rows.tolist()])
        lp.row_lower[idx] = lp.row_upper[idx] = val
    return lp, c0, r0


def _limit_order(t: int, n: int, states: np.ndarray | None = None, alternate: bool | None = None) -> np.ndarray:
    """The states in the order row ``t`` solves them (``states``: one group's, default all): with ``alternate``
    (default: from :data:`LIMIT_DUAL_FROM_N` states on) increasing on even steps and decreasing on odd ones, else
    increasing (each warm solve starts from the previous objective's optimal basis, and the first state of a step
    is then the last of the step before: neighbouring states share more of their optimal vertex than the two ends
    of the chain)."""
    states = np.arange(n) if states is None else np.asarray(states)
    alternate = n >= LIMIT_DUAL_FROM_N if alternate is None else alternate
    return states[::-1] if alternate and t % 2 == 1 else states


def _limit_targets(tlp: TraceLP, t: int, states: np.ndarray | None = None,
                   alternate: bool | None = None) -> list[tuple[np.ndarray, np.ndarray, str]]:
    """The objectives of row ``t`` of the limit: :math:`x_i(t+1)` for every state ``i`` (of ``states``, default
    all; columns, coefficients, label), in the order of :func:`_limit_order`."""
    cols, M = tlp.xmap[t + 1]
    return [(cols[M[i] != 0], M[i][M[i] != 0], f"state {i}") for i in _limit_order(t, tlp.n, states, alternate)]


def state_groups(n: int) -> list[np.ndarray]:
    """The groups of neighbouring states whose LPs one task solves (:func:`information_limit`, Computation):
    all ``n`` states below :data:`LIMIT_DUAL_FROM_N`, else ``ceil(n / LIMIT_GROUP_STATES)`` contiguous groups of
    sizes differing by at most one.

    Parameters
    ----------
    n : int
        State dimension.

    Returns
    -------
    list of numpy.ndarray of int
        The groups, in increasing order of their states; together ``0 .. n-1`` once each.
    """
    if n < LIMIT_DUAL_FROM_N:
        return [np.arange(n)]
    return [g for g in np.array_split(np.arange(n), -(-n // LIMIT_GROUP_STATES)) if g.size]


def _limit_task(tlp: TraceLP, start: int, rows: list[int], delivered_at: np.ndarray, box: np.ndarray | None,
                solver: str, options: dict | None, fallback: dict | None, states: np.ndarray, alternate: bool
                ) -> tuple[dict[int, tuple[np.ndarray, np.ndarray]], float]:
    """One task of the limit: the rows ``rows`` (one chunk) for the states ``states`` (one group), on a model of
    its own.  Everything it depends on is an argument (a worker process sees the module's defaults): per row the
    states in their solve order (:func:`_limit_order`) and their maxima, and the task's process time (seconds)."""
    cpu = time.process_time()
    vals = solve_range(tlp, start, rows, delivered_at, box, solver, options,
                       targets=functools.partial(_limit_targets, states=states, alternate=alternate), fallback=fallback)
    return {t: (_limit_order(t, tlp.n, states, alternate), v) for t, v in vals.items()}, time.process_time() - cpu


class _LPsAsRows:
    """Adapts a row :class:`~eqrec.lp.parallel.Progress` to tasks that report LPs (``n`` LPs make a row)."""

    def __init__(self, progress, n: int):
        self.progress, self.n, self.lps, self.rows = progress, n, 0, 0

    def advance(self, lps: int) -> None:
        self.lps += int(lps)
        rows = self.lps // self.n
        if rows > self.rows:
            self.progress.advance(rows - self.rows)
            self.rows = rows


def solve_range(tlp: TraceLP, start: int, rows: list[int], delivered_at: np.ndarray, box: np.ndarray | None,
                solver: str, options: dict | None, targets=_limit_targets, rhs: dict | None = None,
                what: str = "information limit", progress=None, fallback: dict | None = None
                ) -> dict[int, np.ndarray]:
    """``max`` of each objective ``targets(tlp, t)`` for the steps ``rows`` (increasing, all ``>= start``) on the
    LP from block ``start`` on.

    Row ``t`` fixes the measurement rows of the ``τ >= start`` delivered by ``t`` (to 0, or to ``rhs[row]``: the
    data's residuals, :func:`eqrec.bounds.consistent.consistent_set`); ``box`` (if given) replaces the box of
    ``x(start)``.  HiGHS: one model per chunk of :data:`CHUNK` steps, warm solves inside (each objective starts
    from the previous one's optimal basis); other solvers: one LP at a time.

    Parameters
    ----------
    tlp : TraceLP
        The trace's LP (:func:`trace_lp`).
    start : int
        First block (a segment start); ``0``: the whole past.
    rows : list of int
        The steps to solve, increasing.
    delivered_at : numpy.ndarray of int
        :func:`delivery_steps` of the trace.
    box : numpy.ndarray or None
        Radii of the box of ``x(start)`` (``None``: the LP's own).
    solver : str
        LP solver name.
    options : dict or None
        Solver options.
    targets : callable, optional
        ``targets(tlp, t)``: the objectives of step ``t``, a list of ``(columns, coefficients, label)``
        (default: :math:`x_i(t+1)` for every state, the limit's).
    rhs : dict of int to float or None, optional
        The value of each delivered measurement row (default 0: the zero-data LP).
    what : str, optional
        What is solved, for error messages.
    progress : eqrec.lp.parallel.Progress or None, optional
        Advanced by one per row solved.
    fallback : dict or None, optional
        HiGHS only: each objective gets :data:`LIMIT_PRIMAL_ITERATIONS` primal simplex iterations, then goes on
        with these options (:data:`LIMIT_HIGHS_OPTIONS`); ``None`` (default): the primal simplex to the end.

    Returns
    -------
    dict of int to numpy.ndarray
        Per step of ``rows``, the maxima in the order of ``targets``.

    Raises
    ------
    InfeasibleDesign
        An LP infeasible (the data inconsistent, with ``rhs``) or unbounded.
    SolverFailure
        An LP without an answer.
    """
    by_step: dict[int, list] = {}
    for tau in range(start, rows[-1] + 1):  # delivered by the last row: stamped at most then
        r = tlp.meas.get(tau)
        if r is not None:
            by_step.setdefault(int(delivered_at[tau]), []).append(r)
    out: dict[int, np.ndarray] = {}
    fixed: list = []  # measurement rows delivered before the step being processed
    t_next = start

    def values(rows_: list) -> np.ndarray | None:
        return None if rhs is None else np.array([rhs[r] for r in np.concatenate(rows_).tolist()])

    for c0 in range(start, rows[-1] + 1, CHUNK if solver == "highs" else 1):
        chunk = [t for t in rows if c0 <= t < c0 + CHUNK] if solver == "highs" else [t for t in rows if t == c0]
        if not chunk:
            continue
        for t in range(t_next, chunk[0]):
            fixed += by_step.get(t, [])
        t_next = chunk[0]
        if solver == "highs":
            model = _HighsModel(*_window_lp(tlp, start, chunk[-1] + 1, fixed, box, rhs), options, fallback)
            for t in range(chunk[0], chunk[-1] + 1):
                if t in by_step:
                    model.deliver(np.concatenate(by_step[t]), values(by_step[t]))
                fixed += by_step.get(t, [])
                if t in chunk:
                    out[t] = np.array([model.maximise(cols, coef, f"{what}, step {t}, {label}", label)
                                       for cols, coef, label in targets(tlp, t)])
                    if progress is not None:
                        progress.advance(1)
            t_next = chunk[-1] + 1
        else:
            t = chunk[0]
            fixed += by_step.get(t, [])
            t_next = t + 1
            lp, col0, _ = _window_lp(tlp, start, t + 1, fixed, box, rhs)
            vals = []
            for cols, coef, label in targets(tlp, t):
                lp.c[:] = 0.0
                lp.c[cols - col0] = -coef
                vals.append(-solve_lp(lp, solver, options).require_optimal(f"{what}, step {t}, {label}").objective)
            out[t] = np.array(vals)
            if progress is not None:
                progress.advance(1)
    return out


#: Estimated seconds above which :func:`information_limit` (and :func:`eqrec.bounds.consistent.consistent_set`)
#: refuse to start unless ``force=True`` (10 minutes, as ``eqrec design``).
MAX_ESTIMATED_SECONDS = 600.0
#: Estimated seconds from which a call shows its progress on stderr (:class:`eqrec.lp.parallel.Progress`: a bar
#: on a terminal, a line at the start and one at the end otherwise).
PROGRESS_SECONDS = 20.0
#: The time model of :func:`estimate_seconds` (below :data:`LIMIT_DUAL_FROM_N` states, and for the consistent set at
#: every ``n``; above, :data:`LIMIT_SECONDS_PER_STATE_STEP`): a row ``t`` of the exact limit costs about
#: ``SECONDS_PER_STATE * n + SECONDS_PER_STATE_STEP * n**STATE_EXPONENT * t`` seconds of process time (``n``
#: warm LPs over the ``t`` steps of the past: the simplex iterations and their cost both grow with ``t``, so the
#: sum over the rows is at least quadratic in the trace's length).  A windowed row's LP holds ``W`` to
#: ``2W + SEGMENT`` steps, so ``t`` is replaced by ``1.5 W + SEGMENT`` there.  Fit on this project's 2-core
#: machine (HiGHS 1.15, process time): ACC exact at 1,000 and 4,000 steps (2.4 and 35.9 s; the model says 2.4 and
#: 29) and windowed (``W = 100``: 2.3 ms per row; the model 1.3), chains of coupled tanks
#: (``benchmarks/bench_information_limit.py``, 150 steps) at n = 4, 10, 20 and 30 (0.54, 6.9, 159 and 559 s; the
#: model 0.3, 7.4, 149 and 883).  The iterations per LP grow with the plant's memory, so the growth in the length lies
#: between ``N^2`` (ACC) and ``N^2.8`` (the tanks, 60 to 150 steps): the estimate is meant to within a factor 4,
#: high on short traces of large plants (n = 30 at 60 steps: 140 s estimated, 38 s measured).
SECONDS_PER_STATE, SECONDS_PER_STATE_STEP, STATE_EXPONENT = 2.7e-4, 2.5e-8, 4.4

#: The second term of the time model for the limit's own path from :data:`LIMIT_DUAL_FROM_N` states on (the
#: primal-then-dual fallback, unscaled, :data:`LIMIT_SHARED_OPTIONS`): ``LIMIT_SECONDS_PER_STATE_STEP *
#: n**LIMIT_STATE_EXPONENT * t`` instead.  Fit on the tank chains at 150 steps (issue 45, fifth session, one
#: process, process time, load 4-8): n = 20 and 30 in 33.3 and 102.3 s (the model 33.7 and 103.6); n = 30 at 60
#: steps 10.8-13.3 s (the model 16.2).  The model of before said 149 and 883 s there, past the refusal at n = 30.
LIMIT_SECONDS_PER_STATE_STEP, LIMIT_STATE_EXPONENT = 6.7e-7, 2.8


def estimate_seconds(system: AffineSystem, rows, window: int | None = None, *, primal: bool = False) -> float:
    """The estimated seconds of the rows ``rows`` of :func:`information_limit` (time model:
    :data:`SECONDS_PER_STATE_STEP`, from :data:`LIMIT_DUAL_FROM_N` states on :data:`LIMIT_SECONDS_PER_STATE_STEP`),
    before anything is solved.

    Parameters
    ----------
    system : AffineSystem
        The plant (its state dimension ``n``).
    rows : int or iterable of int
        The steps ``t`` to solve, or a trace length ``N`` (every row ``0..N-1``).
    window : int or None, optional
        ``None``: exact rows; ``W``: windowed rows.
    primal : bool, optional
        ``True``: the primal simplex path at every ``n`` (the consistent set's,
        :func:`eqrec.bounds.consistent.consistent_set`), so the first model whatever ``n``; default ``False``: the
        limit's.

    Returns
    -------
    float
        Seconds of process time.
    """
    t = np.arange(rows, dtype=float) if np.isscalar(rows) else np.asarray(list(rows), float)
    if window is not None:
        t = np.minimum(t, 1.5 * window + SEGMENT)
    n = system.n
    if n >= LIMIT_DUAL_FROM_N and not primal:
        return float(t.size * SECONDS_PER_STATE * n
                     + LIMIT_SECONDS_PER_STATE_STEP * n ** LIMIT_STATE_EXPONENT * t.sum())
    return float(t.size * SECONDS_PER_STATE * n + SECONDS_PER_STATE_STEP * n ** STATE_EXPONENT * t.sum())


def suggested_window(system: AffineSystem, steps: int) -> int:
    """The longest window (200, 100, 50 or 20 steps) whose estimated cost on ``steps`` steps stays under half
    :data:`MAX_ESTIMATED_SECONDS` (20 if none does).

    Parameters
    ----------
    system : AffineSystem
        The plant.
    steps : int
        The trace's length.

    Returns
    -------
    int
        ``W``.
    """
    for W in (200, 100, 50, 20):
        if estimate_seconds(system, steps, W) <= MAX_ESTIMATED_SECONDS / 2:
            return W
    return 20


def _refusal(system: AffineSystem, steps: int, todo: list, window: int | None, seconds: float) -> str:
    when = f"{seconds / 60:.0f} min" if seconds < 7200 else f"{seconds / 3600:.3g} h"
    if window is None:
        W = suggested_window(system, steps)
        return (f"refused: the exact limit of {len(todo)} rows on {steps} steps at n = {system.n} would take about "
                f"{when} (its cost grows as the square of the length; documented limit "
                f"{MAX_ESTIMATED_SECONDS:.0f} s); pass force=True to run it anyway, or window={W}, about "
                f"{estimate_seconds(system, todo, W):.0f} s, whose values are >= the exact limit (each row forgets "
                "the data older than the window and keeps a box there: a relaxation, so it errs upward)")
    return (f"refused: {len(todo)} rows with window={window} on {steps} steps at n = {system.n} would take about "
            f"{when} (documented limit {MAX_ESTIMATED_SECONDS:.0f} s); pass force=True, or a shorter window")


def information_limit(system: AffineSystem, trace: ArrivalTrace, x0_radius, *, solver: str = "highs",
                      window: int | None = None, cache: bool = True,
                      solver_options: dict | None = None, force: bool = False, n_jobs: int | None = None
                      ) -> np.ndarray:
    r"""Per step and state, the smallest worst-case error any estimator can guarantee on ``trace``.

    Row ``t`` is :math:`r(t+1)`, the radius of information of the estimate :math:`\hat x(t+1)` that an
    estimator's ``step`` returns at step ``t``, from the data delivered at steps ``<= t`` (the LP: module
    docstring).  No estimator, linear or not, with any memory, guarantees less (Notes, Theorem 1); inside one
    block the limit is the class engine's class level (Theorem 2).  One LP per state and step, through
    :mod:`eqrec.lp`.

    Parameters
    ----------
    system : AffineSystem
        The plant; matrices read at absolute time ``A_at(k)``, ``E_at(k)``, ``C_at(τ)``, ``V_at(τ)`` with the
        trace starting at time 0.  Inputs and ``f`` do not matter (they are known).
    trace : ArrivalTrace
        The arrivals: ``y(τ)`` with delay ``d`` is delivered at step ``τ + d``; :data:`NEVER` is lost.
    x0_radius : float or array_like, shape (n,)
        Radius of the box of the initial error :math:`x(0) - \hat x(0)` (one number, or one per state).
    solver : str, optional
        LP solver, a name of :data:`eqrec.lp.solvers.SOLVER_NAMES` (default ``"highs"``, warm-started).
    window : int or None, optional
        ``None`` (default): exact.  ``W >= 1``: each row forgets the data older than ``W`` to
        ``2W + SEGMENT`` steps and keeps a box there instead; the value is then **>= the exact limit**
        (module docstring), an upper estimate and not a lower bound.  Exact for the rows ``t < W``.
    cache : bool, optional
        Reuse rows of earlier calls with the same system, radius, solver, step and delivered data (default
        ``True``; :func:`cache_info`, :func:`clear_cache`); traces longer than :data:`CACHE_MAX_STEPS` are not
        cached.
    solver_options : dict or None, optional
        Passed to the solver.
    force : bool, optional
        Run even when the trace's rows are estimated (:func:`estimate_seconds`, before anything is read or
        solved) to take more than :data:`MAX_ESTIMATED_SECONDS`; default ``False``: refuse them (the message gives
        the estimate and a window, with its own estimate, whose values err upward).
    n_jobs : int or None, optional
        Worker processes for a plant of at least :data:`LIMIT_DUAL_FROM_N` states (HiGHS), whose LPs are solved in
        independent tasks (:func:`state_groups`); the values do not depend on it.  ``None`` (default): every core
        when the rows are estimated to take :data:`PARALLEL_SECONDS` or more, else this process; ``-1``: every
        core; ``1``: this process.  Smaller plants solve in this process whatever it says.

    Returns
    -------
    numpy.ndarray, shape (trace.steps, n)
        ``out[t, i] = r_i(t+1) >= 0``.

    Raises
    ------
    InputError
        ``system`` not an :class:`AffineSystem`, ``trace`` not an :class:`ArrivalTrace` or longer than a
        time-varying system (field ``system``, ``trace``); ``x0_radius`` negative, NaN, infinite, of the wrong
        length or above :data:`MAX_X0_RADIUS` (field ``x0_radius``); unknown ``solver``; ``window`` not an
        integer ``>= 1``; ``solver_options`` not a dict; ``n_jobs`` not a positive integer, ``-1`` or ``None``
        (field ``n_jobs``); the rows estimated past :data:`MAX_ESTIMATED_SECONDS`
        without ``force`` (field ``trace``).
    SolverFailure
        An LP without an optimal solution (it is feasible and bounded, so a solver fault; an 'infeasible' or
        'unbounded' answer is reported so, naming ``x0_radius`` and the noise bounds that set the LP's scale).

    Notes
    -----
    **Theorem 1 (no estimator guarantees less).**  *For every estimator* :math:`\varphi` *(linear or not, any
    memory, any use of the stamps), every step* ``t`` *and state* ``i``, :math:`\sup_{\delta \in \mathcal B}
    |x_i(t+1) - \varphi_i(\text{data})| \ge r_i(t+1)`.

    *Proof.* The uncertainty :math:`\delta = (x(0) - \hat x(0), w, v)` ranges over a box :math:`\mathcal B`:
    convex and symmetric (:math:`\delta \in \mathcal B \Rightarrow -\delta \in \mathcal B`).  The delivered data
    and the state are affine in it, data :math:`= \bar y + Z\delta` and :math:`x(t+1) = \bar x + G\delta`, with
    :math:`\bar y, \bar x` known (the prediction from :math:`\hat x(0)`, the inputs and ``f``): the information
    is linear.  The LP's maximum :math:`r_i` is attained (a compact feasible set) at some :math:`\delta^\star`:
    :math:`Z\delta^\star = 0`, :math:`G_i\delta^\star = r_i`.  Both :math:`\pm\delta^\star` lie in
    :math:`\mathcal B` and give the same data :math:`\bar y`, hence the same estimate :math:`e =
    \varphi_i(\bar y)`, whatever :math:`\varphi` does with it, while the states are :math:`\bar x_i \pm r_i`.  The
    larger of the two errors is :math:`\max(|\bar x_i + r_i - e|, |\bar x_i - r_i - e|) \ge r_i`.  ∎

    The bound is attained state by state (Smolyak's theorem: for a linear functional on a symmetric convex set
    with linear information, some linear estimator attains the radius of information): with the optimal
    multipliers :math:`k_i` of the dual below, :math:`\hat x_i = \bar x_i + k_i^\top(\text{data} - \bar y)` has
    error :math:`(G_i - k_i^\top Z)\delta`, whose worst case over the box is
    :math:`\sum_c \beta_c |(G_i - k_i^\top Z)_c| = r_i`.  Different states and steps may need different
    :math:`k_i`, so no single recursive estimator need attain every row at once.

    **Theorem 2 (inside one block the class engine reaches the limit).**  For a block of the class engine
    (:mod:`eqrec.design.classes.engine`), with a box of radius ``μ1`` at its start (``x0_radius = μ1``, time 0)
    and the data ``S`` available at ``d - 1``, the class level is :math:`\ell(d, S) = \max_i r_i(d)` with
    :math:`\mathcal D_{d-1} = S`, and row by row the class's worst case is :math:`r_i(d)`.

    *Proof.* The class LP of row ``i`` (:mod:`eqrec.design.classes.engine`, theorem "separation") is
    :math:`\min_k \sum_c \beta_c |(E_d - k^\top Z_S)_{ic}|` with :math:`\beta = (\eta_w, \eta_v, \mu_1)` per
    coordinate of :math:`\delta`.  It is the LP dual of :math:`\max\{E_{d,i}\delta : Z_S\delta = 0,
    |\delta_c| \le \beta_c\}`: for any ``k`` the Lagrangian :math:`E_{d,i}\delta - k^\top Z_S\delta` maximised
    over the box is :math:`\sum_c \beta_c |(E_{d,i} - k^\top Z_S)_c|` (weak duality), and strong duality holds
    (the primal is feasible, at :math:`\delta = 0`, and bounded).  That primal is :math:`r_i(d)`: the same box
    and the same constraints, the rows of :math:`Z_S` being :math:`C(\tau)x(\tau) + V(\tau)v(\tau)` for
    :math:`\tau \in S`, delivered by ``d - 1``.  ∎

    So every class level is the information limit of its class, and a class-engine estimator is optimal within
    a block; what it loses against the limit on a long run is what the box reset at each block start forgets.
    The identity holds for every class, inner or terminal: the engine stores each row's LP minimum
    (``design.class_certificate.bounds``, the gains' exact worst case, and their largest row in
    ``design.class_levels``), never a value capped at ``μ1``; ``tests/test_information_limit.py``
    checks it on every class of two designs to 1e-9 (measured: 1e-14).  With ``state_weights`` the design's
    system is the weighted one (:meth:`AffineSystem.scaled`), and the identity holds for ``design.system``.

    Examples
    --------
    A scalar random walk measured directly, ``y(1)`` lost:

    >>> import eqrec
    >>> walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    >>> trace = eqrec.ArrivalTrace([0, eqrec.arrivals.traces.NEVER, 0])
    >>> eqrec.information_limit(walk, trace, 1.0).ravel().round(3).tolist()
    [0.6, 0.7, 0.6]
    """
    r0, window = _check(system, trace, x0_radius, solver, window, solver_options)
    if not isinstance(force, (bool, np.bool_)):  # a string such as "no" would read as true
        raise InputError(f"must be True or False, got {force!r}", field="force")
    workers = None if n_jobs is None else check_jobs(n_jobs)
    N, n = trace.steps, system.n
    out = np.zeros((N, n))
    if N == 0:
        return out
    if not force and estimate_seconds(system, N, window) > MAX_ESTIMATED_SECONDS:
        # refused before the cache is read: its keys alone grow as the square of the length
        raise InputError(_refusal(system, N, list(range(N)), window, estimate_seconds(system, N, window)),
                         field="trace")
    delivered_at = delivery_steps(trace)  # step at which y(τ) is delivered (N: not within)
    cache = cache and N <= CACHE_MAX_STEPS
    ctx = (_fingerprint(system, r0, solver, solver_options), window)
    keys: list = [None] * N
    todo: list[int] = []
    for t in range(N if cache else 0):
        if window is None:  # the value depends on (t, D_t) only
            key = (ctx, t, np.packbits(delivered_at[: t + 1] <= t).tobytes())
        else:  # on the arrival times up to t (the boxes of earlier rows)
            key = (ctx, t, np.minimum(delivered_at[: t + 1], t + 1).astype(np.int32).tobytes())
        keys[t] = key
        hit = _CACHE.get(key)
        if hit is not None:
            out[t] = hit
            _STATS["hits"] += 1
            _CACHE.move_to_end(key)
        else:
            todo.append(t)
    if not cache:
        todo = list(range(N))
    if todo:
        tlp = trace_lp(system, trace, r0, SEGMENT)
        _STATS["misses"] += len(todo)
        seconds = estimate_seconds(system, todo, window)
        progress = Progress(len(todo), "information limit: rows") if seconds >= PROGRESS_SECONDS else None
        try:
            if workers is None:
                workers = cpu_count() if n >= LIMIT_DUAL_FROM_N and seconds >= PARALLEL_SECONDS else 1
            _solve_limit(tlp, todo, delivered_at, window, solver, solver_options, out, progress, workers)
        except InfeasibleDesign as exc:  # the zero-data LP is feasible (δ = 0) and bounded: a solver fault
            raise SolverFailure(f"{exc}, although the zero-data LP is feasible and bounded; x0_radius (largest "
                                f"{float(r0.max()):.3g}) and the noise bounds (eta_w {system.eta_w:.3g}, eta_v "
                                f"{system.eta_v:.3g}) set its scale") from exc
        if cache:
            for t in todo:
                _CACHE[keys[t]] = out[t].copy()
            while len(_CACHE) > CACHE_SIZE:
                _CACHE.popitem(last=False)
    return out


def _solve_limit(tlp: TraceLP, todo: list[int], delivered_at: np.ndarray, window: int | None, solver: str,
                 options: dict | None, out: np.ndarray, progress=None, workers: int = 1) -> None:
    """Fill the rows ``todo`` of ``out`` (exact, or windowed: module docstring) on ``workers`` processes."""
    N = out.shape[0]
    fallback = LIMIT_HIGHS_OPTIONS if solver == "highs" and out.shape[1] >= LIMIT_DUAL_FROM_N else None
    _LAST_SOLVE.update(workers=1, tasks=0, task_seconds=0.0)
    if window is None:  # one growing model from time 0
        _limit_rows(tlp, 0, todo, delivered_at, None, solver, options, fallback, out, workers, progress)
        return
    # chunk k holds the rows kW..(k+1)W-1 and starts at s = (k-1)W with the box of row s-1
    pending = set(todo)
    for c0 in range(0, N, window):
        rows = [t for t in range(c0, min(N, c0 + window)) if t in pending]
        if not rows:
            continue
        s = max(0, c0 - window) // SEGMENT * SEGMENT  # x(s) is a variable
        box = None if s == 0 else out[s - 1]
        _limit_rows(tlp, s, rows, delivered_at, box, solver, options, fallback, out, workers, progress)


def _limit_rows(tlp: TraceLP, start: int, rows: list[int], delivered_at: np.ndarray, box: np.ndarray | None,
                solver: str, options: dict | None, fallback: dict | None, out: np.ndarray, workers: int,
                progress) -> None:
    """Fill the rows ``rows`` of ``out`` from the LP of block ``start`` on: one task per chunk of :data:`CHUNK`
    steps and group of :func:`state_groups` (HiGHS from :data:`LIMIT_DUAL_FROM_N` states on), on ``workers``
    processes, the largest chunks first; else, below, one model per chunk for all the states, as before."""
    n = out.shape[1]
    groups = state_groups(n)
    if solver != "highs" or len(groups) == 1:
        for t, v in solve_range(tlp, start, rows, delivered_at, box, solver, options, progress=progress,
                                fallback=fallback).items():
            # the set is symmetric: the maximum is >= 0 (a solver's -0.0 reads 0)
            out[t, _limit_order(t, n)] = np.maximum(v, 0.0)
        return
    chunks = [[t for t in rows if c <= t < c + CHUNK] for c in range(start, rows[-1] + 1, CHUNK)]
    tasks = [(tlp, start, chunk, delivered_at, box, solver, options, fallback, g, True)
             for chunk in reversed(chunks) if chunk for g in groups]
    workers = min(workers, len(tasks))
    results = run_tasks(_limit_task, tasks, n_jobs=workers,
                        progress=None if progress is None else _LPsAsRows(progress, n),
                        units=[len(task[2]) * task[8].size for task in tasks])
    for vals, seconds in results:
        for t, (order, v) in vals.items():
            out[t, order] = np.maximum(v, 0.0)
        _LAST_SOLVE["task_seconds"] += seconds
    _LAST_SOLVE["workers"] = max(_LAST_SOLVE["workers"], workers)
    _LAST_SOLVE["tasks"] += len(tasks)


def block_limit(system: AffineSystem, depth: int, available, x0_radius) -> np.ndarray:
    r"""The information limit of one block: depth ``d``, data ``S`` available at ``d - 1``, box ``x0_radius``.

    The radius :math:`r(d)` with :math:`\mathcal D_{d-1} = S` (measurements of ``S`` on time, the others lost):
    the class ``(d, S)`` of the class engine, whose level is :math:`\max_i r_i(d)` when ``x0_radius = μ1``
    (module docstring, second theorem).

    Parameters
    ----------
    system : AffineSystem
        The plant (from time 0).
    depth : int
        ``d >= 1``.
    available : iterable of int
        ``S``: measurement times in ``0..d-1``.
    x0_radius : float or array_like, shape (n,)
        Radius of the box at the block start (``μ1``).

    Returns
    -------
    numpy.ndarray, shape (n,)
        :math:`r_i(d)` per state.

    Raises
    ------
    InputError
        ``depth < 1`` (field ``depth``), a time of ``available`` outside ``0..d-1`` (field ``available``), or
        the errors of :func:`information_limit`.
    """
    d = integer(depth, "depth", low=1)
    S = sorted({integer(i, "available") for i in available})
    if S and S[-1] >= d:
        raise InputError(f"available times lie in 0..{d - 1}, got {S}", field="available")
    delays = np.full(d, NEVER, np.int64)
    delays[S] = 0
    return information_limit(system, ArrivalTrace(delays), x0_radius)[d - 1]
