"""Simulation of the true affine system with the causal estimator in the loop, within one horizon.

The system (eq. (3) of the prefix-based paper with noise gains) is driven by
an input sequence and noise drawn uniformly in the box, at random box
vertices, or at the worst-case vertex of a certified bound; the estimator of
:mod:`eqrec.core.estimator` runs causally on the time-stamped packets that
arrive (:func:`closed_loop`).  :func:`simulate_run` is one run along an
arrival pattern, :func:`monte_carlo` many runs on a language.  Runs over
many periods (Section III-B3 of the delayed-data paper) are in
:mod:`eqrec.core.long_runs`.

Gains are node gains (:class:`eqrec.core.gains.GainSchedule`, run by
:class:`eqrec.core.estimator.RecoveryEstimator`) or class gains
(:class:`eqrec.core.classes.ClassGains`, run by the class-form
:class:`eqrec.core.estimator.ClassEstimator`); every function taking gains
accepts both (:func:`eqrec.core.estimator.make_estimator`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Sequence

import numpy as np

from eqrec.core.arrivals import uniform_words
from eqrec.core.classes import ClassGains
from eqrec.core.estimator import ClassEstimator, Packet, RecoveryEstimator, make_estimator
from eqrec.core.gains import GainSchedule
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.stacking import UncertaintyLayout
from eqrec.core.switching import SwitchingEstimator
from eqrec.core.systems import AffineSystem
from eqrec.core.words import as_pattern


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
        Uniform inside the box or at random vertices (:class:`ValueError` otherwise).

    Returns
    -------
    ndarray
        The draws, of shape ``shape``.
    """
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
    system : AffineSystem
        The true system.
    est : RecoveryEstimator, ClassEstimator or SwitchingEstimator
        The estimator, started at ``x̂(0) = x0 - ξ0`` (its :meth:`step` takes the packets and ``u``).
    arrive : sequence of sequence of int
        ``arrive[t]``: the measurement times whose packets reach the estimator at ``t``;
        ``N = len(arrive)`` steps.
    x0, xi0 : ndarray, shape (n,)
        Initial state and initial error.
    w, v : ndarray
        Noise, shapes ``(N, nw)`` and ``(N, nv)``.
    u_at : callable
        ``(t, x̂(t)) -> u(t)``.
    after_step : callable or None, optional
        Called with ``t`` after each step.

    Returns
    -------
    x, xhat : ndarray, shape (N+1, n)
        True states and estimates.
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
        word = uniform_words(rng, words) if word_choice == "random" else words[i % len(words)]
        delta = sample_uncertainty(lay, radius, rng, kind)
        errs[i] = simulate_run(system, schedule, word, delta, x0, inputs).error
        used.append(word.label)
    return errs, used
