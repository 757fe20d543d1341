"""The study harness: step paths, code inputs, configuration (schema defaults), atomic writers, logs, exit status."""
import ast
import copy
import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pandas as pd
import pytest
import yaml
from snakemake.iocontainers import Namedlist

from eqrec.errors import InputError
from eqrec.studies.pipeline import code, harness, logs
from eqrec.studies.pipeline import outputs
from eqrec import errors
from eqrec.studies.pipeline import configuration

ROOT = Path(__file__).resolve().parents[1]
RULES = ROOT / "workflow" / "rules"


def _rule_steps():
    """(rule, step, body, rules file) of every rule that runs the harness: inherits the Snakefile's template rule
    ``step`` (``use rule step as p1_model with:``)."""
    out = []
    for smk in RULES.glob("*.smk"):
        text = smk.read_text()
        assert "script:" not in text, smk.name  # no rule runs anything but the template's script
        for rule, body in re.findall(r"^use rule step as (\w+) with:\n(.*?)(?=^(?:use )?rule |\Z)", text,
                                     flags=re.S | re.M):
            out.append((rule, re.search(r'step="([\w.:]+)"', body).group(1), body, smk.stem))
    return out


def test_every_rule_names_a_step_function_and_runs_it_through_the_one_script():
    rules = _rule_steps()
    assert len(rules) >= 27
    for rule, step, body, study in rules:
        fn = harness.resolve_step(step, rule)  # the path resolves (pkgutil.resolve_name) to a step function
        assert callable(fn) and step == f"{fn.__module__}:{fn.__name__}" and fn.__name__.startswith("step_"), rule
        assert step.startswith(f"eqrec.studies.{study}.") and harness.step_names(step)[0] == study, rule
        assert rule.startswith(study), rule  # rules files, rules, step folders: one study each
        # its code inputs are those of its own step, its configuration keys of its own section
        assert f'code=code_inputs("{step}")' in body, rule
        assert "study=" not in body and body.count("step=") == 1, rule
        cfg = re.search(r"\n        cfg=(.*?),\n(?:    benchmark:|\n|\Z)", body, flags=re.S)
        assert cfg is None or cfg.group(1).startswith((f'step_config(\n            "{study}",',
                                                       f'step_config("{study}",')), (rule, cfg)
    for smk in RULES.glob("*.smk"):
        assert "shell:" not in smk.read_text() and "python -m" not in smk.read_text(), smk.name
    template = re.search(r"^rule step:\n(.*?)\n\n", (ROOT / "Snakefile").read_text(), flags=re.S | re.M).group(1)
    assert "output:" not in template and 'script:\n        f"{workflow.basedir}/workflow/scripts/run_step.py"' in template
    script = (ROOT / "workflow" / "scripts" / "run_step.py").read_text()
    assert "run_from_snakemake(snakemake)" in script


def test_the_template_rule_asked_for_by_name_says_what_it_is(tmp_path):
    """`snakemake step` (the Snakefile's template) stops with a one-line explanation, not a traceback."""
    smk = SimpleNamespace(params=SimpleNamespace(), rule="step", log=[str(tmp_path / "step.log")])
    with pytest.raises(SystemExit, match="template of the rules that do"):
        harness.run_from_snakemake(smk)


def test_study_modules_have_no_command_line_and_no_defaults_table():
    for path in (ROOT / "src" / "eqrec" / "studies").glob("*.py"):
        text = path.read_text()
        assert "argparse" not in text and "__main__" not in text, path.name
        assert "DEFAULTS" not in text, path.name
        tree = ast.parse(text)
        for node in ast.walk(tree):  # cfg.get("x", 5): a second defaults table in disguise
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "get"
                    and len(node.args) == 2 and "cfg" in ast.unparse(node.func.value)
                    and isinstance(node.args[1], (ast.Constant, ast.List, ast.Dict, ast.Tuple))):
                pytest.fail(f"{path.name}: {ast.unparse(node)}")


def test_defaults_come_from_the_schemas():
    cfg = configuration.load_config("p2", overrides={"p2": {"runs": 7}}, root=ROOT)
    schema = yaml.safe_load((ROOT / "config" / "schemas" / "p2.schema.yaml").read_text())
    assert cfg["runs"] == 7 and cfg["realaxis"]["grid_denominator"] == 14
    c = {"p1": {"mu1": 2.0, "language": ["1011"]}}
    configuration.validate_section(c, "p1", root=ROOT)
    assert c["p1"]["timing_repeats"] == 5 and c["p1"]["extensions"]["T_max"] == 14  # filled in by the schema
    assert schema["properties"]["noise"]["default"] == "uniform"


