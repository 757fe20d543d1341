"""One protocol in fact (issue 32, section 2, last point): every estimator runs as ``reset`` then ``step``.

Every family, the raw causal estimators included (class form, node gains, switching, augmented), is an
:class:`eqrec.estimators.protocol.Estimator` once reset, ``reset`` returns the estimator and ``step`` returns
``(x̂, bound)`` (a float; ``inf`` for a raw estimator built without its design's levels, the levels when built
with them) or ``(x̂, covariance)``; :func:`eqrec.simulate.loop.closed_loop` runs them all one way.
"""
from __future__ import annotations

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.draws import ArrivalTrace
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import full_delay_language
from eqrec.design.augmented.model import AugmentedGains
from eqrec.design.augmented.runtime import prefix_to_augmented, schedule_from_augmented
from eqrec.design.delay.design import design_delay, design_delay_global
from eqrec.design.observers import place_observer
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InputError
from eqrec.estimators.augmented import AugmentedEstimator
from eqrec.estimators.causal import ClassEstimator, RecoveryEstimator, make_estimator
from eqrec.estimators.intake import StampedEstimator
from eqrec.estimators.kalman import make_filter
from eqrec.estimators.protocol import Estimator, OnTimeOnly
from eqrec.estimators.switching import SwitchingEstimator
from eqrec.simulate.long_runs import long_run_switching
from eqrec.simulate.loop import closed_loop
from eqrec.systems.affine import AffineSystem
from eqrec.systems.noise import GaussianNoise
from test_atomic_steps import state_of

PLANT = AffineSystem(A=[[0.9, 0.2], [-0.1, 0.7]], B=[[0.0], [1.0]], C=[[1.0, 0.5]], E=[[0.0], [1.0]], eta_w=0.5,
                     eta_v=0.2)
LOSS = ["000", "300", "030", "003"]  # delay words: at most one packet of three lost
MISSING = ["1111", "0111", "1011", "1101", "1110"]  # 0/1 words: at most one packet of four lost
MU1 = 3.0


@pytest.fixture(scope="module")
def designs():
    classes = design_delay_global(PLANT, LOSS).design
    node = design_prefix(PLANT, MISSING, "free", engine="tree")
    perf = design_delay(PLANT, ["0"], MU1, kind="delay")
    rec = design_delay(PLANT, [w for w in full_delay_language(3, 1) if w[0] != "0"], MU1, kind="delay")
    return classes, node, perf, rec


def _word_gains(rng, word="1101"):
    """One word's augmented gains, drawn (block lower triangular ``M``, zero columns where the word lacks y)."""
    n, p, T = 2, 1, len(word)
    M = np.zeros((T * n, T * p))
    for k in range(T):
        for i in range(k + 1):
            if word[i] == "1":
                M[k * n:(k + 1) * n, i * p:(i + 1) * p] = rng.normal(size=(n, p)) * 0.3
    return AugmentedGains(word, rng.normal(size=(n, p)) * 0.5, rng.normal(size=n), M, rng.normal(size=T * n) * 0.1)


@pytest.fixture(scope="module")
def families(designs):
    """Every family, not yet reset: name -> maker."""
    classes, node, perf, rec = designs
    rng = np.random.default_rng(0)
    word = _word_gains(rng)
    L = place_observer(PLANT.A, PLANT.C, [0.1, 0.2]).L
    prefix = prefix_to_augmented(PLANT, PrefixTree(MISSING, kind="missing"), node.schedule, L, np.array([0.1, -0.2]))
    kalman = GaussianNoise.from_box(PLANT, mu1=1.0).design(PLANT)
    return {
        "ClassEstimator": lambda: ClassEstimator(PLANT, classes.class_gains, periodic=True),
        "RecoveryEstimator": lambda: RecoveryEstimator(PLANT, node.schedule, periodic=True),
        "make_estimator": lambda: make_estimator(PLANT, classes.class_gains, periodic=True),
        "SwitchingEstimator": lambda: SwitchingEstimator(PLANT, perf.schedule, rec.schedule),
        "AugmentedEstimator, one word": lambda: AugmentedEstimator(PLANT, word),
        "AugmentedEstimator, prefix gains": lambda: AugmentedEstimator(PLANT, prefix),
        "GuaranteedEstimator": lambda: classes.estimator(),
        "GuaranteedEstimator, strict=False": lambda: classes.estimator(strict=False),
        "ZonotopeEstimator": lambda: eqrec.ZonotopeEstimator(PLANT, x0_radius=1.0, max_delay=2),
        "exact_bound": lambda: eqrec.exact_bound(ClassEstimator(PLANT, classes.class_gains, periodic=True), PLANT, 1.0),
        "Kalman, time-stamped": lambda: make_filter("timestamped", PLANT, kalman),
        "OnTimeOnly": lambda: OnTimeOnly(make_filter("unaware", PLANT, kalman), 1),
    }


