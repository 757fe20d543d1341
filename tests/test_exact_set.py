"""Filtered and predicted sets (issue 45 §1) and the exact set-membership estimator (§3), against the exact hull of
the whole horizon computed by a direct LP (tests/exact_hull_reference.py, SciPy's HiGHS; a test-only reference).

The reference is an LP optimum, accurate to HiGHS's tolerances (about 1e-9 here): containment of it is checked
with that allowance on the reference's side only; the true state is checked with none."""

from __future__ import annotations

import pickle

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.packets import Packet
from eqrec.bounds.window_lp import dual_bound, lp_hull, window_set
from eqrec.errors import InputError
from eqrec.estimators.exact_set import ExactSetEstimator
from eqrec.estimators.protocol import StateSet
from eqrec.estimators.zonotope import ZonotopeEstimator
from eqrec.systems.examples import tank_chain
from exact_hull_reference import exact_hulls, simulate
from test_zonotope import lossy_trace

#: The reference LP's accuracy (its side only).
REF_TOL = 1e-8


def oscillator() -> eqrec.AffineSystem:
    th = 0.3
    A = 0.995 * np.array([[np.cos(th), -np.sin(th)], [np.sin(th), np.cos(th)]])
    return eqrec.AffineSystem(A=A, C=[[1.0, 0.0]], E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05, name="oscillator")