@pytest.mark.parametrize("study,override,field", [
    ("p4", {"T": -1}, "p4.T"), ("p4", {"eta_bar": 1.5}, "p4.eta_bar"), ("p4", {"eta_bar": "0.8"}, "p4.eta_bar"),
    ("p4", {"sweep_eta": {"chunks": 0}}, "p4.sweep_eta.chunks"), ("p4", {"mc": {"runs": "10000"}}, "p4.mc.runs"),
    ("p4", {"tracking": {"example": "ex3"}}, "p4.tracking.example"), ("p1", {"mu1": "1"}, "p1.mu1"),
    ("p1", {"language": ["101", "11"]}, "p1.language"), ("p2", {"heatmap": {"n_r": 2.5}}, "p2.heatmap.n_r"),
    ("compare", {"runs": 0}, "compare.runs"), ("compare", {"systems": {"acc": {"model": "motor"}}},
                                                        "compare.systems.acc.model"),
    ("compare", {"settings": {"burst": {"burst": 0.5}}}, "compare.settings.burst.burst"),
    ("compare", {"settings": {"burst": {"loss": 0.9, "burst": 4}}}, "compare.settings.burst.burst"),  # 4 < 9 steps
    ("compare", {"settings": {"loss_01": {"loss": 0.1}}}, "compare.settings")])
def test_config_errors_name_file_and_field(tmp_path, study, override, field):
    over = tmp_path / "over.yaml"
    over.write_text(yaml.safe_dump({study: override}))
    default = ROOT / configuration.SECTIONS[study].config_file
    with pytest.raises(configuration.ConfigError) as exc:
        configuration.load_config(study, default, over, root=ROOT)
    assert f"field '{field}'" in str(exc.value) and "over.yaml" in str(exc.value)


def test_cli_values_get_the_types_their_schema_wants():
    config = {"p1": {"mu1": "1.5", "language": ["1011"], "timing_repeats": "3"}}
    configuration.type_cli_config(config, {"p1": {"mu1": "1.5", "language": ["1011"], "timing_repeats": "3"}}, ROOT)
    assert config["p1"] == {"mu1": 1.5, "language": ["1011"], "timing_repeats": 3}


def test_cli_values_under_a_ref_with_own_properties_get_their_types():
    """p4.sweep_eta is ``$ref: grid`` plus its own ``properties`` (lo, hi): chunks keeps the grid's integer type
    (the SLURM profile sets it with --config)."""
    config = {"p4": {"sweep_eta": {"lo": "0.2", "chunks": "3"}, "sweep_q": {"chunks": "7"}}}
    configuration.type_cli_config(config, copy.deepcopy(config), ROOT)
    assert config["p4"] == {"sweep_eta": {"lo": 0.2, "chunks": 3}, "sweep_q": {"chunks": 7}}


# --------------------------------------------------------------------------- timings

def test_write_json_puts_timings_in_their_own_file_and_read_json_puts_them_back(tmp_path):
    data = {"mu2": 1.5, "timing": {"solve_s": 0.01, "iterations": 17}, "rows": [{"wall_time": 2.0, "J": 3.0}, {"J": 4.0}],
            "worst_time": 3}  # worst_time is a time index, a result
    out, timed = tmp_path / "r.json", tmp_path / "timings" / "r.json"
    outputs.write_json(out, data, timings=timed)
    assert json.loads(out.read_text()) == {"mu2": 1.5, "timing": {"iterations": 17}, "rows": [{"J": 3.0}, {"J": 4.0}],
                                           "worst_time": 3}
    assert json.loads(timed.read_text()) == {"timing": {"solve_s": 0.01}, "rows": [{"wall_time": 2.0}, None]}
    assert outputs.read_json(out, timings=timed) == data


def test_a_step_cannot_write_a_timing_next_to_the_results(tmp_path):
    with pytest.raises(errors.StepError, match="solve_time"):
        outputs.write_json(tmp_path / "r.json", {"a": {"solve_time": 0.1}})
    assert not (tmp_path / "r.json").exists()
    frame = pd.DataFrame({"r": [0.0, 1.0], "mu2": [1.0, 2.0], "solve_time": [0.1, 0.2]})
    with pytest.raises(errors.StepError, match="solve_time"):
        outputs.write_csv(tmp_path / "t.csv", frame)
    outputs.write_csv(tmp_path / "t.csv", frame, timings=tmp_path / "tt.csv", keys=["r"])
    assert (tmp_path / "t.csv").read_text() == "r,mu2\n0.0,1.0\n1.0,2.0\n"
    assert (tmp_path / "tt.csv").read_text() == "r,solve_time\n0.0,0.1\n1.0,0.2\n"


P1, P4 = "eqrec.studies.p1.steps:step_", "eqrec.studies.p4.steps:step_"


