"""The classes of the full delay language {0..D}^T built in time and memory linear in T (issue 41 §2): the same
classes, in the same order, with the same weights, node counts and counts as the previous construction (kept here
verbatim as the reference), whose data were tuples and weights integers built per class (quadratic in T)."""
import pickle
from itertools import combinations
from math import prod

import pytest

from eqrec.bounds.data_classes import (ClassSet, DataClass, WindowData, classes_of_full_language,
                                       full_language_counts)
from eqrec.design.delay.languages import delay_classes
from eqrec.design.inputs import ESTIMATE_PRINT_SECONDS, class_shape


# --- the previous construction (src/eqrec/bounds/data_classes.py at commit 3d6680f), the reference -------------

def _arrival_values(i, T, max_delay):
    return min(max_delay, T - 1 - i) + 1 + (1 if i + max_delay >= T else 0)


def _arrived_by(i, k, max_delay):
    return min(max_delay, k - i) + 1


def old_counts(T, D):
    sequences = prod(_arrival_values(i, T, D) for i in range(T))
    nodes, old_power = 0, 1
    for d in range(1, T + 1):
        n_old = max(0, d - D)
        if n_old:
            old_power *= D + 1
        nodes += old_power * prod(_arrived_by(i, d - 1, D) + 1 for i in range(n_old, d))
    return {"words": (D + 1) ** T, "sequences": sequences, "nodes": nodes}


def old_classes(T, D):
    """(depth, data tuple, terminal, inner, weight, nodes) of every class, in the previous order."""
    tail = [1] * (T + 1)
    for i in range(T - 1, -1, -1):
        tail[i] = tail[i + 1] * _arrival_values(i, T, D)
    classes = []
    old_power, n_old = 1, 0
    times = tuple(range(T))
    for d in range(1, T + 1):
        k = d - 1
        if k - D + 1 > n_old:
            n_old, old_power = n_old + 1, old_power * (D + 1)
        always = times[:n_old]
        window = times[n_old:k + 1]
        inner = d < T
        by_k = {i: _arrived_by(i, k, D) for i in window}
        not_yet = {i: _arrival_values(i, T, D) - by_k[i] for i in window}
        for r in range(len(window) + 1):
            for chosen in combinations(window, r):
                S = always + chosen
                s = set(chosen)
                nodes = old_power * prod(by_k[i] for i in chosen)
                weight = 0
                if inner:
                    weight = tail[d] * old_power * prod(by_k[i] if i in s else not_yet[i] for i in window)
                classes.append((d, S, not inner, inner, weight, nodes))
    return classes


def fields(c):
    return c.depth, tuple(c.available), c.terminal, c.inner, c.weight, c.nodes


CASES = [(T, D) for D in range(0, 6) for T in (1, 2, 3, 4, 5, 6, 7, 9, 12, 17, 25)] + [(60, 2), (40, 4), (33, 9)]


@pytest.mark.parametrize("T,D", CASES)
def test_the_same_classes_as_the_previous_construction(T, D):
    new = classes_of_full_language(T, D)
    reference = old_classes(T, D)
    assert [fields(c) for c in new] == reference  # same classes, same order, same weights and node counts
    assert full_language_counts(T, D) == old_counts(T, D)
    assert (new.words, new.sequences, new.nodes) == tuple(old_counts(T, D).values())
    assert [fields(c) for c in classes_of_full_language(T, D, 0)] == reference  # m = 0: the same classes


@pytest.mark.parametrize("T,D", [(9, 2), (17, 3), (25, 1)])
def test_window_classes_read_as_tuples(T, D):
    """Equal to (and hashed as) DataClass of tuples: as dict keys, in ClassSet.index, labels, pickling, slicing."""
    new = classes_of_full_language(T, D)
    plain = [DataClass(*f) for f in old_classes(T, D)]
    assert list(new) == plain and plain == list(new)
    assert [hash(c) for c in new] == [hash(c) for c in plain]
    assert [c.label for c in new] == [c.label for c in plain]
    assert [hash(c.key) for c in new] == [hash(c.key) for c in plain]
    tuples = ClassSet(classes=tuple(plain), horizon=T, words=new.words, sequences=new.sequences, nodes=new.nodes,
                      source="window")
    for i, c in enumerate(plain):
        assert new.index(c.depth, reversed(c.available)) == i == tuples.index(c.depth, c.available)
        S = c.available
        view = new.classes[i].available
        assert isinstance(view, WindowData) and view == S and S == view and len(view) == len(S)
        assert [view[j] for j in range(-len(S), len(S))] == list(S) + list(S)
        assert view[1:-1] == S[1:-1] and repr(view) == repr(S)
        assert all((t in view) == (t in S) for t in range(-1, T + 1)) and (0.5 in view) is False
        with pytest.raises(IndexError):
            view[len(S)]
    assert pickle.loads(pickle.dumps(new)).classes == new.classes
    assert [fields(c) for c in pickle.loads(pickle.dumps(new))] == [fields(c) for c in plain]
    assert sorted(new, key=lambda c: (c.depth, len(c.available), c.available)) == plain  # ClassSet order


def _sequences_with_data(T, D, d, S):
    """Sequences of {0..D}^T whose data at d - 1 is S, one measurement at a time (independent outcomes)."""
    total = 1
    for i in range(T):
        values = _arrival_values(i, T, D)
        if i >= d:
            total *= values
        elif i in S:
            total *= _arrived_by(i, d - 1, D)
        else:
            total *= values - _arrived_by(i, d - 1, D)
    return total


