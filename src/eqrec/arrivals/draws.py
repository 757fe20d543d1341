r"""The one arrival model: traces of packet arrivals (:mod:`eqrec.arrivals.traces`) and the samplers that draw them.

An :class:`~eqrec.arrivals.traces.ArrivalTrace` says, for a run of ``N`` steps, when each
measurement ``y(τ)`` reaches the estimator: its delay ``d(τ)`` (arrival at
``τ + d(τ)``) or :data:`NEVER` when it is lost.  Read per step,
:meth:`ArrivalTrace.arriving_at` is the list of time stamps arriving at
``t`` (the ``arrive[t]`` every simulation loop builds packets from,
:func:`eqrec.simulate.loop.closed_loop`).

Every random arrival of the package is drawn here, from a
:class:`numpy.random.Generator` (the same seed gives the same trace):

* :func:`uniform_words` — words drawn uniformly from a language (one per run
  of a Monte Carlo, one per period of a long run);
* :func:`bernoulli_arrivals` / :func:`bernoulli_trace` — i.i.d. arrivals,
  a packet lost with probability ``loss`` (the Bernoulli ``η(t)`` of the LMV
  study arrives with probability ``η̄ = 1 − loss``);
* :func:`delay_trace` — i.i.d. delays with probabilities ``p_0 .. p_D``
  (lost with the remaining probability ``1 − Σ p_d``);
* :func:`draw_delays` — the i.i.d. delays of the switching runs of the
  delayed-data paper (on time with probability ``p_on_time``, else uniform on
  ``1..τ̄``), with the draw order of the stored results;
* :func:`gilbert_elliott_trace` — bursts: a two-state (good/bad) Markov
  channel with its own loss probability in each state (Gilbert–Elliott).

And the block law of the comparison's trace model (losses independent or in
Gilbert bursts, delays uniform ``0..D``, :func:`eqrec.compare.families.draw_trace`):
:func:`block_loss_probabilities` (the law of the number of losses in a block of
``T`` measurements) and :func:`loss_coverage` (the smallest loss budget ``m`` of
the loss-aware language :func:`eqrec.delay_classes` whose block probability
reaches a coverage).
"""

from __future__ import annotations

from typing import Sequence, TypeVar

import numpy as np

from eqrec.checks import generator, integer
from eqrec.arrivals.traces import NEVER, ArrivalTrace  # noqa: F401  (the trace type, re-exported with its samplers)
from eqrec.errors import InputError

W = TypeVar("W")


def _probability(value: float, field: str) -> float:
    try:
        p = float(value)
    except (TypeError, ValueError):
        raise InputError(f"a probability must be a number, got {value!r}", field=field) from None
    if not (0.0 <= p <= 1.0):  # also refuses NaN
        raise InputError(f"a probability must lie in [0, 1], got {p}", field=field)
    return p


def _steps(value: int, field: str = "steps") -> int:
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, np.integer)) or value < 0:
        raise InputError(f"the number of steps must be a non-negative integer, got {value!r}", field=field)
    return int(value)


# ------------------------------------------------------------------------------ samplers

def uniform_words(rng: np.random.Generator, words: Sequence[W], size: int | None = None) -> "W | list[W]":
    """Words drawn uniformly and independently from a language.

    One call ``rng.integers(len(words), size=size)``: ``size=None`` draws one
    word (one Monte Carlo run), an integer a list of them (one per period of a
    long run).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    words : sequence
        The language (words, patterns or anything to pick from); not empty.
    size : int or None, optional
        Number of words (``None``: one word, not a list).

    Returns
    -------
    object or list
        ``words[i]`` for a uniform ``i``, or a list of ``size`` of them.

    Examples
    --------
    >>> import numpy as np
    >>> from eqrec.arrivals.draws import uniform_words
    >>> uniform_words(np.random.default_rng(0), ["101", "110", "111"], size=4)
    ['111', '110', '110', '101']
    """
    if not hasattr(words, "__len__") or isinstance(words, str) or len(words) == 0:
        raise InputError(f"need a non-empty sequence of words to draw from, got {words!r:.60}", field="words")
    if size is None:
        return words[generator(rng).integers(len(words))]
    idx = generator(rng).integers(len(words), size=_steps(size, "size"))
    return [words[i] for i in idx]


def bernoulli_arrivals(rng: np.random.Generator, shape: "int | tuple[int, ...]", arrival: float) -> np.ndarray:
    """I.i.d. arrival indicators ``η = (U < η̄)`` with ``U`` uniform on ``[0, 1)``: one ``rng.random(shape)``.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    shape : int or tuple of int
        Shape of the draws (e.g. ``(runs, T+1)``).
    arrival : float
        Arrival probability ``η̄`` in ``[0, 1]``.

    Returns
    -------
    ndarray of bool
        ``True`` where the packet arrives.
    """
    p = _probability(arrival, "arrival")
    for size in shape if isinstance(shape, tuple) else (shape,):  # non-negative integers
        _steps(size, "shape")
    return generator(rng).random(shape) < p


