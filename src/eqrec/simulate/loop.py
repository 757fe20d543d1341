"""Simulation of the true affine system with the causal estimator in the loop, within one horizon.

The system (eq. (3) of the prefix-based paper with noise gains) is driven by
an input sequence and noise drawn uniformly in the box, at random box
vertices, or at the worst-case vertex of a certified bound; an estimator runs
causally on the time-stamped packets that arrive.  :func:`closed_loop` is the
package's one simulation loop: it runs any estimator of the protocol
(:mod:`eqrec.estimators.protocol`: guaranteed, Kalman-type, LMV, and the raw
estimators of :mod:`eqrec.estimators.causal`) on an arrival trace
(:mod:`eqrec.arrivals.draws`), all in one way.  :func:`simulate_run` is one run along an
arrival pattern, :func:`monte_carlo` many runs on a language.  Runs over
many periods (Section III-B3 of the delayed-data paper) are in
:mod:`eqrec.simulate.long_runs`.

Gains are node gains (:class:`eqrec.bounds.gains.GainSchedule`, run by
:class:`eqrec.estimators.causal.RecoveryEstimator`) or class gains
(:class:`eqrec.bounds.data_classes.ClassGains`, run by the class-form
:class:`eqrec.estimators.causal.ClassEstimator`); every function taking gains
accepts both (:func:`eqrec.estimators.causal.make_estimator`).
"""

from __future__ import annotations

import time

from dataclasses import dataclass, field
from typing import Callable, Sequence

import numpy as np

from eqrec.arrivals.draws import ArrivalTrace, uniform_words
from eqrec.checks import check_allocation, floats, instance, integer, positive, seeded
from eqrec.bounds.data_classes import ClassGains
from eqrec.estimators.protocol import check_estimator
from eqrec.bounds.gains import GainSchedule
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.systems.affine import AffineSystem
from eqrec.arrivals.packets import Packet, finite_array
from eqrec.arrivals.words import as_language, as_pattern
from eqrec.errors import InputError


@dataclass
class Trajectory:
    """One simulated run: true states, estimates and errors ``ξ = x - x̂``.

    Parameters
    ----------
    word : str
        Label of the run's arrival pattern.
    x : ndarray, shape (T+1, n)
        True states ``x(0..T)``.
    xhat : ndarray, shape (T+1, n)
        Estimates ``x̂(0..T)``.
    """

    word: str
    x: np.ndarray  # (T+1, n)
    xhat: np.ndarray  # (T+1, n)

    @property
    def error(self) -> np.ndarray:
        """The errors ``ξ(t) = x(t) - x̂(t)``, shape ``(T+1, n)``."""
        return self.x - self.xhat


def sample_uncertainty(layout: UncertaintyLayout, radius: np.ndarray, rng: np.random.Generator,
                       kind: str = "uniform", size: int | None = None) -> np.ndarray:
    """Draw ``δ = (w, v, ξ0)`` in the box: ``"uniform"`` inside it or ``"vertex"`` at random corners.

    Parameters
    ----------
    layout : UncertaintyLayout
        Layout of ``δ`` (its length ``layout.size``).
    radius : ndarray, shape (layout.size,)
        Half-widths of the box (``layout.radius(eta_w, eta_v, mu1)``).
    rng : numpy.random.Generator
        Random generator.
    kind : {"uniform", "vertex"}, optional
        Uniform inside the box (default) or at random vertices.
    size : int or None, optional
        Number of draws (``None``: one draw).

    Returns
    -------
    ndarray, shape (layout.size,) or (size, layout.size)
        The draws.
    """
    shape = (layout.size,) if size is None else (size, layout.size)
    return draw_box(rng, radius, shape, kind)


def draw_box(rng: np.random.Generator, radius: "float | np.ndarray", shape: tuple[int, ...], kind: str) -> np.ndarray:
    """Draws in ``[-radius, radius]``: ``"uniform"`` inside the box or ``"vertex"`` at its corners.

    Parameters
    ----------
    rng : numpy.random.Generator
        Random generator.
    radius : float or ndarray
        Half-widths of the box (broadcast against ``shape``).
    shape : tuple of int
        Shape of the draws.
    kind : {"uniform", "vertex"}
        Uniform inside the box or at random vertices (:class:`InputError` naming ``kind`` otherwise).

    Returns
    -------
    ndarray
        The draws, of shape ``shape``.
    """
    if kind == "uniform":
        return rng.uniform(-1.0, 1.0, shape) * radius
    if kind == "vertex":
        return rng.choice([-1.0, 1.0], shape) * radius
    raise InputError(f"unknown noise kind {kind!r} (uniform or vertex)", field="kind")


