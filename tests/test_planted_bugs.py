"""Tests that catch the bugs a mutation probe planted and the suite let through (issue 35).

One test (or one parametrised family) per point of the issue's "Required" list; the docstring of each names
the bug it catches.  Each was seen to fail with its bug planted and to pass on the code as it is.
"""
from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np
import pytest

import eqrec
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import full_delay_language
from eqrec.design.augmented.runtime import prefix_to_augmented
from eqrec.estimators.augmented import AugmentedEstimator
from eqrec.design.delay.design import delay_classes, design_delay, design_delay_global
from eqrec.design.observers import place_observer
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InputError
from eqrec.estimators.causal import ClassEstimator, RecoveryEstimator, make_estimator
from eqrec.estimators.kalman import DelayUnawareKalman, TimestampedKalman, make_filter
from eqrec.estimators.protocol import OnTimeOnly
from eqrec.estimators.switching import SwitchingEstimator
from eqrec.lmv.estimator import LMVEstimator
from eqrec.lmv.model import system_of
from eqrec.lmv.plant import Plant
from eqrec.lmv.recursion import lmv_recursion
from eqrec.systems.affine import AffineSystem
from eqrec.systems.noise import GaussianNoise, NoisySystem
from test_atomic_steps import state_of  # the whole state of an estimator, as comparable bytes

LOSS = ["000", "300", "030", "003"]  # delay words: at most one packet of three lost
MISSING = ["1111", "0111", "1011", "1101", "1110"]  # 0/1 words: at most one packet of four lost


# --------------------------------------------------------------------------------------------------------------------
# Every way of building every runtime estimator, on one small plant (n = 2, m = p = 1)
# --------------------------------------------------------------------------------------------------------------------

#: A stable plant (the LMV filters need one) with a negative entry in A.
PLANT = AffineSystem(A=[[0.9, 0.2], [-0.1, 0.7]], B=[[0.0], [1.0]], C=[[1.0, 0.5]], E=[[0.0], [1.0]], eta_w=0.5,
                     eta_v=0.2)
T0 = 5  # the start time of the estimators that take one: stamps are absolute times, not period times


class Way(NamedTuple):
    """One way of building an estimator: ``make(xhat0)`` returns it at time ``T0``, ready to step.

    ``resets``: the initial estimate goes through ``reset`` (else through the constructor)."""

    make: Callable
    resets: bool
    inputs: bool = True  # it has an input model (else ``u`` must be ``None`` or zero)


