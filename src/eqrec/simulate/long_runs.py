"""Long runs: one design's gains reused period after period, and the switching scheme.

Section III-B3 of the delayed-data paper ("Implementation Strategy"):
:func:`long_run_periodic` reuses one design's gains every ``T`` steps on
delay words drawn per period; :func:`long_run_switching` runs the
:class:`eqrec.estimators.switching.SwitchingEstimator` on i.i.d. delays.  Both
record, for every time, the guarantee on ``‖ξ(t)‖∞`` (the level of the node
of the observed prefix, ``μ1`` at period boundaries and in performance mode).
Every packet is delivered at its true arrival time, also when that is past
the end of its period: the estimator drops it there, which is what the
design language assumes (a delay past the horizon means missing);
:func:`periodic_model_gap` checks a run against the design model.  The
words and delays are drawn by the one arrival model
(:mod:`eqrec.arrivals.draws`) and every run is a call of the one loop,
:func:`eqrec.simulate.loop.closed_loop`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from eqrec.arrivals.draws import ArrivalTrace, draw_delays, uniform_words
from eqrec.bounds.certify import closed_loop_maps
from eqrec.bounds.data_classes import ClassGains, class_error_map
from eqrec.estimators.causal import make_estimator
from eqrec.bounds.gains import GainSchedule
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.simulate.loop import closed_loop, draw_box
from eqrec.bounds.stacking import Stacking, UncertaintyLayout
from eqrec.estimators.switching import SwitchingEstimator
from eqrec.systems.affine import AffineSystem
from eqrec.arrivals.words import as_pattern, parse_delay_word, parse_delays
from eqrec.errors import InputError

@dataclass
class LongRun:
    """A long run of the true system and a causal estimator on time-stamped packets.

    Parameters
    ----------
    x, xhat : ndarray, shape (N+1, n)
        True states and estimates.
    level : ndarray, shape (N+1,)
        Guarantee on ``‖ξ(t)‖∞`` at each time.
    delays : ndarray of int, shape (N,)
        Delay of ``y(t)`` (:data:`~eqrec.arrivals.draws.NEVER`: not delivered).
    recovering : ndarray of bool, shape (N,)
        ``True`` at the steps taken in recovery mode (switching scheme).
    words : list of str, optional
        The delay word of each period (periodic reuse).
    switch_times, revert_times : list of int, optional
        Start of each recovery phase and the times performance mode resumed.
    dropped : list of tuple of int, optional
        Packets delivered after their period (or phase) ended, as ``(stamp, arrival)``.
    w, v : ndarray or None, optional
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
    trace = ArrivalTrace(delays)
    schedule = trace.schedule()  # each step's stamps in increasing order
    dropped: list[tuple[int, int]] = []
    counted = [0]

    def after(k: int) -> None:
        # the packets the estimator dropped at step k are those stamped before its period (or phase): the
        # earliest of the step's stamps, as many as its counter grew
        new = est.dropped_packets - counted[0]
        dropped.extend((int(tau), k) for tau in schedule[k][:new])
        counted[0] = est.dropped_packets
        after_step(k)

    run = closed_loop(system, est, trace, x0, xi0, w, v, lambda t, xh: _inputs(system, controller, inputs, t, xh),
                      after)
    return run.x, run.xhat, dropped, w, v


def long_run_periodic(system: AffineSystem, schedule: "GainSchedule | ClassGains", words: Sequence[str], periods: int,
                      rng: np.random.Generator, *, mu1: float, path_levels: Callable[[str], np.ndarray],
                      kind: str = "uniform", x0: np.ndarray | None = None, controller=None,
                      inputs: np.ndarray | None = None, sequence: Sequence[str] | None = None) -> LongRun:
    """The gains of one design reused every ``T`` steps, a delay word drawn per period (Section III-B3 of P3).

    Parameters
    ----------
    system : AffineSystem
        The true system and the estimator's model.
    schedule : GainSchedule or ClassGains
        Gains of a design of horizon ``T`` (run with ``periodic=True``): node
        gains, or class gains (the class-form estimator, re-anchored at every
        period's start).
    words : sequence of str
        The design language as delay words (digit strings; a delay reaching
        past the period's end means missing).  Each period draws one word
        uniformly, independently.
    periods : int
        Number of periods; the run has ``N = periods * T`` steps.
    rng : numpy.random.Generator
        Random source of the words, the noise and ``ξ(0)``.
    mu1 : float
        Recovery level: ``ξ(0)`` is drawn in the box of radius ``mu1``.
    path_levels : callable
        ``word -> levels (T+1,)``: the guarantee along the word's path
        (``μ1`` at ``k = 0`` and ``k = T``).
    kind : str, optional
        Noise (and ``ξ(0)``) drawn ``"uniform"`` in the box or at ``"vertex"`` corners.
    x0 : ndarray, shape (n,), optional
        True initial state (default zero); the estimate starts at ``x0 - ξ(0)``.
    controller : callable, optional
        ``u(t) = controller(x̂(t))`` (feedback on the estimate; the estimator knows ``u``).
    inputs : ndarray, optional
        Fixed inputs, ``(m,)`` or ``(N, m)``, when there is no controller (default zero).
    sequence : sequence of str, optional
        The words of the periods, instead of random draws (tests).

    Returns
    -------
    LongRun
        With ``words`` (one per period) and ``dropped``.
    """
    T = schedule.horizon
    if sequence is None:
        sequence = uniform_words(rng, list(words), size=int(periods))
    sequence = list(sequence)
    parsed = {w: parse_delays(w, field_name="words") for w in dict.fromkeys(sequence)}  # each distinct word once
    dl = [parsed[w] for w in sequence]
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
    est = make_estimator(system, schedule, periodic=True)  # reset by the loop at x̂(0) = x0 − ξ0
    x, xhat, dropped, w, v = _drive(system, est, delays, x0, xi0, kind, rng, controller, inputs, lambda t: None)
    return LongRun(x=x, xhat=xhat, level=level, delays=delays, recovering=np.zeros(N, bool), words=sequence,
                   dropped=dropped, w=w, v=v)