RAW = ("ClassEstimator", "RecoveryEstimator", "make_estimator", "SwitchingEstimator", "AugmentedEstimator, one word",
       "AugmentedEstimator, prefix gains")
FAMILIES = RAW + ("GuaranteedEstimator", "GuaranteedEstimator, strict=False", "ZonotopeEstimator", "exact_bound",
                  "Kalman, time-stamped", "OnTimeOnly")


def test_the_list_is_the_fixture(families):
    assert sorted(FAMILIES) == sorted(families)


@pytest.mark.parametrize("name", FAMILIES)
def test_every_family_follows_the_protocol(families, name):
    """reset returns the estimator, which is then an Estimator; step returns (x̂, bound) or (x̂, covariance)."""
    est = families[name]()
    assert est.reset(np.array([0.1, -0.2]), 5) is est
    assert isinstance(est, Estimator)
    assert est.kind in ("guaranteed", "stochastic") and isinstance(est.name, str) and est.name
    assert est.time == 5 and np.array_equal(est.x, [0.1, -0.2])
    for y in (np.array([0.3]), [(6, np.array([0.2]))], np.array([-0.1])):  # on time, on time as a packet, on time
        xhat, spread = est.step(y, np.array([0.1]))
        assert isinstance(xhat, np.ndarray) and xhat.shape == (2,) and np.all(np.isfinite(xhat))
        if est.kind == "guaranteed":
            assert isinstance(spread, (float, np.floating)) and not np.isnan(spread)
            assert spread == np.inf if name in RAW else np.isfinite(spread)  # raw without levels: no bound
        else:
            assert isinstance(spread, np.ndarray) and spread.shape == (2, 2) and np.all(np.isfinite(spread))
    assert est.time == 8
    again = est.reset(np.zeros(2))  # reset starts a new run
    assert again is est and est.time == 0 and np.array_equal(est.x, np.zeros(2))


@pytest.mark.parametrize("name", RAW)
def test_raw_estimators_refuse_a_step_before_reset_and_a_bad_reset_changes_nothing(families, name):
    est = families[name]()
    with pytest.raises(InputError, match="reset"):
        est.step(np.array([0.3]))
    est.reset(np.zeros(2), 5)
    est.step(np.array([0.3]))
    before = state_of(est)
    for bad, field in (((np.array([np.nan, 0.0]),), "xhat0"), ((np.zeros(3),), "xhat0"), ((np.zeros(2), 1.5), "t0")):
        with pytest.raises(InputError) as exc:
            est.reset(*bad)
        assert exc.value.field == field
        assert state_of(est) == before
    twin = families[name]().reset(np.zeros(2), 5)  # the compatible constructor form gives the same run
    twin.step(np.array([0.3]))
    assert np.array_equal(est.step(None)[0], twin.step(None)[0])


def test_the_constructor_still_takes_the_initial_estimate(designs):
    classes, node, perf, rec = designs
    y1, y2 = np.array([0.2]), np.array([0.1])
    for a, b, ys in ((ClassEstimator(PLANT, classes.class_gains, np.ones(2), periodic=True, t0=3),
                      ClassEstimator(PLANT, classes.class_gains, periodic=True).reset(np.ones(2), 3),
                      (y1, [(4, y2)], y1, None, y2)),  # a loss in the second period
                     (SwitchingEstimator(PLANT, perf.schedule, rec.schedule, np.ones(2), t0=3),
                      SwitchingEstimator(PLANT, perf.schedule, rec.schedule).reset(np.ones(2), 3),
                      (y1, [(4, y2)], None, [(5, y1), (6, y2)], y1))):  # y(5) one step late: a recovery phase
        for y in ys:
            (xa, ba), (xb, bb) = a.step(y), b.step(y)
            assert np.array_equal(xa, xb) and ba == bb == np.inf