@pytest.fixture(scope="module")
def ways() -> dict[str, Way]:
    classes = design_delay_global(PLANT, LOSS).design  # class engine: class gains
    node = design_prefix(PLANT, MISSING, "free", engine="tree")  # node gains
    perf = design_delay(PLANT, ["0"], 3.0, kind="delay")
    rec = design_delay(PLANT, [w for w in full_delay_language(3, 1) if w[0] != "0"], 3.0, kind="delay")
    aug = eqrec.design_augmented(PLANT, ["1101", "1011"], 2.0)  # one word's gains
    L = place_observer(PLANT.A, PLANT.C, [0.1, 0.2]).L
    aug_prefix = prefix_to_augmented(PLANT, PrefixTree(MISSING, kind="missing"), node.schedule, L,
                                     np.array([0.1, -0.2]))  # prefix gains
    gauss = GaussianNoise.from_box(PLANT, mu1=1.0)
    kalman = gauss.design(PLANT)
    lmv_plant = Plant.from_description(NoisySystem(PLANT, gauss))
    zero, hold = system_of(lmv_plant, "zero-input", 0.8), system_of(lmv_plant, "hold-input", 0.8)
    zero_gains = lmv_recursion(zero, 30)

    def reset(make_est):
        return lambda x0: make_est().reset(x0, T0)

    out = {
        "guaranteed, class engine": Way(reset(lambda: classes.estimator()), True),
        "guaranteed, class engine, strict=False": Way(reset(lambda: classes.estimator(strict=False)), True),
        "guaranteed, class engine, not periodic": Way(reset(lambda: classes.estimator(periodic=False)), True),
        "guaranteed, node gains": Way(reset(lambda: node.estimator()), True),
        "guaranteed, on time only": Way(reset(lambda: OnTimeOnly(classes.estimator(), 1)), True),
        "ClassEstimator": Way(reset(lambda: ClassEstimator(PLANT, classes.class_gains, periodic=True)), True),
        "ClassEstimator, not periodic": Way(reset(lambda: ClassEstimator(PLANT, classes.class_gains)), True),
        "ClassEstimator, x̂0 to the constructor": Way(lambda x0: ClassEstimator(PLANT, classes.class_gains, x0,
                                                                                periodic=True, t0=T0), False),
        "RecoveryEstimator": Way(reset(lambda: RecoveryEstimator(PLANT, node.schedule, periodic=True)), True),
        "RecoveryEstimator, x̂0 to the constructor": Way(lambda x0: RecoveryEstimator(PLANT, node.schedule, x0,
                                                                                      periodic=True, t0=T0), False),
        "make_estimator, class gains": Way(reset(lambda: make_estimator(PLANT, classes.class_gains)), True),
        "make_estimator, node gains": Way(reset(lambda: make_estimator(PLANT, node.schedule)), True),
        "SwitchingEstimator, node gains": Way(reset(lambda: SwitchingEstimator(PLANT, perf.schedule, rec.schedule)),
                                              True),
        "SwitchingEstimator, class gains": Way(reset(lambda: SwitchingEstimator(PLANT, perf.class_gains,
                                                                                rec.class_gains)), True),
        "SwitchingEstimator, x̂0 to the constructor": Way(lambda x0: SwitchingEstimator(
            PLANT, perf.schedule, rec.schedule, x0, t0=T0), False),
        "AugmentedEstimator, one word": Way(reset(lambda: AugmentedEstimator(PLANT, aug.augmented.gains)), True),
        "AugmentedEstimator, one word, hold": Way(reset(lambda: AugmentedEstimator(PLANT, aug.augmented.gains,
                                                                                   runtime="hold")), True),
        "AugmentedEstimator, prefix gains": Way(reset(lambda: AugmentedEstimator(PLANT, aug_prefix)), True),
        "AugmentedEstimator, x̂0 to the constructor": Way(lambda x0: AugmentedEstimator(PLANT, aug_prefix, x0, t0=T0),
                                                         False),
        "Kalman, time-stamped": Way(reset(lambda: make_filter("timestamped", PLANT, kalman)), True),
        "Kalman, delay-unaware": Way(reset(lambda: make_filter("unaware", PLANT, kalman)), True),
        "Kalman, time-stamped, by hand": Way(reset(lambda: TimestampedKalman(PLANT, kalman)), True),
        "Kalman, delay-unaware, by hand": Way(reset(lambda: DelayUnawareKalman(PLANT, kalman)), True),
        "LMV, random delay": Way(reset(lambda: make_filter("random_delay_lmv", PLANT, kalman, horizon=40, max_delay=1,
                                                           x0_mean=np.zeros(2))), True),
        "LMV, zero-input": Way(reset(lambda: LMVEstimator(zero)), True, inputs=False),
        "LMV, zero-input, gains given": Way(reset(lambda: LMVEstimator(zero, zero_gains)), True, inputs=False),
        "LMV, hold-input": Way(reset(lambda: LMVEstimator(hold)), True, inputs=False),
        "LMV, zero-input, system=": Way(reset(lambda: LMVEstimator(zero, system=PLANT)), True),
        "LMV, zero-input, gains given, system=": Way(reset(lambda: LMVEstimator(zero, zero_gains, system=PLANT)),
                                                     True),
        "LMV, hold-input, system=": Way(reset(lambda: LMVEstimator(hold, system=PLANT)), True),
        "LMV, on time only, system=": Way(reset(lambda: OnTimeOnly(LMVEstimator(hold, system=PLANT), 1)), True),
    }
    return out