def six_states(seed: int = 3) -> eqrec.AffineSystem:
    """A random stable plant, n = 6, two outputs, negative entries."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(6, 6))
    A *= 0.9 / max(abs(np.linalg.eigvals(A)))
    return eqrec.AffineSystem(A=A, C=rng.normal(size=(2, 6)), E=0.1 * rng.normal(size=(6, 2)), eta_w=1.0,
                              eta_v=0.05, name="six")


def _run(system, make, steps, seed, radius=0.5, every=1):
    """Run each estimator of ``make`` on uniform noise; per checked step the filtered and predicted sets and the
    reference hulls."""
    rng = np.random.default_rng(seed)
    trace = lossy_trace(seed, steps)
    n = system.n
    w = rng.uniform(-1, 1, (steps, system.nw))
    v = rng.uniform(-1, 1, (steps, system.nv))
    xi0 = radius * rng.uniform(-1, 1, n)
    x, y, arrivals = simulate(system, trace, np.zeros(n), xi0, w, v)
    ests = {k: m().reset(np.zeros(n)) for k, m in make.items()}
    _run.last = ests
    rows = []
    for t in range(steps):
        out = {k: e.step(arrivals[t]) for k, e in ests.items()}
        if t % every and t != steps - 1:
            continue
        ref = exact_hulls(system, trace, np.zeros(n), radius, y, t)
        rows.append((t, {k: (e.filtered, e.predicted, out[k]) for k, e in ests.items()}, ref, x[t], x[t + 1]))
    return rows


def _ratio(S: StateSet, ref) -> float:
    lo, hi = ref
    return float(np.max((S.upper - S.lower) / (hi - lo)))


def _check_contains(S: StateSet, ref, x):
    lo, hi = ref
    assert np.all(S.lower <= x) and np.all(x <= S.upper), "the set misses the true state"
    width = hi - lo
    assert np.all(S.lower <= lo + REF_TOL * (1 + width)) and np.all(S.upper >= hi - REF_TOL * (1 + width)), \
        "the set misses part of the exact hull"


def corner_run(system: eqrec.AffineSystem, est, seed: int, N: int, radius: float = 0.5):
    """A closed-loop run of ``est`` on ``lossy_trace(seed, N)`` with the initial error and the noise at random
    corners of their boxes (seeded by ``seed``): the played-back worst cases of the guarantee tests."""
    rng = np.random.default_rng(seed)
    return eqrec.simulate.loop.closed_loop(system, est, lossy_trace(seed, N), np.zeros(system.n),
                                           radius * rng.choice([-1.0, 1.0], system.n),
                                           system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw)),
                                           system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv)))


@pytest.mark.parametrize("plant", [oscillator, six_states])
def test_exact_estimator_meets_the_goals_on_small_plants(plant):
    """Filtered hull / exact hull <= 1.01 at the last step and <= 1.05 at every step (issue 45 §3), every set
    containing the exact hull and the true state, on a plant it was not tuned on."""
    system = plant()
    rows = _run(system, {"exact": lambda: ExactSetEstimator(system, 0.5, max_delay=2)}, 60, 7)
    ratios = []
    for t, sets, ref, x_t, x_t1 in rows:
        filt, pred, (xhat, bound) = sets["exact"]
        _check_contains(filt, ref[0], x_t)
        _check_contains(pred, ref[1], x_t1)
        assert filt.time == t and pred.time == t + 1 and filt.generators is None
        assert np.array_equal(pred.centre, xhat) and bound == pred.radius.max() or bound >= np.max(
            np.abs(x_t1 - xhat))
        ratios.append(_ratio(filt, ref[0]))
    assert _run.last["exact"].lp_fallbacks == 0  # data from the model: every hull LP has an optimum
    assert ratios[-1] <= 1.01, ratios[-1]
    assert max(ratios) <= 1.05, max(ratios)


def test_exact_estimator_is_tighter_than_the_zonotope_estimator_on_two_carts():
    """On the two-cart plant (the slowest to forget its prior; not among the goal's plants: 1.021 measured at the
    last of these 80 steps, 1.001 after 150 on another seed) the exact estimator ends within 1.05 of the exact
    hull, below the zonotope estimator; both contain the exact hull at every checked step."""
    system = eqrec.two_mass()
    rows = _run(system, {"exact": lambda: ExactSetEstimator(system, 0.5, max_delay=2),
                         "zonotope": lambda: ZonotopeEstimator(system, 0.5, max_delay=2)}, 80, 1, every=4)
    last = {}
    for t, sets, ref, x_t, x_t1 in rows:
        for k, (filt, pred, _) in sets.items():
            _check_contains(filt, ref[0], x_t)
            _check_contains(pred, ref[1], x_t1)
            last[k] = (_ratio(filt, ref[0]), _ratio(pred, ref[1]))
    assert last["exact"][0] <= 1.05 and last["exact"][1] <= 1.05, last
    assert last["exact"][0] < last["zonotope"][0], last


def test_zonotope_filtered_set_contains_the_exact_hull_at_every_step():
    """§1 for the zonotope estimator: the filtered set (x(t) given data to t) and the predicted one (x(t+1))
    contain the exact hull at every step; the prediction is what step returns; the filtered set is no wider than
    the prediction's of the step before (it adds y(t))."""
    system = eqrec.two_mass()
    rows = _run(system, {"z": lambda: ZonotopeEstimator(system, 0.5, max_delay=2, window=5, order=3)}, 40, 2)
    prev_pred = None
    for t, sets, ref, x_t, x_t1 in rows:
        filt, pred, (xhat, bound) = sets["z"]
        _check_contains(filt, ref[0], x_t)
        _check_contains(pred, ref[1], x_t1)
        assert np.array_equal(pred.centre, xhat) and np.all(pred.radius >= 0) and pred.radius.max() >= bound
        # the zonotope lies inside the bounds (its row sums, rounded)
        for S in (filt, pred):
            r = np.abs(S.generators).sum(axis=1)
            assert np.all(S.centre - r >= S.lower - 1e-12) and np.all(S.centre + r <= S.upper + 1e-12)
        if prev_pred is not None:
            assert filt.time == prev_pred.time
        prev_pred = pred


def test_sets_right_after_reset():
    system = eqrec.two_mass()
    for est in (ZonotopeEstimator(system, 0.5), ExactSetEstimator(system, 0.5)):
        with pytest.raises(InputError):
            est.predicted  # noqa: B018 - before reset
        est.reset(np.ones(4), t0=5)
        S = est.predicted
        assert S.time == 5 and np.all(S.lower <= 0.5) and np.all(S.upper >= 1.5)
        with pytest.raises(InputError) as info:
            est.filtered  # noqa: B018 - no data yet
        assert info.value.field == "filtered"


