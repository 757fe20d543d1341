"""Recompute the P3 numbers and compare them with the stored results/p3 (refreshed only by the pipeline).

Tolerances: discretisation 1e-12; languages exact; LP optima and levels 1e-6 relative (any pinned
HiGHS); filter worst cases 1e-9 relative (closed-form maps, same μ1); simulated errors 1e-9 absolute
(same seed, deterministic). The μ1-free global route is not rerun here (seconds matter): the stored
optimum is checked by the LP at that μ1 and by infeasibility just below the certified bracket.
"""
import json
from pathlib import Path

import numpy as np
import pytest

from eqrec.systems.examples import acc_system
from eqrec.design.delay.design import delay_language, design_delay
from eqrec.errors import InfeasibleDesign
from eqrec.studies.pipeline import harness
from eqrec.studies.pipeline import configuration
from eqrec.studies.p3 import steps as p3_study

#: The paths of the steps run here, as the rules name them.
P3 = "eqrec.studies.p3.steps:step_"
P3_VALUES = "eqrec.studies.p3.values:step_"

ROOT = Path(__file__).resolve().parents[1]
RES = ROOT / "results" / "p3"
CFG = configuration.load_config("p3", root=ROOT)


@pytest.fixture(scope="module")
def stored():
    names = ("languages", "reactor_model", "reactor_designs", "augmented", "kalman", "acc", "values")
    return {n: json.loads((RES / f"{n}.json").read_text()) for n in names}


def test_languages(stored, tmp_path):
    out = {k: tmp_path / f"{k}.out" for k in ("json", "csv", "md", "counts")}
    fresh = harness.run_step(P3 + "languages", CFG, outputs=out)
    assert json.loads(json.dumps(fresh)) == stored["languages"]
    assert out["md"].read_text() == (RES / "examples.md").read_text()


def test_discretisation(stored, tmp_path):
    fresh = harness.run_step(P3 + "reactor_model", CFG, outputs={"json": tmp_path / "m.json"})
    for key in ("A", "B"):
        np.testing.assert_allclose(fresh[key], stored["reactor_model"][key], atol=1e-12)


def test_batch_reactor_optimum_and_reading(stored):
    system = p3_study.reactor_from_config(CFG)
    words = p3_study.reactor_language(CFG)
    g = stored["reactor_designs"]["global"]
    d = design_delay(system, words, g["mu1"], cost=CFG["batch_reactor"]["cost"])
    assert d.J == pytest.approx(g["J"], rel=1e-6)
    assert d.mu2 == pytest.approx(g["mu2"], rel=1e-6)
    assert g["lower_bound"] <= g["J"] and g["gap"] <= 1e-5
    for engine in ("classes", "tree"):  # below the certified smallest level no estimator recovers
        with pytest.raises(InfeasibleDesign):
            design_delay(system, words, g["mu1_min"]["lower"] * (1 - 1e-4), certify=False, engine=engine)
    for r in stored["reactor_designs"]["readings"]:
        assert design_delay(system, words, r["mu1"]).mu2 == pytest.approx(r["mu2"], rel=1e-6)
    assert stored["values"]["br_max_mu2"]["value"] == pytest.approx(g["mu2"], rel=1e-12)


def test_acc_designs(stored):
    acc = stored["acc"]
    for cost in ("sum", "max"):
        d = design_delay(acc_system(), acc["language"], acc["mu1"], cost=cost)
        assert d.mu2 == pytest.approx(acc["fixed"][cost]["mu2"], rel=1e-6)
    for cost, e in acc["free"].items():
        g = e["global"]
        assert design_delay(acc_system(), acc["language"], g["mu1"], cost=cost).mu2 == pytest.approx(g["mu2"],
                                                                                                     rel=1e-6)
    assert [p.canonical_label for p in delay_language(acc["language"])] == acc["missing_data_language"]


def test_kalman_worst_cases(stored, tmp_path):
    k = stored["kalman"]
    cfg = configuration.load_config("p3", root=ROOT, overrides={"p3": {"kalman": {"mu1": k["mu1"]}}})
    fresh = harness.run_step(P3 + "kalman", cfg, outputs={"json": tmp_path / "k.json", "npz": tmp_path / "k.npz"})
    np.testing.assert_allclose(fresh["levels"], k["levels"], rtol=1e-6)
    for name, e in k["filters"].items():
        for est in ("prediction", "filtered"):
            np.testing.assert_allclose(fresh["filters"][name][est]["worst"], e[est]["worst"], rtol=1e-9, atol=1e-14)
            assert fresh["filters"][name][est]["verdict"] == e[est]["verdict"]
    a, b = np.load(tmp_path / "k.npz"), np.load(RES / "kalman.npz")
    np.testing.assert_allclose(a["deltas"], b["deltas"], atol=1e-15)
    np.testing.assert_allclose(a["proposed_errors"], b["proposed_errors"], atol=1e-9)


def test_acc_simulation(tmp_path):
    harness.run_step(P3 + "acc_simulate", CFG, outputs={"npz": tmp_path / "a.npz"})
    a, b = np.load(tmp_path / "a.npz"), np.load(RES / "acc_simulation.npz")
    for key in ("proposed_errors", "prefix_errors", "proposed_bounds", "prefix_bounds"):
        np.testing.assert_allclose(a[key], b[key], atol=1e-9)


def test_values_are_what_the_values_step_makes_of_the_stored_results(stored, tmp_path):
    inputs = {"languages": RES / "languages.json", "model": RES / "reactor_model.json",
              "designs": RES / "reactor_designs.json", "augmented": RES / "augmented.json",
              "kalman": RES / "kalman.json", "acc": RES / "acc.json", "acc_npz": RES / "acc_simulation.npz"}
    harness.run_step(P3_VALUES + "values", CFG, inputs=inputs, outputs={"json": tmp_path / "v.json"})
    assert json.loads((tmp_path / "v.json").read_text()) == stored["values"]
