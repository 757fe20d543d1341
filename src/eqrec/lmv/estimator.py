r"""The LMV filter and one-step predictor of the companion study in step form, and the batch run built on it.

:class:`LMVEstimator` follows the estimator protocol (:mod:`eqrec.estimators.protocol`,
``kind = "stochastic"``): ``reset(x̂0, t0)``, then one ``step(y, u)`` per time
with the measurement ``y(t)`` or ``None`` for a lost packet.  The
compensation of a loss is the one of the system the gains belong to
(:func:`~eqrec.lmv.model.system_of`):

* **zero-input** (eq. (3), Theorems 1-3 of the paper): a lost packet is
  ``y_z(t) = 0``;
* **hold-input** (ref. [15]): the estimator holds the last received value,
  ``y_h(t) = y_h(t-1)``, starting from ``y_h(-1)`` (the mean the system was
  built with, zero by default).

Each step forms the innovation ``ε(t) = y_c(t) − C x̂(t|t−1)`` and returns the
one-step prediction (eqs. (4)-(5))

.. math:: \hat x(t+1|t) = A \hat x(t|t-1) + L(t)\,\varepsilon(t)

with its error covariance ``P(t+1|t)`` (eq. (9)) on the plant state; the
filter ``x̂(t|t) = x̂(t|t−1) + K(t, 0) ε(t)`` (Theorem 3, ``j = 0``) is
:attr:`LMVEstimator.filtered` with ``P(t|t)`` in
:attr:`LMVEstimator.P_filtered`.  The gains are those of
:func:`~eqrec.lmv.recursion.lmv_recursion` (given, or computed step by step
by the same recursion, so the horizon is unbounded).  A packet that arrives
late counts as lost (the dropout model has no delays).  A call that raises
leaves the estimator as it was.

:func:`apply_estimator`, the batch run of the study (vectorised over runs,
with the fixed-lag smoother), is the step form run on already compensated
measurements: bit for bit the same estimates.
"""

from __future__ import annotations

import numpy as np

from eqrec.arrivals.packets import as_packets, plain_vector
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError
from eqrec.lmv.model import MultNoiseSystem, check_ms_stable
from eqrec.lmv.recursion import LMVResult, SmootherResult, lmv_step, moment_step, smoother_step

__all__ = ["COMPENSATIONS", "LMVEstimator", "apply_estimator"]

#: How a lost packet is replaced (``"none"``: every measurement must be given, already compensated).
COMPENSATIONS = ("zero-input", "hold-input", "none")