def test_exact_estimator_protocol_delays_atomic_reset():
    """Late packets are used at their own time, too-late ones dropped; a refused call changes nothing; reset
    starts again from scratch (the same outputs twice)."""
    system = eqrec.two_mass()
    est = ExactSetEstimator(system, 0.5, max_delay=2, window=5)
    with pytest.raises(InputError):
        est.step(None)
    est.reset(np.zeros(4))
    est.step(np.array([0.1]))
    est.step(None)
    est.step([Packet(1, np.array([0.12]))])
    assert est.replays == 1 and est.time == 3
    est.step([Packet(0, np.array([0.1]))])  # 3 steps late: dropped
    assert est.dropped_packets == 1
    before = pickle.dumps(est)
    for bad in (dict(y=np.array([np.nan])), dict(y=[Packet(9, np.array([0.1]))]), dict(y=[Packet(2, np.array([0.0])),
                                                                                           Packet(2, np.array([0.0]))])):
        with pytest.raises(InputError):
            est.step(**bad)
        assert pickle.dumps(est) == before
    seq = [np.array([0.1]), None, np.array([0.3]), [Packet(1, np.array([0.2])), Packet(3, np.array([0.25]))], None,
           np.array([0.0])]
    outs = []
    for _ in range(2):
        est.reset(np.zeros(4))
        outs.append([est.step(y) for y in seq])
    for (a, ba), (b, bb) in zip(*outs):
        assert np.array_equal(a, b) and ba == bb
    assert est.state_bounds.shape == (4,)
    with pytest.raises(InputError) as info:
        ExactSetEstimator(system, 0.5, gain=("fradius", "reweighted"))
    assert info.value.field == "gain"


def test_exact_estimator_guarantee_at_box_corners():
    """error <= bound at every step with the noise at random corners of its box (the worst cases of the linear
    estimators; the exact estimator's bound holds for every noise in the box)."""
    system = oscillator()
    N = 60
    for seed in range(3):
        out = corner_run(system, ExactSetEstimator(system, 0.5, max_delay=2, window=10), seed, N)
        assert np.all(np.abs(out.error[1:]).max(axis=1) <= out.bound)


def _carts_window(L: int) -> tuple[np.ndarray, ...]:
    """The two carts' window model over ``L`` steps as :func:`window_set` takes it: ``A, C``, and ``E, V`` with the
    noise bounds folded in, one copy per step."""
    system = eqrec.two_mass()
    n = system.n
    return (np.broadcast_to(system.A, (L, n, n)).copy(), np.broadcast_to(system.C, (L, 1, n)).copy(),
            np.broadcast_to(system.eta_w * system.E, (L, n, 2)).copy(),
            np.broadcast_to(system.eta_v * system.V, (L, 1, 1)).copy())


def test_dual_bound_is_a_bound_for_any_multipliers():
    """Weak duality (bounds/window_lp.py): the bound from any multipliers is >= the LP's maximum; the LP hull
    equals the full-window LP (no prior information lost) and contains a brute-force sample of the set."""
    rng = np.random.default_rng(0)
    system, (A, C, E, V) = eqrec.two_mass(), _carts_window(6)
    L, n = 6, 4
    measured = np.array([True, False, True, True, False, True])
    G0 = 0.5 * np.eye(n)
    xi = rng.uniform(-1, 1, n + L * 2 + 4)
    x = G0 @ xi[:n]
    Y = np.zeros((L, 1))
    k = 0
    for j in range(L):
        Y[j] = system.C @ x + (system.eta_v * system.V @ xi[n + 2 * L + k:n + 2 * L + k + 1] if measured[j] else 0)
        k += measured[j]
        x = system.A @ x + system.eta_w * system.E @ xi[n + 2 * j:n + 2 * j + 2]
    ws = window_set(A, C, E, V, np.zeros((L, n)), measured, Y, np.zeros(n), G0)
    lo, hi, fb = lp_hull(ws, "pred")
    assert fb == 0 and np.all(lo <= x) and np.all(x <= hi)
    for _ in range(20):
        y = rng.normal(size=ws.M.shape[0])
        b = dual_bound(ws.X_pred[0], ws.M, ws.lower, ws.upper, y, ws.mag_pred[0], ws.mag_rows, ws.kappa)
        assert ws.centre_pred[0] + b >= hi[0] - 1e-12


