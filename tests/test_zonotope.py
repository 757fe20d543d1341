"""The zonotopic set-membership estimator (:mod:`eqrec.estimators.zonotope`) and its exact window
(:mod:`eqrec.bounds.window`): guarantee, late packets, reduction, atomicity, the window against an LP."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import linprog

import eqrec
from eqrec.arrivals.draws import bernoulli_trace, with_uniform_delays
from eqrec.arrivals.packets import Packet
from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.errors import InputError
from eqrec.estimators.protocol import Estimator
from eqrec.estimators.zonotope import ZonotopeEstimator, reduce_girard, reduce_pca
from eqrec.simulate.loop import closed_loop
from eqrec.systems.examples import tank_chain


def rotating_plant() -> eqrec.AffineSystem:
    """A lightly damped rotation with negative entries, two outputs sharing one noise channel (V not diagonal)."""
    th = 0.3
    A = 0.99 * np.array([[np.cos(th), -np.sin(th), 0.0], [np.sin(th), np.cos(th), 0.0], [0.0, 0.2, -0.8]])
    return eqrec.AffineSystem(A=A, C=[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]], E=[[0.1, 0.0], [0.0, 0.05], [0.02, 0.0]],
                              eta_w=1.0, eta_v=0.05, V=[[1.0, 0.5], [0.0, 1.0]], B=[[0.0], [1.0], [0.0]])


PLANTS = {"two_mass": eqrec.two_mass, "rotation": rotating_plant}


def lossy_trace(seed: int, steps: int, loss: float = 0.3, max_delay: int = 2) -> ArrivalTrace:
    rng = np.random.default_rng(seed)
    return with_uniform_delays(rng, bernoulli_trace(rng, steps, loss), max_delay)


def run(system, est, trace, xi0, w, v, x0=None):
    """``closed_loop`` recording the per-state bounds after every step."""
    bounds = []
    x0 = np.zeros(system.n) if x0 is None else x0
    out = closed_loop(system, est, trace, x0, xi0, w, v, after_step=lambda k: bounds.append(est.state_bounds),
                      u_at=lambda k, xhat: np.array([np.sin(0.1 * k)] * system.m))
    return out, np.array(bounds)


def test_protocol_and_names():
    est = ZonotopeEstimator(eqrec.two_mass(), x0_radius=0.5, max_delay=2, order=20)
    assert (est.kind, est.name) == ("guaranteed", "set-membership, zonotope")
    assert est.reset(np.zeros(4)) is est and est.time == 0
    assert isinstance(est, Estimator)  # after reset: before it, reading time or x raises InputError, as the filters'
    xhat, bound = est.step(np.array([0.1]), np.array([0.0]))
    assert xhat.shape == (4,) and isinstance(bound, float) and est.time == 1
    assert bound == est.state_bounds.max() and np.array_equal(est.x, xhat)
    assert eqrec.ZonotopeEstimator is ZonotopeEstimator


@pytest.mark.parametrize("plant", PLANTS)
@pytest.mark.parametrize("gain, window, iterations", [(("fradius", "reweighted"), 20, 2), ("fradius", 20, 2),
                                                      ("reweighted", 20, 2), ("reweighted", 1, 0),
                                                      ("reweighted", 6, 5)])
def test_guarantee_at_random_box_corners_with_losses_and_delays(plant, gain, window, iterations):
    system = PLANTS[plant]()
    assert np.any(system.A < 0) and np.any(np.abs(np.linalg.eigvals(system.A).imag) > 0)
    N, r0 = 80, 0.5
    for seed in range(4):
        rng = np.random.default_rng(seed)
        trace = lossy_trace(seed, N)
        w = system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw))
        v = system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv))
        xi0 = r0 * rng.choice([-1.0, 1.0], system.n)
        est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=3, gain=gain, window=window,
                                iterations=iterations)
        out, beta = run(system, est, trace, xi0, w, v, x0=rng.normal(size=system.n))
        err = np.abs(out.error[1:])
        assert np.all(err <= beta)  # exact, per state: no tolerance on the guarantee side
        assert np.all(err.max(axis=1) <= out.bound)


def error_map(system, trace, make, N):
    """The exact linear map from the unit noise ``(ξ0, w, v)`` to the final error (unit perturbations)."""
    n, nw, nv = system.n, system.nw, system.nv
    cols, radii = [], []
    for kind, size, radius in (("x0", n, 0.5), ("w", N * nw, system.eta_w), ("v", N * nv, system.eta_v)):
        for k in range(size):
            xi0, w, v = np.zeros(n), np.zeros((N, nw)), np.zeros((N, nv))
            {"x0": xi0.reshape(-1), "w": w.reshape(-1), "v": v.reshape(-1)}[kind][k] = radius
            out = closed_loop(system, make(), trace, xi0, xi0, w, v)
            cols.append(out.error[-1])
            radii.append((kind, k, radius))
    return np.array(cols).T, radii


@pytest.mark.parametrize("plant", PLANTS)
@pytest.mark.parametrize("order", [None, 10])
@pytest.mark.parametrize("gain", ["fradius", ("fradius", "reweighted")])
def test_played_back_worst_case(plant, order, gain):
    """The worst state's bound is attained (no reduction) or not exceeded (with reduction) by its worst vertex."""
    system = PLANTS[plant]()
    N = 25
    trace = lossy_trace(7, N)

    def make():
        return ZonotopeEstimator(system, x0_radius=0.5, max_delay=2, order=order, gain=gain)

    M, radii = error_map(system, trace, make, N)
    est = make()
    out = closed_loop(system, est, trace, np.zeros(system.n), np.zeros(system.n), np.zeros((N, system.nw)),
                      np.zeros((N, system.nv)))
    beta = est.state_bounds
    i = int(np.argmax(beta))
    s = np.sign(M[i])  # the vertex that maximises error i
    xi0, w, v = np.zeros(system.n), np.zeros((N, system.nw)), np.zeros((N, system.nv))
    for sign, (kind, k, radius) in zip(s, radii):
        {"x0": xi0.reshape(-1), "w": w.reshape(-1), "v": v.reshape(-1)}[kind][k] = sign * radius
    est = make()
    out = closed_loop(system, est, trace, xi0, xi0, w, v)
    err = abs(out.error[-1][i])
    assert err <= est.state_bounds[i]  # exact
    if order is None:  # tolerance: the bound carries a rounding allowance of a few ulps (module docstring)
        assert err >= est.state_bounds[i] * (1 - 1e-9)
    else:  # the reduction is outer: the bound may be loose, but not absurdly
        assert err >= 0.5 * est.state_bounds[i]


