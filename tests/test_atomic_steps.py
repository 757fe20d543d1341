"""Every call of a runtime estimator is all-or-nothing, and non-finite data is refused (issue 24, section 1).

For every error path: the estimator's whole state (pickled) is the same before and after the call that
raises, and a twin that never saw the bad call gives bit-identical estimates afterwards.
"""
import numpy as np
import pytest

from eqrec.estimators.causal import ClassEstimator, Packet, RecoveryEstimator
from eqrec.estimators.switching import SwitchingEstimator
from eqrec.systems.affine import AffineSystem
from eqrec.design.delay.design import design_delay_global
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InputError

LOSS = ["000", "300", "030", "003"]  # delay words: at most one packet of three lost


def state_of(obj, seen=None):
    """The whole state of an object as comparable bytes: arrays by dtype, shape and bytes; eqrec objects through
    their attributes (recursively); functions by identity."""
    seen = set() if seen is None else seen
    if isinstance(obj, np.ndarray):
        return ("array", obj.dtype.str, obj.shape, obj.tobytes())
    if isinstance(obj, (list, tuple)):
        return (type(obj).__name__, tuple(state_of(v, seen) for v in obj))
    if isinstance(obj, dict):
        return ("dict", tuple((repr(k), state_of(v, seen)) for k, v in obj.items()))
    if isinstance(obj, (set, frozenset)):
        return ("set", tuple(sorted(repr(v) for v in obj)))
    if callable(obj) and not hasattr(obj, "__dict__") or type(obj).__name__ in ("function", "method"):
        return ("callable", id(obj))
    if type(obj).__module__.startswith("eqrec"):
        if id(obj) in seen:
            return ("seen", id(obj))
        seen.add(id(obj))
        fields = vars(obj) if hasattr(obj, "__dict__") else {k: getattr(obj, k) for k in obj.__slots__}
        return (type(obj).__name__, tuple((k, state_of(v, seen)) for k, v in fields.items()))
    return ("value", repr(obj))


class pickle:  # the snapshot the tests compare (the estimators hold closures, which pickle refuses)
    dumps = staticmethod(state_of)


@pytest.fixture(scope="module")
def plant():
    return AffineSystem(A=np.array([[1.0, 0.1], [0.0, 1.0]]), B=np.array([[0.005], [0.1]]),
                        C=np.array([[1.0, 0.0]]), E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)


@pytest.fixture(scope="module")
def class_design(plant):
    return design_delay_global(plant, LOSS).design


@pytest.fixture(scope="module")
def node_design(acc, L1_words):
    return design_prefix(acc, L1_words, 1.0, engine="tree")


# (name, bad y, bad u): each must raise InputError at time 1 after y(0) arrived on time
BAD_CALLS = [
    ("y a string", "1.0", None),
    ("y wrong length", np.zeros(3), None),
    ("y NaN", np.array([np.nan]), None),
    ("y inf", np.array([np.inf]), None),
    ("y of a list", [[1.0], [2.0]], None),
    ("packet from the future", [(5, np.zeros(1))], None),
    ("stamp not an integer", [(1.5, np.zeros(1))], None),
    ("stamp a bool", [(True, np.zeros(1))], None),
    ("two packets one stamp", [(1, np.zeros(1)), (1, np.ones(1))], None),
    ("a stamp received before", [(0, np.zeros(1))], None),
    ("packet NaN", [Packet(1, np.array([np.nan]))], None),
    ("u NaN", np.zeros(1), np.array([np.nan])),
    ("u inf", np.zeros(1), np.array([np.inf])),
    ("u wrong length", np.zeros(1), np.zeros(3)),
    ("u a string", np.zeros(1), "0"),
    ("malformed packet", [("a", np.zeros(1))], None),
    # issue 41 census: data whose propagation overflows (an inf / NaN estimate and bound before)
    ("y overflows", np.array([1e308]), None),
    ("packet overflows", [Packet(1, np.array([1e200]))], None),
    ("u overflows", np.zeros(1), np.array([-1e300])),
]


def _good_steps(rng, k0, steps, p=1):
    """A sequence of (y, u) in the loss language starting at time k0 (period-aligned, one loss per period)."""
    out = []
    for k in range(k0, k0 + steps):
        y = None if k % 3 == 2 else rng.normal(size=p)
        out.append((y, rng.normal(size=1)))
    return out


