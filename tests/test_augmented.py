"""Augmented estimator: stacked maps, conversion both ways, runtime recursions."""
import numpy as np
import pytest

from eqrec.bounds.gains import schedule_from_word_gains
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_pattern
from eqrec.design.augmented.model import AugmentedGains, AugmentedStacking, as_time_varying_L
from eqrec.design.augmented.runtime import (augmented_to_prefix, augmented_to_time_based, prefix_to_augmented,
                                            schedule_from_augmented)
from eqrec.estimators.augmented import AugmentedEstimator
from eqrec.bounds.certify import closed_loop_maps
from eqrec.errors import InputError
from eqrec.simulate.loop import sample_uncertainty, simulate_run
from eqrec.bounds.stacking import UncertaintyLayout


def paper_blocks(aug, M):
    """Eq. (5) of the augmented paper literally: ``Θ, Ψ, Ξ, Υ`` from the Appendix matrices (time-varying ``Φ_k``).

    ``C``, ``V`` and ``W`` unmasked; missing data enters only through ``M Λ_i = 0`` and the
    block-diagonal ``L`` (zero at missing steps in "theorem2" and "masked_gain").
    """
    m = aug.appendix_matrices()
    E, A, Gam, Phi, C, L, W, V = (m[k] for k in ("E", "A", "Gamma", "Phi", "C", "L", "W", "V"))
    I = np.eye(A.shape[0])
    ML = M + L
    Xi = (I + E @ ML @ C) @ Phi
    return {"Theta": (I + E @ ML @ C) @ Gam @ W, "Psi": (E @ ML @ (np.eye(C.shape[0]) - C @ Gam @ L) - Gam @ L) @ V,
            "Xi": Xi, "Upsilon": A - Xi, "E": E}


def random_gains(rng, word, n=3, p=2, mode="theorem2", time_varying=False):
    T = len(word)
    L = rng.normal(size=(T, n, p)) * 0.5 if time_varying else rng.normal(size=(n, p)) * 0.5
    M = np.zeros((T * n, T * p))
    for k in range(T):
        for i in range(k + 1):
            if word[i] == "1":
                M[k * n:(k + 1) * n, i * p:(i + 1) * p] = rng.normal(size=(n, p)) * 0.3
    return AugmentedGains(word, as_time_varying_L(L, T, n, p), rng.normal(size=n), M, rng.normal(size=T * n) * 0.1, mode)


@pytest.mark.parametrize("word", ["111111", "100111", "011010"])
@pytest.mark.parametrize("mode", ["theorem2", "leak"])
def test_paper_formulas_match_propagation(acc, rng, word, mode):
    """Eq. (5) literally (Appendix matrices, time-varying Φ_k) equals the propagated error map."""
    g = random_gains(rng, word, time_varying=True)
    aug = AugmentedStacking(acc, word, g.L, mode)
    G, c = aug.error_map(g.M, g.nu, g.s0)
    pb = paper_blocks(aug, g.M)
    Gp = np.hstack([pb["Theta"], pb["Psi"], pb["Xi"]])
    assert np.allclose(Gp, G, atol=1e-12)
    assert np.allclose(pb["Upsilon"] @ g.s0 + pb["E"] @ g.nu, c, atol=1e-12)


@pytest.mark.parametrize("word", ["111111", "100111", "110011"])
def test_forward_conversion_reproduces_error_map(acc, rng, word):
    """The converted time-based estimator has exactly the augmented error map (eq. (10))."""
    g = random_gains(rng, word)
    sch = schedule_from_augmented(acc, g)
    Gc, cc, lay = closed_loop_maps(acc, sch, word)
    G, c = AugmentedStacking(acc, word, g.L, "theorem2").error_map(g.M, g.nu, g.s0)
    assert np.allclose(Gc.reshape(-1, lay.size), G, atol=1e-12)
    assert np.allclose(cc.reshape(-1), c, atol=1e-12)