# ---------------------------------------------------------------------------------------------- the second value

def test_with_the_levels_the_raw_estimators_return_the_guaranteed_estimators_bound(designs):
    """Built with the design's levels, ClassEstimator and RecoveryEstimator return exactly what
    GuaranteedEstimator (strict) returns: the level of the observed prefix or class, μ1 at period ends, each plus the
    rounding allowance."""
    classes, node, _, _ = designs
    rng = np.random.default_rng(3)
    for design, gains in ((classes, classes.class_gains), (node, node.schedule)):
        guaranteed = design.estimator().reset(np.zeros(2))
        raw = make_estimator(PLANT, gains, periodic=True, bound_of=guaranteed.bound_of, mu1=guaranteed.mu1)
        assert raw.reset(np.zeros(2)).bound == guaranteed.bound == design.mu1
        T = gains.horizon
        for k in range(6 * T):
            y = None if k % T == 1 else rng.normal(size=1)  # one loss per period: in both languages
            (xa, ba), (xb, bb) = raw.step(y), guaranteed.step(y)
            assert np.array_equal(xa, xb) and ba == bb and np.isfinite(ba)
            # the level plus the rounding allowance (eqrec.estimators.intake), rounded up
            assert ba == np.nextafter(raw._level() + raw.rounding, np.inf) and ba - raw._level() < 1e-12
            assert (raw._level() == design.mu1) == ((k + 1) % T == 0)


def test_levels_are_both_or_neither(designs):
    classes = designs[0]
    rule = classes.estimator().bound_of
    for kw, field in (({"bound_of": rule}, "mu1"), ({"mu1": 1.0}, "bound_of"), ({"bound_of": 1.0, "mu1": 1.0},
                                                                                  "bound_of"),
                      ({"bound_of": rule, "mu1": np.inf}, "mu1"), ({"bound_of": rule, "mu1": -1.0}, "mu1")):
        with pytest.raises(InputError) as exc:
            ClassEstimator(PLANT, classes.class_gains, **kw)
        assert exc.value.field == field


def test_switching_with_the_levels_returns_the_long_runs_guarantee(designs):
    """The switching estimator's bound is the per-time guarantee long_run_switching records (μ1 in performance
    mode and at each recovery phase's end, the recovery level in between), and it holds."""
    _, _, perf, rec = designs
    rule = rec.estimator().bound_of
    r = long_run_switching(PLANT, perf.schedule, rec.schedule, 400, np.random.default_rng(4), mu1=MU1,
                           recovery_level=rule, max_delay=1, p_on_time=0.7)
    assert len(r.switch_times) > 10
    est = SwitchingEstimator(PLANT, perf.schedule, rec.schedule, bound_of=rule, mu1=MU1)
    run = closed_loop(PLANT, est, ArrivalTrace(r.delays), r.x[0], r.x[0] - r.xhat[0], r.w, r.v)
    # the level plus the rounding allowance (eqrec.estimators.intake): never below it, a relative 1e-9 at most
    assert np.all(run.bound >= r.level[1:]) and np.allclose(run.bound, r.level[1:], rtol=1e-9, atol=0)
    # ξ0 is recomputed as x(0) − x̂(0), which may differ from the drawn one in the last bit: hence the tolerance
    np.testing.assert_allclose(run.xhat, r.xhat, rtol=0, atol=1e-12)
    # the designs' levels are LP optima (certified to the solver's tolerance, tests/test_p3_strategy.py): 1e-9
    assert np.all(np.abs(run.error[1:]).max(axis=1) <= run.bound * (1 + 1e-9))
    assert est.switch_times == r.switch_times and est.dropped_packets == len(r.dropped)


