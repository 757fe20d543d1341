import pytest

from eqrec.design.prefix.time_based import design_time_based
from eqrec.errors import InputError


def test_time_based_is_designed_for_the_worst_case_word(acc, L1_words):
    d = design_time_based(acc, L1_words, 1.0)
    assert d.worst_case_word == "100001"
    assert d.schedule.time_based and d.schedule.designed_words == ("100001",)
    # certified on every word of the language and on the worst-case word itself
    assert set(d.certificate.words) == set(L1_words) | {"100001"}


def test_time_based_rejects_mixed_lengths(acc):
    with pytest.raises(InputError, match="mixed lengths"):
        design_time_based(acc, ["1011", "10111"], 1.0)


def test_sweeps_refuse_an_unknown_method_naming_the_field(acc):
    """A misspelt method is an InputError (the project's bad-input error, exit 1 in the CLI), naming the field."""
    from eqrec.studies.searches import min_feasible_mu1
    from eqrec.errors import InputError

    with pytest.raises(InputError, match="unknown method 'prefx'") as info:
        min_feasible_mu1(acc, ["101111"], method="prefx")
    assert info.value.field == "method"
