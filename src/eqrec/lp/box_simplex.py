r"""Small dense box LPs with many objectives: a compiled dual simplex, and the same through a persistent HiGHS model.

The problem
-----------
The interval hull of a constrained zonotope (:mod:`eqrec.bounds.window_lp`) is ``2n`` linear programs over one
feasible set, each a different objective:

.. math::
    \max\ g^\top z \quad \text{s.t.}\quad \underline b \le Mz \le \overline b,\qquad \underline z \le z \le
    \overline z ,

with every bound finite (a box), ``M`` dense and small (``m`` rows, ``Q`` columns, ``m`` a few tens to a few
hundred).  What the caller needs from each solve is not the optimum but **row multipliers** ``y``: by weak
duality every ``y`` whatsoever gives the guaranteed bound
:math:`\sum_j \max(y_j\underline b_j, y_j\overline b_j) + \sum_c \max((g - M^\top y)_c\underline z_c,
(g - M^\top y)_c\overline z_c)` (:func:`eqrec.bounds.window_lp.dual_bound`), equal to the optimum when ``y`` is
optimal.  So a solver here only decides how *tight* the bound is, never whether it holds.

:func:`box_lp_multipliers` is the entry point; the solver is a parameter (:data:`BOX_SOLVERS`):

``"dense"``
    A dual simplex on the dense matrix, compiled with Numba, that keeps the basis and its explicit inverse
    between the objectives.  Boxed variables make every basis dual feasible once each nonbasic variable sits at
    the bound its reduced cost asks for, so a new objective needs no phase 1: the reduced costs are recomputed,
    the nonbasic variables moved to their bounds, and the dual simplex goes on from the previous basis.  The rows
    are written with slacks, :math:`Mz - s = 0`, :math:`\underline b \le s \le \overline b`, and the first basis is
    the slacks'.  The leaving row is the one of largest infeasibility relative to the norm of its row of the
    inverse (dual steepest edge; the weights exact, recomputed from the rows each update changes: 7-30 % fewer
    pivots than the most infeasible row on the exact estimator's windows at n = 4 to 6); the ratio test flips the
    bounded variables whose breakpoints the step passes while the leaving row stays infeasible (the
    bound-flipping ratio test: about 2.5 times fewer pivots than the textbook test on the exact estimator's
    windows; the breakpoints found by selection, few per pivot, not by sorting them all), then takes the largest
    pivot within Harris's relaxation (1e-9) among the rest; the inverse is updated in product form and computed afresh
    every :data:`REFACTOR_EVERY` pivots (the reduced costs and values then too, and a variable whose fresh reduced
    cost changed sign moves to its other bound).  The first basis may also be given (:func:`box_lp_solve`,
    ``start``: a neighbouring LP's last basis, completed to a nonsingular one); by the same argument any start is
    dual feasible, so it changes the pivots, never the validity of the multipliers.  No HiGHS call and no Python per pivot: on the exact
    estimator's windows at n = 4 (30 rows, 126 to 206 columns) the ``2n`` objectives of a step cost about
    0.5-0.7 ms against 5 ms for a warm-started HiGHS model (about 600 µs per run, most of it HiGHS's fixed cost
    per run).  A pivot costs about ``m·Q`` operations (the pivot row and its pricing; a few ``m²`` for the
    inverse): measured 5-8 µs at 33 rows and 150 columns, 17-33 µs at 78 rows and 402 columns (min over repeats).
    On large windows (145 rows and 1,465 columns at n = 30) it is no match for HiGHS's sparse factors and stalls
    on the degenerate vertices (thousands of pivots where HiGHS needs 200-500), and on ranged rows beyond about 50
    rows (the ``"zonotope+box"`` prior at n = 30: up to 7 times HiGHS's iterations), hence ``"auto"``.
``"auto"`` (default)
    ``"dense"`` up to :data:`DENSE_MAX_ROWS` rows, and beyond for equality rows up to :data:`DENSE_MAX_ENTRIES`
    entries of ``M``; ``"highs"`` otherwise.
``"highs"``
    One HiGHS model (:func:`eqrec.lp.solvers.highs_model`) for all the objectives, each run warm-started from the
    previous optimal basis (dual simplex, no presolve, one thread); its row duals are the multipliers.

An objective the dense solver leaves without an optimum (its pivot budget spent, a singular basis, data no point
satisfies) is solved again by HiGHS.  One that still has no optimum keeps the multipliers the dense solve ended
with (zero from HiGHS alone) and is counted; the bound they give still holds.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np
import scipy.sparse as sp

from eqrec.errors import InputError
from eqrec.lp.model import LinearProgram
from eqrec.lp.solvers import highs_model

#: The solvers of :func:`box_lp_multipliers`.
BOX_SOLVERS = ("auto", "dense", "highs")

#: ``solver="auto"`` uses the dense dual simplex up to this many rows whatever the LP (at 145 rows and 1,465
#: columns, the exact estimator's window at n = 30, the dense solver's explicit inverse and full pricing cost more
#: than HiGHS's sparse factors, and its pivots on those degenerate LPs run into the thousands).
DENSE_MAX_ROWS = 64

#: ... and beyond :data:`DENSE_MAX_ROWS` rows, for LPs whose rows are all equalities, up to this many entries of
#: ``M`` (rows times columns): a dense pivot costs about ``m·Q`` operations (the pivot row and its pricing).
#: Measured on the exact estimator's windows (each LP's ``2n`` objectives, min of repeats, warm-started as in the
#: estimator): tanks n = 6, window 50 (64-82 rows, 388-406 columns, about 33,000 entries) dense 4-8 ms against
#: 15-26 ms for HiGHS (which keeps no basis from one step to the next); tank chain n = 20, window 40, dense against
#: HiGHS 0.27-0.86 up to 35,000 entries, 0.44-2.1 at 51,000-116,000.  LPs with ranged rows (the
#: ``"zonotope+box"`` prior) stay at :data:`DENSE_MAX_ROWS`: the dense solver stalls on them (n = 30, window 10:
#: 55-65 rows, 5,000-72,000 pivots against HiGHS's 1,400-10,800).
DENSE_MAX_ENTRIES = 40_000

#: The dense solver's pivot budget per objective: this many per row (plus 50); past it the objective goes to HiGHS.
DENSE_PIVOTS_PER_ROW = 20

#: Pivots between two fresh inverses of the dense dual simplex's basis (the product-form updates in between).
REFACTOR_EVERY = 50

_NO_START = np.zeros(0, np.bool_)  # the slack basis

#: HiGHS options of the ``"highs"`` backend: the simplex (warm starts between objectives), no presolve (redone at
#: every run otherwise), one thread.
HIGHS_BOX_OPTIONS = {"solver": "simplex", "presolve": "off", "threads": 1}

_PRIMAL_TOL = 1e-9  # a basic variable this far outside its bounds (relative to the bound's size) is infeasible
_DUAL_TOL = 1e-9  # Harris's relaxation of the ratio test
_PIVOT_TOL = 1e-9  # smallest pivot accepted (relative to the row's largest entry)
_PERTURB = 1e-7  # the costs' perturbation (relative to the objective's largest entry)
_START_PIVOT_TOL = 1e-9  # a start basis: smallest pivot of its elimination (relative to the block's largest entry)
_SELECT_PASSES = 8  # bound flipping: breakpoints found by selection before the rest is sorted
_START_MAX_COND = 1e10  # a start basis whose inverse is larger than this (times the basis's size) is not used


@numba.njit(cache=True)
def _column(M, j, Q, out):
    """Column ``j`` of ``[M, -I]`` into ``out``."""
    m = M.shape[0]
    if j < Q:
        for i in range(m):
            out[i] = M[i, j]
    else:
        for i in range(m):
            out[i] = 0.0
        out[j - Q] = -1.0


@numba.njit(cache=True)
def _refactor(M, basis, Q, Binv):
    """``Binv = B⁻¹`` for the basis columns of ``[M, -I]``; ``False`` if singular to working precision."""
    m = M.shape[0]
    B = np.empty((m, m))
    col = np.empty(m)
    for p in range(m):
        _column(M, basis[p], Q, col)
        B[:, p] = col
    if m == 0:
        return True
    try:  # an exactly singular basis raises inside LAPACK's getrf: report it as singular, as documented
        inv = np.linalg.inv(B)
    except Exception:  # noqa: BLE001 - Numba catches only the bare class
        return False
    if not np.all(np.isfinite(inv)):
        return False
    Binv[:, :] = inv
    return True


@numba.njit(cache=True)
def _row_norms(Binv, weight):
    """``weight[p] = ‖row p of B⁻¹‖²`` (the dual steepest-edge weights; at least 1e-300)."""
    m = Binv.shape[0]
    for p in range(m):
        acc = 0.0
        for c in range(m):
            acc += Binv[p, c] * Binv[p, c]
        weight[p] = max(acc, 1e-300)


@numba.njit(cache=True)
def _well_conditioned(M, basis, Q, Binv):
    """Whether ``‖B‖_max ‖B⁻¹‖_max · m`` (a cheap bound of the condition number's size) is below
    :data:`_START_MAX_COND`."""
    m = M.shape[0]
    bmax = 0.0
    for p in range(m):
        j = basis[p]
        if j < Q:
            for i in range(m):
                bmax = max(bmax, abs(M[i, j]))
        else:
            bmax = max(bmax, 1.0)
    imax = 0.0
    for p in range(m):
        for i in range(m):
            imax = max(imax, abs(Binv[p, i]))
    return bmax * imax * m < _START_MAX_COND


@numba.njit(cache=True)
def _primal_values(M, basis, nonbasic_value, is_basic, Q, Binv, x):
    """``x`` of the nonbasic variables at their bounds and of the basic ones from ``B x_B = -A_N x_N``."""
    m = M.shape[0]
    xn = np.zeros(Q)
    for j in range(Q):
        if not is_basic[j]:
            x[j] = nonbasic_value[j]
            xn[j] = x[j]
    rhs = np.empty(m)
    for i in range(m):  # row by row (M is C-contiguous)
        acc = 0.0
        for j in range(Q):
            acc -= M[i, j] * xn[j]
        rhs[i] = acc
    for k in range(m):
        j = Q + k
        if not is_basic[j]:
            x[j] = nonbasic_value[j]
            rhs[k] += x[j]  # column -e_k
    for p in range(m):
        acc = 0.0
        for i in range(m):
            acc += Binv[p, i] * rhs[i]
        x[basis[p]] = acc


@numba.njit(cache=True)
def _multipliers(basis, f, Binv, y):
    """``y = B⁻ᵀ f_B``."""
    m = Binv.shape[0]
    for i in range(m):
        y[i] = 0.0
    for p in range(m):  # row by row of B⁻¹ (C-contiguous)
        fp = f[basis[p]]
        if fp != 0.0:
            for i in range(m):
                y[i] += Binv[p, i] * fp


@numba.njit(cache=True)
def _reduced_costs(M, basis, f, Q, Binv, d, y):
    """``y = B⁻ᵀ f_B`` and ``d = f - Aᵀy`` for ``A = [M, -I]``."""
    m = M.shape[0]
    _multipliers(basis, f, Binv, y)
    for j in range(Q):
        d[j] = f[j]
    for i in range(m):
        yi = y[i]
        if yi != 0.0:
            for j in range(Q):
                d[j] -= M[i, j] * yi
    for k in range(m):
        d[Q + k] = f[Q + k] + y[k]


@numba.njit(cache=True)
def _start_basis(M, Q, want):
    """A nonsingular basis of ``[M, -I]`` close to the wanted variables ``want`` (bool, ``Q + m``): the wanted
    columns of ``M`` that are independent on the rows whose slack is not wanted (Gaussian elimination with partial
    pivoting on that block, column by column: a column without a pivot is dropped), and the slacks of every other
    row.  Returns the basis (``m`` variable indices)."""
    m = M.shape[0]
    rows = np.empty(m, np.int64)
    nr = 0
    for i in range(m):
        if not want[Q + i]:
            rows[nr] = i
            nr += 1
    cols = np.empty(Q, np.int64)
    nc = 0
    for j in range(Q):
        if want[j]:
            cols[nc] = j
            nc += 1
    T = np.empty((nr, nc))
    scale = 0.0
    for a in range(nr):
        for b in range(nc):
            T[a, b] = M[rows[a], cols[b]]
            scale = max(scale, abs(T[a, b]))
    used_r = np.zeros(nr, np.bool_)
    covered = np.zeros(m, np.bool_)  # rows whose slack leaves the basis for a wanted column
    basis = np.empty(m, np.int64)
    nb = 0
    for b in range(nc):  # the wanted columns in order, each pivoted on its largest remaining entry (or dropped)
        best, pa = 0.0, -1
        for a in range(nr):
            if not used_r[a] and abs(T[a, b]) > best:
                best, pa = abs(T[a, b]), a
        if pa < 0 or best <= _START_PIVOT_TOL * scale:
            continue
        used_r[pa] = True
        inv = 1.0 / T[pa, b]
        for a in range(nr):
            if not used_r[a] and T[a, b] != 0.0:
                fac = T[a, b] * inv
                for c in range(b + 1, nc):
                    T[a, c] -= fac * T[pa, c]
        covered[rows[pa]] = True
        basis[nb] = cols[b]
        nb += 1
    for i in range(m):
        if not covered[i]:
            basis[nb] = Q + i
            nb += 1
    return basis


@numba.njit(cache=True)
def _dual_simplex(M, lo, hi, objectives, max_iter, perturb, start_want, start_upper):
    """The dense dual simplex over the objectives in order (module docstring), from the slack basis, or (when
    ``start_want`` has ``Q + m`` entries) from the nonsingular basis nearest the wanted variables
    (:func:`_start_basis`), each nonbasic variable first at its upper bound where ``start_upper`` says so (the
    first objective's reduced costs then move the others to the bound they ask for: dual feasible whatever the
    start).  A start basis that is singular or ill-conditioned to working precision is replaced by the slacks'.

    Returns the multipliers in the maximisation convention (``g ≈ Mᵀy`` plus the box part), per objective,
    the status per objective (0 optimal, 1 iteration limit, 2 infeasible, 3 singular basis), the pivots, the
    final basis (``is_basic``, and which nonbasic variables sit at their upper bound) and whether the given start
    was used.
    """
    m, Q = M.shape
    nv = Q + m
    K = objectives.shape[0]
    ys = np.zeros((K, m))
    status = np.zeros(K, np.int64)
    basis = np.arange(Q, Q + m)
    is_basic = np.zeros(nv, np.bool_)
    Binv = -np.eye(m)
    started = False
    if start_want.shape[0] == nv:
        trial = _start_basis(M, Q, start_want)
        if _refactor(M, trial, Q, Binv) and _well_conditioned(M, trial, Q, Binv):
            basis = trial
            started = True
        else:
            Binv = -np.eye(m)
    for p in range(m):
        is_basic[basis[p]] = True
    x = np.zeros(nv)
    d = np.zeros(nv)
    y = np.zeros(m)
    f = np.zeros(nv)
    nb_value = lo.copy()
    if start_upper.shape[0] == nv:
        for j in range(nv):
            if start_upper[j] and not is_basic[j]:
                nb_value[j] = hi[j]
    weight = np.empty(m)  # dual steepest edge: the squared norms of the rows of B⁻¹
    _row_norms(Binv, weight)
    alpha = np.empty(nv)
    col = np.empty(m)
    cand = np.empty(nv, np.int64)
    ratio = np.empty(nv)
    dlt = np.empty(m)
    a_col = np.empty(m)
    pivots = 0
    since = 0
    phases = 2 if perturb else 1
    for kp in range(phases * K):
        k, perturbed = kp // phases, perturb and kp % 2 == 0
        gmax = 0.0
        for j in range(Q):
            f[j] = -objectives[k, j]  # minimise -g
            gmax = max(gmax, abs(f[j]))
        for j in range(Q, nv):
            f[j] = 0.0
        if perturbed:
            # first with costs perturbed (deterministically) away from the ties that stall the dual simplex on a
            # degenerate box LP, then from that basis with the true costs (module docstring)
            for j in range(nv):
                if lo[j] != hi[j]:
                    e = _PERTURB * max(gmax, 1.0) * (1.0 + ((j * 2654435761) % 1024) / 1024.0)
                    f[j] += -e if (not is_basic[j] and nb_value[j] == hi[j]) else e
        _reduced_costs(M, basis, f, Q, Binv, d, y)
        for j in range(nv):  # every nonbasic variable at the bound its reduced cost asks for: dual feasible
            if not is_basic[j]:  # (a reduced cost within the tolerance of zero leaves its variable where it is)
                if d[j] > _DUAL_TOL:
                    nb_value[j] = lo[j]
                elif d[j] < -_DUAL_TOL:
                    nb_value[j] = hi[j]
        _primal_values(M, basis, nb_value, is_basic, Q, Binv, x)
        st = 1
        for _ in range(max_iter):
            # leaving: the largest infeasibility relative to its row of B⁻¹ (dual steepest edge, exact weights)
            p_out = -1
            worst = 0.0
            for p in range(m):
                j = basis[p]
                tol = _PRIMAL_TOL * (1.0 + max(abs(lo[j]), abs(hi[j])))
                if x[j] < lo[j] - tol:
                    v = lo[j] - x[j]
                elif x[j] > hi[j] + tol:
                    v = x[j] - hi[j]
                else:
                    continue
                v = v * v / weight[p]
                if v > worst:
                    worst, p_out = v, p
            if p_out < 0:
                st = 0
                break
            r = basis[p_out]
            to_lower = x[r] < lo[r]
            for j in range(Q):
                alpha[j] = 0.0
            for i in range(m):
                ri = Binv[p_out, i]
                if ri != 0.0:
                    for j in range(Q):
                        alpha[j] += ri * M[i, j]
            amax = 0.0
            for j in range(Q):
                amax = max(amax, abs(alpha[j]))
            for kk in range(m):
                alpha[Q + kk] = -Binv[p_out, kk]
                amax = max(amax, abs(alpha[Q + kk]))
            ptol = _PIVOT_TOL * max(amax, 1.0)
            # the candidates (a nonbasic, not fixed variable whose move reduces the infeasibility) and their ratios
            nc = 0
            for j in range(nv):
                if is_basic[j] or lo[j] == hi[j]:
                    continue  # a fixed nonbasic variable never needs to enter
                a = alpha[j]
                at_upper = nb_value[j] == hi[j]
                if to_lower:
                    ok = (a < -ptol and not at_upper) or (a > ptol and at_upper)
                else:
                    ok = (a > ptol and not at_upper) or (a < -ptol and at_upper)
                if ok:
                    cand[nc] = j
                    ratio[nc] = max(-d[j] if at_upper else d[j], 0.0) / abs(a)
                    nc += 1
            if nc == 0:
                st = 2  # no entering column: no point satisfies the rows and the box
                break
            # bound flipping: pass the breakpoints in increasing order while the leaving row's infeasibility stays
            # positive.  Selection, not a sort: the smallest remaining ratio is swapped to the front, one pass over
            # the candidates per breakpoint passed (few per pivot); past _SELECT_PASSES of them the rest is sorted.
            # cand[:kq] end as the passed breakpoints in order, cand[kq:] the others (in any order).
            slope = abs(x[r] - (lo[r] if to_lower else hi[r]))
            kq = nc - 1
            for kk in range(nc):
                if kk < _SELECT_PASSES:
                    bi = kk
                    for c2 in range(kk + 1, nc):
                        if ratio[c2] < ratio[bi]:
                            bi = c2
                    if bi != kk:
                        cand[kk], cand[bi] = cand[bi], cand[kk]
                        ratio[kk], ratio[bi] = ratio[bi], ratio[kk]
                elif kk == _SELECT_PASSES:  # many breakpoints passed: sort the rest once, then walk it
                    order = np.argsort(ratio[kk:nc]) + kk
                    cs = cand[order].copy()
                    rs = ratio[order].copy()
                    cand[kk:nc] = cs
                    ratio[kk:nc] = rs
                j = cand[kk]
                slope -= abs(alpha[j]) * (hi[j] - lo[j])
                if slope < 0.0:
                    kq = kk
                    break
            # Harris: among the breakpoints not passed, the largest pivot within the relaxed step
            theta_max = np.inf
            for kk in range(kq, nc):
                j = cand[kk]
                t = (ratio[kk] * abs(alpha[j]) + _DUAL_TOL) / abs(alpha[j])
                if t < theta_max:
                    theta_max = t
            q = -1
            best = 0.0
            for kk in range(kq, nc):
                j = cand[kk]
                if ratio[kk] <= theta_max and abs(alpha[j]) > best:
                    best, q = abs(alpha[j]), j
            # the passed breakpoints flip to their other bound
            nflip = 0
            for i in range(m):
                dlt[i] = 0.0
            for kk in range(kq):
                j = cand[kk]
                if j == q:
                    continue
                new = lo[j] if nb_value[j] == hi[j] else hi[j]
                step = new - nb_value[j]
                nb_value[j] = new
                x[j] = new
                _column(M, j, Q, col)
                for i in range(m):
                    dlt[i] += col[i] * step
                nflip += 1
            if nflip:
                for p in range(m):
                    acc = 0.0
                    for i in range(m):
                        acc += Binv[p, i] * dlt[i]
                    x[basis[p]] -= acc
            dq = d[q]
            if (nb_value[q] == hi[q] and dq > 0.0) or (nb_value[q] != hi[q] and dq < 0.0):
                dq = 0.0  # within Harris's tolerance on the wrong side: a degenerate step, not a loss of feasibility
            theta_d = dq / alpha[q]
            for j in range(nv):
                if not is_basic[j]:
                    d[j] -= theta_d * alpha[j]
            d[q] = 0.0
            d[r] = -theta_d
            # primal step: the entering column through the basis
            if q < Q:
                for p in range(m):
                    acc = 0.0
                    for i in range(m):
                        acc += Binv[p, i] * M[i, q]
                    a_col[p] = acc
            else:
                for p in range(m):
                    a_col[p] = -Binv[p, q - Q]
            bound = lo[r] if to_lower else hi[r]
            theta_p = (x[r] - bound) / a_col[p_out]
            for p in range(m):
                x[basis[p]] -= theta_p * a_col[p]
            x[q] = nb_value[q] + theta_p
            x[r] = bound
            nb_value[r] = bound
            # the inverse: product-form update
            # (and the rows' squared norms, the steepest-edge weights, computed afresh from the rows changed)
            piv = a_col[p_out]
            acc = 0.0
            for c in range(m):
                Binv[p_out, c] /= piv
                acc += Binv[p_out, c] * Binv[p_out, c]
            weight[p_out] = acc
            for p in range(m):
                if p != p_out and a_col[p] != 0.0:
                    f_ = a_col[p]
                    acc = 0.0
                    for c in range(m):
                        Binv[p, c] -= f_ * Binv[p_out, c]
                        acc += Binv[p, c] * Binv[p, c]
                    weight[p] = acc
            basis[p_out] = q
            is_basic[q] = True
            is_basic[r] = False
            pivots += 1
            since += 1
            if since >= REFACTOR_EVERY:
                since = 0
                if not _refactor(M, basis, Q, Binv):
                    st = 3
                    break
                _row_norms(Binv, weight)
                _reduced_costs(M, basis, f, Q, Binv, d, y)
                for j in range(nv):  # the fresh reduced costs may disagree in sign: move to the other bound
                    if not is_basic[j]:
                        if d[j] > _DUAL_TOL:
                            nb_value[j] = lo[j]
                        elif d[j] < -_DUAL_TOL:
                            nb_value[j] = hi[j]
                _primal_values(M, basis, nb_value, is_basic, Q, Binv, x)
        if perturbed:
            continue
        _multipliers(basis, f, Binv, y)  # the multipliers of the final basis, computed afresh
        for i in range(m):
            ys[k, i] = -y[i]  # of min -g: the maximisation's multipliers are their negatives
        status[k] = st
    at_upper = np.zeros(nv, np.bool_)
    for j in range(nv):
        at_upper[j] = (not is_basic[j]) and nb_value[j] == hi[j] and lo[j] != hi[j]
    return ys, status, pivots, is_basic, at_upper, started


@dataclass(frozen=True)
class BoxLPResult:
    """What :func:`box_lp_solve` found.

    Parameters
    ----------
    y : numpy.ndarray, shape (K, m)
        Multipliers per objective (optimal ones where ``optimal``); any of them gives a bound.
    optimal : numpy.ndarray of bool, shape (K,)
        Whether the solve of each objective ended at an optimum.
    pivots : int
        Simplex pivots of the dense solver plus simplex iterations of HiGHS, over all the objectives.
    is_basic, at_upper : numpy.ndarray of bool, shape (Q + m,) or None
        The dense solver's final basis (the columns, then the rows' slacks) and its nonbasic variables at their
        upper bound: a start for a neighbouring LP (``start=``).  ``None`` when HiGHS solved them all.
    warm : bool
        Whether the given ``start`` was used (``False`` without one, or when its basis was singular).
    """

    y: np.ndarray
    optimal: np.ndarray
    pivots: int
    is_basic: "np.ndarray | None"
    at_upper: "np.ndarray | None"
    warm: bool


def box_lp_multipliers(M: np.ndarray, row_lower: np.ndarray, row_upper: np.ndarray, col_lower: np.ndarray,
                       col_upper: np.ndarray, objectives: np.ndarray, solver: str = "auto",
                       max_iterations: int | None = None, perturb: bool = False) -> tuple[np.ndarray, np.ndarray]:
    r"""Row multipliers of :math:`\max g_k^\top z` over one box LP, for every objective ``g_k`` in order, from the
    slack basis (:func:`box_lp_solve` without a start; module docstring).

    Parameters
    ----------
    M : numpy.ndarray, shape (m, Q)
        The rows.
    row_lower, row_upper : numpy.ndarray, shape (m,)
        Their bounds (finite; equal for an equality).
    col_lower, col_upper : numpy.ndarray, shape (Q,)
        The box (finite).
    objectives : numpy.ndarray, shape (K, Q)
        The objectives ``g_k``, maximised.
    solver : {"auto", "dense", "highs"}, optional
        :data:`BOX_SOLVERS` (:func:`box_lp_solve`).
    max_iterations : int, optional
        Pivots per objective of the dense solver (default ``DENSE_PIVOTS_PER_ROW · m + 50``).
    perturb : bool, optional
        Dense solver: cost perturbation first (:func:`box_lp_solve`).

    Returns
    -------
    y : numpy.ndarray, shape (K, m)
        Multipliers per objective: ``g_k - Mᵀy_k`` is the box's part (optimal ones when ``optimal[k]``).
    optimal : numpy.ndarray of bool, shape (K,)
        Whether the solve of each objective ended at an optimum.

    Raises
    ------
    InputError
        An unknown ``solver``, or a bound that is not finite.
    """
    res = box_lp_solve(M, row_lower, row_upper, col_lower, col_upper, objectives, solver, max_iterations, perturb)
    return res.y, res.optimal


def box_lp_solve(M: np.ndarray, row_lower: np.ndarray, row_upper: np.ndarray, col_lower: np.ndarray,
                 col_upper: np.ndarray, objectives: np.ndarray, solver: str = "auto",
                 max_iterations: int | None = None, perturb: bool = False,
                 start: "tuple[np.ndarray, np.ndarray] | None" = None) -> BoxLPResult:
    r"""Row multipliers of :math:`\max g_k^\top z` over one box LP, for every objective ``g_k`` in order (module
    docstring), optionally warm-started from a basis, with the pivots spent and the final basis.

    Parameters
    ----------
    M : numpy.ndarray, shape (m, Q)
        The rows.
    row_lower, row_upper : numpy.ndarray, shape (m,)
        Their bounds (finite; equal for an equality).
    col_lower, col_upper : numpy.ndarray, shape (Q,)
        The box (finite).
    objectives : numpy.ndarray, shape (K, Q)
        The objectives ``g_k``, maximised.
    solver : {"auto", "dense", "highs"}, optional
        :data:`BOX_SOLVERS`.  ``"auto"`` (default): ``"dense"`` up to :data:`DENSE_MAX_ROWS` rows (and beyond, for
        equality rows, up to :data:`DENSE_MAX_ENTRIES` entries of ``M``), ``"highs"`` otherwise; either way the
        objectives the dense solver leaves without an optimum are solved again by HiGHS.
    max_iterations : int, optional
        Pivots per objective of the dense solver (default ``DENSE_PIVOTS_PER_ROW · m + 50``).
    perturb : bool, optional
        Dense solver: solve each objective first with its costs perturbed by about 1e-7 of their size (breaks
        the ties on which the dual simplex can stall), then from that basis with the true costs.  Default
        ``False``: on the exact estimator's windows (n = 4) it costs a third more pivots and time.
    start : tuple of numpy.ndarray of bool, optional
        Dense solver: ``(wanted, at_upper)``, each of ``Q + m`` entries (the columns, then the rows' slacks): the
        first objective starts from the nonsingular basis nearest the wanted variables (the wanted columns
        independent on the rows whose slack is not wanted, and the other rows' slacks), the nonbasic variables
        marked at their upper bound, the others at their lower one, then each moved to the bound its reduced
        cost asks for.  With boxed variables any nonsingular basis so placed is dual feasible, so any start is
        a valid one: a poor one costs pivots, never a wrong answer.  A start whose basis is singular or
        ill-conditioned is replaced by the slack basis.  Ignored by HiGHS.

    Returns
    -------
    BoxLPResult
        Multipliers, optimality, pivots, the final basis.

    Raises
    ------
    InputError
        An unknown ``solver``, a bound that is not finite, or a ``start`` of the wrong size.
    """
    if solver not in BOX_SOLVERS:
        raise InputError(f"unknown box-LP solver {solver!r}; one of {', '.join(BOX_SOLVERS)}", field="solver")
    M = np.ascontiguousarray(M, dtype=float)
    objectives = np.ascontiguousarray(np.atleast_2d(objectives), dtype=float)
    m, Q = M.shape
    lo = np.concatenate([np.asarray(col_lower, float), np.asarray(row_lower, float)])
    hi = np.concatenate([np.asarray(col_upper, float), np.asarray(row_upper, float)])
    if not (np.all(np.isfinite(lo)) and np.all(np.isfinite(hi))):
        raise InputError("a box LP needs finite bounds on every row and column", field="bounds")
    if start is None:
        want = upper = _NO_START
    else:
        want, upper = (np.require(a, np.bool_, ("C",)) for a in start)
        if want.shape != (Q + m,) or upper.shape != (Q + m,):
            raise InputError(f"a start basis has one entry per column and row ({Q + m}), got {want.shape} and "
                             f"{upper.shape}", field="start")
    K = objectives.shape[0]
    if m == 0:
        return BoxLPResult(np.zeros((K, 0)), np.ones(K, dtype=bool), 0, None, None, False)
    if solver == "auto":
        solver = "dense" if _dense_by_default(M, lo[Q:], hi[Q:]) else "highs"
    if solver == "highs":
        y, optimal, its = _highs_multipliers(M, lo, hi, objectives)
        return BoxLPResult(y, optimal, its, None, None, False)
    iters = DENSE_PIVOTS_PER_ROW * m + 50 if max_iterations is None else int(max_iterations)
    y, status, pivots, is_basic, at_upper, warm = _dual_simplex(M, lo, hi, objectives, iters, perturb, want, upper)
    optimal = status == 0
    if not optimal.all():
        again = np.flatnonzero(~optimal)  # HiGHS for the objectives the dense solver left without an optimum
        y2, opt2, its = _highs_multipliers(M, lo, hi, objectives[again])
        pivots += its
        keep = opt2  # a HiGHS answer replaces the dense one only when it is an optimum
        y[again[keep]] = y2[keep]
        optimal[again[keep]] = True
    return BoxLPResult(y, optimal, int(pivots), is_basic, at_upper, bool(warm))


def _dense_by_default(M: np.ndarray, row_lower: np.ndarray, row_upper: np.ndarray) -> bool:
    """``solver="auto"``'s choice: the dense solver up to :data:`DENSE_MAX_ROWS` rows, or up to
    :data:`DENSE_MAX_ENTRIES` entries of ``M`` when every row is an equality; HiGHS otherwise."""
    m, Q = M.shape
    if m <= DENSE_MAX_ROWS:
        return True
    return m * Q <= DENSE_MAX_ENTRIES and bool(np.array_equal(row_lower, row_upper))


def _highs_multipliers(M: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                       objectives: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The ``"highs"`` backend: one model, each objective warm-started from the previous optimal basis; the
    multipliers, which objectives ended optimal, and HiGHS's simplex iterations."""
    m, Q = M.shape
    K = objectives.shape[0]
    lp = LinearProgram(c=np.zeros(Q), A=sp.csc_matrix(M), row_lower=lo[Q:], row_upper=hi[Q:],
                       col_lower=lo[:Q], col_upper=hi[:Q])
    h = highs_model(lp, HIGHS_BOX_OPTIONS)
    cols = np.arange(Q, dtype=np.int32)
    y = np.zeros((K, m))
    optimal = np.zeros(K, dtype=bool)
    its = 0
    for k in range(K):
        h.changeColsCost(Q, cols, np.ascontiguousarray(-objectives[k]))
        h.run()
        its += max(int(h.getInfo().simplex_iteration_count), 0)
        sol = h.getSolution()
        if int(h.getModelStatus()) == 7 and sol.dual_valid:
            y[k] = -np.asarray(sol.row_dual)  # HiGHS: c - Mᵀ(row_dual) = reduced costs, c = -g
            optimal[k] = True
        else:
            h.clearSolver()  # the next objective from scratch
    return y, optimal, its
