"""The class-form estimator (:class:`eqrec.estimators.causal.ClassEstimator`) at run time.

x̂(d) = x̄(d) + K_(d,S) (y_S − ȳ_S) must give the same estimates as the node gains derived from the
same K (:func:`eqrec.design.classes.engine.node_schedule`), attain every class level at a worst-case vertex,
and run periodically and in the switching scheme exactly as the schedule does.
"""
import math
from dataclasses import replace
from functools import partial

import numpy as np
import pytest
import scipy.linalg as sla

from eqrec.bounds.data_classes import ClassGains, class_maps, classes_of_tree
from eqrec.estimators.causal import ClassEstimator, Packet, RecoveryEstimator, make_estimator
from eqrec.estimators.switching import SwitchingEstimator
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import parse_delay_word
from eqrec.lp.robust import worst_case_vertex
from eqrec.simulate.long_runs import class_closed_loop_maps, long_run_periodic, long_run_switching, periodic_model_gap
from eqrec.simulate.loop import monte_carlo, simulate_run
from eqrec.bounds.stacking import Stacking, UncertaintyLayout
from eqrec.systems.affine import AffineSystem
from eqrec.design.delay.design import delay_classes, delay_language, design_delay, min_recovery_level
from eqrec.design.report import node_level, path_levels
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InputError
from eqrec.systems.examples import batch_reactor

ATOL = 1e-9
RTOL = 1e-9


# --------------------------------------------------------------------------- the three designs

@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


@pytest.fixture(scope="module")
def random_system():
    """Seeded: 4 states, 2 outputs, process noise through 2 channels, unstable A (spectral radius 1.15)."""
    rng = np.random.default_rng(7)
    n, p = 4, 2
    A = rng.normal(size=(n, n))
    A *= 1.15 / np.abs(np.linalg.eigvals(A)).max()
    return AffineSystem(A=A, C=rng.normal(size=(p, n)), E=0.5 * rng.normal(size=(n, 2)), eta_w=0.05, eta_v=0.1,
                        B=rng.normal(size=(n, 1)), f=rng.normal(size=n), name="random")


@pytest.fixture(scope="module")
def cases(acc, L1_words, reactor, random_system):
    """name -> (system to simulate, design, mu1).  The reactor is simulated with a nonzero ``f`` (it does not
    enter the error, so the design holds)."""
    out = {"acc_L1": (acc, design_prefix(acc, L1_words, 1.0), 1.0)}
    d = design_delay(reactor, delay_language(max_delay=2, horizon=4), 0.5, cost="sum")
    out["reactor_delay"] = (replace(reactor, f=np.array([0.3, -0.2, 0.1, 0.5])), d, 0.5)
    words = delay_language(max_delay=1, horizon=5)
    mu1 = min_recovery_level(random_system, words).upper * 1.5
    out["random"] = (random_system, design_delay(random_system, words, mu1, cost="sum"), mu1)
    return out


CASES = ["acc_L1", "reactor_delay", "random"]


def _inputs(system, T, rng):
    return rng.normal(size=(T, system.m)) * 10.0


def _class_of_pattern(design, pattern, d):
    return design.class_gains.classes.index(d, pattern.available(d - 1))


# --------------------------------------------------------------------------- same estimates as the node gains

@pytest.mark.parametrize("name", CASES)
def test_class_form_gives_the_node_gains_estimates(cases, name):
    system, design, mu1 = cases[name]
    assert design.schedule is not None and isinstance(design.class_gains, ClassGains)
    assert np.any(system.f != 0) and system.m > 0
    rng = np.random.default_rng(11)
    T = design.T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    radius = lay.radius(system.eta_w, system.eta_v, mu1)
    for pat in design.patterns:
        for _ in range(3):
            delta = rng.uniform(-1, 1, lay.size) * radius
            x0 = rng.normal(size=system.n) * 5.0
            u = _inputs(system, T, rng)
            a = simulate_run(system, design.schedule, pat, delta, x0, u)
            b = simulate_run(system, design.class_gains, pat, delta, x0, u)
            np.testing.assert_array_equal(a.x, b.x)
            np.testing.assert_allclose(b.xhat, a.xhat, rtol=0, atol=ATOL)
            # and exactly the class maps (E_d - K Z_S) δ
            G, c, _ = class_closed_loop_maps(system, design.class_gains, pat)
            np.testing.assert_allclose(b.error, np.einsum("tnd,d->tn", G, delta) + c, rtol=0, atol=ATOL)


