"""The window LP's rounding allowance (src/eqrec/bounds/window_lp.py, *Soundness*), issue 45 §3.

(a) On a plant with rho(|A|) > 1 > rho(A) the allowance follows the true products, not |A|^L: far below the bound
    at window 50 (the magnitudes propagated through |A| gave 1.33 times the exact hull there).
(b) The error bounds cover the actual rounding, checked against the window computed in exact rational arithmetic
    (fractions.Fraction): the rows of x(t+1) and x(t), their centres, the measured rows and residuals; and every
    reported end is >= the exact weak-duality bound of the same multipliers on the exact data.  A plant built so
    that a backward product cancels to 0 in floating point checks the products' own rounding (the u^2 term).
(c) With the noise played back at box corners, error <= bound at window 50, no tolerance."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

import eqrec
from eqrec.bounds.window_lp import bounds_from_multipliers, window_set
from eqrec.estimators.exact_set import ExactSetEstimator
from eqrec.lp.box_simplex import box_lp_solve
from test_exact_set import corner_run, six_states


def _tiles(system, L):
    """The plant's window model as ExactSetEstimator passes it (η-scaled E and V in floating point)."""
    n, p = system.n, system.p
    return (np.broadcast_to(system.A, (L, n, n)).copy(), np.broadcast_to(system.C, (L, p, n)).copy(),
            np.broadcast_to(system.eta_w * system.E, (L, n, system.nw)).copy(),
            np.broadcast_to(system.eta_v * system.V, (L, p, system.nv)).copy())


def _window_data(system, L, seed, measured=None):
    """A window of ``L`` steps of the plant with data from the model (uniform noise) and a zonotope prior."""
    rng = np.random.default_rng(seed)
    n = system.n
    A, C, E, V = _tiles(system, L)
    if measured is None:
        measured = rng.random(L) < 0.7
    G0 = 0.5 * np.eye(n) + 0.05 * rng.normal(size=(n, n))
    x = G0 @ rng.uniform(-1, 1, n)
    Y = np.zeros((L, system.p))
    for j in range(L):
        Y[j] = C[j] @ x + V[j] @ rng.uniform(-1, 1, system.nv)
        x = A[j] @ x + E[j] @ rng.uniform(-1, 1, system.nw)
    return A, C, E, V, np.zeros((L, n)), np.asarray(measured, bool), Y, np.zeros(n), G0


def _allowance_over_bound(ws):
    """Per end of the predicted hull, (bound - the raw dual value) / bound, the multipliers of the LP's optimum."""
    X = np.concatenate([ws.X_pred, -ws.X_pred])
    ones = np.ones(X.shape[1])
    res = box_lp_solve(ws.M, ws.lower, ws.upper, -ones, ones, X, "dense")
    assert res.optimal.all()
    mags = np.concatenate([ws.mag_pred, ws.mag_pred])
    bound = bounds_from_multipliers(X, ws.M, ws.lower, ws.upper, res.y, mags, ws.mag_rows, ws.kappa)
    raw = np.maximum(res.y * ws.lower, res.y * ws.upper).sum(axis=1) + np.abs(X - res.y @ ws.M).sum(axis=1)
    return (bound - raw) / bound


@pytest.mark.parametrize("L", [40, 50])
def test_allowance_follows_the_true_products_not_abs_a_powers(L):
    """six_states (rho(A) = 0.9, rho(|A|) > 1): the allowance is below 1e-9 of each end's bound at windows 40 and
    50 (the magnitudes propagated through |A| reached 7e9 there: an allowance of 0.001-0.03 on ends of 0.02-0.7).
    It is about 1.2e-10 at window 40 with the simulated true state's rounding covered as well."""
    system = six_states()
    assert max(abs(np.linalg.eigvals(np.abs(system.A)))) > 1.5 > 1 > max(abs(np.linalg.eigvals(system.A)))
    ws = window_set(*_window_data(system, L, 1))
    ratio = _allowance_over_bound(ws)
    assert np.all(ratio > 0) and ratio.max() < 1e-9, ratio.max()


