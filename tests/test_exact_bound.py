"""The exact run-time bound (issue 32 §2): the zonotope of the error carried online, ``strict=False`` and
``eqrec.exact_bound``, checked against the worst case computed from unit perturbations, against the noise
played back at that worst case, and against the designed levels inside the language."""
import numpy as np
import pytest

import eqrec
from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.bounds.zonotope import ErrorMap, ErrorSet, outer_row_sums, reduce_order
from eqrec.design.delay.design import design_delay_global
from eqrec.errors import InputError
from eqrec.estimators.exact import exact_bound
from eqrec.estimators.kalman import DelayUnawareKalman, TimestampedKalman
from eqrec.simulate.loop import closed_loop
from eqrec.systems.affine import AffineSystem
from eqrec.systems.noise import GaussianNoise


def _oscillator() -> AffineSystem:
    """Lightly damped, complex eigenvalues, negative entries in A (|A| != A)."""
    th = 0.3
    A = 0.995 * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return AffineSystem(A=A, C=[[1.0, 0.0]], E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05, name="oscillator")


@pytest.fixture(scope="module")
def oscillator():
    return _oscillator()


@pytest.fixture(scope="module")
def osc_design(oscillator):
    # at most one loss per block of three, delays 0
    return design_delay_global(oscillator, ["000", "300", "030", "003"]).design


def _unit_responses(system, make, trace, xhat0, radius_x0):
    """The error of a (linear) estimator run as ``c + G δ``: one run at δ = 0 and one per unit perturbation.

    The initial estimate is ``xhat0`` in every run and the true initial state ``xhat0 + ξ0`` (what a run-time
    bound knows: the estimate, not the state)."""
    N, n = trace.steps, system.n
    D = n + N * (system.nw + system.nv)
    r = np.concatenate([np.broadcast_to(radius_x0, (n,)), np.full(N * system.nw, system.eta_w),
                        np.full(N * system.nv, system.eta_v)])

    def run(delta):
        xi0, w, v = delta[:n], delta[n:n + N * system.nw].reshape(N, system.nw), delta[n + N * system.nw:].reshape(
            N, system.nv)
        out = closed_loop(system, make(), trace, xhat0 + xi0, xi0, w, v)
        return out.error[1:], np.array(out.spread)

    c, spread = run(np.zeros(D))
    G = np.stack([run(r * np.eye(D)[j])[0] - c for j in range(D)], axis=-1)  # (N, n, D)
    return c, G, r, spread


def _trace(seed, N, loss, max_delay):
    rng = np.random.default_rng(seed)
    d = rng.integers(0, max_delay + 1, N)
    d[rng.random(N) < loss] = NEVER
    return ArrivalTrace(d)


# -- the zonotope mathematics -----------------------------------------------------------------------------------
def test_reduction_is_outer_and_bounded():
    rng = np.random.default_rng(0)
    G = rng.normal(size=(3, 200)) * rng.random(200) ** 3
    R = reduce_order(G, 5)
    assert R.shape[1] <= 15
    assert np.all(outer_row_sums(R) >= np.abs(G).sum(axis=1))
    for d in rng.normal(size=(200, 3)):  # support functions never smaller
        assert np.abs(d @ R).sum() >= np.abs(d @ G).sum() * (1 - 1e-12)


def test_error_set_carries_anchored_maps_exactly():
    es = ErrorSet.box(1.0, 2, t0=5)
    b = es.advance(ErrorMap(5, np.array([[1.0, -1.0], [0.0, 1.0]]), np.array([[0.1], [0.0]])))
    assert b.tolist() == pytest.approx([2.1, 1.0])
    assert np.all(b >= [2.1, 1.0])
    with pytest.raises(InputError, match="anchor"):
        es.propose(ErrorMap(3, np.eye(2), np.zeros((2, 0))))


