"""The exact consistent set (issue 45 §2): the hull of the states consistent with the measured data.

On random plants, traces (losses, delays) and data drawn by the one simulation loop:
* the true state lies in the filtered and the predicted hull (it is consistent with its own data);
* Theorem 1: the predicted hull lies in its centre ± the information limit;
* Theorem 2: the zonotope estimator's predicted set, ``x̂ ± state_bounds`` rounded outward, contains the
  predicted hull (and so its centre ± the limit need not, but its set must).
Comparisons carry no tolerance: the estimator's interval and the limit's interval are rounded outward by one
unit in the last place (``np.nextafter``), nothing more.  The hulls are LP optima (HiGHS, 1e-9 on the rows);
where a tie is exact in the mathematics (a step with no data: hull radius = limit) the two optima come from the
same LP vertex and agree to rounding.
Hand-checked values, the data forms, the inputs and centre, and bad input.
"""

from __future__ import annotations

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.bounds.consistent import ConsistentSet, consistent_set
from eqrec.bounds.information import information_limit
from eqrec.simulate.loop import closed_loop


def _random_plant(seed: int) -> eqrec.AffineSystem:
    rng = np.random.default_rng(seed)
    n = int(rng.integers(2, 5))
    p = int(rng.integers(1, 3))
    A = rng.normal(size=(n, n))
    A *= rng.uniform(0.7, 1.05) / max(abs(np.linalg.eigvals(A)))
    C = rng.normal(size=(p, n))
    E = rng.normal(size=(n, int(rng.integers(1, n + 1))))
    return eqrec.AffineSystem(A=A, C=C, E=E, eta_w=float(rng.uniform(0.01, 0.2)), eta_v=float(rng.uniform(0.01, 0.3)),
                              B=rng.normal(size=(n, 1)))


def _random_trace(N: int, loss: float, max_delay: int, seed: int) -> ArrivalTrace:
    rng = np.random.default_rng(seed)
    return ArrivalTrace(np.where(rng.random(N) < loss, NEVER, rng.integers(0, max_delay + 1, N)))


def _run(system, trace, radius, seed, estimator=None, inputs=None):
    """A closed-loop run with noise uniform in the boxes; the estimator's x̂(t+1) and state bounds per step."""
    rng = np.random.default_rng(seed)
    N, n = trace.steps, system.n
    x0 = rng.uniform(-1, 1, n)
    xi0 = rng.uniform(-1, 1, n) * radius
    w = rng.uniform(-1, 1, (N, system.nw)) * system.eta_w
    v = rng.uniform(-1, 1, (N, system.nv)) * system.eta_v
    est = estimator or eqrec.ZonotopeEstimator(system, x0_radius=radius, max_delay=2)
    bounds = []
    u_at = None if inputs is None else (lambda k, _x: inputs[k])
    run = closed_loop(system, est, trace, x0, xi0, w, v, u_at=u_at,
                      after_step=lambda k: bounds.append(est.state_bounds))
    return run, np.array(bounds)


@pytest.mark.parametrize("seed", range(6))
def test_random_plants_truth_limit_and_estimator(seed):
    system = _random_plant(seed)
    trace = _random_trace(30, 0.3, 2, 100 + seed)
    radius = 0.8
    u = np.random.default_rng(seed).normal(size=(30, 1))
    run, beta = _run(system, trace, radius, seed, inputs=u)
    xhat0 = run.xhat[0]
    hull = consistent_set(system, trace, run.y, radius, x0_centre=xhat0, inputs=u)
    assert isinstance(hull, ConsistentSet) and hull.steps == 30
    for arr in (hull.filtered_lower, hull.filtered_upper, hull.predicted_lower, hull.predicted_upper):
        assert arr.shape == (30, system.n) and np.all(np.isfinite(arr))
    # the true state is consistent with its own data (LP optima: 1e-9 on the rows, the state's scale ~1)
    assert np.all(hull.filtered_lower <= run.x[:-1] + 1e-7) and np.all(run.x[:-1] <= hull.filtered_upper + 1e-7)
    assert np.all(hull.predicted_lower <= run.x[1:] + 1e-7) and np.all(run.x[1:] <= hull.predicted_upper + 1e-7)
    # Theorem 1: centre ± limit contains the predicted hull (rounded outward, no tolerance)
    limit = information_limit(system, trace, radius)
    c = hull.predicted_centre
    assert np.all(np.nextafter(c - limit, -np.inf) <= hull.predicted_lower)
    assert np.all(hull.predicted_upper <= np.nextafter(c + limit, np.inf))
    assert np.all(hull.predicted_radius <= np.nextafter(limit, np.inf))
    # Theorem 2: the zonotope estimator's predicted set contains the predicted hull (rounded outward)
    lo = np.nextafter(run.xhat[1:] - beta, -np.inf)
    hi = np.nextafter(run.xhat[1:] + beta, np.inf)
    assert np.all(lo <= hull.predicted_lower), np.max(lo - hull.predicted_lower)
    assert np.all(hull.predicted_upper <= hi), np.max(hull.predicted_upper - hi)