@pytest.mark.parametrize("prior", ["zonotope+box", "box"])
@pytest.mark.parametrize("plant", [oscillator, lambda: tank_chain(4, 1)], ids=["oscillator", "tanks4"])
def test_box_prior_guarantee_at_box_corners(plant, prior):
    """The earlier hull as the prior: error <= bound at every step, no tolerance, with the noise at random corners of
    its box and a short window (the prior's box then binds at every step; a box that missed the state, e.g. keyed to
    the wrong time, fails here)."""
    system = plant()
    N = 60
    for seed in range(3):
        est = ExactSetEstimator(system, 0.5, max_delay=2, window=4, prior=prior)
        out = corner_run(system, est, seed, N)
        assert np.all(np.abs(out.error[1:]).max(axis=1) <= out.bound)
        assert est.lp_fallbacks == 0


def test_box_prior_contains_the_exact_hull_and_is_tighter():
    """The tank chain n = 6 (two sensors), window 5: with each prior every set contains the exact hull and the
    true state; with "zonotope+box" each is no wider than with the zonotope (a subset's LP optimum, up to the
    rounding allowance), and strictly tighter somewhere (the prior's box binds on this slow plant)."""
    system = tank_chain(6, 2)
    make = {k: (lambda k=k: ExactSetEstimator(system, 0.5, max_delay=2, window=5, prior=k))
            for k in ("zonotope+box", "box", "zonotope")}
    rows = _run(system, make, 40, 3, every=3)
    gains = []
    for t, sets, ref, x_t, x_t1 in rows:
        sets["plain"], sets["box"] = sets["zonotope"], sets["zonotope+box"]
        for k in make:
            filt, pred, _ = sets[k]
            _check_contains(filt, ref[0], x_t)
            _check_contains(pred, ref[1], x_t1)
        for S_box, S_plain in zip(sets["box"][:2], sets["plain"][:2]):
            w_box, w_plain = S_box.upper - S_box.lower, S_plain.upper - S_plain.lower
            assert np.all(w_box <= w_plain * (1 + 1e-9) + 1e-12)
            gains.append(float(np.max(w_plain / w_box)))
    assert max(gains) > 1.05, max(gains)
    with pytest.raises(InputError) as info:
        ExactSetEstimator(system, 0.5, prior="boxes")
    assert info.value.field == "prior"


def test_default_prior_and_window_depend_on_the_plant_size():
    """``prior=None`` is the filter's zonotope below ``EXACT_BOX_STATES`` states and the box from there on;
    ``window=None`` is 50 steps with the zonotope (alone or within the box) and 10 with the box alone; explicit
    values are kept; a bad system is still refused naming its field."""
    from eqrec.estimators import exact_set

    small = tank_chain(exact_set.EXACT_BOX_STATES - 1, 2)
    large = tank_chain(exact_set.EXACT_BOX_STATES, 2)
    est = ExactSetEstimator(small, 0.5)
    assert (est.prior, est.window) == ("zonotope", exact_set.EXACT_WINDOW) == ("zonotope", 50)
    est = ExactSetEstimator(large, 0.5)
    assert (est.prior, est.window) == ("box", exact_set.EXACT_WINDOW_BOX) == ("box", 10)
    assert (ExactSetEstimator(large, 0.5, prior="zonotope").window, ExactSetEstimator(small, 0.5, prior="box").window,
            ExactSetEstimator(large, 0.5, prior="zonotope+box").window) == (50, 10, 50)
    assert ExactSetEstimator(large, 0.5, window=7).window == 7
    assert ExactSetEstimator(large, 0.5, max_delay=12)._W == 13  # (the window used: at least max_delay + 1 steps)
    with pytest.raises(InputError) as info:
        ExactSetEstimator("plant", 0.5)
    assert info.value.field == "system"


