"""The delayed-data design (Theorem 1 / Proposition 1 of the delayed-data paper) on the core's prefix LP."""
import numpy as np
import pytest

from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import full_delay_language, parse_delay_word
from eqrec.simulate.loop import simulate_run
from eqrec.lp.solvers import solve_lp
from eqrec.design.cost import cost_weights, paper_cost
from eqrec.design.delay.design import delay_language, design_delay, design_delay_global, min_recovery_level
from eqrec.design.report import level_table, path_levels, to_json, word_certificate
from eqrec.design.delay.ipopt import bilinear_problem, compare_free_routes, design_delay_ipopt
from eqrec.design.prefix.design import design_prefix
from eqrec.design.prefix.tree_lp import build_prefix_lp
from eqrec.errors import InfeasibleDesign, InputError
from eqrec.systems.examples import batch_reactor

ACC_DELAY = ["060000", "006000", "000600", "000060"]  # Sec. IV-B: delay 6 = beyond the horizon = missing


@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


@pytest.fixture(scope="module")
def small_language():
    return delay_language(max_delay=1, horizon=3)  # 8 words, 7 event sequences


def test_delay_language_reduction():
    assert len(delay_language(max_delay=2, horizon=5)) == 162  # |L| = 243 -> |L^E'| = 162
    acc = delay_language(ACC_DELAY, max_delay=6)
    assert [p.canonical_label for p in acc] == ["101111", "110111", "111011", "111101"]
    with pytest.raises(InputError):
        delay_language()


@pytest.mark.parametrize("engine", ["classes", "tree"])
def test_cost_counts_k0_and_kT_as_mu1_per_sequence(reactor, small_language, engine):
    tree = PrefixTree(small_language)
    a, w = cost_weights(tree, "sum")
    assert a == 1 + 2 * len(tree.patterns)
    d = design_delay(reactor, tree, 1.0, cost="sum", engine=engine)

    def level_of(pat, k):  # μ2,k^α literally: μ1 at k = 0 and k = T, the prefix node's level in between
        return d.mu1 if k in (0, pat.T) else d.levels[pat.prefix(k).label]

    J_literal = d.mu1 + sum(level_of(pat, k) for pat in tree.patterns for k in range(tree.depth + 1))  # μ1 + Σ_k Σ_α
    assert d.J == pytest.approx(J_literal, rel=1e-12)
    assert paper_cost(tree, d.mu1, d.levels) == pytest.approx(J_literal, rel=1e-12)
    if engine == "tree":  # the tree LP's objective is J without its μ1 term
        assert d.J == pytest.approx(d.solution.objective + a * d.mu1, rel=1e-9)
    assert d.J_certified <= d.J * (1 + 1e-6)
    for pat in tree.patterns:
        lv = path_levels(d, pat)
        assert lv[0] == lv[-1] == d.mu1 and len(lv) == pat.T + 1
        assert np.all(word_certificate(d, pat).bounds.max(axis=1) <= lv * (1 + 1e-6))


def test_acc_language_with_mu1_1_is_the_p1_prefix_problem(acc, published):
    """Sec. IV-B: the missing-data language written as delays, μ1 = 1: the same problem as P1's prefix design."""
    p1 = design_prefix(acc, ["101111", "110111", "111011", "111101"], 1.0)
    d_max = design_delay(acc, ACC_DELAY, 1.0, cost="max")
    d_sum = design_delay(acc, ACC_DELAY, 1.0, cost="sum")
    assert d_max.mu2 == pytest.approx(p1.mu2, rel=1e-9)
    assert d_sum.mu2 == pytest.approx(p1.mu2, rel=1e-7)  # the sum cost reaches the same largest level
    assert round(d_max.mu2, 4) == published("P3-ACC:mu2")
    assert min(d_sum.levels.values()) == pytest.approx(1.0)  # time-varying: not always at the maximum


def test_bilinear_problem_at_fixed_mu1_is_the_tree_lp(reactor, small_language):
    """Problem (10) as data (IPOPT's route): at μ1 fixed it is the tree LP at that μ1."""
    from eqrec.lp.model import LinearProgram

    tree = PrefixTree(small_language)
    bl = bilinear_problem(reactor, tree, "sum")
    a, _ = cost_weights(tree, "sum")
    for mu in (0.8, 1.3):
        direct = solve_lp(build_prefix_lp(reactor, tree, mu, levels="sum").lp)
        lo, hi = bl["base"].col_lower.copy(), bl["base"].col_upper.copy()
        lo[bl["mu1_col"]] = hi[bl["mu1_col"]] = mu
        lo[bl["level_cols"]] = mu
        lp = LinearProgram(c=bl["base"].c, A=bl["A0"] + mu * bl["dA"], row_lower=bl["L0"] + mu * bl["dL"],
                           row_upper=bl["U0"] + mu * bl["dU"], col_lower=lo, col_upper=hi)
        assert solve_lp(lp).objective == pytest.approx(direct.objective + a * mu, rel=1e-9)


