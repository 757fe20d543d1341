"""A true bound when the arrivals leave the designed language (strict=False), and the time convention of the
runtime estimators on time-varying systems (issue 24, sections 1 and 2)."""
import numpy as np
import pytest

from eqrec.systems.affine import AffineSystem
from eqrec.design.delay.design import design_delay_global
from eqrec.errors import InputError

LOSS = ["000", "300", "030", "003"]  # at most one loss per block of three


@pytest.fixture(scope="module")
def plant():
    return AffineSystem(A=np.array([[1.0, 0.1], [0.0, 1.0]]), B=np.array([[0.005], [0.1]]),
                        C=np.array([[1.0, 0.0]]), E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)


@pytest.fixture(scope="module")
def design(plant):
    return design_delay_global(plant, LOSS).design


def _monte_carlo(system, true_A, design, loss, runs, steps, seed, t0=0, burst=False):
    """Runs with Bernoulli (or bursty) losses beyond the design and noise at the box corners.

    Returns the largest error/bound ratio, the number of out-of-design steps and of returns to the design."""
    rng = np.random.default_rng(seed)
    worst, outside, returns = 0.0, 0, 0
    for _ in range(runs):
        est = design.estimator(strict=False)
        x = rng.uniform(-3, 3, system.n)
        est.reset(x - rng.choice([-1.0, 1.0], system.n) * design.mu1, t0=t0)
        previous, bad = True, False
        for k in range(t0, t0 + steps):
            u = np.array([np.cos(0.2 * k)])
            y = system.C_at(0) @ x + system.V_at(0) @ (rng.choice([-1.0, 1.0], system.nv) * system.eta_v)
            bad = (rng.random() < (0.6 if bad else 0.1)) if burst else rng.random() < loss
            xhat, bound = est.step(None if bad else y, u)
            w = rng.choice([-1.0, 1.0], system.nw) * system.eta_w
            x = true_A(k) @ x + system.B_at(0) @ u + system.f + system.E_at(0) @ w
            worst = max(worst, float(np.abs(x - xhat).max() / bound))
            outside += not est.in_design
            returns += est.in_design and not previous
            previous = est.in_design
    return worst, outside, returns


@pytest.mark.parametrize("loss,burst", [(0.3, False), (0.6, False), (0.0, True)])
def test_the_bound_holds_outside_the_language(plant, design, loss, burst):
    worst, outside, returns = _monte_carlo(plant, lambda k: plant.A, design, loss, runs=60, steps=60, seed=7,
                                           burst=burst)
    assert worst <= 1 + 1e-12
    assert outside > 0 and returns > 0  # the traces did leave the language, and the guarantee came back


def test_inside_the_language_strict_false_gives_the_designed_bounds(plant, design):
    strict = design.estimator().reset(np.zeros(2))
    plain = design.estimator(strict=False, tight=False).reset(np.zeros(2))
    tight = design.estimator(strict=False).reset(np.zeros(2))
    rng = np.random.default_rng(3)
    tighter = 0
    for k in range(30):
        y = None if k % 3 == 1 else rng.normal(size=1)
        a, b, c = strict.step(y), plain.step(y), tight.step(y)
        # plain: the same estimate; the exact bound keeps what earlier periods told, so it is never above the level
        assert np.array_equal(a[0], b[0]) and b[1] <= a[1] and plain.in_design
        assert np.all(plain.state_bounds <= a[1])
        # tight: per state never above the plain bound, so never above the designed level (a priori levels kept)
        assert tight.in_design and np.all(tight.state_bounds <= plain.state_bounds) and c[1] <= a[1]
        assert c[1] == tight.state_bounds.max() and np.array_equal(c[0], tight.x)
        tighter += c[1] < b[1]
    assert tighter > 10  # the set-membership estimate is the tighter one on most steps here


def test_leaving_the_language_reports_it_and_the_box(design):
    est = design.estimator(strict=False).reset(np.zeros(2))
    est.step(None)
    assert est.in_design
    _, bound = est.step(None)  # a second loss in the block: outside the language
    assert not est.in_design and bound == est.state_bounds.max() and np.isfinite(bound)
    strict = design.estimator().reset(np.zeros(2))
    assert np.array_equal(strict.state_bounds, np.full(2, design.mu1))  # strict=True: the designed level per state
    strict.step(None)
    assert np.array_equal(strict.error_box, np.full(2, strict.bound))
    with pytest.raises(InputError, match="reset"):
        design.estimator().state_bounds


