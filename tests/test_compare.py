"""``eqrec compare``: every estimator family on the same traces (issue 24, section 4)."""
import subprocess
from pathlib import Path
import sys

import numpy as np
import pandas as pd
import pytest

from eqrec.compare.families import BOUNDED, EXACT
from eqrec.compare import COLUMNS, FAMILIES, CompareSetup, compare_families, draw_trace, write_table
from eqrec.arrivals.draws import NEVER
from eqrec.errors import InputError
from eqrec.systems.examples import batch_reactor


@pytest.fixture(scope="module")
def reactor_result():
    return compare_families(batch_reactor(), CompareSetup(loss=0.2, max_delay=1, horizon=4, runs=12, periods=5,
                                                          seed=3))


def test_every_family_has_a_row_and_every_bound_holds(reactor_result):
    table = reactor_result.table
    assert list(table["estimator"]) == list(FAMILIES)
    assert list(table.columns[:len(COLUMNS)]) == list(COLUMNS)
    bounded = table[table["estimator"].isin(BOUNDED) & table["rms"].notna()]
    assert len(bounded) >= 6  # the zonotope, both Kalman and both LMV filters, and at least one design
    assert (bounded["violations"] == 0).all()
    assert (bounded["max_error"] <= bounded["bound"]).all()
    # no data-independent bound below the information limit; the exact family's hull reads the data, and can be
    linear = bounded[bounded["estimator"] != EXACT]
    assert (linear["bound_over_limit_median"] >= 1 - 1e-9).all()
    missing = table[table["rms"].isna()]  # a design that does not exist is a row saying why
    assert missing["design"].str.startswith("no design").all()
    assert set(BOUNDED) == set(FAMILIES)  # every family with a bound: the LMV ones too (exact_bound)
    for family, err in reactor_result.errors.items():  # the exact family on the first exact_runs (4) runs only
        assert err.shape == ((4 if family == EXACT else 12), 20) and np.all(np.isfinite(err))
    assert reactor_result.limit.shape == (12, 20) and np.all(reactor_result.limit > 0)


def test_every_set_holds_the_exact_consistent_set_and_the_exact_family_reaches_it(reactor_result):
    """Issue 45 §5: hull_over_exact, each family's set over the exact consistent set of the runs' own data, on the
    first exact_runs runs; every sound set contains that set (eqrec.consistent_set, Theorem 2), the exact
    estimator's hull equals it up to its window's prior, and the exact set is never wider than the limit."""
    table = reactor_result.table.set_index("estimator")
    hull = reactor_result.exact_hull
    assert hull.shape == (4, 20) and np.all(hull > 0)
    assert np.all(hull <= reactor_result.limit[:4] * (1 + 1e-9))  # the limit is the worst case over data
    ran = table[table["rms"].notna()]
    assert ran["hull_over_exact_median"].notna().all() and ran["hull_over_exact_p95"].notna().all()
    assert (ran["hull_over_exact_median"] >= 1 - 1e-9).all()  # no sound set is smaller than the exact one
    assert (ran["hull_over_exact_p95"] >= ran["hull_over_exact_median"]).all()
    for family, bound in reactor_result.bounds.items():  # the column is what it says, recomputed here
        over = bound[:4] / hull
        assert table.loc[family, "hull_over_exact_median"] == np.median(over)
    assert table.loc[EXACT, "hull_over_exact_median"] <= 1.05  # the exact estimator: at the exact set
    assert table.loc[EXACT, "hull_over_exact_median"] <= table.loc[FAMILIES[2], "hull_over_exact_median"]
    assert table.loc[EXACT, "violations"] == 0


def test_no_exact_runs_gives_no_exact_row_and_no_hull_columns():
    result = compare_families(batch_reactor(), CompareSetup(loss=0.2, max_delay=1, horizon=4, runs=2, periods=2,
                                                            exact_runs=0))
    table = result.table.set_index("estimator")
    assert np.isnan(table.loc[EXACT, "rms"]) and EXACT not in result.errors
    assert table["hull_over_exact_median"].isna().all() and result.exact_hull.shape == (0, 8)


def test_the_table_is_the_errors_it_summarises(reactor_result):
    row = reactor_result.table.set_index("estimator").loc[FAMILIES[2]]
    assert row["max_error"] == reactor_result.errors[FAMILIES[2]].max()
    per_state = [row[f"rms_x{i}"] for i in range(1, 5)]
    assert row["rms"] == pytest.approx(np.sqrt(np.mean(np.square(per_state))))


def test_in_the_language_the_class_engine_stays_in_design():
    result = compare_families(batch_reactor(), CompareSetup(loss=0.0, max_delay=1, horizon=4, runs=5, periods=4))
    row = result.table.set_index("estimator").loc[FAMILIES[0]]
    assert row["outside_design"] == 0 and row["violations"] == 0
    assert row["bound"] <= result.mu1[FAMILIES[0]] * 10
    assert row["design"] == "delays 0..1, at most 0 of 4 lost"


