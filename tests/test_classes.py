"""The class engine (eqrec.bounds.data_classes, eqrec.design.classes.engine) against the tree LP and brute force."""
import itertools

import numpy as np
import pytest
import scipy.sparse as sp

from eqrec.bounds.certify import certify_schedule
from eqrec.bounds.data_classes import classes_of_full_language, classes_of_tree, full_language_counts
from eqrec.lp.model import LinearProgram
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import full_delay_language
from eqrec.lp.solvers import SOLVER_NAMES, solve_lp
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.gains import node_schedule
from eqrec.design.classes.block_lp import active_columns, active_maps, build_class_lp
from eqrec.design.classes.engine import class_design, solve_classes
from eqrec.design.cost import class_cost
from eqrec.design.delay.design import delay_language, design_delay, design_delay_global
from eqrec.design.classes.mu1_min import min_recovery_level
from eqrec.design.prefix.design import design_prefix
from eqrec.errors import InfeasibleDesign
from eqrec.systems.examples import batch_reactor

ACC_DELAY = ["060000", "006000", "000600", "000060"]


@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


def random_system(seed: int, n: int = 3, p: int = 2, nw: int = 2, unstable: bool = True) -> AffineSystem:
    """A seeded system with process noise, several outputs and (by default) an unstable A."""
    rng = np.random.default_rng(seed)
    A = rng.normal(size=(n, n))
    A *= (1.15 if unstable else 0.8) / max(abs(np.linalg.eigvals(A)))
    return AffineSystem(A=A, C=rng.normal(size=(p, n)), E=0.3 * rng.normal(size=(n, nw)), eta_w=0.05, eta_v=0.1,
                        V=np.eye(p), f=rng.normal(size=n), B=rng.normal(size=(n, 1)))


def random_language(seed: int, T: int, max_delay: int, count: int) -> list[str]:
    rng = np.random.default_rng(seed)
    return sorted({"".join(str(d) for d in rng.integers(0, max_delay + 1, T)) for _ in range(count)})


def node_levels_equal(system, words, mu1, kind="delay"):
    """Per node: the class level equals the tree LP's per-node optimum (sum cost: each node at its minimum)."""
    tree = PrefixTree(words, kind=kind)
    classes = classes_of_tree(tree)
    cls = solve_classes(system, classes, mu1)
    try:
        ref = design_delay(system, tree, mu1, cost="sum", engine="tree", certify=False)
    except InfeasibleDesign:
        with pytest.raises(InfeasibleDesign):
            design_delay(system, tree, mu1, cost="sum")
        return None
    for node in tree:
        if not node.terminal:
            assert ref.levels[node.label] == pytest.approx(max(mu1, cls.levels[classes.node_class[node.index]]),
                                                           rel=1e-7, abs=1e-9)
    d = design_delay(system, tree, mu1, cost="sum")
    assert d.J == pytest.approx(ref.J, rel=1e-8)
    for cost in ("max",):
        dm = design_delay(system, tree, mu1, cost=cost)
        rm = design_delay(system, tree, mu1, cost=cost, engine="tree", certify=False)
        assert dm.mu2 == pytest.approx(rm.mu2, rel=1e-7)
    return d


# --- classes ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("T,tau", [(1, 0), (2, 1), (3, 1), (4, 2), (5, 2), (4, 3), (6, 2), (5, 4)])
def test_window_rule_classes_equal_brute_force(T, tau):
    tree = PrefixTree(full_delay_language(T, tau), kind="delay")
    from_tree = classes_of_tree(tree)
    window = classes_of_full_language(T, tau)
    key = lambda c: (c.key, c.terminal, c.inner, c.weight, c.nodes)  # noqa: E731
    assert [key(c) for c in window] == [key(c) for c in from_tree]
    counts = full_language_counts(T, tau)
    assert counts == {"words": (tau + 1) ** T, "sequences": len(tree.patterns), "nodes": len(tree)}
    assert len(window) == sum(2 ** min(tau, d) for d in range(1, T + 1))


def test_class_counts_quoted_in_the_issue():
    assert len(classes_of_full_language(5, 2)) == 18
    assert len(classes_of_full_language(8, 3)) == 54
    big = classes_of_full_language(30, 4)
    assert len(big) == 446 and big.words == 5 ** 30


# --- separation: class engine = tree LP ---------------------------------------------------------------------