def test_window_set_ranged_prior_rows():
    """window_set's ranged prior rows (A0, lower, upper): the rows are the prior's then the measured ones, and the
    LP hull equals SciPy's optimum of the same LP written independently (inequalities for the ranged rows)."""
    from scipy.optimize import linprog

    rng = np.random.default_rng(5)
    system, (A, C, E, V) = eqrec.two_mass(), _carts_window(6)
    L, n = 6, 4
    measured = np.array([True, True, False, True, True, True])
    G0 = 0.5 * np.eye(n) + 0.1 * rng.normal(size=(n, n))
    Y = rng.normal(scale=0.05, size=(L, 1))
    lo, hi = -0.2 * np.ones(n), 0.1 * np.ones(n)
    plain = window_set(A, C, E, V, np.zeros((L, n)), measured, Y, np.zeros(n), G0)
    boxed = window_set(A, C, E, V, np.zeros((L, n)), measured, Y, np.zeros(n), G0, (G0, lo, hi))
    Q = plain.M.shape[1]
    G0_rows = np.concatenate([G0, np.zeros((n, Q - n))], axis=1)
    assert np.array_equal(boxed.M, np.concatenate([G0_rows, plain.M]))
    assert np.array_equal(boxed.lower[:n], lo) and np.array_equal(boxed.upper[:n], hi)
    low, up, fb = lp_hull(boxed, "pred")
    assert fb == 0
    for i in range(n):
        for sign, end in ((-1.0, up[i]), (1.0, low[i])):
            res = linprog(sign * boxed.X_pred[i], A_ub=np.vstack([G0_rows, -G0_rows]), b_ub=np.concatenate([hi, -lo]),
                          A_eq=plain.M, b_eq=plain.lower, bounds=(-1, 1), method="highs")
            assert res.status == 0
            opt = boxed.centre_pred[i] + sign * res.fun
            assert abs(end - opt) <= 1e-7 * (1 + abs(opt)), (i, sign, end, opt)
            assert (end >= opt - REF_TOL) if sign < 0 else (end <= opt + REF_TOL)


@pytest.mark.parametrize("prior", ["zonotope+box", "box"])
def test_box_prior_atomic_and_reset(prior):
    """With the earlier hull as the prior, a refused step changes nothing (the hulls kept for later windows
    included), and reset starts from scratch: the same outputs twice; a start time other than 0 keys the hulls by
    absolute time."""
    system = tank_chain(4, 1)
    seq = [np.array([0.1]), None, np.array([0.3]), [Packet(1, np.array([0.2]))], np.array([0.25]), None,
           np.array([0.0]), np.array([0.1]), None, np.array([0.2])]
    est = ExactSetEstimator(system, 0.5, max_delay=2, window=3, prior=prior)
    outs = []
    for t0 in (0, 0, 7):
        est.reset(np.zeros(4), t0=t0)
        run = []
        for y in seq:
            if isinstance(y, list):
                y = [Packet(p.time + t0, p.y) for p in y]
            run.append(est.step(y))
            before = pickle.dumps(est)
            with pytest.raises(InputError):
                est.step(np.array([np.nan]))
            assert pickle.dumps(est) == before
        outs.append(run)
    for runs in (outs[1], outs[2]):
        for (a, ba), (b, bb) in zip(outs[0], runs):
            assert np.array_equal(a, b) and ba == bb


def _lossy_arrivals(system, steps, seed):
    rng = np.random.default_rng(seed)
    trace = lossy_trace(seed, steps)
    n = system.n
    x, y, arrivals = simulate(system, trace, np.zeros(n), 0.5 * rng.uniform(-1, 1, n),
                              rng.uniform(-1, 1, (steps, system.nw)), rng.uniform(-1, 1, (steps, system.nv)))
    return x, arrivals


@pytest.mark.parametrize("plant", [eqrec.two_mass, lambda: tank_chain(4, 1)], ids=["carts", "tanks4"])
def test_warm_start_across_steps_same_hulls_fewer_pivots(plant):
    """The LPs started from the previous window's basis (the default) give the hulls of the slack-basis start to
    1e-7 of their width, predicted and filtered, with fewer pivots; every step with data after the first is
    warm-started."""
    system = plant()
    x, arrivals = _lossy_arrivals(system, 50, 4)
    ests = {w: ExactSetEstimator(system, 0.5, max_delay=2, window=20, warm_start=w).reset(np.zeros(system.n))
            for w in (False, True)}
    with_rows = 0  # steps whose window has measured rows (the others solve no LP)
    for t, a in enumerate(arrivals):
        for e in ests.values():
            e.step(a)
        cold, warm = ests[False], ests[True]
        with_rows += warm._ws.M.shape[0] > 0
        for S, T in ((cold.predicted, warm.predicted), (cold.filtered, warm.filtered)):
            tol = 1e-7 * (S.upper - S.lower)
            assert np.all(np.abs(S.lower - T.lower) <= tol) and np.all(np.abs(S.upper - T.upper) <= tol)
        assert np.all(warm.predicted.lower <= x[t + 1]) and np.all(x[t + 1] <= warm.predicted.upper)
    assert ests[True].lp_warm_starts == with_rows - 1 and ests[False].lp_warm_starts == 0
    assert ests[True].lp_pivots < ests[False].lp_pivots, (ests[True].lp_pivots, ests[False].lp_pivots)
    assert ests[True].lp_fallbacks == ests[False].lp_fallbacks == 0


