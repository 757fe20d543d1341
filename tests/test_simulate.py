import numpy as np

from eqrec.design.prefix.design import design_prefix
from eqrec.simulate.loop import monte_carlo, sample_uncertainty
from eqrec.bounds.stacking import UncertaintyLayout


def test_samples_stay_in_the_box(rng):
    lay = UncertaintyLayout(6, 1, 2, 3)
    r = lay.radius(0.1, 0.05, 1.0)
    u = sample_uncertainty(lay, r, rng, "uniform", size=200)
    v = sample_uncertainty(lay, r, rng, "vertex", size=200)
    assert np.all(np.abs(u) <= r) and np.allclose(np.abs(v), r)


def test_monte_carlo_inside_certified_bounds(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    errs, words = monte_carlo(acc, d.schedule, L1_words, 1.0, 50, seed=3, kind="vertex")
    bounds = np.stack([d.certificate.words[w].bounds for w in words])
    assert np.all(np.abs(errs) <= bounds + 1e-9)
    assert set(words) <= set(L1_words)


# ---------------------------------------------------------------------------- the one loop

def _acc_run_data(acc, rng, N):
    w = rng.uniform(-1, 1, (N, acc.nw)) * acc.eta_w
    v = rng.uniform(-1, 1, (N, acc.nv)) * acc.eta_v
    return w, v, np.array([20.0, 40.0, 20.0]), rng.uniform(-1, 1, 3)


def test_closed_loop_runs_a_protocol_estimator_like_the_raw_one(acc, L1_words, rng):
    """The same design run as GuaranteedEstimator and as the raw RecoveryEstimator, both reset/step -> (x̂, bound),
    in the one loop: the same estimates; the raw one built with the design's levels returns the same bounds, which
    hold, and built without them it returns inf."""
    from eqrec.arrivals.draws import uniform_words, ArrivalTrace
    from eqrec.estimators.causal import make_estimator
    from eqrec.simulate.loop import closed_loop

    d = design_prefix(acc, L1_words, 1.0)
    words = uniform_words(rng, L1_words, size=5)
    trace = ArrivalTrace.from_pattern("".join(words))
    N = trace.steps
    w, v, x0, xi0 = _acc_run_data(acc, rng, N)
    u_at = lambda k, xh: np.array([206.0 + np.sin(k)])  # noqa: E731
    guaranteed = d.estimator()
    raw = closed_loop(acc, make_estimator(acc, guaranteed.gains, periodic=True), trace, x0, xi0, w, v, u_at)
    leveled = closed_loop(acc, make_estimator(acc, guaranteed.gains, periodic=True, bound_of=guaranteed.bound_of,
                                              mu1=guaranteed.mu1), trace, x0, xi0, w, v, u_at)
    prot = closed_loop(acc, guaranteed, trace, x0, xi0, w, v, u_at)
    assert raw.spread == [np.inf] * N and len(prot.spread) == N and leveled.spread == prot.spread
    np.testing.assert_array_equal(prot.xhat, raw.xhat)
    np.testing.assert_array_equal(prot.x, raw.x)
    np.testing.assert_array_equal(leveled.xhat, raw.xhat)
    assert np.all(np.abs(prot.error[1:]).max(axis=1) <= prot.bound * (1 + 1e-9))
    # mu1 = 1 at the end of each period, plus the rounding allowance
    assert abs(prot.bound.max() - d.mu2) <= 1e-9 and 1.0 <= prot.bound[5] <= 1.0 + 1e-9


def test_a_shared_plant_run_gives_the_same_bits(acc, L1_words, rng):
    """closed_loop(plant=plant_run(...)): the true states and measurements simulated once for several estimators
    give each the run it gives without them, bit for bit; a plant run of another start, with an input, or of
    other noise is refused."""
    import pytest
    from eqrec.arrivals.draws import uniform_words, ArrivalTrace
    from eqrec.errors import InputError
    from eqrec.simulate.loop import closed_loop, plant_run

    d = design_prefix(acc, L1_words, 1.0)
    trace = ArrivalTrace.from_pattern("".join(uniform_words(rng, L1_words, size=4)))
    N = trace.steps
    w, v, x0, xi0 = _acc_run_data(acc, rng, N)
    plant = plant_run(acc, N, x0, w, v)
    for make in (lambda: d.estimator(), lambda: d.estimator(strict=False)):
        alone, shared = closed_loop(acc, make(), trace, x0, xi0, w, v), closed_loop(acc, make(), trace, x0, xi0, w,
                                                                                    v, plant=plant)
        for name in ("x", "xhat", "y"):
            np.testing.assert_array_equal(getattr(shared, name), getattr(alone, name))
        assert shared.spread == alone.spread and shared.x is not plant[0]  # copied: a run cannot change the plant's
    with pytest.raises(InputError) as exc:
        closed_loop(acc, d.estimator(), trace, x0 + 1.0, xi0, w, v, plant=plant)
    assert exc.value.field == "plant"
    with pytest.raises(InputError) as exc:
        closed_loop(acc, d.estimator(), trace, x0, xi0, w, v, lambda k, xh: np.ones(1), plant=plant)
    assert exc.value.field == "plant"
    for other in ((w[::-1].copy(), v), (w, v[::-1].copy())):  # another run's noise: its first or last step differs
        with pytest.raises(InputError, match="step") as exc:
            closed_loop(acc, d.estimator(), trace, x0, xi0, *other, plant=plant)
        assert exc.value.field == "plant"


def test_what_arrived_is_the_protocol_form():
    from eqrec.estimators.causal import Packet
    from eqrec.simulate.loop import what_arrived

    y = np.arange(8.0).reshape(4, 2)
    assert what_arrived([], 2, y) is None
    np.testing.assert_array_equal(what_arrived([2], 2, y), y[2])
    late = what_arrived([0, 2], 2, y, t0=10)
    assert [p.time for p in late] == [10, 12] and all(isinstance(p, Packet) for p in late)
    np.testing.assert_array_equal(late[0].y, y[0])


def test_closed_loop_refuses_short_or_non_finite_noise(acc, rng):
    import pytest
    from eqrec.simulate.loop import closed_loop
    from eqrec.errors import InputError

    class Never:  # fails the test if the loop steps it
        def reset(self, xhat0, t0=0):
            return self

        def step(self, y=None, u=None):
            raise AssertionError("stepped")

    w, v, x0, xi0 = _acc_run_data(acc, rng, 3)
    with pytest.raises(InputError) as exc:
        closed_loop(acc, Never(), [[0], [1], [2], [3]], x0, xi0, w, v)
    assert exc.value.field == "w"
    v[1, 0] = np.nan
    with pytest.raises(InputError) as exc:
        closed_loop(acc, Never(), [[0], [1], [2]], x0, xi0, w, v)
    assert exc.value.field == "v"


def test_closed_loop_refuses_a_bad_initial_state(acc, rng):
    import pytest
    from eqrec.simulate.loop import closed_loop
    from eqrec.errors import InputError

    w, v, x0, xi0 = _acc_run_data(acc, rng, 2)
    for bad_x0, bad_xi0, field in ((np.array([1.0, np.nan, 0.0]), xi0, "x0"), (x0, np.zeros(2), "xi0")):
        with pytest.raises(InputError) as exc:
            closed_loop(acc, object(), [[0], [1]], bad_x0, bad_xi0, w, v)
        assert exc.value.field == field


def test_importing_the_loop_and_the_table_steps_loads_no_numba():
    """The P2 and P3 steps import the loop at the top; the steps that run no estimator (their tables) must not
    pay for loading Numba (about 0.35 s of CPU a job): the causal estimators are imported where they run."""
    import subprocess
    import sys

    code = ("import sys, eqrec.simulate.loop, eqrec.studies.p2.steps, eqrec.studies.p3.steps; "
            "print('numba' in sys.modules); from eqrec.simulate.loop import simulate_run, Packet")
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.split() == ["False"], res.stdout
