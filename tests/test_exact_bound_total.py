"""``eqrec.exact_bound`` on every protocol estimator in every state (issue 40 §4): in and out of the design, after a
return to it and after ``reset``; a refused call changes nothing (checked against a twin that never saw it, bit for
bit); the node-gain estimators; on the set-membership estimator and ``strict=False`` the bound is at least the worst
case measured by unit perturbations at every step, exactly, and the worst case played back stays below it."""
import copy

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.traces import NEVER, ArrivalTrace
from eqrec.design.delay.design import design_delay_global
from eqrec.design.delay.languages import delay_classes
from eqrec.errors import InputError
from eqrec.estimators.exact import exact_bound
from eqrec.estimators.zonotope import ZonotopeEstimator
from eqrec.simulate.loop import closed_loop
from test_rounding import cartpole, unit_responses

L1 = ["101111", "110111", "111011", "111101"]


@pytest.fixture(scope="module")
def cart():
    system = cartpole()
    return system, design_delay_global(system, delay_classes(max_delay=2, horizon=6, max_lost=1)).design


def _lossy(seed: int, N: int, loss: float, D: int) -> ArrivalTrace:
    rng = np.random.default_rng(seed)
    d = rng.integers(0, D + 1, N)
    d[rng.random(N) < loss] = NEVER
    return ArrivalTrace(d)


def test_the_node_gain_estimator_of_the_issue():
    """``exact_bound(design_prefix(acc, L1, 1.0, engine='tree').estimator(), acc, 1.0, steps=6)``: run as copies
    (it has no error maps), equal to the worst case of unit perturbations."""
    acc = eqrec.acc_system()
    design = eqrec.design_prefix(acc, L1, 1.0, engine="tree")
    make = lambda: exact_bound(design.estimator(), acc, 1.0, steps=6)  # noqa: E731
    assert make().mode == "copies"
    trace = ArrivalTrace.from_arrived([1, 0, 1, 1, 1, 1])
    G, r, run = unit_responses(acc, make, trace, np.array([1.0, 20.0, 30.0]), 1.0)
    exact = np.abs(G).sum(axis=-1).max(axis=1)
    spread = run(np.zeros(r.size)).bound
    assert np.all(spread >= exact) and np.all(spread <= exact * (1 + 1e-9))


def _twin_check(make, system, trace, x0, bad_steps, bad):
    """Run ``make()`` and a twin on ``trace``; at ``bad_steps`` the first also gets a refused call first.  Every
    output must be bit-identical, the refused call raising ``InputError``."""
    rng = np.random.default_rng(0)
    N = trace.steps
    w = rng.uniform(-1, 1, (N, system.nw)) * system.eta_w
    v = rng.uniform(-1, 1, (N, system.nv)) * system.eta_v
    est, twin = make(), make()
    outs = []
    for e, refuse in ((est, True), (twin, False)):
        out = []

        def after(k, e=e, refuse=refuse):
            if refuse and k in bad_steps:
                with pytest.raises(InputError):
                    e.step(*bad(e))
                out.append(("refused", e.time))

        run = closed_loop(system, e, trace, x0, np.zeros(system.n), w, v, after_step=after)
        outs.append((run.xhat, np.array(run.bound), getattr(e, "state_bounds", None)))
        # and after reset: the same again
        run = closed_loop(system, e, trace, x0, np.zeros(system.n), w, v)
        outs.append((run.xhat, np.array(run.bound)))
    (a, b, sa), (a2, b2), (c, d, sc), (c2, d2) = outs
    assert np.array_equal(a, c) and np.array_equal(b, d) and np.array_equal(a2, c2) and np.array_equal(b2, d2)
    assert np.array_equal(a, a2) and np.array_equal(b, b2)  # reset starts afresh
    assert np.all(np.isfinite(b))


def _future_packet(e):
    return [eqrec.Packet(e.time + 1, np.zeros(2))], None


