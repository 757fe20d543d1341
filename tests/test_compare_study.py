"""The compare study's configuration and merge step: the planning-time check refuses what CompareSetup refuses,
errors name the field of config/compare.yaml, and the table step refuses jobs that do not cover the pairs."""
import copy
from pathlib import Path

import pytest

from eqrec.compare import FAMILIES, CompareSetup
from eqrec.errors import InputError
from eqrec.studies.compare import steps as compare
from eqrec.studies.pipeline import configuration, harness
from eqrec.studies.pipeline.checks import check_compare

#: The paths of the steps run here, as the rules name them.
COMPARE = "eqrec.studies.compare.steps:step_"

ROOT = Path(__file__).resolve().parents[1]
CFG = configuration.load_config("compare", root=ROOT)
RES = ROOT / "results" / "compare"


@pytest.mark.parametrize("loss", [0.0, 0.1, 0.5, 0.8, 0.81, 0.9, 0.99])
@pytest.mark.parametrize("burst", [1.0, 1.5, 4.0, 9.0])
def test_the_planning_check_accepts_exactly_the_settings_compare_setup_accepts(loss, burst):
    try:
        CompareSetup(loss=loss, max_delay=1, horizon=4, burst=burst)
        accepted = True
    except InputError:
        accepted = False
    cfg = {"settings": {"b": {"loss": loss, "burst": burst}}}
    if accepted:
        check_compare(cfg)
    else:
        with pytest.raises(InputError, match="settings.b.burst"):
            check_compare(cfg)


def test_the_default_configuration_has_the_settings_of_the_issue():
    assert {(s["model"], s["horizon"], s["max_delay"]) for s in CFG["systems"].values()} == {
        ("acc", 6, 1), ("batch_reactor", 5, 2)}
    settings = sorted((s["loss"], s.get("burst", 0)) for s in CFG["settings"].values())
    assert settings == [(0.1, 0), (0.1, 4), (0.3, 0), (0.4, 0)]  # 0: independent losses; 0.4: heavy loss


def test_setup_errors_name_the_field_of_the_section():
    cfg = copy.deepcopy(CFG)
    cfg["systems"]["acc"]["horizon"] = 40  # past CompareSetup's range (the schema says the same)
    with pytest.raises(InputError, match=r"field 'systems\.acc\.horizon'"):
        compare.setup_of(cfg, "acc", "loss01")
    setup = compare.setup_of(CFG, "reactor", "burst")
    assert (setup.loss, setup.burst, setup.max_delay, setup.horizon, setup.runs) == (0.1, 4.0, 2, 5, CFG["runs"])


def test_the_table_step_refuses_jobs_that_do_not_cover_the_pairs(tmp_path):
    pairs = [(s, k) for s in CFG["systems"] for k in CFG["settings"]]
    out = {"csv": tmp_path / "compare.csv", "json": tmp_path / "summary.json"}
    short = {"csv": [RES / f"{s}_{k}.csv" for s, k in pairs[:-1]],
             "json": [RES / f"{s}_{k}.json" for s, k in pairs[:-1]]}
    with pytest.raises(InputError, match="exactly once"):
        harness.run_step(COMPARE + "table", CFG, inputs=short, outputs=out)
    swapped = {"csv": [RES / f"{s}_{k}.csv" for s, k in pairs[::-1]],
               "json": [RES / f"{s}_{k}.json" for s, k in pairs]}
    with pytest.raises(InputError, match="same order"):
        harness.run_step(COMPARE + "table", CFG, inputs=swapped, outputs=out)
    assert not out["csv"].exists()


def test_the_run_step_refuses_outputs_that_are_not_one_per_setting(tmp_path):
    # one job per system: its outputs are named <system>_<setting>.<ext>, one per setting of the section
    settings = list(CFG["settings"])
    files = {ext: [tmp_path / f"acc_{k}.{ext}" for k in settings] for ext in ("csv", "json", "png", "pdf")}
    files["timings"] = [tmp_path / "timings" / f"acc_{k}.json" for k in settings[:-1]]  # one setting short
    with pytest.raises(InputError, match="not one per setting"):
        harness.run_step(COMPARE + "run", CFG, outputs=files, wildcards={"system": "acc"})
    files["timings"].append(tmp_path / "timings" / f"acc_{settings[-1]}.json")
    files["csv"][-1] = tmp_path / f"reactor_{settings[-1]}.csv"  # another system's name
    with pytest.raises(InputError, match="not one per setting"):
        harness.run_step(COMPARE + "run", CFG, outputs=files, wildcards={"system": "acc"})
    assert not list(tmp_path.glob("*.csv"))


def test_the_merged_table_puts_system_and_setting_first():
    import pandas as pd

    table = pd.read_csv(RES / "compare.csv")
    assert list(table.columns[:7]) == [*compare.KEYS, "estimator"]
    assert len(table) == len(FAMILIES) * len(CFG["systems"]) * len(CFG["settings"])
    ran = table[table["rms"].notna()]  # every family that ran has a bound, and no violation
    assert (ran["violations"] == 0).all() and ran["bound"].notna().all()
    assert ran.loc[~ran["estimator"].str.startswith("guaranteed"), "outside_design"].isna().all()
    missing = table[table["rms"].isna()]  # a design that does not exist: the row says why
    assert missing["design"].str.startswith("no design").all()


@pytest.mark.parametrize("enabled", [True, False])
def test_the_run_step_pauses_the_garbage_collector_and_restores_it(tmp_path, monkeypatch, enabled):
    """The pairs run with the garbage collector paused; after the step, also one that raises, it is as before."""
    import gc

    seen = []

    def families(*args, **kwargs):
        seen.append(gc.isenabled())
        raise RuntimeError("a pair that fails")

    monkeypatch.setattr(compare, "compare_families", families)
    files = {k: [str(tmp_path / f"acc_{s}.{k}") for s in sorted(CFG["settings"])]
             for k in ("csv", "json", "png", "pdf", "timings")}
    was = gc.isenabled()
    (gc.enable if enabled else gc.disable)()
    try:
        with pytest.raises(RuntimeError, match="a pair that fails"):
            compare.step_run(CFG, None, files, {"system": "acc"})
        assert seen == [False] and gc.isenabled() is enabled
    finally:
        (gc.enable if was else gc.disable)()