def test_acc_prefix_design_is_p1_optimum(acc, L1_words):
    classes = classes_of_tree(PrefixTree(L1_words))
    assert len(classes) == 18
    d = design_prefix(acc, L1_words, 1.0)
    ref = design_prefix(acc, L1_words, 1.0, engine="tree")
    assert d.mu2 == pytest.approx(ref.mu2, rel=1e-8)
    assert d.certificate.mu2 <= d.mu2 * (1 + 1e-6) and d.class_certificate.mu2 <= d.mu2 * (1 + 1e-6)
    for levels in ("sum", "max"):
        a = design_prefix(acc, L1_words, 1.0, levels=levels)
        b = design_prefix(acc, L1_words, 1.0, levels=levels, engine="tree")
        assert a.mu2 == pytest.approx(b.mu2, rel=1e-8)


@pytest.mark.parametrize("T", [5, 6])
def test_reactor_classes_equal_tree_node_by_node(reactor, T):
    d = node_levels_equal(reactor, full_delay_language(T, 2), 0.5)
    assert d.classes == 18 if T == 5 else d.classes == 22


def test_missing_only_language(acc):
    words = ["101111", "110111", "111011", "111101", "011111", "100111"]
    node_levels_equal(acc, words, 1.2, kind="missing")


def test_acc_delay_language_is_the_missing_language(acc):
    d = design_delay(acc, ACC_DELAY, 1.0, cost="max")
    p1 = design_prefix(acc, ["101111", "110111", "111011", "111101"], 1.0)
    assert d.mu2 == pytest.approx(p1.mu2, rel=1e-9)


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
def test_random_systems_and_languages(seed):
    system = random_system(seed)
    words = random_language(seed, T=5, max_delay=2, count=25)
    mu1 = 1.5 * min_recovery_level(system, classes_of_tree(PrefixTree(words, kind="delay"))).upper
    d = node_levels_equal(system, words, mu1)
    assert d is not None and d.certificate.terminal <= mu1 * (1 + 1e-6)


def test_time_varying_system(acc):
    A = np.stack([acc.A * (1 + 0.03 * k) for k in range(6)])
    tv = AffineSystem(A=A, C=acc.C, E=acc.E, eta_w=acc.eta_w, eta_v=acc.eta_v)
    a = design_prefix(tv, ["101111", "110111", "111011"], 1.0)
    b = design_prefix(tv, ["101111", "110111", "111011"], 1.0, engine="tree")
    assert a.mu2 == pytest.approx(b.mu2, rel=1e-8)


@pytest.mark.parametrize("solver", [s for s in SOLVER_NAMES])
def test_every_registry_solver_gives_the_class_gains(reactor, solver):
    classes = classes_of_full_language(4, 2)
    ref = solve_classes(reactor, classes, 0.5)
    sol = solve_classes(reactor, classes, 0.5, solver=solver, rtol=1e-5)
    np.testing.assert_allclose(sol.levels, ref.levels, rtol=1e-5)
    np.testing.assert_allclose(sol.certificate.levels, ref.certificate.levels, rtol=1e-5)


# --- gains: node gains derived from the class gains ---------------------------------------------------------

def test_node_gains_give_the_class_errors(reactor):
    tree = PrefixTree(full_delay_language(4, 2), kind="delay")
    classes = classes_of_tree(tree)
    sol = solve_classes(reactor, classes, 0.6)
    schedule = node_schedule(reactor, sol.gains, tree)
    cert = certify_schedule(reactor, schedule, tree.patterns, 0.6)
    for pat in tree.patterns:
        wc = cert.words[pat.label]
        for node in tree.path(pat):
            i = classes.node_class[node.index]
            np.testing.assert_allclose(wc.bounds[node.depth], sol.certificate.bounds[i], rtol=1e-9, atol=1e-12)


# --- μ1 free ------------------------------------------------------------------------------------------------

def test_reactor_mu1_free_equals_the_certified_global_route(reactor):
    """The values of the certified branch-and-bound route it replaces (results of commit 3973e51)."""
    g = design_delay_global(reactor, full_delay_language(5, 2), cost="sum")
    assert g.mu1 == pytest.approx(0.329310024715344, rel=1e-9)
    assert g.J == pytest.approx(355.4930438835216, rel=1e-9)
    assert g.mu2 == pytest.approx(0.6897494128881275, rel=1e-9)
    assert g.mu1_min.lower < g.mu1 and g.mu1_min.lower_margin > 0
    assert g.lower_bound <= g.J and g.gap < 1e-5
    assert g.mu1_min.binding["time"] == 5


@pytest.mark.parametrize("cost", ["sum", "max"])
def test_acc_footnote_mu1_free(acc, cost, published):
    g = design_delay_global(acc, ACC_DELAY, cost=cost)
    assert round(g.design.mu2, 4) == published("P3-ACC:footnote-mu1-free")
    assert g.mu1 == pytest.approx(0.249280, abs=1e-6)


