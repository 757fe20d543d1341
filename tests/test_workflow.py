"""The workflow plans, lints, and rejects a bad configuration."""
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


def run(args, cwd=ROOT):
    return subprocess.run(SNAKEMAKE + args, cwd=cwd, capture_output=True, text=True, timeout=300)


def test_dry_run_plans():
    out = run(["-n", "--quiet"])
    assert out.returncode == 0, out.stderr[-2000:]


def test_bad_config_is_rejected(tmp_path):
    for item in ("Snakefile", "workflow", "config"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    cfg = tmp_path / "config" / "config.yaml"
    cfg.write_text(cfg.read_text().replace('language: ["101111"', 'language: ["10a111"'))
    out = run(["-n", "--quiet"], cwd=tmp_path)
    assert out.returncode != 0
    assert "language" in (out.stdout + out.stderr)