def test_late_packet_equals_on_time_use():
    """A packet used late (by the window) gives bit for bit the estimate it would have given on time."""
    system = eqrec.two_mass()
    ys = [np.array([0.1 * k]) for k in range(6)]
    late = ZonotopeEstimator(system, 0.5, max_delay=2, order=None).reset(np.zeros(4))
    ontime = ZonotopeEstimator(system, 0.5, max_delay=2, order=None).reset(np.zeros(4))
    for k in range(6):
        if k == 2:
            late.step(None)
        elif k == 4:
            late.step([Packet(2, ys[2]), Packet(4, ys[4])])
        else:
            late.step(ys[k])
        ontime.step(ys[k])
    assert late.replays == 1 and late.dropped_packets == 0
    assert np.array_equal(late.x, ontime.x) and np.array_equal(late.generators, ontime.generators)


def test_old_packet_is_dropped_counted_and_ignored():
    system = eqrec.two_mass()
    ys = [np.array([0.05 * k]) for k in range(6)]
    est = ZonotopeEstimator(system, 0.5, max_delay=1, order=None).reset(np.zeros(4))
    ref = ZonotopeEstimator(system, 0.5, max_delay=1, order=None).reset(np.zeros(4))
    for k in range(6):
        arrived = None if k == 1 else ys[k]
        est.step([Packet(1, ys[1]), Packet(4, ys[4])] if k == 4 else arrived)  # y(1) three steps late: D = 1
        ref.step(arrived)
    assert est.dropped_packets == 1 and est.replays == 0
    assert np.array_equal(est.x, ref.x) and np.array_equal(est.state_bounds, ref.state_bounds)
    # and the run stays guaranteed when old packets are dropped (D = 0 with delays up to 2)
    N = 60
    rng = np.random.default_rng(3)
    trace = lossy_trace(3, N)
    est = ZonotopeEstimator(system, 0.5, max_delay=0, order=10)
    out, beta = run(system, est, trace, 0.5 * rng.choice([-1.0, 1.0], 4), rng.choice([-1.0, 1.0], (N, 2)),
                    0.05 * rng.choice([-1.0, 1.0], (N, 1)))
    assert est.dropped_packets == int(np.sum((trace.delays > 0) & (np.arange(N) + trace.delays < N)))
    assert np.all(np.abs(out.error[1:]) <= beta)


@pytest.mark.parametrize("reduce", [reduce_girard, reduce_pca])
def test_reduction_is_outer(reduce):
    rng = np.random.default_rng(0)
    for _ in range(20):
        n = int(rng.integers(2, 6))
        G = rng.normal(size=(n, 40)) * rng.exponential(size=40)
        R = reduce(G, 3 * n)
        assert R.shape[1] <= 3 * n
        assert np.all(np.abs(R).sum(axis=1) >= np.abs(G).sum(axis=1))  # interval hull not smaller
        D = rng.normal(size=(200, n))
        assert np.all(np.abs(D @ R).sum(axis=1) >= np.abs(D @ G).sum(axis=1))  # support functions not smaller
    assert reduce(G, 100) is G


def test_reduction_boxes_the_first_of_the_stable_sort():
    """The reduction's selection of the generators to box (np.partition) is the first ``nbox`` of the stable sort
    of their costs: ties broken by the lower index, NaN costs last, -0.0 equal to 0.0."""
    from eqrec.bounds.zonotope import _smallest

    rng = np.random.default_rng(5)
    for trial in range(400):
        q = int(rng.integers(1, 40))
        cost = rng.integers(0, 4, q).astype(float) if trial % 2 else rng.normal(size=q)  # many ties, or none
        if trial % 5 == 0:
            cost[rng.integers(0, q, 3)] = np.nan
        if trial % 7 == 0:
            cost[cost == 0.0] = -0.0
        for nbox in range(-1, q + 2):
            want = np.zeros(q, dtype=bool)
            want[np.argsort(cost, kind="mergesort")[:max(nbox, 0)]] = True
            assert np.array_equal(_smallest(cost, nbox), want), (cost, nbox)


def test_girard_of_one_zonotope_is_the_stack_path():
    """reduce_girard of one zonotope (one compiled call) gives the bytes of the stack's reduction of a stack of
    one, and of that reduction with its zero box columns dropped (there are none: each box is rounded up), the
    path it replaces."""
    from eqrec.bounds.zonotope import _reduce

    rng = np.random.default_rng(3)
    for trial in range(300):
        n = int(rng.integers(1, 7))
        q = int(rng.integers(n + 1, 60))
        limit = int(rng.integers(n, q))
        G = rng.normal(size=(n, q))
        if trial % 3 == 0:
            G[rng.integers(0, n), :] = 0.0
        if trial % 4 == 0:
            G = np.asfortranarray(G)
        stack = _reduce(np.ascontiguousarray(G)[None], limit, principal=False)[0]
        kept = stack.shape[1] - n
        expected = np.concatenate([stack[:, :kept], stack[:, kept:][:, np.any(stack[:, kept:] != 0, axis=0)]], axis=1)
        got = reduce_girard(G, limit)
        assert stack.tobytes() == np.ascontiguousarray(expected).tobytes()
        assert got.shape == expected.shape and got.tobytes() == np.ascontiguousarray(expected).tobytes()