# -- (b) against exact rational arithmetic ------------------------------------------------------------------------

def _exact_window(A, C, E, V, drive, measured, Y, c0, G0):
    """The window's rows, centres, measured rows and residuals in exact arithmetic on the given floats (the same
    columns as window_set: the prior's, the process noises by time, the measured noises by measured time)."""
    F = np.vectorize(Fraction, otypes=[object])
    A, C, E, V, drive, Y, c0, G0 = (F(a) for a in (A, C, E, V, drive, Y, c0, G0))
    L, n = drive.shape
    p, nw, nv, q0 = C.shape[1], E.shape[2], V.shape[2], G0.shape[1]
    Q = q0 + L * nw + int(np.count_nonzero(measured)) * nv
    X = np.full((n, Q), Fraction(0), dtype=object)
    X[:, :q0] = G0
    xc = c0.copy()
    rows, res, col_v = [], [], q0 + L * nw
    for j in range(L):
        if j == L - 1:
            Xf, xf = X.copy(), xc.copy()
        if measured[j]:
            H = C[j].dot(X)
            H[:, col_v:col_v + nv] = V[j]
            col_v += nv
            rows.append(H)
            res.append(Y[j] - C[j].dot(xc))
        X = A[j].dot(X)
        X[:, q0 + j * nw:q0 + (j + 1) * nw] = E[j]
        xc = A[j].dot(xc) + drive[j]
    M = np.concatenate(rows) if rows else np.zeros((0, Q), dtype=object)
    r = np.concatenate(res) if res else np.zeros(0, dtype=object)
    return xc, X, xf, Xf, M, r


def _abs_err(got, want):
    """Per row, sum of |got - want| in exact arithmetic (got: floats)."""
    return [sum((abs(Fraction(float(g)) - w) for g, w in zip(gr, wr)), Fraction(0)) for gr, wr in zip(got, want)]


def _check_against_exact(data, prior_rows=None):
    """Every error bound covers the actual error entrywise, and every end (centre + the rounded-up bound from the
    solver's multipliers) is >= the exact centre + the exact weak-duality bound of the same multipliers."""
    ws = window_set(*data, prior_rows)
    xc, X, xf, Xf, M, r = _exact_window(*data)
    for centre, rows, ex_c, ex_X, err in ((ws.centre_pred, ws.X_pred, xc, X, ws.mag_pred),
                                          (ws.centre_filt, ws.X_filt, xf, Xf, ws.mag_filt)):
        actual = [e + abs(Fraction(float(c)) - ec) for e, c, ec in zip(_abs_err(rows, ex_X), centre, ex_c)]
        assert all(a <= Fraction(float(b)) for a, b in zip(actual, err)), (actual, err)
    k = ws.M.shape[0]
    k_prior = k - M.shape[0]
    actual = [e + abs(Fraction(float(g)) - w) for e, g, w in zip(_abs_err(ws.M[k_prior:], M), ws.lower[k_prior:], r)]
    assert all(a <= Fraction(float(b)) for a, b in zip(actual, ws.mag_rows[k_prior:])), (actual, ws.mag_rows)
    for centre, rows, ex_c, ex_X, err in ((ws.centre_pred, ws.X_pred, xc, X, ws.mag_pred),
                                          (ws.centre_filt, ws.X_filt, xf, Xf, ws.mag_filt)):
        objectives = np.concatenate([rows, -rows])
        ones = np.ones(rows.shape[1])
        res = box_lp_solve(ws.M, ws.lower, ws.upper, -ones, ones, objectives, "dense")
        bounds = bounds_from_multipliers(objectives, ws.M, ws.lower, ws.upper, res.y, np.concatenate([err, err]),
                                         ws.mag_rows, ws.kappa)
        n = rows.shape[0]
        ex_M = np.concatenate([np.vectorize(Fraction, otypes=[object])(ws.M[:k_prior]), M]) if k_prior else M
        ex_lo = [Fraction(float(v)) for v in ws.lower[:k_prior]] + list(r)
        ex_hi = [Fraction(float(v)) for v in ws.upper[:k_prior]] + list(r)
        for o in range(2 * n):
            i, sign = o % n, (1 if o < n else -1)
            y = [Fraction(float(v)) for v in res.y[o]]
            dual = sum((max(yk * lo, yk * hi) for yk, lo, hi in zip(y, ex_lo, ex_hi)), Fraction(0))
            resid = sum((abs(sign * ex_X[i, c] - sum((y[kk] * ex_M[kk, c] for kk in range(k)), Fraction(0)))
                         for c in range(rows.shape[1])), Fraction(0))
            # the reported end: centre + bound (then rounded outward), against the exact end of these multipliers
            assert sign * Fraction(float(centre[i])) + Fraction(float(bounds[o])) >= sign * ex_c[i] + dual + resid
    return ws


