"""Augmented designs: LP with fixed L, s0 (HiGHS/Clarabel), value updates, IPOPT, certification."""
import numpy as np
import pytest

from eqrec.design.augmented.model import AugmentedGains, AugmentedStacking
from eqrec.design.augmented.runtime import augmented_to_time_based
from eqrec.design.augmented.design import design_augmented
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.nlp import solve_free_ipopt
from eqrec.design.observers import place_observer
from eqrec.studies.p2.readings import heatmap_poles
from eqrec.design.prefix.time_based import design_time_based
from eqrec.errors import InputError
from eqrec.lp.solvers import solve_lp


@pytest.fixture(scope="module")
def L0(acc):
    return place_observer(acc.A, acc.C, [0.0, 0.5, -0.5]).L


@pytest.fixture(scope="module")
def tb_100111(acc):
    return design_time_based(acc, ["100111"], 1.0).mu2


def test_pole_placement(acc):
    pp = place_observer(acc.A, acc.C, heatmap_poles(0.8, 1.0))
    assert pp.ok
    assert np.allclose(np.sort_complex(np.linalg.eigvals(acc.A - pp.L @ acc.C)),
                       np.sort_complex(heatmap_poles(0.8, 1.0)), atol=1e-8)
    bad = place_observer(acc.A, acc.C, [0.0, 0.0, 0.0])  # triple pole, rank C = 2
    assert not bad.ok and bad.L is None and "repeated" in bad.message
    assert place_observer(acc.A, acc.C, heatmap_poles(0.5, np.pi)).ok  # θ = π is a real double pole


@pytest.mark.parametrize("word", ["111111", "100111"])
def test_lp_equals_time_based_and_solvers_agree(acc, L0, word):
    """Fixed L, s0: the augmented optimum is the time-based optimum (bijection); HiGHS and Clarabel agree."""
    m = AugmentedLP(acc, word, 1.0, L0)
    h = m.solve("highs").require_optimal()
    c = m.solve("clarabel").require_optimal()
    tb = design_time_based(acc, [word], 1.0).mu2
    assert h.objective == pytest.approx(tb, rel=1e-7)
    assert c.objective == pytest.approx(h.objective, rel=1e-6)


@pytest.mark.parametrize("mode", ["leak", "theorem2", "masked_gain"])
def test_set_L_matches_fresh_build(acc, L0, mode):
    """The in-place update (coefficients, and in the literal reading the bounds of the rows of G0) is the LP a
    fresh build gives at the new L, entry for entry, bit for bit; so are the answers."""
    m = AugmentedLP(acc, "100111", 1.0, L0, mode=mode)
    for r, theta in ((1.2, 0.4), (0.3, 2.5)):
        L1 = place_observer(acc.A, acc.C, heatmap_poles(r, theta)).L
        lp = m.set_L(L1)
        fresh = AugmentedLP(acc, "100111", 1.0, L1, mode=mode).lp
        assert np.array_equal(lp.A.toarray(), fresh.A.toarray())
        assert np.array_equal(lp.row_upper, fresh.row_upper) and np.array_equal(lp.row_lower, fresh.row_lower)
        a, b = solve_lp(lp), solve_lp(fresh)
        assert a.status == b.status and (a.status != "optimal" or np.array_equal(a.x, b.x))


def test_masked_gain_with_s0_is_rebuilt_at_each_L(acc, L0):
    s0 = np.array([1.0, -2.0, 0.5])
    m = AugmentedLP(acc, "100111", 1.0, L0, s0=s0, mode="masked_gain")
    L1 = place_observer(acc.A, acc.C, heatmap_poles(0.8, 1.1)).L
    lp = m.set_L(L1)
    fresh = AugmentedLP(acc, "100111", 1.0, L1, s0=s0, mode="masked_gain").lp
    assert np.array_equal(lp.row_upper, fresh.row_upper) and np.array_equal(lp.A.toarray(), fresh.A.toarray())


def test_s0_invariance(acc, L0, tb_100111):
    """P2-S0: s0 changes neither the optimum nor, for the mapped optimum, the estimator."""
    m0 = AugmentedLP(acc, "100111", 1.0, L0)
    g0 = m0.gains(m0.solve().require_optimal())
    s0 = np.array([1.0, -2.0, 0.5])
    m1 = AugmentedLP(acc, "100111", 1.0, L0, s0=s0)
    assert m1.solve().objective == pytest.approx(tb_100111, rel=1e-7)
    with pytest.raises(InputError):
        m1.set_L(L0)
    z0 = AugmentedStacking(acc, "100111", L0).Zs.reshape(-1, 3) @ s0
    g1 = AugmentedGains("100111", g0.L, s0, g0.M, g0.nu - g0.M @ z0)
    F0, u00 = augmented_to_time_based(acc, g0)
    F1, u01 = augmented_to_time_based(acc, g1)
    assert np.allclose(F0, F1, atol=1e-10) and np.allclose(u00, u01, atol=1e-10)
    g_bad = AugmentedGains("100111", g0.L, s0, g0.M, g0.nu)  # same (M, ν), other s0: a different estimator
    assert np.abs(augmented_to_time_based(acc, g_bad)[1] - u00).max() > 1e-3