def state_of(est):
    return (est.time, est.x, est.generators, est.state_bounds, est.dropped_packets, est.replays,
            est._known.copy(), est._y.copy(), est._drive.copy(), est.carried_set[1])


def same(a, b):
    return all(np.array_equal(p, q) if isinstance(p, np.ndarray) else p == q for p, q in zip(a, b))


def test_atomic_errors():
    system = eqrec.two_mass()
    est = ZonotopeEstimator(system, 0.5, max_delay=2, order=10)
    with pytest.raises(InputError):
        est.step(None)  # before reset
    est.reset(np.zeros(4))
    est.step(np.array([0.1]))
    est.step(None)
    before = state_of(est)
    bad = [
        (dict(y=np.array([np.nan])), "y"),
        (dict(y=np.array([0.1]), u=np.array([np.inf])), "u"),
        (dict(y=[Packet(5, np.array([0.1]))]), "y"),  # from the future
        (dict(y=[Packet(0, np.array([0.1]))]), "y"),  # stamp 0 received twice
        (dict(y=[Packet(1, np.array([0.1])), Packet(2, np.array([np.nan]))]), "y"),
        (dict(y=np.array([0.1, 0.2])), "y"),
    ]
    for kwargs, field in bad:
        with pytest.raises(InputError) as info:
            est.step(**kwargs)
        assert info.value.field == field
        assert same(state_of(est), before)
    with pytest.raises(InputError) as info:
        est.reset(np.array([0.0, np.nan, 0.0, 0.0]))
    assert info.value.field == "xhat0" and same(state_of(est), before)


@pytest.mark.parametrize("kwargs, field", [
    (dict(x0_radius=-1.0), "x0_radius"), (dict(x0_radius=[1.0, 2.0]), "x0_radius"),
    (dict(x0_radius=np.nan), "x0_radius"), (dict(max_delay=-1), "max_delay"), (dict(max_delay=1.5), "max_delay"),
    (dict(order=0.5), "order"), (dict(order=True), "order"), (dict(gain="kalman"), "gain"), (dict(gain=()), "gain"),
    (dict(gain=("fradius", "fradius")), "gain"), (dict(gain=("fradius", 3)), "gain"),
    (dict(reduction="none"), "reduction"), (dict(gain="interval"), "gain"), (dict(window=0), "window"),
    (dict(window=2.5), "window"), (dict(iterations=-1), "iterations"), (dict(iterations="2"), "iterations"),
    (dict(window_generators=0), "window_generators"), (dict(window_generators=2.5), "window_generators"),
    (dict(window_generators=True), "window_generators"),
])
def test_constructor_checks(kwargs, field):
    with pytest.raises(InputError) as info:
        ZonotopeEstimator(eqrec.two_mass(), **kwargs)
    assert info.value.field == field


def reference_limit(system, trace, r0):
    """The information limit by one scipy LP per state and step (the zero-data problem), a small independent check."""
    n, nw, nv, N = system.n, system.nw, system.nv, trace.steps
    arrival = trace.arrival_times()
    out = np.zeros((N, n))
    for t in range(N):
        T = t + 1  # x(0..T); variables: x(0) (n), w(0..t) (T nw), v(0..t) (T nv)
        nvar = n + T * nw + T * nv
        Phi = [np.hstack([np.eye(n), np.zeros((n, nvar - n))])]
        for k in range(T):
            row = system.A @ Phi[-1]
            row[:, n + k * nw:n + (k + 1) * nw] += system.eta_w * system.E
            Phi.append(row)
        eq = []
        for tau in range(T):
            if arrival[tau] != NEVER and arrival[tau] <= t:
                row = system.C @ Phi[tau]
                row[:, n + T * nw + tau * nv:n + T * nw + (tau + 1) * nv] += system.eta_v * system.V
                eq.append(row)
        A_eq = np.vstack(eq) if eq else None
        bounds = [(-r0, r0)] * n + [(-1, 1)] * (T * (nw + nv))
        for i in range(n):
            res = linprog(-Phi[T][i], A_eq=A_eq, b_eq=None if A_eq is None else np.zeros(A_eq.shape[0]),
                          bounds=bounds, method="highs")
            out[t, i] = -res.fun
    return out


@pytest.mark.parametrize("gain", [("fradius", "reweighted"), "reweighted"])
def test_bound_never_below_the_information_limit(gain):
    system, N, r0 = eqrec.two_mass(), 20, 0.5
    trace = lossy_trace(11, N)
    lim = reference_limit(system, trace, r0)
    est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=10, gain=gain)
    out, beta = run(system, est, trace, np.zeros(4), np.zeros((N, 2)), np.zeros((N, 1)))
    # tolerance on the limit's side only: the LP is solved to ~1e-9 (at step 0 the bound equals the limit)
    assert np.all(out.bound >= lim.max(axis=1) * (1 - 1e-7))
    assert np.all(beta >= lim * (1 - 1e-7) - 1e-12)


