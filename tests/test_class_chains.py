"""The level LPs along a chain of classes (eqrec.design.classes.chains, eqrec.lp.solvers.solve_lp_chain): the per-class
levels, a certified design, the same bytes whatever the workers; a delay above 1 keeps the per-class solves."""
from pathlib import Path

import numpy as np
import pytest

from eqrec.bounds.certify import class_bounds
from eqrec.bounds.stacking import Stacking
from eqrec.design.classes import blocks as class_blocks
from eqrec.design.classes.chains import build_chain_lp, chain_classes
from eqrec.design.classes.engine import solve_classes_at
from eqrec.design.delay.design import delay_classes, design_delay_global
from eqrec.lp.solvers import leading_lp, solve_lp, solve_lp_chain
from eqrec.systems.files import load_system

ROOT = Path(__file__).resolve().parents[1]
T = 60
#: Lowered so that the classes of a T = 60 design take the chain path (the default keeps them per class).
LOW = 2_000
MU1S = [0.58, 0.57]


@pytest.fixture(scope="module")
def two_mass():
    return load_system(ROOT / "examples" / "two_mass.yaml")[0]


@pytest.fixture(scope="module")
def classes():
    return delay_classes(max_delay=1, horizon=T)


def test_chain_is_the_large_classes_of_delay_one_only(two_mass, classes, monkeypatch):
    assert chain_classes(classes, two_mass, "highs") == []  # the default threshold: none at T = 60
    monkeypatch.setattr(class_blocks, "LARGE_CLASS_WORK", LOW)
    chain = chain_classes(classes, two_mass, "highs")
    assert len(chain) > 50 and chain == list(range(chain[0], len(classes)))
    assert chain_classes(classes, two_mass, "clarabel") == []
    assert chain_classes(delay_classes(max_delay=2, horizon=30), two_mass, "highs") == []  # a tree: per class


def test_each_class_lp_is_a_leading_block(two_mass, classes):
    """Each class's state-space LP is a leading block of the chain's; grown and warm-started, it has the optimum of
    the same LP solved alone, at each radius of ξ0."""
    chain = list(classes.classes[10:16])
    model = build_chain_lp(Stacking(two_mass, T), chain, MU1S[0])
    costs = []
    for (rows, cols), x_d in zip(model.prefixes, model.state):
        assert model.lp.A[:rows, cols:].nnz == 0  # its rows touch none of the later columns
        costs.append(np.zeros(cols))
        costs[-1][x_d[1]] = -1.0
    bounds = [model.bounds_at(mu1) for mu1 in MU1S]
    grown = solve_lp_chain(model.lp, model.prefixes, costs, bounds)
    for (rows, cols), c, sols in zip(model.prefixes, costs, grown):
        for b, sol in zip(bounds, sols):
            alone = solve_lp(leading_lp(model.lp, rows, cols, c, b))
            assert sol.optimal and alone.optimal and sol.objective == pytest.approx(alone.objective, rel=1e-9)
            assert sol.row_dual.size == rows and sol.x.size == cols


def test_chain_levels_equal_the_per_class_levels(two_mass, classes, monkeypatch):
    ref = solve_classes_at(two_mass, classes, MU1S, n_jobs=1, path="blocks")
    monkeypatch.setattr(class_blocks, "LARGE_CLASS_WORK", LOW)
    new = solve_classes_at(two_mass, classes, MU1S, n_jobs=1, path="blocks")
    st = Stacking(two_mass, T)
    for a, b, mu1 in zip(ref, new, MU1S):
        np.testing.assert_allclose(b.lp_levels, a.lp_levels, rtol=1e-7, atol=1e-12)
        # the certificate is recomputed from the chain's gains, and no level lies below it
        bounds = class_bounds(two_mass, b.gains, mu1, st)
        assert np.array_equal(bounds, b.certificate.bounds) and np.all(bounds <= b.lp_levels)


def _bytes(res) -> bytes:
    d = res.design
    return b"".join([np.float64([res.mu1, res.J, res.lower_bound, d.mu2]).tobytes(),
                     d.class_certificate.bounds.tobytes(), *(k.tobytes() for k in d.class_gains.K),
                     np.asarray(d.class_levels).tobytes()])


def test_chain_design_certifies_and_is_the_same_whatever_the_workers(two_mass, classes, monkeypatch):
    monkeypatch.setattr(class_blocks, "LARGE_CLASS_WORK", LOW)
    monkeypatch.setattr(class_blocks, "POOL_MIN_WORK", 0)  # the worker processes, even this small
    monkeypatch.setattr(class_blocks, "MONOLITHIC_MAX_WORK", 0)  # per class (and chain), not the one block LP
    one = design_delay_global(two_mass, classes, n_jobs=1)
    two = design_delay_global(two_mass, classes, n_jobs=2)
    assert _bytes(one) == _bytes(two)
    d = one.design
    bounds = class_bounds(two_mass, d.class_gains, d.mu1)  # exact worst cases of the gains written
    terminal = np.array([c.terminal for c in classes.classes])
    assert np.all(bounds.max(axis=1)[terminal] <= d.mu1)
    assert np.all(bounds.max(axis=1) <= np.asarray(d.class_levels))
    assert np.all(bounds.max(axis=1)[~terminal] <= d.mu2)
