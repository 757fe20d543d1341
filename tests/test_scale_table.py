"""The P3 scale table with both engines: configuration, the default run's plan, and the class engine's rows.

The tree LP (node per event prefix) and the class engine (one LP per (time,
available data) class and state row, classes from the window rule) must
agree on ``J``; the default run tabulates the fast tree sizes and the class
sizes and never plans the slow tree sizes (target ``p3_scale`` only).
"""
import json
import subprocess
import sys
from pathlib import Path

import numpy as np

import pytest

from eqrec.studies.p3.size_run import FIELDS, class_count, measure_size, run_size
from eqrec.systems.examples import batch_reactor
from eqrec.studies.pipeline import harness
from eqrec.studies.p3 import scale_table as p3_scale
from eqrec.studies.pipeline import outputs
from eqrec.studies.pipeline import configuration
from eqrec.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]


@pytest.fixture(scope="module")
def reactor():
    return batch_reactor()


@pytest.fixture(scope="module")
def cfg():
    return configuration.load_config("p3", root=ROOT)


def _planned(target: str) -> str:
    """The files a dry run of ``target`` would build, as printed (every job: --forceall)."""
    out = subprocess.run(SNAKEMAKE + [target, "-n", "--forceall", "--quiet", "progress"], cwd=ROOT,
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, (out.stdout + out.stderr)[-3000:]
    return out.stdout + out.stderr


# --------------------------------------------------------------------------- configuration

def test_scale_config_validates_with_its_defaults(cfg):
    sc = cfg["scale"]
    assert set(sc) == {"tree_sizes", "tree_slow_sizes", "class_sizes", "method", "builder", "mu1", "time_limit",
                       "mem_limit_gb"}
    assert [5, 2] in sc["tree_sizes"] and [6, 2] in sc["tree_sizes"] and [8, 3] not in sc["tree_sizes"]
    assert [8, 3] in sc["tree_slow_sizes"]
    assert [30, 4] in sc["class_sizes"] and [5, 2] in sc["class_sizes"]
    # every key has a schema default: an empty scale section gets the same values
    bare = configuration.load_config("p3", root=ROOT, overrides={"p3": {"scale": {"method": sc["method"]}}})
    assert bare["scale"] == sc


@pytest.mark.parametrize("override,field", [({"sizes": [[5, 2]]}, "sizes"),
                                            ({"class_sizes": [[5]]}, "p3.scale.class_sizes.0"),
                                            ({"method": "barrier"}, "p3.scale.method")])
def test_bad_scale_config_names_the_field(override, field):
    with pytest.raises(configuration.ConfigError) as err:
        configuration.load_config("p3", root=ROOT, overrides={"p3": {"scale": override}})
    assert field in str(err.value)


# --------------------------------------------------------------------------- the plan

def test_default_run_plans_class_sizes_and_fast_tree_sizes_only(cfg):
    sc = cfg["scale"]
    text = _planned("all")
    for T, tau in sc["class_sizes"]:
        assert f"results/p3/scale/classes_T{T}_tau{tau}.json" in text
    for T, tau in sc["tree_sizes"]:
        assert f"results/p3/scale/T{T}_tau{tau}.json" in text
    for T, tau in sc["tree_slow_sizes"]:
        assert f"results/p3/scale/T{T}_tau{tau}.json" not in text
    assert "results/p3/scale/T8_tau3.json" not in text
    assert "results/p3/scale_table.md" in text and "scale_table_full" not in text


def test_p3_scale_target_adds_the_slow_tree_sizes():
    text = _planned("p3_scale")
    assert "results/p3/scale/T8_tau3.json" in text and "results/p3/scale_table_full.md" in text
    assert "results/p3/scale/classes_T30_tau4.json" in text


# --------------------------------------------------------------------------- the class engine's rows

def test_class_engine_matches_the_tree_lp_on_5_2(reactor):
    tree = measure_size(reactor, 5, 2, "simplex", 0.5, engine="tree")
    cls = measure_size(reactor, 5, 2, "simplex", 0.5, engine="classes")
    assert tree["status"] == cls["status"] == "optimal"
    assert cls["classes"] == 18 == class_count(5, 2) and tree["classes"] == 18
    assert (cls["words"], cls["sequences"], cls["nodes"]) == (tree["words"], tree["sequences"], tree["nodes"]) \
        == (243, 162, 242)
    assert cls["J"] == pytest.approx(tree["J"], rel=1e-6)
    assert cls["max_level"] == pytest.approx(tree["max_level"], rel=1e-6)
    assert cls["terminal_level"] <= 0.5 * (1 + 1e-9)
    assert cls["engine"] == "classes" and cls["builder"] == "classes" and cls["cols"] < tree["cols"]
    assert set(cls) <= set(FIELDS) and set(tree) <= set(FIELDS)


def test_class_engine_in_a_fresh_process_never_enumerates(reactor):
    """(30, 4): 9.3e20 words; the worker builds 446 classes (measured: seconds, a few hundred MB)."""
    r = run_size(reactor, 30, 4, "simplex", 0.5, time_limit=120, mem_limit_gb=4, engine="classes", wall_margin=60)
    assert r["status"] == "optimal", r
    assert r["words"] == 5**30 and r["classes"] == 446 and r["sequences"] > 10**20
    assert r["peak_mb"] < 1024 and r["terminal_level"] <= 0.5 * (1 + 1e-9)


def test_worker_cli_engine_flag(reactor):
    args = {"system": reactor.to_dict(), "T": 3, "tau": 1, "method": "simplex", "mu1": 0.5, "time_limit": 60,
            "mem_limit_gb": 0, "builder": "core", "options": {}}
    out = subprocess.run([sys.executable, "-m", "eqrec.studies.p3.size_run", json.dumps(args), "--engine", "classes"],
                         capture_output=True, text=True, timeout=120)
    row = json.loads([ln for ln in out.stdout.splitlines() if ln.startswith("{")][-1])
    assert row["engine"] == "classes" and row["classes"] == class_count(3, 1) == 6 and row["status"] == "optimal"


# --------------------------------------------------------------------------- the table

def test_table_reads_old_tree_rows_and_names_the_slow_sizes(tmp_path):
    old = {"T": 8, "tau": 2, "method": "simplex", "builder": "core", "mu1": 0.5, "time_limit": 600.0,
           "mem_limit_gb": 16.0, "words": 6561, "sequences": 4374, "nodes": 6560, "rows": 10, "cols": 20, "nnz": 30,
           "build_time": 1.0, "status": "optimal", "solve_time": 2.0, "objective": 100.0, "peak_mb": 3.0}
    new = {"engine": "classes", "T": 8, "tau": 2, "method": "simplex", "builder": "classes", "mu1": 0.5,
           "time_limit": 600.0, "mem_limit_gb": 16.0, "words": 6561, "sequences": 4374, "nodes": 6560,
           "classes": 30, "rows": 5, "cols": 6, "nnz": 7, "build_time": 0.1, "solve_time": 0.2, "J": 4474.5,
           "status": "optimal", "peak_mb": 2.0}
    files, timings = [], []
    for i, row in enumerate((new, old)):
        files.append(str(tmp_path / f"{i}.json"))
        timings.append(str(tmp_path / "timings" / f"{i}.json"))
        outputs.write_json(files[-1], row, timings=timings[-1])
    assert "peak_mb" not in Path(files[0]).read_text() and "peak_mb" in Path(timings[0]).read_text()
    out = {"csv": str(tmp_path / "t.csv"), "md": str(tmp_path / "t.md"),
           "timings_csv": str(tmp_path / "timings" / "t.csv"), "timings_md": str(tmp_path / "timings" / "t.md")}
    frame = p3_scale.step_scale_table({"scale": {"tree_slow_sizes": [[8, 2], [8, 3]]}},
                                         harness.Files(sizes=files, timings=timings), harness.Files(**out),
                                         harness.Wildcards())
    assert frame["engine"].tolist() == ["tree", "classes"] and list(frame.columns) == list(FIELDS)
    assert frame["classes"].tolist() == [30, 30]  # the closed form for the old row
    assert frame["J"].tolist() == [100.0 + (1 + 2 * 4374) * 0.5, 4474.5]
    md = Path(out["md"]).read_text()
    assert "T·2^τ̄" in md and "(τ̄+1)^T" in md and "separation theorem" in md
    assert "Tree LP at (8, 3)" in md and "scale_table_full.md" in md  # (8, 2) is here; (8, 3) is not
    assert "## Side by side" in md
    # measurements only in the timings table (they change from run to run)
    assert "[s]" not in md and "[MB]" not in md and "results/timings/p3/" in md
    timed_md = Path(out["timings_md"]).read_text()
    assert "solve [s]" in timed_md and "peak [MB]" in timed_md and "classes total [s]" in timed_md
    assert "peak_mb" not in Path(out["csv"]).read_text().splitlines()[0]
    assert Path(out["timings_csv"]).read_text().splitlines()[0].startswith("engine,T,tau,")


def test_a_worker_reports_its_own_peak_not_its_parents(reactor):
    """A parent of 400 MB starts a small size: the worker's peak is its own (ru_maxrss survived the fork and exec
    of a memory-limited worker and reported the parent's size; a long test session's made this size's 200 MB
    read 1,060 MB)."""
    ballast = np.ones(50_000_000)  # 400 MB, touched
    r = run_size(reactor, 3, 1, "simplex", 0.5, time_limit=60, mem_limit_gb=4, engine="classes", wall_margin=60)
    assert r["status"] == "optimal", r
    assert r["peak_mb"] < 0.6 * ballast.nbytes / 2**20, r["peak_mb"]


# --------------------------------------------------------------------------- the class engine's sizes in one job

def test_default_run_plans_the_class_sizes_as_one_job():
    text = _planned("all")
    assert text.count("rule p3_scale_class_sizes:") == 1 and "p3_scale_class_size:" not in text


@pytest.mark.parametrize("names", [["classes_T6_tau2.json"],  # not the configured size
                                   ["classes_T5_tau2.json", "classes_T5_tau2.json"],  # twice
                                   ["classes_T5_tau2.csv"],  # not a size file
                                   ["T5_tau2.json"]])  # the tree LP's file
def test_sizes_step_refuses_outputs_that_are_not_the_configured_class_sizes(cfg, tmp_path, names):
    section = {**cfg, "scale": {**cfg["scale"], "class_sizes": [[5, 2]]}}
    outs = harness.Files(json=[str(tmp_path / n) for n in names], timings=[str(tmp_path / "t" / n) for n in names])
    with pytest.raises(InputError, match="scale"):
        p3_scale.step_scale_sizes(section, harness.Files(), outs, harness.Wildcards())
    assert not any(tmp_path.rglob("*.json"))  # refused before any size ran


def test_sizes_step_writes_each_size_as_its_own_job_would(cfg, tmp_path):
    one = {**cfg, "scale": {**cfg["scale"], "class_sizes": [[5, 2]]}}
    a = harness.Files(json=str(tmp_path / "a" / "classes_T5_tau2.json"),
                      timings=str(tmp_path / "a" / "t" / "classes_T5_tau2.json"))
    b = harness.Files(json=[str(tmp_path / "b" / "classes_T5_tau2.json")],
                      timings=[str(tmp_path / "b" / "t" / "classes_T5_tau2.json")])
    p3_scale.step_scale_size(one, harness.Files(), a, harness.Wildcards(T="5", tau="2", engine="classes"))
    p3_scale.step_scale_sizes(one, harness.Files(), b, harness.Wildcards())
    assert Path(a.json).read_bytes() == Path(b.json[0]).read_bytes()
    assert json.loads(Path(b.json[0]).read_text())["status"] == "optimal"
