"""Prefix-based and time-based designs (Theorem 3 of the prefix-based paper)."""
import cvxpy as cp
import numpy as np
import pytest

from eqrec.design.prefix.design import design_prefix
from eqrec.design.prefix.tree_lp import build_prefix_lp
from eqrec.design.prefix.time_based import design_time_based
from eqrec.errors import InfeasibleDesign, InputError
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import prefixes
from eqrec.bounds.stacking import Stacking


def paper_copy_per_word_optimum(system, words, mu1):
    """The paper's form: one (Q(i), r(i)) per word, equality constraints BM_|p| on shared prefixes (eq. (11)),
    error from eq. (13) with the paper's stacked matrices, robust counterpart by |.| (cvxpy)."""
    T = len(words[0])
    st = Stacking(system, T)
    n, p = system.n, system.p
    radius = st.layout.radius(system.eta_w, system.eta_v, mu1)
    mu2 = cp.Variable()
    Qs = {w: cp.Variable((T * n, T * p)) for w in words}
    rs = {w: cp.Variable(T * n) for w in words}
    cons = [mu2 >= mu1]
    mask = np.kron(np.tril(np.ones((T, T))), np.ones((n, p)))  # block lower triangular
    for w in words:
        cons.append(cp.multiply(1 - mask, Qs[w]) == 0)
        S, Cb, J, N = st.S, st.C_bar(w), st.J, st.N(w)
        I = np.eye(S.shape[0])
        G = cp.hstack([(S + S @ Qs[w] @ Cb @ S) @ st.E_blk, S @ Qs[w] @ N, (I + S @ Qs[w] @ Cb) @ J])
        c = S @ rs[w]
        worst = cp.abs(c) + cp.abs(G) @ radius
        cons += [worst[: T * n] <= mu2, worst[T * n:] <= mu1]
    for a in words:
        for b in words:
            if a < b:
                k = max(len(q) for q in prefixes(a) if b.startswith(q)) if a[0] == b[0] else 0
                if k:
                    cons += [Qs[a][: k * n, : k * p] == Qs[b][: k * n, : k * p], rs[a][: k * n] == rs[b][: k * n]]
    prob = cp.Problem(cp.Minimize(mu2), cons)
    prob.solve(solver=cp.CLARABEL)
    return prob.value


@pytest.mark.parametrize("words", [["1011", "1101"], ["101111", "110111", "111011", "111101"]])
def test_node_shared_form_equals_paper_copy_per_word_form(acc, words):
    ours = design_prefix(acc, words, 1.0).mu2
    paper = paper_copy_per_word_optimum(acc, words, 1.0)
    assert ours == pytest.approx(paper, rel=1e-6)


@pytest.mark.parametrize("form", ["split", "abs", "dual"])
@pytest.mark.parametrize("solver", ["highs", "clarabel"])
def test_solvers_and_robust_forms_agree(acc, L1_words, solver, form):
    ref = design_prefix(acc, L1_words, 1.0).mu2
    d = design_prefix(acc, L1_words, 1.0, solver=solver, form=form, engine="tree")
    assert d.mu2 == pytest.approx(ref, rel=1e-6)
    assert d.certificate.mu2 <= d.mu2 * (1 + 1e-6)


def test_prefix_beats_time_based_and_proposition_3(acc, L1_words):
    p = design_prefix(acc, L1_words, 1.0)
    t = design_time_based(acc, L1_words, 1.0)
    assert p.mu2 < t.mu2
    # Proposition 3: a time-based estimator is a prefix-based one, certified on every word of L1
    for w in L1_words:
        assert t.certificate.words[w].bounds.max() <= t.mu2 * (1 + 1e-9)


def test_prefix_gains_are_shared_along_prefixes(acc, L1_words):
    d = design_prefix(acc, L1_words, 1.0)
    F_a, u_a = d.schedule.word_matrices("111011")
    F_b, u_b = d.schedule.word_matrices("111101")
    # shared prefix "111" -> the first three block rows agree (Proposition 1)
    np.testing.assert_allclose(F_a[:9], F_b[:9])
    np.testing.assert_allclose(u_a[:9], u_b[:9])


def test_missing_measurement_columns_are_zero(acc, L1_words):
    d = design_time_based(acc, L1_words, 1.0)
    F, _ = d.schedule.word_matrices("100001")
    for tau in range(1, 5):
        assert np.all(F[:, tau * 2:(tau + 1) * 2] == 0)


def test_finite_length_language(acc):
    d = design_prefix(acc, ["1011", "11011", "111011"], 1.0, fixed_length=False)  # Section V
    for w, wc in d.certificate.words.items():
        assert wc.bounds.shape == (len(w) + 1, 3)
        assert wc.bounds[-1].max() <= 1.0 + 1e-6


def test_infeasible_and_bad_inputs(acc, L1_words):
    with pytest.raises(InfeasibleDesign):
        design_prefix(acc, L1_words, 0.1)
    with pytest.raises(InputError, match="mu1"):
        design_prefix(acc, L1_words, -1.0)
    with pytest.raises(InputError, match="exceed the horizon"):
        build_prefix_lp(acc, L1_words, 1.0, T=4)
    with pytest.raises(InputError, match="alphabet"):
        design_prefix(acc, ["10x111"], 1.0)
    with pytest.raises(InputError, match="engine"):
        design_prefix(acc, L1_words, 1.0, engine="nodes")
    with pytest.raises(InputError, match="tree LP"):
        design_prefix(acc, L1_words, 1.0, form="dual")


def test_optimum_is_a_lower_bound(acc, L1_words):
    # Theorem 3 is necessary and sufficient: below the optimum the LP is infeasible.
    d = design_prefix(acc, L1_words, 1.0)
    m = build_prefix_lp(acc, PrefixTree(L1_words), 1.0)
    m.lp.col_upper[m.mu2_col] = d.mu2 - 1e-5
    from eqrec.lp.solvers import solve_lp

    assert solve_lp(m.lp, "highs").status == "infeasible"


@pytest.mark.parametrize("method", ["prefix", "time"])
def test_zero_offset_loses_no_optimality(acc, L1_words, method):
    from eqrec.arrivals.words import worst_case_word

    words = L1_words if method == "prefix" else [worst_case_word(L1_words)]
    free = design_prefix(acc, words, 1.0, zero_offset=False, engine="tree")
    fixed = design_prefix(acc, words, 1.0, engine="tree")
    assert fixed.mu2 == pytest.approx(free.mu2, rel=1e-7)
    assert np.all(fixed.schedule.word_matrices(words[0])[1] == 0)


def test_time_varying_system_with_constant_data_matches_lti(acc, L1_words):
    from eqrec.systems.affine import AffineSystem

    tv = AffineSystem(A=np.stack([acc.A] * 6), C=np.stack([acc.C] * 6), E=np.stack([acc.E] * 6),
                      eta_w=acc.eta_w, eta_v=acc.eta_v)
    assert design_prefix(tv, L1_words, 1.0).mu2 == pytest.approx(design_prefix(acc, L1_words, 1.0).mu2, rel=1e-8)


def test_time_varying_system_is_certified(acc):
    from eqrec.systems.affine import AffineSystem

    A = np.stack([acc.A * (1 + 0.02 * k) for k in range(5)])
    tv = AffineSystem(A=A, C=acc.C, E=acc.E, eta_w=acc.eta_w, eta_v=acc.eta_v)
    d = design_prefix(tv, ["10111", "11011"], 1.0)
    assert d.certificate.mu2 <= d.mu2 * (1 + 1e-6)
