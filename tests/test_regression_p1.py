"""Recompute the P1 numbers and compare them with the stored results/ (refreshed only by the pipeline).

Tolerances: optimal levels 1e-6 relative (LP optimum, any of the pinned solvers);
model matrices 1e-12; simulated errors 1e-9 (same seed, deterministic).
"""
import json
from pathlib import Path

import numpy as np
import pytest

from eqrec.design.prefix.design import design_prefix
from eqrec.studies.searches import min_feasible_mu1
from eqrec.errors import InfeasibleDesign
from eqrec.design.prefix.time_based import design_time_based
from eqrec.studies.pipeline import harness
from eqrec.studies.pipeline import configuration
from eqrec.studies.p1 import steps as p1_study

#: The paths of the steps run here, as the rules name them.
P1 = "eqrec.studies.p1.steps:step_"

ROOT = Path(__file__).resolve().parents[1]
RES = ROOT / "results" / "p1"
CFG = configuration.load_config("p1", root=ROOT)


@pytest.fixture(scope="module")
def stored():
    return {name: json.loads((RES / f"{name}.json").read_text()) for name in ("model", "designs", "extensions", "values")}


def test_model(stored, tmp_path):
    fresh = harness.run_step(P1 + "model", CFG, outputs={"json": tmp_path / "m.json"})
    for key in ("A", "B", "f", "E"):
        np.testing.assert_allclose(fresh[key], stored["model"][key], atol=1e-12)


@pytest.mark.parametrize("method", ["prefix", "time"])
@pytest.mark.parametrize("solver", ["highs", "clarabel"])
def test_optimal_levels(stored, method, solver):
    system = p1_study.system_from_config(CFG)
    fn = design_prefix if method == "prefix" else design_time_based
    d = fn(system, CFG["language"], CFG["mu1"], solver=solver)
    assert d.mu2 == pytest.approx(stored["designs"]["designs"][method]["mu2"], rel=1e-6)
    assert d.certificate.mu2 <= d.mu2 * (1 + 1e-6)
    assert stored["values"][f"{method}_L1_mu2"]["value"] == pytest.approx(d.mu2, rel=1e-6)


def test_simulation(tmp_path):
    out = tmp_path / "sim.npz"
    harness.run_step(P1 + "simulate", CFG, outputs={"npz": out})
    a, b = np.load(out), np.load(RES / "simulation.npz")
    for key in ("prefix_errors", "time_errors", "prefix_bounds"):
        np.testing.assert_allclose(a[key], b[key], atol=1e-9)
    assert np.all(np.abs(a["prefix_errors"]) <= a["prefix_bounds"] + 1e-9)


def test_extensions_curve(stored):
    system = p1_study.system_from_config(CFG)
    c = stored["extensions"]["curve"]
    for k in (0, len(c["M1"]) // 2, -1):
        assert design_prefix(system, CFG["language"], c["M1"][k]).mu2 == pytest.approx(c["prefix"][k], rel=1e-6)
    m1 = stored["extensions"]["min_M1"]["prefix"]
    assert min_feasible_mu1(system, CFG["language"]).upper == pytest.approx(m1, rel=1e-9)
    design_prefix(system, CFG["language"], m1)  # feasible at the smallest level, by both engines
    design_prefix(system, CFG["language"], m1 * (1 + 1e-6), engine="tree")
    for engine in ("classes", "tree"):  # and infeasible just below it
        with pytest.raises(InfeasibleDesign):
            design_prefix(system, CFG["language"], m1 * (1 - 1e-4), engine=engine)


def test_claims_table_is_complete():
    import pandas as pd

    t = pd.read_csv(ROOT / "results" / "claims.csv")
    assert list(t.columns) == ["id", "quantity", "paper_value", "our_value", "status", "reason"]
    assert set(t["status"]) <= {"reproduced", "differs", "not comparable"}
    assert t.loc[t["status"] == "differs", "reason"].str.len().min() > 20
    ids = set(t["id"])
    for target in ("P1-T1", "P1-M2", "P1-F1", "P1-TIME"):
        assert any(i.startswith(target) for i in ids)
