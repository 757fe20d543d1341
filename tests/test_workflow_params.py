"""Rerun granularity (issue 18): each rule carries only the configuration keys its step reads and, as code inputs,
only the modules its step imports (:mod:`eqrec.studies.pipeline.code`), so a changed figure parameter re-plans that
figure's job and nothing else, and an edit to a module re-plans the jobs whose step imports it.

The rules are read as Snakemake reads them (the Snakefile evaluated through Snakemake's API with a ``--config``
override); a job is re-planned for a changed configuration exactly when its rule's params change (params rerun
trigger).
"""
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
from snakemake.api import SnakemakeApi
from snakemake.settings.types import ConfigSettings, OutputSettings, ResourceSettings

from eqrec.studies.pipeline import code, configuration, harness

ROOT = Path(__file__).resolve().parents[1]


def _rules(config: dict) -> dict[str, tuple[dict, list[str]]]:
    """``rule -> (params, inputs)`` of every rule of the workflow under the ``--config`` override ``config``."""
    with SnakemakeApi(OutputSettings()) as api:
        wf = api.workflow(resource_settings=ResourceSettings(cores=1), config_settings=ConfigSettings(config=config),
                          snakefile=ROOT / "Snakefile", workdir=ROOT)
        return {r.name: (dict(r.params.items()), [str(f) for f in r.input]) for r in wf._workflow.rules}


@pytest.fixture(scope="module")
def default_rules():
    return _rules({})


@pytest.mark.parametrize("override,replanned", [
    # a figure's parameter: only that figure (not the 10^4-step runs or the mu1-free designs before it)
    ({"p3": {"strategy": {"figure": {"window": 30}}}}, {"p3_strategy_figure"}),
    # a parameter of the runs: not the figure drawn from their file
    ({"p3": {"strategy": {"steps": 5000}}}, {"p3_strategy"}),
    # the P2 tolerance: the heat-map figure and the values that read it, no LP
    ({"p2": {"mu2_tol": 1e-5}}, {"p2_figure_heatmap", "p2_values"}),
    # the real-axis grid: the sweep and the values; the figure reads only the sweep's file
    ({"p2": {"realaxis": {"n": 101}}}, {"p2_realaxis", "p2_values"}),
    # the P4 Q grid: its chunks and the figure that merges them, not the Monte Carlo or the tracking run
    ({"p4": {"sweep_q": {"num": 22}}}, {"p4_sweep_q_chunk", "p4_fig6"}),
    # one P1 extension: its job only, not the designs' LPs or the simulation
    ({"p1": {"extensions": {"M1_points": 20}}}, {"p1_extensions"}),
    # the compare seed: the (system, setting) jobs, not the table that merges their files
    ({"compare": {"seed": 1}}, {"compare_run"}),
])
def test_a_changed_parameter_replans_only_the_jobs_whose_step_reads_it(default_rules, override, replanned):
    changed = _rules(override)
    assert changed.keys() == default_rules.keys()
    differ = {rule for rule in default_rules if changed[rule][0] != default_rules[rule][0]}
    assert differ == replanned


def test_every_rule_is_given_the_keys_of_its_own_step_only(default_rules):
    """The strategy figure is given its window and nothing of the runs; the designs nothing of the figures."""
    params = {rule: p for rule, (p, _) in default_rules.items()}
    assert params["p3_strategy_figure"]["cfg"] == {"strategy": {"figure": {"window": 60}}}
    assert "figure" not in params["p3_strategy"]["cfg"]["strategy"]
    assert "cfg" not in params["p2_figure_realaxis"] and "cfg" not in params["p1_figure1"]  # they read none
    full = {s: configuration.load_config(s, root=ROOT) for s in ("p1", "p2", "p3", "p4")}
    for rule, p in params.items():
        study = harness.step_names(p["step"])[0] if "step" in p else None
        if study in full:
            assert p.get("cfg", {}) != full[study], rule  # no rule carries its whole section


def test_every_rule_names_a_step_that_resolves(default_rules):
    """Every rule that runs a step names it by one param, the path of its function, which resolves
    (:func:`pkgutil.resolve_name`); its code inputs are that step's (and the rule carries no other name)."""
    steps = {rule: p["step"] for rule, (p, _) in default_rules.items() if "step" in p}
    assert len(steps) >= 27 and set(default_rules) - set(steps) == {"all", "p1", "p2", "p3", "p4", "p3_scale",
                                                                    "compare", "notebooks", "step"}
    for rule, step in steps.items():
        fn = harness.resolve_step(step, rule)
        assert f"{fn.__module__}:{fn.__name__}" == step, rule
        assert "study" not in default_rules[rule][0], rule
        code_files = [f for f in default_rules[rule][1] if f.startswith("src/")]
        assert code_files == code.code_inputs(step), rule


