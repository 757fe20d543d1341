"""One system description, the stochastic estimators in step form (the protocol of eqrec.estimators.protocol), and the
one simulation loop running them."""

import numpy as np
import pytest

from eqrec.systems.noise import GaussianDesign, GaussianNoise, MultiplicativeNoise, NoisySystem
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError
from eqrec.estimators import kalman
from eqrec.lmv.plant import Plant

EX1 = {"Phi": [[0.8, 0.0], [0.9, 0.2]], "Phi1": [[0.1, 0.05], [0.2, 0.1]], "Gamma": [1.0, 0.5],
       "H": [[1.0, 2.0]], "H1": [[1.0, 2.0]], "Qw": 1.0, "c": 1.0, "Qzeta": 1.0, "Qxi": 2.0, "Qlam": 2.0,
       "sigma0": [0.0, 0.0], "Sigma0": [[1.0, 0.0], [0.0, 1.0]], "name": "Example 1"}


@pytest.fixture(scope="module")
def ex1():
    return Plant.from_dict(EX1)


# ---------------------------------------------------------------------------- one system description

def test_plant_is_a_loader_of_the_one_description(ex1):
    desc = ex1.description()
    sysm, g, mult = desc.system, desc.gaussian, desc.multiplicative
    assert isinstance(sysm, AffineSystem) and (sysm.n, sysm.p, sysm.nw, sysm.nv, sysm.m) == (2, 1, 1, 1, 0)
    np.testing.assert_array_equal(sysm.A, ex1.Phi)
    np.testing.assert_array_equal(sysm.E, ex1.Gamma)
    np.testing.assert_array_equal(g.Qv, [[2.0]])  # v = c w + zeta: Qv = c^2 Qw + Qzeta
    np.testing.assert_array_equal(g.S, [[1.0]])
    np.testing.assert_array_equal(mult.A1, ex1.Phi1)
    assert (mult.Qxi, mult.Qlam) == (2.0, 2.0)
    back = Plant.from_description(desc)
    for key in ex1.__dataclass_fields__:
        a, b = getattr(ex1, key), getattr(back, key)
        assert a == b if isinstance(a, str) else np.array_equal(a, b), key


def test_a_bounded_error_plant_reads_as_an_lmv_plant(acc):
    desc = NoisySystem(acc, GaussianNoise.from_box(acc, mu1=1.0))
    plant = Plant.from_description(desc)
    np.testing.assert_allclose(plant.Qv, (acc.eta_v / 5) ** 2 * np.eye(acc.p))
    np.testing.assert_allclose(plant.Sigma0, np.eye(3) / 25)
    assert plant.Qxi == plant.Qlam == 0.0 and not plant.Phi1.any()
    # the Gaussian statistics of a box are those the Kalman filters are designed with (5 sigma = bound)
    d_box, d_desc = GaussianDesign.from_box(acc, 1.0), desc.design()
    for key in ("P0", "Q", "R"):
        np.testing.assert_allclose(getattr(d_desc, key), getattr(d_box, key), rtol=1e-15, atol=0)
    assert kalman.GaussianDesign is GaussianDesign  # the filters' design statistics are the one description's


@pytest.mark.parametrize("kwargs, field", [
    ({"Qw": [[1.0, 2.0], [2.0, 1.0]], "Qv": 1.0, "x0_cov": np.eye(2)}, "Qw"),
    ({"Qw": 1.0, "Qv": [[np.nan]], "x0_cov": np.eye(2)}, "Qv"),
    ({"Qw": 1.0, "Qv": 1.0, "x0_cov": np.eye(2), "S": [[2.0]]}, "S"),
    ({"Qw": 1.0, "Qv": 1.0, "x0_cov": np.eye(2), "x0_mean": [0.0]}, "x0_mean"),
    ({"Qw": "a", "Qv": 1.0, "x0_cov": np.eye(2)}, "Qw"),
])
def test_bad_gaussian_noise_names_the_field(kwargs, field):
    with pytest.raises(InputError) as exc:
        GaussianNoise(**kwargs)
    assert exc.value.field == field


