r"""Kalman-type estimators for delayed (out-of-sequence) and missing measurements.

Three estimators of the comparison of the delayed-data paper (Fig. 1, its
ref. [9]), each run on the packets that actually arrive:

``TimestampedKalman`` (``"timestamped"``)
    Uses each packet at its own time stamp: at time ``t`` it re-runs the
    Kalman filter from time 0 over the measurements received so far
    (``y(τ)``, ``τ ∈ A(t)``), so ``x̂(t|I_t)`` is the best linear (Gaussian:
    the conditional mean) estimate from the data received so far — the
    complete in-sequence re-filtering of ref. [6] of the paper, equal to a
    state augmented with the last ``τ̄`` states.
``DelayUnawareKalman`` (``"unaware"``)
    A standard Kalman filter that treats whatever arrives at ``t`` as a
    measurement of the current state ``x(t)`` (several packets: sequential
    updates, oldest stamp first); nothing when nothing arrives.
``RandomDelayLMV`` (``"random_delay_lmv"``)
    In the spirit of ref. [9] (Zhang, Feng, Han 2011): the receiver gets the
    sum of what arrives, ``y_r(t) = Σ_d γ_d(t) z(t-d)``, with
    ``γ_d(t) ∈ {0, 1}`` Bernoulli of known probability ``p_d`` (the packet
    of time ``t-d`` arrives at ``t``; uniform delays on ``{0..τ̄}`` give
    ``p_d = 1/(τ̄+1)``), and the linear minimum-variance estimator of
    :mod:`eqrec.lmv` is built on the state ``X(t) = [x(t); z(t-1); ...;
    z(t-τ̄)]`` (``z = C x + V v`` the sensor output):
    ``y_r = (C̄ + Σ_d e_d C_d) X + γ_0 V v`` with ``e_d = γ_d - p_d``
    white, ``W = diag(p_d (1 - p_d))``.  Approximation stated: the
    ``γ_d(t)`` of one packet at different times are mutually exclusive, not
    independent; like ref. [9]'s model, the LMV treats them as white.
    Time stamps are not used.

Each estimator is designed from Gaussian statistics matched to the box
(:class:`GaussianDesign`: ``5σ`` = bound, as in the paper) and runs on
arrays of shape ``(dim, K)``: ``K`` scenarios at once, or the ``1 + D``
coefficient columns of an affine map (:mod:`eqrec.filters.affine`); the
vector ``one`` (length ``K``) says how a constant enters (``1`` in every
scenario, or only in the constant column).
"""

from __future__ import annotations

import numpy as np

from eqrec.core.noise import GaussianDesign
from eqrec.core.systems import AffineSystem
from eqrec.errors import InputError


def _kalman_update(x, P, y, C, R):
    S = C @ P @ C.T + R
    K = np.linalg.solve(S.T, (P @ C.T).T).T
    x = x + K @ (y - C @ x)
    IKC = np.eye(P.shape[0]) - K @ C
    P = IKC @ P @ IKC.T + K @ R @ K.T  # Joseph form
    return x, P


class _Base:
    """Common interface: ``reset(xhat0, one)`` then ``step(t, packets) -> (x̂(t|I_t), x̂(t+1|I_t))``."""

    name = ""

    def __init__(self, system: AffineSystem, design: GaussianDesign, inputs: np.ndarray | None = None):
        self.system, self.design = system, design
        self.inputs = None if inputs is None else np.asarray(inputs, float)

    def _drive(self, t: int) -> np.ndarray:
        """Known part ``B u(t) + f`` of the dynamics."""
        u = np.zeros(self.system.m) if self.inputs is None else self.inputs[t]
        return self.system.B_at(t) @ u + self.system.f


class TimestampedKalman(_Base):
    """Kalman filter using every packet at its own time (re-filtering from time 0 at each step).

    Parameters
    ----------
    system : AffineSystem
        The system (``A(t)``, ``C(t)``, ``B(t)``, ``f``); its noise enters only through ``design``.
    design : GaussianDesign
        The second moments the filter is designed for.
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``; ``None``: zero.
    """

    name = "timestamped"

    def reset(self, xhat0: np.ndarray, one: np.ndarray) -> None:
        """Start a run from the initial estimate ``x̂(0)``.

        Parameters
        ----------
        xhat0 : numpy.ndarray
            Initial estimate, ``(n, K)`` (one column per scenario or affine coefficient).
        one : numpy.ndarray
            ``(K,)``: how a constant enters the columns (module docstring).
        """
        self.xhat0, self.one = np.asarray(xhat0, float), np.asarray(one, float)
        self.received: dict[int, np.ndarray] = {}

    def step(self, t: int, packets) -> tuple[np.ndarray, np.ndarray]:
        """Process the packets arriving at ``t``; return ``(x̂(t|I_t), x̂(t+1|I_t))``.

        Parameters
        ----------
        t : int
            Current time, ``0 <= t < T``.
        packets : sequence of tuple
            ``(τ, y(τ))`` pairs of the packets arriving at ``t``, ``y(τ)`` of shape ``(p, K)``.

        Returns
        -------
        tuple of numpy.ndarray
            Filtered and one-step predicted estimates, each ``(n, K)``.
        """
        sysm, d = self.system, self.design
        for tau, y in packets:
            self.received[int(tau)] = np.asarray(y, float)
        x, P = self.xhat0.copy(), d.P0.copy()
        filt = x
        for tau in range(t + 1):
            if tau in self.received:
                x, P = _kalman_update(x, P, self.received[tau], sysm.C_at(tau), d.R)
            if tau == t:
                filt = x
            A = sysm.A_at(tau)
            x = A @ x + np.outer(self._drive(tau), self.one)
            P = A @ P @ A.T + d.Q
        return filt, x