def bernoulli_trace(rng: np.random.Generator, steps: int, loss: float) -> ArrivalTrace:
    """Bernoulli losses: each packet on time, or lost with probability ``loss``, independently.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    steps : int
        Number ``N`` of measurements.
    loss : float
        Loss probability in ``[0, 1]``.

    Returns
    -------
    ArrivalTrace
        Delays ``0`` or :data:`NEVER`.
    """
    p = _probability(loss, "loss")
    return ArrivalTrace.from_arrived(bernoulli_arrivals(rng, _steps(steps), 1.0 - p))


def delay_trace(rng: np.random.Generator, steps: int, probabilities: "Sequence[float] | np.ndarray") -> ArrivalTrace:
    """I.i.d. delays: ``d`` with probability ``p_d`` (``d = 0..D``), lost with probability ``1 − Σ p_d``.

    One uniform draw per measurement, read through the cumulative probabilities.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    steps : int
        Number ``N`` of measurements.
    probabilities : sequence of float
        ``p_0 .. p_D``, each in ``[0, 1]``, with sum at most 1 (up to ``1e-12``).

    Returns
    -------
    ArrivalTrace
        Delays in ``0..D`` or :data:`NEVER`.
    """
    try:
        p = np.asarray(probabilities, float)
    except (TypeError, ValueError):
        raise InputError(f"delay probabilities must be numbers, got {probabilities!r}", field="probabilities") from None
    if p.ndim != 1 or p.size == 0 or not np.all(np.isfinite(p)) or np.any(p < 0) or np.any(p > 1):
        raise InputError(f"need delay probabilities p_0..p_D in [0, 1], got {p.tolist()}", field="probabilities")
    if p.sum() > 1.0 + 1e-12:
        raise InputError(f"delay probabilities sum to {p.sum()} > 1", field="probabilities")
    u = generator(rng).random(_steps(steps))
    d = np.searchsorted(np.cumsum(p), u, side="right")
    return ArrivalTrace(np.where(d >= p.size, NEVER, d).astype(np.int64))


def draw_delays(rng: np.random.Generator, steps: int, max_delay: int, p_on_time: float) -> np.ndarray:
    """I.i.d. delays: ``0`` with probability ``p_on_time``, else uniform on ``1..max_delay``.

    The delays of the switching runs of the delayed-data paper (Section
    III-B3; :func:`eqrec.simulate.long_runs.long_run_switching`): first one
    ``rng.random(steps)`` (late where ``>= p_on_time``), then one
    ``rng.integers`` for the late ones.  The same law as :func:`delay_trace`
    with ``p_0 = p_on_time``, ``p_d = (1 − p_on_time)/τ̄``, drawn in another
    order (the order of the stored results).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    steps : int
        Number ``N`` of delays.
    max_delay : int
        Largest delay ``τ̄ >= 1``.
    p_on_time : float
        Probability of delay ``0``.

    Returns
    -------
    ndarray of int, shape (N,)
        The delays.
    """
    p = _probability(p_on_time, "p_on_time")
    if isinstance(max_delay, bool) or not isinstance(max_delay, (int, np.integer)) or max_delay < 1:
        raise InputError(f"the largest delay must be an integer >= 1, got {max_delay!r}", field="max_delay")
    late = generator(rng).random(_steps(steps)) >= p
    d = np.zeros(steps, int)
    d[late] = rng.integers(1, max_delay + 1, size=int(late.sum()))
    return d