@pytest.mark.parametrize("name", CASES)
def test_stepwise_state_matches_the_recovery_estimator(cases, name):
    """Same observed prefix, clocks and estimates step by step, with late packets and explicit stamps."""
    system, design, mu1 = cases[name]
    rng = np.random.default_rng(5)
    for pat in design.patterns[:10]:
        x0 = rng.normal(size=system.n)
        a = RecoveryEstimator(system, design.schedule).reset(x0, t0=7)
        b = ClassEstimator(system, design.class_gains).reset(x0, t0=7)
        ys = rng.normal(size=(pat.T, system.p))
        for t in range(pat.T):
            packets = [Packet(7 + tau, ys[tau]) for tau in pat.arriving_at(t)]
            u = rng.normal(size=system.m)
            (xb, bound_b), (xa, bound_a) = b.step(packets, u), a.step(packets, u)
            np.testing.assert_allclose(xb, xa, rtol=0, atol=1e-8)
            assert bound_a == bound_b == np.inf  # built without the design's levels: no bound
            assert b.observed_prefix == a.observed_prefix
            assert (b.time, b.period_time, b.period_start) == (a.time, a.period_time, a.period_start)


# --------------------------------------------------------------------------- worst-case vertices attain the levels

def _word_through_each_class(design):
    """class index -> a designed pattern whose prefix of the class's depth is in that class."""
    classes = design.class_gains.classes
    out = {}
    for pat in design.patterns:
        for d in range(1, pat.T + 1):
            out.setdefault(_class_of_pattern(design, pat, d), pat)
    assert sorted(out) == list(range(len(classes)))
    return out


@pytest.mark.parametrize("name", CASES)
def test_worst_case_vertex_attains_each_class_level(cases, name):
    system, design, mu1 = cases[name]
    gains, cert = design.class_gains, design.class_certificate
    classes = gains.classes
    st = Stacking(system, design.T)
    radius = st.layout.radius(system.eta_w, system.eta_v, mu1)
    rng = np.random.default_rng(2)
    x0 = rng.normal(size=system.n)
    u = _inputs(system, design.T, rng)
    for i, pat in _word_through_each_class(design).items():
        cls = classes.classes[i]
        d = cls.depth
        E, Z = class_maps(st, cls)
        M = E - gains.K[i] @ Z
        r = int(np.argmax(cert.bounds[i]))
        bound = float(np.abs(M[r]) @ radius)
        assert bound == pytest.approx(cert.bounds[i, r], rel=RTOL) and bound == pytest.approx(cert.levels[i], rel=RTOL)
        if cls.terminal:
            assert bound <= mu1 * (1 + 1e-6)
        if cls.inner:
            assert bound <= design.mu2 * (1 + 1e-6)
        delta = worst_case_vertex(M[r], 0.0, radius)
        tr = simulate_run(system, gains, pat, delta, x0, u)
        assert abs(tr.error[d, r]) == pytest.approx(cert.bounds[i, r], rel=RTOL), (cls.label, r)
        # the node gains reach it too (same estimator)
        tr_s = simulate_run(system, design.schedule, pat, delta, x0, u)
        assert abs(tr_s.error[d, r]) == pytest.approx(cert.bounds[i, r], rel=RTOL)


@pytest.mark.parametrize("name", CASES)
def test_random_box_draws_stay_within_the_class_levels(cases, name):
    system, design, mu1 = cases[name]
    cert = design.class_certificate
    words = list(design.patterns)
    for kind in ("uniform", "vertex"):
        errs, used = monte_carlo(system, design.class_gains, words, mu1, 60, seed=4, kind=kind,
                                 x0=np.ones(system.n), inputs=np.ones((design.T, system.m)))
        for e, w in zip(errs, used):
            pat = next(p for p in words if p.label == w)
            assert np.all(np.abs(e[0]) <= mu1 + 1e-12)
            for d in range(1, design.T + 1):
                i = _class_of_pattern(design, pat, d)
                assert np.all(np.abs(e[d]) <= cert.bounds[i] * (1 + RTOL) + 1e-12)
            assert np.abs(e[-1]).max() <= mu1 * (1 + 1e-6)