def _check_atomic(make, bad_y, bad_u, good):
    est, twin = make(), make()
    est.step(np.array([0.3]), np.array([0.1]))
    twin.step(np.array([0.3]), np.array([0.1]))
    before = pickle.dumps(est)
    with pytest.raises(InputError):
        est.step(bad_y, bad_u)
    assert pickle.dumps(est) == before, "a call that raised changed the estimator"
    for y, u in good:
        a, b = est.step(y, u), twin.step(y, u)
        a, b = (a if isinstance(a, tuple) else (a,)), (b if isinstance(b, tuple) else (b,))
        for va, vb in zip(a, b):
            assert np.array_equal(np.asarray(va), np.asarray(vb))


@pytest.mark.parametrize("strict", [True, False])
@pytest.mark.parametrize("name,bad_y,bad_u", BAD_CALLS, ids=[c[0] for c in BAD_CALLS])
def test_guaranteed_estimator_steps_are_all_or_nothing(class_design, strict, name, bad_y, bad_u):
    good = _good_steps(np.random.default_rng(0), 1, 10)
    _check_atomic(lambda: class_design.estimator(strict=strict).reset(np.zeros(2)), bad_y, bad_u, good)


@pytest.mark.parametrize("name,bad_y,bad_u", BAD_CALLS, ids=[c[0] for c in BAD_CALLS])
def test_class_estimator_steps_are_all_or_nothing(plant, class_design, name, bad_y, bad_u):
    good = [(y, u) for y, u in _good_steps(np.random.default_rng(1), 1, 10)]
    _check_atomic(lambda: ClassEstimator(plant, class_design.class_gains, periodic=True).reset(np.zeros(2)), bad_y,
                  bad_u, good)


SWITCHING_BAD = [c for c in BAD_CALLS if c[0] != "a stamp received before"]  # stale in performance mode: dropped


@pytest.mark.parametrize("name,bad_y,bad_u", SWITCHING_BAD, ids=[c[0] for c in SWITCHING_BAD])
def test_switching_estimator_steps_are_all_or_nothing(name, bad_y, bad_u):
    """The switching strategy on the batch reactor (p = 2): the bad calls, widened to two outputs."""
    from eqrec.arrivals.words import full_delay_language
    from eqrec.design.delay.design import design_delay
    from eqrec.systems.examples import batch_reactor

    reactor = batch_reactor()
    perf = design_delay(reactor, ["0"], 0.36, kind="delay").schedule
    rec = design_delay(reactor, [w for w in full_delay_language(3, 1) if w[0] != "0"], 0.36, kind="delay").schedule
    widen = (lambda v: np.concatenate([v, v]) if isinstance(v, np.ndarray) and v.shape == (1,) else v)
    if isinstance(bad_y, list) and bad_y and isinstance(bad_y[0], tuple):
        bad_y = [(s, widen(v)) for s, v in bad_y]
    elif isinstance(bad_y, list) and bad_y and isinstance(bad_y[0], Packet):
        bad_y = [Packet(pk.time, widen(pk.y)) for pk in bad_y]
    else:
        bad_y = widen(bad_y)
    bad_u = None if bad_u is None else (np.zeros(5) if name == "u wrong length" else
                                        (np.concatenate([bad_u, bad_u]) if isinstance(bad_u, np.ndarray) else bad_u))
    good = [(None, np.zeros(2)), ([(1, np.full(2, 0.2)), (2, np.full(2, 0.1))], np.zeros(2)),
            (np.ones(2), np.ones(2)), (np.ones(2), None)]
    est, twin = (SwitchingEstimator(reactor, perf, rec).reset(np.zeros(4)) for _ in range(2))
    for e in (est, twin):
        e.step(np.full(2, 0.3), np.full(2, 0.1))
    before = state_of(est)
    with pytest.raises(InputError):
        est.step(bad_y, bad_u)
    assert state_of(est) == before
    for y, u in good:
        (xa, ba), (xb, bb) = est.step(y, u), twin.step(y, u)
        assert np.array_equal(xa, xb) and ba == bb
    assert (est.mode, est.switch_times, est.revert_times) == (twin.mode, twin.switch_times, twin.revert_times)


def test_the_outside_of_the_language_is_refused_atomically(class_design):
    """strict=True: a second loss in a period raises and changes nothing; the run then goes on."""
    est, twin = (class_design.estimator().reset(np.zeros(2)) for _ in range(2))
    for e in (est, twin):
        e.step(None)  # y(0) lost
    before = pickle.dumps(est)
    with pytest.raises(InputError, match="outside the design"):
        est.step(None)  # y(1) lost too: not in the language
    assert pickle.dumps(est) == before
    for y in (np.ones(1), np.zeros(1), None, np.ones(1)):
        assert np.array_equal(est.step(y)[0], twin.step(y)[0])


