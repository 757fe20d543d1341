import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from eqrec.cli import main

ROOT = Path(__file__).resolve().parents[1]
SYSTEM = ROOT / "examples" / "acc_system.yaml"


def test_design_prefix_writes_contract(tmp_path):
    out = tmp_path / "d.json"
    rc = main(["design", str(SYSTEM), "--words", "101111,110111,111011,111101", "--method", "prefix",
               "--out", str(out)])
    assert rc == 0
    d = json.loads(out.read_text())
    for key in ("method", "mu1", "mu2", "certified_mu2", "solver", "status", "words", "gains"):
        assert key in d
    assert d["certified_mu2"] == pytest.approx(d["mu2"], rel=1e-6)
    F = np.asarray(d["gains"]["101111"]["F"])
    assert F.shape == (6 * 3, 6 * 2) and len(d["gains"]["101111"]["u0"]) == 18
    assert np.allclose(np.triu(F, 2)[:, ::1][0, 2:], 0)  # causal: F(0, τ>0) = 0


def test_time_method_uses_worst_case_word(tmp_path, capsys):
    rc = main(["design", str(SYSTEM), "--words", "101111,110111", "--method", "time", "--solver", "clarabel"])
    assert rc == 0
    d = json.loads(capsys.readouterr().out)
    assert d["worst_case_word"] == "100111" and list(d["gains"]) == ["100111"]


def test_infeasible_exits_3_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "d.json"
    rc = main(["design", str(SYSTEM), "--words", "101111", "--mu1", "0.05", "--out", str(out)])
    assert rc == 3 and not out.exists()
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "infeasible" in err[0]


@pytest.mark.parametrize("words,msg", [("1011,110111", "mixed lengths"), ("10a111", "alphabet"),
                                       ("1011", "required length 6")])
def test_bad_words(words, msg, capsys):
    assert main(["design", str(SYSTEM), "--words", words]) == 1
    assert msg in capsys.readouterr().err


