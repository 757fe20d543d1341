"""Simulation of the true affine system with the causal estimator in the loop.

The system (eq. (3) of the prefix-based paper with noise gains) is driven by
an input sequence and noise drawn uniformly in the box, at random box
vertices, or at the worst-case vertex of a certified bound; the estimator of
:mod:`eqrec.core.estimator` runs causally on the time-stamped packets that arrive.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.core.estimator import Packet, RecoveryEstimator
from eqrec.core.patterns import ArrivalPattern, as_pattern
from eqrec.core.gains import GainSchedule
from eqrec.core.stacking import UncertaintyLayout
from eqrec.core.systems import AffineSystem


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
    if kind == "uniform":
        return rng.uniform(-1.0, 1.0, shape) * radius
    if kind == "vertex":
        return rng.choice([-1.0, 1.0], shape) * radius
    raise ValueError(f"unknown noise kind {kind!r} (uniform or vertex)")


def simulate_run(system: AffineSystem, schedule: GainSchedule, word: "ArrivalPattern | str", delta: np.ndarray,
                 x0: np.ndarray, inputs: np.ndarray | None = None, periodic: bool = False) -> Trajectory:
    """Run the true system and the causal estimator along an arrival pattern for uncertainty ``δ``.

    The initial estimate is ``x̂(0) = x0 - ξ0``; the output ``y(τ) = C x(τ) + V v(τ)``
    is sent in a packet stamped ``τ`` that reaches the estimator at the
    pattern's arrival time (or never).
    """
    pattern = as_pattern(word)
    T = pattern.T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    w, v, xi0 = lay.split(np.asarray(delta, float))
    x = np.zeros((T + 1, system.n))
    xhat = np.zeros((T + 1, system.n))
    x[0] = x0
    xhat[0] = x0 - xi0
    est = RecoveryEstimator(system, schedule, xhat[0], periodic=periodic)
    y = np.zeros((T, system.p))
    for t in range(T):
        u = np.zeros(system.m) if inputs is None else inputs[t]
        y[t] = system.C_at(t) @ x[t] + system.V_at(t) @ v[t]
        packets = [Packet(tau, y[tau]) for tau in pattern.arriving_at(t)]
        xhat[t + 1] = est.step(packets, u)
        x[t + 1] = system.A_at(t) @ x[t] + system.B_at(t) @ u + system.f + system.E_at(t) @ w[t]
    return Trajectory(word=pattern.label, x=x, xhat=xhat)


def monte_carlo(system: AffineSystem, schedule: GainSchedule, words, M1: float, runs: int, seed: int,
                kind: str = "uniform", x0: np.ndarray | None = None, inputs: np.ndarray | None = None,
                word_choice: str = "random") -> tuple[np.ndarray, list[str]]:
    """Errors of ``runs`` simulations with random patterns (or 0/1 words) of the language.

    Returns
    -------
    errors : ndarray, shape (runs, T+1, n)
    words_used : list of str
    """
    rng = np.random.default_rng(seed)
    words = [as_pattern(w) for w in ([words] if isinstance(words, (str, ArrivalPattern)) else words)]
    T = words[0].T
    lay = UncertaintyLayout(T, system.nw, system.nv, system.n)
    radius = lay.radius(system.eta_w, system.eta_v, M1)
    x0 = np.zeros(system.n) if x0 is None else np.asarray(x0, float)
    errs = np.zeros((runs, T + 1, system.n))
    used = []
    for i in range(runs):
        word = words[rng.integers(len(words))] if word_choice == "random" else words[i % len(words)]
        delta = sample_uncertainty(lay, radius, rng, kind)
        errs[i] = simulate_run(system, schedule, word, delta, x0, inputs).error
        used.append(word.label)
    return errs, used