def test_descriptions_must_fit_the_system(acc):
    with pytest.raises(InputError) as exc:
        NoisySystem(acc, GaussianNoise(Qw=1.0, Qv=1.0, x0_cov=np.eye(3)))  # ACC has p = 2 measurement noises
    assert exc.value.field == "Qv"
    with pytest.raises(InputError) as exc:
        NoisySystem(acc, multiplicative=MultiplicativeNoise(A1=np.zeros((2, 2)), C1=np.zeros((1, 2)), Qxi=1, Qlam=1))
    assert exc.value.field == "multiplicative"
    with pytest.raises(InputError) as exc:
        MultiplicativeNoise(A1=np.eye(2), C1=np.zeros((1, 2)), Qxi=-1.0, Qlam=0.0)
    assert exc.value.field == "Qxi"
    with pytest.raises(InputError) as exc:
        NoisySystem(acc).design()
    assert exc.value.field == "gaussian"


# ---------------------------------------------------------------------------- Kalman-type filters in step form

from eqrec.arrivals.draws import NEVER, ArrivalTrace  # noqa: E402
from eqrec.estimators.protocol import Estimator  # noqa: E402
from eqrec.simulate.loop import closed_loop  # noqa: E402
from eqrec.simulate.filter_runs import error_maps  # noqa: E402
from eqrec.estimators.kalman import make_filter
from eqrec.lmv.monte_carlo import compare_moments  # noqa: E402

DELAYED = [0, 1, 2, 0, NEVER, 1, 0, 0, 2, NEVER, 0, 1]
MISSING = [0, NEVER, 0, 0, NEVER, NEVER, 0, 0, 0, NEVER, 0, 0]
X0 = np.array([20.0, 40.0, 20.0])


def _filters(acc, horizon=12, max_delay=2):
    gd = GaussianDesign.from_box(acc, 1.0)
    return {key: make_filter(key, acc, gd, horizon=horizon, max_delay=max_delay, x0_mean=X0)
            for key in ("timestamped", "unaware", "random_delay_lmv")}


def test_filters_follow_the_protocol(acc):
    for key, f in _filters(acc).items():
        assert f.kind == "stochastic" and f.key == key
        assert f.name in ("Kalman, time-stamped", "Kalman, delay-unaware", "LMV, random delay")
        assert f.reset(X0, t0=4) is f and f.time == 4
        assert isinstance(f, Estimator)
        xhat, P = f.step(np.array([1.0, 2.0]), np.array([206.0]))
        assert xhat.shape == (3,) and P.shape == (3, 3) and f.time == 5 and f.filtered.shape == (3,)
        np.testing.assert_array_equal(f.x, xhat)
        assert np.allclose(P, P.T) and np.linalg.eigvalsh(P).min() > -1e-12


def test_step_form_follows_the_exact_affine_maps(acc, rng):
    """One numeric run in the one loop (plain vectors) against the affine error maps of the same filter."""
    trace = ArrivalTrace(DELAYED)
    pattern = trace.pattern()
    for key, f in _filters(acc).items():
        maps = error_maps(f, acc, pattern, X0, 1.0)
        delta = rng.uniform(-1, 1, maps.layout.size) * maps.radius
        w, v, xi0 = maps.layout.split(delta)
        run = closed_loop(acc, f, trace, X0, xi0, w, v)
        np.testing.assert_allclose(run.error, maps.errors(delta)[0], rtol=0, atol=1e-9, err_msg=key)


def _refilter(acc, design, received, t, xhat0):
    """Reference: the time-stamped filter at t, re-run from time 0 over everything received (no cache)."""
    x, P = xhat0.copy(), design.P0.copy()
    for tau in range(t + 1):
        if tau in received:
            C = acc.C
            S = C @ P @ C.T + design.R
            K = P @ C.T @ np.linalg.inv(S)
            x = x + K @ (received[tau] - C @ x)
            P = (np.eye(3) - K @ C) @ P @ (np.eye(3) - K @ C).T + K @ design.R @ K.T
        x = acc.A @ x + acc.f
        P = acc.A @ P @ acc.A.T + design.Q
    return x, P