# -- strict=False ---------------------------------------------------------------------------------------------
@pytest.mark.parametrize("loss", [0.0, 0.1, 0.4])
def test_strict_false_is_tight_and_holds_with_the_worst_case_played_back(oscillator, osc_design, loss):
    design, sysm = osc_design, oscillator
    trace = _trace(11, 24, loss, 0)
    x0 = np.array([0.7, -0.3])
    c, G, r, spread = _unit_responses(sysm, lambda: design.estimator(strict=False), trace, x0, design.mu1)
    exact = np.abs(G).sum(axis=-1).max(axis=1)  # per step, the exact worst case of this estimator
    assert np.abs(c).max() < 1e-12  # unbiased
    assert np.all(np.isfinite(spread))
    ratio = spread / exact
    assert ratio.min() >= 1 - 1e-9 and np.quantile(ratio, 0.95) <= 1.1
    # the noise at the worst row of the worst step, played back: error <= bound, and it is attained
    t, i = np.unravel_index(np.argmax(np.abs(G).sum(axis=-1) / spread[:, None]), G.shape[:2])
    delta = np.sign(G[t, i]) * r
    n, N = sysm.n, trace.steps
    run = closed_loop(sysm, design.estimator(strict=False), trace, x0 + delta[:n], delta[:n],
                      delta[n:n + N * sysm.nw].reshape(N, sysm.nw), delta[n + N * sysm.nw:].reshape(N, sysm.nv))
    err = np.abs(run.error[1:]).max(axis=1)
    # the played-back error attains the bound, and never passes it: the bound carries the rounding allowance of
    # the estimator's arithmetic and of the simulated state (issue 40 §2), so no tolerance
    assert np.all(err <= np.array(run.spread))
    assert err[t] >= (1 - 1e-9) * exact[t]


def test_strict_false_stays_below_the_designed_levels_inside_the_language(oscillator, osc_design):
    trace = ArrivalTrace.from_arrived([1, 0, 1, 1, 1, 0, 1, 1, 1] * 4)
    strict = closed_loop(oscillator, osc_design.estimator(), trace, np.zeros(2), np.zeros(2), np.zeros((36, 2)),
                         np.zeros((36, 1)))
    relaxed_est = osc_design.estimator(strict=False)
    flags = []
    relaxed = closed_loop(oscillator, relaxed_est, trace, np.zeros(2), np.zeros(2), np.zeros((36, 2)),
                          np.zeros((36, 1)), after_step=lambda k: flags.append(relaxed_est.in_design))
    assert all(flags)
    assert np.all(np.array(relaxed.spread) <= np.array(strict.spread))
    assert np.array(relaxed.spread)[-1] < osc_design.mu1  # what earlier periods told is kept


def test_strict_false_never_overflows_and_comes_back(oscillator, osc_design):
    rng = np.random.default_rng(5)
    N = 3000
    d = np.where(rng.random(N) < 0.4, NEVER, 0)
    d[2000:2100] = 0  # 100 good steps
    trace = ArrivalTrace(d)
    est = osc_design.estimator(strict=False)
    flags = []
    run = closed_loop(oscillator, est, trace, np.zeros(2), rng.uniform(-1, 1, 2) * osc_design.mu1,
                      rng.choice([-1, 1], (N, 2)) * 0.1, rng.choice([-1, 1], (N, 1)) * 0.05,
                      after_step=lambda k: flags.append(est.in_design))
    spread = np.array(run.spread)
    assert np.all(np.isfinite(spread)) and spread.max() < 10 * osc_design.mu1
    assert np.all(np.abs(run.error[1:]).max(axis=1) <= spread)
    assert any(flags[2010:2100])  # the designed gains are back during the good stretch


def test_strict_true_names_strict_false_and_reset(oscillator, osc_design):
    est = osc_design.estimator().reset(np.zeros(2))
    est.step(None)
    with pytest.raises(InputError, match=r"strict=False.*reset"):
        est.step(None)


# -- eqrec.exact_bound --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("family", [TimestampedKalman, DelayUnawareKalman])
def test_exact_bound_of_the_kalman_filters_equals_the_unit_perturbation_worst_case(family, oscillator):
    sysm = oscillator
    design = GaussianNoise(Qw=np.eye(2) * 0.002, Qv=np.eye(1) * 0.0004, x0_cov=np.eye(2) * 0.04).design(sysm)
    trace = _trace(3, 20, 0.2, 2)
    x0 = np.array([1.0, -2.0])
    c, G, r, spread = _unit_responses(sysm, lambda: exact_bound(family(sysm, design), sysm, 0.5, steps=20),
                                      trace, x0, 0.5)
    exact = (np.abs(c) + np.abs(G).sum(axis=-1)).max(axis=1)
    assert np.all(spread >= exact * (1 - 1e-12)) and np.all(spread <= exact * (1 + 1e-9))


