"""What the design entries take (issue 24, sections 1 and 5): one reading of a word in Python and on the command
line, every bad input an InputError naming its field, per-channel noise bounds, per-state weights, μ1 free for
the prefix method and the true smallest μ1 in an infeasibility message."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import eqrec
from eqrec.cli import main
from eqrec.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
ACC_FILE = ROOT / "examples" / "acc_system.yaml"
L1 = ["101111", "110111", "111011", "111101"]
L1_AS_DELAYS = ["060000", "006000", "000600", "000060"]  # the delayed-data paper's spelling of L1 (P3-ACC)
ZERO_ONE = ["0111", "1011", "1101"]


@pytest.fixture(scope="module")
def acc():
    return eqrec.acc_system()


# --- 1. one rule for what a word means ----------------------------------------------------------------------------

@pytest.mark.parametrize("entry", ["design_delay", "design_delay_global", "min_recovery_level", "as_language"])
def test_a_zero_one_word_list_is_refused_where_both_readings_apply(acc, entry):
    calls = {"design_delay": lambda: eqrec.design_delay(acc, ZERO_ONE, 1.0),
             "design_delay_global": lambda: eqrec.design_delay_global(acc, ZERO_ONE),
             "min_recovery_level": lambda: eqrec.min_recovery_level(acc, ZERO_ONE),
             "as_language": lambda: eqrec.as_language(ZERO_ONE)}
    with pytest.raises(InputError) as info:
        calls[entry]()
    text = str(info.value)
    assert "missing-data words" in text and "delay words" in text
    assert "kind='missing'" in text and "kind='delay'" in text and "eqrec.missing_words" in text


def test_the_missing_reading_is_the_prefix_design_of_the_same_words(acc):
    prefix = eqrec.design_prefix(acc, L1, 1.0)
    by_kind = eqrec.design_delay(acc, L1, 1.0, kind="missing", cost="max")
    typed = eqrec.design_delay(acc, eqrec.missing_words(L1), 1.0, cost="max")
    spelled_as_delays = eqrec.design_delay(acc, L1_AS_DELAYS, 1.0, cost="max")  # digit 6: delay words, no kind
    assert set(by_kind.patterns) == set(prefix.patterns) == set(typed.patterns) == set(spelled_as_delays.patterns)
    assert by_kind.mu2 == pytest.approx(prefix.mu2, rel=1e-9)
    assert typed.mu2 == by_kind.mu2 == spelled_as_delays.mu2


def test_the_delay_reading_is_another_language(acc):
    missing = eqrec.design_delay_global(acc, ZERO_ONE, kind="missing")
    delay = eqrec.design_delay_global(acc, ZERO_ONE, kind="delay")
    typed = eqrec.design_delay_global(acc, eqrec.delay_words(ZERO_ONE))
    # as delay words 0111 is "y(0) on time, y(1), y(2) one step late, y(3) past the horizon"
    assert eqrec.delay_words(["0111"])[0].arrivals == (0, 2, 3, None)
    assert eqrec.missing_words(["0111"])[0].arrivals == (None, 1, 2, 3)
    assert set(delay.design.patterns) == set(typed.design.patterns) != set(missing.design.patterns)
    assert delay.mu1 == typed.mu1 != pytest.approx(missing.mu1, rel=1e-3)
    assert missing.mu1 == pytest.approx(eqrec.min_recovery_level(acc, ZERO_ONE, kind="missing").upper, rel=1e-12)


def test_unknown_kind_is_refused(acc):
    with pytest.raises(InputError, match="unknown word kind") as info:
        eqrec.design_delay(acc, ZERO_ONE, 1.0, kind="late")
    assert info.value.field == "kind"


def test_missing_data_entries_read_zero_one_strings_as_missing_data(acc):
    assert eqrec.validate_language(ZERO_ONE) == tuple(ZERO_ONE)
    with pytest.raises(InputError, match="outside the alphabet"):
        eqrec.design_prefix(acc, ["0120"], 1.0)  # a delay word is not a missing-data word
    d = eqrec.design_prefix(acc, eqrec.delay_words(L1_AS_DELAYS), 1.0)  # typed delay patterns are accepted
    assert d.mu2 == pytest.approx(eqrec.design_prefix(acc, L1, 1.0).mu2, rel=1e-9)


MIXED = ["1111", "011"]


@pytest.mark.parametrize("entry", ["design_prefix", "design_time_based", "design_augmented"])
def test_words_of_mixed_lengths_are_refused_as_on_the_command_line(acc, entry, tmp_path, capsys):
    with pytest.raises(InputError) as info:
        getattr(eqrec, entry)(acc, MIXED, 1.0)
    assert info.value.field == "words"
    python_text = str(info.value).split("field 'words': ", 1)[1]
    assert main(["design", str(ACC_FILE), "--words", ",".join(MIXED), "--method",
                 {"design_prefix": "prefix", "design_time_based": "time", "design_augmented": "augmented"}[entry]]) == 1
    cli_text = capsys.readouterr().err.split("field '--words': ", 1)[1].strip()
    assert python_text == cli_text == "words of mixed lengths [3, 4] in a fixed-length language: ['1111', '011']"


def test_delay_words_of_mixed_lengths_are_refused_as_on_the_command_line(acc, capsys):
    with pytest.raises(InputError) as info:
        eqrec.design_delay(acc, ["0600", "06000"], 1.0)
    assert main(["design", str(ACC_FILE), "--method", "delay", "--delays", "0600,06000"]) == 1
    cli_text = capsys.readouterr().err.split("field '--delays': ", 1)[1].strip()
    assert str(info.value).split("field 'patterns': ", 1)[1] == cli_text


def test_a_finite_length_language_is_designed_when_asked(acc):
    d = eqrec.design_prefix(acc, ["1011", "11011", "111011"], 1.0, fixed_length=False)
    assert sorted(len(w) for w in d.words) == [4, 5, 6] and d.certificate.terminal <= 1.0 + 1e-6
    with pytest.raises(InputError, match="mixed lengths"):
        eqrec.design_prefix(acc, eqrec.PrefixTree(["1011", "11011"]), 1.0)  # a tree is checked too
