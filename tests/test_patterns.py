import pytest

from eqrec.errors import InputError
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import extend_word, prefixes, validate_language, worst_case_word


def test_worst_case_word_examples_of_the_papers(L1_words):
    assert worst_case_word(L1_words) == "100001"  # prefix-based paper, Sec. VI
    assert worst_case_word(["1011", "1101"]) == "1001"  # prefix-based paper, Sec. III
    assert worst_case_word(["101111", "110111"]) == "100111"  # augmented paper, Sec. IV-B


def test_prefix_tree_of_the_paper_example():
    # Sec. III: gains needed for prefixes {1, 10, 11, 101, 110, 1011, 1101}
    tree = PrefixTree(["1011", "1101"])
    assert {n.label for n in tree} == {"1", "10", "11", "101", "110", "1011", "1101"}
    assert [n.label for n in tree.path("1101")] == ["1", "11", "110", "1101"]
    assert all(tree.nodes[n.parent].label == n.label[:-1] for n in tree if n.parent is not None)
    assert [n.label for n in tree if n.terminal] == ["1011", "1101"]


def test_finite_length_language_marks_inner_terminal_nodes():
    tree = PrefixTree(["10", "101"])
    assert tree.node("10").terminal and tree.node("101").terminal and not tree.node("1").terminal


@pytest.mark.parametrize("words,msg", [(["1012"], "alphabet"), (["101", "1011"], "mixed lengths"), ([], "empty"),
                                       ([""], "empty"), ([101], "string")])
def test_bad_words(words, msg):
    with pytest.raises(InputError, match=msg):
        validate_language(words)


def test_required_length():
    with pytest.raises(InputError, match="required length 6"):
        validate_language(["10111"], length=6)


def test_prefix_outside_language():
    with pytest.raises(InputError, match="not a prefix"):
        PrefixTree(["11"]).node("0")


def test_helpers():
    assert prefixes("101") == ["1", "10", "101"]
    assert extend_word("10", 4) == "1011"


# --- arrival patterns: delay words, events (delayed-data paper, Sec. III-A) ---------------------

from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_language, full_delay_language, parse_delay_word, worst_case_pattern


def test_example_1_and_3_event_sequences_and_reduction():
    words = full_delay_language(2, 2)
    assert words == ("00", "01", "02", "10", "11", "12", "20", "21", "22")  # Example 1
    pats = [parse_delay_word(w, 2) for w in words]
    # Example 3: E_alpha = e_{0,j0} e_{1,j1} with the indices of eq. (2)
    assert [(p.event_index(0), p.event_index(1)) for p in pats] == [
        (1, 3), (1, 2), (1, 2), (0, 3), (0, 2), (0, 2), (0, 1), (0, 0), (0, 0)]
    assert pats[1].events() == ("1", "10")  # W2 = 01: e_{0,1} = 1, e_{1,2} = 10
    reduced = as_language(words, kind="delay", max_delay=2)
    assert len(reduced) == 6  # L^{E'} of Example 3
    assert [p.label for p in reduced] == ["00", "01", "10", "11", "20", "21"]  # first word of each class kept


def test_eq2_index_formula_matches_availability():
    for w in full_delay_language(4, 2):
        p = parse_delay_word(w)
        tau = [int(c) for c in w]
        for k in range(4):
            j = sum(2 ** l for l in range(k + 1) if tau[k - l] <= l)  # eq. (2)-(3)
            assert p.event_index(k) == j


def test_availability_is_nested_and_late_measurements_count():
    p = parse_delay_word("21210")
    assert p.arrivals == (2, 2, 4, 4, 4)
    assert p.available(1) == () and p.available(2) == (0, 1) and p.available(4) == (0, 1, 2, 3, 4)
    assert all(set(p.available(t)) <= set(p.available(t + 1)) for t in range(4))
    assert parse_delay_word("0002").arrivals == (0, 1, 2, None)  # i + τ(i) >= T: missing within the horizon


def test_missing_word_equals_delay_word_with_the_same_events():
    assert ArrivalPattern.from_missing_word("101111") == parse_delay_word("090000")
    assert parse_delay_word("01") == parse_delay_word("02")  # same event sequence for T = 2
    tree = PrefixTree(["01", "02", "00"], kind="delay")
    assert len(tree.patterns) == 2 and len(tree) == 3  # nodes: "1", "1.10", "1.11"


def test_worst_case_pattern_is_the_latest_arrival():
    assert worst_case_pattern(["1011", "1101"]).label == "1001"
    wc = worst_case_pattern([parse_delay_word("0100"), parse_delay_word("0010")])
    assert wc.arrivals == (0, 2, 3, 3)


@pytest.mark.parametrize("word,maxd,msg", [("0a1", None, "not digits"), ("031", 2, "above the maximum delay 2"),
                                           ("", None, "empty")])
def test_bad_delay_words(word, maxd, msg):
    with pytest.raises(InputError, match=msg):
        parse_delay_word(word, maxd)


def test_delay_language_of_mixed_lengths_is_rejected():
    with pytest.raises(InputError, match="mixed lengths"):
        as_language(["01", "012"], kind="delay")


def test_prefix_tree_counts_match_brute_force():
    words = full_delay_language(4, 2)
    tree = PrefixTree(words, kind="delay")
    pats = {parse_delay_word(w) for w in words}
    assert len(tree.patterns) == len(pats)
    for depth in range(1, 5):
        assert tree.nodes_per_depth()[depth - 1] == len({p.prefix(depth) for p in pats})