def test_time_varying_model_is_read_at_the_period_time_over_several_periods():
    """A 3-periodic plant (the design's model covers one period), started at t0 = 5: the guarantee holds in every
    period, and the estimator reads the model at the period time (absolute time would run past the data)."""
    T = 3
    A = np.stack([[[1.0, 0.1 * (1 + 0.5 * t)], [0.0, 0.95 + 0.02 * t]] for t in range(T)])
    system = AffineSystem(A=A, B=np.array([[0.005], [0.1]]), C=np.array([[1.0, 0.0]]), E=0.1 * np.eye(2),
                          eta_w=0.1, eta_v=0.05)
    design = design_delay_global(system, LOSS).design
    t0 = 5
    true_A = (lambda k: A[(k - t0) % T])
    rng = np.random.default_rng(11)
    worst = 0.0
    for _ in range(40):
        est = design.estimator().reset(np.zeros(2), t0=t0)
        x = rng.choice([-1.0, 1.0], 2) * design.mu1
        for k in range(t0, t0 + 8 * T):
            if (k - t0) % T == 0:
                which = rng.integers(0, T + 1)  # the one loss of this period (T: none)
            lost = (k - t0) % T == which
            y = system.C_at(0) @ x + rng.choice([-1.0, 1.0], 1) * 0.05
            xhat, bound = est.step(None if lost else y, np.array([0.3]))
            x = true_A(k) @ x + system.B_at(0) @ np.array([0.3]) + system.E_at(0) @ (rng.choice([-1.0, 1.0], 2) * 0.1)
            worst = max(worst, float(np.abs(x - xhat).max() / bound))
    assert worst <= 1 + 1e-12
    # out of the language too: the same periodic plant, losses beyond the design
    worst, outside, _ = _monte_carlo(system, true_A, design, 0.4, runs=30, steps=30, seed=5, t0=t0)
    assert worst <= 1 + 1e-12 and outside > 0


def test_python_control_system_runs_inside_the_language_only(plant, design):
    """Outside the language the estimator carries a zonotope of varying size: no fixed I/O state holds it."""
    pytest.importorskip("control")
    from eqrec.interop.python_control import estimator_iosys

    with pytest.raises(InputError, match=r"strict=False"):
        estimator_iosys(design, strict=False)


def test_python_control_system_refuses_bad_arrivals_and_non_finite_data(plant, design):
    control = pytest.importorskip("control")
    from eqrec.interop.python_control import estimator_iosys

    io = estimator_iosys(design)
    N = 6
    for row, col, value, field in ((2, 3, 0.5, "arrived"), (0, 2, np.nan, "'u'"), (1, 2, np.inf, "'y'")):
        U = np.vstack([np.zeros(N), np.zeros(N), np.ones(N)])
        U[row, col] = value
        with pytest.raises(InputError, match=field):
            control.input_output_response(io, np.arange(N), U, io.initial_state(np.zeros(2)))
    U = np.vstack([np.zeros(N), np.zeros(N), np.ones(N)])
    U[2, 3], U[1, 3] = 0, 1e300  # a lost packet's y is not read
    r = control.input_output_response(io, np.arange(N), U, io.initial_state(np.zeros(2)))
    assert np.all(np.isfinite(r.outputs))
    assert estimator_iosys(design, dt=0.1).dt == 0.1


def test_python_control_system_carries_the_plants_sampling_time():
    control = pytest.importorskip("control")
    from eqrec.interop.python_control import estimator_iosys, system_from_statespace

    plant = system_from_statespace(control.ss([[1, 0.1], [0, 1]], [[0.005], [0.1]], [[1, 0]], 0, 0.05),
                                   eta_w=0.1, eta_v=0.05, E=0.1 * np.eye(2))
    assert plant.dt == 0.05
    design = design_delay_global(plant, LOSS).design
    assert estimator_iosys(design).dt == 0.05
    with pytest.raises(InputError, match="dt"):
        AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.1, dt=-1)