def test_code_inputs_follow_the_imports_of_each_step():
    designs, model4 = code.code_inputs(P1 + "designs"), code.code_inputs(P4 + "mc")
    assert "src/eqrec/studies/p1/steps.py" in designs and "src/eqrec/studies/searches.py" in designs
    assert not any("/lmv/" in p for p in designs)  # an LMV edit does not re-run the P1 LPs
    # P4 runs no LP; its plant comes from eqrec.lmv.plant (the configuration checks only validate, at planning);
    # of the core it reads only the system description, the noise and the input checks, no LP or estimator
    assert not any(p.startswith(("src/eqrec/design/", "src/eqrec/lp/", "src/eqrec/bounds/")) for p in model4)
    assert "src/eqrec/lmv/plant.py" in model4 and "src/eqrec/studies/pipeline/checks.py" not in model4
    assert "src/eqrec/studies/pipeline/checks.py" not in designs  # P1 steps do not import it
    for files in (designs, model4):  # the harness that runs the step and its parent packages, nothing else
        assert {"src/eqrec/studies/pipeline/harness.py", "src/eqrec/studies/pipeline/__init__.py",
                "src/eqrec/studies/__init__.py", "src/eqrec/__init__.py"} <= set(files)
        assert "src/eqrec/studies/pipeline/code.py" not in files and files == sorted(set(files))
    # a figure's step imports its figures module, not the study's LP modules
    fig = code.code_inputs("eqrec.studies.p1.figures:step_figure1")
    assert "src/eqrec/studies/p1/figures.py" in fig and "src/eqrec/studies/p1/steps.py" not in fig
    assert not any(p.startswith(("src/eqrec/design/", "src/eqrec/lp/")) for p in fig)
    with pytest.raises(errors.StepError, match="no module 'eqrec.studies.p9'"):
        code.code_inputs("eqrec.studies.p9:step_model")


def test_code_inputs_see_lazy_imports():
    """grimp reads imports inside functions too: the notebooks step imports its HTML module when it renders."""
    source = (ROOT / "src/eqrec/studies/notebooks/execute.py").read_text()
    top = [n for n in ast.parse(source).body if isinstance(n, (ast.Import, ast.ImportFrom))]
    assert not any("html" in ast.unparse(n) for n in top)  # imported inside to_html only
    assert "src/eqrec/studies/notebooks/html.py" in code.code_inputs("eqrec.studies.notebooks.execute:step_execute")


# --------------------------------------------------------------------------- atomic writers

@pytest.mark.parametrize("writer,bad", [
    (lambda p: outputs.write_json(p, {"a": object()}), "json"),
    (lambda p: outputs.write_npz(p, a=np.zeros(2), b=_Boom()), "npz"),
    (lambda p: outputs.write_csv(p, _BoomFrame()), "csv"),
    (lambda p: outputs.write_text(p, None), "txt")])
def test_atomic_writers_leave_no_temp_file_and_keep_the_old_file_on_failure(tmp_path, writer, bad):
    target = tmp_path / f"out.{bad}"
    target.write_text("old")
    with pytest.raises(Exception):
        writer(target)
    assert sorted(p.name for p in tmp_path.iterdir()) == [target.name]
    assert target.read_text() == "old"


class _Boom:
    def __array__(self, *a, **k):
        raise RuntimeError("cannot")


class _BoomFrame:
    def to_csv(self, path, **kw):
        Path(path).write_text("half")
        raise RuntimeError("disk full")


def test_figure_writer_is_atomic_too(tmp_path):
    from eqrec.studies.plotting import pyplot

    fig, ax = pyplot().subplots()
    ax.plot([0, 1])
    with pytest.raises(Exception):
        outputs.save_figure(fig, tmp_path / "f.png", tmp_path / "f.unknownformat")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["f.png"]


def test_writers_round_trip(tmp_path):
    outputs.write_json(tmp_path / "a.json", {"x": np.float64(1.5), "n": np.int64(3), "v": np.arange(2)})
    assert (tmp_path / "a.json").read_text() == '{\n  "x": 1.5,\n  "n": 3,\n  "v": [\n    0,\n    1\n  ]\n}\n'
    outputs.write_npz(tmp_path / "a.npz", v=np.arange(3))
    assert np.load(tmp_path / "a.npz")["v"].tolist() == [0, 1, 2]
    outputs.write_csv(tmp_path / "a.csv", pd.DataFrame({"a": [1]}))
    assert (tmp_path / "a.csv").read_text() == "a\n1\n"


# --------------------------------------------------------------------------- running steps

def test_files_behave_like_snakemake_namedlists():
    f = harness.Files(["x"], json="a.json", chunks=["c0", "c1"])
    assert f.json == "a.json" and f["chunks"] == ["c0", "c1"] and list(f) == ["x", "a.json", "c0", "c1"]
    nl = Namedlist(fromdict={"json": "a.json"})
    assert harness.Files.of(nl).json == "a.json"
    with pytest.raises(AttributeError, match="declared"):
        f.csv


