r"""Kalman-type estimators for delayed (out-of-sequence) and missing measurements.

Three estimators of the comparison of the delayed-data paper (Fig. 1, its
ref. [9]), each run on the packets that actually arrive:

``TimestampedKalman`` (``"timestamped"``, "Kalman, time-stamped")
    Uses each packet at its own time stamp: at time ``t`` it re-runs the
    Kalman filter over the measurements received so far (``y(τ)``,
    ``τ ∈ A(t)``), from the earliest stamp received at ``t`` (the filter
    before it is kept), so ``x̂(t|I_t)`` is the best linear (Gaussian:
    the conditional mean) estimate from the data received so far — the
    complete in-sequence re-filtering of ref. [6] of the paper, equal to a
    state augmented with the last ``τ̄`` states.
``DelayUnawareKalman`` (``"unaware"``, "Kalman, delay-unaware")
    A standard Kalman filter that treats whatever arrives at ``t`` as a
    measurement of the current state ``x(t)`` (several packets: sequential
    updates, oldest stamp first); nothing when nothing arrives.
``RandomDelayLMV`` (``"random_delay_lmv"``, "LMV, random delay")
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
(:class:`~eqrec.systems.noise.GaussianDesign`: ``5σ`` = bound, as in the
paper) and follows the estimator protocol (:mod:`eqrec.estimators.protocol`,
``kind = "stochastic"``): ``reset(x̂0, t0)``, then one ``step(y, u)`` per
time with what arrived (``None``, ``y(t)``, or time-stamped packets) and the
input, returning the prediction ``x̂(t+1|I_t)`` and its error covariance
``P(t+1|I_t)`` under the design statistics; the filtered ``x̂(t|I_t)`` is
:attr:`~_Filter.filtered`.  A call that raises leaves the filter as it was.

The same filters run on arrays of shape ``(dim, K)``: ``K`` scenarios at
once, or the ``1 + D`` coefficient columns of an affine map
(:mod:`eqrec.simulate.filter_runs`); ``reset(x̂0, t0, one=...)`` with ``x̂0`` of
shape ``(n, K)`` and the vector ``one`` (length ``K``) saying how a
constant enters (``1`` in every scenario, or only in the constant column).
A plain run is the case ``K = 1``, ``one = [1]``.
"""

from __future__ import annotations

import numpy as np

from eqrec.arrivals.packets import as_packets, in_scale, plain_vector
from eqrec.systems.noise import GaussianDesign
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


def _kalman_update(x, P, y, C, R, dev=None, allowance=None):
    S = C @ P @ C.T + R
    K = np.linalg.solve(S.T, (P @ C.T).T).T
    IKC = np.eye(P.shape[0]) - K @ C
    if allowance is not None:  # the rounding of x + K (y - C x), column by column, summed (module docstring)
        aK, aC = np.abs(K), np.abs(C)
        mag = np.abs(x).sum(axis=1)
        dev = _carry(dev, IKC, allowance(0.0, C.shape[1] + C.shape[0] + 2, mag + aK @ (np.abs(y).sum(axis=1)
                                                                                      + aC @ mag)))
    x = x + K @ (y - C @ x)
    P = IKC @ P @ IKC.T + K @ R @ K.T  # Joseph form
    return x, P, dev


def _predict_rounding(dev, x, A, drive, one, allowance):
    """The rounding allowance carried through ``A x + drive·oneᵀ`` (``None`` without an allowance)."""
    if allowance is None:
        return None
    return _carry(dev, A, allowance(0.0, A.shape[1] + 1, np.abs(A) @ np.abs(x).sum(axis=1)
                                    + np.abs(drive) * np.abs(one).sum()))


