"""Recompute one compare job and the merged table, and compare them with the stored results/compare byte for byte.

The comparison is deterministic (seeded draws in a fixed order, HiGHS designs, no timing in results/): the table,
the summary and the figure of a (system, setting) job, and the merged table of the stored jobs, are the same bytes.
"""
from pathlib import Path

import pytest

from eqrec.studies.pipeline import configuration, harness

#: The paths of the steps run here, as the rules name them.
COMPARE = "eqrec.studies.compare.steps:step_"

ROOT = Path(__file__).resolve().parents[1]
RES = ROOT / "results" / "compare"
CFG = configuration.load_config("compare", root=ROOT)
PAIRS = [(s, k) for s in CFG["systems"] for k in CFG["settings"]]


@pytest.fixture(scope="module")
def recomputed(tmp_path_factory):
    """The pair (acc, loss01) run again, as its rule runs it (the step of the system acc, given that one setting)."""
    out = tmp_path_factory.mktemp("compare")
    files = {"csv": out / "acc_loss01.csv", "json": out / "acc_loss01.json", "pdf": out / "acc_loss01.pdf",
             "png": out / "acc_loss01.png", "timings": out / "timings" / "acc_loss01.json"}
    cfg = {**CFG, "settings": {"loss01": CFG["settings"]["loss01"]}}
    harness.run_step(COMPARE + "run", cfg, outputs=files, wildcards={"system": "acc"})
    return files


@pytest.mark.parametrize("ext", ["csv", "json", "png", "pdf"])
def test_a_compare_job_gives_the_stored_bytes(recomputed, ext):
    assert recomputed[ext].read_bytes() == (RES / f"acc_loss01.{ext}").read_bytes(), f"acc_loss01.{ext} differs"


def test_the_recomputed_job_keeps_its_guarantee_and_its_wall_time_apart(recomputed):
    import json

    import pandas as pd

    table = pd.read_csv(recomputed["csv"])
    bounded = table[table["bound"].notna()]
    assert len(bounded) == 8 and (bounded["violations"] == 0).all()  # every family, the exact one too
    summary = json.loads(recomputed["json"].read_text())
    assert all(g["largest_error_over_bound"] <= 1 for g in summary["guaranteed"].values())
    assert "elapsed_s" not in summary  # the job's wall time and peak memory: the rule's benchmark (results/timings/)


def test_the_merged_table_of_the_stored_jobs_gives_the_stored_bytes(tmp_path):
    out = {"csv": tmp_path / "compare.csv", "json": tmp_path / "summary.json"}
    inputs = {"csv": [RES / f"{s}_{k}.csv" for s, k in PAIRS], "json": [RES / f"{s}_{k}.json" for s, k in PAIRS]}
    harness.run_step(COMPARE + "table", CFG, inputs=inputs, outputs=out)
    assert out["csv"].read_bytes() == (RES / "compare.csv").read_bytes()
    assert out["json"].read_bytes() == (RES / "summary.json").read_bytes()