@dataclass
class LoopRun:
    """What :func:`closed_loop` returns: the true states, the estimates, what the estimator said about them.

    Parameters
    ----------
    x : ndarray, shape (N+1, n) or (N+1, n, K)
        True states ``x(t0..t0+N)``.
    xhat : ndarray, shape (N+1, n) or (N+1, n, K)
        Estimates ``x̂(t0..t0+N)`` (``x̂(t0) = x(t0) − ξ0``).
    spread : list
        Per step, the second value of the estimator's ``step`` (a float
        bound or an ``(n, n)`` covariance for ``x̂(t+1)``).
    y : ndarray, shape (N, p) or (N, p, K)
        The measurements ``y(t) = C x(t) + V v(t)`` (sent, whether they arrive or not).
    """

    x: np.ndarray
    xhat: np.ndarray
    spread: list = field(default_factory=list)
    y: np.ndarray | None = None

    @property
    def error(self) -> np.ndarray:
        """The errors ``ξ = x − x̂``, shape of :attr:`x`."""
        return self.x - self.xhat

    @property
    def bound(self) -> np.ndarray:
        """The spreads as floats, shape ``(N,)`` (a guaranteed estimator's bounds on ``‖ξ(t+1)‖∞``)."""
        return np.array([float(b) for b in self.spread])


def what_arrived(stamps: Sequence[int], now: int, y: np.ndarray, t0: int = 0) -> "None | np.ndarray | list[Packet]":
    """What reaches the estimator at step ``now``, in the protocol's form (:mod:`eqrec.estimators.protocol`).

    Parameters
    ----------
    stamps : sequence of int
        Step indices ``τ`` (from ``t0``) of the packets arriving at step ``now``.
    now : int
        Step index of the arrival (from ``t0``).
    y : ndarray, shape (N, p) or (N, p, K)
        The measurements by step index.
    t0 : int, optional
        Absolute time of step 0 (packets are stamped with absolute times; default 0).

    Returns
    -------
    None, ndarray or list of Packet
        ``None`` when nothing arrives, ``y(now)`` itself when exactly the on-time
        packet arrives, else the packets ``Packet(t0 + τ, y(τ))`` in the order of ``stamps``.
    """
    stamps = list(stamps)
    if not stamps:
        return None
    if stamps == [now]:
        return y[now]
    return [Packet(t0 + int(tau), y[tau]) for tau in stamps]


def _noise(arr, N: int, rows: int, name: str) -> np.ndarray:
    a = floats(arr, name)
    if a.ndim < 2 or a.shape[0] < N or a.shape[1] != rows:
        raise InputError(f"need at least {N} rows of {rows} entries, got shape {a.shape}", field=name)
    if not np.all(np.isfinite(a[:N])):
        raise InputError("contains NaN or infinite entries", field=name)
    return a