def test_design_augmented_certified(acc, tb_100111, published):
    d = design_augmented(acc, ["101111", "110111"], 1.0)
    assert d.method == "augmented" and d.words == ("100111",)
    assert d.schedule.time_based
    assert d.certificate.mu2 == pytest.approx(tb_100111, rel=1e-7)
    assert d.certificate.terminal <= 1.0 + 1e-7
    aug = d.augmented  # the typed record: L, s0, M, nu as the JSON writes them, from the gains
    assert (aug.s0, aug.M, aug.nu) == (aug.gains.s0.tolist(), aug.gains.M.tolist(), aug.gains.nu.tolist())
    assert aug.mode == "theorem2" and d.worst_case_word == "100111" and aug.poles is not None and d.extra == {}
    d2 = design_augmented(acc, ["111111"], 1.0, L=np.zeros((3, 2)), solver="clarabel")
    assert d2.certificate.mu2 == pytest.approx(published("P2-F1:mu2-time"), abs=1e-6)  # no missing data


def test_ipopt_free_design(acc, tb_100111):
    d = design_augmented(acc, ["100111"], 1.0, L="free")
    assert d.solution.solver == "ipopt" and d.augmented.ipopt_iterations > 0
    assert d.certificate.mu2 == pytest.approx(tb_100111, rel=1e-6)  # cannot beat the time-based bound


def test_ipopt_solves_the_lp(acc, L0, tb_100111):
    m = AugmentedLP(acc, "100111", 1.0, L0)
    g0 = AugmentedGains("100111", m.L, np.zeros(3), np.zeros((18, 12)), np.zeros(18))
    res = solve_free_ipopt(m, g0, 10.0, free_L=False, free_s0=False)
    assert res.success and res.mu2 == pytest.approx(tb_100111, rel=1e-6)
    assert np.allclose(res.gains.L, m.L)


def test_strictly_causal_reading_is_worse(acc, L0, published):
    m = AugmentedLP(acc, "111111", 1.0, L0, strictly_causal=True)
    assert m.solve().objective > published("P2-F1:mu2-time") + 1e-3


def test_bad_inputs(acc):
    with pytest.raises(InputError):
        design_augmented(acc, ["111111"], 1.0, L="auto")
    with pytest.raises(InputError):
        design_augmented(acc, ["111111"], 1.0, poles=[0.0, 0.0, 0.0])
    with pytest.raises(InputError):
        AugmentedLP(acc, "111111", -1.0, np.zeros((3, 2)))
    with pytest.raises(InputError):
        design_augmented(acc, ["111111"], 1.0, mode="hold")


def test_masked_gain_reading_reproduces_fig2_and_the_fig3b_interval(acc, published):
    """The Appendix read with Φ = A - LC at every step gives the published μ2 (P2-F2:mu2-masked-gain) and [-10/14, 13/14]."""
    Lp = published("P2-F2:L")  # printed L of Fig. 2 (input data of the figure)
    mu2 = published("P2-F2:mu2-masked-gain")
    m = AugmentedLP(acc, "100111", 1.0, Lp, mode="masked_gain")
    assert m.solve().objective == pytest.approx(mu2, abs=1e-7)
    flat = []
    for k in range(-12, 16):
        if k == 0:
            continue
        m.set_L(place_observer(acc.A, acc.C, np.array([0.0, k / 14, k / 14])).L)
        sol = m.solve()
        if sol.optimal and abs(sol.objective - mu2) < 1e-6:
            flat.append(k)
    assert flat == [k for k in range(-10, 14) if k != 0]
    d = design_augmented(acc, ["101111", "110111"], 1.0, L=Lp, mode="masked_gain")
    assert d.augmented.certified_runtime == "hold" and d.certificate.mu2 > 10  # what the design really guarantees