def test_a_refused_return_to_the_design_changes_nothing(class_design):
    """strict=False out of the design: at every step, and so at the period starts where the designed gains take over
    again, a bad input and a packet the set-membership window already holds (stamped before the new period, which the
    class form would drop) raise and change nothing, the spare class estimator included; a twin that never saw them
    gives the same numbers, over two departures from the design and two returns."""
    rng = np.random.default_rng(3)
    est, twin = (class_design.estimator(strict=False).reset(np.zeros(2)) for _ in range(2))
    arrivals = [True] * 4 + [False, False] + [True] * 10 + [False, False] + [True] * 10
    last, returns, checked = None, 0, 0
    for t, arrived in enumerate(arrivals):
        y = rng.normal(size=1) if arrived else None
        if not est.in_design:
            bad_calls = [(y, np.array([np.nan]))]
            if last is not None:  # the last packet that arrived, again
                bad_calls.append(([Packet(*last)] + ([Packet(t, y)] if arrived else []), None))
            for bad_y, bad_u in bad_calls:
                before = state_of(est)
                with pytest.raises(InputError):
                    est.step(bad_y, bad_u)
                assert state_of(est) == before, f"a refused step at time {t} changed the estimator"
                checked += 1
        was_in = est.in_design
        (xa, ba), (xb, bb) = est.step(y), twin.step(y)
        assert np.array_equal(xa, xb) and ba == bb
        assert np.array_equal(est.state_bounds, twin.state_bounds)
        returns += est.in_design and not was_in
        last = (t, y) if arrived else last
    assert returns == 2 and checked >= 4, (returns, checked)


def test_recovery_estimator_and_node_gains_refuse_atomically(acc, node_design):
    est, twin = (RecoveryEstimator(acc, node_design.schedule, periodic=True).reset(np.zeros(3)) for _ in range(2))
    for e in (est, twin):
        e.step(np.ones(2))
    for bad in (np.array([np.nan, 0.0]), np.zeros(3), "x", [(7, np.zeros(2))]):
        before = pickle.dumps(est)
        with pytest.raises(InputError):
            est.step(bad)
        assert pickle.dumps(est) == before
    with pytest.raises(InputError, match="strict=False needs class gains"):
        node_design.estimator(strict=False)
    for y in (np.ones(2), None, np.ones(2)):
        assert np.array_equal(est.step(y)[0], twin.step(y)[0])


@pytest.mark.parametrize("bad", [np.array([np.nan, 0.0]), np.array([0.0, np.inf]), np.zeros(3), "ab", None])
def test_reset_refuses_bad_initial_estimates_and_keeps_the_run(class_design, bad):
    est = class_design.estimator().reset(np.zeros(2))
    est.step(np.ones(1))
    before = pickle.dumps(est)
    with pytest.raises(InputError, match="xhat0"):
        est.reset(bad)
    assert pickle.dumps(est) == before
    with pytest.raises(InputError, match="t0"):
        est.reset(np.zeros(2), t0=1.5)
    assert pickle.dumps(est) == before


def test_a_horizon_that_is_over_is_refused_atomically(class_design):
    est = class_design.estimator(periodic=False).reset(np.zeros(2))
    for y in (np.ones(1), None, np.ones(1)):
        est.step(y)
    before = pickle.dumps(est)
    with pytest.raises(InputError, match="horizon"):
        est.step(np.ones(1))
    assert pickle.dumps(est) == before


