"""Kalman-type estimators for delayed data: exact worst cases over the box, attained at vertices."""
import numpy as np
import pytest

from eqrec.arrivals.words import parse_delay_word
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.errors import InputError
from eqrec.estimators.kalman import FILTERS, DelayUnawareKalman, GaussianDesign, TimestampedKalman, make_filter
from eqrec.simulate.filter_runs import error_maps, simulate_filter, truncated_normal_deltas
from eqrec.systems.examples import batch_reactor

X0 = np.ones(4)


@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


def _make(name, system, mu1, T, max_delay, x0):
    return make_filter(name, system, GaussianDesign.from_box(system, mu1), horizon=T, max_delay=max_delay,
                       x0_mean=x0)


@pytest.mark.parametrize("name", sorted(FILTERS))
@pytest.mark.parametrize("estimate", ["prediction", "filtered"])
def test_worst_case_is_attained_at_a_vertex(reactor, name, estimate):
    mu1 = 0.33
    maps = error_maps(_make(name, reactor, mu1, 5, 2, X0), reactor, "21210", X0, mu1)
    bounds = maps.bounds(estimate)
    for t in range(1, bounds.shape[0]):
        for i in range(4):
            delta = maps.worst_vertex(t, i, estimate)
            e_pred, e_filt = simulate_filter(_make(name, reactor, mu1, 5, 2, X0), reactor, "21210", delta, X0)
            e = e_pred if estimate == "prediction" else e_filt
            assert abs(e[t, i]) == pytest.approx(bounds[t, i], rel=1e-9, abs=1e-12)
    # and no sample exceeds it
    rng = np.random.default_rng(1)
    deltas = rng.uniform(-1, 1, (200, maps.layout.size)) * maps.radius
    assert np.all(np.abs(maps.errors(deltas, estimate)) <= bounds[None] * (1 + 1e-12) + 1e-15)


def test_maps_match_numeric_runs(acc):
    T, mu1 = 5, 1.0
    x0 = np.array([20.0, 30.0, 22.0])
    lay = UncertaintyLayout(T, acc.nw, acc.nv, acc.n)
    rng = np.random.default_rng(3)
    for name in FILTERS:
        maps = error_maps(_make(name, acc, mu1, T, 2, x0), acc, "20110", x0, mu1)
        for delta in truncated_normal_deltas(lay, maps.radius, rng, 5):
            e, ef = simulate_filter(_make(name, acc, mu1, T, 2, x0), acc, "20110", delta, x0)
            np.testing.assert_allclose(e, maps.errors(delta)[0], atol=1e-10)
            np.testing.assert_allclose(ef, maps.errors(delta, "filtered")[0], atol=1e-10)


def test_timestamped_kalman_is_the_conditional_mean_of_the_data_received(acc):
    """x̂(t|I_t) = E[x(t) | y(τ), τ ∈ A(t)], by Gaussian conditioning on the stacked model (ACC: with process noise)."""
    T, mu1 = 5, 1.0
    pat = parse_delay_word("20110")
    gd = GaussianDesign.from_box(acc, mu1)
    lay = UncertaintyLayout(T, acc.nw, acc.nv, acc.n)
    x0 = np.array([20.0, 30.0, 22.0])
    delta = truncated_normal_deltas(lay, lay.radius(acc.eta_w, acc.eta_v, mu1), np.random.default_rng(7), 1)[0]
    _, e_filt = simulate_filter(TimestampedKalman(acc, gd), acc, pat, delta, x0)
    # x(t) = X[t] z + drive[t], y(t) = Y[t] z + C drive[t], unknowns z = [x(0); w(0..T-1); v(0..T-1)]
    n, nw, p = acc.n, acc.nw, acc.p
    nz = n + T * nw + T * p
    X, drive = [np.eye(n, nz)], [np.zeros(n)]
    for t in range(T):
        Xn = acc.A @ X[-1]
        Xn[:, n + t * nw:n + (t + 1) * nw] += acc.E
        X.append(Xn)
        drive.append(acc.A @ drive[-1] + acc.f)
    Y = []
    for t in range(T):
        Yt = acc.C @ X[t]
        Yt[:, n + T * nw + t * p:n + T * nw + (t + 1) * p] += acc.V
        Y.append(Yt)
    cov = np.zeros((nz, nz))
    cov[:n, :n] = gd.P0
    cov[n:n + T * nw, n:n + T * nw] = (acc.eta_w / 5) ** 2 * np.eye(T * nw)
    cov[n + T * nw:, n + T * nw:] = np.kron(np.eye(T), gd.R)
    w, v, xi0 = lay.split(delta)
    z_true = np.concatenate([x0, w.reshape(-1), v.reshape(-1)])
    z_mean = np.concatenate([x0 - xi0, np.zeros(nz - n)])  # the prior: x̂(0) = x0 - ξ0
    for t in range(T):
        S = list(pat.available(t))
        if not S:
            continue
        H = np.vstack([Y[s] for s in S])
        gain = X[t] @ cov @ H.T @ np.linalg.inv(H @ cov @ H.T)
        xt_mean = X[t] @ z_mean + drive[t] + gain @ (H @ z_true - H @ z_mean)
        np.testing.assert_allclose(X[t] @ z_true + drive[t] - xt_mean, e_filt[t], atol=1e-8)


