"""Snakemake profiles (default and SLURM) and the SLURM check's results comparison.

The SLURM run itself needs root and a one-node cluster:
``workflow/scripts/slurm_local_cluster.sh`` (run by ``.ci/run``).
"""

import importlib.util
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

ROOT = Path(__file__).resolve().parents[1]
SLURM_PROFILE = ROOT / "workflow" / "profiles" / "slurm" / "config.yaml"
DEFAULT_PROFILE = ROOT / "workflow" / "profiles" / "default" / "config.yaml"


def _job_rules() -> set[str]:
    """Rules of the workflow that run a job: a script/shell/run of their own or inherited by `use rule`, and
    outputs (the Snakefile's template `step`, which has none, is never a job), from the rules files."""
    runs, outputs, inherits = set(), set(), []
    for smk in [ROOT / "Snakefile", *sorted((ROOT / "workflow" / "rules").glob("*.smk"))]:
        blocks = re.split(r"^(?:rule (\w+):|use rule (\w+) as (\w+) with:)", smk.read_text(), flags=re.M)
        for name, base, child, body in zip(blocks[1::4], blocks[2::4], blocks[3::4], blocks[4::4]):
            if child:  # runs what its base runs
                name = child
                inherits.append((base, child))
            if re.search(r"^    (script|shell|run|notebook|wrapper):", body, flags=re.M):
                runs.add(name)
            if re.search(r"^    output:", body, flags=re.M):
                outputs.add(name)
    for base, child in inherits:  # in file order: a base is defined before it is used
        if base in runs:
            runs.add(child)
        if base in outputs:
            outputs.add(child)
    return runs & outputs


def test_slurm_profile_sets_resources_for_exactly_the_job_rules():
    prof = yaml.safe_load(SLURM_PROFILE.read_text())
    assert prof["executor"] == "slurm" and prof["slurm-status-command"] == "squeue"
    assert {"runtime", "mem_mb"} <= set(prof["default-resources"])
    per_rule = prof["set-resources"]
    rules = _job_rules()
    assert rules, "no rules found"
    # Snakemake ignores set-resources of unknown rules silently: a renamed rule must fail here
    assert set(per_rule) - rules == set(), "set-resources names rules that do not exist"
    assert rules - set(per_rule) == set(), "rules without resources in the SLURM profile"
    # the scale-table sizes (outside `all`) are the only jobs allowed a large node
    big = {"p3_scale_size"}
    for name, res in per_rule.items():
        max_mem = 20000 if name in big else 8000
        assert 0 < res["runtime"] <= 60 and 500 <= res["mem_mb"] <= max_mem, name


def test_default_profile_settings():
    prof = yaml.safe_load(DEFAULT_PROFILE.read_text())
    assert prof["rerun-incomplete"] is True and prof["cores"] == 2
    assert "rules" in prof["quiet"] and prof["printshellcmds"] is False
    # Snakemake looks for profiles/default next to the (root) Snakefile
    assert (ROOT / "profiles" / "default" / "config.yaml").resolve() == DEFAULT_PROFILE.resolve()


def test_snakemake_uses_the_default_profile():
    out = subprocess.run([sys.executable, "-m", "snakemake", "-n", "p1_model"], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "workflow specific profile profiles/default" in out.stderr


@pytest.mark.skipif(importlib.util.find_spec("snakemake_executor_plugin_slurm") is None,
                    reason="SLURM executor plugin not installed "
                           '(pip install -c requirements/pipeline.lock -e ".[slurm]")')
def test_slurm_profile_is_accepted_by_snakemake():
    out = subprocess.run([sys.executable, "-m", "snakemake", "--profile", "workflow/profiles/slurm", "-n",
                          "p1_model"], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    assert "profiles workflow/profiles/slurm" in out.stderr


def test_cluster_script_syntax_and_help():
    script = ROOT / "workflow" / "scripts" / "slurm_local_cluster.sh"
    assert subprocess.run(["bash", "-n", str(script)]).returncode == 0
    out = subprocess.run(["bash", str(script), "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "slurm-wlm" in out.stdout and "77" in out.stdout


# -- results comparison ------------------------------------------------------------

spec = importlib.util.spec_from_file_location("slurm_compare", ROOT / "workflow" / "scripts" / "slurm_compare.py")
slurm_compare = importlib.util.module_from_spec(spec)
spec.loader.exec_module(slurm_compare)


def _tree(base: Path, mu2=1.149819, solve_s=0.01, png=b"a", npz=1.0, extra=False, extra_timing=False) -> Path:
    """A results tree: numbers, a table, a figure, arrays, and the measured values under timings/."""
    (base / "p1").mkdir(parents=True)
    (base / "timings" / "p1").mkdir(parents=True)
    (base / "p1" / "designs.json").write_text(json.dumps({"prefix": {"mu2": mu2, "words": ["101111"]}}))
    (base / "timings" / "p1" / "designs.json").write_text(json.dumps({"prefix": {"solve_s": solve_s}}))
    (base / "claims.csv").write_text(f"id,our_value\nP1-M2,{mu2}\n")
    (base / "p1" / "fig.png").write_bytes(png)
    np.savez(base / "p1" / "sim.npz", e=np.array([0.5, npz]))
    if extra:
        (base / "p1" / "extra.json").write_text("{}")
    if extra_timing:
        (base / "timings" / "p1" / "extra.json").write_text("{}")
    return base


def test_compare_ignores_only_the_values_under_timings(tmp_path):
    a = _tree(tmp_path / "a")
    b = _tree(tmp_path / "b", solve_s=0.5)
    assert slurm_compare.compare_trees(a, b) == []
    assert slurm_compare.main([str(a), str(b)]) == 0


@pytest.mark.parametrize("change,where", [
    (dict(mu2=1.149820), "p1/designs.json: line 1"),
    (dict(npz=1.0 + 1e-13), "p1/sim.npz: bytes differ"),  # byte for byte: no tolerance
    (dict(png=b"b"), "p1/fig.png"),                       # figures too (fixed metadata)
    (dict(extra=True), "only in"),
    (dict(extra_timing=True), "timings/p1/extra.json: only in"),  # the same timing files
])
def test_compare_reports_differences(tmp_path, change, where):
    a = _tree(tmp_path / "a")
    b = _tree(tmp_path / "b", **change)
    diffs = slurm_compare.compare_trees(a, b)
    assert diffs and any(where in d for d in diffs), diffs
    assert slurm_compare.main([str(a), str(b)]) == 1


def test_compare_subset_allows_extra_reference_files(tmp_path):
    a = _tree(tmp_path / "a", extra=True)  # e.g. a committed target outside the run
    b = _tree(tmp_path / "b")
    assert slurm_compare.compare_trees(a, b) and slurm_compare.compare_trees(a, b, subset=True) == []
    assert slurm_compare.main([str(a), str(b), "--subset"]) == 0
    assert slurm_compare.compare_trees(b, a, subset=True)  # but not files the reference lacks