def long_run_switching(system: AffineSystem, performance: "GainSchedule | ClassGains",
                       recovery: "GainSchedule | ClassGains", steps: int,
                       rng: np.random.Generator, *, mu1: float, recovery_level: Callable[[ArrivalPattern], float],
                       max_delay: int, p_on_time: float, kind: str = "uniform", x0: np.ndarray | None = None,
                       controller=None, inputs: np.ndarray | None = None,
                       delays: np.ndarray | None = None) -> LongRun:
    """The switching scheme of Section III-B3 of P3 (:class:`SwitchingEstimator`) on i.i.d. delays.

    Parameters
    ----------
    system : AffineSystem
        The true system and the estimators' model.
    performance, recovery : GainSchedule or ClassGains
        Gains of the period-1 (equalized-performance) design and of the
        recovery design on the words whose first measurement is late (node
        gains or class gains, either kind for each).
    steps : int
        Length ``N`` of the run.
    rng : numpy.random.Generator
        Random source of the delays, the noise and ``ξ(0)``.
    mu1 : float
        The common level of both designs (``ξ(0)`` drawn in its box; the
        guarantee in performance mode and at the end of each recovery phase).
    recovery_level : callable
        ``ArrivalPattern prefix -> level``: the guarantee on ``ξ`` after the observed recovery
        prefix (events ``0..j``, ``j < T - 1``): its node's level.
    max_delay : int
        Largest delay of :func:`~eqrec.arrivals.draws.draw_delays` (used unless ``delays`` is given).
    p_on_time : float
        Probability of an on-time measurement in :func:`~eqrec.arrivals.draws.draw_delays`.
    kind : str, optional
        Noise (and ``ξ(0)``) drawn ``"uniform"`` in the box or at ``"vertex"`` corners.
    x0 : ndarray, shape (n,), optional
        True initial state (default zero); the estimate starts at ``x0 - ξ(0)``.
    controller : callable, optional
        ``u(t) = controller(x̂(t))`` (feedback on the estimate).
    inputs : ndarray, optional
        Fixed inputs, ``(m,)`` or ``(N, m)``, when there is no controller (default zero).
    delays : ndarray of int, shape (N,), optional
        Delays of the run instead of random draws (:data:`~eqrec.arrivals.draws.NEVER`: not delivered).

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
    est = SwitchingEstimator(system, performance, recovery)  # reset by the loop at x̂(0) = x0 − ξ0
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
    (:func:`eqrec.bounds.data_classes.class_maps`); ``c = 0`` (the class form has no
    offsets).  Raises :class:`InputError` if a class of the pattern is not in
    the gains.

    Parameters
    ----------
    system : AffineSystem
        The system.
    gains : ClassGains
        One ``K`` per class.
    pattern : ArrivalPattern or str
        Pattern (or 0/1 word) of horizon ``T``.

    Returns
    -------
    G : ndarray, shape (T+1, n, D)
        Linear maps from ``δ = (w, v, ξ0)``.
    c : ndarray, shape (T+1, n)
        Zeros.
    layout : UncertaintyLayout
        Positions of ``w(t)``, ``v(t)`` and ``ξ0`` in ``δ``.
    """
    pattern = as_pattern(pattern)
    T, n = pattern.T, system.n
    st = Stacking(system, T)
    lay = st.layout
    G = np.zeros((T + 1, n, lay.size))
    G[0][:, lay.xi0] = np.eye(n)
    for d in range(1, T + 1):
        i = gains.classes.index(d, pattern.available(d - 1))
        G[d] = class_error_map(st, gains, i)
    return G, np.zeros((T + 1, n)), lay


def periodic_model_gap(run: LongRun, system: AffineSystem, schedule: "GainSchedule | ClassGains") -> float:
    """Largest gap between a periodic run's errors and the design model of each period's word.

    Each period ``k`` of :func:`long_run_periodic` must follow the affine
    closed-loop map of its word's pattern,
    ``ξ(kT + j) = G_j δ_k + c_j`` with ``δ_k = (w, v of the period, ξ(kT))``
    (:func:`eqrec.bounds.certify.closed_loop_maps` for node gains,
    :func:`class_closed_loop_maps` for class gains), where the pattern reads a
    delay reaching past the period's end as *missing*.  The run delivers
    such packets in the next period, where the estimator drops them; a gap
    at rounding level shows that the runtime handling and the language agree.

    Parameters
    ----------
    run : LongRun
        A run of :func:`long_run_periodic` (with ``words``, ``w`` and ``v``).
    system : AffineSystem
        The system of the run.
    schedule : GainSchedule or ClassGains
        The gains of the run.

    Returns
    -------
    float
        ``max`` over periods, times and components of ``|ξ - (G δ + c)|``.
    """
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