def test_two_mass_file_is_the_constructor():
    loaded, T = eqrec.load_system("examples/two_mass.yaml")
    built = eqrec.two_mass()
    assert T is None and loaded.n == 4 and loaded.p == 1
    for key in ("A", "B", "C", "E", "V"):
        assert np.allclose(getattr(loaded, key), getattr(built, key), rtol=0, atol=1e-15), key
    assert (loaded.eta_w, loaded.eta_v) == (built.eta_w, built.eta_v)


@pytest.mark.parametrize("plant", PLANTS)
def test_two_gains_report_per_state_the_tighter_filter(plant):
    """With two gains, both filters run on the same data, the window on each, and per state the estimate and
    bound of the tighter one are reported: bit for bit what that gain alone gives for that state."""
    system, N, r0 = PLANTS[plant](), 60, 0.5
    trace = lossy_trace(5, N)
    rng = np.random.default_rng(3)
    noise = (r0 * rng.choice([-1.0, 1.0], system.n), system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw)),
             system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv)))
    runs = {}
    for gain in ("fradius", "reweighted", ("fradius", "reweighted")):
        est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=10, gain=gain, reduction="girard")
        out, beta = run(system, est, trace, *noise)
        runs[gain] = (out.xhat[1:], beta)
    (xf, bf), (xr, br), (xb, both) = runs["fradius"], runs["reweighted"], runs[("fradius", "reweighted")]
    assert np.array_equal(both, np.minimum(bf, br))
    assert np.array_equal(xb, np.where(br < bf, xr, xf))
    est = ZonotopeEstimator(system, x0_radius=r0, order=10, gain="fradius").reset(np.ones(system.n))
    assert np.array_equal(est.x, np.ones(system.n)) and est.generators.shape == (1, system.n, system.n)


def test_more_iterations_never_loosen_the_window():
    """Every reweighted solve's estimate is valid and the tightest is kept, so more solves never widen a bound."""
    system, N, r0 = eqrec.two_mass(), 50, 0.5
    trace = lossy_trace(2, N)
    zero = (np.zeros(system.n), np.zeros((N, system.nw)), np.zeros((N, system.nv)))
    bounds = []
    for iterations in (0, 1, 2, 4):
        est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=10, iterations=iterations)
        bounds.append(run(system, est, trace, *zero)[1])
    for loose, tight in zip(bounds, bounds[1:]):
        assert np.all(tight <= loose)
    assert np.mean(bounds[-1].max(axis=1) < bounds[0].max(axis=1) * (1 - 1e-3)) > 0.5


def window_lp(system, G0, first, t, known):
    """The window's radius of information by one scipy LP per state: ``max x_i(t+1)`` over the zonotope
    ``G0 ε`` at ``first``, the noise, and zero data on the known times (independent of the kernel)."""
    n, nw, nv, q0, L = system.n, system.nw, system.nv, G0.shape[1], t + 1 - first
    A, C, E, V = system.A, system.C, system.eta_w * system.E, system.eta_v * system.V
    nvar = q0 + L * nw + L * nv
    X = np.zeros((n, nvar))
    X[:, :q0] = G0
    eq = []
    for j in range(L):
        if known[j]:
            row = C @ X
            row[:, q0 + L * nw + j * nv:q0 + L * nw + (j + 1) * nv] = V
            eq.append(row)
        X = A @ X
        X[:, q0 + j * nw:q0 + (j + 1) * nw] += E
    A_eq = np.vstack(eq) if eq else None
    out = np.empty(n)
    for i in range(n):
        res = linprog(-X[i], A_eq=A_eq, b_eq=None if A_eq is None else np.zeros(A_eq.shape[0]), bounds=(-1, 1),
                      method="highs")
        out[i] = -res.fun
    return out


@pytest.mark.parametrize("plant", PLANTS)
def test_window_against_an_independent_lp(plant):
    """The window's bound is never below the LP's radius of information over the same window and zonotope (the
    smallest any estimate can have), per state; with enough reweighted solves the reported bound (the largest,
    whose states are solved one by one) comes within one per cent of the LP's, and every state (the others from
    the shared solves) within a few per cent."""
    system, N, r0 = PLANTS[plant](), 40, 0.5
    trace = lossy_trace(9, N)
    sched = trace.schedule()
    ys = np.zeros((N, system.p))
    from eqrec.simulate.loop import what_arrived
    est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=6, window=8, iterations=12)
    est.reset(np.zeros(system.n))
    ratios, tops = [], []
    for t in range(N):
        G0 = est.generators[0]  # the filter's set at the window's start, before the step
        first_before = est.time - est._drive.shape[0]
        est.step(what_arrived(sched[t], t, ys), np.zeros(system.m))
        first = est.time - est._drive.shape[0]
        if first != first_before:
            G0 = est.generators[0]
        if t % 5 == 4:
            lp = window_lp(system, G0, first, t, est._known)
            assert np.all(est.state_bounds >= lp * (1 - 1e-9))
            ratios.append(est.state_bounds / lp)
            tops.append(est.state_bounds.max() / lp.max())
    assert np.median(tops) < 1.01
    assert np.median(np.concatenate(ratios)) < 1.05


def test_carried_set_contains_the_state():
    """The reported set ``x̂ + G ε`` contains the true state (an LP finds ``ε`` with ``|ε| <= 1``) and its
    interval hull is the reported bound."""
    system, N, r0 = rotating_plant(), 30, 0.5
    rng = np.random.default_rng(4)
    trace = lossy_trace(4, N)
    est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=5, gain=("fradius", "reweighted"))
    checked = []

    def check(k):
        c, G = est.carried_set
        checked.append((k, c, G, est.state_bounds))

    out = closed_loop(system, est, trace, np.zeros(system.n), r0 * rng.choice([-1.0, 1.0], system.n),
                      system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw)),
                      system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv)), after_step=check)
    for k, c, G, beta in checked[::6]:
        assert np.all(np.abs(G).sum(axis=1) >= beta * (1 - 1e-15))
        res = linprog(np.zeros(G.shape[1]), A_eq=G, b_eq=out.x[k + 1] - c, bounds=(-1, 1), method="highs")
        assert res.status == 0