def test_error_bounds_cover_the_exact_arithmetic_rounding():
    """A random 3-state plant with large centre, drive and outputs (the residuals and centres carry most of the
    rounding), 9 steps, a zonotope prior and ranged prior rows: every computed row's error <= its bound and every
    end >= the exact weak-duality bound of its multipliers."""
    rng = np.random.default_rng(3)
    L, n, p, nw, nv, q0 = 9, 3, 2, 2, 1, 4
    A = rng.normal(size=(L, n, n))
    A *= 0.9 / max(abs(np.linalg.eigvals(A[0])))
    A[:] = A[0]  # one plant: rho(A) = 0.9, rho(|A|) > 1
    C, E, V = rng.normal(size=(L, p, n)), 0.1 * rng.normal(size=(L, n, nw)), 0.05 * rng.normal(size=(L, p, nv))
    drive = 100.0 * rng.normal(size=(L, n)) / 3.0
    c0 = 1000.0 * rng.normal(size=n) / 7.0
    G0 = 0.3 * rng.normal(size=(n, q0))
    measured = np.array([True, True, False, True, True, False, True, True, True])
    x, Y = c0 + G0 @ rng.uniform(-1, 1, q0), np.zeros((L, p))
    for j in range(L):
        Y[j] = C[j] @ x + V[j] @ rng.uniform(-1, 1, nv)
        x = A[j] @ x + E[j] @ rng.uniform(-1, 1, nw) + drive[j]
    data = (A, C, E, V, drive, measured, Y, c0, G0)
    ws = _check_against_exact(data)
    assert ws.M.shape[0] == p * measured.sum()
    box = np.abs(G0).sum(axis=1)  # the zonotope within a box that cuts it (ranged prior rows, given exactly)
    ws = _check_against_exact(data, (G0, -0.5 * box, 0.7 * box))
    assert ws.M.shape[0] == n + p * measured.sum()


@pytest.mark.parametrize("case", ["centre", "drive"])
def test_error_bounds_cover_the_centres_rounding(case):
    """The centre's rounding alone (prior generators and noises of order 1e-9, so the columns' rounding is
    negligible): "centre", a large centre through a plant with rho(A) = 0.9 and no drive; "drive", a large inexact
    drive through a small plant (the addition of the drive rounds at every step).  Consistent data: the residuals
    are small differences of large numbers, so the measured rows' errors matter in the dual bound."""
    rng = np.random.default_rng(11)
    L, n, p, nw, nv, q0 = 8, 3, 2, 1, 1, 3
    A = rng.normal(size=(n, n))
    A = np.broadcast_to(A * (0.9 if case == "centre" else 0.05) / max(abs(np.linalg.eigvals(A))), (L, n, n)).copy()
    C, E, V = rng.normal(size=(L, p, n)), 1e-9 * rng.normal(size=(L, n, nw)), 0.05 * rng.normal(size=(L, p, nv))
    G0 = 1e-9 * rng.normal(size=(n, q0))
    c0 = 1000.0 * rng.normal(size=n) / 7.0 if case == "centre" else np.zeros(n)
    drive = np.zeros((L, n)) if case == "centre" else 100.0 * rng.normal(size=(L, n)) / 3.0
    measured = np.array([True, True, True, False, True, True, True, True])
    x, Y = c0 + G0 @ rng.uniform(-1, 1, q0), np.zeros((L, p))
    for j in range(L):
        Y[j] = C[j] @ x + V[j] @ rng.uniform(-1, 1, nv)
        x = A[j] @ x + E[j] @ rng.uniform(-1, 1, nw) + drive[j]
    _check_against_exact((A, C, E, V, drive, measured, Y, c0, G0))