WAYS = ["guaranteed, class engine", "guaranteed, class engine, strict=False", "guaranteed, class engine, not periodic",
        "guaranteed, node gains", "guaranteed, on time only", "ClassEstimator", "ClassEstimator, not periodic",
        "ClassEstimator, x̂0 to the constructor", "RecoveryEstimator", "RecoveryEstimator, x̂0 to the constructor",
        "make_estimator, class gains", "make_estimator, node gains",
        "SwitchingEstimator, node gains", "SwitchingEstimator, class gains", "SwitchingEstimator, x̂0 to the constructor",
        "AugmentedEstimator, one word", "AugmentedEstimator, one word, hold", "AugmentedEstimator, prefix gains",
        "AugmentedEstimator, x̂0 to the constructor", "Kalman, time-stamped",
        "Kalman, delay-unaware", "Kalman, time-stamped, by hand", "Kalman, delay-unaware, by hand",
        "LMV, random delay", "LMV, zero-input", "LMV, zero-input, gains given", "LMV, hold-input",
        "LMV, zero-input, system=", "LMV, zero-input, gains given, system=", "LMV, hold-input, system=",
        "LMV, on time only, system="]


def test_the_list_of_ways_is_the_fixtures(ways):
    assert sorted(WAYS) == sorted(ways)


def _good_u(way: Way) -> np.ndarray:
    """A good input: nonzero with an input model, zero without one (the LMV estimator without ``system=``)."""
    return np.array([0.1]) if way.inputs else np.zeros(1)


def _started(way: Way):
    """The estimator after one good step (``y`` on time, a good ``u``): it has a state to keep."""
    est = way.make(np.zeros(2))
    est.step(np.array([0.3]), _good_u(way))
    return est


def _now(est) -> int:
    """The absolute time of the estimator's next step."""
    return int(est.time)


BAD = {"NaN": np.nan, "inf": np.inf, "-inf": -np.inf}


@pytest.mark.parametrize("value", list(BAD), ids=list(BAD))
@pytest.mark.parametrize("what", ["y", "y as a packet", "u"])
@pytest.mark.parametrize("name", WAYS)
def test_non_finite_y_and_u_are_refused_naming_the_field_and_nothing_changes(ways, name, what, value):
    """Catches an estimator that lets NaN or inf in ``y`` or ``u`` through (issue 35: the LMV estimator built with
    ``system=`` whose check on ``u`` refused inf only, and returned ``[nan nan]``), on every way of building every
    estimator; the refused call leaves the estimator as it was."""
    est = _started(ways[name])
    bad = np.array([BAD[value]])
    now = _now(est)
    good_u = _good_u(ways[name])
    y, u = {"y": (bad, good_u), "y as a packet": ([(now, bad)], good_u),
            "u": (np.array([0.3]), bad)}[what]
    before = state_of(est)
    with pytest.raises(InputError) as exc:
        est.step(y, u)
    assert exc.value.field == what.split()[0]
    assert state_of(est) == before, "a refused step changed the estimator"


@pytest.mark.parametrize("value", list(BAD), ids=list(BAD))
@pytest.mark.parametrize("name", WAYS)
def test_a_non_finite_initial_estimate_is_refused_naming_the_field(ways, name, value):
    """Catches an estimator that starts from NaN or inf in ``x̂0`` (by ``reset`` or by its constructor); a refused
    ``reset`` leaves the running estimator as it was."""
    way = ways[name]
    bad = np.array([0.0, BAD[value]])
    if not way.resets:
        with pytest.raises(InputError) as exc:
            way.make(bad)
        assert exc.value.field == "xhat0"
        return
    est = _started(way)
    before = state_of(est)
    with pytest.raises(InputError) as exc:
        est.reset(bad, T0)
    assert exc.value.field == "xhat0"
    assert state_of(est) == before, "a refused reset changed the estimator"


@pytest.mark.parametrize("ahead", [1, 5])
@pytest.mark.parametrize("name", WAYS)
def test_a_packet_from_the_future_is_an_input_error_naming_y(ways, name, ahead):
    """Catches the "packet from the future" check off by one (``tau > now + 1`` in
    :func:`eqrec.arrivals.packets.as_packets`): a stamp of now + 1 must be refused like now + 5, as an
    :class:`InputError` naming ``y`` (not an ``IndexError`` from the estimator's record, nor silently dropped), for
    every estimator that reads time-stamped packets; nothing changes."""
    est = _started(ways[name])
    now, good_u = _now(est), _good_u(ways[name])
    before = state_of(est)
    with pytest.raises(InputError, match="future") as exc:
        est.step([(now + ahead, np.array([0.3]))], good_u)
    assert exc.value.field == "y"
    assert state_of(est) == before
    with pytest.raises(InputError, match="future"):  # among on-time packets too
        est.step([(now, np.array([0.3])), eqrec.Packet(now + ahead, np.array([0.2]))], good_u)
    assert state_of(est) == before


