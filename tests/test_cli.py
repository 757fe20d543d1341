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
