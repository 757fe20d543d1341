r"""The augmented estimator as it runs: P2 eqs. (2)-(3), P3 eqs. (4)-(5), on the shared packet intake.

The estimator carries ``x̂`` and an auxiliary state ``s`` (a Luenberger-like
estimate of the error :math:`\xi = x - \hat x`)::

    x̂(t+1) = A x̂(t) + B u(t) - ue(t) + f
    s(t+1)  = A s(t) + ue(t) + L_t z(t)
    ue(t)   = ν_t + Σ_{τ ∈ A(t)} M(t, τ) z(τ),   z(τ) = (y(τ) - C x̂(τ)) - C s(τ)

with ``A(t)`` the measurements available at ``t`` (P2 eq. (7), its eq. (2)
misprints ŷ; P3 eqs. (4)-(5)).  A measurement that has not arrived by ``t``
enters as ``ỹ(t) = 0``, i.e. ``z(t) = -C s(t)``; ``L_t`` is then zero
(``runtime="theorem2"``, P2 Theorem 2, P3 pattern (7)) or kept (``"hold"``).
The design of the gains, the model and the conversions to gain schedules are
in :mod:`eqrec.design.augmented` (this module reads the gains by their
fields, so the estimators' layer does not import the design).

It follows the protocol of :mod:`eqrec.estimators.protocol` on the shared
all-or-nothing intake (:mod:`eqrec.estimators.intake`): ``reset(xhat0,
t0=0)``, then ``step(y, u) -> (x̂(t+1), bound)``, with the bound of the
design's levels when given (``bound_of``, ``mu1``), else ``inf``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from eqrec.arrivals.packets import Stamped
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.errors import InputError
from eqrec.bounds.rounding import rounding_allowance
from eqrec.estimators.intake import BoundRule, StampedEstimator
from eqrec.systems.affine import AffineSystem

#: The readings of a missing step that can run (:mod:`eqrec.design.augmented.model`).
RUNTIME_MODES = ("theorem2", "hold")


def default_runtime(mode: str) -> str:
    """The runtime a design reading's gains run in unless told otherwise.

    Parameters
    ----------
    mode : str
        The design reading.

    Returns
    -------
    str
        ``"theorem2"`` for the ``"theorem2"`` reading, ``"hold"`` (the constant ``L`` kept) for the others.
    """
    return "theorem2" if mode == "theorem2" else "hold"


def as_time_varying_L(L: np.ndarray, T: int, n: int, p: int) -> np.ndarray:
    """Broadcast an observer gain ``L`` (``n x p`` or ``T x n x p``) to shape ``(T, n, p)``.

    Parameters
    ----------
    L : array_like
        ``(n, p)`` constant or ``(T, n, p)`` time-varying observer gain.
    T, n, p : int
        Horizon, state and output dimensions.

    Returns
    -------
    numpy.ndarray
        ``(T, n, p)`` copy of ``L``.

    Raises
    ------
    InputError
        A gain that is not numeric or has another shape (field ``L``).
    """
    try:
        L = np.asarray(L, dtype=float)
    except (TypeError, ValueError):
        raise InputError("the observer gain L is not numeric", field="L") from None
    if L.shape == (n, p):
        return np.broadcast_to(L, (T, n, p)).copy()
    if L.shape == (T, n, p):
        return L.copy()
    raise InputError(f"L must have shape ({n}, {p}) or ({T}, {n}, {p}), got {L.shape}", field="L")


class AugmentedEstimator(StampedEstimator):
    """The causal augmented estimator running both recursions (module docstring; P2 eqs. (2)-(3); P3 eqs. (4)-(5)).

    Parameters
    ----------
    system : AffineSystem
        The model.
    gains : AugmentedGains or AugmentedPrefixGains
        Designed gains (:mod:`eqrec.design.augmented.model`), read by their
        fields: one word's gains (``word``, ``M``, ``nu``, ``L``, ``s0``,
        ``mode``: measurements the designed word lacks are ignored, and only
        ``y(t)`` itself is taken, no late packet), or gains per event prefix
        (``rows``, ``L``, ``s0``: time-stamped packets).
    xhat0 : array_like, shape (n,), or None, optional
        Initial estimate (then the estimator is reset at once); ``None``
        (default): call :meth:`reset` before the first step.
    runtime : {"theorem2", "hold"} or None, optional
        Treatment of a step whose measurement is not on time (``L_k = 0``, or ``L`` kept with ``ỹ = 0``);
        default ``"theorem2"``, or for one word its design mode's runtime.
    t0 : int, optional
        Absolute time of the first step (default 0); packets stamped before it are dropped.
    bound_of : callable or None, optional
        ``bound_of(prefix) -> level``: the design's guarantee after an observed arrival prefix (with ``mu1``).
    mu1 : float or None, optional
        The design's recovery level: the bound at :meth:`reset` and at the horizon's end.

    Attributes
    ----------
    kind : str
        ``"guaranteed"``: the second value of :meth:`step` is a bound.
    name : str
        ``"augmented, one word"`` or ``"augmented, prefix gains"``.
    bound : float
        The bound of the current estimate: the level of the observed prefix with
        the levels, else ``inf`` (:mod:`eqrec.estimators.intake`).
    s : ndarray, shape (n,)
        The auxiliary state of the current time.

    Raises
    ------
    InputError
        Gains without the fields of either kind (field ``gains``), an unknown
        ``runtime`` (field ``mode``), a gain ``L`` of another shape.
    """

    _restart_hint = ""

    def __init__(self, system: AffineSystem, gains: Any, xhat0: "np.ndarray | None" = None,
                 runtime: "str | None" = None, t0: int = 0, *, bound_of: "BoundRule | None" = None,
                 mu1: "float | None" = None):
        if hasattr(gains, "rows") and hasattr(gains, "L") and hasattr(gains, "s0"):
            self.word = None
        elif all(hasattr(gains, f) for f in ("word", "M", "nu", "L", "s0", "mode")):
            self.word = str(gains.word)
        else:
            raise InputError(f"expected augmented gains (AugmentedGains or AugmentedPrefixGains), got "
                             f"{type(gains).__name__}", field="gains")
        runtime = runtime or ("theorem2" if self.word is None else default_runtime(gains.mode))
        if runtime not in RUNTIME_MODES:
            raise InputError(f"unknown augmented-estimator mode {runtime!r}; choose one of {list(RUNTIME_MODES)}",
                             field="mode")
        self.runtime = runtime
        self.gains = gains
        self.name = "augmented, one word" if self.word is not None else "augmented, prefix gains"
        T = len(self.word) if self.word is not None else len(gains.L)
        self.L = as_time_varying_L(gains.L, T, system.n, system.p)
        self._s0 = np.asarray(gains.s0, float).reshape(system.n).copy()
        self.s: "np.ndarray | None" = None
        super().__init__(system, T, xhat0, False, t0, bound_of, mu1)

    def _on_reset(self) -> None:
        self.s = self._s0.copy()

    def _reference(self, restarted: bool) -> np.ndarray:
        return np.stack((self.xhat, self.s))  # (x̂(τ), s(τ)): z(τ) = (y(τ) - C x̂(τ)) - C s(τ)

    def _residual(self, tau: int, y: np.ndarray, reference: np.ndarray) -> np.ndarray:
        C = self.system.C_at(tau)
        return (y - C @ reference[0]) - C @ reference[1]

    def _packets(self, y: Any) -> list[Stamped]:
        packets = super()._packets(y)
        if self.word is None:
            return packets
        if any(pk.time != self._k for pk in packets):
            raise InputError("an estimator of one word takes y(t) itself (or None), not time-stamped packets",
                             field="y")
        return packets if self._t < self.T and self.word[self._t] == "1" else []  # the word lacks y(t): ignored

    def step(self, y: Any = None, u: "np.ndarray | None" = None) -> tuple[np.ndarray, float]:
        """Process time ``t``: what arrived and the input; return ``x̂(t+1)`` and its bound.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            One word's gains: the measurement of ``t`` (``None`` if missing); prefix gains: the
            time-stamped packets ``(τ, y(τ))`` arriving at ``t`` (or ``y(t)`` itself, on time).
        u : array_like or None, optional
            Known input ``u(t)`` (default zero).

        Returns
        -------
        xhat : ndarray, shape (n,)
            The prediction ``x̂(t+1)`` (a copy).
        bound : float
            Its bound (:attr:`bound`).

        Raises
        ------
        InputError
            Before :meth:`reset`; past the horizon; a malformed measurement, input or packet, a packet
            from the future or a second one with one stamp; for one word's gains a late packet; for prefix
            gains an arrival prefix outside the design (nothing changes).
        """
        sysm = self.system
        n, p = sysm.n, sysm.p
        step = self._open(y, u)
        t, z = step.t, step.yxi
        C = sysm.C_at(t)
        on_time = step.arrivals[t] == t
        if not on_time:  # the innovation with ỹ(t) = 0
            z_missing = np.zeros(p) - C @ self.s
        if self.word is not None:  # ue(t) = ν_t + M(t, 0..t) z(0..t), zero columns at the missing steps
            z.setdefault(t, z_missing if not on_time else None)
            M, nu = self.gains.M[t * n:(t + 1) * n, : (t + 1) * p], self.gains.nu[t * n:(t + 1) * n]
            ue = nu + M @ np.concatenate([z[tau] for tau in range(t + 1)])
        else:
            pre = ArrivalPattern(tuple(step.arrivals))
            if pre not in self.gains.rows:
                raise InputError(f"arrival prefix {pre.label!r} at time {step.k} is not in the design", field="y")
            (M, nu), taus = self.gains.rows[pre], pre.available(t)
            ue = nu + M @ (np.concatenate([z[tau] for tau in taus]) if taus else np.zeros(0))
        Lt = self.L[t] if (on_time or self.runtime == "hold") else np.zeros((n, p))
        s_next = sysm.A_at(t) @ self.s + ue + Lt @ (z[t] if on_time else z_missing)
        xhat = sysm.A_at(t) @ self.xhat + sysm.B_at(t) @ step.u - ue + sysm.f
        rounding = self._rounding(step, M, nu, Lt, z if self.word is not None else
                                  {tau: z[tau] for tau in pre.available(t)}, None if on_time else z_missing)
        self._commit(step, rounding)
        self.s, self.xhat = s_next, xhat
        self.bound = self._with_rounding(self._level())
        return self.xhat.copy(), self.bound

    def _rounding(self, step, M: np.ndarray, nu: np.ndarray, Lt: np.ndarray, used: dict,
                  z_missing: "np.ndarray | None"):
        """The allowance of the augmented estimate (:mod:`eqrec.estimators.intake`), a priori over the horizon
        (the estimator runs one horizon): the magnitudes of ``x``, ``x̂``, ``s`` and of the innovations,
        propagated with absolute values (``record.maps``, per period time; the estimator's rounding at
        :meth:`reset` counts as one more step), and :func:`eqrec.bounds.rounding.rounding_allowance` of their
        sum with ``terms = (t + 3)(2n + m + (t+1) p + n_w + n_v + 4)``."""
        sysm, t, n, p = self.system, step.t, self.system.n, self.system.p
        record = self._period_record(step)
        if t == 0:
            record.maps = [(record.true[0], np.abs(self.xhat), np.abs(self.s))]
        absA, absB, absC, e, v, f = self._absolute_model(t)
        mx, mxhat, ms = record.maps[t]

        def innovation(tau: int, value: np.ndarray) -> np.ndarray:
            cx, cxh, cs = record.maps[tau]
            return np.abs(value) + self._absolute_model(tau)[2] @ (2.0 * cxh + 2.0 * cs + cx) + v

        mz = np.concatenate([innovation(tau, used[tau]) for tau in sorted(used)]) if used else np.zeros(0)
        mue = np.abs(nu) + (np.abs(M) @ mz if mz.size else 0.0)
        mzt = innovation(t, used[t]) if t in used and z_missing is None else absC @ ms
        drive = absB @ np.abs(step.u) + f
        record.maps.append((absA @ mx + drive + e, absA @ mxhat + drive + mue, absA @ ms + mue + np.abs(Lt) @ mzt))
        terms = (t + 3) * (2 * n + sysm.m + (t + 1) * p + sysm.nw + sysm.nv + 4)
        return record, rounding_allowance(0.0, terms, sum(record.maps[t + 1]))