# --------------------------------------------------------------------------------------------------------------------
# The guarantee outside the language (strict=False) on plants where A ≠ |A|, with the worst-case noise played back
# --------------------------------------------------------------------------------------------------------------------

def _rotation(angle: float, radius: float) -> np.ndarray:
    return radius * np.array([[np.cos(angle), -np.sin(angle)], [np.sin(angle), np.cos(angle)]])


#: Plants whose A has negative entries and complex eigenvalues (the suite's other out-of-language plant has A = |A|).
SIGNED_PLANTS = {"A = [[1, -0.1], [0.2, 0.95]]": np.array([[1.0, -0.1], [0.2, 0.95]]),
                 "lightly damped oscillator": _rotation(0.6, 0.99),
                 "oscillator, a quarter turn a step": _rotation(1.5, 0.99)}
#: The played-back worst case may exceed a bound that is exact (the designed levels, and the exact class boxes out of
#: the design) by rounding, the bound's sum and the run's arithmetic rounding differently: measured up to 1.6e-15
#: relative on these plants.  A bound without slack in floating point is issue 32's (section 4); until then this
#: margin, 1000x the rounding measured and far below what a wrong bound gives (the |A| -> A bug: 1.17x to 2217x).
ROUNDING = 1e-12


def _signed_plant(A: np.ndarray) -> AffineSystem:
    return AffineSystem(A=A, B=np.array([[0.005], [0.1]]), C=np.array([[1.0, 0.0]]), E=0.1 * np.eye(2), eta_w=0.1,
                        eta_v=0.05)


def _play(system, design, lost, delta, u):
    """Run ``design.estimator(strict=False)`` with the true plant driven by ``delta = (ξ0, w, v)``: per step, the error
    ``x(k+1) − x̂(k+1)`` and the bound returned."""
    n, N = system.n, len(lost)
    xi0, w, v = delta[:n], delta[n:n + N * system.nw].reshape(N, system.nw), delta[n + N * system.nw:].reshape(N, -1)
    est = design.estimator(strict=False)
    x = np.zeros(n)
    est.reset(x - xi0)  # |x(0) − x̂(0)| = |ξ0| <= μ1
    errors, bounds = np.zeros((N, n)), np.zeros(N)
    for k in range(N):
        y = system.C_at(k) @ x + system.V_at(k) @ v[k]
        xhat, bounds[k] = est.step(None if lost[k] else y, u[k])
        x = system.A_at(k) @ x + system.B_at(k) @ u[k] + system.f + system.E_at(k) @ w[k]
        errors[k] = x - xhat
    return errors, bounds