@pytest.mark.parametrize("cost", ["sum", "max"])
def test_cost_is_nondecreasing_in_mu1(reactor, cost):
    classes = classes_of_full_language(5, 2)
    mm = min_recovery_level(reactor, classes)
    grid = np.linspace(mm.upper, 3 * mm.upper, 9)
    J = [class_cost(classes, mu, solve_classes(reactor, classes, mu).levels, cost) for mu in grid]
    assert np.all(np.diff(J) >= -1e-9 * max(J))
    with pytest.raises(InfeasibleDesign):  # and infeasible just below μ1,min, by both engines
        design_delay(reactor, full_delay_language(5, 2), mm.lower * (1 - 1e-4), cost=cost)
    with pytest.raises(InfeasibleDesign):
        design_delay(reactor, full_delay_language(5, 2), mm.lower * (1 - 1e-4), cost=cost, engine="tree")


def test_dual_certificate_is_a_true_lower_bound(reactor):
    """The dual point behind ``lower`` is feasible for the LAD dual: Z λ = 0, |λ| <= β (checked here again)."""
    from eqrec.bounds.data_classes import class_maps
    from eqrec.bounds.stacking import Stacking
    from eqrec.design.classes.mu1_min import _dual_lower_certificate

    classes = classes_of_full_language(5, 2)
    st = Stacking(reactor, 5)
    mm = min_recovery_level(reactor, classes)
    cls = classes.classes[classes.index(mm.binding["time"], mm.binding["data"])]
    E, Z = class_maps(st, cls)
    beta = st.layout.radius(reactor.eta_w, reactor.eta_v, mm.lower)
    bound = _dual_lower_certificate(E[mm.binding["row"]], Z, beta, "highs")
    assert bound > mm.lower
    # no gain reaches mm.lower on that row: the LAD LP agrees
    lad = solve_classes(reactor, classes, mm.lower)
    assert lad.lp_levels[classes.index(mm.binding["time"], mm.binding["data"]), mm.binding["row"]] > mm.lower


def test_no_recovery_level_when_the_initial_error_cannot_contract():
    unstable = AffineSystem(A=np.array([[2.0]]), C=np.array([[1.0]]), E=np.zeros((1, 0)), eta_w=0.0, eta_v=0.1)
    with pytest.raises(InfeasibleDesign, match="terminal class"):
        min_recovery_level(unstable, classes_of_tree(PrefixTree(["000"], kind="missing")))


# --- scale -------------------------------------------------------------------------------------------------

def test_full_language_30_4_without_enumeration(reactor):
    classes = classes_of_full_language(30, 4)
    mm = min_recovery_level(reactor, classes)
    d = design_delay(reactor, classes, mm.upper * 1.01, cost="sum")
    assert d.schedule is None and d.patterns == ()
    assert d.class_certificate.terminal <= d.mu1 * (1 + 1e-6)
    assert d.class_certificate.mu2 <= d.mu2 * (1 + 1e-6)
    assert np.isfinite(d.J)


def test_block_lp_has_one_block_per_class_and_row(reactor):
    classes = classes_of_full_language(5, 2)
    model = build_class_lp(reactor, classes, 0.5)
    assert model.blocks == len(classes) * reactor.n
    assert isinstance(model.lp, LinearProgram) and sp.issparse(model.lp.A)


def test_active_maps_are_the_class_maps_on_the_active_columns(reactor):
    """active_maps keeps exactly the coordinates E_d or Z_S touches (active_columns), in order; the others are
    zero in both."""
    from eqrec.bounds.data_classes import class_maps
    from eqrec.bounds.stacking import Stacking
    from eqrec.design.delay.languages import delay_classes

    classes = delay_classes(max_delay=2, horizon=5)
    st = Stacking(reactor, classes.horizon)
    for cls in classes.classes:
        E, Z = class_maps(st, cls)
        act = active_columns(E, Z)
        Ea, Za, act2 = active_maps(st, cls)
        np.testing.assert_array_equal(act2, act)
        assert np.all(np.diff(act) > 0)
        assert Ea.tobytes() == E[:, act].tobytes() and Za.tobytes() == Z[:, act].tobytes()
        rest = np.setdiff1d(np.arange(E.shape[1]), act)
        assert not np.any(E[:, rest]) and not np.any(Z[:, rest])
        assert np.all(np.any(E[:, act] != 0, axis=0) | np.any(Z[:, act] != 0, axis=0))