def test_augmented_with_levels_reports_them_along_the_observed_prefix(designs):
    seen = []

    def rule(prefix):
        seen.append(prefix.label)
        return 0.5 + len(seen)

    est = AugmentedEstimator(PLANT, _word_gains(np.random.default_rng(1)), bound_of=rule, mu1=2.0)
    assert est.reset(np.zeros(2)).bound == 2.0
    bounds = [est.step(y)[1] for y in (np.array([0.1]), np.array([0.2]), None, np.array([0.3]))]
    levels = [1.5, 2.5, 3.5, 2.0]  # μ1 at the horizon's end; each plus the rounding allowance
    assert all(b >= lv for b, lv in zip(bounds, levels)) and np.allclose(bounds, levels, rtol=1e-9, atol=0)
    assert seen == ["1", "11", "110"]


# ---------------------------------------------------------------------------------------------- the moved estimator

def test_the_augmented_estimator_lives_in_estimators_on_the_shared_intake(designs):
    import eqrec.design.augmented.model as model
    import eqrec.design.augmented.runtime as runtime
    import eqrec.estimators.augmented as moved

    assert not hasattr(runtime, "AugmentedEstimator")
    assert issubclass(AugmentedEstimator, StampedEstimator)
    assert (model.RUNTIME_MODES, model.as_time_varying_L, model.default_runtime) == (
        moved.RUNTIME_MODES, moved.as_time_varying_L, moved.default_runtime)  # re-exported, one definition
    # the converted time-based estimator: the same affine map computed in another order, so equal to rounding
    gains = _word_gains(np.random.default_rng(2))
    ref = RecoveryEstimator(PLANT, schedule_from_augmented(PLANT, gains)).reset(np.ones(2))
    est = AugmentedEstimator(PLANT, gains).reset(np.ones(2))
    for y in (np.array([0.1]), np.array([0.2]), None, np.array([0.3])):
        np.testing.assert_allclose(est.step(y)[0], ref.step(y)[0], rtol=0, atol=1e-12)
    with pytest.raises(InputError, match="horizon"):
        est.step(None)
    with pytest.raises(InputError) as exc:
        AugmentedEstimator(PLANT, object())
    assert exc.value.field == "gains"


def test_the_augmented_prefix_estimator_drops_packets_of_before_its_start_like_the_others(designs):
    _, node, _, _ = designs
    L = place_observer(PLANT.A, PLANT.C, [0.1, 0.2]).L
    gains = prefix_to_augmented(PLANT, PrefixTree(MISSING, kind="missing"), node.schedule, L, np.zeros(2))
    a = AugmentedEstimator(PLANT, gains).reset(np.zeros(2), t0=10)
    b = AugmentedEstimator(PLANT, gains).reset(np.zeros(2), t0=10)
    xa, _ = a.step([(9, np.array([5.0])), (10, np.array([0.1]))])  # y(9): before the run started
    xb, _ = b.step(np.array([0.1]))
    assert np.array_equal(xa, xb) and (a.dropped_packets, b.dropped_packets) == (1, 0)


# ---------------------------------------------------------------------------------------------- one loop

class Spy:
    """A protocol estimator recording how the loop drives it."""

    kind, name = "guaranteed", "spy"

    def __init__(self):
        self.calls = []
        self._x, self._t = None, 0

    def reset(self, xhat0, t0=0):
        self.calls.append(("reset", np.array(xhat0), t0))
        self._x, self._t = np.array(xhat0, float), t0
        return self

    def step(self, y=None, u=None):
        self.calls.append(("step", y))
        self._t += 1
        return self._x.copy(), 7.0

    time = property(lambda self: self._t)
    x = property(lambda self: self._x.copy())