def gilbert_elliott_trace(rng: np.random.Generator, steps: int, p_good_to_bad: float, p_bad_to_good: float,
                          loss_good: float = 0.0, loss_bad: float = 1.0, start: str = "stationary") -> ArrivalTrace:
    r"""Bursts of losses: the Gilbert–Elliott channel, a two-state Markov chain with a loss probability per state.

    The channel is *good* or *bad*; from one step to the next it goes from
    good to bad with probability ``p_good_to_bad`` and back with
    ``p_bad_to_good``; in each state a packet is lost with that state's
    probability.  In the stationary regime the channel is bad with
    probability :math:`\pi_b = p_{gb} / (p_{gb} + p_{bg})`, the loss rate is
    :math:`(1 - \pi_b)\,\ell_g + \pi_b\,\ell_b`, and a stay in the bad state
    lasts :math:`1 / p_{bg}` steps on average (Gilbert's model:
    ``loss_good = 0``, ``loss_bad = 1``).  Draws, in order: the initial state
    (one ``rng.random()`` for ``start="stationary"``), the ``N`` transitions,
    the ``N`` losses.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    steps : int
        Number ``N`` of measurements.
    p_good_to_bad : float
        Probability of a transition good → bad.
    p_bad_to_good : float
        Probability of a transition bad → good.
    loss_good : float, optional
        Loss probability in the good state (default 0).
    loss_bad : float, optional
        Loss probability in the bad state (default 1).
    start : {"stationary", "good", "bad"}, optional
        Initial state: drawn from the stationary law (default; good when both
        transition probabilities are 0), or fixed.

    Returns
    -------
    ArrivalTrace
        Delays ``0`` or :data:`NEVER`.
    """
    pgb, pbg = _probability(p_good_to_bad, "p_good_to_bad"), _probability(p_bad_to_good, "p_bad_to_good")
    lg, lb = _probability(loss_good, "loss_good"), _probability(loss_bad, "loss_bad")
    N, rng = _steps(steps), generator(rng)
    if start == "stationary":
        pi_bad = pgb / (pgb + pbg) if pgb + pbg > 0 else 0.0
        bad = bool(rng.random() < pi_bad)
    elif start in ("good", "bad"):
        bad = start == "bad"
    else:
        raise InputError(f"start must be 'stationary', 'good' or 'bad', got {start!r}", field="start")
    u_move, u_loss = rng.random(N), rng.random(N)
    lost = np.zeros(N, bool)
    for t in range(N):
        lost[t] = u_loss[t] < (lb if bad else lg)
        bad = (u_move[t] >= pbg) if bad else (u_move[t] < pgb)
    return ArrivalTrace.from_arrived(~lost)


def with_uniform_delays(rng: np.random.Generator, trace: ArrivalTrace, max_delay: int) -> ArrivalTrace:
    """The same losses, each packet that is not lost delayed by ``d`` uniform on ``0..max_delay``.

    One ``rng.integers`` draw per measurement (lost ones included, so the draws
    do not depend on the losses).

    Parameters
    ----------
    rng : numpy.random.Generator
        Random source.
    trace : ArrivalTrace
        The losses (its delays other than :data:`NEVER` are replaced).
    max_delay : int
        Largest delay ``D >= 0``.

    Returns
    -------
    ArrivalTrace
        Delays in ``0..D`` or :data:`NEVER`.

    Raises
    ------
    InputError
        A negative or non-integer ``max_delay``.
    """
    if isinstance(max_delay, bool) or not isinstance(max_delay, (int, np.integer)) or max_delay < 0:
        raise InputError(f"the largest delay must be an integer >= 0, got {max_delay!r}", field="max_delay")
    delays = rng.integers(0, int(max_delay) + 1, trace.steps)
    return ArrivalTrace(np.where(trace.lost, NEVER, delays))


# ------------------------------------------------------------------------------ the block law of the trace model

def _gilbert_rates(loss: float, burst: float) -> tuple[float, float]:
    """``(p_gb, p_bg)`` of the Gilbert channel with stationary loss ``loss`` and mean burst ``burst`` (as drawn)."""
    if loss >= 1.0:
        raise InputError(f"a Gilbert channel needs a loss below 1, got {loss}", field="loss")
    try:
        b = float(burst)
    except (TypeError, ValueError):
        raise InputError(f"the mean burst length must be a number, got {burst!r}", field="burst") from None
    if not (np.isfinite(b) and b >= 1.0):
        raise InputError(f"the mean burst length must be a number >= 1 (steps), got {burst!r}", field="burst")
    p_bg = 1.0 / b
    p_gb = loss * p_bg / (1.0 - loss)
    if p_gb > 1.0:
        raise InputError(f"a mean burst of {b} steps cannot give an average loss of {loss} (the channel would have "
                         "to enter a burst with probability > 1)", field="burst")
    return p_gb, p_bg