def test_error_bound_covers_a_backward_product_that_cancels_in_floating_point():
    """A 2-state window of 3 steps built so that A_0 g0 and A_2 A_1 both compute to exactly 0 while their exact
    values are 2^-60 (x y = 1 + 2^-29 + 2^-60 rounds to 1 + 2^-29, cancelled by z w): the computed rows are 0, the
    exact row 2^-120, and every local term from the computed vectors is 0, so only the products' own rounding
    (2k(n+1)u |A|...|A| times the first step's local bound, of order u^2) covers it."""
    x = y = 1.0 + 2.0 ** -30
    z, w = -(1.0 + 2.0 ** -29), 1.0
    A = np.zeros((3, 2, 2))
    A[0] = A[2] = [[x, z], [0.0, 0.0]]
    A[1] = [[y, 0.0], [w, 0.0]]
    G0 = np.array([[y], [w]])
    L, n = 3, 2
    data = (A, np.ones((L, 1, n)), np.zeros((L, n, 1)), np.ones((L, 1, 1)), np.zeros((L, n)),
            np.zeros(L, bool), np.zeros((L, 1)), np.zeros(n), G0)
    ws = window_set(*data)
    assert ws.X_pred[0, 0] == 0.0
    xc, X, *_ = _exact_window(*data)
    assert X[0, 0] == Fraction(2) ** -120
    assert Fraction(float(ws.mag_pred[0])) >= Fraction(2) ** -120
    _check_against_exact(data)


def test_error_bounds_cover_a_drive_whose_terms_cancel():
    """``B u`` and ``f`` of order 1e6 cancel to a drive of order 1: ``|drive|`` is far below the magnitudes of its
    computation, whose rounding (about 1e-10 here) is then covered only through ``drive_magnitude`` (``|B||u| +
    |f|``). Checked against the window in exact arithmetic with the exact drive ``B u + f``; the bounds from
    ``|drive|`` alone do not cover it (so the test fails if the magnitudes are not used)."""
    rng = np.random.default_rng(5)
    L, n, p, nw, nv, q0, m = 8, 3, 1, 1, 1, 3, 2
    A = rng.normal(size=(n, n))
    A = np.broadcast_to(0.5 * A / max(abs(np.linalg.eigvals(A))), (L, n, n)).copy()
    C, E, V = rng.normal(size=(L, p, n)), 0.01 * rng.normal(size=(L, n, nw)), 0.01 * rng.normal(size=(L, p, nv))
    G0 = 0.1 * rng.normal(size=(n, q0))
    B = 1e3 * rng.normal(size=(n, m)) / 3.0
    u = 1e3 * rng.normal(size=(L, m)) / 7.0
    f = -(B @ u[0]) + 0.1  # the drive's two terms cancel at every step (u moves by a little)
    u[1:] = u[0] + 1e-3 * rng.normal(size=(L - 1, m))
    drive = np.array([B @ u[j] + f for j in range(L)])
    F = np.vectorize(Fraction, otypes=[object])
    exact_drive = np.array([F(B).dot(F(u[j])) + F(f) for j in range(L)], dtype=object)
    assert max(abs(Fraction(float(d)) - e) for d, e in zip(drive.ravel(), exact_drive.ravel())) > 2.0 ** -40
    measured = np.ones(L, bool)
    x, Y = G0 @ rng.uniform(-1, 1, q0), np.zeros((L, p))
    for j in range(L):
        Y[j] = C[j] @ x + V[j] @ rng.uniform(-1, 1, nv)
        x = A[j] @ x + E[j] @ rng.uniform(-1, 1, nw) + drive[j]
    data = (A, C, E, V, drive, measured, Y, np.zeros(n), G0)
    magnitude = np.abs(u) @ np.abs(B).T + np.abs(f)
    xc, X, xf, Xf, M, r = _exact_window(A, C, E, V, exact_drive, measured, Y, np.zeros(n), G0)

    def covered(ws):
        ok = []
        for centre, rows, ex_c, ex_X, err in ((ws.centre_pred, ws.X_pred, xc, X, ws.mag_pred),
                                              (ws.centre_filt, ws.X_filt, xf, Xf, ws.mag_filt)):
            actual = [e + abs(Fraction(float(c)) - ec) for e, c, ec in zip(_abs_err(rows, ex_X), centre, ex_c)]
            ok += [a <= Fraction(float(b)) for a, b in zip(actual, err)]
        actual = [e + abs(Fraction(float(g)) - w) for e, g, w in zip(_abs_err(ws.M, M), ws.lower, r)]
        ok += [a <= Fraction(float(b)) for a, b in zip(actual, ws.mag_rows)]
        return ok

    assert all(covered(window_set(*data, drive_magnitude=magnitude, drive_terms=m + 1)))
    assert not all(covered(window_set(*data)))  # |drive| alone: the cancelled terms' rounding is missed