def test_figure_rules_do_not_list_the_design_modules_as_code(default_rules):
    """A figure is drawn by a figures module that imports no LP, design or LMV code, so it does not re-run when
    one of those changes: every figure rule of the four studies."""
    figures = {"p1_figure1", "p1_figure_ext", "p2_figure_trajectories", "p2_figure_heatmap", "p2_figure_realaxis",
               "p3_figure1", "p3_figure2", "p3_strategy_figure", "p4_fig4", "p4_fig5", "p4_fig6", "p4_compare"}
    assert figures <= default_rules.keys()
    for rule in figures:
        p, inputs = default_rules[rule]
        assert p["step"].partition(":")[0].endswith(".figures"), rule
        files = [f for f in inputs if f.startswith("src/")]
        assert "src/eqrec/studies/plotting.py" in files and "src/eqrec/studies/pipeline/harness.py" in files, rule
        assert not any(f.startswith(("src/eqrec/design/", "src/eqrec/lp/", "src/eqrec/bounds/", "src/eqrec/lmv/"))
                       for f in files), rule
    # and an edit to a figures module does not re-run the LPs: their rules do not list it
    assert not any(f.endswith("/figures.py") for rule in ("p1_designs", "p2_designs", "p3_acc", "p3_reactor_designs")
                   for f in default_rules[rule][1])
    # the LP steps do list the design modules, and no P4 rule lists them
    assert "src/eqrec/design/classes/engine.py" in default_rules["p3_strategy"][1]
    assert "src/eqrec/design/prefix/design.py" in default_rules["p1_designs"][1]
    for rule, (p, inputs) in default_rules.items():
        if p.get("study") == "p4":
            assert not any("/design/" in f for f in inputs), rule


def test_a_step_reading_a_key_its_rule_does_not_give_fails_naming_it(tmp_path):
    with pytest.raises(harness.MissingConfigKey, match=r"'p1\.acc_constants'.*step p1\.model"):
        harness.run_step("eqrec.studies.p1.steps:step_model", {"mu1": 1.0}, outputs={"json": tmp_path / "m.json"})
    with pytest.raises(configuration.ConfigError, match=r"p3\.strategy\.figur"):
        configuration.step_params({"p3": {"strategy": {"figure": {"window": 1}}}}, "p3", "strategy.figur")


def test_an_edit_to_a_module_replans_the_jobs_whose_step_imports_it(tmp_path):
    """In a copy of the workflow and the package with every result newer than the code: nothing to do; an edit to
    the LMV steady state re-plans the P4 jobs (their steps import it) and what reads their files, no LP job; an
    edit to the P1 figures module re-plans the P1 figures, not the P1 designs."""
    for item in ("Snakefile", "workflow", "config", "results", "src"):
        (shutil.copytree if (ROOT / item).is_dir() else shutil.copy)(ROOT / item, tmp_path / item)
    for path in tmp_path.rglob("*"):
        if path.is_file():  # every result newer than the code, the scripts and the configuration
            os.utime(path, (1.5e9, 1.5e9) if path.parts[len(tmp_path.parts)] == "results" else (1e9, 1e9))
    env = {**os.environ, "PYTHONPATH": str(tmp_path / "src")}

    def planned(edit=None) -> set[str]:
        if edit:
            path = tmp_path / "src" / "eqrec" / edit
            path.write_text(path.read_text() + "\n# an edit\n")
        out = subprocess.run([sys.executable, "-m", "snakemake", "-n"], cwd=tmp_path, env=env, capture_output=True,
                             text=True, timeout=600)
        text = out.stdout + out.stderr
        assert out.returncode == 0, text[-3000:]
        return {line.split()[1].rstrip(":") for line in text.splitlines() if line.startswith("rule ")}

    assert planned() == set()
    lmv = planned("lmv/steady.py")
    assert {"p4_tracking", "p4_mc", "p4_sweep_eta_chunk", "p4_sweep_q_chunk", "p4_values"} <= lmv
    assert not lmv & {"p1_designs", "p2_designs", "p3_reactor_designs", "p3_strategy", "compare_run", "p1_figure1"}
    figures = planned("studies/p1/figures.py") - lmv
    assert {"p1_figure1", "p1_figure_ext"} <= figures and not figures & {"p1_designs", "p1_model", "p1_values"}