def test_time_varying_model_reads_the_window_per_time():
    """A time-varying model runs the window on the matrices of each time: with the same matrices at every time it
    gives bit for bit the time-invariant run, and a periodic model with rotations that differ by time (read at the
    period time) stays guaranteed on the plant it describes."""
    system = rotating_plant()
    T, N, r0 = 5, 40, 0.5

    def with_A(As):
        return eqrec.AffineSystem(A=np.stack(As), B=system.B, C=system.C, E=system.E, V=system.V,
                                  eta_w=system.eta_w, eta_v=system.eta_v)

    trace = lossy_trace(6, N)
    rng = np.random.default_rng(6)
    noise = (r0 * rng.choice([-1.0, 1.0], system.n), system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw)),
             system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv)))
    plain = run(system, ZonotopeEstimator(system, r0, max_delay=2, order=5, window=7), trace, *noise)
    stacked = with_A([system.A] * N)
    varying = run(stacked, ZonotopeEstimator(stacked, r0, max_delay=2, order=5, window=7), trace, *noise)
    assert np.array_equal(plain[0].xhat, varying[0].xhat) and np.array_equal(plain[1], varying[1])
    turns = [0.99 * np.array([[np.cos(a), -np.sin(a), 0.0], [np.sin(a), np.cos(a), 0.0], [0.0, 0.2, -0.8]])
             for a in (0.1, 0.5, 0.9, 1.3, -0.4)]
    plant, period = with_A(turns * (N // T)), with_A(turns)
    for seed in range(3):
        rng = np.random.default_rng(seed)
        noise = (r0 * rng.choice([-1.0, 1.0], system.n), system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw)),
                 system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv)))
        est = ZonotopeEstimator(period, r0, max_delay=2, order=5, window=7).periodic_model(T)
        out, beta = run(plant, est, lossy_trace(seed, N), *noise)
        assert np.all(np.abs(out.error[1:]) <= beta)


@pytest.mark.parametrize("gain", ["reweighted", ("fradius", "reweighted")])
def test_guarantee_on_a_larger_plant_shared_and_per_state_solves(gain):
    """n = 12, p = 3: the window's shared solves (one factorization for all states) and its per-state solves both
    give per-state bounds that hold exactly at box corners; more per-state solves never loosen them."""
    system, N, r0 = tank_chain(12, 3), 60, 0.5
    rng = np.random.default_rng(5)
    trace = lossy_trace(5, N)
    w = system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw))
    v = system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv))
    xi0 = r0 * rng.choice([-1.0, 1.0], system.n)
    bounds = []
    for iterations in (0, 3):
        est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=8, gain=gain, window=12,
                                iterations=iterations)
        out, b = run(system, est, trace, xi0, w, v)
        assert np.all(np.abs(out.error[1:]) <= b)  # per state, exactly
        bounds.append(b)
    assert np.all(bounds[1] <= bounds[0])


def _support_exact(G: np.ndarray, d: np.ndarray):
    """The support function ``sum_j |d^T g_j|`` of the centred zonotope ``G``, in exact rational arithmetic."""
    from fractions import Fraction

    dd = [Fraction(float(x)) for x in d]
    return sum(abs(sum(di * Fraction(float(gij)) for di, gij in zip(dd, G[:, j]))) for j in range(G.shape[1]))


@pytest.mark.parametrize("shrink", [1e-2, 1e-12, 64 * np.finfo(float).eps])
def test_pca_reduction_is_outer_in_exact_arithmetic_for_non_orthogonal_axes(shrink):
    """The reduced zonotope contains the original one, checked exactly (rational support functions), for axes
    that are not orthogonal: ``U = (1 - shrink) Q``.  Boxing ``U^T g`` in ``U`` alone shrinks the set along ``Q``'s
    columns by ``(1 - shrink)^2`` (a relative slack on the box does not cover it); the box of the change of axes'
    rounding (:func:`eqrec.bounds.zonotope.reduce_pca`) does, whatever ``U``."""
    rng = np.random.default_rng(5)
    for trial in range(4):
        n = 3
        G = rng.normal(size=(n, 24)) * rng.exponential(size=24)
        Q = np.linalg.qr(rng.normal(size=(n, n)))[0]
        U = (1.0 - shrink) * Q
        R = reduce_pca(G, 4 * n, axes=U)
        assert R.shape == (n, 4 * n)
        directions = list(Q.T) + list(np.eye(n)) + list(rng.normal(size=(6, n)))
        for d in directions:
            assert _support_exact(G, d) <= _support_exact(R, d), (trial, d)


def test_pca_reduction_rounding_box_is_tiny_for_principal_axes():
    """With the computed principal axes the box of the change of axes' rounding is a relative 1e-13 or less of the
    boxed generators' hull (it covers the floating point, not the method)."""
    rng = np.random.default_rng(6)
    n = 30
    G = rng.normal(size=(n, 600)) * rng.exponential(size=600)
    R = reduce_pca(G, 10 * n)
    d = np.diag(R[:, -n:])
    assert np.all(d > 0) and np.all(np.count_nonzero(R[:, -n:], axis=0) == 1)
    assert np.all(d <= 1e-13 * np.abs(G).sum(axis=1))


