import pytest

from eqrec.errors import InputError
from eqrec.core.patterns import PrefixTree, extend_word, prefixes, validate_language, worst_case_word


def test_worst_case_word_examples_of_the_papers(L1_words):
    assert worst_case_word(L1_words) == "100001"  # prefix-based paper, Sec. VI
    assert worst_case_word(["1011", "1101"]) == "1001"  # prefix-based paper, Sec. III
    assert worst_case_word(["101111", "110111"]) == "100111"  # augmented paper, Sec. IV-B


def test_prefix_tree_of_the_paper_example():
    # Sec. III: gains needed for prefixes {1, 10, 11, 101, 110, 1011, 1101}
    tree = PrefixTree(["1011", "1101"])
    assert {n.prefix for n in tree} == {"1", "10", "11", "101", "110", "1011", "1101"}
    assert [n.prefix for n in tree.path("1101")] == ["1", "11", "110", "1101"]
    assert all(tree.nodes[n.parent].prefix == n.prefix[:-1] for n in tree if n.parent is not None)
    assert [n.prefix for n in tree if n.terminal] == ["1011", "1101"]


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
