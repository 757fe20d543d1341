"""Recompute P4 numbers and compare them with the stored results/p4 (refreshed only by the pipeline).

Tolerances: steady-state variances 1e-8 relative (deterministic fixed point); sweep chunks 1e-8 relative.
"""
import copy
import json
from pathlib import Path

import numpy as np
import pytest

from eqrec.lmv.model import hold_input_system, zero_input_system
from eqrec.lmv.steady import steady_state
from eqrec.studies.pipeline import harness
from eqrec.studies.pipeline import configuration
from eqrec.studies.p4 import steps as lmv_study

ROOT = Path(__file__).resolve().parents[1]
RES = ROOT / "results" / "p4"
CFG = configuration.load_config("p4", root=ROOT)


@pytest.mark.parametrize("example", ["ex1", "ex2"])
def test_steady_filter_variances_and_verdicts(example):
    plant = lmv_study.plant_of(CFG, example)
    eta = float(CFG["eta_bar"])
    zero = steady_state(zero_input_system(plant, eta)).P_filt
    hold = steady_state(hold_input_system(plant, eta)).P_filt[: plant.n, : plant.n]
    stored = np.load(RES / f"mc_{example}.npz")
    T = int(CFG["T"])
    np.testing.assert_allclose(np.diag(zero), stored["zero/theory_filt"][T], rtol=1e-6)
    np.testing.assert_allclose(np.diag(hold), stored["hold/theory_filt"][T], rtol=1e-6)
    verdict = json.loads((RES / "values.json").read_text())[f"better_{example}"]["value"]
    fresh = "zero-input" if np.all(np.diag(zero) < np.diag(hold)) else (
        "hold-input" if np.all(np.diag(hold) < np.diag(zero)) else "mixed")
    assert verdict == fresh


def test_sweep_chunk_matches_stored(tmp_path):
    """The first Q_xi row of the Q sweep (one chunk of ``num``), recomputed, against the stored merged sweep."""
    cfg = copy.deepcopy(CFG)
    cfg["sweep_q"]["chunks"] = cfg["sweep_q"]["num"]
    out = tmp_path / "chunk0.npz"
    harness.run_step("eqrec.studies.p4.steps:step_sweep_q_chunk", cfg, outputs={"npz": out},
                     wildcards={"scatteritem": f"1-of-{cfg['sweep_q']['chunks']}"})
    a, b = np.load(out), np.load(RES / "sweep_q.npz")
    assert a["idx"].tolist() == [0]
    keys = [k for k in b.files if k.endswith(("/filt", "/stable"))]
    assert keys and set(keys) <= set(a.files)
    for k in keys:
        np.testing.assert_array_equal(a[k], b[k][:1])  # the same bytes as the whole-grid run