def test_min_recovery_level_is_bracketed_and_certified(acc):
    tree = PrefixTree(delay_language(ACC_DELAY, max_delay=6))
    r = min_recovery_level(acc, tree, rtol=1e-5)
    assert r.lower < r.upper <= r.lower * (1 + 1.1e-5) and r.lower_margin > 0
    assert r.binding["time"] == 6 and 0 <= r.binding["row"] < acc.n
    for engine in ("classes", "tree"):
        design_delay(acc, tree, r.upper, cost="max", engine=engine)  # feasible (and certified) at the upper end
        with pytest.raises(InfeasibleDesign):
            design_delay(acc, tree, r.lower * (1 - 1e-4), cost="max", engine=engine)
    # plain bisection on LP feasibility agrees
    lo, hi = 0.1, 1.0
    for _ in range(25):
        mid = 0.5 * (lo + hi)
        ok = solve_lp(build_prefix_lp(acc, tree, mid).lp).optimal
        lo, hi = (lo, mid) if ok else (mid, hi)
    assert hi == pytest.approx(r.upper, rel=1e-5)
    assert r.lps == 2  # one Charnes-Cooper LP and one dual LP: no search


@pytest.mark.parametrize("cost", ["sum", "max"])
def test_acc_mu1_free_global_and_ipopt(acc, cost, published):
    g = design_delay_global(acc, ACC_DELAY, cost=cost, rtol=1e-4)
    assert g.gap <= 1e-4 and g.design.certificate is not None
    assert round(g.design.mu2, 4) == published("P3-ACC:footnote-mu1-free")  # footnote 1 of Sec. IV-B (μ1 free)
    # the lower bound holds on a grid of μ1 (fixed-μ1 LPs)
    tree = PrefixTree(delay_language(ACC_DELAY, max_delay=6))
    for mu in np.linspace(g.mu1, 3 * g.mu1, 7)[1:]:
        d = design_delay(acc, tree, mu, cost=cost, certify=False)
        assert d.J >= g.lower_bound * (1 - 1e-9)
    i = design_delay_ipopt(acc, ACC_DELAY, cost=cost)
    cmp = compare_free_routes(g, i)
    assert cmp["ipopt_consistent_with_bound"] and cmp["better"] in ("tie", "global")
    assert i.ipopt.polished["J"] == pytest.approx(g.J, rel=1e-4)


def test_delay_design_certified_and_worst_vertices_attained(reactor, small_language):
    d = design_delay(reactor, small_language, 1.0, cost="sum")
    x0 = np.ones(4)
    for pat in small_language:
        wc = word_certificate(d, pat)
        t, i = np.unravel_index(np.argmax(wc.bounds[1:]), wc.bounds[1:].shape)
        t += 1
        run = simulate_run(reactor, d.schedule, pat, wc.worst_vertex(t, i), x0)
        assert abs(run.error[t, i]) == pytest.approx(wc.bounds[t, i], rel=1e-9)
    rows = level_table(d)
    assert rows[0]["k"] == 0 and all(r["certified"] <= r["level"] * (1 + 1e-6) for r in rows)
    js = to_json(d)
    assert js["method"] == "delay" and set(js["gains"]) == {p.label for p in small_language}
    import json

    assert json.loads(json.dumps(js))["mu1"] == d.mu1  # serialisable as the CLI writes it


def test_batch_reactor_at_the_printed_mu1(reactor, published):
    """P3-BR: all 243 words, sum cost, μ1 = 0.33 (the printed, rounded μ1): the largest level as printed (P3-BR:max-mu2)."""
    d = design_delay(reactor, full_delay_language(5, 2), 0.33, cost="sum")
    assert len(d.patterns) == 162
    assert round(d.mu2, 4) == published("P3-BR:max-mu2")
    assert d.certificate.mu2 <= d.mu2 * (1 + 1e-6)


def test_batch_reactor_mu1_free_global(reactor, published):
    """μ1 free: the optimum is the smallest feasible μ1 (0.32931; the paper prints it rounded, P3-BR:mu1)."""
    g = design_delay_global(reactor, full_delay_language(5, 2), cost="sum", rtol=1e-4)
    assert g.gap <= 1e-4
    assert round(g.mu1, 2) == published("P3-BR:mu1") and g.mu1 < published("P3-BR:mu1")
    assert g.mu1 == pytest.approx(g.mu1_min.upper, rel=1e-9)
    assert g.design.mu2 < published("P3-BR:max-mu2")  # max μ2 = ||A^2||_inf μ1 (no data at times 0, 1) is below the printed value
    A2 = np.linalg.matrix_power(batch_reactor().A, 2)
    assert g.design.mu2 == pytest.approx(np.abs(A2).sum(axis=1).max() * g.mu1, rel=1e-7)


