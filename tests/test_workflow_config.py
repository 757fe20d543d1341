"""Configuration overrides reach the steps; bad overrides fail at once naming section and field (issue 7)."""
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


def run(args, cwd):
    return subprocess.run(SNAKEMAKE + args, cwd=cwd, capture_output=True, text=True, timeout=600)


@pytest.fixture
def workdir(tmp_path):
    for item in ("Snakefile", "workflow", "config", "src"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    return tmp_path


@pytest.mark.parametrize("override,field", [("T: -1", "T"), ("eta_bar: 1.5", "eta_bar")])
def test_bad_p4_override_fails_at_once_naming_section_and_field(workdir, override, field):
    (workdir / "bad.yaml").write_text(f"p4:\n  {override}\n")
    out = run(["-n", "--configfile", "bad.yaml"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode != 0
    assert "section 'p4'" in text and "config/schemas/p4.schema.yaml" in text
    assert f"['{field}']" in text


def test_p1_override_replans_p1_jobs_and_reaches_the_step(workdir):
    out = run(["--cores", "1", "results/p1/model.json"], workdir)
    assert out.returncode == 0, out.stderr[-3000:]
    same = run(["-n", "results/p1/model.json"], workdir)
    assert "p1_model" not in same.stdout + same.stderr  # up to date with the default configuration
    (workdir / "override.yaml").write_text("p1:\n  mu1: 1.5\n  timing_repeats: 1\n  solvers: [highs]\n")
    plan = run(["-n", "results/p1/model.json", "results/p1/designs.json", "--configfile", "override.yaml"], workdir)
    text = plan.stdout + plan.stderr
    assert plan.returncode == 0, text[-3000:]
    assert "resolved_config" in text and "p1_model" in text and "p1_designs" in text
    out = run(["--cores", "1", "results/p1/designs.json", "--configfile", "override.yaml"], workdir)
    assert out.returncode == 0, out.stderr[-3000:]
    designs = json.loads((workdir / "results/p1/designs.json").read_text())
    assert designs["M1"] == 1.5
    assert yaml.safe_load((workdir / "resolved/p1.yaml").read_text())["p1"]["mu1"] == 1.5


@pytest.mark.parametrize("chunks", [1, 2, 4, 8])
def test_heatmap_chunks_cover_the_whole_grid_for_any_chunk_count(chunks):
    from eqrec.studies import p2 as p2_study

    cfg = p2_study.load_config(ROOT / "config" / "p2.yaml")
    cfg["heatmap"]["chunks"] = chunks
    idx = np.concatenate([p2_study.theta_chunk(cfg, k) for k in range(chunks)])
    assert sorted(idx.tolist()) == list(range(cfg["heatmap"]["n_theta"]))


def test_heatmap_chunks_follow_the_resolved_config(workdir):
    (workdir / "override.yaml").write_text("p2:\n  heatmap:\n    chunks: 4\n")
    out = run(["-n", "results/p2/heatmap.csv", "--configfile", "override.yaml"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode == 0, text[-3000:]
    resolved = run(["--cores", "1", "resolved/p2.yaml", "--configfile", "override.yaml"], workdir)
    assert resolved.returncode == 0
    assert yaml.safe_load((workdir / "resolved/p2.yaml").read_text())["p2"]["heatmap"]["chunks"] == 4
    for k in range(4):
        assert f"_{k}.csv" in text
    assert "_4.csv" not in text