@pytest.mark.parametrize("loss, seed", [(0.3, 0), (0.6, 1)])
@pytest.mark.parametrize("plant_name", list(SIGNED_PLANTS))
def test_the_bound_out_of_the_language_holds_on_signed_plants_for_the_worst_case_noise(plant_name, loss, seed):
    """Catches the coasting error box written with ``A`` instead of ``|A|`` (``ClassBoxes.coast`` of
    ``estimators/error_boxes.py`` when issue 35 was filed): on plants whose ``A`` has negative entries and complex
    eigenvalues, with losses beyond the design's language, the bound of ``design.estimator(strict=False)`` must be
    finite and at least the error at every step, for noise at the box corners and for the worst-case noise of every
    step and state played back (the error is linear in ``δ = (ξ0, w, v)`` for given arrivals: its maps are read from
    unit perturbations of the estimator itself, so the test holds for any sound bound, whatever its construction)."""
    system = _signed_plant(SIGNED_PLANTS[plant_name])
    design = design_delay_global(system, LOSS).design
    N, n = 36, system.n
    lost = np.random.default_rng(seed).random(N) < loss
    u = np.cos(0.2 * np.arange(N))[:, None]
    eta_w, eta_v = (np.broadcast_to(np.asarray(eta, float), (N * k,)) for eta, k in ((system.eta_w, system.nw),
                                                                                    (system.eta_v, system.nv)))
    radius = np.concatenate([np.full(n, design.mu1), eta_w, eta_v])  # the box of δ = (ξ0, w, v)
    strict = design.estimator().reset(np.zeros(n))
    with pytest.raises(InputError):  # the losses do leave the language (the trace's data are good otherwise)
        for k in range(N):
            strict.step(None if lost[k] else np.zeros(1))
    c, bound = _play(system, design, lost, np.zeros(radius.size), u)
    assert np.all(np.isfinite(bound))
    G = np.stack([_play(system, design, lost, e, u)[0] - c for e in np.eye(radius.size)], axis=-1)  # (N, n, δ)
    played = 0.0
    for k in range(N):
        for i in range(n):  # the vertex of the box that maximises |ξ_i(k+1)|, played back through the estimator
            sign = 1.0 if c[k, i] >= 0 else -1.0
            delta = sign * np.where(G[k, i] >= 0, 1.0, -1.0) * radius
            errors, bounds = _play(system, design, lost, delta, u)
            assert np.abs(errors[k, i]) == pytest.approx(np.abs(c[k, i]) + np.abs(G[k, i]) @ radius, rel=1e-12)
            assert np.all(np.isfinite(bounds))
            played = max(played, float(np.max(np.abs(errors).max(axis=1) / bounds)))
    corners = np.random.default_rng(seed + 10)
    for _ in range(20):
        errors, bounds = _play(system, design, lost, corners.choice([-1.0, 1.0], radius.size) * radius, u)
        assert np.all(np.isfinite(bounds))
        played = max(played, float(np.max(np.abs(errors).max(axis=1) / bounds)))
    assert played <= 1 + ROUNDING, f"error/bound reaches {played}"


# --------------------------------------------------------------------------------------------------------------------
# The violation counter of `eqrec compare`, on bounds made unsound on purpose
# --------------------------------------------------------------------------------------------------------------------

def test_the_violation_counter_counts_every_error_above_the_bound_beyond_rounding():
    """Catches a counter of ``eqrec compare`` that counts too few (issue 35: a violation counted only when the error
    exceeds 2x the bound): it counts exactly ``sum(error > bound·(1 + rtol))``, so an error of 1.01x its bound is one
    violation, and an error within the rounding margin none."""
    from eqrec.compare import count_violations
    from eqrec.compare.families import VIOLATION_RTOL

    assert VIOLATION_RTOL < 1e-6  # a margin for rounding, not for a wrong bound
    assert count_violations(np.array([1.01]), np.array([1.0])) == 1
    assert count_violations(np.array([[1.01, 5.0]]), np.array([[1.0, 5.0]])) == 1
    bounds = np.array([[1.0, 2.0, 3.0, 0.7], [0.5, 4.0, 1.0, 2.0]])
    factor = np.array([[1.01, 1.0, 0.5, 1 + VIOLATION_RTOL / 2], [1.5, 2.5, 1 + 10 * VIOLATION_RTOL, 0.0]])
    expected = int(np.sum(bounds * factor > bounds * (1 + VIOLATION_RTOL)))
    assert count_violations(bounds * factor, bounds) == expected == 4


class _Unsound:
    """A guaranteed design whose estimators report ``scale`` times their bound (an unsound bound, on purpose)."""

    def __init__(self, design, scale: float):
        self.design, self.scale, self.mu1 = design, scale, design.mu1

    def estimator(self, **kw):
        return _UnsoundEstimator(self.design.estimator(**kw), self.scale)

    def __getattr__(self, name: str):  # the design's gains and levels (the class-limit identity reads them)
        return getattr(self.__dict__["design"], name)


class _UnsoundEstimator:
    def __init__(self, inner, scale: float):
        self.inner, self.scale = inner, scale

    def reset(self, xhat0, t0: int = 0):
        self.inner.reset(xhat0, t0)
        return self

    def step(self, y=None, u=None):
        xhat, bound = self.inner.step(y, u)
        return xhat, bound * self.scale

    def __getattr__(self, name: str):
        return getattr(self.__dict__["inner"], name)


