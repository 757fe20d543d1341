"""The information limit (issue 32 §1): shape, hand-checked values, monotonicity, the identity with the class
engine's class levels, the window's direction, the cache and bad input.

Tolerances: the limit is an LP optimum to HiGHS's feasibility tolerance (1e-9, ``HIGHS_OPTIONS``) and the class
levels are LP optima too, so comparisons between them carry a relative 1e-9; values checked by hand carry 1e-12
(the LP's vertex is exact up to rounding there).
"""

from __future__ import annotations

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.bounds.information import block_limit, cache_info, clear_cache, information_limit
from eqrec.systems.examples import tank_chain

REL = 1e-9  # two LP optima of the same problem (module docstring of the test)


def _random_trace(N: int, loss: float, max_delay: int, seed: int) -> ArrivalTrace:
    rng = np.random.default_rng(seed)
    d = rng.integers(0, max_delay + 1, N)
    return ArrivalTrace(np.where(rng.random(N) < loss, NEVER, d))


@pytest.fixture(scope="module")
def acc():
    return eqrec.acc_system()


@pytest.fixture(scope="module")
def acc_design(acc):
    return eqrec.design_delay(acc, eqrec.delay_classes(max_delay=1, horizon=4), mu1=0.4)


@pytest.fixture(scope="module")
def reactor_design():
    return eqrec.design_prefix(eqrec.batch_reactor(), ["11111", "01111", "10111", "11011"], mu1=1.0,
                               state_weights=[1, 2, 1, 0.5])


def test_public_names():
    assert eqrec.information_limit is information_limit
    assert eqrec.ArrivalTrace is ArrivalTrace


def test_shape_and_sign(acc):
    trace = _random_trace(25, 0.3, 2, 0)
    r = information_limit(acc, trace, 0.5)
    assert r.shape == (25, acc.n)
    assert np.all(np.isfinite(r)) and np.all(r >= 0)
    assert information_limit(acc, ArrivalTrace([]), 0.5).shape == (0, acc.n)


def test_scalar_by_hand():
    # x(t+1) = x + w, y = x + v, |w| <= 0.1, |v| <= 0.5, |x(0)| <= 1
    walk = eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], eta_w=0.1, eta_v=0.5)
    # y(0) on time: |x0| <= 0.5, x(1) = x0 + w0 -> 0.6; y(1) lost: 0.7; y(2) on time: |x(2)| <= 0.5 -> 0.6
    r = information_limit(walk, ArrivalTrace([0, NEVER, 0]), 1.0)[:, 0]
    np.testing.assert_allclose(r, [0.6, 0.7, 0.6], rtol=0, atol=1e-12)
    # y(0) delayed by 2: nothing before step 2 (1.1, 1.2); at step 2 |x0| <= 0.5, x(3) = x0 + w0 + w1 + w2 -> 0.8
    r = information_limit(walk, ArrivalTrace([2, NEVER, NEVER]), 1.0)[:, 0]
    np.testing.assert_allclose(r, [1.1, 1.2, 0.8], rtol=0, atol=1e-12)


def test_time_varying_reads_absolute_time():
    # A(0) = 2, A(1) = 3, A(2) = 0.5; y(2) on time: 2.1, 6.4, then |x(2)| <= 0.5 and x(3) = 0.5 x(2) + w -> 0.35
    tv = eqrec.AffineSystem(A=np.array([2.0, 3.0, 0.5]).reshape(3, 1, 1), C=[[1.0]], E=[[1.0]], eta_w=0.1,
                            eta_v=0.5)
    r = information_limit(tv, ArrivalTrace([NEVER, NEVER, 0]), 1.0)[:, 0]
    np.testing.assert_allclose(r, [2.1, 6.4, 0.35], rtol=0, atol=1e-12)
    with pytest.raises(eqrec.InputError) as err:
        information_limit(tv, ArrivalTrace([0, 0, 0, 0]), 1.0)
    assert err.value.field == "trace"


