"""The speed paths of exact_bound's column runs (issue 40 §3) change no number and refuse what was refused:
the scale check of the columns, the marked-as-checked packets, the LMV filter's step matrices made once and
reused by one estimator over several runs."""
import numpy as np
import pytest

from eqrec.arrivals.packets import MAX_DATA_MAGNITUDE, as_packets, checked_columns, in_scale_array, plain_vector
from eqrec.compare.families import _gaussian, _lmv
from eqrec.errors import InputError
from eqrec.estimators.exact import exact_bound
from eqrec.estimators.kalman import DelayUnawareKalman
from eqrec.systems.examples import acc_system


@pytest.mark.parametrize("value, ok", [(np.array([[1.0, -2.0], [0.0, 3.0]]), True), (np.zeros((2, 0)), True),
                                       (np.array([1.0, np.nan]), False), (np.array([1.0, -np.inf]), False),
                                       (np.array([MAX_DATA_MAGNITUDE, -MAX_DATA_MAGNITUDE]), True),
                                       (np.array([2 * MAX_DATA_MAGNITUDE]), False), (np.array([1, 2]), False)])
def test_in_scale_array_is_what_the_reader_accepts(value, ok):
    assert in_scale_array(value) is ok


def test_checked_columns_are_returned_as_they_are_for_their_time_and_shape():
    Y = np.arange(6.0).reshape(2, 3)
    cols = checked_columns([(4, Y)], 5, (2, 3))
    assert as_packets(cols, 5, (2, 3)) is cols and cols[0].y is Y
    again = as_packets(cols, 6, (2, 3))  # another time: read again (a new array)
    assert again is not cols and np.array_equal(again[0].y, Y) and again[0].y is not Y


@pytest.mark.parametrize("value", [np.array([1.0, 2.0]), np.array([1.0, 2.0, 3.0]), [1.0, 2.0], np.array([1, 2]),
                                   np.array([1.0, np.inf]), np.array([[1.0, 2.0]])])
def test_plain_vector_takes_a_flat_float_vector_in_scale_only(value):
    got = plain_vector(value, (2,))
    if isinstance(value, np.ndarray) and value.dtype == np.float64 and value.shape == (2,) and np.isfinite(value).all():
        assert got is not None and got is not value and np.array_equal(got, value)
    else:
        assert got is None


def test_an_out_of_scale_measurement_is_refused_and_changes_nothing():
    acc = acc_system()
    g = _gaussian(acc, None, 0.5, 5.0)
    est = exact_bound(DelayUnawareKalman(acc, g.design(acc)), acc, 0.5, steps=4).reset(np.zeros(3))
    est.step(np.array([0.1, 0.2]))
    before = (est.x.copy(), est.state_bounds.copy(), est.time)
    with pytest.raises(InputError):
        est.step(np.array([0.1, 1e200]))
    assert np.array_equal(est.x, before[0]) and np.array_equal(est.state_bounds, before[1]) and est.time == before[2]


def _run(est, ys):
    est.reset(np.zeros(3))
    out = []
    for y in ys:
        xhat, bound = est.step(y)
        out.append(np.concatenate([xhat, [bound], est.state_bounds]))
    return np.array(out)


@pytest.mark.parametrize("mechanism", ["zero-input", "hold-input"])
def test_one_lmv_estimator_over_several_runs_gives_the_numbers_of_fresh_ones(mechanism):
    acc = acc_system()
    steps = 12
    g = _gaussian(acc, None, 0.5, 5.0)
    make = _lmv(acc, g, mechanism, 0.45, steps)  # one estimator, reused (its step matrices made once)
    rng = np.random.default_rng(3)
    runs = [[None if rng.random() < 0.3 else rng.uniform(-0.2, 0.2, 2) for _ in range(steps)] for _ in range(3)]
    reused = [_run(exact_bound(make(), acc, 0.5, steps=steps), ys) for ys in runs]
    fresh = [_run(exact_bound(_lmv(acc, g, mechanism, 0.45, steps)(), acc, 0.5, steps=steps), ys) for ys in runs]
    for a, b in zip(reused, fresh):
        assert a.tobytes() == b.tobytes()
