"""The one arrival model (eqrec.arrivals.draws): traces and samplers.

Statistical tolerance: a frequency estimated from ``N`` draws is compared with
its probability within ``Z = 5`` standard errors (``sqrt(p (1 - p) / N)`` for
i.i.d. draws; for the Markov channel the standard error of the mean of a
two-state chain, ``sqrt(π (1 − π) / N · (1 + λ) / (1 − λ))`` with ``λ`` the
chain's second eigenvalue).  The draws are seeded, so a test either always
passes or always fails; ``Z = 5`` makes a wrong sampler fail and a right one
pass for all but about one seed in 1.7 million per comparison.
"""

import numpy as np
import pytest

from eqrec.arrivals.draws import (NEVER, ArrivalTrace, bernoulli_arrivals, bernoulli_trace,
                                 delay_trace, draw_delays, gilbert_elliott_trace, uniform_words)
from eqrec.arrivals.words import as_pattern, parse_delay_word
from eqrec.errors import InputError

Z = 5.0
N = 200_000


def _close(freq: float, p: float, n: int, inflation: float = 1.0) -> bool:
    se = np.sqrt(max(p * (1 - p), 1e-300) / n * inflation)
    return abs(freq - p) <= Z * se


# ---------------------------------------------------------------------------- the trace type

def test_trace_reads_per_step_and_per_measurement():
    tr = ArrivalTrace([0, 2, NEVER, 0, 3])
    assert tr.schedule() == [[0], [], [], [1, 3], []]  # y(4) arrives at 7 >= N: left out
    assert [tr.arriving_at(t) for t in range(5)] == tr.schedule()
    assert tr.lost.tolist() == [False, False, True, False, False]
    assert tr.on_time.tolist() == [True, False, False, True, False]
    assert tr.arrival_times().tolist() == [0, 3, NEVER, 3, 7]
    assert tr.pattern().arrivals == (0, 3, None, 3, None)
    assert ArrivalTrace.from_schedule(tr.schedule()).delays.tolist() == [0, 2, NEVER, 0, NEVER]
    assert ArrivalTrace(np.array([0, NEVER, 1, 0])).schedule() == [[0], [], [], [2, 3]]


def test_trace_of_a_pattern_gives_the_pattern_back():
    for p in (parse_delay_word("21210"), parse_delay_word("060000"), as_pattern("101111")):
        tr = ArrivalTrace.from_pattern(p)
        assert tr.pattern().arrivals == p.arrivals
        assert tr.schedule() == [list(p.arriving_at(t)) for t in range(p.T)]
    assert ArrivalTrace.from_arrived([True, False, True]).delays.tolist() == [0, NEVER, 0]


@pytest.mark.parametrize("bad", [[[0, 1]], [0, -2], ["a"], [0.5]])
def test_bad_delays_are_refused_naming_the_field(bad):
    with pytest.raises(InputError) as exc:
        ArrivalTrace(bad)
    assert exc.value.field == "delays"


def test_bad_schedule_is_refused():
    with pytest.raises(InputError, match="twice"):
        ArrivalTrace.from_schedule([[0], [0]])
    with pytest.raises(InputError, match="0..t"):
        ArrivalTrace.from_schedule([[1], []])


def test_trace_is_read_only():
    tr = ArrivalTrace([0, 1])
    with pytest.raises(ValueError):
        tr.delays[0] = 3


# ---------------------------------------------------------------------------- samplers: frequencies

def test_uniform_words_frequencies():
    words = ["a", "b", "c", "d", "e"]
    draws = uniform_words(np.random.default_rng(1), words, size=N)
    for w in words:
        assert _close(draws.count(w) / N, 1 / len(words), N), w
    one = uniform_words(np.random.default_rng(1), words)
    assert one == draws[0]  # one word per call: the draw of a Monte Carlo run


@pytest.mark.parametrize("loss", [0.0, 0.1, 0.3, 1.0])
def test_bernoulli_loss_frequency(loss):
    tr = bernoulli_trace(np.random.default_rng(2), N, loss)
    assert set(tr.delays.tolist()) <= {0, NEVER}
    assert _close(tr.lost.mean(), loss, N)