def _measured(system: AffineSystem, t: int, x: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``y(t) = C(t) x(t) + V(t) v``: the measurement sent at ``t``."""
    return system.C_at(t) @ x + system.V_at(t) @ v


def _next_state(system: AffineSystem, t: int, x: np.ndarray, u: np.ndarray, w: np.ndarray,
                one: np.ndarray | None) -> np.ndarray:
    """``x(t+1) = A(t) x(t) + B(t) u + f + E(t) w`` (``one``: an affine run, the known part ``B u + f`` entering
    the columns as ``outer(B u + f, one)``)."""
    if one is None:
        return system.A_at(t) @ x + system.B_at(t) @ u + system.f + system.E_at(t) @ w
    return system.A_at(t) @ x + np.outer(system.B_at(t) @ u + system.f, one) + system.E_at(t) @ w


def plant_run(system: AffineSystem, steps: int, x0: np.ndarray, w: np.ndarray, v: np.ndarray, *,
              t0: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """The true states and the measurements of a plain run with zero input: what :func:`closed_loop` simulates
    whatever its estimator, so the runs of several estimators on the same noise can share it (``plant=``).

    Parameters
    ----------
    system : AffineSystem
        The true system.
    steps : int
        ``N``, the steps of the run.
    x0 : ndarray, shape (n,)
        The initial state.
    w, v : ndarray
        Noise by step index, shapes ``(N, nw)`` and ``(N, nv)`` (at least ``N`` rows, checked by
        :func:`closed_loop`).
    t0 : int, optional
        Absolute time of step 0.

    Returns
    -------
    x : ndarray, shape (N+1, n)
        ``x(t0..t0+N)``, the same numbers as :attr:`LoopRun.x` of a run with ``u_at=None``.
    y : ndarray, shape (N, p)
        ``y(t0..t0+N-1)``, the same numbers as :attr:`LoopRun.y`.
    """
    x = np.zeros((steps + 1,) + np.shape(x0))
    y = np.zeros((steps, system.p))
    x[0] = x0
    for k in range(steps):
        t = t0 + k
        y[k] = _measured(system, t, x[k], v[k])
        x[k + 1] = _next_state(system, t, x[k], np.zeros(system.m), w[k], None)
    return x, y


def closed_loop(system: AffineSystem, est, arrive: "ArrivalTrace | Sequence[Sequence[int]]", x0: np.ndarray,
                xi0: np.ndarray, w: np.ndarray, v: np.ndarray,
                u_at: Callable[[int, np.ndarray], np.ndarray] | None = None,
                after_step: Callable[[int], None] | None = None, *, t0: int = 0,
                one: np.ndarray | None = None,
                plant: "tuple[np.ndarray, np.ndarray] | None" = None) -> LoopRun:
    """The one simulation loop: the true system (eq. (3) of the prefix-based paper) and any estimator on a trace.

    At each step ``k = 0..N-1`` (absolute time ``t = t0 + k``): the input
    ``u = u_at(k, x̂(t))``; the measurement ``y(t) = C(t) x(t) + V(t) v(k)``
    is sent; what the trace delivers at ``k`` reaches the estimator in the
    protocol's form (:func:`what_arrived`: ``None``, ``y(t)``, or time-stamped
    packets); ``x(t+1) = A(t) x(t) + B(t) u + f + E(t) w(k)``.

    ``est`` is any estimator of the protocol (:mod:`eqrec.estimators.protocol`:
    ``reset``, ``step(y, u) -> (x̂(t+1), spread)``): guaranteed, Kalman-type,
    LMV, set-membership, or the raw causal ones
    (:class:`~eqrec.estimators.causal.RecoveryEstimator`,
    :class:`~eqrec.estimators.causal.ClassEstimator`,
    :class:`~eqrec.estimators.switching.SwitchingEstimator`,
    :class:`~eqrec.estimators.augmented.AugmentedEstimator`); the loop resets
    it at ``x̂(t0) = x0 − ξ0`` and runs every estimator the same way.  A
    Monte Carlo is many calls of this loop (:func:`monte_carlo`,
    :mod:`eqrec.simulate.long_runs`; packets an estimator drops are counted
    by the estimator, ``dropped_packets``).

    **Affine runs** (``one`` given): states, noise and measurements carry a
    last axis of ``K`` columns (scenarios, or the constant and the
    coefficients of an affine map of the uncertainty,
    :mod:`eqrec.simulate.filter_runs`); the known part ``B u + f`` enters the
    columns as ``outer(B u + f, one)`` and the estimator is reset with
    ``one``.

    Parameters
    ----------
    system : AffineSystem
        The true system.
    est : object
        The estimator (see above).
    arrive : ArrivalTrace or sequence of sequence of int
        The arrival trace (:class:`~eqrec.arrivals.draws.ArrivalTrace`), or
        ``arrive[k]``: the step indices of the measurements arriving at step
        ``k``; ``N`` steps.
    x0, xi0 : ndarray, shape (n,) or (n, K)
        Initial state and initial error.
    w, v : ndarray
        Noise by step index, shapes ``(N, nw)`` and ``(N, nv)`` (``(N, nw, K)``,
        ``(N, nv, K)`` for affine runs).
    u_at : callable or None, optional
        ``(k, x̂(t)) -> u(t)`` (``None``: zero input).
    after_step : callable or None, optional
        Called with ``k`` after each step.
    t0 : int, optional
        Absolute time of step 0 (time-varying systems, packet stamps; default 0).
    one : ndarray, shape (K,), or None, optional
        How a constant enters the columns of an affine run (``None``: a plain run).
    plant : tuple of ndarray, or None, optional
        ``(x, y)`` of :func:`plant_run` on the same ``system``, ``x0``, ``w``, ``v`` and ``t0`` (a plain run
        with zero input, ``u_at`` and ``one`` ``None``): the true states and measurements taken from it (copied)
        instead of simulated again, the same numbers.  ``None``: simulated here.

    Returns
    -------
    LoopRun
        States, estimates, spreads and measurements.

    Raises
    ------
    InputError
        Noise arrays too short or not finite, a bad ``arrive``, ``system`` or ``est``, what the estimator refuses,
        a ``plant`` of other shapes, another ``x0``, or whose first or last step does not follow from ``w``,
        ``v`` and ``t0``.
    """
    trace = arrive if isinstance(arrive, ArrivalTrace) else ArrivalTrace.from_schedule(arrive)  # checked (arrive)
    schedule = trace.schedule()  # each step's stamps in increasing order
    N, n = len(schedule), instance(system, AffineSystem, "system").n
    w = _noise(w, N, system.nw, "w")
    v = _noise(v, N, system.nv, "v")
    x0, xi0 = floats(x0, "x0"), floats(xi0, "xi0")
    for name, arr in (("x0", x0), ("xi0", xi0)):
        if arr.shape[:1] != (n,) or arr.shape != x0.shape or not np.all(np.isfinite(arr)):
            raise InputError(f"need finite entries, shape ({n},) (or ({n}, K) with one), got {arr.shape}",
                             field=name)
    check_estimator(est)
    simulate = plant is None
    if simulate:
        x = np.zeros((N + 1,) + x0.shape)
        x[0] = x0
        y = np.zeros((N, system.p) + x0.shape[1:])
    else:
        if u_at is not None or one is not None:
            raise InputError("a shared plant run has zero input and no columns: u_at and one must be None",
                             field="plant")
        x, y = (np.array(a, dtype=float) for a in plant)
        if x.shape != (N + 1,) + x0.shape or y.shape != (N, system.p) or not np.array_equal(x[0], x0):
            raise InputError(f"need plant_run's (x, y) of this run: shapes {(N + 1,) + x0.shape} and "
                             f"{(N, system.p)} from x0, got {x.shape} and {y.shape}", field="plant")
        for k in sorted({0, N - 1}) if N else ():  # the first and last steps again: this run's w, v and t0?
            if not (np.array_equal(y[k], _measured(system, t0 + k, x[k], v[k])) and np.array_equal(
                    x[k + 1], _next_state(system, t0 + k, x[k], np.zeros(system.m), w[k], None))):
                raise InputError(f"plant_run's (x, y) were not made with this run's w, v and t0 (step {k} "
                                 f"differs)", field="plant")
    xhat = np.zeros((N + 1,) + x0.shape)
    xhat[0] = x0 - xi0
    est.reset(xhat[0].copy(), t0) if one is None else est.reset(xhat[0].copy(), t0, one=one)
    run = LoopRun(x=x, xhat=xhat, y=y)
    for k in range(N):
        t = t0 + k
        u = np.zeros(system.m) if u_at is None else u_at(k, xhat[k])
        if simulate:
            y[k] = _measured(system, t, x[k], v[k])
        xhat[k + 1], spread = est.step(what_arrived(schedule[k], k, y, t0), u)
        run.spread.append(spread)
        if simulate:
            x[k + 1] = _next_state(system, t, x[k], u, w[k], one)
        if after_step is not None:
            after_step(k)
    return run


def simulate_run(system: AffineSystem, schedule: "GainSchedule | ClassGains", word: "ArrivalPattern | str",
                 delta: np.ndarray, x0: np.ndarray, inputs: np.ndarray | None = None,
                 periodic: bool = False) -> Trajectory:
    """Run the true system and the causal estimator along an arrival pattern for uncertainty ``δ``.

    The system (eq. (3) of the prefix-based paper with noise gains),
    ``x(t+1) = A x(t) + B u(t) + f + E w(t)``, is driven for ``T`` steps
    with the estimator of eqs. (5), (7) in the loop.
    ``schedule`` is node gains or class gains (:func:`eqrec.estimators.causal.make_estimator`).
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
        (:class:`eqrec.bounds.stacking.UncertaintyLayout`), e.g. a vertex of
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
        Malformed word, or an arrival prefix the gains do not cover; a system, gains or ``periodic`` of another
        type, a ``delta``, ``x0`` or ``inputs`` of another shape or with NaN/inf entries (the field is named).

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
    instance(system, AffineSystem, "system"), instance(periodic, (bool, np.bool_), "periodic", "True or False")
    instance(schedule, (GainSchedule, ClassGains), "schedule", "design.schedule or design.class_gains")
    pattern = as_pattern(word)
    T = pattern.T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    w, v, xi0 = lay.split(finite_array(delta, (lay.size,), "delta", "the uncertainty delta"))
    x0 = finite_array(x0, (system.n,), "x0", "the initial state", "n")
    inputs = None if inputs is None else _noise(inputs, T, system.m, "inputs")
    # here, not at the top: the steps that import this module without running an estimator (the P2 and P3 tables)
    # do not load Numba, which the causal estimators' kernels need (about 0.35 s of CPU a job)
    from eqrec.estimators.causal import make_estimator

    est = make_estimator(system, schedule, periodic=periodic)  # reset by the loop at x̂(0) = x0 − ξ0
    run = closed_loop(system, est, ArrivalTrace.from_pattern(pattern), x0, xi0, w, v,
                      None if inputs is None else (lambda t, _xhat: inputs[t]))
    return Trajectory(word=pattern.label, x=run.x, xhat=run.xhat)