def test_window_rule_classes_run_without_a_prefix_tree(reactor):
    """The full language from the window rule: no tree, no node gains, still an estimator."""
    d = design_delay(reactor, delay_classes(max_delay=2, horizon=4), 0.5)
    assert d.schedule is None and d.class_gains.classes.tree is None
    cert = d.class_certificate
    rng = np.random.default_rng(8)
    lay = UncertaintyLayout(4, reactor.nw, reactor.nv, reactor.n)
    radius = lay.radius(reactor.eta_w, reactor.eta_v, 0.5)
    for word in ("0000", "2222", "1021", "0120", "2001"):
        pat = parse_delay_word(word)
        for _ in range(5):
            delta = rng.choice([-1.0, 1.0], lay.size) * radius
            e = simulate_run(reactor, d.class_gains, pat, delta, np.ones(4)).error
            for t in range(1, 5):
                i = d.class_gains.classes.index(t, pat.available(t - 1))
                assert np.all(np.abs(e[t]) <= cert.bounds[i] * (1 + RTOL) + 1e-12)


# --------------------------------------------------------------------------- periodic reuse

def _lqr(system):
    P = sla.solve_discrete_are(system.A, system.B, np.eye(system.n), np.eye(system.m))
    return np.linalg.solve(np.eye(system.m) + system.B.T @ P @ system.B, system.B.T @ P @ system.A)


def test_periodic_reuse_matches_the_schedule_and_stays_within_the_levels(cases, reactor):
    system, design, mu1 = cases["reactor_delay"]
    words = [p.label for p in design.patterns]
    K = _lqr(reactor)
    T = design.T
    for kind in ("uniform", "vertex"):
        runs = [long_run_periodic(system, g, words, 60, np.random.default_rng(9), mu1=mu1,
                                  path_levels=partial(path_levels, design), kind=kind, x0=np.ones(4),
                                  controller=lambda xh: -K @ xh)
                for g in (design.schedule, design.class_gains)]
        s, c = runs
        assert c.words == s.words and c.dropped == s.dropped and c.dropped
        np.testing.assert_allclose(c.xhat, s.xhat, rtol=0, atol=ATOL)
        assert c.max_ratio <= 1 + RTOL
        assert np.abs(c.error[::T]).max() <= mu1 * (1 + RTOL)
        assert periodic_model_gap(c, system, design.class_gains) < 1e-9


def test_periodic_reuse_on_the_acc_with_a_constant_input(cases):
    system, design, mu1 = cases["acc_L1"]
    words = ["060000", "006000", "000600", "000060"]  # L1 as delay words (6: missing)
    assert {parse_delay_word(w) for w in words} == set(design.patterns)
    runs = [long_run_periodic(system, g, words, 40, np.random.default_rng(4), mu1=mu1,
                              path_levels=lambda w: _acc_levels(design, w), kind="vertex",
                              x0=np.array([20.0, 40.0, 20.0]), inputs=np.array([206.4]))
            for g in (design.schedule, design.class_gains)]
    s, c = runs
    np.testing.assert_allclose(c.xhat, s.xhat, rtol=0, atol=1e-8)
    assert c.max_ratio <= 1 + RTOL and np.abs(c.error[::6]).max() <= mu1 * (1 + RTOL)


def _acc_levels(design, word):
    pat = parse_delay_word(word)
    lv = design.class_certificate.levels
    out = np.full(pat.T + 1, design.mu1)
    for d in range(1, pat.T):
        out[d] = lv[_class_of_pattern(design, pat, d)]
    return out