def test_bernoulli_arrivals_are_the_lmv_eta():
    eta = bernoulli_arrivals(np.random.default_rng(3), (4, N // 4), 0.8)
    assert eta.shape == (4, N // 4) and eta.dtype == bool
    assert _close(eta.mean(), 0.8, N)
    # the same draw as the P4 Monte Carlo has always made
    assert np.array_equal(eta, np.random.default_rng(3).random((4, N // 4)) < 0.8)


def test_delay_distribution_frequencies():
    p = np.array([0.5, 0.2, 0.1, 0.05])  # lost with 0.15
    tr = delay_trace(np.random.default_rng(4), N, p)
    d = tr.delays
    for k, pk in enumerate(p):
        assert _close(np.mean(d == k), pk, N), k
    assert _close(np.mean(d == NEVER), 1 - p.sum(), N)


def test_switching_delays_law_and_draw_order():
    d = draw_delays(np.random.default_rng(5), N, 2, 0.7)
    assert _close(np.mean(d == 0), 0.7, N)
    for k in (1, 2):
        assert _close(np.mean(d == k), 0.15, N)
    rng = np.random.default_rng(5)  # the stored results' order: one random() per step, then the late delays
    late = rng.random(N) >= 0.7
    assert np.array_equal(d[late], rng.integers(1, 3, size=int(late.sum())))


@pytest.mark.parametrize("pgb, pbg", [(0.05, 0.25), (0.2, 0.5)])
def test_gilbert_elliott_loss_rate_and_burst_length(pgb, pbg):
    tr = gilbert_elliott_trace(np.random.default_rng(6), N, pgb, pbg)  # Gilbert: lost exactly in the bad state
    lost = tr.lost
    pi_bad = pgb / (pgb + pbg)
    lam = 1 - pgb - pbg
    assert _close(lost.mean(), pi_bad, N, inflation=(1 + lam) / (1 - lam))
    # bursts: lengths of runs of losses are geometric with mean 1/pbg
    edges = np.flatnonzero(np.diff(np.concatenate([[0], lost.astype(int), [0]])))
    lengths = edges[1::2] - edges[::2]
    se = np.sqrt((1 - pbg) / pbg ** 2 / lengths.size)
    assert abs(lengths.mean() - 1 / pbg) <= Z * se
    # a loss is followed by a loss with probability 1 - pbg (not the i.i.d. pi_bad)
    after = lost[1:][lost[:-1]]
    assert _close(after.mean(), 1 - pbg, after.size)


def test_gilbert_elliott_with_loss_in_both_states():
    pgb, pbg, lg, lb = 0.1, 0.3, 0.05, 0.6
    tr = gilbert_elliott_trace(np.random.default_rng(7), N, pgb, pbg, loss_good=lg, loss_bad=lb)
    pi_bad = pgb / (pgb + pbg)
    rate = (1 - pi_bad) * lg + pi_bad * lb
    lam = 1 - pgb - pbg
    assert _close(tr.lost.mean(), rate, N, inflation=(1 + lam) / (1 - lam))
    start_bad = gilbert_elliott_trace(np.random.default_rng(7), 50, 0.0, 0.0, start="bad")
    assert start_bad.lost.all()


# ---------------------------------------------------------------------------- determinism and bad input

@pytest.mark.parametrize("draw", [
    lambda rng: uniform_words(rng, ["0", "1", "2"], size=200),
    lambda rng: bernoulli_trace(rng, 200, 0.3).delays.tolist(),
    lambda rng: delay_trace(rng, 200, [0.6, 0.3]).delays.tolist(),
    lambda rng: draw_delays(rng, 200, 2, 0.5).tolist(),
    lambda rng: gilbert_elliott_trace(rng, 200, 0.1, 0.3).delays.tolist(),
])
def test_the_seed_determines_the_trace(draw):
    a, b = draw(np.random.default_rng(42)), draw(np.random.default_rng(42))
    c = draw(np.random.default_rng(43))
    assert a == b
    assert a != c


@pytest.mark.parametrize("call, field", [
    (lambda rng: bernoulli_trace(rng, 10, 1.5), "loss"),
    (lambda rng: bernoulli_trace(rng, 10, float("nan")), "loss"),
    (lambda rng: bernoulli_trace(rng, -1, 0.1), "steps"),
    (lambda rng: bernoulli_arrivals(rng, 3, "x"), "arrival"),
    (lambda rng: delay_trace(rng, 10, [0.7, 0.5]), "probabilities"),
    (lambda rng: delay_trace(rng, 10, [0.5, float("inf")]), "probabilities"),
    (lambda rng: draw_delays(rng, 10, 0, 0.5), "max_delay"),
    (lambda rng: gilbert_elliott_trace(rng, 10, 0.1, -0.1), "p_bad_to_good"),
    (lambda rng: gilbert_elliott_trace(rng, 10, 0.1, 0.1, start="odd"), "start"),
    (lambda rng: uniform_words(rng, []), "words"),
])
def test_bad_sampler_input_names_the_field(call, field):
    with pytest.raises(InputError) as exc:
        call(np.random.default_rng(0))
    assert exc.value.field == field


# ---------------------------------------------------------------------------- what reaches an estimator

def test_as_packets_reads_every_form_of_the_protocol():
    from eqrec.estimators.causal import Packet
    from eqrec.arrivals.packets import as_packets

    assert as_packets(None, 3, (2,)) == [] and as_packets([], 3, (2,)) == []
    for y in (np.array([1.0, 2.0]), [1.0, 2.0]):
        (pk,) = as_packets(y, 3, (2,))
        assert pk.time == 3 and pk.y.tolist() == [1.0, 2.0]
    pks = as_packets([Packet(1, np.zeros(2)), (2, [1.0, 1.0])], 3, (2,))
    assert [p.time for p in pks] == [1, 2]
    assert as_packets((0, np.ones(2)), 3, (2,))[0].time == 0
    assert as_packets(np.ones((2, 4)), 3, (2, 4))[0].y.shape == (2, 4)  # columns of an affine run


@pytest.mark.parametrize("y", [np.array([1.0, np.inf]), np.zeros(3), [(4, np.zeros(2))],
                               [(1, np.zeros(2)), (1, np.zeros(2))], [(1.5, np.zeros(2))], {"a": 1}, ["a", "b"]])
def test_as_packets_refuses_bad_data_naming_the_field(y):
    from eqrec.arrivals.packets import as_packets

    with pytest.raises(InputError) as exc:
        as_packets(y, 3, (2,), field="y")
    assert exc.value.field == "y"