#: Estimated seconds past which :func:`monte_carlo` refuses unless ``force`` (the size model's 10 min).
MAX_MONTE_CARLO_SECONDS = 600.0


def monte_carlo(system: AffineSystem, schedule: "GainSchedule | ClassGains", words, mu1: float, runs: int, seed: int,
                kind: str = "uniform", x0: np.ndarray | None = None, inputs: np.ndarray | None = None,
                word_choice: str = "random", force: bool = False) -> tuple[np.ndarray, list[str]]:
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
    force : bool, optional
        Run past the documented size anyway: the runs are refused when their errors would take more than 80 %
        of the available memory, or when the second run's time times ``runs`` exceeds
        :data:`MAX_MONTE_CARLO_SECONDS`.

    Returns
    -------
    errors : ndarray, shape (runs, T+1, n)
        The errors ``ξ(t) = x(t) − x̂(t)`` of every run.
    words_used : list of str
        The label of each run's pattern.

    Raises
    ------
    InputError
        Malformed, no or mixed-length words, an unknown ``kind``, ``runs`` not an integer >= 0, a bad
        ``seed``, ``mu1`` not a positive number, or the errors of :func:`simulate_run` (the field is named);
        runs past the documented size without ``force`` (field ``runs``).

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
    instance(system, AffineSystem, "system")
    runs, mu1, rng = integer(runs, "runs"), positive(mu1, "mu1"), seeded(seed)
    if not isinstance(words, (list, tuple)):  # one word, or an iterable: read (and refused) as a language
        words = as_language(words, kind="missing", fixed_length=False)
    words = [as_pattern(w, field_name="words") for w in words]
    if len({w.T for w in words}) != 1:
        raise InputError(f"need words of one length, got {[w.label for w in words]}", field="words")
    T = words[0].T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    radius = lay.radius(system.eta_w, system.eta_v, mu1)
    x0 = np.zeros(system.n) if x0 is None else finite_array(x0, (system.n,), "x0", "the initial state", "n")
    if not isinstance(force, (bool, np.bool_)):
        raise InputError(f"must be True or False, got {force!r}", field="force")
    check_allocation(8.0 * runs * (T + 1) * system.n, "runs", f"the errors of {runs} runs")
    errs = np.zeros((runs, T + 1, system.n))
    used = []
    for i in range(runs):
        start = time.perf_counter()
        word = uniform_words(rng, words) if word_choice == "random" else words[i % len(words)]
        delta = sample_uncertainty(lay, radius, rng, kind)
        errs[i] = simulate_run(system, schedule, word, delta, x0, inputs).error
        used.append(word.label)
        if i == 1 and not force:  # the time model: the second run's time (the first warms caches) times the runs
            seconds = (time.perf_counter() - start) * runs
            if seconds > MAX_MONTE_CARLO_SECONDS:
                raise InputError(f"refused: {runs} runs would take about {seconds:.3g} s (one takes "
                                 f"{seconds / runs:.2g} s), more than {MAX_MONTE_CARLO_SECONDS:.0f} s; pass "
                                 "force=True to run them anyway, or fewer runs", field="runs")
    return errs, used