def test_periodic_restart_reanchors_the_prediction(cases):
    """Period 2 of a periodic run equals a fresh estimator started at the period's end from x̂(T)."""
    system, design, mu1 = cases["reactor_delay"]
    rng = np.random.default_rng(1)
    pats = [design.patterns[3], design.patterns[17]]
    est = ClassEstimator(system, design.class_gains, periodic=True).reset(np.zeros(4))
    ys = rng.normal(size=(8, system.p))
    us = rng.normal(size=(8, system.m))
    out = []
    for k, pat in enumerate(pats):
        for t in range(4):
            out.append(est.step([Packet(4 * k + tau, ys[4 * k + tau]) for tau in pat.arriving_at(t)]
                                + ([Packet(0, ys[0])] if k == 1 and t == 0 else []), us[4 * k + t])[0])
        if k == 0:
            fresh = ClassEstimator(system, design.class_gains, est.xhat, t0=4)
    assert est.period_start == 4 and est.period_time == 4
    again = [fresh.step([Packet(4 + tau, ys[4 + tau]) for tau in pats[1].arriving_at(t)], us[4 + t])[0]
             for t in range(4)]
    np.testing.assert_array_equal(np.array(out[4:]), np.array(again))  # the stale Packet(0) was dropped


# --------------------------------------------------------------------------- the switching scheme

@pytest.fixture(scope="module")
def switching(reactor):
    """As eqrec.studies.p3.strategy: period-1 design at the smallest period-1 level rounded up, recovery
    design on the words whose first delay is at least 1."""
    mu1 = math.ceil(min_recovery_level(reactor, ["0"], kind="delay").upper * 100 - 1e-9) / 100
    words = [p.label for p in delay_language(max_delay=2, horizon=4)]
    perf = design_delay(reactor, ["0"], mu1, kind="delay", cost="sum")
    rec = design_delay(reactor, [w for w in words if w[0] != "0"], mu1, cost="sum")
    return perf, rec, mu1


def test_switching_with_class_gains_gives_the_schedule_run(reactor, switching):
    perf, rec, mu1 = switching
    K = _lqr(reactor)
    pairs = [(perf.schedule, rec.schedule), (perf.class_gains, rec.class_gains), (perf.schedule, rec.class_gains),
             (perf.class_gains, rec.schedule)]
    for kind in ("uniform", "vertex"):
        runs = [long_run_switching(reactor, p, r, 800, np.random.default_rng(6), mu1=mu1,
                                   recovery_level=partial(node_level, rec), max_delay=2, p_on_time=0.7, kind=kind,
                                   x0=np.ones(4), controller=lambda xh: -K @ xh) for p, r in pairs]
        ref = runs[0]
        assert len(ref.switch_times) > 20 and ref.max_ratio <= 1 + RTOL
        for r in runs[1:]:
            assert r.switch_times == ref.switch_times and r.revert_times == ref.revert_times
            assert r.dropped == ref.dropped
            np.testing.assert_array_equal(r.recovering, ref.recovering)
            np.testing.assert_allclose(r.xhat, ref.xhat, rtol=0, atol=ATOL)
            assert r.max_ratio <= 1 + RTOL


def test_switching_validates_class_gains(reactor, switching):
    perf, rec, mu1 = switching
    with pytest.raises(InputError, match="horizon 1"):
        SwitchingEstimator(reactor, rec.class_gains, rec.class_gains, np.zeros(4))
    late_only = classes_of_tree(PrefixTree(["1"], kind="delay"))  # the class (1, ()): no on-time class
    no_on_time = ClassGains(late_only, [np.zeros((4, 0))], 4, 2)
    with pytest.raises(InputError, match="on-time"):
        SwitchingEstimator(reactor, no_on_time, rec.class_gains, np.zeros(4))
    starts_on_time = design_delay(reactor, ["0000", "1000"], 0.5, kind="delay")
    with pytest.raises(InputError, match="first measurement late"):
        SwitchingEstimator(reactor, perf.class_gains, starts_on_time.class_gains, np.zeros(4))
    with pytest.raises(TypeError):
        SwitchingEstimator(reactor, perf, rec.class_gains, np.zeros(4))


# --------------------------------------------------------------------------- factory and bad inputs