def test_deadbeat_observer_where_place_poles_refuses(acc):
    from eqrec.design.observers import deadbeat_observer

    assert not place_observer(acc.A, acc.C, np.zeros(3)).ok  # triple pole, rank C = 2
    d = deadbeat_observer(acc.A, acc.C)
    assert d.ok
    assert np.linalg.norm(np.linalg.matrix_power(acc.A - d.L @ acc.C, 3)) < 1e-10


# --------------------------------------------------------------------------- best guarantee among the LP's optima

@pytest.fixture(scope="module")
def printed_L(published):
    return published("P2-F2:L")


def test_runtimes_agree_until(acc, printed_L):
    """The hold and theorem2 runtimes have the same error up to t = 3 on 100111 for any gains, not after."""
    from eqrec.bounds.certify import closed_loop_maps
    from eqrec.design.augmented.guarantee import runtimes_agree_until
    from eqrec.design.augmented.runtime import schedule_from_augmented

    assert runtimes_agree_until("100111") == 3 and runtimes_agree_until("111111") == 6
    assert runtimes_agree_until("111100") == 6
    m = AugmentedLP(acc, "100111", 1.0, printed_L, mode="masked_gain")
    g = m.gains_from_x(np.random.default_rng(1).normal(size=m.lp.shape[1]))
    maps = {rt: closed_loop_maps(acc, schedule_from_augmented(acc, g, rt), "100111")[:2] for rt in ("hold", "theorem2")}
    for k in range(2):
        assert np.allclose(maps["hold"][k][:4], maps["theorem2"][k][:4], atol=1e-10)
        assert not np.allclose(maps["hold"][k][4:], maps["theorem2"][k][4:], atol=1e-6)


@pytest.mark.parametrize("runtime", ["theorem2", "hold"])
def test_best_guarantee_among_optima(acc, printed_L, runtime):
    """γ* over the masked_gain optima at the printed L: ≤ every solver's pick as run, = certify() of its own
    gains, which are optimal for the masked_gain LP; HiGHS and Clarabel agree."""
    from eqrec.lp.robust import worst_case_abs
    from eqrec.design.augmented.design import certify_augmented
    from eqrec.design.augmented.guarantee import best_guarantee_among_optima

    words = ["100111", "101111", "110111"]
    m = AugmentedLP(acc, "100111", 1.0, printed_L, mode="masked_gain")
    res = {}
    for solver in ("highs", "clarabel"):
        r = best_guarantee_among_optima(acc, "100111", 1.0, printed_L, runtime=runtime, solver=solver)
        assert r.exact and r.lower <= r.upper * (1 + 1e-9) + 1e-9
        cert = certify_augmented(acc, r.gains, words, 1.0, runtime)[1]
        assert cert.mu2 == pytest.approx(r.value, rel=1e-6)
        # the gains are optimal for the masked_gain design LP (within its stated tolerance)
        G, c = AugmentedStacking(acc, "100111", printed_L, "masked_gain").error_map(r.gains.M, r.gains.nu, r.gains.s0)
        wc = worst_case_abs(G, c, m.radius).reshape(7, 3)
        assert wc[:-1].max() <= r.optimum_bound * (1 + 1e-8) and wc[-1].max() <= 1.0 + 1e-8
        assert r.optimum_bound == pytest.approx(r.design_optimum * (1 + 1e-7) + 1e-9, rel=1e-12)
        # the solver's own pick is one optimum: its certified worst case as run is at least γ*
        pick = certify_augmented(acc, m.gains(m.solve(solver).require_optimal()), words, 1.0, runtime)[1]
        assert r.value <= pick.mu2 * (1 + 1e-6)
        res[solver] = r.value
    assert res["highs"] == pytest.approx(res["clarabel"], rel=1e-6)


def test_best_terminal_among_optima_and_inputs(acc, printed_L):
    from eqrec.design.augmented.design import certify_augmented
    from eqrec.design.augmented.guarantee import best_guarantee_among_optima

    r = best_guarantee_among_optima(acc, "100111", 1.0, printed_L, bound="terminal")
    cert = certify_augmented(acc, r.gains, ["100111"], 1.0, "theorem2")[1]
    assert r.exact and cert.terminal == pytest.approx(r.value, rel=1e-6)
    rec = best_guarantee_among_optima(acc, "100111", 1.0, printed_L, recover=True)
    assert certify_augmented(acc, rec.gains, ["100111"], 1.0, "theorem2")[1].terminal <= 1.0 + 1e-6
    with pytest.raises(InputError):
        best_guarantee_among_optima(acc, "100111", 1.0, printed_L, bound="middle")
    with pytest.raises(InputError):
        best_guarantee_among_optima(acc, "100111", 1.0, printed_L, runtime="leak")