@pytest.mark.parametrize("bad_y,bad_u", [
    (np.array([np.nan, 0.0]), None), ("12", None), (np.zeros(3), None), (np.zeros(2), np.array([np.inf])),
    (np.zeros(2), np.zeros(4)), ([(0, np.zeros(2))], None),
])
def test_augmented_estimator_steps_are_all_or_nothing(acc, bad_y, bad_u):
    """The state-augmented estimator (one word): every refused step leaves (x̂, s, the record) as they were."""
    from eqrec.design.augmented.model import AugmentedGains
    from eqrec.estimators.augmented import AugmentedEstimator, as_time_varying_L

    rng = np.random.default_rng(4)
    word, n, p = "110111", 3, 2
    M = np.zeros((6 * n, 6 * p))
    for k in range(6):
        for i in range(k + 1):
            if word[i] == "1":
                M[k * n:(k + 1) * n, i * p:(i + 1) * p] = rng.normal(size=(n, p)) * 0.3
    gains = AugmentedGains(word, as_time_varying_L(rng.normal(size=(n, p)) * 0.5, 6, n, p), rng.normal(size=n), M,
                           rng.normal(size=6 * n) * 0.1, "theorem2")
    est, twin = (AugmentedEstimator(acc, gains).reset(np.ones(3)) for _ in range(2))
    for e in (est, twin):
        e.step(np.array([0.5, 0.2]))
    before = state_of(est)
    with pytest.raises(InputError):
        est.step(bad_y, bad_u)
    assert state_of(est) == before
    for y in (None, np.array([0.1, 0.3]), np.array([0.0, 1.0])):
        assert np.array_equal(est.step(y)[0], twin.step(y)[0])
    with pytest.raises(InputError, match="xhat0"):
        AugmentedEstimator(acc, gains, np.array([np.nan, 0.0, 0.0]))
    before = state_of(est)
    with pytest.raises(InputError, match="xhat0"):
        est.reset(np.array([np.nan, 0.0, 0.0]))
    assert state_of(est) == before


def test_weighted_estimator_reset_and_steps_are_all_or_nothing(plant):
    design = design_delay_global(plant, LOSS, state_weights=[1.0, 4.0]).design
    est, twin = (design.estimator(strict=False).reset(np.zeros(2)) for _ in range(2))
    for e in (est, twin):
        e.step(np.array([0.3]))
    before = state_of(est)
    for bad in ((np.array([np.nan]),), ("x",)):
        with pytest.raises(InputError):
            est.step(*bad)
    with pytest.raises(InputError, match="xhat0"):
        est.reset("0.5")
    assert state_of(est) == before
    for y in (None, np.array([0.2]), None):
        a, b = est.step(y), twin.step(y)
        assert np.array_equal(a[0], b[0]) and a[1] == b[1]
    assert np.array_equal(est.error_box, twin.error_box)


# --- issue 41 census: every estimator refuses data whose propagation overflows, atomically ------------------------

def _overflow_estimators(plant, class_design):
    import eqrec
    from eqrec.estimators.kalman import TimestampedKalman
    from eqrec.systems.noise import GaussianDesign

    gauss = GaussianDesign.from_box(plant, 1.0)
    return {
        "zonotope": lambda: eqrec.ZonotopeEstimator(plant, x0_radius=0.5, max_delay=1),
        "exact set": lambda: eqrec.ExactSetEstimator(plant, x0_radius=0.5, max_delay=1),
        "kalman, exact bound": lambda: eqrec.exact_bound(TimestampedKalman(plant, gauss), plant, 0.5, steps=20),
        "guaranteed": lambda: class_design.estimator(),
        "class form": lambda: ClassEstimator(plant, class_design.class_gains, periodic=True),
    }


@pytest.mark.parametrize("kind", ["zonotope", "exact set", "kalman, exact bound", "guaranteed", "class form"])
@pytest.mark.parametrize("bad_y,bad_u", [(np.array([1e308]), None), (np.zeros(1), np.array([1e200]))],
                         ids=["y 1e308", "u 1e200"])
def test_overflowing_data_is_refused_by_every_estimator_atomically(plant, class_design, kind, bad_y, bad_u):
    make = _overflow_estimators(plant, class_design)[kind]
    est, twin = make().reset(np.zeros(2)), make().reset(np.zeros(2))
    est.step(np.array([0.3]), np.array([0.1]))
    twin.step(np.array([0.3]), np.array([0.1]))
    with pytest.raises(InputError) as exc:
        est.step(bad_y, bad_u)
    assert exc.value.field == ("y" if bad_u is None else "u")
    for y in (np.array([0.2]), None, np.array([0.1])):
        a, b = est.step(y, np.zeros(1)), twin.step(y, np.zeros(1))
        assert np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1]) and np.all(np.isfinite(a[0]))


@pytest.mark.parametrize("kind", ["zonotope", "exact set", "kalman, exact bound", "guaranteed", "class form"])
def test_an_initial_estimate_that_overflows_is_refused(plant, class_design, kind):
    est = _overflow_estimators(plant, class_design)[kind]()
    with pytest.raises(InputError) as exc:
        est.reset(np.full(2, 1e308))
    assert exc.value.field == "xhat0"
    x, bound = est.reset(np.full(2, 1e100)).step(np.array([0.0]))  # large but in scale: finite
    assert np.all(np.isfinite(x)) and (np.isfinite(bound) or kind == "class form")  # no levels: bound inf
