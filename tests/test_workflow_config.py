"""Configuration overrides reach the steps; bad values fail at once naming file and field (issue 7).

Snakemake runs in a temporary copy of the workflow (Snakefile, workflow/,
config/, results/); the package is the installed one.
"""
import copy
import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from snakemake.utils import update_config

from eqrec.studies.pipeline import code, harness
from eqrec.studies.pipeline import configuration

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


def run(args, cwd):
    return subprocess.run(SNAKEMAKE + args, cwd=cwd, capture_output=True, text=True, timeout=600)


@pytest.fixture
def workdir(tmp_path):
    for item in ("Snakefile", "workflow", "config", "results"):
        src = ROOT / item
        (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    return tmp_path


def test_p1_override_replans_the_jobs_that_read_it_and_reaches_the_step(workdir):
    out = run(["--cores", "1", "results/p1/model.json", "--forcerun", "p1_model"], workdir)
    assert out.returncode == 0, out.stderr[-3000:]
    same = run(["-n", "results/p1/model.json"], workdir)
    assert "p1_model" not in same.stdout + same.stderr  # up to date with the default configuration
    (workdir / "override.yaml").write_text("p1:\n  mu1: 1.5\n  timing_repeats: 1\n  solvers: [highs]\n")
    plan = run(["-n", "results/p1/model.json", "--configfile", "override.yaml"], workdir)
    text = plan.stdout + plan.stderr
    assert plan.returncode == 0, text[-3000:]
    assert "p1_model" not in text  # the model's step does not read mu1 or the solvers: not re-planned
    (workdir / "model.yaml").write_text("p1:\n  acc_constants: {Ts: 0.2}\n")
    plan = run(["-n", "results/p1/model.json", "--configfile", "model.yaml"], workdir)
    text = plan.stdout + plan.stderr
    assert plan.returncode == 0, text[-3000:]
    assert "rule p1_model" in text and "Params have changed since last execution" in text
    changes = run(["--list-changes", "params", "--configfile", "model.yaml"], workdir)
    assert "results/p1/model.json" in changes.stdout
    (workdir / "results/p1/designs.json").unlink()  # copied without metadata: let the override build it
    out = run(["--cores", "1", "results/p1/designs.json", "--configfile", "override.yaml"], workdir)
    assert out.returncode == 0, (out.stdout + out.stderr)[-3000:]
    designs = json.loads((workdir / "results/p1/designs.json").read_text())
    assert designs["M1"] == 1.5 and list(designs["designs"]["prefix"]["solvers"]) == ["highs"]
    assert "[p1] step designs done" in (workdir / "logs/p1/designs.log").read_text()
    # an edit to code P1 does not import (the LMV model) does not re-plan P1
    assert not any("/lmv/" in p for step in ("model", "designs")
                   for p in code.code_inputs(f"eqrec.studies.p1.steps:step_{step}"))


def test_config_override_on_the_command_line(workdir):
    plan = run(["-n", "results/p1/model.json", "--config", "p1={mu1: 2.5, language: ['1011']}"], workdir)
    assert plan.returncode == 0, (plan.stdout + plan.stderr)[-3000:]
    bad = run(["-n", "--config", "p1={mu1: abc, language: ['1011']}"], workdir)
    text = bad.stdout + bad.stderr
    assert bad.returncode != 0 and "--config" in text and "p1.mu1" in text and "is not of type 'number'" in text


@pytest.mark.parametrize("old,new,field", [("T: 100 ", "T: -1 ", "p4.T"), ("eta_bar: 0.8", "eta_bar: 1.5", "p4.eta_bar"),
                                           ("num: 21\n    chunks: 2 ", "num: 21\n    chunks: 22 ", "p4.sweep_q.chunks")])
def test_bad_p4_config_fails_at_once_naming_file_and_field(workdir, old, new, field):
    cfg = workdir / "config" / "p4.yaml"
    assert old in cfg.read_text()
    cfg.write_text(cfg.read_text().replace(old, new))
    out = run(["-n"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode != 0
    assert f"config/p4.yaml: field '{field}'" in text, text[-2000:]
    assert "Building DAG" not in text  # stopped before planning any job


def test_bad_override_names_the_override_file(workdir):
    (workdir / "bad.yaml").write_text("p2:\n  mu1: '0.1'\n")
    out = run(["-n", "--configfile", "bad.yaml"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode != 0 and "bad.yaml: field 'p2.mu1'" in text and "is not of type 'number'" in text


@pytest.mark.parametrize("how", ["config", "configfile"])
def test_unknown_section_is_refused_naming_it(workdir, how):
    if how == "config":
        out = run(["-n", "--config", "p5={x: 1}"], workdir)
        where = "--config: field 'p5'"
    else:
        (workdir / "typo.yaml").write_text("p2x:\n  mu1: 2\n")
        out = run(["-n", "--configfile", "typo.yaml"], workdir)
        where = "typo.yaml: field 'p2x'"
    text = out.stdout + out.stderr
    assert out.returncode != 0 and where in text and "unknown configuration section" in text
    assert "Building DAG" not in text


def _default_config():
    """The five default files merged, as the Snakefile's ``configfile:`` lines load them."""
    config = {}
    for section in configuration.SECTIONS.values():
        config.update(yaml.safe_load((ROOT / section.config_file).read_text()))
    return config


def test_the_five_sections_validate_and_an_unknown_one_is_refused():
    config = _default_config()
    assert set(configuration.validate_config(config, root=ROOT)) == set(configuration.SECTIONS)
    with pytest.raises(configuration.ConfigError, match="unknown configuration section 'p5'"):
        configuration.validate_config({**config, "p5": {}}, root=ROOT)


@pytest.mark.parametrize("override,field", [
    ({"p1": {"simulation": {"bogus": 1}}}, "p1.simulation.bogus"),
    ({"p2": {"heatmap": {"bogus": 1}}}, "p2.heatmap.bogus"),
    ({"p3": {"kalman": {"bogus": 1}}}, "p3.kalman.bogus"),
    ({"p3": {"strategy": {"reactor": {"bogus": 1}}}}, "p3.strategy.reactor.bogus"),
    ({"p4": {"sweep_eta": {"bogus": 1}}}, "p4.sweep_eta.bogus"),  # a $ref with its own properties
    ({"p4": {"examples": {"ex1": {"bogus": 1}}}}, "p4.examples.ex1.bogus"),
    ({"compare": {"systems": {"acc": {"bogus": 1}}}}, "compare.systems.acc.bogus")])
def test_unknown_nested_key_is_refused_naming_file_and_field(tmp_path, override, field):
    """Every object of every section is closed (additionalProperties: false): a nested misspelt key is named."""
    over = tmp_path / "over.yaml"
    over.write_text(yaml.safe_dump(override))
    config = _default_config()
    update_config(config, override)
    with pytest.raises(configuration.ConfigError) as err:
        configuration.validate_config(config, root=ROOT, configfiles=[over])
    assert f"over.yaml: field '{field}': unknown key 'bogus'" in str(err.value)
    config = _default_config()
    update_config(config, override)
    with pytest.raises(configuration.ConfigError) as err:  # the same through --config
        configuration.validate_config(config, root=ROOT, overrides=override)
    assert f"--config: field '{field}': unknown key 'bogus'" in str(err.value)


def test_unknown_nested_key_on_the_command_line_stops_snakemake(workdir):
    out = run(["-n", "--config", "p3={strategy: {reactor: {horizn: 4}}}"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode != 0 and "--config: field 'p3.strategy.reactor.horizn': unknown key 'horizn'" in text
    assert "Building DAG" not in text


def test_defaults_are_filled_at_every_level_of_every_section():
    config = _default_config()
    for section, key in [("p1", "simulation"), ("p2", "heatmap"), ("p3", "strategy"),
                         ("p4", "steady"), ("p4", "smoother_lag"), ("compare", "seed")]:
        del config[section][key]
    del config["p4"]["examples"]["ex1"]["mc_mult_dist"]
    configuration.validate_config(config, root=ROOT)
    assert config["p1"]["simulation"] == {"runs": 100, "seed": 2019, "x0": [20.0, 40.0, 20.0], "input_force": 206.4}
    # not in config/config.yaml at all
    assert config["p1"]["probe_solvers"] == ["highs", "clarabel"] and config["p1"]["acc_constants"] == {}
    assert config["p2"]["heatmap"]["chunks"] == 2 and config["p2"]["heatmap"]["second_solver"] == "clarabel"
    assert config["p3"]["strategy"]["reactor"]["horizon"] == 5 and config["p3"]["strategy"]["figure"] == {"window": 60}
    assert config["p4"]["steady"] == {"tol": 1.0e-12, "max_iter": 100000} and config["p4"]["smoother_lag"] == 2
    assert config["p4"]["examples"]["ex1"]["mc_mult_dist"] == "gaussian"
    assert config["compare"]["seed"] == 0


def test_cli_text_is_typed_only_where_the_schema_wants_a_number():
    config = _default_config()
    cli = {"p1": {"mu1": "1.5", "language": ["1011"]}, "p2": {"realaxis": {"grid_denominator": "null"}},
           "p3": {"kalman": {"mu1": "0.5", "true_pattern": "21210"}}, "p4": {"sweep_q": {"chunks": "7"}}}
    update_config(config, copy.deepcopy(cli))
    configuration.type_cli_config(config, cli, ROOT)
    assert config["p1"]["mu1"] == 1.5 and config["p1"]["language"] == ["1011"]  # a word stays text
    assert config["p2"]["realaxis"]["grid_denominator"] is None and config["p4"]["sweep_q"]["chunks"] == 7
    assert config["p3"]["kalman"] == {**config["p3"]["kalman"], "mu1": 0.5, "true_pattern": "21210"}
    configuration.validate_config(config, root=ROOT, overrides=cli)


def test_heatmap_chunks_follow_the_resolved_config(workdir):
    """The scattergather count of the heat map is the resolved p2.heatmap.chunks (or --set-scatter)."""
    (workdir / "override.yaml").write_text("p2:\n  heatmap:\n    chunks: 4\n")
    out = run(["-n", "results/p2/heatmap.csv", "--configfile", "override.yaml", "--forceall"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode == 0, text[-3000:]
    for k in range(1, 5):
        assert f"intermediate/p2/heatmap/chunk_{k}-of-4.csv" in text
    assert "chunk_5-of-4.csv" not in text and "-of-2.csv" not in text
    out = run(["-n", "results/p2/heatmap.csv", "--set-scatter", "heatmap=3", "--forceall"], workdir)
    text = out.stdout + out.stderr
    assert out.returncode == 0 and "intermediate/p2/heatmap/chunk_3-of-3.csv" in text and "-of-2.csv" not in text


SWEEPS = "eqrec.studies.p2.sweeps:step_"


def _heatmap(tmp_path, chunks):
    """The reduced heat map (4 x 4 grid, a sub-grid of the configured 31 x 31 one) in ``chunks`` jobs."""
    cfg = configuration.load_config("p2", root=ROOT, overrides={"p2": {"heatmap": {"n_r": 4, "n_theta": 4, "chunks": chunks}}})
    files = []
    for k in range(chunks):
        files.append(tmp_path / f"chunk_{k}.csv")
        harness.run_step(SWEEPS + "heatmap_chunk", cfg, outputs={"csv": files[-1]},
                         wildcards={"scatteritem": f"{k + 1}-of-{chunks}"})
    out = tmp_path / f"heatmap_{chunks}.csv"
    harness.run_step(SWEEPS + "heatmap_merge", cfg, inputs={"chunks": files},
                     outputs={"csv": out, "timings": tmp_path / "timings.csv"})
    return pd.read_csv(out)


def test_heatmap_override_of_chunks_gives_the_same_whole_grid(tmp_path):
    two, four = _heatmap(tmp_path / "two", 2), _heatmap(tmp_path / "four", 4)
    # byte for byte: the chunk count (2 on a laptop, 8 through the SLURM profile) leaves no trace
    assert (tmp_path / "two" / "heatmap_2.csv").read_bytes() == (tmp_path / "four" / "heatmap_4.csv").read_bytes()
    cols = ["variant", "word", "r", "theta", "status"]
    pd.testing.assert_frame_equal(two[cols].reset_index(drop=True), four[cols].reset_index(drop=True))
    np.testing.assert_allclose(two["mu2"], four["mu2"], rtol=1e-9)
    assert len(two) == 16 * two["variant"].nunique()
    # the same points of the stored full-grid heat map have the same status and mu2
    stored = pd.read_csv(ROOT / "results" / "p2" / "heatmap.csv")
    for _, row in four.iterrows():
        hit = stored[(stored["variant"] == row["variant"]) & np.isclose(stored["r"], row["r"])
                     & np.isclose(stored["theta"], row["theta"])]
        assert len(hit) == 1 and hit["status"].iloc[0] == row["status"]
        if row["status"] == "optimal":
            assert hit["mu2"].iloc[0] == pytest.approx(row["mu2"], rel=1e-6)


def test_sweep_merge_checks_the_grid(tmp_path):
    cfg = configuration.load_config("p4", root=ROOT, overrides={"p4": {"sweep_eta": {"num": 4, "chunks": 2}}})
    files = [tmp_path / f"chunk{k}.npz" for k in range(2)]
    for k, f in enumerate(files):
        harness.run_step("eqrec.studies.p4.steps:step_sweep_eta_chunk", cfg, outputs={"npz": f},
                         wildcards={"scatteritem": f"{k + 1}-of-2"})
    from eqrec.errors import InputError
    from eqrec.studies.pipeline.chunks import merge_npz as merge_chunks

    with pytest.raises(InputError, match="exactly once"):
        merge_chunks(files[:1], 4, tmp_path / "m.npz")
    with pytest.raises(InputError, match="4-point grid"):
        merge_chunks(files, 5, tmp_path / "m.npz")
    assert list(merge_chunks(files, 4, tmp_path / "m.npz")["idx"]) == [0, 1, 2, 3]