def _smk(tmp_path, step, cfg, output, rule="a_rule", **wildcards):
    log = Namedlist([str(tmp_path / "logs" / "step.log")])
    params = Namedlist(fromdict={"step": step, "cfg": cfg})
    return SimpleNamespace(params=params, input=Namedlist([]), output=Namedlist(fromdict=output), rule=rule,
                           wildcards=Namedlist(fromdict={k: str(v) for k, v in wildcards.items()}), log=log)


def test_a_disabled_study_logger_still_logs(tmp_path):
    """logging.config.dictConfig (disable_existing_loggers, as Snakemake's API calls it) must not silence a step run
    later in the same process."""
    import logging

    logger = logs.get_logger("p1")
    logger.disabled = True
    try:
        harness.run_step(P1 + "model", configuration.load_config("p1", root=ROOT),
                         outputs={"json": str(tmp_path / "model.json")}, log=tmp_path / "step.log")
        assert (tmp_path / "step.log").read_text().startswith("[p1] step model")
        assert logger.disabled  # restored
    finally:
        logger.disabled = False
    assert logging.getLogger("eqrec.studies").handlers == []


def test_run_from_snakemake_logs_and_writes(tmp_path):
    cfg = configuration.load_config("p1", root=ROOT)
    harness.run_from_snakemake(_smk(tmp_path, P1 + "model", cfg, {"json": str(tmp_path / "model.json")}))
    assert (tmp_path / "model.json").is_file()
    log = (tmp_path / "logs" / "step.log").read_text().splitlines()
    assert log[0] == "[p1] step model" and log[-1].startswith("[p1] step model done in")


def test_a_failing_step_exits_1_naming_the_config_field(tmp_path, capfd):
    cfg = configuration.load_config("p2", root=ROOT)
    smk = _smk(tmp_path, "eqrec.studies.p2.sweeps:step_heatmap_chunk", cfg, {"csv": str(tmp_path / "c.csv")},
               variant="theorem2", scatteritem="10-of-2")
    with pytest.raises(SystemExit) as exc:
        harness.run_from_snakemake(smk)
    assert exc.value.code == 1
    err = capfd.readouterr().err
    assert "[p2] step heatmap_chunk failed" in err and "p2.heatmap.chunks" in err and "config/p2.yaml" in err
    assert "Traceback" in (tmp_path / "logs" / "step.log").read_text()
    assert not (tmp_path / "c.csv").exists()


def test_a_step_must_write_its_declared_outputs(tmp_path):
    cfg = configuration.load_config("p1", root=ROOT)
    with pytest.raises(errors.StepError, match="did not write"):
        harness.run_step(P1 + "model", cfg, outputs={"json": tmp_path / "m.json", "extra": tmp_path / "x.json"})


def test_a_step_that_does_not_resolve_is_named_with_its_rule(tmp_path, capfd):
    with pytest.raises(errors.StepError, match=r"rule p1_model: step 'eqrec.studies.p1.steps:step_nope' does not "
                                               r"resolve: AttributeError"):
        harness.resolve_step(P1 + "nope", "p1_model")
    with pytest.raises(errors.StepError, match=r"step 'eqrec.studies.p9.steps:step_model' does not resolve: "
                                               r"ModuleNotFoundError"):
        harness.resolve_step("eqrec.studies.p9.steps:step_model")
    for bad in ("model", "eqrec.studies.p1.steps.step_model", "os:getcwd"):
        with pytest.raises(errors.StepError, match="is not the path of a step function"):
            harness.resolve_step(bad)
    with pytest.raises(SystemExit) as exc:
        harness.run_from_snakemake(_smk(tmp_path, P1 + "nope", {}, {"json": str(tmp_path / "m.json")}, "p1_model"))
    assert exc.value.code == 1
    assert "[p1] step nope failed: StepError: rule p1_model: step 'eqrec.studies.p1.steps:step_nope'" in \
        capfd.readouterr().err


def test_progress_lines(caplog):
    import logging

    log = logs.get_logger("p2")
    with caplog.at_level(logging.INFO, logger="eqrec.studies"):
        prog = logs.Progress(log, 20, "sweep")
        for _ in range(20):
            prog.advance()
    lines = [r.getMessage() for r in caplog.records]
    assert 2 <= len(lines) <= 12 and lines[-1].startswith("sweep: 20/20 points")


def test_input_errors_of_steps_name_the_section_field():
    msg = harness.failure_message("p4", "fig5", InputError("chunks cover 0..5", field="chunks"))
    assert "p4.chunks" in msg and "config/p4.yaml" in msg