def test_reduce_pca_pair_is_two_reductions():
    """Both results of :func:`eqrec.bounds.zonotope.reduce_pca_pair` are those of :func:`reduce_pca` (the same
    numbers), and a limit not below the generators gives ``G`` itself."""
    from eqrec.bounds.zonotope import principal_axes, reduce_pca_pair

    rng = np.random.default_rng(8)
    G = rng.normal(size=(2, 5, 70)) * rng.exponential(size=70)
    U = principal_axes(G)
    a, b = reduce_pca_pair(G, 40, 15, axes=U)
    assert np.array_equal(a, reduce_pca(G, 40, axes=U)) and np.array_equal(b, reduce_pca(G, 15, axes=U))
    assert a.shape == (2, 5, 40) and b.shape == (2, 5, 15)
    a, b = reduce_pca_pair(G, 80, 15, axes=U)
    assert a is G and np.array_equal(b, reduce_pca(G, 15, axes=U))


@pytest.mark.parametrize("reduction", ["pca", "girard"])
def test_window_prior_reduced_stays_guaranteed_and_none_is_the_filters_set(reduction):
    """With a small ``window_generators`` the window starts from the filters' set reduced once more: at most that
    many generators (``>= 2n``), the guarantee holds exactly at random box corners, and the bound stays close to
    the one from the filters' own set (the reduced set contains the filters', but the window's weights are
    approximate, so either can be the smaller).  With ``None`` the prior is the filters' set."""
    system = rotating_plant()
    N, r0 = 60, 0.5
    rng = np.random.default_rng(11)
    trace = lossy_trace(11, N)
    w = system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw))
    v = system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv))
    xi0 = r0 * rng.choice([-1.0, 1.0], system.n)
    bounds = {}
    for wg in (None, 8):
        est = ZonotopeEstimator(system, x0_radius=r0, max_delay=2, order=10, reduction=reduction,
                                window_generators=wg)
        out, beta = run(system, est, trace, xi0, w, v)
        assert np.all(np.abs(out.error[1:]) <= beta)
        if wg is None:
            assert est._P is est._G
        else:
            assert est._P.shape[2] <= max(wg, 2 * system.n) and est._G.shape[2] > est._P.shape[2]
        bounds[wg] = out.bound
    assert 0.99 <= np.median(bounds[8] / bounds[None]) <= 1.10  # close: the weights are approximate, either way


# -- the window's linear algebra and its warm start (issue 45 §4) ------------------------------------------------
def _explicit_window(A, C, E, V, measured, G0):
    """The window's X (``x(t+1)`` on the unit uncertainty) and H (the measured outputs on it), column by column
    from unit runs: the prior's generators, then w by time, then v of the measured times."""
    L, n = A.shape[0], A.shape[1]
    p, nw, nv = C.shape[1], E.shape[2], V.shape[2]
    times = [j for j in range(L) if measured[j]]

    def run(x0, w_at=None, v_at=None):
        x, ys = x0.copy(), []
        for j in range(L):
            if measured[j]:
                ys.append(C[j] @ x + (v_at[1] if v_at is not None and v_at[0] == j else 0.0))
            x = A[j] @ x + (w_at[1] if w_at is not None and w_at[0] == j else 0.0)
        return x, (np.concatenate(ys) if ys else np.zeros(0))

    cols = [run(G0[:, q]) for q in range(G0.shape[1])]
    cols += [run(np.zeros(n), w_at=(j, E[j][:, q])) for j in range(L) for q in range(nw)]
    cols += [run(np.zeros(n), v_at=(j, V[j][:, q])) for j in times for q in range(nv)]
    X = np.column_stack([c[0] for c in cols])
    H = np.column_stack([c[1] for c in cols]) if times else np.zeros((0, len(cols)))
    return X, H


@pytest.mark.parametrize("duplicate", [False, True])
def test_window_kalman_weights_are_the_weighted_least_squares_ones(duplicate):
    """The window's weights from its Kalman filter (:func:`eqrec.bounds.window._kalman_gains`, read back by
    :func:`~eqrec.bounds.window._residuals`) are :math:`XWH^T(HWH^T)^{-1}`, and the residuals are
    :math:`X - \\lambda H`, against the explicit matrices of unit runs; with an output repeated without noise
    (``HWH^T`` singular) the fitted :math:`\\lambda H` is the pseudo-inverse's."""
    from eqrec.bounds.window import _kalman_gains, _residuals, sparse_columns, sparse_rows

    rng = np.random.default_rng(11)
    L, n, p, nw, nv, q0 = 7, 4, 2, 3, 2, 5
    A = rng.normal(scale=0.5, size=(L, n, n)) * (rng.random((L, n, n)) < 0.6)
    C = rng.normal(size=(L, p, n))
    E = rng.normal(size=(L, n, nw)) * (rng.random((L, n, nw)) < 0.7)
    V = rng.normal(scale=0.3, size=(L, p, nv))
    if duplicate:  # output 1 repeats output 0, with no noise on either
        C[:, 1] = C[:, 0]
        V[:, :, :] = 0.0
        V[:, :, 0] = 0.0
    measured = np.array([True, False, True, True, False, True, True])
    G0 = rng.normal(size=(n, q0))
    X, H = _explicit_window(A, C, E, V, measured, G0)
    W = rng.uniform(0.2, 5.0, size=X.shape[1])
    if duplicate:  # a noiseless output: the prior and process noise only
        W[q0 + L * nw:] = 0.0
    aptr, acol, aval = sparse_rows(A)
    eptr, erow, evals = sparse_columns(E)
    cptr, crow, cval = sparse_columns(A)
    times = int(measured.sum())
    K = np.zeros((times, p, n))
    _kalman_gains(A, C, E, V, measured, (G0 * W[:q0]) @ G0.T, W, q0, K, aptr, acol, aval, eptr, erow, evals)
    lamT = np.zeros((times * p, n))
    TT = np.eye(n)
    resT = np.empty((X.shape[1] - q0, n))
    _residuals(A, C, E, V, measured, K, lamT, TT, resT, cptr, crow, cval, eptr, erow, evals)
    M = (H * W) @ H.T
    lam_ref = (X * W) @ H.T @ np.linalg.pinv(M, rcond=1e-12, hermitian=True)
    fit, fit_ref = lamT.T @ H, lam_ref @ H
    assert np.allclose(fit, fit_ref, rtol=1e-9, atol=1e-9 * np.abs(X).max())
    if not duplicate:
        assert np.allclose(lamT.T, lam_ref, rtol=1e-9, atol=1e-9 * np.abs(lam_ref).max())
    R = X - lamT.T @ H  # the residuals the window reports: prior part T(0) G0, then the noise columns
    assert np.allclose(TT.T @ G0, R[:, :q0], rtol=1e-12, atol=1e-12 * np.abs(X).max())
    assert np.allclose(resT.T, R[:, q0:], rtol=1e-12, atol=1e-12 * np.abs(X).max())


