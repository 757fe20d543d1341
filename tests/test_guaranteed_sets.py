"""``GuaranteedEstimator.predicted`` and ``.filtered`` (issue 45 §1, the protocol's sets,
:mod:`eqrec.estimators.protocol`): the predicted set is the set of the reported estimate with its reported bounds
(per state the designed or the set-membership row, as reported), and both contain the true state with the worst
noise at box corners, in and out of the design, with no tolerance."""
import numpy as np
import pytest

from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.design.delay.design import design_delay_global
from eqrec.design.delay.languages import delay_classes
from eqrec.errors import InputError
from eqrec.estimators.protocol import StateSet
from eqrec.simulate.loop import closed_loop, draw_box
from eqrec.systems.examples import two_mass


@pytest.fixture(scope="module")
def design():
    system = two_mass()
    return system, design_delay_global(system, delay_classes(max_delay=2, horizon=6, max_lost=1)).design


def _run(design, tight: bool, loss: float, seed: int = 2, N: int = 72):
    system, d = design
    rng = np.random.default_rng(seed)
    trace = with_uniform_delays(rng, bernoulli_trace(rng, N, loss), 2)
    w = draw_box(rng, system.eta_w, (N, system.nw), "vertex")
    v = draw_box(rng, system.eta_v, (N, system.nv), "vertex")
    xi0 = draw_box(rng, d.mu1, (system.n,), "vertex")
    est = d.estimator(strict=False, tight=tight)
    seen = []

    def after(k):
        seen.append((est.predicted, est.filtered, est.x, est.state_bounds, est.in_design,
                     None if est._use_sm is None else est._use_sm.copy(), est.time))

    run = closed_loop(system, est, trace, np.full(system.n, 2.0), xi0, w, v, after_step=after)
    return run, seen


@pytest.mark.parametrize("tight", [True, False])
def test_the_predicted_set_is_the_reported_estimate_with_its_bounds_and_holds_the_state(design, tight):
    system, d = design
    run, seen = _run(design, tight, 0.4)
    outside = chosen = 0
    for k, (pred, filt, x, bounds, inside, use_sm, time) in enumerate(seen):
        assert pred.time == time == k + 1 and filt.time == k
        assert np.array_equal(pred.centre, x)
        ref = StateSet.around(time, x, bounds)
        assert np.array_equal(pred.lower, ref.lower) and np.array_equal(pred.upper, ref.upper)
        # the true states: x(t+1) in the predicted set, x(t) in the filtered one (no tolerance)
        assert np.all(pred.lower <= run.x[k + 1]) and np.all(run.x[k + 1] <= pred.upper), k
        assert np.all(filt.lower <= run.x[k]) and np.all(run.x[k] <= filt.upper), k
        # the zonotope holds x(t+1) too: |x − centre| within its row sums, and its hull is the reported bounds
        G = pred.generators
        sums = np.abs(G).sum(axis=1)
        assert np.all(np.abs(run.x[k + 1] - pred.centre) <= sums * (1 + 1e-12)), k
        assert np.all(sums <= bounds * (1 + 1e-12)) and np.all(sums >= bounds * (1 - 1e-12)), k
        outside += not inside
        if inside and use_sm is not None:
            chosen += use_sm.any() and not use_sm.all()
    assert outside > 0  # the run leaves the design and comes back
    if tight:
        assert chosen > 0  # some steps report some states from each estimate


def test_the_predicted_rows_follow_the_per_state_choice(design):
    """In the design, tight: a state reported from the set-membership estimate has its row of the carried set, one
    reported from the designed estimate its row of the designed set (each zero on the other's generators)."""
    system, d = design
    rng = np.random.default_rng(4)
    N = 30
    trace = with_uniform_delays(rng, bernoulli_trace(rng, N, 0.0), 2)
    w = draw_box(rng, system.eta_w, (N, system.nw), "vertex")
    v = draw_box(rng, system.eta_v, (N, system.nv), "vertex")
    est = d.estimator(strict=False)
    checked = 0

    def after(k):
        nonlocal checked
        G = est.predicted.generators
        use_sm = est._use_sm
        if use_sm is None:
            return
        q = est._set.current.shape[1]
        designed, sm = G[:, :q], G[:, q:q + est._sm.carried_set[1].shape[1]]
        pad = G[:, -system.n:]
        for i in range(system.n):
            if use_sm[i]:
                assert not designed[i].any() and np.array_equal(sm[i], est._sm.carried_set[1][i])
            elif designed[i].any():
                assert not sm[i].any() and np.array_equal(designed[i], est._set.current[i])
            else:  # the designed level below the set's worst case: the level's box
                assert not sm[i].any() and pad[i, i] == est.state_bounds[i]
        checked += 1

    closed_loop(system, est, trace, np.zeros(system.n), np.zeros(system.n), w, v, after_step=after)
    assert checked == N


def test_sets_before_and_right_after_reset_and_with_strict_true(design):
    system, d = design
    est = d.estimator(strict=False)
    with pytest.raises(InputError):
        est.predicted
    with pytest.raises(InputError):
        est.filtered
    x0 = np.array([1.0, -2.0, 0.5, 0.0])
    est.reset(x0)
    box = est.predicted
    assert box.time == 0 and np.array_equal(box.centre, x0)
    assert np.allclose(np.abs(box.generators).sum(axis=1), d.mu1, rtol=1e-15)
    with pytest.raises(InputError, match="no step"):
        est.filtered
    strict = d.estimator().reset(x0)
    p = strict.predicted
    assert np.array_equal(p.centre, x0) and np.array_equal(p.generators, d.mu1 * np.eye(system.n))
    strict.step(np.zeros(system.p))
    p = strict.predicted
    assert p.time == 1 and np.all(p.radius >= strict.bound)
    with pytest.raises(InputError, match="strict=True"):
        strict.filtered
