r"""Vectorised Monte Carlo of the plant of eqs. (1)-(3) with random arrivals.

The simulation works on the *plant* (eqs. (1)-(2)) and the compensators
(zero-input eq. (3); hold-input ``y_h(t) = eta y + (1 - eta) y_h(t-1)``)
directly - not on the common description of :mod:`eqrec.lmv` - so that it
checks the mapping of each mechanism onto that description as well as the
recursion.  All runs advance together: arrays carry the run index first.

Distributions (the LMV theory uses second moments only, so any choice with
these moments is valid): ``w``, ``zeta`` Gaussian; ``xi``, ``lambda``
Gaussian (``mult_dist="gaussian"``) or two-point ``+-sqrt(Q)``
(``mult_dist="two-point"``, the distribution of least kurtosis),
``x(0) ~ N(sigma0, Sigma0)``, ``v = c w + zeta`` when the plant was built
that way (in general ``(w, v)`` jointly Gaussian with the plant's
``Qw, S, Qv``), ``eta(t)`` Bernoulli(``eta_bar``), all independent over time.

Statistical tolerance
---------------------
For an error component pair ``(i, j)`` at time ``t`` the Monte Carlo
estimate of ``P_ij`` is the sample mean of ``e_i e_j`` over ``R``
independent runs; its standard error is ``sqrt(Var(e_i e_j) / R)`` with
``Var(e_i e_j)`` estimated from the same sample (for ``i = j`` this is the
variance of the sample variance, ``(m4 - m2^2)/R``: the errors are not
Gaussian because of the multiplicative noises, so the fourth moment is
estimated, not assumed).  A comparison of ``K`` entries passes if every
``|z| = |P_mc - P_theory| / se <= z_crit`` with the Bonferroni threshold
``z_crit = Phi^{-1}(1 - alpha / (2 K))`` for family-wise level ``alpha``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.arrivals.draws import bernoulli_arrivals
from eqrec.errors import InputError
from eqrec.lmv.model import MECHANISM_KEYS, MultNoiseSystem, system_of
from eqrec.lmv.plant import Plant
from eqrec.lmv.estimator import apply_estimator
from eqrec.lmv.recursion import (LMVResult, SmootherResult, filter_smoother, lmv_recursion, n_step_predictor,
                                 symmetric_part)

__all__ = ["fourth_moment_radius", "simulate_plant", "MCComparison", "compare_moments", "bonferroni_z", "run_mc", "MCRun"]


MULT_DISTS = ("gaussian", "two-point")


def _mult_noise(dist: str, var: float, shape: tuple, rng: np.random.Generator) -> np.ndarray:
    if dist == "gaussian":
        return rng.standard_normal(shape) * np.sqrt(var)
    if dist == "two-point":
        return np.where(rng.random(shape) < 0.5, -1.0, 1.0) * np.sqrt(var)
    raise InputError(f"unknown distribution {dist!r}; one of {MULT_DISTS}", None, "mult_dist")


def fourth_moment_radius(plant: Plant, mult_dist: str = "gaussian") -> float:
    """Spectral radius of ``E[(Phi + xi Phi1)^{(x)4}]`` (``< 1``: finite fourth moments of ``x``).

    ``E[xi^2] = Q_xi``, ``E[xi^4] = 3 Q_xi^2`` (Gaussian) or ``Q_xi^2`` (two-point).  Finite fourth moments
    make the standard errors of :func:`compare_moments` meaningful.

    Parameters
    ----------
    plant : Plant
        The plant, eq. (1) (``Phi``, ``Phi1``, ``Qxi``).
    mult_dist : str, optional
        Distribution of ``xi``: ``"gaussian"`` (default) or ``"two-point"``.

    Returns
    -------
    float
        Spectral radius of the ``(n^4, n^4)`` fourth-moment operator.
    """
    from itertools import product
    kurt = {"gaussian": 3.0, "two-point": 1.0}
    if mult_dist not in kurt:
        raise InputError(f"unknown distribution {mult_dist!r}; one of {MULT_DISTS}", None, "mult_dist")
    Q = plant.Qxi
    moments = {0: 1.0, 1: 0.0, 2: Q, 3: 0.0, 4: kurt[mult_dist] * Q * Q}
    n = plant.n
    M = np.zeros((n ** 4, n ** 4))
    for sel in product((0, 1), repeat=4):
        c = moments[sum(sel)]
        if c == 0.0:
            continue
        K = np.ones((1, 1))
        for s in sel:
            K = np.kron(K, plant.Phi1 if s else plant.Phi)
        M += c * K
    return float(np.max(np.abs(np.linalg.eigvals(M))))


def simulate_plant(plant: Plant, eta_bar: float, T: int, runs: int, rng: np.random.Generator,
                   yh0: np.ndarray | None = None, mult_dist: str = "gaussian") -> dict[str, np.ndarray]:
    """Simulate ``runs`` independent realisations of eqs. (1)-(2) for ``t = 0..T``.

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    eta_bar : float
        Arrival probability of the Bernoulli ``eta(t)``.
    T : int
        Last time (``T >= 0``).
    runs : int
        Number of independent runs ``R >= 1``.
    rng : numpy.random.Generator
        Source of all random draws.
    yh0 : numpy.ndarray or None, optional
        Held output ``y_h(-1)``, ``(m,)`` (or ``(runs, m)``); ``None``: zero.
    mult_dist : str, optional
        Distribution of ``xi``, ``lambda``: ``"gaussian"`` (default) or ``"two-point"`` (module docstring).

    Returns
    -------
    dict of str to numpy.ndarray
        ``x (runs, T+1, n)``, ``y (runs, T+1, m)`` (sensor output, eq. (2)), ``eta (runs, T+1)``, ``y_zero``
        (eq. (3)) and ``y_hold`` (hold-input, ``y_h(-1) = yh0``), both ``(runs, T+1, m)``.
    """
    if runs < 1 or T < 0:
        raise InputError(f"need runs >= 1 and T >= 0, got runs={runs}, T={T}", None, "runs")
    n, m, r = plant.n, plant.m, plant.Gamma.shape[1]
    # joint additive noise (w, v) with covariance [[Qw, S], [S^T, Qv]]
    J = np.block([[plant.Qw, plant.S], [plant.S.T, plant.Qv]])
    Lj = _psd_sqrt(J)
    Ls0 = _psd_sqrt(plant.Sigma0)
    x = np.empty((runs, T + 1, n))
    y = np.empty((runs, T + 1, m))
    x[:, 0] = plant.sigma0 + rng.standard_normal((runs, n)) @ Ls0.T
    wv = rng.standard_normal((runs, T + 1, r + m)) @ Lj.T
    w, v = wv[..., :r], wv[..., r:]
    xi = _mult_noise(mult_dist, plant.Qxi, (runs, T + 1), rng)
    lam = _mult_noise(mult_dist, plant.Qlam, (runs, T + 1), rng)
    eta = bernoulli_arrivals(rng, (runs, T + 1), eta_bar).astype(float)
    PhiT, Phi1T, GT, HT, H1T = plant.Phi.T, plant.Phi1.T, plant.Gamma.T, plant.H.T, plant.H1.T
    for t in range(T + 1):
        xt = x[:, t]
        y[:, t] = xt @ HT + lam[:, t, None] * (xt @ H1T) + v[:, t]
        if t < T:
            x[:, t + 1] = xt @ PhiT + xi[:, t, None] * (xt @ Phi1T) + w[:, t] @ GT
    y_zero = eta[..., None] * y
    y_hold = np.empty_like(y)
    prev = np.zeros((runs, m)) if yh0 is None else np.broadcast_to(np.asarray(yh0, float), (runs, m)).copy()
    for t in range(T + 1):
        prev = eta[:, t, None] * y[:, t] + (1.0 - eta[:, t, None]) * prev
        y_hold[:, t] = prev
    return {"x": x, "y": y, "eta": eta, "y_zero": y_zero, "y_hold": y_hold}


def _psd_sqrt(M: np.ndarray) -> np.ndarray:
    w, V = np.linalg.eigh(symmetric_part(M))
    return V * np.sqrt(np.clip(w, 0.0, None))


def bonferroni_z(alpha: float, k: int) -> float:
    """Two-sided Bonferroni threshold for ``k`` comparisons at family-wise level ``alpha``.

    Parameters
    ----------
    alpha : float
        Family-wise level, ``0 < alpha < 1``.
    k : int
        Number of comparisons (values below 1 count as 1).

    Returns
    -------
    float
        ``z_crit = Phi^{-1}(1 - alpha / (2 k))`` (``Phi`` the standard normal distribution function).
    """
    # imported here: only the Monte Carlo check needs it, and scipy.stats costs ~1 s CPU per job to import
    # (the tracking and sweep jobs of P4 import this module and never test moments)
    from scipy.stats import norm

    return float(norm.ppf(1.0 - alpha / (2.0 * max(int(k), 1))))


@dataclass
class MCComparison:
    """Empirical vs theoretical second moments of estimation errors (built by :func:`compare_moments`).

    Parameters
    ----------
    emp : numpy.ndarray
        Monte Carlo estimate of ``E[e e^T]``, ``(T', n, n)``.
    theory : numpy.ndarray
        The theoretical second moments, ``(T', n, n)``.
    se : numpy.ndarray
        Standard errors of ``emp``, ``(T', n, n)`` (module docstring).
    z : numpy.ndarray
        Standardised differences ``(emp - theory) / se``, ``(T', n, n)``; NaN below the diagonal.
    z_crit : float
        Bonferroni threshold over the ``k`` compared entries and the ``T' n`` compared means.
    k : int
        Number of distinct compared entries, ``T' n (n+1) / 2``.
    runs : int
        Number of Monte Carlo runs ``R``.
    mean_z : float
        The largest standardised error *mean* (should be ``O(1)``: the LMV estimator is unbiased).
    """

    emp: np.ndarray
    theory: np.ndarray
    se: np.ndarray
    z: np.ndarray
    z_crit: float
    k: int
    runs: int
    mean_z: float

    @property
    def max_abs_z(self) -> float:
        """Largest ``|z|`` over the compared entries."""
        return float(np.nanmax(np.abs(self.z)))

    @property
    def passed(self) -> bool:
        """Whether ``max_abs_z`` and ``mean_z`` are both within ``z_crit``."""
        return self.max_abs_z <= self.z_crit and self.mean_z <= self.z_crit

    @property
    def max_rel_err(self) -> float:
        """Largest relative error of the empirical variances (the diagonals) against the theory."""
        d = np.einsum("tii->ti", self.theory)
        e = np.einsum("tii->ti", self.emp)
        return float(np.nanmax(np.abs(e - d) / np.abs(d)))

    def summary(self) -> str:
        """One line for logs and reports.

        Returns
        -------
        str
            Runs, entries, ``max|z|`` against ``z_crit``, ``mean_z`` and the largest relative variance error.
        """
        return (f"{self.runs} runs, {self.k} entries: max|z| = {self.max_abs_z:.2f} "
                f"(Bonferroni z_crit = {self.z_crit:.2f}), max|mean z| = {self.mean_z:.2f}, "
                f"max relative error of variances = {100 * self.max_rel_err:.1f}%")


def compare_moments(err: np.ndarray, theory: np.ndarray, alpha: float = 1e-3) -> MCComparison:
    """Compare ``E[e e^T]`` estimated from ``err (runs, T', n)`` with ``theory (T', n, n)``.

    The test of the module docstring: standard errors from the sample fourth moments, Bonferroni threshold.

    Parameters
    ----------
    err : numpy.ndarray
        Estimation errors, ``(runs, T', n)``.
    theory : numpy.ndarray
        Theoretical ``E[e e^T]`` (e.g. ``P(t|t-1)`` of Theorem 1), ``(T', n, n)``.
    alpha : float, optional
        Family-wise level of the test (default ``1e-3``).

    Returns
    -------
    MCComparison
        The comparison; :attr:`MCComparison.passed` is the verdict.
    """
    err = np.asarray(err, float)
    R = err.shape[0]
    prod = err[..., :, None] * err[..., None, :]            # (R, T', n, n)
    emp = prod.mean(axis=0)
    se = np.sqrt(prod.var(axis=0, ddof=1) / R)
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.where(se > 0, (emp - theory) / se, np.where(np.isclose(emp, theory), 0.0, np.inf))
    n = err.shape[-1]
    k = err.shape[1] * n * (n + 1) // 2
    mse = err.std(axis=0, ddof=1) / np.sqrt(R)
    with np.errstate(divide="ignore", invalid="ignore"):
        mean_z = float(np.nanmax(np.abs(np.where(mse > 0, err.mean(axis=0) / mse, 0.0))))
    iu = np.triu_indices(n)
    zc = bonferroni_z(alpha, k + err.shape[1] * n)
    z_u = z.copy()
    mask = np.zeros((n, n), bool)
    mask[iu] = True
    z_u[:, ~mask] = np.nan
    return MCComparison(emp, theory, se, z_u, zc, k, R, mean_z)


@dataclass
class MCRun:
    """One Monte Carlo experiment of one mechanism: truth, estimates, theory (built by :func:`run_mc`).

    Theory and errors are on the plant state (the leading ``n_x`` components).

    Parameters
    ----------
    sys : MultNoiseSystem
        The compensated system (:func:`~eqrec.lmv.model.system_of`).
    res : LMVResult
        Its one-step predictor, Theorem 1.
    sm : SmootherResult
        Its filter and smoothers, Theorem 3.
    sim : dict
        The realisations, :func:`simulate_plant`.
    est : dict
        The estimates, :func:`~eqrec.lmv.estimator.apply_estimator`.
    P_pred : numpy.ndarray
        Theory ``P(t|t-1)``, ``(T+1, n_x, n_x)``.
    P_smooth : numpy.ndarray
        Theory ``P(t|t+j)``, ``j = 0..N`` (``j = 0`` the filter), ``(T+1, N+1, n_x, n_x)``.
    err_pred : numpy.ndarray
        Errors ``x(t) - xh(t|t-1)``, ``(R, T+1, n_x)``.
    err_smooth : numpy.ndarray
        Errors ``x(t) - xh(t|t+j)``, ``(R, T+1, N+1, n_x)`` (NaN where ``t + j > T``).
    pred_steps : int, optional
        The ``Np`` of the ``Np``-step predictor, Theorem 2 (default 1).
    P_npred : numpy.ndarray or None, optional
        Theory ``P(t+Np|t)``, eq. (16), for ``t = 0..T-Np``: ``(T-Np+1, n_x, n_x)``.
    err_npred : numpy.ndarray or None, optional
        Errors ``x(t+Np) - xh(t+Np|t)``, ``(R, T-Np+1, n_x)``.
    """

    sys: MultNoiseSystem
    res: LMVResult
    sm: SmootherResult
    sim: dict
    est: dict
    P_pred: np.ndarray
    P_smooth: np.ndarray
    err_pred: np.ndarray
    err_smooth: np.ndarray
    pred_steps: int = 1
    P_npred: np.ndarray | None = None
    err_npred: np.ndarray | None = None


def run_mc(plant: Plant, eta_bar: float, mechanism: str, T: int, runs: int, N_smooth: int,
           rng: np.random.Generator, sim: dict | None = None, mult_dist: str = "gaussian",
           pred_steps: int = 2) -> MCRun:
    """Simulate, estimate with the LMV recursion of ``mechanism`` and collect the errors.

    ``sim`` (from :func:`simulate_plant`) may be passed to evaluate both
    mechanisms on the same realisations.

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    eta_bar : float
        Arrival probability.
    mechanism : str
        ``"zero-input"`` or ``"hold-input"`` (:func:`~eqrec.lmv.model.system_of`).
    T : int
        Last time; the recursion and the simulation run over ``t = 0..T``.
    runs : int
        Number of runs ``R`` (used only when ``sim`` is ``None``).
    N_smooth : int
        Smoothing lag ``N`` of Theorem 3.
    rng : numpy.random.Generator
        Random source of the simulation (used only when ``sim`` is ``None``).
    sim : dict or None, optional
        Realisations from :func:`simulate_plant` over the same ``T``; ``None``: simulate here.
    mult_dist : str, optional
        Distribution of the multiplicative noises when simulating (default ``"gaussian"``).
    pred_steps : int, optional
        ``Np`` of the ``Np``-step predictor, Theorem 2 (``1 <= Np <= T``, default 2).

    Returns
    -------
    MCRun
        Truth, estimates, theoretical covariances and errors.
    """
    sys = system_of(plant, mechanism, eta_bar)
    key = "y_" + MECHANISM_KEYS[mechanism]
    res = lmv_recursion(sys, T)
    sm = filter_smoother(res, N_smooth)
    if sim is None:
        sim = simulate_plant(plant, eta_bar, T, runs, rng, mult_dist=mult_dist)
    est = apply_estimator(res, sim[key], sm)
    nx = plant.n
    x = sim["x"]
    err_pred = x - est["pred"][:, : T + 1, :nx]
    err_smooth = x[:, :, None, :] - est["smooth"][..., :nx]
    # N-step predictor (Theorem 2): xh(t+Np|t) = A^(Np-1) xh(t+1|t), t = 0..T-Np
    Np = int(pred_steps)
    if Np < 1 or Np > T:
        raise InputError(f"prediction steps must lie in 1..T, got {Np}", None, "pred_steps")
    Apow = np.linalg.matrix_power(sys.A, Np - 1)
    tt = np.arange(0, T - Np + 1)                                   # t with t + Np <= T
    npred = est["pred"][:, tt + 1] @ Apow.T                         # xh(t+Np|t)
    err_npred = x[:, tt + Np] - npred[..., :nx]
    P_npred = n_step_predictor(res, Np)[tt][:, :nx, :nx]
    return MCRun(sys, res, sm, sim, est, res.P_pred[: T + 1, :nx, :nx], sm.P[:, :, :nx, :nx],
                 err_pred, err_smooth, Np, P_npred, err_npred)