def test_the_hull_is_tighter_than_the_limit_on_data():
    """On data the hull can be strictly smaller than the limit (the ruler on the data), never larger."""
    system = _random_plant(3)
    trace = _random_trace(40, 0.1, 1, 7)
    run, _ = _run(system, trace, 0.8, 7)
    hull = consistent_set(system, trace, run.y, 0.8, x0_centre=run.xhat[0])
    limit = information_limit(system, trace, 0.8)
    assert np.all(hull.predicted_radius <= np.nextafter(limit, np.inf))
    assert np.any(hull.predicted_radius < 0.999 * limit)


def test_scalar_by_hand():
    # x(t+1) = x + w, y = x + v, |w| <= 0.1, |v| <= 0.5, |x(0)| <= 1; y(0) = 0.3, y(1) lost, y(2) = 0.2
    walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    trace = ArrivalTrace([0, NEVER, 0])
    hull = consistent_set(walk, trace, [[0.3], [np.nan], [0.2]], 1.0)
    np.testing.assert_allclose(hull.filtered_lower[:, 0], [-0.2, -0.3, -0.3], atol=1e-12)
    np.testing.assert_allclose(hull.filtered_upper[:, 0], [0.8, 0.9, 0.7], atol=1e-12)
    np.testing.assert_allclose(hull.predicted_lower[:, 0], [-0.3, -0.4, -0.4], atol=1e-12)
    np.testing.assert_allclose(hull.predicted_upper[:, 0], [0.9, 1.0, 0.8], atol=1e-12)
    np.testing.assert_allclose(hull.filtered_centre[:, 0], [0.3, 0.3, 0.2], atol=1e-12)
    np.testing.assert_allclose(hull.predicted_radius[:, 0], [0.6, 0.7, 0.6], atol=1e-12)


def test_a_late_packet_counts_from_its_arrival():
    # y(0) arrives at step 2: the filtered hull of x(0) and x(1) ignore it, x(2)'s uses it
    walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    hull = consistent_set(walk, ArrivalTrace([2, NEVER, NEVER]), [[0.3], [0.0], [0.0]], 1.0)
    np.testing.assert_allclose(hull.filtered_radius[:, 0], [1.0, 1.1, 0.7], atol=1e-12)
    np.testing.assert_allclose(hull.filtered_lower[2, 0], -0.4, atol=1e-12)


def test_data_forms_agree():
    system = _random_plant(1)
    trace = _random_trace(20, 0.3, 2, 3)
    run, _ = _run(system, trace, 0.5, 3)
    delivered = {tau: run.y[tau] for tau in range(20) if trace.delays[tau] != NEVER and tau + trace.delays[tau] < 20}
    a = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0])
    masked = run.y.copy()
    masked[[tau for tau in range(20) if tau not in delivered]] = np.nan  # lost packets have no value
    b = consistent_set(system, trace, masked, 0.5, x0_centre=run.xhat[0])
    c = consistent_set(system, trace, delivered, 0.5, x0_centre=run.xhat[0])
    for other in (b, c):
        np.testing.assert_array_equal(a.filtered_upper, other.filtered_upper)
        np.testing.assert_array_equal(a.predicted_lower, other.predicted_lower)