def test_warm_start_pickled_copy_steps_the_same_and_reset_forgets_the_basis():
    """The carried basis is part of the state: a pickled copy steps exactly as the original; reset drops it (the
    run after reset repeats the first run bit for bit, its first step from the slack basis)."""
    system = eqrec.two_mass()
    _, arrivals = _lossy_arrivals(system, 30, 6)
    est = ExactSetEstimator(system, 0.5, max_delay=2, window=12).reset(np.zeros(4))
    first = [est.step(a) for a in arrivals[:15]]
    assert est._lp_carry is not None
    copy = pickle.loads(pickle.dumps(est))
    for a in arrivals[15:]:
        (x1, b1), (x2, b2) = est.step(a), copy.step(a)
        assert np.array_equal(x1, x2) and b1 == b2
        assert np.array_equal(est.filtered.lower, copy.filtered.lower)
    est.reset(np.zeros(4))
    assert est._lp_carry is None and est.lp_warm_starts == 0 and est.lp_pivots == 0
    again = [est.step(a) for a in arrivals[:15]]
    for (a, ba), (b, bb) in zip(first, again):
        assert np.array_equal(a, b) and ba == bb


def test_a_wrong_carried_basis_costs_pivots_never_the_guarantee(monkeypatch):
    """A deliberately bad start at every step (a random wanted set and random bound sides in place of the carried
    basis): every end is still a guarantee (the true state inside, no tolerance; the exact hull inside, the
    reference's tolerance) and the hull is the good start's to 1e-7 of its width."""
    import eqrec.estimators.exact_set as exact_module

    system = eqrec.two_mass()
    rng = np.random.default_rng(8)
    _, arrivals = _lossy_arrivals(system, 40, 9)
    x, _ = _lossy_arrivals(system, 40, 9)

    def bad(old_labels, old_basis, labels):
        size = labels[0].shape[0] + labels[1].shape[0]
        return rng.random(size) < 0.5, rng.random(size) < 0.5

    good = ExactSetEstimator(system, 0.5, max_delay=2, window=15).reset(np.zeros(4))
    good_out = [(good.step(a), good.predicted) for a in arrivals]
    monkeypatch.setattr(exact_module, "carry_basis", bad)
    est = ExactSetEstimator(system, 0.5, max_delay=2, window=15).reset(np.zeros(4))
    for t, a in enumerate(arrivals):
        est.step(a)
        S, G = est.predicted, good_out[t][1]
        assert np.all(S.lower <= x[t + 1]) and np.all(x[t + 1] <= S.upper)
        tol = 1e-7 * (G.upper - G.lower)
        assert np.all(np.abs(S.lower - G.lower) <= tol) and np.all(np.abs(S.upper - G.upper) <= tol)
    assert est.lp_warm_starts > 0



def test_a_wrong_carried_basis_keeps_error_within_bound_at_box_corners(monkeypatch):
    """The bad start of the test above at every step, with the noise at random corners of its box and the initial
    error at a corner: error <= bound at every step in floating point, no tolerance (the ends are the weak-duality
    bounds of whatever multipliers the solve ends with)."""
    import eqrec.estimators.exact_set as exact_module

    rng = np.random.default_rng(11)

    def bad(old_labels, old_basis, labels):
        size = labels[0].shape[0] + labels[1].shape[0]
        return rng.random(size) < 0.5, rng.random(size) < 0.5

    monkeypatch.setattr(exact_module, "carry_basis", bad)
    system = eqrec.two_mass()
    N = 60
    for seed in range(2):
        est = ExactSetEstimator(system, 0.5, max_delay=2, window=10)
        out = corner_run(system, est, seed, N)
        assert est.lp_warm_starts > 0
        assert np.all(np.abs(out.error[1:]).max(axis=1) <= out.bound)