class LMVEstimator:
    """The LMV one-step predictor and filter in step form (module docstring).

    Parameters
    ----------
    sys : MultNoiseSystem
        The compensated system (:func:`~eqrec.lmv.model.zero_input_system`,
        :func:`~eqrec.lmv.model.hold_input_system`), or any system in the common description.
    result : LMVResult or None, optional
        Precomputed gains of ``sys`` (:func:`~eqrec.lmv.recursion.lmv_recursion`); beyond its horizon, and
        without it, the gains are computed by the same recursion as the steps go.
    compensation : {"zero-input", "hold-input", "none"} or None, optional
        What a lost packet becomes (default: the mechanism ``sys`` was built for, ``"none"`` for another system).
    system : AffineSystem or None, optional
        Known part of the dynamics: ``B(t) u(t) + f`` is added to the plant block of the prediction (``None``:
        no input).  The gains stay those of ``sys`` (whose second moment ``q`` does not see the input's mean).
    check_stability : bool, optional
        Refuse a system that is not mean-square stable when the gains are computed here (default ``True``;
        :class:`~eqrec.errors.NotMeanSquareStable`).

    Attributes
    ----------
    filtered : numpy.ndarray or None
        ``x̂(t|t)`` of the last step (plant state).
    P_filtered : numpy.ndarray or None
        ``P(t|t)`` of the last step (plant block).

    Raises
    ------
    InputError
        ``sys`` not a :class:`~eqrec.lmv.model.MultNoiseSystem`, ``system`` not an :class:`AffineSystem` of its
        plant's size, gains of another system, an unknown ``compensation`` (the field is named).
    """

    kind = "stochastic"

    def __init__(self, sys: MultNoiseSystem, result: LMVResult | None = None, *, compensation: str | None = None,
                 system: AffineSystem | None = None, check_stability: bool = True):
        if not isinstance(sys, MultNoiseSystem):
            raise InputError(f"expected a MultNoiseSystem (eqrec.lmv.model.zero_input_system, hold_input_system or "
                             f"system_of), got {type(sys).__name__}", field="sys")
        if system is not None and not isinstance(system, AffineSystem):
            raise InputError(f"expected an AffineSystem or None, got {type(system).__name__}", field="system")
        mech = sys.meta.get("mechanism", "none") if compensation is None else compensation
        if mech not in COMPENSATIONS:
            raise InputError(f"unknown compensation {mech!r}; one of {COMPENSATIONS}", sys.name, "compensation")
        if mech == "hold-input" and sys.n != sys.n_x + sys.m:
            raise InputError("hold-input compensation needs the augmented state [x; y_h] (hold_input_system)",
                             sys.name, "compensation")
        if result is not None and (not isinstance(result, LMVResult) or result.sys is not sys):
            raise InputError("need the LMVResult of this system (lmv_recursion(sys, N)) or None", sys.name, "result")
        if system is not None and system.n != sys.n_x:
            raise InputError(f"the system has n = {system.n} states, the LMV plant n_x = {sys.n_x}", sys.name,
                             "system")
        if result is None and check_stability:
            check_ms_stable(sys)
        self.sys, self.compensation, self.system = sys, mech, system
        self.name = "LMV" if mech == "none" else f"LMV, {mech}"
        if result is None:
            self._q = [np.outer(sys.x0_mean, sys.x0_mean) + sys.x0_cov]
            self._P, self._L, self._Qe = [sys.x0_cov], [], []
        else:
            self._q, self._P = list(result.q), list(result.P_pred)
            self._L, self._Qe = list(result.L), list(result.Qe)
        self._X: np.ndarray | None = None
        self._one: np.ndarray | None = None
        self.filtered: np.ndarray | None = None
        self.P_filtered: np.ndarray | None = None
        self._per_step: dict[int, tuple] = {}  # _step_matrices, by step index (the gains never change)

    # -- gains ----------------------------------------------------------------
    def _gains(self, k: int) -> tuple[np.ndarray, np.ndarray]:
        """``L(k)`` and ``Qe(k)``, extending the recursion of Theorem 1 as far as needed."""
        while len(self._L) <= k:
            j = len(self._L)
            Qe, L, P_next = lmv_step(self.sys, self._P[j], self._q[j])
            q_next = moment_step(self.sys, self._q[j]) if len(self._q) <= j + 1 else self._q[j + 1]
            self._Qe.append(Qe)
            self._L.append(L)
            if len(self._P) <= j + 1:
                self._P.append(P_next)
            if len(self._q) <= j + 1:
                self._q.append(q_next)
        return self._L[k], self._Qe[k]

    def _step_matrices(self, k: int) -> tuple:
        """What step ``k`` uses that depends on ``k`` alone, made once per estimator (a run started again with
        :meth:`reset` reuses it): the smoother's gain and ``P(t|t)`` (:func:`eqrec.lmv.recursion.smoother_step`)
        and the absolute values of ``A``, ``L(k)``, ``C`` and ``A − L(k) C`` of :meth:`_rounding`, each computed
        as it would be at the step (the same numbers)."""
        cached = self._per_step.get(k)
        if cached is None:
            sys = self.sys
            L, Qe = self._gains(k)
            K, P_filt, _ = smoother_step(sys, self._P[k], self._P[k], Qe, sys.A - L @ sys.C)
            cached = (K, P_filt, np.abs(sys.A), np.abs(L), np.abs(sys.C), np.abs(sys.A - L @ sys.C))
            self._per_step[k] = cached
        return cached

    # -- the protocol -----------------------------------------------------------
    def reset(self, xhat0: "np.ndarray | None" = None, t0: int = 0, one: "np.ndarray | None" = None,
              allowance=None) -> "LMVEstimator":
        """Start from ``x̂(t0|t0−1) = xhat0`` (the plant state; ``None``: its mean ``E[x(0)]``).

        Parameters
        ----------
        xhat0 : numpy.ndarray or None, optional
            Initial estimate, ``(n_x,)``, or ``(..., n_x)`` for runs advanced together (:meth:`advance`), or
            ``(n_x, K)`` columns with ``one`` (affine runs, as the filters of :mod:`eqrec.estimators.kalman`).
        t0 : int, optional
            Absolute time of the first step (default 0); the gains count from it.
        one : numpy.ndarray or None, optional
            ``(K,)``: an affine run, whose ``K`` columns carry a constant with these weights (the known input,
            ``f`` and the initial held measurement enter as ``outer(·, one)``); :meth:`step` then takes and
            returns columns (``eqrec.exact_bound`` runs it so).
        allowance : callable or None, optional
            The rounding formula (:func:`eqrec.bounds.rounding.rounding_allowance`, given by
            ``eqrec.exact_bound`` to an affine run): the estimator then carries :attr:`rounding_vector`, per plant
            state a bound on the rounding of its own arithmetic (eqs. (4)-(5) on every column, summed over the
            columns; the same linear maps on absolute values carry it, :mod:`eqrec.bounds.rounding`).

        Returns
        -------
        LMVEstimator
            The estimator itself.

        Raises
        ------
        InputError
            A non-finite or wrongly shaped ``xhat0``, a non-integer ``t0``.
        """
        sys, nx = self.sys, self.sys.n_x
        x = sys.x0_mean[:nx] if xhat0 is None else xhat0
        try:
            x = np.asarray(x, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"not numeric: {xhat0!r}", sys.name, "xhat0") from None
        if one is not None and x.ndim == 2:  # columns (n_x, K): checked as runs (K, n_x)
            x = x.T
        if x.ndim == 0 or x.shape[-1] != nx or not np.all(np.isfinite(x)):
            raise InputError(f"need {nx} finite entries (last axis), got shape {x.shape}", sys.name, "xhat0")
        if isinstance(t0, (bool, np.bool_)) or not isinstance(t0, (int, np.integer)):
            raise InputError(f"the start time is an integer, got {t0!r}", sys.name, "t0")
        if one is not None:  # an affine run: the columns are kept as runs (K, n_x) inside
            one = np.asarray(one, dtype=float)
            if x.ndim != 2 or one.shape != (x.shape[0],) or not np.all(np.isfinite(one)):
                raise InputError(f"columns need xhat0 of shape ({nx}, K) and one of shape (K,), got "
                                 f"{np.shape(xhat0)} and {one.shape}", sys.name, "one")
        rest = (np.broadcast_to(sys.x0_mean[nx:], x.shape[:-1] + (sys.n - nx,)) if one is None
                else np.outer(one, sys.x0_mean[nx:]))
        self._X = np.concatenate([x, rest], axis=-1)
        # y_h(-1) of the hold-input register (per column in an affine run)
        self._held = np.array(sys.x0_mean[nx:], float) if one is None else np.outer(one, sys.x0_mean[nx:])
        self._one = None if one is None else one.copy()
        self._allowance = allowance
        self._dev = None if allowance is None else np.zeros(sys.n)
        self._k, self._t0 = 0, int(t0)
        self.filtered = self.P_filtered = None
        return self

    def _running(self) -> np.ndarray:
        if self._X is None:
            raise InputError("call reset() before running the estimator", self.sys.name)
        return self._X

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        self._running()
        return self._t0 + self._k

    @property
    def x(self) -> np.ndarray:
        """A copy of the current prediction ``x̂(t|t−1)`` of the plant state (``(n_x, K)`` for an affine run)."""
        X = self._running()[..., : self.sys.n_x]
        return (X if getattr(self, "_one", None) is None else X.T).copy()

    @property
    def rounding_vector(self) -> "np.ndarray | None":
        """With an ``allowance`` given to :meth:`reset`: per plant state, a bound on the rounding of the current
        prediction's columns, summed over the columns (``None`` otherwise)."""
        dev = getattr(self, "_dev", None)
        return None if dev is None else dev[: self.sys.n_x].copy()

    @property
    def augmented(self) -> np.ndarray:
        """A copy of the whole state of the common description (``[x̂; ŷ_h]`` for hold-input)."""
        return self._running().copy()

    def _compensated(self, y, t: int) -> tuple[np.ndarray, bool]:
        """``(y_c(t), arrived)`` from what arrived (checked; late packets count as lost)."""
        m, one = self.sys.m, self._one
        shape = (m,) if one is None else (m, one.size)
        on_time = [pk.y if one is None else pk.y.T for pk in as_packets(y, t, shape) if pk.time == t]
        if on_time:
            return on_time[0], True
        if self.compensation == "none":
            raise InputError(f"no compensation: the measurement of time {t} must be given", self.sys.name, "y")
        zero = np.zeros(m) if one is None else np.zeros((one.size, m))
        return (zero if self.compensation == "zero-input" else self._held.copy()), False

    def _drive(self, t: int, u) -> np.ndarray | None:
        """``B(t) u + f`` (checked) or ``None`` without a known part."""
        if self.system is None:
            if u is not None:
                try:
                    uu = np.asarray(u, dtype=float)
                except (TypeError, ValueError):
                    raise InputError(f"not numeric: {u!r}", self.sys.name, "u") from None
                if uu.size and not (np.all(np.isfinite(uu)) and np.all(uu == 0)):
                    raise InputError("this estimator has no input model (give system=...)", self.sys.name, "u")
            return None
        m = self.system.m
        plain = None if u is None else plain_vector(u, (m,))  # a flat float vector in scale: read at once
        if plain is not None:
            return self.system.B_at(t) @ plain + self.system.f
        try:
            uu = np.zeros(m) if u is None else np.asarray(u, dtype=float).reshape(m)
        except (TypeError, ValueError):
            raise InputError(f"need {m} numbers, got {u!r}", self.sys.name, "u") from None
        if not np.all(np.isfinite(uu)):
            raise InputError("contains NaN or infinite entries", self.sys.name, "u")
        return self.system.B_at(t) @ uu + self.system.f

    def _predict(self, X: np.ndarray, y_c: np.ndarray, k: int, drive) -> tuple[np.ndarray, np.ndarray]:
        """Eqs. (4)-(5): ``(ε(t), x̂(t+1|t))`` without changing the estimator."""
        sys = self.sys
        L, _ = self._gains(k)
        eps = y_c - X @ sys.C.T
        X_next = X @ sys.A.T + eps @ L.T
        if drive is not None:
            X_next[..., : sys.n_x] += drive if self._one is None else np.outer(self._one, drive)
        return eps, X_next

    def _rounding(self, X: np.ndarray, y_c: np.ndarray, k: int, drive) -> np.ndarray:
        """The rounding allowance carried through eqs. (4)-(5) on the columns ``X`` (``(K, n)``): the deviation
        through ``|A − L C|`` (the map that carries an error of the estimate), plus the allowance of this step's products and sums on the columns'
        magnitudes."""
        sys = self.sys
        _, _, aA, aL, aC, aF = self._step_matrices(k)
        mag = np.abs(X).reshape(-1, sys.n).sum(axis=0)  # a plain run is one column
        mu = aA @ mag + aL @ (np.abs(y_c).reshape(-1, sys.m).sum(axis=0) + aC @ mag)
        if drive is not None:
            mu[: sys.n_x] += np.abs(drive) * (1.0 if self._one is None else np.abs(self._one).sum())
        return aF @ self._dev + self._allowance(0.0, sys.n + sys.m + 3, mu)

    def step(self, y=None, u=None) -> tuple[np.ndarray, np.ndarray]:
        """Process time ``t``: ``y(t)`` or ``None`` (lost), and the input; return ``(x̂(t+1|t), P(t+1|t))``.

        Parameters
        ----------
        y : numpy.ndarray, Packet, sequence of packets, or None, optional
            The measurement ``y(t)`` (``(m,)``), or ``None`` when the packet was lost (time-stamped packets are
            accepted: the on-time one is used, late ones count as lost).
        u : numpy.ndarray or None, optional
            The input ``u(t)`` (only with ``system``; otherwise ``None`` or zeros).

        Returns
        -------
        tuple of numpy.ndarray
            The prediction of the plant state, ``(n_x,)``, and its error covariance ``P(t+1|t)`` (plant block,
            ``(n_x, n_x)``); the filter is then :attr:`filtered`, :attr:`P_filtered`.

        Raises
        ------
        InputError
            Before :meth:`reset`, for runs reset together (use :meth:`advance`), a measurement or input of the
            wrong shape or not finite, a packet from the future; nothing changes.
        """
        X, sys = self._running(), self.sys
        if X.ndim != 1 and self._one is None:
            raise InputError("several runs were reset together: step them with advance()", sys.name, "y")
        t, k, nx = self.time, self._k, sys.n_x
        y_c, arrived = self._compensated(y, t)
        drive = self._drive(t, u)
        eps, X_next = self._predict(X, y_c, k, drive)
        K, P_filt = self._step_matrices(k)[:2]
        filtered = (X + np.einsum("ij,...j->...i", K, eps))[..., :nx]
        self.filtered = filtered if self._one is None else filtered.T
        self.P_filtered = P_filt[:nx, :nx].copy()
        if arrived and self.compensation == "hold-input":
            self._held = y_c.copy()
        if self._dev is not None:
            self._dev = self._rounding(X, y_c, k, drive)
        self._X, self._k = X_next, k + 1
        prediction = X_next[..., :nx] if self._one is None else X_next[:, :nx].T
        return prediction.copy(), self._P[k + 1][:nx, :nx].copy()

    def advance(self, y_c: np.ndarray) -> np.ndarray:
        """One step of runs advanced together on compensated measurements (no input): returns ``ε(t)``.

        Parameters
        ----------
        y_c : numpy.ndarray
            ``y_z(t)`` or ``y_h(t)`` of every run, ``(..., m)`` (the leading axes of :meth:`reset`).

        Returns
        -------
        numpy.ndarray
            The innovations ``ε(t)``, ``(..., m)``; the predictions are then :attr:`augmented`.
        """
        eps, self._X = self._predict(self._running(), y_c, self._k, None)
        self._k += 1
        return eps