def test_strict_false_in_and_out_of_the_design_and_back_and_refusals_change_nothing(cart):
    """40 % loss on a design for at most one loss per block: steps out of the design and returns to it."""
    system, design = cart
    trace = _lossy(2, 60, 0.4, 2)
    flags = []
    est = exact_bound(design.estimator(strict=False), system, design.mu1)
    closed_loop(system, est, trace, np.ones(4), np.zeros(4), np.zeros((60, 4)), np.zeros((60, 2)),
                after_step=lambda k: flags.append(est.estimator.in_design))
    assert not all(flags) and any(flags[flags.index(False):])  # out of the design, then back in
    _twin_check(lambda: exact_bound(design.estimator(strict=False), system, design.mu1), system, trace, np.ones(4),
                {3, flags.index(False), len(flags) - 2}, _future_packet)


@pytest.mark.parametrize("family", ["strict=True", "node gains", "zonotope", "raw class form", "Kalman"])
def test_every_family_refusals_change_nothing(cart, family):
    system, design = cart
    acc = eqrec.acc_system()
    if family == "node gains":
        system, trace = acc, ArrivalTrace.from_arrived([int(c) for c in "101111110111"])
        make = lambda: exact_bound(eqrec.design_prefix(acc, L1, 1.0, engine="tree").estimator(), acc, 1.0,  # noqa
                                   steps=12)
    elif family == "Kalman":
        from eqrec.estimators.kalman import TimestampedKalman
        from eqrec.systems.noise import GaussianNoise

        gd = GaussianNoise(Qw=np.eye(4) * 1e-4, Qv=np.eye(2) * 1e-4, x0_cov=np.eye(4)).design(system)
        trace = _lossy(1, 12, 0.3, 2)
        make = lambda: exact_bound(TimestampedKalman(system, gd), system, 1.0, steps=12)  # noqa: E731
    else:
        trace = ArrivalTrace(np.zeros(18, dtype=int))  # on time: in the design
        make = {"strict=True": lambda: exact_bound(design.estimator(), system, design.mu1),
                "zonotope": lambda: exact_bound(ZonotopeEstimator(system, design.mu1, max_delay=2), system, design.mu1),
                "raw class form": lambda: exact_bound(eqrec.ClassEstimator(system, design.class_gains, periodic=True),
                                                      system, design.mu1)}[family]
    x0 = np.ones(system.n)
    _twin_check(make, system, trace, x0, {0, 4, trace.steps - 2}, _future_packet if system is not acc else
                (lambda e: ([eqrec.Packet(e.time + 1, np.zeros(2))], None)))


@pytest.mark.parametrize("family", ["strict=False", "zonotope"])
def test_at_least_the_unit_perturbation_worst_case_and_the_worst_case_played_back_stays_inside(cart, family):
    """At every step, in and out of the design: the bound is at least the worst case from unit perturbations
    (no tolerance) and close to it (module docstring of eqrec.estimators.exact); the noise at that worst case
    played back gives ``error <= bound`` at every step, exactly."""
    system, design = cart
    make = {"strict=False": lambda: exact_bound(design.estimator(strict=False), system, design.mu1),
            "zonotope": lambda: exact_bound(ZonotopeEstimator(system, design.mu1, max_delay=2), system,
                                            design.mu1)}[family]
    trace = _lossy(5, 18, 0.4, 2)
    xhat0 = np.array([0.3, -0.2, 0.1, 0.05])
    G, r, run = unit_responses(system, make, trace, xhat0, design.mu1)
    nominal = run(np.zeros(r.size))
    exact = np.abs(G).sum(axis=-1).max(axis=1) + np.abs(nominal.error[1:]).max(axis=1)
    spread = nominal.bound
    assert np.all(spread >= exact), float((spread / exact).min() - 1)
    assert np.all(spread <= exact * (1 + 1e-8)), float((spread / exact).max() - 1)
    for t in range(0, trace.steps, 3):
        i = int(np.argmax(np.abs(G[t]).sum(axis=-1)))
        out = run(np.sign(G[t, i]) * r)
        err = np.abs(out.error[1:]).max(axis=1)
        assert np.all(err <= out.bound), (t, float((err / out.bound).max() - 1))