def test_traces_follow_the_settings():
    rng = np.random.default_rng(0)
    setup = CompareSetup(loss=0.3, max_delay=2, horizon=5, periods=400)
    d = draw_trace(rng, setup).delays
    lost = d == NEVER
    assert abs(lost.mean() - 0.3) < 5 * np.sqrt(0.3 * 0.7 / d.size)
    assert set(d[~lost].tolist()) == {0, 1, 2}
    burst = draw_trace(np.random.default_rng(1), CompareSetup(loss=0.2, max_delay=0, horizon=5, periods=2000,
                                                              burst=5.0)).delays == NEVER
    runs = np.diff(np.flatnonzero(np.diff(np.r_[0, burst.astype(int), 0])))[::2]
    assert abs(burst.mean() - 0.2) < 0.03 and abs(runs.mean() - 5.0) < 0.6  # mean burst length


def test_results_are_reproducible_byte_for_byte(tmp_path):
    setup = CompareSetup(loss=0.1, max_delay=1, horizon=4, runs=4, periods=3, seed=5)
    for name in ("a.csv", "b.csv"):
        write_table(compare_families(batch_reactor(), setup), str(tmp_path / name))
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    table = pd.read_csv(tmp_path / "a.csv")
    assert table.loc[2:, "bound"].notna().all()


@pytest.mark.parametrize("kwargs,field", [
    (dict(loss=1.2), "loss"), (dict(loss="0.1"), "loss"), (dict(max_delay=-1), "max_delay"),
    (dict(horizon=0), "horizon"), (dict(runs=2.5), "runs"), (dict(burst=0.5), "burst"),
    (dict(loss=0.9, burst=2.0), "burst"), (dict(loss=0.0, burst=3.0), "burst"), (dict(seed=-1), "seed"),
    (dict(exact_runs=-1), "exact_runs"), (dict(exact_runs=1.5), "exact_runs"),
])
def test_bad_settings_name_the_field(kwargs, field):
    base = dict(loss=0.1, max_delay=1, horizon=4)
    with pytest.raises(InputError) as exc:
        CompareSetup(**{**base, **kwargs})
    assert exc.value.field == field


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "eqrec", "compare", *args], capture_output=True, text=True)


def test_cli_writes_the_table_and_the_figure(tmp_path):
    out = tmp_path / "cmp"
    r = _cli("examples/batch_reactor.yaml", "--loss", "0.1", "--max-delay", "1", "--horizon", "4", "--runs", "4",
             "--periods", "3", "--out", str(out))
    assert r.returncode == 0, r.stderr
    assert {p.name for p in out.iterdir()} == {"compare.csv", "compare.png", "compare.pdf"}
    assert "guaranteed, class engine" in r.stdout and "Traceback" not in r.stderr


@pytest.mark.parametrize("args,code,text", [
    (["--loss", "1.5"], 1, "loss"),
    (["--loss", "0.1", "--burst", "0.2"], 1, "burst"),
    (["--loss", "0.1", "--solver", "gurobi"], 1, "solver"),
    (["--loss", "abc"], 2, "invalid float"),
])
def test_cli_refuses_bad_input_and_writes_nothing(tmp_path, args, code, text):
    out = tmp_path / "cmp"
    r = _cli("examples/batch_reactor.yaml", "--max-delay", "1", "--horizon", "4", "--runs", "2", "--periods", "2",
             *args, "--out", str(out))
    assert r.returncode == code and text in r.stderr and "Traceback" not in r.stderr
    assert not out.exists()


def test_cli_refuses_an_output_folder_without_parent_and_a_bad_gaussian_section(tmp_path):
    r = _cli("examples/batch_reactor.yaml", "--loss", "0.1", "--max-delay", "1", "--horizon", "4",
             "--out", str(tmp_path / "missing" / "cmp"))
    assert r.returncode == 1 and "--out" in r.stderr
    system = tmp_path / "plant.yaml"
    system.write_text("A: [[1.0, 0.1], [0.0, 1.0]]\nC: [[1.0, 0.0]]\nE: [[0.1, 0.0], [0.0, 0.1]]\n"
                      "eta_w: 0.1\neta_v: 0.05\ngaussian: {Qw: [[1.0, 2.0], [2.0, 1.0]]}\n")
    r = _cli(str(system), "--loss", "0.1", "--max-delay", "1", "--horizon", "3", "--runs", "2", "--periods", "2",
             "--out", str(tmp_path / "g"))
    assert r.returncode == 1 and "Qw" in r.stderr and not (tmp_path / "g").exists()