def test_variants_coincide_without_delays(reactor):
    mu1 = 0.33
    on_time = "00000"
    m = {name: error_maps(_make(name, reactor, mu1, 5, 0, X0), reactor, on_time, X0, mu1) for name in FILTERS}
    np.testing.assert_allclose(m["timestamped"].G, m["unaware"].G, atol=1e-12)
    np.testing.assert_allclose(m["random_delay_lmv"].G, m["unaware"].G, atol=1e-10)  # τ̄ = 0, p0 = 1: the KF
    np.testing.assert_allclose(m["random_delay_lmv"].G_filt, m["unaware"].G_filt, atol=1e-10)


def test_only_the_delay_unaware_filter_depends_on_the_true_state(reactor):
    mu1 = 0.33
    ts = error_maps(_make("timestamped", reactor, mu1, 5, 2, X0), reactor, "21210", X0, mu1)
    un = error_maps(DelayUnawareKalman(reactor, GaussianDesign.from_box(reactor, mu1)), reactor, "21210", X0, mu1)
    assert np.abs(ts.c).max() < 1e-12  # unbiased: the time stamps are used
    assert np.abs(un.c).max() > 1e-3  # C (x(τ) - x(t)) enters as a bias


def test_truncated_normal_draws(reactor):
    lay = UncertaintyLayout(5, 0, 2, 4)
    radius = lay.radius(0.0, 0.05, 0.33)
    d = truncated_normal_deltas(lay, radius, np.random.default_rng(0), 4000)
    assert np.all(np.abs(d) <= radius)
    np.testing.assert_allclose(d.std(axis=0), radius / 5, rtol=0.08)


def test_bad_inputs(reactor):
    gd = GaussianDesign.from_box(reactor, 0.33)
    with pytest.raises(InputError, match="unknown filter"):
        make_filter("ekf", reactor, gd)
    with pytest.raises(InputError, match="horizon"):
        make_filter("random_delay_lmv", reactor, gd)


def test_compare_with_bounds(reactor):
    from eqrec.simulate.filter_runs import compare_with_bounds

    mu1 = 0.33
    maps = error_maps(_make("unaware", reactor, mu1, 5, 2, X0), reactor, "21210", X0, mu1)
    worst = maps.bounds()
    r = compare_with_bounds(maps, worst, worst.max(axis=1), np.zeros((3, maps.layout.size)))
    assert not r["exceeds"].any() and r["max_ratio"] == pytest.approx(1.0)
    assert r["sampled_exceed"] == 0 and r["samples"] == 3
    r2 = compare_with_bounds(maps, 0.5 * worst)
    assert r2["exceeds"].all() and r2["max_ratio"] == pytest.approx(2.0)