def test_timestamped_filter_equals_refiltering_from_the_start(acc, rng):
    f = _filters(acc)["timestamped"].reset(X0)
    trace = ArrivalTrace(DELAYED)
    ys = rng.normal(size=(12, 2)) + np.array([40.0, 20.0])
    received = {}
    for t in range(12):
        for tau in trace.arriving_at(t):
            received[tau] = ys[tau]
        got, P = f.step([(tau, ys[tau]) for tau in trace.arriving_at(t)])
        want, Pw = _refilter(acc, f.design, received, t, X0)
        np.testing.assert_allclose(got, want, rtol=1e-12, atol=1e-10)
        np.testing.assert_allclose(P, Pw, rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize("key, arrivals", [("timestamped", DELAYED), ("unaware", MISSING)])
def test_covariance_is_the_error_covariance_by_monte_carlo(acc, key, arrivals):
    """Gaussian noise with the design's statistics: the P each step returns is E[e eᵀ] of x(t+1) - x̂(t+1|I_t)
    (exact for the time-stamped filter on any trace, and for the delay-unaware one without delays); R runs at once
    as columns, tolerance of lmv.simulate.compare_moments (Bonferroni at family-wise level 1e-3)."""
    R = 4000
    rng = np.random.default_rng(7)
    g = GaussianNoise.from_box(acc, 1.0)
    f = _filters(acc)[key]
    trace = ArrivalTrace(arrivals)
    N = trace.steps
    w = rng.normal(size=(N, acc.nw, R)) * np.sqrt(g.Qw[0, 0])
    v = rng.normal(size=(N, acc.nv, R)) * np.sqrt(g.Qv[0, 0])
    xi0 = rng.normal(size=(3, R)) * np.sqrt(g.x0_cov[0, 0])
    run = closed_loop(acc, f, trace, np.outer(X0, np.ones(R)), xi0, w, v, one=np.ones(R))
    err = np.moveaxis(run.error[1:], -1, 0)  # (R, N, n)
    check = compare_moments(err, np.stack(run.spread))
    assert check.passed, check.summary()


def test_filter_time_runs_on_absolute_time(acc, rng):
    """t0 != 0 on a time-varying system: the filter reads A(t), C(t) at absolute times, like a run of the
    system shifted by t0 from 0."""
    T = 10
    A = np.stack([acc.A * (1 + 0.01 * k) for k in range(T)])
    C = np.stack([acc.C * (1 - 0.02 * k) for k in range(T)])
    tv = AffineSystem(A=A, C=C, E=acc.E, B=np.broadcast_to(acc.B, (T,) + acc.B.shape), f=acc.f,
                      eta_w=acc.eta_w, eta_v=acc.eta_v)
    shifted = AffineSystem(A=A[3:], C=C[3:], E=acc.E, B=np.broadcast_to(acc.B, (T - 3,) + acc.B.shape), f=acc.f,
                           eta_w=acc.eta_w, eta_v=acc.eta_v)
    gd = GaussianDesign.from_box(acc, 1.0)
    ys = rng.normal(size=(7, 2))
    for key in ("timestamped", "unaware"):
        a = make_filter(key, tv, gd).reset(X0, t0=3)
        b = make_filter(key, shifted, gd).reset(X0)
        for k in range(7):
            pk_a = [(3 + tau, ys[tau]) for tau in ArrivalTrace(DELAYED[:7]).arriving_at(k)]
            pk_b = [(tau, ys[tau]) for tau in ArrivalTrace(DELAYED[:7]).arriving_at(k)]
            (xa, Pa), (xb, Pb) = a.step(pk_a, np.array([1.0])), b.step(pk_b, np.array([1.0]))
            np.testing.assert_array_equal(xa, xb)
            np.testing.assert_array_equal(Pa, Pb)


BAD_STEPS = [
    ({"y": np.array([1.0, np.nan])}, "y"),
    ({"y": np.array([1.0, 2.0, 3.0])}, "y"),
    ({"y": [(9, np.zeros(2))]}, "y"),  # from the future
    ({"y": [(3, np.zeros(2)), (3, np.zeros(2))]}, "y"),
    ({"y": np.zeros(2), "u": np.array([np.inf])}, "u"),
    ({"y": np.zeros(2), "u": np.zeros(2)}, "u"),
    ({"y": "abc"}, "y"),
]


@pytest.mark.parametrize("bad, field", BAD_STEPS)
def test_a_refused_step_leaves_the_filter_unchanged(acc, rng, bad, field):
    ys = rng.normal(size=(8, 2))
    for key in ("timestamped", "unaware", "random_delay_lmv"):
        f, twin = _filters(acc)[key].reset(X0), _filters(acc)[key].reset(X0)
        for t in range(3):
            f.step(ys[t]), twin.step(ys[t])
        before = (f.time, f.x, f.filtered)
        with pytest.raises(InputError) as exc:
            f.step(**bad)
        assert exc.value.field == field, key
        assert f.time == before[0] and np.array_equal(f.x, before[1]) and np.array_equal(f.filtered, before[2])
        for t in range(3, 8):
            pk = None if t == 4 else [(4, ys[4]), (5, ys[5])] if t == 5 else ys[t]
            (xa, Pa), (xb, Pb) = f.step(pk), twin.step(pk)
            assert np.array_equal(xa, xb) and np.array_equal(Pa, Pb), key


def test_a_second_packet_of_one_stamp_is_refused_by_the_timestamped_filter(acc):
    f = _filters(acc)["timestamped"].reset(X0)
    f.step(np.zeros(2))
    x = f.x
    with pytest.raises(InputError, match="second packet stamped 0"):
        f.step([(0, np.ones(2))])
    np.testing.assert_array_equal(f.x, x)
    with pytest.raises(InputError):
        _filters(acc)["unaware"].step(None)  # before reset
    with pytest.raises(InputError) as exc:
        _filters(acc)["unaware"].reset([1.0, np.nan, 0.0])
    assert exc.value.field == "xhat0"


# ---------------------------------------------------------------------------- P4's LMV filter and predictor in step form

from eqrec.arrivals.draws import bernoulli_trace  # noqa: E402
from eqrec.lmv.estimator import LMVEstimator, apply_estimator  # noqa: E402
from eqrec.lmv.model import system_of  # noqa: E402
from eqrec.lmv.recursion import filter_smoother, lmv_recursion  # noqa: E402
from eqrec.lmv.monte_carlo import simulate_plant  # noqa: E402


@pytest.fixture(scope="module")
def ex1_sim(ex1):
    return simulate_plant(ex1, 0.8, 40, 3, np.random.default_rng(3))


@pytest.mark.parametrize("mechanism, key", [("zero-input", "y_zero"), ("hold-input", "y_hold")])
def test_step_form_is_bit_identical_to_the_batch_recursion(ex1, ex1_sim, mechanism, key):
    """Each run of the P4 Monte Carlo, stepped with y(t) or None (lost), gives the batch run's predictions and
    filtered estimates to the last bit; the covariances are those of Theorems 1 and 3."""
    sys = system_of(ex1, mechanism, 0.8)
    res = lmv_recursion(sys, 40)
    sm = filter_smoother(res, 0)
    for r in range(3):
        batch = apply_estimator(res, ex1_sim[key][r], sm)
        est = LMVEstimator(sys, res).reset()
        assert est.name == f"LMV, {mechanism}" and est.time == 0
        for t in range(41):
            y = ex1_sim["y"][r, t] if ex1_sim["eta"][r, t] else None
            pred, P = est.step(y)
            assert np.array_equal(pred, batch["pred"][t + 1, :2]), (r, t)
            assert np.array_equal(est.filtered, batch["smooth"][t, 0, :2]), (r, t)
            np.testing.assert_array_equal(P, res.P_pred[t + 1][:2, :2])
            np.testing.assert_array_equal(est.P_filtered, sm.P_filt[t][:2, :2])
        assert est.time == 41 and not ex1_sim["eta"][r].all()  # the runs do lose packets


def test_gains_computed_as_the_steps_go_are_those_of_the_recursion(ex1, ex1_sim):
    sys = system_of(ex1, "hold-input", 0.8)
    res = lmv_recursion(sys, 10)  # the step form extends it beyond t = 10 by the same recursion
    longer = lmv_recursion(sys, 40)
    a, b, c = LMVEstimator(sys, res).reset(), LMVEstimator(sys).reset(), LMVEstimator(sys, longer).reset()
    for t in range(41):
        y = ex1_sim["y"][0, t] if ex1_sim["eta"][0, t] else None
        (xa, Pa), (xb, Pb), (xc, Pc) = a.step(y), b.step(y), c.step(y)
        assert np.array_equal(xa, xb) and np.array_equal(xa, xc)
        assert np.array_equal(Pa, Pb) and np.array_equal(Pa, Pc)


@pytest.mark.parametrize("bad, field", [
    ({"y": np.array([np.nan])}, "y"), ({"y": np.zeros(2)}, "y"), ({"y": [(20, np.zeros(1))]}, "y"),
    ({"y": np.zeros(1), "u": np.array([1.0])}, "u"), ({"y": np.zeros(1), "u": "x"}, "u"),
])
def test_a_refused_lmv_step_leaves_the_estimator_unchanged(ex1, ex1_sim, bad, field):
    sys = system_of(ex1, "hold-input", 0.8)
    est, twin = LMVEstimator(sys).reset(t0=5), LMVEstimator(sys).reset(t0=5)
    ys = ex1_sim["y"][0]
    for t in range(3):
        est.step(ys[t]), twin.step(ys[t])
    est.step(None), twin.step(None)  # something is held
    before = (est.time, est.augmented, est.filtered)
    with pytest.raises(InputError) as exc:
        est.step(**bad)
    assert exc.value.field == field
    assert est.time == before[0] and np.array_equal(est.augmented, before[1])
    assert np.array_equal(est.filtered, before[2])
    for t in range(4, 12):
        y = None if t % 3 == 0 else ys[t]
        (xa, Pa), (xb, Pb) = est.step(y), twin.step(y)
        assert np.array_equal(xa, xb) and np.array_equal(est.filtered, twin.filtered)


def test_late_packets_count_as_lost_and_reset_checks(ex1, ex1_sim):
    sys = system_of(ex1, "zero-input", 0.8)
    a, b = LMVEstimator(sys).reset(t0=3), LMVEstimator(sys).reset(t0=3)
    a.step(ex1_sim["y"][0, 0])
    b.step(ex1_sim["y"][0, 0])
    np.testing.assert_array_equal(a.step([(3, ex1_sim["y"][0, 0])])[0], b.step(None)[0])
    with pytest.raises(InputError) as exc:
        LMVEstimator(sys).reset([0.0, np.inf])
    assert exc.value.field == "xhat0"
    with pytest.raises(InputError):
        LMVEstimator(sys).step(None)
    for bad in ("nothing", "hold-input"):  # hold-input needs the augmented state of hold_input_system
        with pytest.raises(InputError) as exc:
            LMVEstimator(sys, compensation=bad)
        assert exc.value.field == "compensation"
    assert isinstance(LMVEstimator(sys).reset(), Estimator)


def test_lmv_in_the_one_loop_on_a_bounded_error_plant_by_monte_carlo():
    """One plant for every family: an affine system with Gaussian noise read as an LMV plant; the zero- and
    hold-input estimators run in closed_loop on Bernoulli traces (Monte Carlo = many calls of the loop); the
    covariance each step returns is the error covariance over the noise and the arrivals (compare_moments,
    Bonferroni at family-wise level 1e-3)."""
    system = AffineSystem(A=[[0.9, 0.2], [0.0, 0.7]], C=[[1.0, 0.5]], E=[[0.0], [1.0]], B=[[0.0], [1.0]],
                          eta_w=0.5, eta_v=0.2)
    gauss = GaussianNoise.from_box(system, mu1=1.0)
    plant = Plant.from_description(NoisySystem(system, gauss))
    R, N, eta = 1500, 15, 0.7
    rng = np.random.default_rng(11)
    for mech in ("zero-input", "hold-input"):
        est = LMVEstimator(system_of(plant, mech, eta), system=system)
        errs, Ps = [], None
        for _ in range(R):
            trace = bernoulli_trace(rng, N, 1 - eta)
            w = rng.normal(size=(N, 1)) * np.sqrt(gauss.Qw[0, 0])
            v = rng.normal(size=(N, 1)) * np.sqrt(gauss.Qv[0, 0])
            xi0 = rng.normal(size=2) * np.sqrt(gauss.x0_cov[0, 0])
            run = closed_loop(system, est, trace, xi0, xi0, w, v)  # x(0) = ξ0, x̂(0) = E x(0) = 0
            errs.append(run.error[1:])
            Ps = np.stack(run.spread)
        check = compare_moments(np.array(errs), Ps)
        assert check.passed, (mech, check.summary())
