"""Recompute P2 numbers and compare them with the stored results/p2 (refreshed only by the pipeline).

Tolerances: optimal levels 1e-6 relative (LP / IPOPT optimum); heat-map rows 1e-6 relative on mu2 (1e-5 on the
certified worst case of a point's gains, which amplifies the LP's last digits),
status identical.
"""
import copy
import json
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from eqrec.systems.examples import acc_system
from eqrec.design.augmented.design import design_augmented
from eqrec.design.prefix.time_based import design_time_based
from eqrec.studies.pipeline import harness
from eqrec.studies.pipeline import configuration

#: The paths of the steps run here, as the rules name them.
P2 = "eqrec.studies.p2.steps:step_"
P2_SWEEPS = "eqrec.studies.p2.sweeps:step_"

ROOT = Path(__file__).resolve().parents[1]
RES = ROOT / "results" / "p2"
CFG = configuration.load_config("p2", root=ROOT)


@pytest.fixture(scope="module")
def values():
    return json.loads((RES / "values.json").read_text())


@pytest.mark.parametrize("fig,words", [("f1", CFG["f1_words"]), ("f2", CFG["f2_words"])])
def test_time_and_augmented_lp_levels(values, fig, words):
    acc = acc_system()
    t = design_time_based(acc, words, CFG["mu1"])
    assert t.mu2 == pytest.approx(values[f"{fig}_mu2_time"]["value"], rel=1e-6)
    a = design_augmented(acc, words, CFG["mu1"], poles=CFG["init_poles"])
    # with L fixed the augmented LP reaches the time-based optimum (same class of estimators)
    assert a.mu2 == pytest.approx(t.mu2, rel=1e-6)
    assert a.certificate.mu2 <= a.mu2 * (1 + 1e-6)


def _theta_zero_chunk(tmp_path) -> tuple[pd.DataFrame, pd.DataFrame]:
    """The heat map's first θ (θ = 0: one chunk of ``n_theta`` chunks), every variant, recomputed, and the
    stored rows of ``heatmap.csv`` at that θ, in the same order."""
    cfg = copy.deepcopy(CFG)
    cfg["heatmap"]["chunks"] = cfg["heatmap"]["n_theta"]
    out = tmp_path / "chunk.csv"
    harness.run_step(P2_SWEEPS + "heatmap_chunk", cfg, outputs={"csv": out},
                     wildcards={"scatteritem": f"1-of-{cfg['heatmap']['chunks']}"})
    fresh = pd.read_csv(out).sort_values(["variant", "r"], kind="stable").reset_index(drop=True)
    stored = pd.read_csv(RES / "heatmap.csv")
    stored = stored[stored["theta"] == 0.0].sort_values(["variant", "r"], kind="stable").reset_index(drop=True)
    return fresh, stored


def test_heatmap_chunk_matches_stored(tmp_path):
    """Every variant at θ = 0: the same classes, observers, optima and certified worst cases as stored."""
    fresh, stored = _theta_zero_chunk(tmp_path)
    assert len(fresh) == len(stored) == CFG["heatmap"]["n_r"] * len(CFG["heatmap"]["variants"])
    for col in ("variant", "status", "observer"):
        assert list(fresh[col]) == list(stored[col]), col
    ok = fresh["status"] == "optimal"
    assert ok.any()
    np.testing.assert_allclose(fresh.loc[ok, "mu2"], stored.loc[ok, "mu2"], rtol=1e-6)
    np.testing.assert_allclose(fresh.loc[ok, "certified_mu2"], stored.loc[ok, "certified_mu2"], rtol=1e-5)


def test_printed_L_step_matches_stored(tmp_path):
    """The Fig. 2 design at the printed L (read from config/claims.yaml) and its certified guarantees."""
    out = tmp_path / "printed.json"
    fresh = harness.run_step(P2 + "printed", CFG, inputs={"claims": ROOT / "config" / "claims.yaml"},
                             outputs={"json": out})
    stored = json.loads((RES / "printed.json").read_text())
    for mode in ("theorem2", "masked_gain"):
        assert fresh[mode]["mu2"] == pytest.approx(stored[mode]["mu2"], rel=1e-6)
        for rt in ("hold", "theorem2"):
            assert fresh[mode][f"certified_{rt}"]["mu2"] == pytest.approx(stored[mode][f"certified_{rt}"]["mu2"],
                                                                         rel=1e-6)
    assert [r.get("masked_gain") for r in fresh["r0_deadbeat"]] == pytest.approx(
        [r.get("masked_gain") for r in stored["r0_deadbeat"]], rel=1e-6)
    # the best guarantee among the masked_gain optima as run: solver-independent, so it matches per solver
    fa, sa = fresh["masked_gain"]["among_optima"], stored["masked_gain"]["among_optima"]
    for rt in ("hold", "theorem2"):
        for solver, e in sa["runtimes"][rt].items():
            assert fa["runtimes"][rt][solver]["upper"] == pytest.approx(e["upper"], rel=1e-6)
            assert fa["runtimes"][rt][solver]["certified"]["mu2"] == pytest.approx(e["upper"], rel=1e-6)
    for solver, e in sa["terminal_theorem2"].items():
        assert fa["terminal_theorem2"][solver]["upper"] == pytest.approx(e["upper"], rel=1e-6)


def test_stored_best_guarantee_among_optima(values):
    """P2-F2:certified-masked-gain: γ* agrees across solvers and runtimes, certify() confirms it, and it is at
    most the certified guarantee of every solver's own pick."""
    ev = values["f2_masked_gain_certified"]["evidence"]
    ao = ev["among_optima"]
    assert ao["agree"]
    gamma = values["f2_masked_gain_certified"]["value"]
    for rt, r in ao["runtimes"].items():
        assert r["exact"] and r["design_optimal"] and r["solver_spread"] <= 1e-6 and r["certify_difference"] <= 1e-6
        assert all(v == pytest.approx(gamma, rel=1e-6) for v in r["by_solver"].values())
    for pick in ev["by_solver"].values():
        assert gamma <= pick["hold"] * (1 + 1e-6) and gamma <= pick["theorem2_runtime"] * (1 + 1e-6)
    assert gamma > ev["time_mu2"]


def test_stored_counts_add_up_to_the_grid(values):
    grid = CFG["heatmap"]["n_r"] * CFG["heatmap"]["n_theta"]
    variants = values["f3a_mu2_region"]["evidence"]["variants"]
    assert set(variants) == set(CFG["heatmap"]["variants"])
    for c in variants.values():
        assert c["optimal"] + c["infeasible"] + c["solver_failed"] + c["placement_failed"] == c["points"] == grid
        assert c["placement_failed"] == 0 and c["deadbeat"] == CFG["heatmap"]["n_theta"]  # r = 0: nilpotent L
    hm = pd.read_csv(RES / "heatmap.csv")
    assert len(hm) == grid * len(variants)


