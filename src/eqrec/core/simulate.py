"""Simulation of the true affine system with the causal estimator in the loop.

The system (eq. (3) of the prefix-based paper with noise gains) is driven by
an input sequence and noise drawn uniformly in the box, at random box
vertices, or at the worst-case vertex of a certified bound; the estimator of
:mod:`eqrec.core.estimator` runs causally on the time-stamped packets that arrive.

Long runs (Section III-B3 of the delayed-data paper, "Implementation
Strategy"): :func:`long_run_periodic` reuses one design's gains every ``T``
steps on delay words drawn per period; :func:`long_run_switching` runs the
:class:`eqrec.core.switching.SwitchingEstimator` on i.i.d. delays.  Both
record, for every time, the guarantee on ``‖ξ(t)‖∞`` (the level of the node
of the observed prefix, ``μ1`` at period boundaries and in performance mode).
Every packet is delivered at its true arrival time, also when that is past
the end of its period: the estimator drops it there, which is what the
design language assumes (a delay past the horizon means missing).

Gains are node gains (:class:`eqrec.core.gains.GainSchedule`, run by
:class:`eqrec.core.estimator.RecoveryEstimator`) or class gains
(:class:`eqrec.core.classes.ClassGains`, run by the class-form
:class:`eqrec.core.estimator.ClassEstimator`); every function taking gains
accepts both (:func:`eqrec.core.estimator.make_estimator`).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from eqrec.core.classes import ClassGains, class_maps
from eqrec.core.estimator import ClassEstimator, Packet, RecoveryEstimator, make_estimator
from eqrec.core.switching import SwitchingEstimator
from eqrec.core.patterns import ArrivalPattern, as_pattern
from eqrec.core.gains import GainSchedule
from eqrec.core.stacking import UncertaintyLayout
from eqrec.core.systems import AffineSystem
from eqrec.errors import InputError


@dataclass
class Trajectory:
    """One simulated run: true states, estimates and errors ``ξ = x - x̂``."""

    word: str
    x: np.ndarray  # (T+1, n)
    xhat: np.ndarray  # (T+1, n)

    @property
    def error(self) -> np.ndarray:
        return self.x - self.xhat


def sample_uncertainty(layout: UncertaintyLayout, radius: np.ndarray, rng: np.random.Generator,
                       kind: str = "uniform", size: int | None = None) -> np.ndarray:
    """Draw ``δ = (w, v, ξ0)`` in the box: ``"uniform"`` inside it or ``"vertex"`` at random corners."""
    shape = (layout.size,) if size is None else (size, layout.size)
    return draw_box(rng, radius, shape, kind)


def draw_box(rng: np.random.Generator, radius: "float | np.ndarray", shape: tuple[int, ...], kind: str) -> np.ndarray:
    """Draws in ``[-radius, radius]``: ``"uniform"`` inside the box or ``"vertex"`` at its corners."""
    if kind == "uniform":
        return rng.uniform(-1.0, 1.0, shape) * radius
    if kind == "vertex":
        return rng.choice([-1.0, 1.0], shape) * radius
    raise ValueError(f"unknown noise kind {kind!r} (uniform or vertex)")


def closed_loop(system: AffineSystem, est: "RecoveryEstimator | ClassEstimator | SwitchingEstimator",
                arrive: Sequence[Sequence[int]], x0: np.ndarray, xi0: np.ndarray, w: np.ndarray, v: np.ndarray,
                u_at: Callable[[int, np.ndarray], np.ndarray], after_step: Callable[[int], None] | None = None
                ) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]]]:
    """Step the true system (eq. (3) of the prefix-based paper) and a causal estimator on time-stamped packets.

    Parameters
    ----------
    est
        The estimator, started at ``x̂(0) = x0 - ξ0`` (its :meth:`step` takes the packets and ``u``).
    arrive
        ``arrive[t]``: the measurement times whose packets reach the estimator at ``t``;
        ``N = len(arrive)`` steps.
    x0, xi0
        Initial state and initial error.
    w, v
        Noise, shapes ``(N, nw)`` and ``(N, nv)``.
    u_at
        ``(t, x̂(t)) -> u(t)``.
    after_step
        Called with ``t`` after each step.

    Returns
    -------
    x, xhat : ndarray, shape (N+1, n)
    dropped : list of (stamp, arrival)
        Packets that arrived stamped before the estimator's current period.
    """
    N = len(arrive)
    n = system.n
    x = np.zeros((N + 1, n))
    xhat = np.zeros((N + 1, n))
    x[0] = x0
    xhat[0] = x0 - xi0
    y = np.zeros((N, system.p))
    dropped = []
    for t in range(N):
        u = u_at(t, xhat[t])
        y[t] = system.C_at(t) @ x[t] + system.V_at(t) @ v[t]
        packets = [Packet(tau, y[tau]) for tau in arrive[t]]
        xhat[t + 1] = est.step(packets, u)
        dropped += [(tau, t) for tau in arrive[t] if tau < est.period_start]  # stamped before this period
        x[t + 1] = system.A_at(t) @ x[t] + system.B_at(t) @ u + system.f + system.E_at(t) @ w[t]
        if after_step is not None:
            after_step(t)
    return x, xhat, dropped


def simulate_run(system: AffineSystem, schedule: "GainSchedule | ClassGains", word: "ArrivalPattern | str",
                 delta: np.ndarray, x0: np.ndarray, inputs: np.ndarray | None = None,
                 periodic: bool = False) -> Trajectory:
    """Run the true system and the causal estimator along an arrival pattern for uncertainty ``δ``.

    The system (eq. (3) of the prefix-based paper with noise gains),
    ``x(t+1) = A x(t) + B u(t) + f + E w(t)``, is driven for ``T`` steps
    with the estimator of eqs. (5), (7) in the loop.
    ``schedule`` is node gains or class gains (:func:`eqrec.core.estimator.make_estimator`).
    The initial estimate is ``x̂(0) = x0 - ξ0``; the output ``y(τ) = C x(τ) + V v(τ)``
    is sent in a packet stamped ``τ`` that reaches the estimator at the
    pattern's arrival time (or never).

    Parameters
    ----------
    system : AffineSystem
        The true system (also the estimator's model).
    schedule : GainSchedule or ClassGains
        The design's gains (``design.schedule`` or ``design.class_gains``).
    word : ArrivalPattern or str
        The arrival pattern (a 0/1 word is a missing-data pattern) of length ``T``.
    delta : ndarray, shape (T*(nw+nv) + n,)
        The uncertainty ``δ = [w(0..T-1); v(0..T-1); ξ0]``
        (:class:`eqrec.core.stacking.UncertaintyLayout`), e.g. a vertex of
        the box from a certificate or a draw of
        :func:`sample_uncertainty`.
    x0 : ndarray, shape (n,)
        The true initial state.
    inputs : ndarray, shape (T, m), or None, optional
        Inputs ``u(0..T-1)`` (``None``: zero).
    periodic : bool, optional
        Run the estimator in periodic mode (no effect within one horizon;
        default ``False``).

    Returns
    -------
    Trajectory
        ``x`` and ``xhat`` of shape ``(T+1, n)`` and the error
        ``ξ = x − x̂`` (``error``).

    Raises
    ------
    InputError
        Malformed word, or an arrival prefix the gains do not cover.

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> design = eqrec.design_prefix(acc, ["101111", "110111", "111011", "111101"], mu1=1.0)
    >>> delta = np.zeros(6 * (acc.nw + acc.nv) + acc.n)
    >>> delta[-3:] = [1.0, -1.0, 1.0]  # ξ(0) at a vertex of the μ1 box, no noise
    >>> run = eqrec.simulate_run(acc, design.schedule, "101111", delta, np.zeros(3))
    >>> run.error.shape, bool(np.abs(run.error).max() <= design.mu2 + 1e-9)
    ((7, 3), True)
    """
    pattern = as_pattern(word)
    T = pattern.T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    w, v, xi0 = lay.split(np.asarray(delta, float))
    est = make_estimator(system, schedule, x0 - xi0, periodic=periodic)
    arrive = [pattern.arriving_at(t) for t in range(T)]
    x, xhat, _ = closed_loop(system, est, arrive, x0, xi0, w, v,
                             lambda t, _xhat: np.zeros(system.m) if inputs is None else inputs[t])
    return Trajectory(word=pattern.label, x=x, xhat=xhat)


def monte_carlo(system: AffineSystem, schedule: "GainSchedule | ClassGains", words, mu1: float, runs: int, seed: int,
                kind: str = "uniform", x0: np.ndarray | None = None, inputs: np.ndarray | None = None,
                word_choice: str = "random") -> tuple[np.ndarray, list[str]]:
    """Errors of ``runs`` simulations with random patterns (or 0/1 words) of the language.

    Each run draws the uncertainty ``δ = (w, v, ξ0)`` in the box of radii
    ``(η_w, η_v, μ1)`` (:func:`sample_uncertainty`) and a pattern of the
    language, and runs :func:`simulate_run` from ``x0``; within the
    guarantee every error stays below the design's levels (the Monte Carlo
    runs of Fig. 1 of the prefix-based paper).
    ``schedule`` is node gains or class gains (as :func:`simulate_run`).

    Parameters
    ----------
    system : AffineSystem
        The true system.
    schedule : GainSchedule or ClassGains
        The design's gains.
    words : str, ArrivalPattern or sequence of them
        The language (patterns or 0/1 words, of one length ``T``).
    mu1 : float
        Recovery level: the radius of the initial-error box.
    runs : int
        Number of simulations.
    seed : int
        Seed of :func:`numpy.random.default_rng` (the runs are reproducible).
    kind : {"uniform", "vertex"}, optional
        Draw ``δ`` uniformly in the box (default) or at random vertices.
    x0 : ndarray, shape (n,), or None, optional
        The true initial state (``None``: zero).
    inputs : ndarray, shape (T, m), or None, optional
        Inputs ``u(0..T-1)`` of every run (``None``: zero).
    word_choice : {"random", "cycle"}, optional
        Draw each run's pattern at random (default) or cycle through the
        language in order (any value other than ``"random"`` cycles).

    Returns
    -------
    errors : ndarray, shape (runs, T+1, n)
        The errors ``ξ(t) = x(t) − x̂(t)`` of every run.
    words_used : list of str
        The label of each run's pattern.

    Raises
    ------
    InputError
        Malformed words.
    ValueError
        An unknown ``kind``.

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> L1 = ["101111", "110111", "111011", "111101"]
    >>> design = eqrec.design_prefix(acc, L1, mu1=1.0)
    >>> errors, used = eqrec.monte_carlo(acc, design.schedule, L1, mu1=1.0, runs=20, seed=0)
    >>> errors.shape, bool(np.abs(errors).max() <= design.mu2 + 1e-9)
    ((20, 7, 3), True)
    """
    rng = np.random.default_rng(seed)
    words = [as_pattern(w) for w in ([words] if isinstance(words, (str, ArrivalPattern)) else words)]
    T = words[0].T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    radius = lay.radius(system.eta_w, system.eta_v, mu1)
    x0 = np.zeros(system.n) if x0 is None else np.asarray(x0, float)
    errs = np.zeros((runs, T + 1, system.n))
    used = []
    for i in range(runs):
        word = words[rng.integers(len(words))] if word_choice == "random" else words[i % len(words)]
        delta = sample_uncertainty(lay, radius, rng, kind)
        errs[i] = simulate_run(system, schedule, word, delta, x0, inputs).error
        used.append(word.label)
    return errs, used


# ---------------------------------------------------------------------------
# Long runs: periodic reuse and the switching scheme (Section III-B3 of P3)
# ---------------------------------------------------------------------------

#: Delay code of a measurement that is never delivered.
NEVER = -1


@dataclass
class LongRun:
    """A long run of the true system and a causal estimator on time-stamped packets.

    Attributes
    ----------
    x, xhat
        True states and estimates, shape ``(N+1, n)``.
    level
        Guarantee on ``‖ξ(t)‖∞`` at each time, shape ``(N+1,)``.
    delays
        Delay of ``y(t)`` (:data:`NEVER`: not delivered), shape ``(N,)``.
    recovering
        ``True`` at the steps taken in recovery mode (switching scheme), shape ``(N,)``.
    words
        The delay word of each period (periodic reuse).
    switch_times, revert_times
        Start of each recovery phase and the times performance mode resumed.
    dropped
        Packets delivered after their period (or phase) ended, as ``(stamp, arrival)``.
    w, v
        The noise of the run, shapes ``(N, nw)`` and ``(N, nv)``.
    """

    x: np.ndarray
    xhat: np.ndarray
    level: np.ndarray
    delays: np.ndarray
    recovering: np.ndarray
    words: list[str] = field(default_factory=list)
    switch_times: list[int] = field(default_factory=list)
    revert_times: list[int] = field(default_factory=list)
    dropped: list[tuple[int, int]] = field(default_factory=list)
    w: np.ndarray | None = None
    v: np.ndarray | None = None

    @property
    def error(self) -> np.ndarray:
        """``ξ = x - x̂``, shape ``(N+1, n)``."""
        return self.x - self.xhat

    @property
    def ratio(self) -> np.ndarray:
        """``‖ξ(t)‖∞ / level(t)`` at each time."""
        return np.abs(self.error).max(axis=1) / self.level

    @property
    def max_ratio(self) -> float:
        """Largest ratio of the error to its guarantee over the run (``<= 1`` inside the guarantees)."""
        return float(self.ratio.max())


def delay_word_delays(word: str) -> tuple[int, ...]:
    """The delays ``τ(0..T-1)`` of a delay word (digit string, eq. (1) of the delayed-data paper)."""
    if not (isinstance(word, str) and word.isdigit() and word.isascii()):
        raise InputError(f"a delay word must be a string of digits, got {word!r}", field="words")
    return tuple(int(c) for c in word)


def arrival_schedule(delays: np.ndarray) -> list[list[int]]:
    """``out[t]``: the measurement times whose packets arrive at ``t`` (``t < N``), from per-measurement delays."""
    N = len(delays)
    out: list[list[int]] = [[] for _ in range(N)]
    for tau, d in enumerate(np.asarray(delays, int)):
        if d != NEVER and tau + d < N:
            out[tau + d].append(tau)
    return out


def _inputs(system: AffineSystem, controller, inputs, t: int, xhat: np.ndarray) -> np.ndarray:
    if controller is not None:
        return np.asarray(controller(xhat), float).reshape(system.m)
    if inputs is None:
        return np.zeros(system.m)
    u = np.asarray(inputs, float)
    return u.reshape(system.m) if u.ndim <= 1 else u[t]


def _drive(system: AffineSystem, est, delays: np.ndarray, x0: np.ndarray, xi0: np.ndarray, kind: str,
           rng: np.random.Generator, controller, inputs, after_step: Callable[[int], None]
           ) -> tuple[np.ndarray, np.ndarray, list[tuple[int, int]], np.ndarray, np.ndarray]:
    N = len(delays)
    v = draw_box(rng, system.eta_v, (N, system.nv), kind)
    w = draw_box(rng, system.eta_w, (N, system.nw), kind)
    x, xhat, dropped = closed_loop(system, est, arrival_schedule(delays), x0, xi0, w, v,
                                   lambda t, xh: _inputs(system, controller, inputs, t, xh), after_step)
    return x, xhat, dropped, w, v


def long_run_periodic(system: AffineSystem, schedule: "GainSchedule | ClassGains", words: Sequence[str], periods: int,
                      rng: np.random.Generator, *, mu1: float, path_levels: Callable[[str], np.ndarray],
                      kind: str = "uniform", x0: np.ndarray | None = None, controller=None,
                      inputs: np.ndarray | None = None, sequence: Sequence[str] | None = None) -> LongRun:
    """The gains of one design reused every ``T`` steps, a delay word drawn per period (Section III-B3 of P3).

    Parameters
    ----------
    schedule
        Gains of a design of horizon ``T`` (run with ``periodic=True``): node
        gains, or class gains (the class-form estimator, re-anchored at every
        period's start).
    words
        The design language as delay words (digit strings; a delay reaching
        past the period's end means missing).  Each period draws one word
        uniformly, independently.
    periods
        Number of periods; the run has ``N = periods * T`` steps.
    mu1
        Recovery level: ``ξ(0)`` is drawn in the box of radius ``M1``.
    path_levels
        ``word -> levels (T+1,)``: the guarantee along the word's path
        (``μ1`` at ``k = 0`` and ``k = T``).
    kind
        Noise (and ``ξ(0)``) drawn ``"uniform"`` in the box or at ``"vertex"`` corners.
    controller, inputs
        The input ``u(t)``: ``controller(x̂(t))`` (feedback on the estimate;
        the estimator knows ``u``), or fixed ``inputs`` (``(m,)`` or ``(N, m)``),
        or zero.
    sequence
        The words of the periods, instead of random draws (tests).

    Returns
    -------
    LongRun
    """
    T = schedule.horizon
    if sequence is None:
        idx = rng.integers(len(words), size=int(periods))
        sequence = [words[i] for i in idx]
    sequence = list(sequence)
    dl = [delay_word_delays(w) for w in sequence]
    if any(len(d) != T for d in dl):
        raise InputError(f"every delay word must have the design's length T = {T}", field="words")
    delays = np.array([d for ds in dl for d in ds], int)
    N = delays.size
    cache: dict[str, np.ndarray] = {}
    level = np.empty(N + 1)
    for k, w in enumerate(sequence):
        if w not in cache:
            cache[w] = np.asarray(path_levels(w), float)
        level[k * T:(k + 1) * T] = cache[w][:T]
    level[N] = mu1
    xi0 = draw_box(rng, mu1, (system.n,), kind)
    x0 = np.zeros(system.n) if x0 is None else np.asarray(x0, float)
    est = make_estimator(system, schedule, x0 - xi0, periodic=True)
    x, xhat, dropped, w, v = _drive(system, est, delays, x0, xi0, kind, rng, controller, inputs, lambda t: None)
    return LongRun(x=x, xhat=xhat, level=level, delays=delays, recovering=np.zeros(N, bool), words=sequence,
                   dropped=dropped, w=w, v=v)


def draw_delays(rng: np.random.Generator, steps: int, max_delay: int, p_on_time: float) -> np.ndarray:
    """I.i.d. delays: ``0`` with probability ``p_on_time``, else uniform on ``1..max_delay``."""
    late = rng.random(steps) >= p_on_time
    d = np.zeros(steps, int)
    d[late] = rng.integers(1, max_delay + 1, size=int(late.sum()))
    return d


def long_run_switching(system: AffineSystem, performance: "GainSchedule | ClassGains",
                       recovery: "GainSchedule | ClassGains", steps: int,
                       rng: np.random.Generator, *, mu1: float, recovery_level: Callable[[ArrivalPattern], float],
                       max_delay: int, p_on_time: float, kind: str = "uniform", x0: np.ndarray | None = None,
                       controller=None, inputs: np.ndarray | None = None,
                       delays: np.ndarray | None = None) -> LongRun:
    """The switching scheme of Section III-B3 of P3 (:class:`SwitchingEstimator`) on i.i.d. delays.

    Parameters
    ----------
    performance, recovery
        Gains of the period-1 (equalized-performance) design and of the
        recovery design on the words whose first measurement is late (node
        gains or class gains, either kind for each).
    steps
        Length ``N`` of the run.
    mu1
        The common level of both designs (``ξ(0)`` drawn in its box; the
        guarantee in performance mode and at the end of each recovery phase).
    recovery_level
        ``prefix -> level``: the guarantee on ``ξ`` after the observed recovery
        prefix (events ``0..j``, ``j < T - 1``): its node's level.
    max_delay, p_on_time
        Delays are i.i.d. (:func:`draw_delays`) unless ``delays`` is given.

    Returns
    -------
    LongRun
        With ``recovering``, ``switch_times`` and ``revert_times``.
    """
    if delays is None:
        delays = draw_delays(rng, int(steps), int(max_delay), float(p_on_time))
    delays = np.asarray(delays, int)
    N = delays.size
    xi0 = draw_box(rng, mu1, (system.n,), kind)
    x0 = np.zeros(system.n) if x0 is None else np.asarray(x0, float)
    est = SwitchingEstimator(system, performance, recovery, x0 - xi0)
    level = np.full(N + 1, float(mu1))
    recovering = np.zeros(N, bool)
    T = recovery.horizon

    def after(t: int) -> None:
        if est.mode == "recovery":
            recovering[t] = True
            if est.recovery_step < T:
                level[t + 1] = recovery_level(est.recovery_prefix)

    x, xhat, dropped, w, v = _drive(system, est, delays, x0, xi0, kind, rng, controller, inputs, after)
    return LongRun(x=x, xhat=xhat, level=level, delays=delays, recovering=recovering,
                   switch_times=list(est.switch_times), revert_times=list(est.revert_times), dropped=dropped,
                   w=w, v=v)


def class_closed_loop_maps(system: AffineSystem, gains: ClassGains, pattern: "ArrivalPattern | str"
                           ) -> tuple[np.ndarray, np.ndarray, UncertaintyLayout]:
    r"""Maps ``ξ(d) = G[d] δ + c[d]``, ``d = 0..T``, of the class-form estimator along ``pattern``.

    :math:`G[0]` picks :math:`\xi_0`; :math:`G[d] = E_d - K_{(d,S)} Z_S` with
    ``S`` the data available at ``d - 1`` along the pattern
    (:func:`eqrec.core.classes.class_maps`); ``c = 0`` (the class form has no
    offsets).  Raises :class:`InputError` if a class of the pattern is not in
    the gains.
    """
    from eqrec.core.stacking import Stacking

    pattern = as_pattern(pattern)
    T, n = pattern.T, system.n
    st = Stacking(system, T)
    lay = st.layout
    G = np.zeros((T + 1, n, lay.size))
    G[0][:, lay.xi0] = np.eye(n)
    for d in range(1, T + 1):
        i = gains.classes.index(d, pattern.available(d - 1))
        E, Z = class_maps(st, gains.classes.classes[i])
        G[d] = E - gains.K[i] @ Z
    return G, np.zeros((T + 1, n)), lay


def periodic_model_gap(run: LongRun, system: AffineSystem, schedule: "GainSchedule | ClassGains") -> float:
    """Largest gap between a periodic run's errors and the design model of each period's word.

    Each period ``k`` of :func:`long_run_periodic` must follow the affine
    closed-loop map of its word's pattern,
    ``ξ(kT + j) = G_j δ_k + c_j`` with ``δ_k = (w, v of the period, ξ(kT))``
    (:func:`eqrec.core.certify.closed_loop_maps` for node gains,
    :func:`class_closed_loop_maps` for class gains), where the pattern reads a
    delay reaching past the period's end as *missing*.  The run delivers
    such packets in the next period, where the estimator drops them; a gap
    at rounding level shows that the runtime handling and the language agree.
    """
    from eqrec.core.certify import closed_loop_maps
    from eqrec.core.patterns import parse_delay_word

    maps_of = class_closed_loop_maps if isinstance(schedule, ClassGains) else closed_loop_maps
    T = schedule.horizon
    err = run.error
    maps: dict[str, tuple[np.ndarray, np.ndarray, UncertaintyLayout]] = {}
    gap = 0.0
    for k, word in enumerate(run.words):
        if word not in maps:
            maps[word] = maps_of(system, schedule, parse_delay_word(word))
        G, c, lay = maps[word]
        delta = np.zeros(lay.size)
        for j in range(T):
            delta[lay.w(j)] = run.w[k * T + j]
            delta[lay.v(j)] = run.v[k * T + j]
        delta[lay.xi0] = err[k * T]
        pred = np.einsum("tnd,d->tn", G, delta) + c
        gap = max(gap, float(np.abs(err[k * T:(k + 1) * T + 1] - pred).max()))
    return gap