def test_centre_and_inputs_shift_the_hull():
    """Shifting x(0) and the data by a noise-free run shifts the hull by that run (the LP sees residuals)."""
    walk = eqrec.AffineSystem(A=[[0.9]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5, B=[[1.0]])
    trace = ArrivalTrace([0, 0, 1])
    u = np.array([[1.0], [2.0], [-1.0]])
    xbar = [5.0]
    for k in range(3):
        xbar.append(0.9 * xbar[-1] + u[k, 0])
    xbar = np.array(xbar)
    y = np.array([[0.3], [-0.1], [0.2]])
    base = consistent_set(walk, trace, y, 1.0)
    moved = consistent_set(walk, trace, y + xbar[:3, None], 1.0, x0_centre=[5.0], inputs=u)
    np.testing.assert_allclose(moved.filtered_lower - base.filtered_lower, xbar[:3, None], atol=1e-12)
    np.testing.assert_allclose(moved.predicted_upper - base.predicted_upper, xbar[1:, None], atol=1e-12)


def test_inconsistent_data_name_the_step():
    walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    with pytest.raises(eqrec.InputError, match="delivered by step 1") as info:
        consistent_set(walk, ArrivalTrace([0, 0, 0]), [[0.0], [5.0], [0.0]], 1.0)
    assert info.value.field == "data"


@pytest.mark.parametrize("kwargs,field", [
    (dict(data=np.zeros((2, 1))), "data"),
    (dict(data=[[0.0], [np.nan], [0.0]]), "data"),  # y(1) is delivered: it needs a value
    (dict(data={0: [0.0], 2: [0.0]}), "data"),
    (dict(data=np.zeros((3, 2))), "data"),
    (dict(x0_radius=-1.0), "x0_radius"),
    (dict(x0_radius=1e300), "x0_radius"),
    (dict(x0_centre=[np.nan]), "x0_centre"),
    (dict(x0_centre=[0.0, 1.0]), "x0_centre"),
    (dict(inputs=np.zeros((2, 1))), "inputs"),
    (dict(trace=[0, 0, 0]), "trace"),
    (dict(system="walk"), "system"),
    (dict(kinds=("smoothed",)), "kinds"),
    (dict(kinds=()), "kinds"),
    (dict(kinds=("predicted", "predicted")), "kinds"),
    (dict(kinds="predicted"), "kinds"),
])
def test_bad_input(kwargs, field):
    walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5, B=[[1.0]])
    args = dict(system=walk, trace=ArrivalTrace([0, 0, 0]), data=np.zeros((3, 1)), x0_radius=1.0)
    args.update(kwargs)
    with pytest.raises(eqrec.InputError) as info:
        consistent_set(**args)
    assert info.value.field == field


def test_public_name_and_empty_trace():
    assert eqrec.consistent_set is consistent_set and "consistent_set" in eqrec.__all__
    walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    hull = consistent_set(walk, ArrivalTrace([]), np.zeros((0, 1)), 1.0)
    assert hull.filtered_lower.shape == (0, 1) and hull.predicted_radius.shape == (0, 1)


def test_other_solver_agrees():
    system = _random_plant(2)
    trace = _random_trace(10, 0.3, 1, 5)
    run, _ = _run(system, trace, 0.5, 5)
    a = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0])
    b = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0], solver="scipy")
    np.testing.assert_allclose(a.predicted_lower, b.predicted_lower, atol=1e-7)
    np.testing.assert_allclose(a.filtered_upper, b.filtered_upper, atol=1e-7)


def test_one_kind_agrees_with_both():
    """``kinds=`` one hull alone (the compare study's predicted hulls at half the LPs): the same hull as with both,
    to the solver's tolerance (the warm starts differ), and the other kind NaN."""
    system = _random_plant(3)
    trace = _random_trace(20, 0.3, 2, 4)
    run, _ = _run(system, trace, 0.5, 4)
    both = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0])
    pred = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0], kinds=("predicted",))
    filt = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0], kinds=("filtered",))
    np.testing.assert_allclose(pred.predicted_lower, both.predicted_lower, atol=1e-7)
    np.testing.assert_allclose(pred.predicted_upper, both.predicted_upper, atol=1e-7)
    np.testing.assert_allclose(filt.filtered_lower, both.filtered_lower, atol=1e-7)
    np.testing.assert_allclose(filt.filtered_upper, both.filtered_upper, atol=1e-7)
    assert np.isnan(pred.filtered_lower).all() and np.isnan(filt.predicted_upper).all()
    assert not np.isnan(pred.predicted_radius).any() and not np.isnan(filt.filtered_radius).any()
    again = consistent_set(system, trace, run.y, 0.5, x0_centre=run.xhat[0], kinds=("predicted", "filtered"))
    np.testing.assert_array_equal(again.predicted_upper, both.predicted_upper)  # the LPs' order is fixed
