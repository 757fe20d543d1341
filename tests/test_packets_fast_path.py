"""The packet intake's fast path (issue 40 §3) reads exactly what the general reader reads: the same arrays (values,
sign of zero, memory order, a new array), and every value the general checks refuse is refused with their message."""
import numpy as np
import pytest

import eqrec.arrivals.packets as packets
from eqrec.arrivals.packets import Packet, as_packets, check_input
from eqrec.errors import InputError


def _general(y, now, shape):
    """The general reader alone (the fast path switched off)."""
    real = packets._plain_measurement
    packets._plain_measurement = lambda value, shape: None
    try:
        return as_packets(y, now, shape)
    finally:
        packets._plain_measurement = real


def _same(a, b):
    assert [p.time for p in a] == [p.time for p in b]
    for p, q in zip(a, b):
        assert p.y.dtype == q.y.dtype and p.y.shape == q.y.shape
        assert np.array_equal(p.y, q.y) and np.array_equal(np.signbit(p.y), np.signbit(q.y))
        assert p.y.flags.c_contiguous == q.y.flags.c_contiguous and p.y.flags.f_contiguous == q.y.flags.f_contiguous


@pytest.mark.parametrize("y", [np.array([0.5, -0.0]), np.array([1e150, -1e150]), np.arange(6.0)[::3],
                               [Packet(3, np.array([1.0, 2.0])), Packet(5, np.array([-0.0, 4.0]))],
                               [Packet(4, np.array([1.0, 2.0])), (5, np.array([3.0, 4.0]))],
                               np.array([1, 2]), [1.0, 2.0]])
def test_fast_path_reads_what_the_general_reader_reads(y):
    fast, slow = as_packets(y, 5, (2,)), _general(y, 5, (2,))
    _same(fast, slow)
    for pk in fast:  # a new array, never the caller's
        assert not any(np.shares_memory(pk.y, getattr(item, "y", item)) for item in (y if isinstance(y, list) else [y])
                       if isinstance(getattr(item, "y", item), np.ndarray))


def test_fast_path_keeps_the_memory_order_of_an_affine_run():
    y = np.asfortranarray(np.arange(6.0).reshape(2, 3))
    _same(as_packets(y, 1, (2, 3)), _general(y, 1, (2, 3)))


@pytest.mark.parametrize("bad,words", [(np.array([np.nan, 1.0]), "NaN or infinite"),
                                       (np.array([np.inf, 1.0]), "NaN or infinite"),
                                       (np.array([1e151, 1.0]), "above 1e+150"),
                                       (np.array([1.0, 2.0, 3.0]), "expected p = 2"),
                                       ([Packet(5, np.array([np.nan, 1.0]))], "NaN or infinite"),
                                       ([Packet(6, np.array([1.0, 1.0]))], "from the future")])
def test_refused_values_keep_the_general_message(bad, words):
    with pytest.raises(InputError) as fast:
        as_packets(bad, 5, (2,))
    with pytest.raises(InputError) as slow:
        _general(bad, 5, (2,))
    assert str(fast.value) == str(slow.value) and words in str(fast.value)


def test_input_fast_path():
    u = np.array([0.25, -0.0])
    got = check_input(u, 2)
    assert np.array_equal(got, u) and np.signbit(got[1]) and not np.shares_memory(got, u)
    for bad, words in ((np.array([np.nan, 0.0]), "NaN"), (np.array([1e200, 0.0]), "above"),
                       (np.array([[1.0], [2.0]]), "flat vector"), (np.array([1.0]), "expected m = 2")):
        with pytest.raises(InputError, match=words):
            check_input(bad, 2)