class DelayUnawareKalman(_Base):
    """Kalman filter treating every packet arriving at ``t`` as a measurement of ``x(t)``.

    Parameters
    ----------
    system : AffineSystem
        The system (``A(t)``, ``C(t)``, ``B(t)``, ``f``); its noise enters only through ``design``.
    design : GaussianDesign
        The second moments the filter is designed for.
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``; ``None``: zero.
    """

    name = "unaware"

    def reset(self, xhat0: np.ndarray, one: np.ndarray) -> None:
        """Start a run from the initial estimate ``x̂(0)``.

        Parameters
        ----------
        xhat0 : numpy.ndarray
            Initial estimate, ``(n, K)`` (one column per scenario or affine coefficient).
        one : numpy.ndarray
            ``(K,)``: how a constant enters the columns (module docstring).
        """
        self.x, self.one = np.asarray(xhat0, float).copy(), np.asarray(one, float)
        self.P = self.design.P0.copy()

    def step(self, t: int, packets) -> tuple[np.ndarray, np.ndarray]:
        """Process the packets arriving at ``t``; return ``(x̂(t|I_t), x̂(t+1|I_t))``.

        Parameters
        ----------
        t : int
            Current time, ``0 <= t < T``.
        packets : sequence of tuple
            ``(τ, y(τ))`` pairs of the packets arriving at ``t``, ``y(τ)`` of shape ``(p, K)``.

        Returns
        -------
        tuple of numpy.ndarray
            Filtered and one-step predicted estimates, each ``(n, K)``.
        """
        sysm, d = self.system, self.design
        for _, y in sorted(packets, key=lambda pk: pk[0]):
            self.x, self.P = _kalman_update(self.x, self.P, np.asarray(y, float), sysm.C_at(t), d.R)
        filt = self.x
        A = sysm.A_at(t)
        self.x = A @ self.x + np.outer(self._drive(t), self.one)
        self.P = A @ self.P @ A.T + d.Q
        return filt, self.x