def apply_estimator(res: LMVResult, y: np.ndarray, sm: SmootherResult | None = None) -> dict[str, np.ndarray]:
    """Run the estimator on measurements ``y[..., t, :]`` (``t = 0..T``), vectorised over leading axes.

    Eqs. (4)-(5) by the step form (:meth:`LMVEstimator.advance`, all runs together) and the fixed-lag
    smoother (17) in the general form.

    Parameters
    ----------
    res : LMVResult
        Gains of the one-step predictor.
    y : numpy.ndarray
        Measurements (``y_z`` or ``y_h``), ``(..., T+1, m)``.
    sm : SmootherResult or None, optional
        Smoother gains; ``None``: no filtered or smoothed estimates.

    Returns
    -------
    dict of str to numpy.ndarray
        ``pred[..., t, :] = xh(t|t-1)`` (``t = 0..T+1``), the innovations ``eps[..., t, :]`` and, with ``sm``,
        ``smooth[..., t, j, :] = xh(t|t+j)`` (NaN where ``t + j > T``; ``j = 0`` is the filter).
    """
    sys, T = res.sys, res.T
    y = np.asarray(y, float)
    if y.shape[-2:] != (T + 1, sys.m):
        raise InputError(f"measurements have shape {y.shape}, expected (..., {T + 1}, {sys.m})", None, "y")
    lead = y.shape[:-2]
    pred = np.empty(lead + (T + 2, sys.n))
    eps = np.empty(lead + (T + 1, sys.m))
    pred[..., 0, :] = sys.x0_mean
    est = LMVEstimator(sys, res, compensation="none").reset(pred[..., 0, : sys.n_x])
    for t in range(T + 1):
        eps[..., t, :] = est.advance(y[..., t, :])
        pred[..., t + 1, :] = est.augmented
    out = {"pred": pred, "eps": eps}
    if sm is not None:
        N = sm.K.shape[1] - 1
        smooth = np.full(lead + (T + 1, N + 1, sys.n), np.nan)
        acc = pred[..., : T + 1, :].copy()
        for j in range(N + 1):
            valid = T + 1 - j
            acc[..., :valid, :] = acc[..., :valid, :] + np.einsum(
                "tij,...tj->...ti", sm.K[:valid, j], eps[..., j: j + valid, :])
            smooth[..., :valid, j, :] = acc[..., :valid, :]
        out["smooth"] = smooth
    return out