def test_window_kernel_matches_a_plain_propagation():
    """The compiled window (explicit loops) against the states propagated in plain NumPy: x(t+1) and x(t) in ζ and
    the measured rows, to 1e-13."""
    rng = np.random.default_rng(12)
    L, n, p, nw, nv, q0 = 7, 3, 2, 2, 1, 4
    A = rng.normal(size=(L, n, n)) * 0.6
    C, E, V = rng.normal(size=(L, p, n)), rng.normal(size=(L, n, nw)), rng.normal(size=(L, p, nv))
    drive, Y = rng.normal(size=(L, n)), rng.normal(size=(L, p))
    measured = np.array([True, False, True, True, False, True, True])
    c0, G0 = rng.normal(size=n), rng.normal(size=(n, q0))
    ws = window_set(A, C, E, V, drive, measured, Y, c0, G0)
    Q = q0 + L * nw + measured.sum() * nv
    xc, X = c0.copy(), np.concatenate([G0, np.zeros((n, Q - q0))], axis=1)
    rows, r, col_v = [], [], q0 + L * nw
    for j in range(L):
        if j == L - 1:
            xf, Xf = xc.copy(), X.copy()
        if measured[j]:
            H = C[j] @ X
            H[:, col_v:col_v + nv] = V[j]
            col_v += nv
            rows.append(H)
            r.append(Y[j] - C[j] @ xc)
        X = A[j] @ X
        X[:, q0 + j * nw:q0 + (j + 1) * nw] = E[j]
        xc = A[j] @ xc + drive[j]
    for got, want in ((ws.centre_pred, xc), (ws.X_pred, X), (ws.centre_filt, xf), (ws.X_filt, Xf),
                      (ws.M, np.concatenate(rows)), (ws.lower, np.concatenate(r))):
        np.testing.assert_allclose(got, want, rtol=0, atol=1e-13 * (1 + np.abs(want).max()))


def test_carried_basis_keeps_the_priors_columns_and_rows_by_place():
    """window_labels names the prior's generators and rows by their place (negative labels, never a noise's or an
    output's); carry_basis gives them the status of the previous prior's in the same place, a common noise column
    and measured row keep theirs, a new column is nonbasic at its lower bound and a new row's slack basic."""
    from eqrec.bounds.window_lp import carry_basis, window_labels

    measured = np.array([True, False, True])
    cols, rows = window_labels(7, measured, 1, 1, 1, 3, 2)  # q0 = 3 generators, 2 prior rows
    assert list(cols[:3]) == [-1, -2, -3] and list(rows[:2]) == [-1, -2]
    assert np.all(cols[3:] >= 0) and np.all(rows[2:] >= 0)
    new_cols, new_rows = window_labels(8, measured, 1, 1, 1, 3, 2)  # the window one step later
    Qo, Qn = cols.size, new_cols.size
    basic = np.zeros(Qo + rows.size, bool)
    upper = np.zeros(Qo + rows.size, bool)
    basic[1] = True  # the prior's second generator basic, its third at its upper bound
    upper[2] = True
    basic[Qo + 0] = False  # the first prior row's slack nonbasic, the second basic
    basic[Qo + 1] = True
    w_idx = int(np.flatnonzero(cols == 8 * 2 + 0)[0])  # w(8): in both windows
    basic[w_idx] = True
    want, up = carry_basis((cols, rows), (basic, upper), (new_cols, new_rows))
    assert want[1] and not want[0] and not want[2] and up[2] and not up[1]
    assert not want[Qn + 0] and want[Qn + 1]
    assert want[int(np.flatnonzero(new_cols == 8 * 2 + 0)[0])]
    newest = int(np.flatnonzero(new_cols == 10 * 2 + 0)[0])  # w(10): new to the window
    assert not want[newest] and not up[newest]
    newest_row = int(np.flatnonzero(new_rows == 10)[0])  # y(10): a new row, its slack basic
    assert want[Qn + newest_row]