def test_closed_loop_resets_and_steps_every_estimator_the_same_way(designs):
    classes = designs[0]
    N, rng = 9, np.random.default_rng(5)
    w, v = rng.uniform(-0.5, 0.5, (N, 1)), rng.uniform(-0.2, 0.2, (N, 1))
    trace = ArrivalTrace.from_pattern("011" * 3)
    x0, xi0 = np.array([1.0, -1.0]), np.array([0.5, 0.25])
    spy = Spy()
    run = closed_loop(PLANT, spy, trace, x0, xi0, w, v, t0=4)
    assert [c[0] for c in spy.calls] == ["reset"] + ["step"] * N
    assert np.array_equal(spy.calls[0][1], x0 - xi0) and spy.calls[0][2] == 4
    assert run.spread == [7.0] * N
    # a raw estimator started elsewhere is restarted by the loop at x0 − ξ0: the run of a fresh one
    started = ClassEstimator(PLANT, classes.class_gains, np.full(2, 9.0), periodic=True)
    a = closed_loop(PLANT, started, trace, x0, xi0, w, v)
    b = closed_loop(PLANT, ClassEstimator(PLANT, classes.class_gains, periodic=True), trace, x0, xi0, w, v)
    np.testing.assert_array_equal(a.xhat, b.xhat)
    assert a.spread == b.spread == [np.inf] * N
    with pytest.raises(InputError) as exc:  # no reset: not an estimator of the protocol
        closed_loop(PLANT, type("StepOnly", (), {"step": lambda self, y, u: None})(), trace, x0, xi0, w, v)
    assert exc.value.field == "est" and "reset" in str(exc.value)


NO_MAPS = ("RecoveryEstimator", "SwitchingEstimator", "AugmentedEstimator, one word",
           "AugmentedEstimator, prefix gains")


@pytest.mark.parametrize("name", NO_MAPS)
def test_exact_bound_runs_copies_of_an_estimator_without_error_maps(families, name):
    """Issue 32 §2: the node-gain, switching and augmented estimators get their exact worst case too
    (``exact_bound`` runs copies of them on the columns of the uncertainty): it equals the worst case read from
    unit perturbations of closed-loop runs (up to the rounding allowances, 1e-7), the estimates are the estimator's own, and the worst-case
    noise of the last step played back reaches the bound and stays inside it."""
    N, r0, n = (4 if name.startswith("Augmented") else 8), 0.3, PLANT.n  # the augmented ones run one horizon
    trace = ArrivalTrace([0] * N)  # every packet on time: in every design's language
    xhat0 = np.array([0.1, -0.2])
    wrapped = eqrec.exact_bound(families[name](), PLANT, r0, steps=N)
    assert wrapped.mode == "copies"
    out = closed_loop(PLANT, wrapped, trace, xhat0, np.zeros(n), np.zeros((N, PLANT.nw)), np.zeros((N, PLANT.nv)))
    plain = closed_loop(PLANT, families[name](), trace, xhat0, np.zeros(n), np.zeros((N, PLANT.nw)),
                        np.zeros((N, PLANT.nv)))
    assert np.array_equal(out.xhat, plain.xhat)  # copy 0 is the estimator itself
    D = n + N * (PLANT.nw + PLANT.nv)
    r = np.concatenate([np.full(n, r0), np.full(N * PLANT.nw, PLANT.eta_w), np.full(N * PLANT.nv, PLANT.eta_v)])

    def error(delta, make):
        xi0, w, v = delta[:n], delta[n:n + N * PLANT.nw].reshape(N, -1), delta[n + N * PLANT.nw:].reshape(N, -1)
        run = closed_loop(PLANT, make(), trace, xhat0 + xi0, xi0, w, v)
        return run.error[1:], np.array(run.spread)

    c, _ = error(np.zeros(D), families[name])
    G = np.stack([error(r * np.eye(D)[j], families[name])[0] - c for j in range(D)], axis=-1)
    worst = (np.abs(c) + np.abs(G).sum(axis=-1)).max(axis=1)
    # at least the worst case, and above it by the rounding allowances only (every copy's: a priori for the augmented)
    assert np.all(np.array(out.spread) >= worst) and np.allclose(np.array(out.spread), worst, rtol=1e-7, atol=0)
    i = int(np.argmax(np.abs(c[-1]) + np.abs(G[-1]).sum(axis=-1)))  # the worst state (c: a biased estimator)
    side = 1.0 if c[-1, i] >= 0 else -1.0
    err, bound = error(side * np.sign(G[-1, i]) * r, lambda: eqrec.exact_bound(families[name](), PLANT, r0, steps=N))
    assert np.all(np.abs(err).max(axis=1) <= bound * (1 + 1e-12))
    assert np.abs(err[-1]).max() >= bound[-1] * (1 - 1e-7)  # attained, up to the rounding allowance