def time_based_to_augmented(system, word, F, u0, L, s0, runtime):
    """One word's time-based gains as augmented prefix gains (:func:`prefix_to_augmented` on a one-word tree)."""
    tree = PrefixTree([word])
    sch = schedule_from_word_gains(tree, {word: (F, u0)}, system.n, system.p, time_based=True)
    return prefix_to_augmented(system, tree, sch, L, s0, runtime)


@pytest.mark.parametrize("runtime", ["theorem2", "hold"])
@pytest.mark.parametrize("word", ["111111", "100111"])
def test_round_trip_both_directions(acc, rng, word, runtime):
    T, n, p = 6, 3, 2
    pattern = as_pattern(word)
    g = random_gains(rng, word, mode=runtime)
    F, u0 = augmented_to_time_based(acc, g, runtime)
    g2 = time_based_to_augmented(acc, word, F, u0, g.L, g.s0, runtime)
    for k in range(T):  # M(k, i) over the measurements available at k: M's columns there
        cols = np.concatenate([np.arange(i * p, (i + 1) * p) for i in pattern.prefix(k + 1).available(k)])
        M, nu = g2.rows[pattern.prefix(k + 1)]
        assert np.allclose(M, g.M[k * n:(k + 1) * n, cols], atol=1e-10)
        assert np.allclose(nu, g.nu[k * n:(k + 1) * n], atol=1e-10)
    # time-based -> augmented -> time-based for random (F, u0), another L and s0
    F = np.zeros((T * n, T * p))
    for k in range(T):
        for i in range(k + 1):
            if word[i] == "1":
                F[k * n:(k + 1) * n, i * p:(i + 1) * p] = rng.normal(size=(n, p))
    u0 = rng.normal(size=T * n)
    ga = time_based_to_augmented(acc, word, F, u0, rng.normal(size=(n, p)), rng.normal(size=n), runtime)
    F2, u02 = augmented_to_prefix(acc, PrefixTree([word]), ga, runtime).word_matrices(word)
    assert np.allclose(F2, F, atol=1e-9) and np.allclose(u02, u0, atol=1e-9)
    # M has a column block per available measurement only (zero gains on missing steps by construction)
    assert all(M.shape == (n, p * len(pre.available(pre.T - 1))) for pre, (M, _) in ga.rows.items())


@pytest.mark.parametrize("runtime", ["theorem2", "hold"])
def test_runtime_estimator_equals_converted(acc, rng, runtime):
    """Both recursions (x̂, s) run causally give the x̂ of the converted time-based estimator."""
    word = "100111"
    g = random_gains(rng, word, mode=runtime)
    sch = schedule_from_augmented(acc, g, runtime)
    lay = UncertaintyLayout(6, acc.nw, acc.nv, acc.n)
    rad = lay.radius(acc.eta_w, acc.eta_v, 1.0)
    x0 = np.array([20.0, 40.0, 20.0])
    for actual in ("100111", "101111"):
        delta = sample_uncertainty(lay, rad, rng)
        tr = simulate_run(acc, sch, actual, delta, x0)
        w, v, xi0 = lay.split(delta)
        est = AugmentedEstimator(acc, g, runtime=runtime).reset(x0 - xi0)
        x = x0.copy()
        for t in range(6):
            y = acc.C @ x + v[t] if actual[t] == "1" else None
            xh, _ = est.step(y)
            x = acc.A @ x + acc.f + acc.E @ w[t]
            assert np.allclose(xh, tr.xhat[t + 1], atol=1e-10)
    with pytest.raises(InputError):
        est.step(None)


def test_hold_and_theorem2_differ(acc, rng):
    """The missing-step reading matters for given gains (not a vacuous option)."""
    g = random_gains(rng, "100111")
    F1, _ = augmented_to_time_based(acc, g, "theorem2")
    F2, _ = augmented_to_time_based(acc, g, "hold")
    assert np.abs(F1 - F2).max() > 1e-3