def test_bad_inputs(acc):
    with pytest.raises(InputError, match="cost"):
        design_delay(acc, ACC_DELAY, 1.0, cost="mean")
    with pytest.raises(InputError, match="fixed-length"):
        design_delay(acc, [parse_delay_word("0600"), parse_delay_word("06000")], 1.0)


# --- the augmented form (4) with fixed L, s0 -----------------------------------------------------------------

def test_augmented_form_optimum_does_not_depend_on_L_or_s0(reactor):
    """Two pole placements and two s0: the LP in (M^α, ν^α) has the prefix design's optimum (both costs)."""
    from eqrec.design.augmented.tree_lp import solve_augmented_delay
    from eqrec.design.augmented.runtime import augmented_to_prefix
    from eqrec.design.observers import place_observer
    from eqrec.bounds.certify import certify_schedule

    tree = PrefixTree(delay_language(max_delay=2, horizon=4))
    mu1 = 0.5
    ref_sum = design_delay(reactor, tree, mu1, cost="sum", engine="tree")
    ref_max = design_delay(reactor, tree, mu1, cost="max", engine="tree")
    for poles in ([0.1, 0.2, 0.3, 0.4], [-0.5, 0.0, 0.5, 0.9]):
        L = place_observer(reactor.A, reactor.C, poles).L
        for s0 in (np.zeros(4), np.array([0.1, -0.2, 0.05, 0.3])):
            g, sol, _ = solve_augmented_delay(reactor, tree, mu1, L, s0, levels="sum")
            assert sol.objective == pytest.approx(ref_sum.solution.objective, rel=1e-7)
            cert = certify_schedule(reactor, augmented_to_prefix(reactor, tree, g), tree.patterns, mu1)
            assert cert.terminal <= mu1 * (1 + 1e-6)
            if s0.any():
                _, sol_max, _ = solve_augmented_delay(reactor, tree, mu1, L, s0, levels="common")
                assert sol_max.objective == pytest.approx(ref_max.mu2, rel=1e-7)


def test_augmented_gains_are_a_reparametrisation_of_the_prefix_gains(reactor):
    from eqrec.bounds.stacking import UncertaintyLayout
    from eqrec.design.augmented.runtime import augmented_to_prefix, prefix_to_augmented
    from eqrec.estimators.augmented import AugmentedEstimator
    from eqrec.design.observers import place_observer

    tree = PrefixTree(delay_language(max_delay=2, horizon=3))
    d = design_delay(reactor, tree, 0.5, cost="sum")
    L = place_observer(reactor.A, reactor.C, [0.1, 0.2, 0.3, 0.4]).L
    s0 = np.array([0.1, -0.2, 0.05, 0.3])
    aug = prefix_to_augmented(reactor, tree, d.schedule, L, s0)
    back = augmented_to_prefix(reactor, tree, aug)
    for pre, row in d.schedule.rows.items():
        np.testing.assert_allclose(back.row(pre).F, row.F, atol=1e-10)
        np.testing.assert_allclose(back.row(pre).u0, row.u0, atol=1e-10)
    # the augmented runtime (x̂, s on time-stamped packets) gives the prefix estimator's x̂
    rng = np.random.default_rng(0)
    x0 = np.ones(4)
    for pat in tree.patterns:
        lay = UncertaintyLayout(3, 0, 2, 4)
        delta = rng.uniform(-1, 1, lay.size) * lay.radius(0, 0.05, 0.5)
        run = simulate_run(reactor, d.schedule, pat, delta, x0)
        _, v, _ = lay.split(delta)
        est = AugmentedEstimator(reactor, aug).reset(run.xhat[0])
        y = [reactor.C @ run.x[t] + v[t] for t in range(3)]
        xh = [est.step([(tau, y[tau]) for tau in pat.arriving_at(t)])[0] for t in range(3)]
        np.testing.assert_allclose(np.array(xh), run.xhat[1:], atol=1e-10)


def test_noise_free_system_has_no_smallest_positive_mu1(reactor):
    from eqrec.systems.affine import AffineSystem

    quiet = AffineSystem(A=reactor.A, C=reactor.C, E=reactor.E, eta_w=0.0, eta_v=0.0)
    with pytest.raises(InputError, match="smallest recovery level is 0"):
        design_delay_global(quiet, ["000", "010"], kind="delay")
