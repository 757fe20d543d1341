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


def test_report_builds_with_png_items_captions_and_no_machine_paths(tmp_path):
    """`snakemake --report` (README) builds from the stored results; every item has a caption (issue 10)."""
    import re

    out_file = tmp_path / "report.html"
    out = run(["--report", str(out_file)])
    assert out.returncode == 0, (out.stdout + out.stderr)[-3000:]
    html = out_file.read_text(errors="replace")
    assert str(ROOT) not in html and "/root/" not in html and "/home/" not in html
    items = []
    for smk in (ROOT / "workflow" / "rules").glob("*.smk"):
        for item, caption in re.findall(r'report\(\s*"([^"]+)",\s*caption="([^"]+)"', smk.read_text()):
            items.append(item)
            assert not item.endswith(".pdf"), f"{smk.name}: report item {item} is a PDF (blank in a browser)"
            assert "{" not in caption, f"{smk.name}: caption path {caption} has a wildcard"
            assert (smk.parent / caption).resolve().is_file(), f"{smk.name}: caption {caption} missing"
    assert "results/claims.csv" in items and "results/REPRODUCTION.md" in items  # the claims table is an item
    assert sum(i.endswith(".png") for i in items) >= 10
    for name in ("claims.csv", "REPRODUCTION.md", "fig1_trajectories.png", "f3a_heatmap.png", "regions.png"):
        assert name in html
    assert "The replication pipeline of the equalized-recovery" in html  # the workflow description
    assert "{% if" not in html  # the captions' templates were rendered per item
    for caption in ("P2-F1 (augmented paper, Fig. 1)", "P2-F2 (augmented paper, Fig. 2)", "P4-F7 (Fig. 7)",
                    "P4-F8 (Fig. 8)"):  # one caption per figure, also where one rule draws two
        assert caption in html, caption