def test_bad_inputs(acc):
    with pytest.raises(InputError):
        as_time_varying_L(np.zeros((2, 2)), 6, 3, 2)
    with pytest.raises(InputError):
        AugmentedStacking(acc, "100111", np.zeros((3, 2)), mode="hold")
    with pytest.raises(InputError):
        AugmentedStacking(acc, "10a111", np.zeros((3, 2)))
    with pytest.raises(InputError):
        augmented_to_time_based(acc, AugmentedGains("111111", np.zeros((6, 3, 2)), np.zeros(3), np.zeros((18, 12)),
                                                    np.zeros(18)), "leak")


def test_masked_gain_reading_is_the_appendix_formula_and_differs_from_the_dynamics(acc, rng):
    """'masked_gain': Φ_k = A - L C at every step, block-diagonal L zeroed at missing steps (issue 9)."""
    word = "100111"
    g = random_gains(rng, word)
    aug = AugmentedStacking(acc, word, g.L, "masked_gain")
    G, c = aug.error_map(g.M, g.nu, g.s0)
    pb = paper_blocks(aug, g.M)
    assert np.allclose(np.hstack([pb["Theta"], pb["Psi"], pb["Xi"]]), G, atol=1e-12)
    assert np.allclose(pb["Upsilon"] @ g.s0 + pb["E"] @ g.nu, c, atol=1e-12)
    # on a word without missing steps every reading is the same model
    full = AugmentedStacking(acc, "111111", g.L, "masked_gain").error_map(g.M, g.nu, g.s0)[0]
    assert np.allclose(full, AugmentedStacking(acc, "111111", g.L, "theorem2").error_map(g.M, g.nu, g.s0)[0])
    # with missing steps it is not the closed loop of any running estimator
    assert not np.allclose(G, AugmentedStacking(acc, word, g.L, "leak").error_map(g.M, g.nu, g.s0)[0])


@pytest.mark.parametrize("runtime", ["theorem2", "hold"])
def test_runtime_on_packets_equals_the_converted_prefix_schedule(acc, rng, runtime):
    """Delay words (P3 form (4)): the estimator on time-stamped packets gives the x̂ of its prefix-based schedule,
    late measurements entering through M with the stored x̂(τ), s(τ)."""
    from eqrec.arrivals.words import full_delay_language
    from eqrec.design.augmented.model import AugmentedPrefixGains

    n, p, T = 3, 2, 4
    tree = PrefixTree(full_delay_language(T, 1), kind="delay")
    rows = {node.prefix: (rng.normal(size=(n, p * len(node.available))) * 0.3, rng.normal(size=n) * 0.1)
            for node in tree}
    gains = AugmentedPrefixGains(rows, as_time_varying_L(rng.normal(size=(n, p)) * 0.5, T, n, p), rng.normal(size=n))
    sch = augmented_to_prefix(acc, tree, gains, runtime)
    lay = UncertaintyLayout(T, acc.nw, acc.nv, acc.n)
    rad = lay.radius(acc.eta_w, acc.eta_v, 1.0)
    x0 = np.array([20.0, 40.0, 20.0])
    late = 0
    for pat in tree.patterns:
        late += any(a is not None and a > t for t, a in enumerate(pat.arrivals))
        delta = sample_uncertainty(lay, rad, rng)
        tr = simulate_run(acc, sch, pat, delta, x0)
        _, v, xi0 = lay.split(delta)
        est = AugmentedEstimator(acc, gains, runtime=runtime).reset(x0 - xi0)
        y = [acc.C @ tr.x[t] + v[t] for t in range(T)]
        xh = [est.step([(tau, y[tau]) for tau in pat.arriving_at(t)])[0] for t in range(T)]
        assert np.allclose(np.array(xh), tr.xhat[1:], atol=1e-9)
    assert late > 0