def test_malformed_system_names_file_and_field(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("A: [[1, 0], [0, 1]]\nC: [[1, 0, 0]]\nE: [[0], [1]]\neta_w: 0.1\neta_v: 0.1\n")
    assert main(["design", str(bad), "--words", "11"]) == 1
    err = capsys.readouterr().err
    assert "bad.yaml" in err and "'C'" in err


def test_console_script_help():
    out = subprocess.run([sys.executable, "-m", "eqrec.cli", "design", "--help"], capture_output=True, text=True)
    assert out.returncode == 0 and "SYSTEM.yaml keys" in out.stdout and "--method" in out.stdout


def test_augmented_free_L_prints_clean_json(capsys):
    # IPOPT's banner must not leak into the JSON written to stdout
    assert main(["design", str(SYSTEM), "--words", "111111", "--method", "augmented", "--L", "free"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["method"] == "augmented" and np.asarray(d["L"]).shape == (3, 2)
    assert d["certified_mu2"] <= d["mu2"] * (1 + 1e-6) + 1e-9


def test_augmented_options_rejected_for_other_methods(capsys):
    assert main(["design", str(SYSTEM), "--words", "111111", "--L", "free"]) == 1
    assert "augmented only" in capsys.readouterr().err


def test_version_and_usage_error_codes(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--version"])
    assert e.value.code == 0 and "eqrec" in capsys.readouterr().out
    with pytest.raises(SystemExit) as e:
        main(["design"])  # usage error: argparse's 2, not the infeasible-design code
    assert e.value.code == 2
    with pytest.raises(SystemExit):
        main(["design", "--help"])
    assert "3 infeasible" in capsys.readouterr().out


@pytest.mark.parametrize("target", ["missing_dir/d.json", "."])
def test_bad_out_path_is_rejected_before_designing(tmp_path, capsys, target):
    out = tmp_path / target
    rc = main(["design", str(SYSTEM), "--words", "101111", "--out", str(out)])
    err = capsys.readouterr().err
    assert rc == 1 and "--out" in err
    assert not list(tmp_path.rglob("*.tmp"))


def test_directory_as_system_file(tmp_path, capsys):
    rc = main(["design", str(tmp_path), "--words", "101111"])
    assert rc == 1 and "is a directory" in capsys.readouterr().err


def test_augmented_default_poles_follow_the_system_size(tmp_path, capsys):
    sysfile = tmp_path / "two_state.yaml"
    sysfile.write_text("A: [[1.0, 0.1], [0.0, 0.9]]\nC: [[1.0, 0.0]]\nE: [[0.0], [0.1]]\neta_w: 0.1\neta_v: 0.05\n")
    rc = main(["design", str(sysfile), "--words", "1111,1011", "--method", "augmented", "--mu1", "2"])
    assert rc == 0, capsys.readouterr().err
    d = json.loads(capsys.readouterr().out)
    assert d["certified_mu2"] <= d["mu2"] + 1e-6


def test_python_dash_m_eqrec():
    out = subprocess.run([sys.executable, "-m", "eqrec", "--version"], capture_output=True, text=True)
    assert out.returncode == 0 and out.stdout.startswith("eqrec ")


def _acc_with(tmp_path, old, new):
    text = SYSTEM.read_text()
    assert old in text
    f = tmp_path / "sys.yaml"
    f.write_text(text.replace(old, new))
    return f


@pytest.mark.parametrize("value,msg", [("1e308", "exceeds"), ('"0.1"', "quoted number")])
def test_noise_bound_errors_name_file_and_field(tmp_path, capsys, value, msg):
    f = _acc_with(tmp_path, "eta_w: 0.1", f"eta_w: {value}")
    assert main(["design", str(f), "--words", "101111"]) == 1
    err = capsys.readouterr().err
    assert "sys.yaml" in err and "'eta_w'" in err and msg in err and "Not Set" not in err


@pytest.mark.parametrize("mu1", ["1e30", "inf"])
def test_mu1_out_of_lp_range_is_an_input_error(capsys, mu1):
    assert main(["design", str(SYSTEM), "--words", "101111", "--mu1", mu1]) == 1
    assert "--mu1" in capsys.readouterr().err


def test_out_written_atomically_and_overwritten(tmp_path):
    out = tmp_path / "d.json"
    out.write_text("old")
    assert main(["design", str(SYSTEM), "--words", "111111", "--out", str(out)]) == 0
    assert json.loads(out.read_text())["method"] == "prefix"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d.json"]


def test_poles_help_mentions_complex(capsys):
    with pytest.raises(SystemExit):
        main(["design", "--help"])
    out = capsys.readouterr().out
    assert "complex" in out and "0.3+0.2j" in out


def test_explicit_complex_poles(capsys):
    rc = main(["design", str(SYSTEM), "--words", "111111", "--method", "augmented",
               "--poles", "0,0.3+0.2j,0.3-0.2j"])
    assert rc == 0, capsys.readouterr().err
    assert json.loads(capsys.readouterr().out)["method"] == "augmented"


# --------------------------------------------------------------------------- --method delay

ACC_DELAYS = "060000,006000,000600,000060"
BATCH_REACTOR = ROOT / "examples" / "batch_reactor.yaml"


def test_delay_fixed_mu1_is_the_prefix_design(tmp_path):
    """Delays past the horizon are missing data: the same problem as the prefix design on L1 (P3-ACC)."""
    out_d, out_p = tmp_path / "d.json", tmp_path / "p.json"
    assert main(["design", str(SYSTEM), "--method", "delay", "--delays", ACC_DELAYS, "--cost", "max",
                 "--out", str(out_d)]) == 0
    assert main(["design", str(SYSTEM), "--words", "101111,110111,111011,111101", "--out", str(out_p)]) == 0
    d, p = json.loads(out_d.read_text()), json.loads(out_p.read_text())
    assert d["method"] == "delay" and d["cost"] == "max"
    assert d["mu2"] == pytest.approx(p["mu2"], rel=1e-6)
    assert d["certified_mu2"] == pytest.approx(d["mu2"], rel=1e-6)
    for key in ("levels", "event_sequences", "J", "gains", "words"):
        assert key in d
    assert set(d["gains"]) == set(ACC_DELAYS.split(","))
    # event sequence of 060000: y(1) never arrives within T = 6
    assert d["event_sequences"]["060000"][-1] == "101111"


def test_delay_mu1_free_reports_its_certificate(tmp_path):
    out = tmp_path / "d.json"
    assert main(["design", str(SYSTEM), "--method", "delay", "--delays", ACC_DELAYS, "--mu1", "free",
                 "--cost", "max", "--out", str(out)]) == 0
    d = json.loads(out.read_text())
    free = d["mu1_free"]
    assert free["route"] == "global"
    assert free["lower_bound"] <= free["J"] <= free["lower_bound"] * (1 + 1e-4)
    # the free optimum is below the mu1 = 1 optimum (P3-ACC:mu2) and mu1 is at least the smallest feasible one
    assert d["mu2"] < 1.0
    assert d["mu1"] >= free["mu1_min"]["lower"]


def test_delay_full_language_with_levels_per_prefix(tmp_path):
    out = tmp_path / "d.json"
    assert main(["design", str(BATCH_REACTOR), "--method", "delay", "--max-delay", "1", "--horizon", "3",
                 "--mu1", "1", "--out", str(out)]) == 0
    d = json.loads(out.read_text())
    assert len(d["words"]) <= 2 ** 3 and d["cost"] == "sum"
    levels = d["levels"]
    assert all(row["certified"] <= row["level"] * (1 + 1e-6) + 1e-9 for row in levels)
    assert max(row["level"] for row in levels) == pytest.approx(d["mu2"])
    # the delayed first measurement: F(0, 0) is zero on sequences where y(0) arrives late
    F = np.array(d["gains"]["100"]["F"])
    assert np.all(F[:4, :2] == 0)  # zero pattern (7): y(0) not yet available at t = 0


@pytest.mark.parametrize("args, field", [
    (["--delays", "2x210"], "--delays"),
    (["--delays", "21210,212"], "--delays"),
    (["--delays", "210", "--words", "101"], "--words"),
    (["--max-delay", "2"], "--horizon"),
    (["--max-delay", "12", "--horizon", "3"], "--max-delay"),
    (["--max-delay", "1", "--horizon", "0"], "--horizon"),
    (["--delays", "210", "--max-delay", "1", "--horizon", "3"], "--delays"),
    (["--delays", "210", "--mu1", "-1"], "--mu1"),
    (["--delays", "210", "--mu1", "abc"], "--mu1"),
    (["--delays", "210", "--L", "free"], "--method"),
    ([], "--delays"),
])
def test_delay_bad_input_names_the_field(capsys, args, field):
    assert main(["design", str(SYSTEM), "--method", "delay", *args]) == 1
    assert f"'{field}'" in capsys.readouterr().err


@pytest.mark.parametrize("args, field", [
    (["--words", "101111", "--method", "augmented", "--mu1", "free"], "--mu1"),  # prefix and time take free
    (["--words", "101111", "--cost", "sum"], "--cost"),
    (["--words", "101111", "--delays", "000000"], "--delays"),
    ([], "--words"),
])
def test_delay_options_rejected_for_other_methods(capsys, args, field):
    assert main(["design", str(SYSTEM), *args]) == 1
    assert f"'{field}'" in capsys.readouterr().err


def test_delay_words_must_match_the_system_horizon(capsys):
    assert main(["design", str(SYSTEM), "--method", "delay", "--delays", "210"]) == 1
    assert "field 'T'" in capsys.readouterr().err


def test_delay_infeasible_exit_code_writes_nothing(tmp_path, capsys):
    out = tmp_path / "d.json"
    assert main(["design", str(BATCH_REACTOR), "--method", "delay", "--delays", "21210", "--mu1", "0.001",
                 "--out", str(out)]) == 3
    assert not out.exists() and not list(tmp_path.iterdir())


def test_batch_reactor_example_is_the_zoh_model():
    from eqrec.systems.files import load_system
    from eqrec.systems.examples import batch_reactor

    system, _ = load_system(BATCH_REACTOR)
    ref = batch_reactor()
    np.testing.assert_allclose(system.A, ref.A, atol=5e-6)
    np.testing.assert_array_equal(system.C, ref.C)
    assert system.eta_v == ref.eta_v and system.eta_w == 0


# --------------------------------------------------------------------------- --engine, --node-gains, big languages

ACC_WORDS = "101111,110111,111011,111101"


def _run_json(capsys, argv):
    assert main(argv) == 0, capsys.readouterr().err
    return json.loads(capsys.readouterr().out)


def test_prefix_engines_agree_on_acc(capsys, published):
    base = ["design", str(SYSTEM), "--words", ACC_WORDS, "--method", "prefix", "--mu1", "1"]
    d = _run_json(capsys, base)
    t = _run_json(capsys, [*base, "--engine", "tree"])
    assert d["engine"] == "classes" and t["engine"] == "tree"
    assert d["mu2"] == pytest.approx(t["mu2"], rel=1e-6)
    assert d["mu2"] == pytest.approx(published("P3-ACC:mu2"), abs=1e-4)
    # every earlier key stays; the class engine adds its class table, the tree engine has none
    for key in ("method", "mu1", "mu2", "certified_mu2", "certified_terminal", "solver", "status", "words",
                "designed_words", "gains"):
        assert key in d and key in t
    assert "classes" not in t
    rows = d["classes"]
    assert max(r["level"] for r in rows if not r["terminal"]) == pytest.approx(d["mu2"], rel=1e-6)
    assert all(r["certified"] <= 1.0 * (1 + 1e-6) for r in rows if r["terminal"])
    label = rows[-1]["class"]  # "d:S": time d, then a 0/1 string over the times 0..d-1
    depth, data = label.split(":")
    assert int(depth) == rows[-1]["k"] == len(data)
    assert [i for i, c in enumerate(data) if c == "1"] == rows[-1]["data"]
    assert np.asarray(rows[-1]["K"]).shape == (3, 2 * len(rows[-1]["data"]))


def test_time_method_reports_its_engine(capsys):
    d = _run_json(capsys, ["design", str(SYSTEM), "--words", "101111,110111", "--method", "time"])
    assert d["engine"] == "classes" and d["worst_case_word"] == "100111" and d["classes"]


def test_delay_engines_agree_on_the_batch_reactor(capsys):
    base = ["design", str(BATCH_REACTOR), "--method", "delay", "--max-delay", "2", "--horizon", "5", "--mu1", "0.5"]
    d = _run_json(capsys, base)
    t = _run_json(capsys, [*base, "--engine", "tree"])
    assert d["engine"] == "classes" and t["engine"] == "tree"
    assert d["mu2"] == pytest.approx(t["mu2"], rel=1e-6)
    assert d["J"] == pytest.approx(t["J"], rel=1e-6)
    assert len(d["classes"]) == 18
    # 162 event sequences: small enough that the node gains are written by default, with the word lists
    assert len(d["words"]) == len(t["words"]) == 162 and len(d["gains"]) == 162 and "designed_words" in d


def test_delay_mu1_free_engines_agree(capsys):
    base = ["design", str(SYSTEM), "--method", "delay", "--delays", ACC_DELAYS, "--mu1", "free"]
    d = _run_json(capsys, base)
    t = _run_json(capsys, [*base, "--engine", "tree"])
    # the same μ1,min; the tree LP's round-off may leave a terminal worst case a few ulps above it, and μ1 is then
    # raised to what its gains certify (eqrec.bounds.certify): equal to 1e-12, never below μ1,min
    assert t["engine"] == "tree" and t["mu1"] == pytest.approx(d["mu1"], rel=1e-12)
    assert min(t["mu1"], d["mu1"]) >= d["mu1_free"]["mu1_min"]["upper"] * (1 - 1e-15)
    assert t["J"] == pytest.approx(d["J"], rel=1e-6) and t["mu2"] == pytest.approx(d["mu2"], rel=1e-6)
    assert t["mu1_free"]["lower_bound"] <= t["J"] <= t["mu1_free"]["lower_bound"] * (1 + 1e-4)


def test_delay_30_4_free_runs_from_the_classes(tmp_path, capsys):
    """{0..4}^30 (9.3e20 words) is designed from its 446 classes, never enumerating a word."""
    out = tmp_path / "d.json"
    assert main(["design", str(BATCH_REACTOR), "--method", "delay", "--max-delay", "4", "--horizon", "30",
                 "--mu1", "free", "--out", str(out)]) == 0, capsys.readouterr().err
    assert out.stat().st_size < 3_000_000
    d = json.loads(out.read_text())
    assert d["engine"] == "classes" and len(d["classes"]) == 446
    assert "gains" not in d and "levels" not in d and "designed_words" not in d
    assert d["words"] == 5 ** 30 and d["max_delay"] == 4 and d["horizon"] == 30
    assert d["certified_mu2"] <= d["mu2"] * (1 + 1e-6)
    assert d["J_certified"] <= d["J"] * (1 + 1e-6)
    free = d["mu1_free"]
    assert free["route"] == "global" and free["lower_bound"] <= free["J"]


def test_medium_language_writes_counts_unless_node_gains_asked(capsys):
    """{0..2}^6: 486 event sequences, over the default node-gain limit; --node-gains enumerates the words."""
    base = ["design", str(BATCH_REACTOR), "--method", "delay", "--max-delay", "2", "--horizon", "6", "--mu1", "1"]
    d = _run_json(capsys, base)
    assert d["words"] == 3 ** 6 and "gains" not in d and "designed_words" not in d
    g = _run_json(capsys, [*base, "--node-gains"])
    assert len(g["words"]) == 486 and len(g["gains"]) == 486 and g["designed_words"] and g["levels"]
    assert g["mu2"] == pytest.approx(d["mu2"], rel=1e-9) and len(g["classes"]) == len(d["classes"])


@pytest.mark.parametrize("args, field", [(["--node-gains"], "--node-gains"), (["--engine", "tree"], "--engine")])
def test_big_language_refuses_what_needs_the_words(tmp_path, capsys, args, field):
    out = tmp_path / "d.json"
    assert main(["design", str(BATCH_REACTOR), "--method", "delay", "--max-delay", "4", "--horizon", "30",
                 "--mu1", "free", *args, "--out", str(out)]) == 1
    err = capsys.readouterr().err
    assert f"'{field}'" in err and "9.31e+20 words" in err
    assert not out.exists()


def test_delay_classes_infeasible_fixed_mu1_exits_3(tmp_path, capsys):
    out = tmp_path / "d.json"
    assert main(["design", str(BATCH_REACTOR), "--method", "delay", "--max-delay", "2", "--horizon", "5",
                 "--mu1", "0.01", "--out", str(out)]) == 3
    assert "infeasible" in capsys.readouterr().err
    assert not out.exists() and not list(tmp_path.iterdir())


def test_unknown_engine_is_a_usage_error(capsys):
    with pytest.raises(SystemExit) as e:
        main(["design", str(SYSTEM), "--words", ACC_WORDS, "--engine", "bogus"])
    assert e.value.code == 2 and "--engine" in capsys.readouterr().err


@pytest.mark.parametrize("args, field", [
    (["--method", "time", "--engine", "tree"], "--engine"),
    (["--method", "augmented", "--engine", "classes"], "--engine"),
    (["--node-gains"], "--node-gains"),
])
def test_engine_and_node_gains_rejected_where_they_do_not_apply(capsys, args, field):
    assert main(["design", str(SYSTEM), "--words", "111111", *args]) == 1
    assert f"'{field}'" in capsys.readouterr().err


def test_help_describes_engines_and_classes(capsys):
    with pytest.raises(SystemExit):
        main(["design", "--help"])
    out = capsys.readouterr().out
    for text in ("--engine", "--node-gains", '"d:S"', "K (y_S - ybar_S)", "T = 30"):
        assert text in out


def test_help_states_the_node_gains_limit_of_to_json():
    from eqrec.cli import JSON_NODE_GAINS_SEQUENCES
    from eqrec.design.report import JSON_NODE_GAINS_LIMIT

    assert JSON_NODE_GAINS_SEQUENCES == JSON_NODE_GAINS_LIMIT


def test_mu1_free_on_a_language_no_estimator_recovers_exits_3(tmp_path, capsys):
    """An unstable state never measured within the horizon: infeasible for every mu1 (the theorem's test), exit 3."""
    system = tmp_path / "unstable.yaml"
    system.write_text("A: [[2.0]]\nC: [[1.0]]\nE: [[0.0]]\neta_w: 0.0\neta_v: 0.1\n")
    out = tmp_path / "d.json"
    for engine in ("classes", "tree"):
        rc = main(["design", str(system), "--method", "delay", "--delays", "333", "--mu1", "free",
                   "--engine", engine, "--out", str(out)])
        assert rc == 3 and not out.exists()
        err = capsys.readouterr().err
        assert "infeasible" in err and "terminal class" in err


@pytest.mark.parametrize("extra,msg", [(["--s0", "[1,2]"], "s0 must be a vector of n = 3"),
                                       (["--L", "[[1,2]]"], "L must be an n x p = 3 x 2"),
                                       (["--poles", "0,0.5"], "give n = 3 poles")])
def test_augmented_shapes_are_validated(extra, msg, capsys):
    rc = main(["design", str(SYSTEM), "--words", "101111", "--method", "augmented", "--mu1", "1", *extra])
    err = capsys.readouterr().err
    assert rc == 1 and msg in err and "Traceback" not in err


def test_augmented_on_an_unobservable_system_is_infeasible_and_says_observability(tmp_path, capsys):
    system = tmp_path / "unobservable.yaml"
    system.write_text("A: [[1.0, 0.1, 0], [0, 1.0, 0], [0, 0, 0.9]]\nC: [[1.0, 0, 0]]\nE: [[0], [0], [0]]\n"
                      "eta_w: 0.0\neta_v: 0.1\n")
    rc = main(["design", str(system), "--words", "1111", "--method", "augmented", "--mu1", "1"])
    err = capsys.readouterr().err
    assert rc == 3 and "not observable" in err and "controllab" not in err


def test_design_dispatches_through_the_table_of_methods(monkeypatch, capsys):
    """``--method`` names an entry of ``DESIGN_METHODS`` (the parser's choices are its keys); ``run_design`` does the
    shared checks, then calls that entry with the loaded system, its ``T``, ``μ1``, weights and parallel options."""
    import eqrec.cli as cli

    assert list(cli.DESIGN_METHODS) == ["time", "prefix", "augmented", "delay"]
    called = []
    monkeypatch.setitem(cli.DESIGN_METHODS, "time", lambda args, system, T, mu1, weights, par:
                        called.append((system.n, T, mu1, weights, par)) or {"method": "time", "mu1": mu1})
    assert cli.run_design(cli._parser().parse_args(["design", str(SYSTEM), "--method", "time", "--mu1", "free"])) == \
        {"method": "time", "mu1": "free"}
    assert called == [(3, 6, "free", None, {"n_jobs": None, "scheduler": None})]  # the file gives T = 6
    with pytest.raises(SystemExit):  # a method outside the table is a usage error (exit 2)
        cli._parser().parse_args(["design", str(SYSTEM), "--method", "nope"])
    assert "invalid choice: 'nope'" in capsys.readouterr().err