def _up(q: Fraction) -> float:
    """The smallest double >= q."""
    f = float(q)
    return f if Fraction(f) >= q else float(np.nextafter(f, np.inf))


def test_bound_covers_data_anywhere_within_the_stated_errors():
    """bounds_from_multipliers' contract: for computed rows, right-hand sides and objectives within the stated
    error bounds of the exact ones (here pushed to those bounds against the multipliers' signs), the bound is >= the
    exact weak-duality value on the exact data (each error term is needed: the pushes are 1e-6, the evaluation's
    own allowance about 1e-13)."""
    rng = np.random.default_rng(21)
    K, k, Q = 4, 5, 12
    X, M, r = rng.normal(size=(K, Q)), rng.normal(size=(k, Q)), rng.normal(size=k)
    y = rng.normal(size=(K, k))
    X_hat = X - 1e-6 * np.sign(X - y @ M)  # each residual 1e-6 smaller in magnitude: the exact l1 is larger
    M_hat = M.copy()
    r_hat = r - 1e-6 * np.sign(y).sum(axis=0)  # y^T r smaller for most objectives
    F = np.vectorize(Fraction, otypes=[object])
    err_obj = [_up(sum((abs(a - b) for a, b in zip(F(X_hat[o]), F(X[o]))), Fraction(0))) for o in range(K)]
    err_rows = [_up(abs(Fraction(a) - Fraction(b))) for a, b in zip(r_hat, r)]
    bound = bounds_from_multipliers(X_hat, M_hat, r_hat, r_hat, y, np.array(err_obj), np.array(err_rows),
                                    2.0 * (k + Q + 8))
    for o in range(K):
        yo, Xo = F(y[o]), F(X[o])
        exact = sum((yk * Fraction(rk) for yk, rk in zip(yo, r)), Fraction(0)) + sum(
            (abs(Xo[c] - sum((yo[j] * Fraction(M[j, c]) for j in range(k)), Fraction(0))) for c in range(Q)),
            Fraction(0))
        assert Fraction(float(bound[o])) >= exact, o


# -- (c) played back at box corners, window 50 ----------------------------------------------------------------------

@pytest.mark.parametrize("plant", [eqrec.two_mass, six_states], ids=["carts", "six_states"])
def test_window_50_guarantee_at_box_corners(plant):
    """error <= bound at every step, no tolerance, window 50 (the allowance of every window from 1 to 50 steps),
    the noise and the initial error at random corners of their boxes."""
    system = plant()
    for seed in range(2):
        est = ExactSetEstimator(system, 0.5, max_delay=2, window=50)
        out = corner_run(system, est, seed, 70)
        assert np.all(np.abs(out.error[1:]).max(axis=1) <= out.bound)
        assert est.lp_fallbacks == 0