def test_make_estimator_picks_by_the_kind_of_gains(cases):
    system, design, _ = cases["acc_L1"]
    assert type(make_estimator(system, design.schedule, np.zeros(3))) is RecoveryEstimator
    est = make_estimator(system, design.class_gains, np.zeros(3), periodic=True, t0=5)
    assert type(est) is ClassEstimator and est.periodic and est.time == 5 and est.T == 6
    later = make_estimator(system, design.class_gains, periodic=True)  # no x̂0: reset before the first step
    with pytest.raises(InputError, match="reset"):
        later.step(np.zeros(2))
    np.testing.assert_array_equal(later.reset(np.zeros(3), t0=5).step(np.ones(2))[0], est.step(np.ones(2))[0])
    with pytest.raises(InputError, match="GainSchedule or ClassGains"):  # an eqrec error naming the field
        make_estimator(system, design, np.zeros(3))


def _both(design, system, **kw):
    return [RecoveryEstimator(system, design.schedule, np.zeros(system.n), **kw),
            ClassEstimator(system, design.class_gains, np.zeros(system.n), **kw)]


def _message(f):
    with pytest.raises(InputError) as exc:
        f()
    return str(exc.value)


def test_bad_inputs_raise_the_recovery_estimators_errors(cases):
    system, design, _ = cases["reactor_delay"]
    y = np.zeros(system.p)
    # a packet from the future
    msgs = [_message(lambda e=e: e.step([Packet(1, y)])) for e in _both(design, system)]
    assert msgs[0] == msgs[1] and "future" in msgs[1]
    # a second packet with the same stamp (same step, and a later step)
    for later in (False, True):
        ests = _both(design, system)
        for e in ests:
            e.step([Packet(0, y)])
        msgs = [_message(lambda e=e: e.step([Packet(0, y)] if later else [Packet(1, y), Packet(1, y)]))
                for e in ests]
        assert msgs[0] == msgs[1] and "second packet" in msgs[1]
    # wrong length
    msgs = [_message(lambda e=e: e.step(np.zeros(system.p + 1))) for e in _both(design, system)]
    assert msgs[0] == msgs[1] and f"p = {system.p}" in msgs[1]
    # horizon over without periodic
    ests = _both(design, system)
    for e in ests:
        for t in range(design.T):
            e.step(y)
    msgs = [_message(lambda e=e: e.step(y)) for e in ests]
    assert msgs[0] == msgs[1] and "horizon" in msgs[1]
    # periodic: the same gains again
    for e in _both(design, system, periodic=True):
        for t in range(3 * design.T):
            e.step(y)
        assert e.period_start == 2 * design.T and e.period_time == design.T


def test_unknown_class_names_the_observed_data(cases):
    system, design, _ = cases["acc_L1"]
    est = ClassEstimator(system, design.class_gains, np.zeros(3), t0=10)
    with pytest.raises(InputError, match=r"observed data.*time 10.*\(1, \[\]\)"):
        est.step(None)  # L1: y(0) always arrives
    # L1 has one missing measurement per word: after y(0), y(1) on time, y(2) and y(3) missing is no class
    est = ClassEstimator(system, design.class_gains, np.zeros(3))
    for y in (np.zeros(2), np.zeros(2), None):
        est.step(y)
    with pytest.raises(InputError, match=r"arrival prefix '1100'.*times \[0, 1\].*\(4, \[0, 1\]\)"):
        est.step(None)
    # the schedule refuses the same prefix
    rec = RecoveryEstimator(system, design.schedule, np.zeros(3))
    for y in (np.zeros(2), np.zeros(2), None):
        rec.step(y)
    with pytest.raises(InputError, match="not a prefix"):
        rec.step(None)


def test_gains_that_do_not_fit_the_system(cases, reactor):
    system, design, _ = cases["acc_L1"]
    with pytest.raises(InputError, match="do not fit"):
        ClassEstimator(reactor, design.class_gains, np.zeros(4))
    g = design.class_gains
    bad = ClassGains(g.classes, [k[:, :-1] if k.shape[1] else k for k in g.K], g.n, g.p)
    with pytest.raises(InputError, match="has shape"):
        ClassEstimator(system, bad, np.zeros(3))
