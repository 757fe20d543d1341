"""The box-LP solvers of eqrec.lp.box_simplex: the compiled dense dual simplex against HiGHS on random box LPs
(the optimum its multipliers certify), the window LPs of the exact estimator, and their failure modes."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.optimize

from eqrec.bounds.window_lp import bounds_from_multipliers, dual_bound, lp_hull, window_set
from eqrec.errors import InputError
from eqrec.lp.box_simplex import box_lp_multipliers, box_lp_solve


def weak_dual(g, M, lo, hi, y):
    """The weak-duality bound of max g·z over lo <= Mz <= hi, |z| <= 1, from multipliers y (no rounding)."""
    return float(np.maximum(y * lo, y * hi).sum() + np.abs(g - y @ M).sum())


def random_box_lp(rng, m, Q, ranged):
    M = rng.normal(size=(m, Q)) * (rng.random((m, Q)) < 0.6)
    z = rng.uniform(-1, 1, Q)  # a feasible point
    b = M @ z
    width = rng.uniform(0, 0.5, m) if ranged else np.zeros(m)
    return M, b - width, b + width


@pytest.mark.parametrize("m,Q,ranged", [(3, 8, False), (12, 40, False), (12, 40, True), (30, 126, False),
                                        (50, 200, True)])
def test_dense_multipliers_certify_the_optimum(m, Q, ranged):
    """Each objective's multipliers give a weak-duality bound equal to the LP's optimum (SciPy's HiGHS) to 1e-7,
    for every objective of a chain; the HiGHS backend agrees."""
    rng = np.random.default_rng(m * 1000 + Q + ranged)
    M, lo, hi = random_box_lp(rng, m, Q, ranged)
    G = rng.normal(size=(6, Q))
    ones = np.ones(Q)
    for solver in ("dense", "highs"):
        y, optimal = box_lp_multipliers(M, lo, hi, -ones, ones, G, solver)
        assert optimal.all(), solver
        for g, yk in zip(G, y):
            ref = scipy.optimize.linprog(-g, A_ub=np.vstack([M, -M]), b_ub=np.concatenate([hi, -lo]),
                                         bounds=(-1, 1), method="highs")
            best = -ref.fun
            bound = weak_dual(g, M, lo, hi, yk)
            assert bound >= best - 1e-7 * (1 + abs(best))  # weak duality (up to the reference's accuracy)
            assert bound <= best + 1e-7 * (1 + abs(best)), (solver, bound, best)  # optimal multipliers


def test_infeasible_and_iteration_limit_still_give_bounds():
    """Rows no point satisfies: the dense solve ends without an optimum (HiGHS too) and reports it; an iteration
    limit of one pivot falls back to HiGHS for the objectives left without an optimum."""
    M = np.array([[1.0, 1.0], [1.0, -1.0]])
    lo = hi = np.array([3.0, 0.0])  # z1 + z2 = 3 is outside the box
    y, optimal = box_lp_multipliers(M, lo, hi, -np.ones(2), np.ones(2), np.eye(2), "dense")
    assert not optimal.any()
    rng = np.random.default_rng(5)
    M, lo, hi = random_box_lp(rng, 20, 60, False)
    G = rng.normal(size=(3, 60))
    y, optimal = box_lp_multipliers(M, lo, hi, -np.ones(60), np.ones(60), G, "dense", max_iterations=1)
    assert optimal.all()  # the objectives the dense solver left were solved by HiGHS
    y0, _ = box_lp_multipliers(M, lo, hi, -np.ones(60), np.ones(60), G, "highs")
    for g, a, b in zip(G, y, y0):
        assert weak_dual(g, M, lo, hi, a) == pytest.approx(weak_dual(g, M, lo, hi, b), rel=1e-7)


def test_bad_input():
    with pytest.raises(InputError, match="unknown box-LP solver"):
        box_lp_multipliers(np.ones((1, 1)), [0.0], [0.0], [-1.0], [1.0], [[1.0]], "simplex")
    with pytest.raises(InputError, match="finite bounds"):
        box_lp_multipliers(np.ones((1, 1)), [0.0], [np.inf], [-1.0], [1.0], [[1.0]])


def test_window_hull_dense_equals_highs_and_vectorised_bound_is_dual_bound():
    """The window set's hull by the dense solver and by HiGHS agree to 1e-7 (both optimal), each end at least the
    other's optimum up to that; the vectorised bound is dual_bound's to rounding."""
    rng = np.random.default_rng(11)
    L, n, p, nw, nv = 25, 4, 1, 2, 1
    A = np.broadcast_to(0.9 * np.linalg.qr(rng.normal(size=(n, n)))[0], (L, n, n)).copy()
    C = rng.normal(size=(L, p, n))
    E = 0.1 * rng.normal(size=(L, n, nw))
    V = 0.05 * np.ones((L, p, nv))
    measured = rng.random(L) < 0.7
    G0 = 0.5 * np.eye(n)
    x = G0 @ rng.uniform(-1, 1, n)
    Y = np.zeros((L, p))
    for j in range(L):
        Y[j] = C[j] @ x + V[j] @ rng.uniform(-1, 1, nv)
        x = A[j] @ x + E[j] @ rng.uniform(-1, 1, nw)
    ws = window_set(A, C, E, V, np.zeros((L, n)), measured, Y, np.zeros(n), G0)
    lo_d, hi_d, fb_d = lp_hull(ws, "pred", "dense")
    lo_h, hi_h, fb_h = lp_hull(ws, "pred", "highs")
    assert fb_d == fb_h == 0
    assert np.all(lo_d <= x) and np.all(x <= hi_d)
    np.testing.assert_allclose(hi_d, hi_h, rtol=0, atol=1e-7)
    np.testing.assert_allclose(lo_d, lo_h, rtol=0, atol=1e-7)
    y = rng.normal(size=(3, ws.M.shape[0]))
    rows = ws.X_pred[:3]
    vec = bounds_from_multipliers(rows, ws.M, ws.lower, ws.upper, y, ws.mag_pred[:3], ws.mag_rows, ws.kappa)
    one = [dual_bound(r, ws.M, ws.lower, ws.upper, yk, mg, ws.mag_rows, ws.kappa)
           for r, yk, mg in zip(rows, y, ws.mag_pred[:3])]
    np.testing.assert_allclose(vec, one, rtol=1e-12)


def test_exactly_singular_basis_is_reported_not_raised():
    """``_refactor`` on an exactly singular basis returns False (the solver then hands the objective over), as its
    docstring says, instead of raising LAPACK's LinAlgError out of the compiled solver."""
    from eqrec.lp.box_simplex import _refactor

    M = np.array([[1.0, 2.0, 0.0], [2.0, 4.0, 0.0]])  # columns 0 and 1 are parallel: that basis is singular
    Binv = np.full((2, 2), 7.0)
    assert _refactor(M, np.array([0, 1]), M.shape[1], Binv) is False
    assert np.all(Binv == 7.0)  # nothing written
    assert _refactor(M, np.array([0, 4]), M.shape[1], Binv) is True  # column 0 and the second row's slack


def _feasible_lp(seed, m=20, Q=70):
    """A random box LP with equality rows through a known point ``z`` (feasible up to the rows' rounding)."""
    rng = np.random.default_rng(seed)
    M = rng.normal(size=(m, Q)) * (rng.random((m, Q)) < 0.6)
    z = rng.uniform(-1, 1, Q)
    b = M @ z
    return rng, M, b, z


def test_warm_start_from_the_own_optimum_needs_no_pivot():
    """Started from the final basis of the same LP and objective, the dense solver ends at once (no pivot) with the
    same certified bound; the final basis has one basic variable per row."""
    rng, M, b, _ = _feasible_lp(21)
    g = rng.normal(size=(1, M.shape[1]))
    ones = np.ones(M.shape[1])
    cold = box_lp_solve(M, b, b, -ones, ones, g, "dense")
    assert cold.optimal.all() and not cold.warm and cold.pivots > 0
    assert cold.is_basic.sum() == M.shape[0]
    warm = box_lp_solve(M, b, b, -ones, ones, g, "dense", start=(cold.is_basic, cold.at_upper))
    assert warm.warm and warm.optimal.all() and warm.pivots == 0
    assert weak_dual(g[0], M, b, b, warm.y[0]) == pytest.approx(weak_dual(g[0], M, b, b, cold.y[0]), rel=1e-9)


@pytest.mark.parametrize("kind", ["random", "all columns", "singular", "no slack"])
def test_a_bad_start_basis_still_gives_sound_bounds(kind):
    """Any start is valid (the module docstring's claim): a random wanted set with random bound sides, every column
    wanted, two parallel columns wanted (the basis must drop one), no slack wanted: each objective's bound from
    the multipliers (the window's rounded-upward bound) is >= g·z at the known feasible point, no tolerance, and
    equals the cold start's optimum to 1e-7."""
    rng, M, b, z = _feasible_lp(33)
    m, Q = M.shape
    if kind == "singular":
        M[:, 1] = 2.0 * M[:, 0]
        b = M @ z
    G = rng.normal(size=(5, Q))
    ones = np.ones(Q)
    want = {"random": rng.random(Q + m) < 0.5, "all columns": np.r_[np.ones(Q, bool), np.zeros(m, bool)],
            "singular": np.r_[np.isin(np.arange(Q), [0, 1]), np.zeros(m, bool)],
            "no slack": np.r_[rng.random(Q) < 0.3, np.zeros(m, bool)]}[kind]
    upper = rng.random(Q + m) < 0.5
    cold = box_lp_solve(M, b, b, -ones, ones, G, "dense")
    warm = box_lp_solve(M, b, b, -ones, ones, G, "dense", start=(want, upper))
    assert cold.optimal.all() and warm.optimal.all() and warm.warm  # the start completed to a nonsingular basis
    mags = np.abs(G) @ np.ones(Q)
    mag_rows = np.abs(M).sum(axis=1) + np.abs(b)
    for res in (cold, warm):
        bounds = bounds_from_multipliers(G, M, b, b, res.y, mags, mag_rows, 4.0 * (m + Q))
        assert np.all(bounds >= G @ z)  # sound, whatever the start
    for g, a, c in zip(G, warm.y, cold.y):
        assert weak_dual(g, M, b, b, a) == pytest.approx(weak_dual(g, M, b, b, c), rel=1e-7, abs=1e-9)


def test_start_of_the_wrong_size_is_refused():
    M = np.ones((2, 3))
    with pytest.raises(InputError) as info:
        box_lp_solve(M, [0.0, 0.0], [0.0, 0.0], -np.ones(3), np.ones(3), [[1.0, 0.0, 0.0]], "dense",
                     start=(np.zeros(4, bool), np.zeros(5, bool)))
    assert info.value.field == "start"


def test_start_basis_is_nonsingular_and_keeps_independent_wanted_columns():
    """``_start_basis``: of two parallel wanted columns one is kept; every row whose slack is wanted keeps it; the
    basis is nonsingular (``_refactor``)."""
    from eqrec.lp.box_simplex import _refactor, _start_basis

    M = np.array([[1.0, 2.0, 0.0, 1.0], [2.0, 4.0, 1.0, 0.0], [0.0, 0.0, 0.0, 3.0]])
    want = np.array([True, True, True, False, False, False, True])  # columns 0, 1, 2; the third row's slack
    basis = _start_basis(M, 4, want)
    assert sorted(basis) == [0, 2, 6] or sorted(basis) == [1, 2, 6]
    assert _refactor(M, basis, 4, np.empty((3, 3)))


@pytest.mark.parametrize("b", [39.5, 10.25, -37.0])
def test_one_pivot_passes_many_breakpoints(b):
    """One row ``Σ z_j = b`` far from the sum at the slack basis's vertex: the bound-flipping ratio test passes most
    breakpoints in one pivot (more than the selection's passes, so the sorted rest is walked too), and the
    multipliers certify the optimum (SciPy's HiGHS)."""
    rng = np.random.default_rng(5)
    Q = 40
    M = np.ones((1, Q))
    g = rng.normal(size=(1, Q))
    ones = np.ones(Q)
    res = box_lp_solve(M, np.array([b]), np.array([b]), -ones, ones, g, "dense")
    assert res.optimal.all() and res.pivots <= 2
    ref = scipy.optimize.linprog(-g[0], A_eq=M, b_eq=[b], bounds=(-1, 1), method="highs")
    bound = weak_dual(g[0], M, np.array([b]), np.array([b]), res.y[0])
    assert bound == pytest.approx(-ref.fun, rel=1e-9, abs=1e-9)


@pytest.mark.parametrize("m,Q,ranged,dense", [(60, 700, True, True), (70, 300, False, True), (70, 300, True, False),
                                              (70, 600, False, False)])
def test_auto_chooses_the_dense_solver_by_rows_entries_and_equalities(m, Q, ranged, dense):
    """``solver="auto"``: dense up to 64 rows whatever the LP; beyond, only for equality rows and at most 40,000
    entries of ``M`` (the dense solver returns its basis, HiGHS none); both certify the optimum."""
    rng = np.random.default_rng(m + Q)
    M, lo, hi = random_box_lp(rng, m, Q, ranged)
    g = rng.normal(size=(1, Q))
    ones = np.ones(Q)
    res = box_lp_solve(M, lo, hi, -ones, ones, g)
    assert (res.is_basic is not None) == dense
    assert res.optimal.all()
    ref = scipy.optimize.linprog(-g[0], A_ub=np.vstack([M, -M]), b_ub=np.concatenate([hi, -lo]), bounds=(-1, 1),
                                 method="highs")
    assert weak_dual(g[0], M, lo, hi, res.y[0]) == pytest.approx(-ref.fun, rel=1e-7, abs=1e-7)