def test_more_data_never_increases_the_limit(acc):
    trace = _random_trace(40, 0.4, 1, 3)
    base = information_limit(acc, trace, 0.5)
    lost = np.flatnonzero(trace.lost)
    tau = int(lost[len(lost) // 2])
    more = trace.delays.copy()
    more[tau] = 1  # the lost y(τ) now arrives at τ + 1
    richer = information_limit(acc, ArrivalTrace(more), 0.5)
    assert np.all(richer <= base * (1 + REL))
    np.testing.assert_array_equal(richer[:tau + 1], base[:tau + 1])  # same delivered sets: the same rows (cache)
    assert richer[tau + 1:].sum() < base[tau + 1:].sum()  # the extra measurement tells something
    wider = information_limit(acc, trace, 0.8)  # a larger initial box never decreases it
    assert np.all(wider >= base * (1 - REL))


@pytest.mark.parametrize("which", ["acc_design", "reactor_design"])
def test_class_levels_are_information_limits(which, request):
    """Every class (d, S), inner or terminal: its certified per-row worst case = the one-block limit."""
    design = request.getfixturevalue(which)
    classes = design.class_gains.classes.classes
    bounds = design.class_certificate.bounds
    levels = design.class_levels
    assert len(classes) >= 8
    for cls, row_bounds, level in zip(classes, bounds, levels):
        limit = block_limit(design.system, cls.depth, cls.available, design.mu1)
        np.testing.assert_allclose(limit, row_bounds, rtol=0, atol=REL * row_bounds.max(), err_msg=cls.label)
        assert abs(limit.max() - level) <= REL * level, cls.label


def test_limit_below_the_class_bound_on_a_long_run(acc, acc_design):
    """In the language, the class estimator guarantees its class level at every step: the limit is below it
    (equal in the first block, which starts from the same box)."""
    T, gains = acc_design.T, acc_design.class_gains
    trace = _random_trace(6 * T, 0.0, 1, 7)
    limit = information_limit(acc, trace, acc_design.mu1)
    arrival = trace.arrival_times()
    for t in range(trace.steps):
        b, d = divmod(t, T)
        S = tuple(int(tau) - b * T for tau in range(b * T, t + 1) if arrival[tau] <= t)
        level = acc_design.class_levels[gains.classes.index(d + 1, S)]
        assert limit[t].max() <= level * (1 + REL)
        if b == 0:
            assert limit[t].max() >= level * (1 - REL)


def test_window_errs_upward(acc):
    trace = _random_trace(60, 0.3, 2, 11)
    exact = information_limit(acc, trace, 0.5, cache=False)
    for W in (3, 10):
        windowed = information_limit(acc, trace, 0.5, window=W, cache=False)
        assert np.all(windowed >= exact * (1 - REL))
        np.testing.assert_allclose(windowed[:W], exact[:W], rtol=REL)  # the same LPs in other models
    np.testing.assert_allclose(information_limit(acc, trace, 0.5, window=60, cache=False), exact, rtol=REL)
    # the batch reactor has no process noise: the box forgets what x(0) was, visibly
    reactor = eqrec.batch_reactor()
    trace = _random_trace(40, 0.2, 1, 5)
    exact = information_limit(reactor, trace, 1.0)
    assert np.max(information_limit(reactor, trace, 1.0, window=4) / exact) > 1.01


def test_cache_shares_rows(acc):
    clear_cache()
    trace = _random_trace(30, 0.3, 1, 2)
    first = information_limit(acc, trace, 0.5)
    assert cache_info()["misses"] == 30 and cache_info()["hits"] == 0
    np.testing.assert_array_equal(information_limit(acc, trace, 0.5), first)
    assert cache_info()["hits"] == 30
    # another run with the same deliveries up to step 19 (only the later delays differ)
    other = trace.delays.copy()
    other[25:] = NEVER
    information_limit(acc, ArrivalTrace(other), 0.5)
    assert cache_info()["hits"] >= 30 + 20
    information_limit(acc, trace, [0.5, 0.5, 0.6])  # another radius: no hit
    assert cache_info()["misses"] >= 30 + 30


def test_other_solver_agrees(acc):
    trace = _random_trace(10, 0.3, 1, 4)
    np.testing.assert_allclose(information_limit(acc, trace, 0.5, solver="scipy", cache=False),
                               information_limit(acc, trace, 0.5, cache=False), rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("kwargs, field", [
    ({"trace": [0, 1]}, "trace"),
    ({"system": "acc"}, "system"),
    ({"x0_radius": -1.0}, "x0_radius"),
    ({"x0_radius": float("nan")}, "x0_radius"),
    ({"x0_radius": [1.0, 1.0]}, "x0_radius"),
    ({"x0_radius": np.inf}, "x0_radius"),
    ({"x0_radius": 1e300}, "x0_radius"),  # HiGHS reads 1e20 as infinite: refused by name (MAX_X0_RADIUS)
    ({"x0_radius": [0.5, 1e16, 0.5]}, "x0_radius"),
    ({"solver": "gurobi"}, "solver"),
    ({"window": 0}, "window"),
    ({"solver_options": 3}, "solver_options"),
    ({"n_jobs": 0}, "n_jobs"),
    ({"n_jobs": 1.5}, "n_jobs"),
])
def test_bad_input(acc, kwargs, field):
    args = {"system": acc, "trace": ArrivalTrace([0, 1]), "x0_radius": 0.5, **kwargs}
    with pytest.raises(eqrec.InputError) as err:
        information_limit(args.pop("system"), args.pop("trace"), args.pop("x0_radius"), **args)
    assert err.value.field == field


def test_block_limit_bad_input(acc):
    with pytest.raises(eqrec.InputError) as err:
        block_limit(acc, 0, (), 1.0)
    assert err.value.field == "depth"
    with pytest.raises(eqrec.InputError) as err:
        block_limit(acc, 3, (0, 3), 1.0)
    assert err.value.field == "available"


def test_a_failed_warm_solve_is_solved_again(acc, monkeypatch):
    """A warm HiGHS solve without an optimum (forced here: an iteration limit of 0 on the first model) is solved
    cold by solve_lp and the model reloaded; the values do not change."""
    import eqrec.bounds.information as info

    trace = _random_trace(12, 0.3, 1, 9)
    reference = information_limit(acc, trace, 0.5, cache=False)
    loaded = []

    def crippled(lp, options):
        h = original(lp, options)
        if not loaded:
            h.setOptionValue("simplex_iteration_limit", 0)
        loaded.append(lp.shape)
        return h

    original = info.highs_model
    monkeypatch.setattr(info, "highs_model", crippled)
    np.testing.assert_allclose(information_limit(acc, trace, 0.5, cache=False), reference, rtol=REL)
    assert len(loaded) >= 2  # the first model failed and was replaced


@pytest.mark.parametrize("segment", [1, 3])
def test_segment_length_does_not_change_the_values(acc, segment, monkeypatch):
    """The state eliminated inside segments of K steps: the same LP optimum as with x at every step."""
    import eqrec.bounds.information as info

    trace = _random_trace(30, 0.3, 2, 13)
    reference = information_limit(acc, trace, 0.5, cache=False)
    monkeypatch.setattr(info, "SEGMENT", segment)
    np.testing.assert_allclose(information_limit(acc, trace, 0.5, cache=False), reference, rtol=REL, atol=1e-15)
    windowed = information_limit(acc, trace, 0.5, cache=False, window=7)
    assert np.all(windowed >= reference * (1 - REL))


def test_a_packet_past_the_end_is_not_a_delivery_and_keys_the_cache_by_the_delivered_set(acc):
    """Issue 41 §3: a delay of 2**63 - 1 overflowed arrival_times to a negative time; the limit then cached the
    rows of a trace that never delivers y(1) under the key of one that delivers it at step 1, and served them to
    that trace.  Such a delay is now refused by ArrivalTrace (at most 2**62); the largest one allowed arrives
    past the end, and the delivered sets come from the delays alone, for the LP and the key alike."""
    with pytest.raises(eqrec.InputError, match="delays"):
        ArrivalTrace([0, 2**63 - 1])
    clear_cache()
    far = information_limit(acc, ArrivalTrace([0, 2**62]), 0.5)
    lost = information_limit(acc, ArrivalTrace([0, NEVER]), 0.5, cache=False)
    np.testing.assert_array_equal(far, lost)
    on_time = information_limit(acc, ArrivalTrace([0, 0]), 0.5)
    fresh = information_limit(acc, ArrivalTrace([0, 0]), 0.5, cache=False)
    np.testing.assert_array_equal(on_time, fresh)
    assert on_time[1].max() < lost[1].max()  # y(1) delivered at step 1 tightens row 1


def test_a_long_exact_limit_is_estimated_and_refused_with_the_window_offered(acc):
    """Issue 41 §2: 10^5 steps (about hours) are refused before any LP is built, within a second; the message
    gives the estimate, force=True and a window with its own estimate; the windowed call itself is allowed."""
    import time

    import eqrec.bounds.information as info

    trace = ArrivalTrace(np.zeros(100_000, np.int64))
    t0 = time.perf_counter()
    with pytest.raises(eqrec.InputError) as err:
        information_limit(acc, trace, 0.5, cache=False)
    assert time.perf_counter() - t0 < 5
    assert err.value.field == "trace"
    msg = str(err.value)
    assert "force=True" in msg and "window=" in msg and ">= the exact limit" in msg and " h " in msg
    W = info.suggested_window(acc, 100_000)
    assert info.estimate_seconds(acc, 100_000, W) <= info.MAX_ESTIMATED_SECONDS
    assert info.estimate_seconds(acc, 100_000) > info.MAX_ESTIMATED_SECONDS
    # the model: quadratic in the length exactly, linear with a window
    e1, e2 = info.estimate_seconds(acc, 1000), info.estimate_seconds(acc, 4000)
    assert 10 < e2 / e1 < 16
    w1, w2 = info.estimate_seconds(acc, 1000, 20), info.estimate_seconds(acc, 4000, 20)
    assert 3.9 < w2 / w1 < 4.1


def test_force_runs_past_the_estimate(acc, monkeypatch):
    import eqrec.bounds.information as info

    trace = _random_trace(12, 0.3, 1, 21)
    reference = information_limit(acc, trace, 0.5, cache=False)
    monkeypatch.setattr(info, "MAX_ESTIMATED_SECONDS", 0.0)
    with pytest.raises(eqrec.InputError, match="refused"):
        information_limit(acc, trace, 0.5, cache=False)
    np.testing.assert_array_equal(information_limit(acc, trace, 0.5, cache=False, force=True), reference)


def test_an_unbounded_answer_is_a_solver_failure_naming_x0_radius(acc, monkeypatch):
    """The zero-data LP is feasible and bounded: a solver's 'unbounded' is a fault, reported as SolverFailure
    (the documented error) with the scale that set it."""
    import eqrec.bounds.information as info
    from eqrec.errors import InfeasibleDesign

    def unbounded(*args, **kwargs):
        raise InfeasibleDesign("information limit, step 0, state 0 is unbounded (highs)")

    monkeypatch.setattr(info, "solve_range", unbounded)
    with pytest.raises(eqrec.SolverFailure, match="x0_radius"):
        information_limit(acc, ArrivalTrace([0, 0]), 0.5, cache=False)


@pytest.mark.parametrize("window", [None, 6])
def test_large_plants_dual_simplex_in_alternating_order_gives_the_same_rows(window, monkeypatch):
    """From LIMIT_DUAL_FROM_N states on the limit solves with the primal-then-dual fallback and the states in
    alternating order (lowered here to reach that path on a small asymmetric chain): every row, in state order,
    equals the primal simplex's in fixed order and an independent solver's (a row stored in the solve order would
    differ: the chain's sensors and leak make its states differ)."""
    import eqrec.bounds.information as info

    plant = tank_chain(5, 2, eta_v=0.05)
    trace = _random_trace(20, 0.3, 2, 45)
    primal = information_limit(plant, trace, 1.0, cache=False, window=window)
    monkeypatch.setattr(info, "LIMIT_DUAL_FROM_N", 1)
    assert list(info._limit_order(1, 5)) == [4, 3, 2, 1, 0]
    dual = information_limit(plant, trace, 1.0, cache=False, window=window)
    np.testing.assert_allclose(dual, primal, rtol=REL, atol=1e-12)
    assert np.max(np.abs(primal - primal[:, ::-1])) > 1e-3  # the order matters on this chain
    np.testing.assert_allclose(dual, information_limit(plant, trace, 1.0, solver="scipy", cache=False, window=window),
                               rtol=1e-7, atol=1e-9)


@pytest.mark.parametrize("primal_iterations", [0, 3])
def test_large_plants_primal_then_dual_fallback_gives_the_same_rows(primal_iterations, monkeypatch):
    """From LIMIT_DUAL_FROM_N states on each objective gets LIMIT_PRIMAL_ITERATIONS primal simplex iterations and
    goes on with the dual simplex from where they stopped (lowered here so that the fallback is taken, and with
    0 iterations taken on every solve; a state that needed it goes to the dual simplex at once on the next
    step): every row equals the plain primal simplex's and an independent solver's, and the fallback ran."""
    import eqrec.bounds.information as info

    plant = tank_chain(6, 2, eta_v=0.05)
    trace = _random_trace(24, 0.3, 2, 46)
    primal = information_limit(plant, trace, 1.0, cache=False)
    monkeypatch.setattr(info, "LIMIT_DUAL_FROM_N", 1)
    monkeypatch.setattr(info, "LIMIT_PRIMAL_ITERATIONS", primal_iterations)
    runs = {"primal": 0, "dual": 0}
    original = info._HighsModel._run

    def counted(self, key=None):
        before = set(self.hard)
        status = original(self, key)
        runs["dual" if key in self.hard or key in before else "primal"] += 1
        return status

    monkeypatch.setattr(info._HighsModel, "_run", counted)
    hybrid = information_limit(plant, trace, 1.0, cache=False)
    assert runs["dual"] > 0  # the fallback was exercised
    np.testing.assert_allclose(hybrid, primal, rtol=REL, atol=1e-12)
    np.testing.assert_allclose(hybrid, information_limit(plant, trace, 1.0, solver="scipy", cache=False),
                               rtol=1e-7, atol=1e-9)


def test_the_fallback_restores_the_primal_settings(monkeypatch):
    """After a fallback to the dual simplex the model's strategy and iteration limit are the primal phase's
    again (a model left on the dual simplex would silently change the method of every later solve)."""
    import eqrec.bounds.information as info

    monkeypatch.setattr(info, "LIMIT_PRIMAL_ITERATIONS", 0)
    plant = tank_chain(6, 2, eta_v=0.05)
    trace = _random_trace(10, 0.3, 2, 47)
    tlp = info.trace_lp(plant, trace, np.ones(6), info.SEGMENT)
    lp, c0, r0 = tlp.window(0, 10)
    model = info._HighsModel(lp, c0, r0, None, info.LIMIT_HIGHS_OPTIONS)
    cols, M = tlp.xmap[10]
    for i in range(6):  # the first run may end in HiGHS's presolve; the warm ones hit the limit of 0
        assert model.maximise(cols[M[i] != 0], M[i][M[i] != 0], f"state {i}", f"state {i}") > 0
    assert model.hard  # some objective fell back to the dual simplex
    assert info._option(model.h, "simplex_strategy") == info.HIGHS_OPTIONS["simplex_strategy"]
    assert info._option(model.h, "simplex_iteration_limit") == 0
    assert model.restore["simplex_iteration_limit"] == 2**31 - 1
    for key, val in info.LIMIT_SHARED_OPTIONS.items():  # both phases: no scaling, the tighter dual tolerance
        assert info._option(model.h, key) == val


def test_the_time_model_of_large_plants_is_the_limits_own_path():
    """From LIMIT_DUAL_FROM_N states on the limit's estimate uses the fallback path's model (LIMIT_STATE_EXPONENT):
    150 steps of 30 tanks are no longer refused (measured about 100 s, the old model said 883 s), while the
    consistent set (primal=True, the primal simplex at every n) and smaller plants keep the first model."""
    import eqrec.bounds.information as info

    big, small = tank_chain(30, 5), tank_chain(info.LIMIT_DUAL_FROM_N - 1, 3)
    assert info.estimate_seconds(big, 150) < info.MAX_ESTIMATED_SECONDS
    assert info.estimate_seconds(big, 150, primal=True) > info.MAX_ESTIMATED_SECONDS
    t = np.arange(150.0)
    first = 150 * info.SECONDS_PER_STATE * 30 + info.SECONDS_PER_STATE_STEP * 30 ** info.STATE_EXPONENT * t.sum()
    assert info.estimate_seconds(big, 150, primal=True) == pytest.approx(first, rel=1e-12)
    assert info.estimate_seconds(small, 150) == info.estimate_seconds(small, 150, primal=True)


def test_the_unscaled_options_are_those_of_large_plants_only():
    """LIMIT_SHARED_OPTIONS (no scaling, dual feasibility tolerance 1e-10) go to the models of the fallback path
    (from LIMIT_DUAL_FROM_N states on) and not to the primal path below it, whose models keep HiGHS's scaling and
    HIGHS_OPTIONS' tolerance (the limits of the compare study's small plants stay those of before, byte for
    byte); the caller's solver_options override them."""
    import eqrec.bounds.information as info

    plant = tank_chain(6, 2, eta_v=0.05)
    tlp = info.trace_lp(plant, _random_trace(10, 0.3, 2, 47), np.ones(6), info.SEGMENT)
    lp, c0, r0 = tlp.window(0, 10)
    large = info._HighsModel(lp, c0, r0, None, info.LIMIT_HIGHS_OPTIONS)
    small = info._HighsModel(lp, c0, r0, None)
    assert info._option(large.h, "simplex_scale_strategy") == 0
    assert info._option(large.h, "dual_feasibility_tolerance") == 1e-10
    assert info._option(small.h, "simplex_scale_strategy") != 0
    assert info._option(small.h, "dual_feasibility_tolerance") == info.HIGHS_OPTIONS["dual_feasibility_tolerance"]
    mine = info._HighsModel(lp, c0, r0, {"simplex_scale_strategy": 2}, info.LIMIT_HIGHS_OPTIONS)
    assert info._option(mine.h, "simplex_scale_strategy") == 2


def test_state_groups_partition_the_states_into_neighbours():
    """Below LIMIT_DUAL_FROM_N one group (the path of before); from there contiguous groups of at most
    LIMIT_GROUP_STATES states, sizes differing by at most one, covering every state once."""
    import eqrec.bounds.information as info

    assert [g.tolist() for g in info.state_groups(5)] == [[0, 1, 2, 3, 4]]
    for n in (info.LIMIT_DUAL_FROM_N, 20, 30, 33):
        groups = info.state_groups(n)
        assert np.array_equal(np.concatenate(groups), np.arange(n))
        sizes = [g.size for g in groups]
        assert max(sizes) <= info.LIMIT_GROUP_STATES and max(sizes) - min(sizes) <= 1
        assert len(groups) == -(-n // info.LIMIT_GROUP_STATES)


@pytest.mark.parametrize("window", [None, 12])
def test_groups_on_worker_processes_give_the_serial_rows_byte_for_byte(window, monkeypatch):
    """From LIMIT_DUAL_FROM_N states on (lowered here, with groups of 2 states, on a 5-state chain over 70 steps:
    3 chunks of CHUNK steps) the limit is solved in tasks of one group and one chunk: on 2 worker processes the
    rows are the same bytes as in this process (each task carries its settings; the workers see the module's
    defaults), every state is filled (none left at 0 by a misplaced group), and they agree with the path of one
    model for all the states and with an independent solver to the LP tolerance."""
    import eqrec.bounds.information as info

    plant = tank_chain(5, 2, eta_v=0.05)
    trace = _random_trace(70, 0.3, 2, 48)
    whole = information_limit(plant, trace, 1.0, cache=False, window=window)
    monkeypatch.setattr(info, "LIMIT_DUAL_FROM_N", 1)
    monkeypatch.setattr(info, "LIMIT_GROUP_STATES", 2)
    serial = information_limit(plant, trace, 1.0, cache=False, window=window, n_jobs=1)
    assert info.last_solve_info()["workers"] == 1
    parallel = information_limit(plant, trace, 1.0, cache=False, window=window, n_jobs=2)
    ran = info.last_solve_info()
    assert ran["workers"] == 2 and ran["task_seconds"] > 0
    # 3 groups (2, 2, 1 states) times 3 chunks (rows 0-31, 32-63, 64-69), or 6 windows of one chunk each
    assert ran["tasks"] == 3 * (3 if window is None else 6)
    np.testing.assert_array_equal(parallel, serial)
    assert np.all(serial > 0)
    np.testing.assert_allclose(serial, whole, rtol=REL, atol=1e-12)
    np.testing.assert_allclose(serial, information_limit(plant, trace, 1.0, solver="scipy", cache=False,
                                                         window=window), rtol=1e-7, atol=1e-9)


def test_small_plants_never_start_worker_processes(acc):
    """Below LIMIT_DUAL_FROM_N states the limit solves in this process whatever n_jobs says (one model per chunk
    for all the states: the values of before, byte for byte, as the results' plants need)."""
    import eqrec.bounds.information as info

    trace = _random_trace(40, 0.3, 2, 49)
    one = information_limit(acc, trace, 0.5, cache=False, n_jobs=1)
    two = information_limit(acc, trace, 0.5, cache=False, n_jobs=2)
    assert info.last_solve_info() == {"workers": 1, "tasks": 0, "task_seconds": 0.0}
    np.testing.assert_array_equal(one, two)


def test_hard_states_from_their_own_basis_in_two_phases_give_the_same_rows(monkeypatch):
    """From LIMIT_DUAL_FROM_N states on (lowered here, with 3 primal iterations so that states fall back) a state
    that needed the dual simplex starts the next step from its own optimal basis, the rows delivered since freed
    for a primal phase and fixed again for the dual one: the path is taken, with rows to free and without, the
    model's rows are fixed again afterwards, and every row equals the plain primal simplex's and an independent
    solver's."""
    import eqrec.bounds.information as info

    plant = tank_chain(6, 2, eta_v=0.05)
    trace = _random_trace(40, 0.3, 2, 50)
    primal = information_limit(plant, trace, 1.0, cache=False)
    monkeypatch.setattr(info, "LIMIT_DUAL_FROM_N", 1)
    monkeypatch.setattr(info, "LIMIT_PRIMAL_ITERATIONS", 3)
    freed = []
    original = info._HighsModel._run_own

    def counted(self, key):
        freed.append(len(self.batches) - self.bases[key][1])
        status = original(self, key)
        for idx, val in self.batches:  # every delivered row is fixed again in the model
            lower = np.array(self.h.getLp().row_lower_)[idx]
            np.testing.assert_array_equal(lower, val)
        return status

    monkeypatch.setattr(info._HighsModel, "_run_own", counted)
    hybrid = information_limit(plant, trace, 1.0, cache=False)
    assert any(f > 0 for f in freed) and any(f == 0 for f in freed)
    np.testing.assert_allclose(hybrid, primal, rtol=REL, atol=1e-12)
    np.testing.assert_allclose(hybrid, information_limit(plant, trace, 1.0, solver="scipy", cache=False),
                               rtol=1e-7, atol=1e-9)