class RandomDelayLMV(_Base):
    """LMV estimator for random delays (ref. [9] of the delayed-data paper), on ``X = [x; z(t-1..t-τ̄)]``.

    The gains are those of the general form of Theorems 1 and 3 (``j = 0``) of the LMV study
    (:func:`~eqrec.lmv.recursion.lmv_recursion`, :func:`~eqrec.lmv.recursion.filter_smoother`); the model is in
    the module docstring.

    Parameters
    ----------
    system : AffineSystem
        The system; must be time-invariant.
    design : GaussianDesign
        Second moments: ``P0`` the covariance of ``x(0)``, ``Q`` of ``E w``, ``R`` of ``V v``.
    horizon : int
        Number of steps ``T`` (gains for ``t = 0..T-1``).
    max_delay : int
        ``τ̄``.
    x0_mean : numpy.ndarray
        Mean of ``x(0)``, ``(n,)`` (the LMV gains use the raw second moment ``E[X Xᵀ]``).
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``; ``None``: zero.
    probabilities : numpy.ndarray or None, optional
        ``p_d``, ``d = 0..τ̄``, ``(τ̄+1,)`` (default uniform ``1/(τ̄+1)``).
    """

    name = "random_delay_lmv"

    def __init__(self, system: AffineSystem, design: GaussianDesign, horizon: int, max_delay: int,
                 x0_mean: np.ndarray, inputs: np.ndarray | None = None, probabilities=None):
        super().__init__(system, design, inputs)
        from eqrec.lmv.model import MultNoiseSystem
        from eqrec.lmv.recursion import filter_smoother, lmv_recursion

        if system.is_time_varying:
            raise InputError("the random-delay LMV estimator needs a time-invariant system")
        n, p, tb = system.n, system.p, int(max_delay)
        pd = np.full(tb + 1, 1.0 / (tb + 1)) if probabilities is None else np.asarray(probabilities, float)
        if pd.shape != (tb + 1,) or np.any(pd < 0) or np.any(pd > 1):
            raise InputError(f"need {tb + 1} delay probabilities in [0, 1], got {pd}", field="probabilities")
        A, C, V = system.A, system.C, system.V
        N = n + tb * p
        Aa = np.zeros((N, N))
        Aa[:n, :n] = A
        if tb:
            Aa[n:n + p, :n] = C  # z(t) enters the first slot
            for d in range(1, tb):
                Aa[n + d * p:n + (d + 1) * p, n + (d - 1) * p:n + d * p] = np.eye(p)
        Cbar = np.zeros((p, N))
        Cbar[:, :n] = pd[0] * C
        Ck = np.zeros((tb + 1, p, N))
        Ck[0][:, :n] = C
        for d in range(1, tb + 1):
            Cbar[:, n + (d - 1) * p:n + d * p] = pd[d] * np.eye(p)
            Ck[d][:, n + (d - 1) * p:n + d * p] = np.eye(p)
        Rv = design.R  # covariance of V v
        Qu = np.zeros((N, N))
        Qu[:n, :n] = design.Q
        S = np.zeros((N, p))
        if tb:
            Qu[n:n + p, n:n + p] = Rv
            S[n:n + p] = pd[0] * Rv
        mean0 = np.zeros(N)
        mean0[:n] = np.asarray(x0_mean, float).reshape(n)
        cov0 = np.zeros((N, N))
        cov0[:n, :n] = design.P0
        self.model = MultNoiseSystem(A=Aa, Ak=np.zeros((tb + 1, N, N)), C=Cbar, Ck=Ck,
                                     W=np.diag(pd * (1 - pd)), Qu=Qu, R=pd[0] * Rv, S=S, x0_mean=mean0,
                                     x0_cov=cov0, n_x=n, name="random-delay")
        self.res = lmv_recursion(self.model, int(horizon) - 1, check_stability=False)
        self.Kf = filter_smoother(self.res, 0).K[:, 0]
        self.N, self.tb = N, tb

    def reset(self, xhat0: np.ndarray, one: np.ndarray) -> None:
        """Start a run from the initial estimate ``x̂(0)``.

        Parameters
        ----------
        xhat0 : numpy.ndarray
            Initial estimate, ``(n, K)`` (one column per scenario or affine coefficient).
        one : numpy.ndarray
            ``(K,)``: how a constant enters the columns (module docstring).
        """
        xhat0 = np.asarray(xhat0, float)
        self.one = np.asarray(one, float)
        self.X = np.zeros((self.N, xhat0.shape[1]))
        self.X[: self.system.n] = xhat0

    def step(self, t: int, packets) -> tuple[np.ndarray, np.ndarray]:
        """Process the packets arriving at ``t``; return ``(x̂(t|I_t), x̂(t+1|I_t))``.

        Parameters
        ----------
        t : int
            Current time, ``0 <= t < T``.
        packets : sequence of tuple
            ``(τ, y(τ))`` pairs of the packets arriving at ``t``, ``y(τ)`` of shape ``(p, K)``.
            Only the sum of the ``y`` enters (time stamps are not used).

        Returns
        -------
        tuple of numpy.ndarray
            Filtered and one-step predicted estimates, each ``(n, K)``.
        """
        n, p = self.system.n, self.system.p
        yr = np.zeros((p, self.X.shape[1]))
        for _, y in packets:
            yr = yr + np.asarray(y, float)
        eps = yr - self.model.C @ self.X
        filt = (self.X + self.Kf[t] @ eps)[:n]
        drive = np.zeros(self.N)
        drive[:n] = self._drive(t)
        self.X = self.model.A @ self.X + self.res.L[t] @ eps + np.outer(drive, self.one)
        return filt, self.X[:n]


FILTERS = {"timestamped": TimestampedKalman, "unaware": DelayUnawareKalman, "random_delay_lmv": RandomDelayLMV}


def make_filter(name: str, system: AffineSystem, design: GaussianDesign, *, horizon: int | None = None,
                max_delay: int | None = None, x0_mean=None, inputs=None):
    """A filter of :data:`FILTERS` by name (the LMV needs ``horizon``, ``max_delay`` and ``x0_mean``).

    Parameters
    ----------
    name : str
        ``"timestamped"``, ``"unaware"`` or ``"random_delay_lmv"``.
    system : AffineSystem
        The system.
    design : GaussianDesign
        Second moments of the design (e.g. :meth:`GaussianDesign.from_box`).
    horizon : int or None, optional
        Number of steps ``T`` (random-delay LMV only).
    max_delay : int or None, optional
        ``τ̄`` (random-delay LMV only; uniform delay probabilities).
    x0_mean : numpy.ndarray or None, optional
        Mean of ``x(0)``, ``(n,)`` (random-delay LMV only).
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``; ``None``: zero.

    Returns
    -------
    TimestampedKalman, DelayUnawareKalman or RandomDelayLMV
        The filter, to be reset and stepped (as :mod:`eqrec.filters.affine` does).
    """
    if name not in FILTERS:
        raise InputError(f"unknown filter {name!r}; choose one of {list(FILTERS)}", field="filter")
    if name == "random_delay_lmv":
        if horizon is None or max_delay is None or x0_mean is None:
            raise InputError("the random-delay LMV needs horizon, max_delay and x0_mean", field="filter")
        return RandomDelayLMV(system, design, horizon, max_delay, x0_mean, inputs)
    return FILTERS[name](system, design, inputs)