def test_window_prior_covariance_in_single_precision_and_the_symmetric_products():
    """The prior covariance :math:`G_0 W G_0^T` the window's weights start from (single precision: it only sets the
    weights) is the double-precision product to single precision's rounding; the symmetric product of a propagation
    (``lower=True``) is the full product, its upper triangle mirrored from the lower."""
    from eqrec.bounds.window import _prior_covariance, _single, _times_sparse, sparse_rows

    rng = np.random.default_rng(5)
    n, q0 = 6, 40
    G1 = rng.normal(size=(n, q0))
    W1 = rng.uniform(0.01, 1.0, size=q0 + 9)  # the prior's weights first, then the noise columns'
    # far outside single precision's range (1e38), both ways: the scalings by powers of two keep it
    for G0, W in ((G1, W1), (1e100 * G1, 1e-100 * W1), (1e-100 * G1, W1), (1e150 * G1, 1e-30 * W1)):
        GT32, inv, colmax = _single(G0)
        S = _prior_covariance(G0, GT32, inv, colmax, W, np.empty((n, q0), dtype=np.float32))
        ref = (G0 * W[:q0]) @ G0.T
        scale = (np.abs(G0) * W[:q0]) @ np.abs(G0).T
        assert S.dtype == np.float64
        assert np.all(np.abs(S - ref) <= 1e-5 * scale)
        assert np.abs(S - ref).max() > 0.0  # (single precision indeed)
    ref = (G1 * W1[:q0]) @ G1.T
    A = rng.normal(size=(2, n, n)) * (rng.random((2, n, n)) < 0.5)
    aptr, acol, aval = sparse_rows(A)
    Sig = ref.copy()
    tmp = np.empty((n, n))
    out = np.full((n, n), np.nan)
    _times_sparse(aptr, acol, aval, 1, Sig, n, tmp)
    _times_sparse(aptr, acol, aval, 1, tmp.T, n, out, True)
    full = A[1] @ ref @ A[1].T
    assert np.allclose(out, full, rtol=1e-12, atol=1e-12 * np.abs(full).max())
    assert np.array_equal(out, out.T)


def test_warm_weights_map_the_last_window_by_distance_from_its_end():
    from eqrec.bounds.window import _warm_weights

    rng = np.random.default_rng(4)
    n, q0p, q0, nw, nv, L, delta = 3, 5, 4, 2, 1, 6, 0.01
    known_prev = np.array([True, False, True, True, False, True])
    known = np.array([False, True, True, False, True, True])  # the window slid by one; the last time measured
    times_p = int(known_prev.sum())
    row = rng.uniform(0.5, 2.0, q0p + L * nw + times_p * nv)
    G0 = rng.normal(size=(n, q0))
    Tm = rng.normal(size=(2, n))
    scale = np.array([0.5, 2.0])
    W = np.empty(q0 + L * nw + int(known.sum()) * nv)
    _warm_weights(row, Tm, scale, known_prev, known, G0, nw, nv, delta, W)
    a = np.empty_like(W)
    a[:q0] = (np.abs(Tm @ G0) * scale[:, None]).sum(axis=0)
    a[q0:q0 + L * nw] = row[q0p:q0p + L * nw]  # the same distance from the end: the same position (equal lengths)
    v_old = row[q0p + L * nw:]  # by the last window's measured times 0, 2, 3, 5
    # the new measured positions 1, 2, 4, 5 -> the nearest old measured 0 (tie with 2: the earlier), 2, 3 (tie with
    # 5: the earlier), 5
    a[q0 + L * nw:] = v_old[[0, 1, 2, 3]]
    expected = 1.0 / np.maximum(a, delta * a.max())
    assert np.allclose(W, expected, rtol=1e-14, atol=0.0)
    # a longer new window: its oldest times take the last window's oldest
    W2 = np.empty(q0 + (L + 2) * nw + int(known.sum()) * nv)
    known2 = np.concatenate([[False, False], known])
    _warm_weights(row, Tm, scale, known_prev, known2, G0, nw, nv, delta, W2)
    aw = 1.0 / np.maximum(np.concatenate([row[q0p:q0p + nw]] * 2 + [row[q0p:q0p + L * nw]]), delta * a.max())
    assert np.allclose(W2[q0:q0 + (L + 2) * nw], aw, rtol=1e-14, atol=0.0)


