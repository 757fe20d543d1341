"""The workflow plans, lints, and rejects a bad configuration."""
import re
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


def _report_items() -> list[tuple[str, str, str]]:
    """(rule, output, caption file) of every output a rule shows in the report, as Snakemake parsed them (the
    rules write them through common.smk's in_report/figure); wildcards' constraints dropped."""
    from snakemake.api import SnakemakeApi
    from snakemake.io import get_flag_value, is_flagged
    from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings

    with SnakemakeApi(OutputSettings()) as api:
        wf = api.workflow(resource_settings=ResourceSettings(cores=1), config_settings=ConfigSettings(),
                          snakefile=ROOT / "Snakefile", workdir=ROOT)
        return [(r.name, re.sub(r"\{(\w+),[^}]*\}", r"{\1}", str(f)),
                 str(get_flag_value(f, "report").caption.get_path_or_uri(secret_free=True)))
                for r in wf._workflow.rules for f in r.output if is_flagged(f, "report")]


def test_report_builds_with_png_items_captions_and_no_machine_paths(tmp_path):
    """`snakemake --report` (README) builds from the stored results; every item has a caption (issue 10)."""

    out_file = tmp_path / "report.html"
    out = run(["--report", str(out_file)])
    assert out.returncode == 0, (out.stdout + out.stderr)[-3000:]
    html = out_file.read_text(errors="replace")
    assert str(ROOT) not in html and "/root/" not in html and "/home/" not in html
    items = []
    for rule, item, caption in _report_items():
        items.append(item)
        assert not item.endswith(".pdf"), f"{rule}: report item {item} is a PDF (blank in a browser)"
        assert "{" not in caption, f"{rule}: caption path {caption} has a wildcard"
        assert Path(caption).is_file(), f"{rule}: caption {caption} missing"
    assert "results/claims.csv" in items and "results/REPRODUCTION.md" in items  # the claims table is an item
    assert sum(i.endswith(".png") for i in items) >= 10
    for name in ("claims.csv", "REPRODUCTION.md", "fig1_trajectories.png", "f3a_heatmap.png", "regions.png"):
        assert name in html
    assert "The replication pipeline of the equalized-recovery" in html  # the workflow description
    assert "{% if" not in html  # the captions' templates were rendered per item
    for caption in ("P2-F1 (augmented paper, Fig. 1)", "P2-F2 (augmented paper, Fig. 2)", "P4-F7 (Fig. 7)",
                    "P4-F8 (Fig. 8)"):  # one caption per figure, also where one rule draws two
        assert caption in html, caption