def _no_rounding(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The rounding history of a fresh estimate: none (see :func:`_carry`)."""
    return np.zeros((0, n, n)), np.zeros((0, n))


def _carry(dev, M, rho):
    """The rounding history ``(Φ, ρ)`` carried through the exact linear map ``M`` of a step, with that step's
    allowance ``rho`` added: each earlier rounding ``ρ_s`` reaches the estimate through the product ``Φ_s`` of
    the maps since, so the deviation is at most ``Σ_s |Φ_s| ρ_s`` (:func:`_deviation_of`), far below carrying
    the bound itself by ``|M|`` step by step (whose growth ignores the maps' cancellations)."""
    Phi, R = dev
    return np.concatenate([M @ Phi, np.eye(M.shape[0])[None]]), np.concatenate([R, rho[None]])


def _deviation_of(dev) -> np.ndarray:
    """``Σ_s |Φ_s| ρ_s``: the bound on the estimate's rounding from its history (:func:`_carry`)."""
    Phi, R = dev
    return np.einsum("kij,kj->i", np.abs(Phi), R)


def _finite(value, shape: tuple[int, ...], field: str) -> np.ndarray:
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise InputError(f"not numeric: {value!r}", field=field) from None
    if arr.shape != shape:
        if len(shape) == 1 and arr.size == shape[0]:
            arr = arr.reshape(shape)
        else:
            raise InputError(f"shape {arr.shape}, expected {shape}", field=field)
    if not np.all(np.isfinite(arr)):
        raise InputError("contains NaN or infinite entries", field=field)
    return arr


class _Filter:
    """The protocol shared by the three filters (module docstring): validation, the clock, the columns.

    Subclasses implement ``_start()`` (state after :meth:`reset`) and
    ``_advance(t, packets, drive)``, which computes the step without
    changing the filter and returns ``(filtered, prediction, covariance,
    commit)``; ``commit()`` stores the new state.
    """

    kind = "stochastic"
    name = ""
    key = ""
    #: With an ``allowance`` given to :meth:`reset`: per state, a bound on the rounding of the current
    #: prediction's columns, summed over the columns (``None`` otherwise).
    rounding_vector: "np.ndarray | None" = None

    def __init__(self, system: AffineSystem, design: GaussianDesign, inputs: np.ndarray | None = None):
        for key, value, kind in (("system", system, AffineSystem), ("design", design, GaussianDesign)):
            if not isinstance(value, kind):
                raise InputError(f"expected a {kind.__name__}, got {type(value).__name__}", field=key)
        self.system, self.design = system, design
        rows = len(inputs) if isinstance(inputs, (list, tuple, np.ndarray)) else 0
        self.inputs = None if inputs is None else _finite(inputs, (rows, system.m), "inputs")
        self._time: int | None = None
        self.filtered: np.ndarray | None = None

    def reset(self, xhat0: np.ndarray, t0: int = 0, one: np.ndarray | None = None,
              allowance=None) -> "_Filter":
        """Start a run from the initial estimate ``x̂(t0)``.

        Parameters
        ----------
        xhat0 : numpy.ndarray
            Initial estimate, ``(n,)`` (a plain run) or ``(n, K)`` (one column per scenario or affine coefficient).
        t0 : int, optional
            Absolute time of the first step (default 0).
        one : numpy.ndarray or None, optional
            ``(K,)``: how a constant enters the columns (module docstring); default ones.
        allowance : callable or None, optional
            The rounding formula (:func:`eqrec.bounds.rounding.rounding_allowance`): given, the filter carries
            :attr:`rounding_vector`, a bound on the rounding of its own arithmetic, summed over the columns
            (``eqrec.exact_bound`` passes it); ``None``: not carried.

        Returns
        -------
        _Filter
            The filter itself.

        Raises
        ------
        InputError
            A non-finite or wrongly shaped ``xhat0`` or ``one``, or a non-integer ``t0``.
        """
        n = self.system.n
        try:
            x = np.asarray(xhat0, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"not numeric: {xhat0!r}", field="xhat0") from None
        if x.ndim not in (1, 2) or x.shape[0] != n:
            raise InputError(f"shape {x.shape}, expected ({n},) or ({n}, K)", field="xhat0")
        x = in_scale(_finite(x, x.shape, "xhat0"), "xhat0", "the initial estimate")
        K = 1 if x.ndim == 1 else x.shape[1]
        one = np.ones(K) if one is None else _finite(one, (K,), "one")
        if isinstance(t0, (bool, np.bool_)) or not isinstance(t0, (int, np.integer)):
            raise InputError(f"the start time is an integer, got {t0!r}", field="t0")
        self._vector = x.ndim == 1
        self.xhat0 = x.reshape(n, 1) if self._vector else x
        self.one = one
        self._allowance = allowance
        self.rounding_vector = None if allowance is None else np.zeros(n)
        self._time, self._t0 = int(t0), int(t0)
        self.filtered = None
        self._start()
        return self

    def _start(self) -> None:
        raise NotImplementedError

    def _advance(self, t: int, packets: list, drive: np.ndarray):
        raise NotImplementedError

    def _prediction(self) -> np.ndarray:
        raise NotImplementedError

    def _deviation(self) -> np.ndarray:
        raise NotImplementedError

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        if self._time is None:
            raise InputError("call reset(xhat0) before running the filter")
        return self._time

    @property
    def x(self) -> np.ndarray:
        """A copy of the current prediction ``x̂(t|I_{t-1})`` (``(n,)``, or ``(n, K)`` for columns)."""
        self.time  # noqa: B018 - raises before reset
        return self._out(self._prediction()).copy()

    def _out(self, X: np.ndarray) -> np.ndarray:
        return X[:, 0] if self._vector else X

    def _drive(self, t: int, u=None) -> np.ndarray:
        """Known part ``B u(t) + f`` of the dynamics (``u = None``: the inputs given at construction, else zero)."""
        if u is None:
            if self.inputs is not None and not 0 <= t < len(self.inputs):
                raise InputError(f"the inputs given at construction cover times 0..{len(self.inputs) - 1}, not {t}",
                                 field="inputs")
            u = np.zeros(self.system.m) if self.inputs is None else self.inputs[t]
        return self.system.B_at(t) @ u + self.system.f

    def step(self, y=None, u=None) -> tuple[np.ndarray, np.ndarray]:
        """Process time ``t``: what arrived and the input; return ``(x̂(t+1|I_t), P(t+1|I_t))``.

        Parameters
        ----------
        y : numpy.ndarray, Packet, sequence of packets, or None, optional
            What arrived at ``t``: ``None``, ``y(t)`` (``(p,)``, or ``(p, K)``
            for columns), or time-stamped packets ``(τ, y(τ))``, ``τ <= t``.
        u : numpy.ndarray or None, optional
            The input ``u(t)``, ``(m,)`` (``None``: the inputs given at construction, else zero).

        Returns
        -------
        tuple of numpy.ndarray
            The prediction (``(n,)`` or ``(n, K)``) and its error covariance ``(n, n)`` under the design
            statistics; the filtered estimate is then :attr:`filtered`.

        Raises
        ------
        InputError
            Before :meth:`reset`; a measurement or input of the wrong shape or not finite, a stamp from the
            future or given twice (the filter is left unchanged).
        """
        t = self.time
        sysm = self.system
        shape = (sysm.p,) if self._vector else (sysm.p, self.one.size)
        packets = as_packets(y, t, shape)
        if self._vector:
            packets = [(pk.time, pk.y.reshape(sysm.p, 1)) for pk in packets]
        else:
            packets = [(pk.time, pk.y) for pk in packets]
        if u is not None:  # a plain float vector in scale at once, anything else through the general checks
            plain = plain_vector(u, (sysm.m,))
            u = plain if plain is not None else in_scale(_finite(u, (sysm.m,), "u"), "u", "the input u")
        drive = self._drive(t, u)
        filt, pred, P, commit = self._advance(t, packets, drive)
        commit()
        if self._allowance is not None:
            self.rounding_vector = self._deviation()
        self._time = t + 1
        self.filtered = self._out(filt).copy()
        return self._out(pred).copy(), P.copy()


class TimestampedKalman(_Filter):
    """Kalman filter using every packet at its own time (re-filtering from the earliest new stamp at each step).

    Parameters
    ----------
    system : AffineSystem
        The system (``A(t)``, ``C(t)``, ``B(t)``, ``f``); its noise enters only through ``design``.
    design : GaussianDesign
        The second moments the filter is designed for.
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``, used when :meth:`step` gets no ``u``; ``None``: zero.
    """

    name = "Kalman, time-stamped"
    key = "timestamped"

    def _start(self) -> None:
        self.received: dict[int, np.ndarray] = {}
        self._drives: list[np.ndarray] = []
        # the prediction of t0 + k before its update, its covariance and its rounding (None: not carried)
        dev0 = None if self._allowance is None else _no_rounding(self.system.n)
        self._pre = [(self.xhat0.copy(), self.design.P0.copy(), dev0)]

    def _prediction(self) -> np.ndarray:
        return self._pre[-1][0]

    def _deviation(self) -> np.ndarray:
        return _deviation_of(self._pre[-1][2])

    def _advance(self, t, packets, drive):
        sysm, d, t0 = self.system, self.design, self._t0
        new = {}
        for tau, y in packets:
            if tau < t0:
                continue  # stamped before the run started
            if tau in self.received:
                raise InputError(f"a second packet stamped {tau} received at time {t}", field="y")
            new[int(tau)] = y
        received = {**self.received, **new}
        drives = self._drives + [drive]
        s = min([*new, t])
        x, P, dev = self._pre[s - t0]
        pre = self._pre[: s - t0 + 1]
        filt = x
        for tau in range(s, t + 1):
            if tau in received:
                x, P, dev = _kalman_update(x, P, received[tau], sysm.C_at(tau), d.R, dev, self._allowance)
            if tau == t:
                filt = x
            A = sysm.A_at(tau)
            dev = _predict_rounding(dev, x, A, drives[tau - t0], self.one, self._allowance)
            x = A @ x + np.outer(drives[tau - t0], self.one)
            P = A @ P @ A.T + d.Q
            pre.append((x, P, dev))

        def commit():
            self.received, self._drives, self._pre = received, drives, pre
        return filt, x, P, commit


class DelayUnawareKalman(_Filter):
    """Kalman filter treating every packet arriving at ``t`` as a measurement of ``x(t)``.

    Parameters
    ----------
    system : AffineSystem
        The system (``A(t)``, ``C(t)``, ``B(t)``, ``f``); its noise enters only through ``design``.
    design : GaussianDesign
        The second moments the filter is designed for.
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``, used when :meth:`step` gets no ``u``; ``None``: zero.
    """

    name = "Kalman, delay-unaware"
    key = "unaware"

    def _start(self) -> None:
        self.X, self.P = self.xhat0.copy(), self.design.P0.copy()
        self._dev = None if self._allowance is None else _no_rounding(self.system.n)

    def _prediction(self) -> np.ndarray:
        return self.X

    def _deviation(self) -> np.ndarray:
        return _deviation_of(self._dev)

    def _advance(self, t, packets, drive):
        sysm, d = self.system, self.design
        x, P, dev = self.X, self.P, self._dev
        for _, y in sorted(packets, key=lambda pk: pk[0]):
            x, P, dev = _kalman_update(x, P, y, sysm.C_at(t), d.R, dev, self._allowance)
        filt = x
        A = sysm.A_at(t)
        dev = _predict_rounding(dev, x, A, drive, self.one, self._allowance)
        x = A @ x + np.outer(drive, self.one)
        P = A @ P @ A.T + d.Q

        def commit():
            self.X, self.P, self._dev = x, P, dev
        return filt, x, P, commit


class RandomDelayLMV(_Filter):
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

    name = "LMV, random delay"
    key = "random_delay_lmv"

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
        A, C = system.A, system.C
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

    def _start(self) -> None:
        self.X = np.zeros((self.N, self.xhat0.shape[1]))
        self.X[: self.system.n] = self.xhat0
        self._dev = None if self._allowance is None else np.zeros(self.N)

    def _prediction(self) -> np.ndarray:
        return self.X[: self.system.n]

    def _deviation(self) -> np.ndarray:
        return self._dev[: self.system.n]

    def _advance(self, t, packets, drive):
        n, p, k = self.system.n, self.system.p, t - self._t0
        if k >= self.Kf.shape[0]:
            raise InputError(f"the gains cover {self.Kf.shape[0]} steps from t0 = {self._t0}; time {t} is past them",
                             field="horizon")
        yr = np.zeros((p, self.X.shape[1]))
        for _, y in packets:  # only the sum enters (time stamps are not used)
            yr = yr + y
        eps = yr - self.model.C @ self.X
        filt = (self.X + self.Kf[k] @ eps)[:n]
        full = np.zeros(self.N)
        full[:n] = drive
        X = self.model.A @ self.X + self.res.L[k] @ eps + np.outer(full, self.one)
        P = self.res.P_pred[k + 1][:n, :n]
        dev = self._dev
        if self._allowance is not None:  # A X + L (y - C X) + drive, column by column, summed
            aA, aL, aC = np.abs(self.model.A), np.abs(self.res.L[k]), np.abs(self.model.C)
            mag = np.abs(self.X).sum(axis=1)
            dev = np.abs(self.model.A - self.res.L[k] @ self.model.C) @ dev + self._allowance(
                0.0, self.N + p + 3 + len(packets), aA @ mag + aL @ (np.abs(yr).sum(axis=1) + aC @ mag)
                + np.abs(full) * np.abs(self.one).sum())

        def commit():
            self.X, self._dev = X, dev
        return filt, X[:n], P, commit


#: The filters by key.
FILTERS = {cls.key: cls for cls in (TimestampedKalman, DelayUnawareKalman, RandomDelayLMV)}


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
        The filter, to be reset and stepped (as :mod:`eqrec.simulate.filter_runs` does).
    """
    if name not in FILTERS:
        raise InputError(f"unknown filter {name!r}; choose one of {list(FILTERS)}", field="filter")
    if name == "random_delay_lmv":
        if horizon is None or max_delay is None or x0_mean is None:
            raise InputError("the random-delay LMV needs horizon, max_delay and x0_mean", field="filter")
        return RandomDelayLMV(system, design, horizon, max_delay, x0_mean, inputs)
    return FILTERS[name](system, design, inputs)