def test_state_weights_measure_every_error_bound_and_limit_in_the_weighted_norm():
    """``state_weights``: errors, bounds and limit as ``max_i w_i |·_i|``; every bound still holds."""
    from eqrec.systems.examples import acc_system

    w = np.array([1.0, 0.2, 4.0])
    setup = CompareSetup(loss=0.1, max_delay=1, horizon=6, runs=3, periods=3, seed=2)
    weighted = compare_families(acc_system(), setup, state_weights=w)
    plain = compare_families(acc_system(), setup)
    table = weighted.table.set_index("estimator")
    ran = table[table["rms"].notna()]
    assert (ran["violations"] == 0).all() and (ran.drop(index=EXACT)["bound_over_limit_median"] >= 1 - 1e-9).all()
    assert (ran["hull_over_exact_median"] >= 1 - 1e-9).all()  # the exact set in the weighted norm too
    assert weighted.state_weights.tolist() == w.tolist() and plain.state_weights is None
    assert not np.allclose(weighted.limit, plain.limit)  # a different norm
    with pytest.raises(InputError) as exc:
        compare_families(acc_system(), setup, state_weights=[1.0, -1.0, 1.0])
    assert exc.value.field == "state_weights"


def test_cli_compare_takes_state_weights(tmp_path):
    from eqrec.cli import main

    acc = str(Path(__file__).resolve().parents[1] / "examples" / "acc_system.yaml")
    assert main(["compare", acc, "--loss", "0.1", "--max-delay", "1", "--horizon", "6", "--runs", "2", "--periods",
                 "2", "--state-weights", "1,0.2,4", "--out", str(tmp_path / "w")]) == 0
    assert (tmp_path / "w" / "compare.csv").exists()
    assert main(["compare", acc, "--loss", "0.1", "--max-delay", "1", "--horizon", "6", "--runs", "2",
                 "--state-weights", "1,2", "--out", str(tmp_path / "bad")]) == 1


def test_a_memo_shared_by_settings_of_one_system_changes_no_byte(tmp_path):
    """The settings of one system share their guaranteed designs through ``memo`` (the compare study's job): the
    tables are those of fresh calls, and a setting whose loss budgets were all tried makes no design again."""
    from eqrec.bounds import information

    system = batch_reactor()
    setups = [CompareSetup(loss=loss, max_delay=1, horizon=4, runs=3, periods=2, seed=5, exact_runs=1)
              for loss in (0.3, 0.1, 0.3)]
    memo, made = {}, []
    for i, setup in enumerate(setups):
        information.clear_cache()
        write_table(compare_families(system, setup), str(tmp_path / f"fresh{i}.csv"))
        information.clear_cache()
        before = len(memo)
        write_table(compare_families(system, setup, memo=memo), str(tmp_path / f"memo{i}.csv"))
        made.append(len(memo) - before)
        assert (tmp_path / f"fresh{i}.csv").read_bytes() == (tmp_path / f"memo{i}.csv").read_bytes()
    assert made[0] > 0 and made[2] == 0  # the third setting is the first's: nothing made again
    other = {}
    compare_families(system, setups[1], memo=other)
    compare_families(batch_reactor(), setups[1], memo=other)  # another system object: the memo starts again
    assert other["system"] is not system and sum(k[0] == "design" for k in other if k != "system") > 0


def test_figures_drawn_again_on_a_memo_are_the_bytes_of_figures_of_their_own(tmp_path):
    """The compare job draws its settings' figures on one figure kept in ``compare_figure``'s memo: every file is
    the one a figure of its own gives, whatever the figure before it drew (other axis limits and titles, a panel
    without a design, a weighted norm's label)."""
    from eqrec.compare import compare_figure
    from eqrec.systems.examples import acc_system

    results = [compare_families(batch_reactor(), CompareSetup(loss=0.2, max_delay=1, horizon=4, runs=3, periods=2,
                                                              seed=3, exact_runs=1)),
               compare_families(batch_reactor(), CompareSetup(loss=0.3, max_delay=2, horizon=2, runs=2, periods=2,
                                                              exact_runs=0)),
               compare_families(acc_system(), CompareSetup(loss=0.1, max_delay=1, horizon=3, runs=2, periods=2,
                                                           exact_runs=1), state_weights=[1.0, 2.0, 1.0])]
    assert "no design" in results[1].designs[FAMILIES[0]] and FAMILIES[1] in results[1].errors
    memo: dict = {}
    for i, result in enumerate([*results, results[0]]):
        own = [str(tmp_path / f"own{i}.{ext}") for ext in ("png", "pdf")]
        again = [str(tmp_path / f"again{i}.{ext}") for ext in ("png", "pdf")]
        compare_figure(result, *own, title=f"figure {i}")
        compare_figure(result, *again, title=f"figure {i}", memo=memo)
        for a, b in zip(own, again):
            assert Path(a).read_bytes() == Path(b).read_bytes(), f"{b} differs from a figure of its own"
    assert "panels" in memo  # one figure, drawn four times