def test_exact_bound_shares_the_true_columns_and_gives_the_same_bits():
    """``truths=``: the runs that simulate the same true columns share them (one simulation per start and inputs)
    and report the same bounds, bit for bit, as runs of their own; a run whose inputs differ from the shared
    trail's leaves it at that step."""
    osc = _oscillator()
    sysm = AffineSystem(A=osc.A, C=osc.C, E=osc.E, eta_w=osc.eta_w, eta_v=osc.eta_v, B=[[0.0], [1.0]])
    design = GaussianNoise(Qw=np.eye(2) * 0.002, Qv=np.eye(1) * 0.0004, x0_cov=np.eye(2) * 0.04).design(sysm)
    trace, N = _trace(5, 16, 0.2, 2), 16
    rng = np.random.default_rng(1)
    w, v, xi0 = 0.1 * rng.uniform(-1, 1, (N, 2)), 0.05 * rng.uniform(-1, 1, (N, 1)), rng.uniform(-0.5, 0.5, 2)
    x0 = np.array([1.0, -2.0])
    inputs = {"zero": lambda k, xhat: np.zeros(1), "late kick": lambda k, xhat: np.array([0.3 * (k >= 6)])}

    def spreads(family, u_at, truths):
        run = closed_loop(sysm, exact_bound(family(sysm, design), sysm, 0.5, steps=N, truths=truths), trace, x0, xi0,
                          w, v, u_at=u_at)
        return np.array(run.spread), run.xhat

    shared: dict = {}
    for family in (TimestampedKalman, DelayUnawareKalman):
        for u_at in inputs.values():
            alone, together = spreads(family, u_at, None), spreads(family, u_at, shared)
            assert np.array_equal(alone[0], together[0]) and np.array_equal(alone[1], together[1])
    (trail,) = [steps for _, steps in shared.values()]  # one start: one trail, of the first inputs' N steps
    assert len(trail) == N and trail[0].u == np.zeros(1).tobytes()
    assert not trail[-1].truth.flags.writeable  # shared: read only


def test_exact_bound_of_a_design_equals_plain_strict_false_inside_the_language(oscillator, osc_design):
    trace = ArrivalTrace.from_arrived([1, 0, 1, 1, 1, 0] * 3)
    rng = np.random.default_rng(2)
    w, v = rng.uniform(-0.1, 0.1, (18, 2)), rng.uniform(-0.05, 0.05, (18, 1))
    a = closed_loop(oscillator, exact_bound(osc_design.estimator(), oscillator, osc_design.mu1, order=40), trace,
                    np.zeros(2), np.zeros(2), w, v)
    b = closed_loop(oscillator, osc_design.estimator(strict=False, tight=False), trace, np.zeros(2), np.zeros(2),
                    w, v)
    assert np.array_equal(a.xhat, b.xhat)
    assert np.all(np.array(b.spread) <= np.array(a.spread))


def test_exact_bound_refuses_bad_arguments(oscillator):
    design = GaussianNoise(Qw=np.eye(2) * 0.002, Qv=np.eye(1) * 0.0004, x0_cov=np.eye(2)).design(oscillator)
    with pytest.raises(InputError, match="steps"):
        exact_bound(TimestampedKalman(oscillator, design), oscillator, 0.5)
    with pytest.raises(InputError, match="x0_radius"):
        exact_bound(TimestampedKalman(oscillator, design), oscillator, -1.0, steps=3)
    with pytest.raises(InputError, match="order"):
        exact_bound(TimestampedKalman(oscillator, design), oscillator, 1.0, order=0.5, steps=3)
    est = exact_bound(TimestampedKalman(oscillator, design), oscillator, 1.0, steps=1).reset(np.zeros(2))
    est.step(None)
    with pytest.raises(InputError, match="steps"):
        est.step(None)
    assert eqrec.exact_bound is exact_bound