def test_warm_start_changes_nothing_until_the_window_is_full_then_stays_as_tight():
    system = eqrec.two_mass()
    N, W = 120, 30
    trace = lossy_trace(11, N)
    rng = np.random.default_rng(11)
    w = system.eta_w * rng.choice([-1.0, 1.0], (N, system.nw))
    v = system.eta_v * rng.choice([-1.0, 1.0], (N, system.nv))
    xi0 = 0.5 * rng.choice([-1.0, 1.0], system.n)
    outs = {}
    for warm in (True, False):
        est = ZonotopeEstimator(system, x0_radius=0.5, max_delay=2, window=W, warm_start=warm)
        outs[warm], beta = run(system, est, trace, xi0, w, v)
        assert np.all(np.abs(outs[warm].error[1:]) <= beta)  # guaranteed either way, per state, exactly
    hot, cold = np.asarray(outs[True].bound), np.asarray(outs[False].bound)
    assert np.array_equal(hot[:W], cold[:W])  # the window still growing: both start cold
    assert not np.array_equal(hot[W + 1:], cold[W + 1:])  # then the carried weights are used
    assert 0.98 <= np.median(hot[W:] / cold[W:]) <= 1.02  # and the bound stays as tight
    again = ZonotopeEstimator(system, x0_radius=0.5, max_delay=2, window=W, warm_start=True)
    run(system, again, trace, xi0, w, v)
    replay, _ = run(system, again, trace, xi0, w, v)  # reset drops the carried weights: the same run again
    assert np.array_equal(np.asarray(replay.bound), hot)


def test_warm_start_must_be_a_bool():
    with pytest.raises(InputError, match="warm_start") as err:
        ZonotopeEstimator(eqrec.two_mass(), x0_radius=0.5, warm_start="yes")
    assert err.value.field == "warm_start"


def test_a_warm_window_whose_last_window_measured_nothing_starts_cold():
    """With nothing measured in the last window there are no weights to carry for the new measurement: the window
    starts cold, as with ``warm_start=False`` (the same bits at that step)."""
    system = eqrec.two_mass()
    ests = [ZonotopeEstimator(system, x0_radius=0.5, window=10, warm_start=w).reset(np.zeros(4)) for w in (True, False)]
    for _ in range(25):  # nothing arrives: both windows full and empty of measurements
        outs = [e.step(None) for e in ests]
    assert outs[0][1] == outs[1][1]
    outs = [e.step(np.array([0.3])) for e in ests]  # the first measurement
    assert outs[0][1] == outs[1][1] and np.array_equal(ests[0].state_bounds, ests[1].state_bounds)


@pytest.mark.parametrize("plant", PLANTS)
def test_warm_start_worst_case_played_back_at_every_step_and_never_below_the_limit(plant):
    """``warm_start=True`` (window 6: warm from step 6 on): at every step, the sign of the worst state's row of the
    exact error map (unit runs), the initial error at its box corner, played back: the error stays inside the bound
    exactly, and every state's bound is at least the information limit (tolerance on the LP's side only)."""
    system, N, r0 = PLANTS[plant](), 18, 0.5
    trace = lossy_trace(5, N)

    def make():
        return ZonotopeEstimator(system, x0_radius=r0, max_delay=2, window=6, warm_start=True)

    n, nw, nv = system.n, system.nw, system.nv
    cols, radii = [], []  # the error at every step of each unit perturbation
    for kind, size, radius in (("x0", n, r0), ("w", N * nw, system.eta_w), ("v", N * nv, system.eta_v)):
        for k in range(size):
            xi0, w, v = np.zeros(n), np.zeros((N, nw)), np.zeros((N, nv))
            {"x0": xi0.reshape(-1), "w": w.reshape(-1), "v": v.reshape(-1)}[kind][k] = radius
            cols.append(closed_loop(system, make(), trace, xi0, xi0, w, v).error[1:])
            radii.append((kind, k, radius))
    M = np.stack(cols, axis=-1)  # (N, n, columns)
    lim = reference_limit(system, trace, r0)
    for t in range(N):
        est = make()
        _, beta = run(system, est, trace, np.zeros(n), np.zeros((N, nw)), np.zeros((N, nv)))
        i = int(np.argmax(beta[t]))
        xi0, w, v = np.zeros(n), np.zeros((N, nw)), np.zeros((N, nv))
        for sign, (kind, k, radius) in zip(np.sign(M[t, i]), radii):
            {"x0": xi0.reshape(-1), "w": w.reshape(-1), "v": v.reshape(-1)}[kind][k] = sign * radius
        out, beta_played = run(system, make(), trace, xi0, w, v, x0=xi0)
        assert np.all(np.abs(out.error[1:]) <= beta_played)  # every step, every state, exactly
        assert abs(out.error[t + 1][i]) >= 0.5 * beta_played[t][i]  # the vertex is the worst one, not a random one
        assert np.all(beta_played[t] >= lim[t] * (1 - 1e-7) - 1e-12)


def test_default_per_state_solves_depend_on_the_plant_size():
    """``iterations=None`` (the default) is two reweighted per-state solves up to ``LARGE_PLANT_STATES`` states and
    one beyond (:data:`eqrec.estimators.zonotope.DEFAULT_ITERATIONS_LARGE`); an explicit value is kept; a bad one is
    refused naming the field."""
    from eqrec.estimators import zonotope as zmod

    small = tank_chain(zmod.LARGE_PLANT_STATES, 2)
    large = tank_chain(zmod.LARGE_PLANT_STATES + 2, 2)
    assert ZonotopeEstimator(small).iterations == zmod.DEFAULT_ITERATIONS == 2
    assert ZonotopeEstimator(large).iterations == zmod.DEFAULT_ITERATIONS_LARGE == 1
    assert ZonotopeEstimator(large, iterations=2).iterations == 2
    assert ZonotopeEstimator(small, iterations=0).iterations == 0
    with pytest.raises(InputError) as err:
        ZonotopeEstimator(small, iterations=-1)
    assert err.value.field == "iterations"