def block_loss_probabilities(horizon: int, loss: float, burst: float | None = None) -> np.ndarray:
    r"""The law of the number of measurements lost in a block of ``T`` under the comparison's trace model.

    Independent losses (``burst=None``): binomial,
    :math:`P(j) = \binom{T}{j}\,\ell^j (1-\ell)^{T-j}`.  Gilbert bursts: the
    channel of :func:`gilbert_elliott_trace` (every packet lost in the bad
    state, none in the good one) with ``p_bg = 1/burst`` and
    ``p_gb = ℓ p_bg / (1 − ℓ)``, so the stationary loss is ``ℓ`` (the
    parameters of :func:`eqrec.compare.families.draw_trace`).  The trace
    starts in the stationary law, so every block does; the law is computed
    exactly by a dynamic programme over the block on (channel state, losses
    so far), started from the stationary distribution.  The delays of the
    packets kept do not count: a delay is never a loss.

    Parameters
    ----------
    horizon : int
        ``T``, the measurements of a block, at least 1.
    loss : float
        Average loss probability ``ℓ`` in ``[0, 1]`` (below 1 with ``burst``).
    burst : float or None, optional
        Mean length of a burst of losses, ``>= 1`` (``None``: independent losses).

    Returns
    -------
    ndarray, shape (T + 1,)
        ``P(j lost)`` for ``j = 0..T`` (sums to 1 up to rounding).

    Raises
    ------
    InputError
        ``horizon`` not an integer >= 1, ``loss`` not a probability, or a ``burst`` that is not a number
        >= 1 or cannot give the loss (the field is named).

    Examples
    --------
    >>> import numpy as np
    >>> from eqrec.arrivals.draws import block_loss_probabilities
    >>> np.round(block_loss_probabilities(3, 0.5), 3)
    array([0.125, 0.375, 0.375, 0.125])
    """
    T = _steps(horizon, "horizon")
    if T < 1:
        raise InputError(f"the horizon must be an integer >= 1, got {horizon!r}", field="horizon")
    p = _probability(loss, "loss")
    if burst is None:
        # one measurement at a time: j lost among the first t, then lost or not
        law = np.zeros(T + 1)
        law[0] = 1.0
        for t in range(T):
            law[1:t + 2] = law[1:t + 2] * (1.0 - p) + law[:t + 1] * p
            law[0] *= 1.0 - p
        return law
    p_gb, p_bg = _gilbert_rates(p, burst)
    pi_bad = p_gb / (p_gb + p_bg) if p_gb + p_bg > 0 else 0.0
    good, bad = np.zeros(T + 1), np.zeros(T + 1)  # P(state at t, j lost among 0..t-1)
    good[0], bad[0] = 1.0 - pi_bad, pi_bad
    for _ in range(T):
        bad = np.concatenate(([0.0], bad[:-1]))  # the packet of a bad step is lost
        good, bad = good * (1.0 - p_gb) + bad * p_bg, good * p_gb + bad * (1.0 - p_bg)
    return good + bad


#: The longest block :func:`loss_coverage` computes the law of (its cost grows as ``T^2``: about 2 s here).
MAX_COVERAGE_HORIZON = 10_000


def loss_coverage(max_delay: int, horizon: int, loss: float, coverage: float = 0.99,
                  burst: float | None = None) -> int:
    """The smallest loss budget ``m`` whose block probability under the trace model reaches ``coverage``.

    The block probability of ``m`` is the probability that a block of ``T``
    measurements of a trace drawn as :func:`eqrec.compare.families.draw_trace`
    draws it (losses independent with probability ``loss``, or in Gilbert
    bursts of mean length ``burst`` with the same average loss; delays uniform
    ``0..D``) is a word of the loss-aware language of
    :func:`eqrec.delay_classes` with ``max_lost = m``: at most ``m`` lost
    (:func:`block_loss_probabilities`).  The delays never make a word leave
    that language (a delay past the block's end is not a loss), so
    ``max_delay`` is only checked.  ``m = T`` always qualifies; with
    ``coverage = 1`` it is the smallest ``m`` whose tail probability is 0 in
    floating point.

    Parameters
    ----------
    max_delay : int
        ``D``, the largest delay, ``>= 0``.
    horizon : int
        ``T``, the block length, ``>= 1``.
    loss : float
        Average loss probability in ``[0, 1]``.
    coverage : float, optional
        Required block probability in ``(0, 1]`` (default 0.99).
    burst : float or None, optional
        Mean burst length ``>= 1`` (``None``: independent losses).

    Returns
    -------
    int
        ``m`` in ``0..T``: ``P(at most m lost in a block) >= coverage``, and ``m − 1`` does not reach it.

    Raises
    ------
    InputError
        A value out of range (the field is named; ``horizon`` at most :data:`MAX_COVERAGE_HORIZON`).

    Examples
    --------
    >>> import eqrec
    >>> eqrec.loss_coverage(2, 20, 0.1), eqrec.loss_coverage(2, 20, 0.1, burst=4.0)
    (6, 13)
    """
    integer(max_delay, "max_delay")
    # the block law costs about T^2 (0.15 s at T = 3000): past the limit it would run for hours, at once refused
    integer(horizon, "horizon", low=1, high=MAX_COVERAGE_HORIZON)
    try:
        c = float(coverage)
    except (TypeError, ValueError):
        raise InputError(f"the coverage must be a number in (0, 1], got {coverage!r}", field="coverage") from None
    if not 0.0 < c <= 1.0:
        raise InputError(f"the coverage must be a number in (0, 1], got {coverage!r}", field="coverage")
    law = block_loss_probabilities(horizon, loss, burst)
    tail = np.cumsum(law[::-1])[::-1]  # tail[j] = P(at least j lost)
    T = law.size - 1
    for m in range(T):
        if tail[m + 1] <= 1.0 - c:  # P(more than m lost) <= 1 - coverage
            return m
    return T