@pytest.mark.parametrize("mechanism", ["zero-input", "hold-input"])
def test_exact_bound_of_the_lmv_predictors_equals_the_unit_perturbation_worst_case(mechanism):
    """The LMV predictors run on affine columns too (``LMVEstimator.reset(..., one=)``), held measurement included."""
    from eqrec.compare.families import _lmv
    from eqrec.systems.examples import acc_system

    acc = acc_system()
    make = _lmv(acc, GaussianNoise.from_box(acc, 0.5, 5.0), mechanism, 0.35, 20)
    trace = _trace(3, 20, 0.3, 1)
    c, G, r, spread = _unit_responses(acc, lambda: exact_bound(make(), acc, 0.5, steps=20), trace,
                                      np.array([1.0, 2.0, 3.0]), 0.5)
    exact = (np.abs(c) + np.abs(G).sum(axis=-1)).max(axis=1)
    assert np.all(spread >= exact * (1 - 1e-12)) and np.all(spread <= exact * (1 + 1e-9))


def _played_back(system, make, trace, xhat0, delta):
    """One run with the uncertainty ``δ = (ξ0, w, v)`` played back; returns per step ``(error, bound)``."""
    n, N = system.n, trace.steps
    w = delta[n:n + N * system.nw].reshape(N, system.nw)
    v = delta[n + N * system.nw:].reshape(N, system.nv)
    run = closed_loop(system, make(), trace, xhat0 + delta[:n], delta[:n], w, v)
    return np.abs(run.error[1:]).max(axis=1), np.array(run.spread)


@pytest.mark.parametrize("loss", [0.0, 0.1, 0.4])
@pytest.mark.parametrize("family", ["strict=False", "strict=False, plain", "zonotope", "zonotope, window 5, order 3",
                                    "zonotope, large-plant solves", "Kalman, time-stamped"])
def test_every_worst_case_played_back_stays_inside_and_no_bound_is_below_the_information_limit(
        oscillator, osc_design, family, loss):
    """For every step ``t``: the noise at the sign of the worst row of the error map at ``t`` (initial error at
    its box corner) played back gives error <= bound at every step (no tolerance: the bounds carry their rounding allowance),
    and the bound is never below the information limit (1e-9 relative: the limit is an LP optimum)."""
    from eqrec.bounds.information import information_limit
    from eqrec.estimators.zonotope import DEFAULT_ITERATIONS_LARGE, ZonotopeEstimator

    sysm, mu1 = oscillator, osc_design.mu1
    kalman = GaussianNoise(Qw=np.eye(2) * 0.002, Qv=np.eye(1) * 0.0004, x0_cov=np.eye(2) * 0.04).design(sysm)
    make = {"strict=False": lambda: osc_design.estimator(strict=False),
            "strict=False, plain": lambda: osc_design.estimator(strict=False, tight=False),
            "zonotope": lambda: ZonotopeEstimator(sysm, x0_radius=mu1, max_delay=0, order=None),
            # the filter 5 steps behind, reduced: the window's prior is a filtered, reduced zonotope from step 5 on
            "zonotope, window 5, order 3": lambda: ZonotopeEstimator(sysm, x0_radius=mu1, max_delay=0, order=3,
                                                                     window=5),
            # the per-state solves a plant of more than LARGE_PLANT_STATES states gets by default (one reweighted)
            "zonotope, large-plant solves": lambda: ZonotopeEstimator(sysm, x0_radius=mu1, max_delay=0, order=3,
                                                                      window=5, iterations=DEFAULT_ITERATIONS_LARGE),
            "Kalman, time-stamped": lambda: exact_bound(TimestampedKalman(sysm, kalman), sysm, mu1, steps=18)}[family]
    trace = _trace(7, 18, loss, 0)
    xhat0 = np.array([0.4, -0.2])
    c, G, r, spread = _unit_responses(sysm, make, trace, xhat0, mu1)
    limit = information_limit(sysm, trace, mu1).max(axis=1)
    assert np.all(spread >= limit * (1 - 1e-9))
    for t in range(trace.steps):
        i = int(np.argmax(np.abs(G[t]).sum(axis=-1)))
        err, bound = _played_back(sysm, make, trace, xhat0, np.sign(G[t, i]) * r)
        assert np.all(err <= bound), (t, float((err / bound).max()))
        assert np.all(bound >= limit * (1 - 1e-9))