def test_a_long_horizon_holds_no_long_tuple():
    """At (2, 20000) (80,000 classes; as tuples 8e8 data entries) every class holds its window only, and the
    weights expanded when read are the sequences through the class, counted one measurement at a time."""
    T, D = 20_000, 2
    classes = classes_of_full_language(T, D)
    assert len(classes) == 4 * T - 2
    assert all(isinstance(c.available, WindowData) and len(c.available.chosen) <= D for c in classes)
    stored = lambda c: (c.depth, c._old, *c._weight_power, *c._node_power)  # noqa: E731
    assert all(v.bit_length() < 64 for c in classes for v in stored(c))  # no O(T)-bit integer held
    assert not hasattr(classes.classes[0], "__dict__")
    for i in (0, 1, 5, len(classes) // 2, len(classes) - 5, len(classes) - 1):
        c = classes.classes[i]
        S = set(c.available)
        assert c.weight == (_sequences_with_data(T, D, c.depth, S) if c.inner else 0)
        assert c.nodes == (D + 1) ** c.available.old * prod(_arrived_by(j, c.depth - 1, D)
                                                              for j in c.available.chosen)


def test_the_size_model_is_linear_for_window_classes():
    """The build estimate is per class (no Σ|S| term): {0..1}^100000 builds unannounced (a few seconds),
    {0..1}^(10^8) is refused; the loss-aware language keeps its per-entry model."""
    seconds, memory = class_shape(1, 100_000).build_cost(100_000, 1)
    assert seconds < ESTIMATE_PRINT_SECONDS and memory < 1e9
    big_s, big_m = class_shape(1, 10**6).build_cost(10**6, 1)
    assert big_s == pytest.approx(10 * seconds, rel=1e-6) and big_m - 2e8 == pytest.approx(10 * (memory - 2e8))
    lossy = class_shape(1, 1000, 1)
    assert not lossy.windows and lossy.build_cost(1000, 1)[0] > lossy.classes * 2e-5
    from eqrec.errors import InputError

    with pytest.raises(InputError, match="refused"):
        delay_classes(max_delay=1, horizon=10**8)


def test_a_full_language_past_64_letters():
    """{0}^80 is one word (numpy.indices took at most 64 dimensions: a raw ValueError in eqrec design
    --max-delay 0 --horizon 80); the order of the words is unchanged (the first delay varies slowest)."""
    from eqrec.arrivals.words import full_delay_language

    assert full_delay_language(80, 0) == ("0" * 80,)
    assert full_delay_language(3, 1) == ("000", "001", "010", "011", "100", "101", "110", "111")
    assert len(full_delay_language(70, 0)) == 1 and len(full_delay_language(5, 3)) == 4 ** 5


# --- issue 41 §2: messages quote a 1,000-character label by its ends and its length ----------------------------

def _short(message: str, label: str) -> None:
    assert label not in message and len(message) < 600, message
    assert "…" in message and f"({len(label)} characters)" in message


def test_long_class_labels_and_words_are_shortened_in_messages():
    from eqrec.arrivals.patterns import ArrivalPattern
    from eqrec.arrivals.prefix_tree import PrefixTree
    from eqrec.arrivals.words import as_language, parse_delay_word
    from eqrec.errors import InputError

    T = 1000
    classes = classes_of_full_language(T, 1)
    with pytest.raises(InputError) as exc:  # no such class: the data list (4,000 characters) is shortened
        classes.index(T, range(0, T, 2))
    _short(str(exc.value), str(list(range(0, T, 2))))
    word = "0" * 999 + "7"
    with pytest.raises(InputError) as exc:
        parse_delay_word(word, max_delay=1)
    _short(str(exc.value), repr(word))
    with pytest.raises(InputError) as exc:
        parse_delay_word("0" * 999 + "a")
    _short(str(exc.value), repr("0" * 999 + "a"))
    with pytest.raises(InputError) as exc:  # mixed lengths: the list of labels is shortened
        as_language(["0" * 1000, "0" * 999], kind="delay")
    assert "mixed lengths" in str(exc.value) and len(str(exc.value)) < 600
    with pytest.raises(InputError) as exc:  # the two readings of 0/1 words: each word shortened
        as_language(["1" * 1000])
    assert "1" * 200 not in str(exc.value) and "(1000 characters)" in str(exc.value)
    tree = PrefixTree([ArrivalPattern(tuple(range(T)), "1" * T)])
    with pytest.raises(InputError) as exc:
        tree.node(ArrivalPattern((None,) * T, "0" * T))
    _short(str(exc.value), "0" * T)
    pattern = ArrivalPattern(tuple(range(T)), "1" * T)
    with pytest.raises(InputError) as exc:
        pattern.extend(3)
    _short(str(exc.value), "1" * T)


def test_class_sets_and_classes_print_at_any_horizon():
    """repr of a long horizon's class set and classes: their counts have more digits than Python prints (raw
    ValueError before), so they are shown by order of magnitude; a short one prints its counts in full."""
    from eqrec.design.delay.languages import delay_classes

    long = delay_classes(max_delay=1, horizon=20000)
    text = repr(long)
    assert text.startswith(f"ClassSet({len(long)} classes, horizon=20000, words=~1e") and len(text) < 300
    inner = repr(next(c for c in reversed(long.classes) if c.inner and c.depth > 10000))
    assert "weight=~1e" in inner and "nodes=~1e" in inner and len(inner) < 300
    short = delay_classes(max_delay=1, horizon=3)
    assert f"words={short.words}," in repr(short) and f"weight={short.classes[0].weight}," in repr(short.classes[0])
