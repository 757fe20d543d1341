"""LMV recursion of the companion study (zero- and hold-input instances), checked against Monte Carlo.

Tolerance: every covariance entry at every time is compared with the sample second moment through its
standard error (from the sample fourth moments); the family of comparisons passes if the largest |z| is
below the two-sided Bonferroni threshold at family-wise level 1e-3 (z_crit ~ 4.5 for the sizes here).
"""
from pathlib import Path

import numpy as np
import pytest

from eqrec.errors import InputError, NotMeanSquareStable
from eqrec.lmv.model import check_ms_stable, hold_input_system, zero_input_system
from eqrec.lmv.plant import Plant
from eqrec.lmv.recursion import filter_smoother, lmv_recursion, theorem1_as_printed
from eqrec.lmv.steady import steady_state
from eqrec.lmv.monte_carlo import compare_moments, run_mc, simulate_plant
from eqrec.studies.p4.steps import load_config, plant_of

ROOT = Path(__file__).resolve().parents[1]
CFG = load_config(ROOT / "config" / "p4.yaml")


@pytest.fixture(scope="module")
def ex1():
    return plant_of(CFG, "ex1")


@pytest.mark.parametrize("mechanism", ["zero-input", "hold-input"])
def test_theory_matches_monte_carlo(ex1, mechanism):
    rng = np.random.default_rng(7)
    mc = run_mc(ex1, 0.8, mechanism, T=30, runs=4000, N_smooth=2, rng=rng, pred_steps=2)
    T = 30
    checks = [compare_moments(mc.err_pred, mc.P_pred),
              compare_moments(mc.err_smooth[:, :, 0], mc.P_smooth[:, 0]),
              # the lag-2 smoother needs y(t+2): times 0..T-2
              compare_moments(mc.err_smooth[:, : T - 1, 2], mc.P_smooth[: T - 1, 2]),
              compare_moments(mc.err_npred, mc.P_npred)]
    for c in checks:
        assert c.passed, c.summary()


def test_monte_carlo_detects_a_wrong_formula(ex1):
    """The printed eq. (9) under-states P(t|t-1) of Example 1; the same test must reject it."""
    T = 30
    rng = np.random.default_rng(8)
    mc = run_mc(ex1, 0.8, "zero-input", T=T, runs=4000, N_smooth=0, rng=rng)
    printed = theorem1_as_printed(ex1, 0.8, T)
    assert not compare_moments(mc.err_pred, printed["P"][: T + 1]).passed


def test_printed_eq9_equals_corrected_without_output_noise(ex1):
    plant = ex1.with_(Qlam=0.0)
    T = 20
    printed = theorem1_as_printed(plant, 0.8, T)
    res = lmv_recursion(zero_input_system(plant, 0.8), T)
    np.testing.assert_allclose(printed["P"][: T + 1], res.P_pred[: T + 1], rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("builder", [zero_input_system, hold_input_system])
def test_smoother_filter_predictor_ordering(ex1, builder):
    res = lmv_recursion(builder(ex1, 0.8), 40)
    sm = filter_smoother(res, 2)
    n = ex1.n
    for t in range(1, 38):
        pred, filt, smooth = res.P_pred[t, :n, :n], sm.P[t, 0, :n, :n], sm.P[t, 2, :n, :n]
        assert np.linalg.eigvalsh(pred - filt).min() >= -1e-10
        assert np.linalg.eigvalsh(filt - smooth).min() >= -1e-10


@pytest.mark.parametrize("builder", [zero_input_system, hold_input_system])
def test_recursion_converges_to_steady_state(ex1, builder):
    sys = builder(ex1, 0.8)
    ss = steady_state(sys, N_smooth=2)
    res = lmv_recursion(sys, 300)
    np.testing.assert_allclose(res.P_pred[300], ss.P_pred, rtol=1e-6, atol=1e-9)


def test_not_mean_square_stable_is_a_clear_error(ex1):
    unstable = ex1.with_(Qxi=60.0)
    with pytest.raises(NotMeanSquareStable, match="spectral radius"):
        check_ms_stable(zero_input_system(unstable, 0.8))
    with pytest.raises(NotMeanSquareStable):
        steady_state(zero_input_system(unstable, 0.8))


def test_bad_inputs(ex1):
    with pytest.raises(InputError, match="eta_bar"):
        zero_input_system(ex1, 1.5)
    d = dict(CFG["examples"]["ex1"])
    d.pop("mc_mult_dist", None)
    d["H"] = [[1.0, 2.0, 3.0]]
    with pytest.raises(InputError, match="H"):
        Plant.from_dict(d, "p4.yaml")


def test_simulation_is_vectorised_and_fast_enough_for_the_goal(ex1):
    rng = np.random.default_rng(0)
    sim = simulate_plant(ex1, 0.8, 100, 2000, rng)
    assert sim["x"].shape == (2000, 101, 2)
    # arrivals are Bernoulli(eta_bar)
    assert abs(sim["eta"].mean() - 0.8) < 0.01
