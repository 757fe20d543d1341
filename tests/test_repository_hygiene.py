"""Defects a new user met: what the repository's own files promise must exist."""
import re
import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_config_files_name_existing_schemas():
    for cfg in sorted((ROOT / "config").glob("*.yaml")):
        for ref in re.findall(r"config/schemas/[\w.]+\.yaml", cfg.read_text()):
            assert (ROOT / ref).is_file(), f"{cfg.name} names {ref}, which does not exist"


def test_report_is_ignored_by_git():
    out = subprocess.run(["git", "check-ignore", "-q", "report.html"], cwd=ROOT)
    assert out.returncode == 0, "report.html (snakemake --report) is not ignored by git"


def test_readme_says_how_to_recover_from_a_stale_lock():
    text = (ROOT / "docs" / "guide" / "workflow.md").read_text()  # the workflow manual, moved from the README
    assert "LockException" in text and "snakemake --unlock" in text


def test_config_readme_names_every_section_and_top_level_key():
    import yaml

    from eqrec.studies.pipeline.configuration import SECTIONS

    text = (ROOT / "config" / "README.md").read_text()
    assert {"p1", "p2", "p3", "p4", "compare"} <= set(SECTIONS)
    for section in SECTIONS:
        schema = yaml.safe_load((ROOT / "config" / "schemas" / f"{section}.schema.yaml").read_text())
        assert f"`{section}`" in text
        for key in schema["properties"]:
            assert f"`{key}`" in text, f"config/README.md does not describe {section}.{key}"