def test_compare_counts_the_violations_of_a_bound_made_unsound(monkeypatch):
    """Catches the same counter through ``compare_families`` itself: with the guaranteed families' bounds scaled to
    0.1x (unsound on purpose), the table's ``violations`` is exactly ``sum(error > bound·(1 + rtol))`` over the
    errors and bounds the comparison returns, and some of them are between 1x and 2x the bound (where the 2x
    counter sees nothing)."""
    from eqrec.compare import families
    from eqrec.compare.families import FAMILIES, VIOLATION_RTOL, CompareSetup, compare_families
    from eqrec.systems.examples import batch_reactor

    real = families.guaranteed_designs
    monkeypatch.setattr(families, "guaranteed_designs",
                        lambda *a, **kw: {f: (d if isinstance(d, str) else _Unsound(d, 0.1), m)  # str: infeasible
                                          for f, (d, m) in real(*a, **kw).items()})
    result = compare_families(batch_reactor(), CompareSetup(loss=0.1, max_delay=1, horizon=4, runs=6, periods=4,
                                                            seed=3))
    table = result.table.set_index("estimator")
    guaranteed = [f for f in FAMILIES[:2] if f in result.bounds]  # a family whose design is infeasible has no run
    assert guaranteed
    for family in guaranteed:
        err, bnd = result.errors[family], result.bounds[family]
        over = err > bnd * (1 + VIOLATION_RTOL)
        assert table.loc[family, "violations"] == int(over.sum()) > 0
        assert np.any(over & (err <= 2 * bnd))


# --------------------------------------------------------------------------------------------------------------------
# The class-block engine: per-class results in class order, whatever the batching
# --------------------------------------------------------------------------------------------------------------------

def test_per_class_results_match_the_block_lp_class_by_class_when_batching_reorders(monkeypatch):
    """Catches the class-block engine putting its results back in batch order instead of class order
    (``design/classes/blocks.py``; issue 35, where only a crash in a fixture showed it): with one class per batch,
    handed out heaviest first (so the batches reorder the classes), each class's levels from
    :func:`~eqrec.design.classes.blocks.solve_level_blocks` equal, class by class, the optima of that class's
    blocks in the one block LP (:func:`~eqrec.design.classes.block_lp.build_class_lp`), and each gain has the
    class's shape.  Tolerance 1e-9 relative: two solves of the same LPs reach the same optimum to the solver's
    accuracy, not to the bit (a degenerate LP has several optimal vertices)."""
    from eqrec.design.classes import blocks as class_blocks
    from eqrec.design.classes.block_lp import block_lp_options, block_objectives, build_class_lp
    from eqrec.lp.solvers import solve_lp
    from eqrec.systems.examples import batch_reactor

    reactor, classes, mu1 = batch_reactor(), delay_classes(max_delay=3, horizon=6), 0.5
    monkeypatch.setattr(class_blocks, "MIN_BATCH_WORK", 0)
    monkeypatch.setattr(class_blocks, "BATCHES_PER_WORKER", 10_000)
    planned = []
    plan = class_blocks.plan_batches
    monkeypatch.setattr(class_blocks, "plan_batches", lambda *a: planned.append(plan(*a)) or planned[-1])
    options = block_lp_options("highs")
    (per_class,), _ = class_blocks.solve_level_blocks(reactor, classes, [mu1], solver="highs", options=options,
                                                      n_jobs=1)
    order = [i for run in planned[0] for i in run]
    assert sorted(order) == list(range(len(classes))) and order != sorted(order)  # the batches do reorder them
    model = build_class_lp(reactor, classes, mu1)
    levels = np.zeros((len(classes), reactor.n))
    levels[model.block_class, model.block_row] = block_objectives(model, solve_lp(model.lp, "highs", options))
    assert len(per_class) == len(classes)
    for i, (cls, block) in enumerate(zip(classes.classes, per_class)):
        np.testing.assert_allclose(block.levels, levels[i], rtol=1e-9, atol=1e-12, err_msg=cls.label)
        assert block.K.shape == (reactor.n, len(cls.available) * reactor.p), cls.label
        assert np.all(block.bounds >= block.levels * (1 - 1e-9))  # the certificate of the class's own gain
    assert len({tuple(np.round(row, 6)) for row in levels}) > len(classes) // 2  # distinct levels: order shows
