r"""State-augmented equalized-recovery estimator (the *augmented paper*, eqs. (2)-(3), (9)-(10)).

The estimator carries ``x̂`` and an auxiliary state ``s`` (a Luenberger-like
estimate of the error :math:`\xi = x - \hat x`)::

    x̂(k+1) = A x̂(k) + B u(k) - ue(k) + f
    s(k+1)  = A s(k) + ue(k) + L_k (ỹ(k) - C s(k))              (eq. (7); eq. (2) prints ŷ, a misprint)
    ue(k)   = ν_k + Σ_{i<=k} M(k,i) (ỹ(i) - C s(i))             (eq. (3))

with :math:`\tilde y = y - C\hat x` (the core's :math:`y_\xi`).  With
:math:`e = \xi - s` the error of ``s``, :math:`\Phi_k = A_k - L_k C_k` and
:math:`z_k = \tilde y_k - C s_k = C e_k + V v_k` (eq. (9)):

.. math:: e_{k+1} = \Phi_k e_k + W w_k - L_k V v_k, \qquad
          \xi = \mathrm{Ol}\,\delta + S(\nu + M z),

so for fixed ``L`` and ``s0`` the error is affine in ``(M, ν)`` with
``z`` independent of them: a Q-parametrisation in which the innovation
``z`` plays the role of the open-loop output (Theorem 1).

Missing data (Theorem 2) and readings of the text
--------------------------------------------------
``mode`` selects how a step ``k`` whose measurement is missing is treated:

``"theorem2"``
    The text of Theorem 2: ``M(., k) = 0`` and ``L_k = 0`` (so
    :math:`\Phi_k = A_k` and ``s(k+1) = A s(k) + ue(k)``).  Implementable;
    the runtime sets ``ỹ(k) = 0``.
``"hold"``
    A *constant* ``L`` kept at missing steps with ``ỹ(k) = 0``:
    ``s(k+1) = (A - L C) s(k) + ue(k)``.  Implementable (this is what a
    single printed ``L`` implies at run time); ``e`` is then no longer
    independent of ``M`` so it has no LP of its own, but its gains are
    reachable through :func:`time_based_to_augmented`.
``"leak"``
    The stacked formulas (5) with only ``M Λ_i = 0`` imposed and a constant
    ``L`` at the missing steps: the design's ``s`` receives
    ``L_k (C e_k + V v_k)`` at a missing step, i.e. the missing measurement.
    Not implementable; its gains run as the actual estimator in ``"hold"``
    (or ``"theorem2"``) mode, where they guarantee what the certificate says.
``"masked_gain"``
    The Appendix's stacked matrices read with the transition products
    ``Φ_i^k``, ``Γ`` built from ``Φ_k = A_k - L C_k`` at *every* step while
    the gain on the measurement (the block-diagonal ``L`` of the ``Γ L V``
    and ``(M + L)`` terms) is zeroed at missing steps: ``e(k+1) = (A - L C)
    e(k) + W w(k)`` there.  What an implementation forming ``Φ`` from the
    constant ``L`` and masking only the measurement term designs; not the
    estimator that runs (at a missing step ``s`` has no measurement), so its
    gains are certified in ``"hold"`` (or ``"theorem2"``) mode.

Equivalence with the time-based estimator
-----------------------------------------
``s`` is a causal affine function of past ``ỹ`` and ``s0``, hence so is
``ue``: every augmented estimator (implementable modes) *is* a time-based
estimator ``ue = u0 + F ỹ`` (:func:`augmented_to_time_based`).  Conversely,
for given ``L`` and ``s0`` the map ``ỹ -> z`` is affine with unit block
lower-triangular linear part, so every time-based ``(F, u0)`` has a unique
``(M, ν)`` (:func:`time_based_to_augmented`).  Consequently, for every ``L``
and ``s0``, the optimal ``μ2`` of the augmented estimator equals the
time-based optimum on the same word.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from eqrec.errors import InputError
from eqrec.core.gains import GainSchedule, schedule_from_word_gains
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.prefix_tree import PrefixTree
from eqrec.core.words import as_pattern
from eqrec.core.stacking import Stacking
from eqrec.core.systems import AffineSystem

MODES = ("theorem2", "hold", "leak", "masked_gain")
RUNTIME_MODES = ("theorem2", "hold")
#: Readings whose error ``e`` of ``s`` does not depend on ``M`` (an LP for fixed ``L``).
DESIGN_MODES = ("theorem2", "leak", "masked_gain")


def check_mode(mode: str, allowed: tuple[str, ...] = MODES) -> str:
    """Validate a missing-step reading (see the module docstring)."""
    if mode not in allowed:
        raise InputError(f"unknown augmented-estimator mode {mode!r}; choose one of {list(allowed)}", field="mode")
    return mode


def as_time_varying_L(L: np.ndarray, T: int, n: int, p: int) -> np.ndarray:
    """Broadcast an observer gain ``L`` (``n x p`` or ``T x n x p``) to shape ``(T, n, p)``."""
    try:
        L = np.asarray(L, dtype=float)
    except (TypeError, ValueError):
        raise InputError("the observer gain L is not numeric", field="L") from None
    if L.shape == (n, p):
        return np.broadcast_to(L, (T, n, p)).copy()
    if L.shape == (T, n, p):
        return L.copy()
    raise InputError(f"L must have shape ({n}, {p}) or ({T}, {n}, {p}), got {L.shape}", field="L")


def missing_data_pattern(word: "ArrivalPattern | str") -> ArrivalPattern:
    """The pattern of ``word``, which must be a missing-data pattern (each measurement on time or never).

    The augmented estimator of the augmented paper uses ``ỹ(k)`` at step ``k``
    only; delayed measurements need the event-based design of the
    delayed-data paper (``eqrec design --method prefix`` with delay words).
    """
    pattern = as_pattern(word)
    if not pattern.is_missing_data:
        raise InputError(f"pattern {pattern.label!r} has delayed measurements; the augmented estimator of the "
                         "augmented paper handles missing data only (use the prefix-based design for delays)",
                         field="words")
    return pattern


def arrival_indicator(word: "ArrivalPattern | str") -> np.ndarray:
    """``q(k)`` (1 if the measurement of step ``k`` arrives) of a missing-data pattern."""
    pattern = missing_data_pattern(word)
    return np.array([1 if pattern.arrives(k) else 0 for k in range(pattern.T)])


def effective_L(L: np.ndarray, word: str, mode: str) -> np.ndarray:
    """``L_k`` multiplying the measurement: zeroed at missing steps in ``"theorem2"`` (eq. (12)) and ``"masked_gain"``."""
    L = np.array(L, dtype=float)
    if mode in ("theorem2", "masked_gain"):
        for k, q in enumerate(word):
            if q == "0":
                L[k] = 0.0
    return L


@dataclass
class AugmentedGains:
    """Gains ``(M, ν, L, s0)`` of the augmented estimator along one word (eq. (3)).

    Attributes
    ----------
    word
        The designed (worst-case) word; ``M`` has zero columns at its missing steps.
    L : ndarray, shape (T, n, p)
        Observer gains ``L_k``.
    s0 : ndarray, shape (n,)
    M : ndarray, shape (Tn, Tp)
        Block lower-triangular injection gains ``M(k, i)``.
    nu : ndarray, shape (Tn,)
    mode
        Missing-step reading used by the design.
    """

    word: str
    L: np.ndarray
    s0: np.ndarray
    M: np.ndarray
    nu: np.ndarray
    mode: str = "theorem2"
    extra: dict = field(default_factory=dict)

    @property
    def T(self) -> int:
        return len(self.word)


# ---------------------------------------------------------------------------
# Stacked maps (eqs. (9)-(10) and Appendix)
# ---------------------------------------------------------------------------

class AugmentedStacking:
    """Stacked matrices of the augmented estimator on one word, built on :class:`eqrec.stacking.Stacking`.

    Parameters
    ----------
    system
        The system (time-varying allowed).
    word
        Word of length ``T`` (``q_k``).
    L
        Observer gain, ``n x p`` (constant) or ``T x n x p``.
    mode
        One of :data:`DESIGN_MODES` (the readings whose ``e`` is independent of ``M``).
    stacking
        Optional core stacking to reuse.
    """

    def __init__(self, system: AffineSystem, word: str, L: np.ndarray, mode: str = "theorem2",
                 stacking: Stacking | None = None):
        word = missing_data_pattern(word).label
        check_mode(mode, DESIGN_MODES)
        self.system, self.word, self.mode = system, word, mode
        self.T = T = len(word)
        self.st = stacking if stacking is not None and stacking.T == T else Stacking(system, T)
        n, p = system.n, system.p
        self.L = as_time_varying_L(L, T, n, p)
        self.L_eff = effective_L(self.L, word, mode)
        # the transition keeps L at every step in the "masked_gain" reading
        L_phi = self.L if mode == "masked_gain" else self.L_eff
        self.Phi = np.stack([system.A_at(k) - L_phi[k] @ system.C_at(k) for k in range(T)])
        self._propagate()

    def _propagate(self) -> None:
        sys, lay, T, n = self.system, self.st.layout, self.T, self.system.n
        D = lay.size
        Ge = np.zeros((T + 1, n, D))
        He = np.zeros((T + 1, n, n))  # e(k) = Ge[k] δ + He[k] s0
        Ge[0][:, lay.xi0] = np.eye(n)
        He[0] = -np.eye(n)
        for k in range(T):
            Ge[k + 1] = self.Phi[k] @ Ge[k]
            Ge[k + 1][:, lay.w(k)] += sys.E_at(k)
            Ge[k + 1][:, lay.v(k)] -= self.L_eff[k] @ sys.V_at(k)
            He[k + 1] = self.Phi[k] @ He[k]
        self.Ge, self.He = Ge, He
        Z = np.einsum("kpn,knd->kpd", np.stack([sys.C_at(k) for k in range(T)]), Ge[:T])
        for k in range(T):
            Z[k][:, lay.v(k)] += sys.V_at(k)
        self.Z = Z  # z(k) = Z[k] δ + Zs[k] s0 (innovation, eq. (9))
        self.Zs = np.einsum("kpn,knm->kpm", np.stack([sys.C_at(k) for k in range(T)]), He[:T])
        self.G0 = self.st.open_loop.reshape((T + 1) * n, -1)  # constant part of G
        self.Hs = np.zeros(((T + 1) * n, n))  # constant part of c per unit s0
        if self.mode == "masked_gain":
            self._literal_maps()

    # -- the error as a function of (M, ν, s0) ---------------------------------
    def error_map(self, M: np.ndarray, nu: np.ndarray, s0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Eq. (10): ``ξ = G δ + c`` with ``G`` of shape ``((T+1)n, D)`` in the core δ layout."""
        T, n, p = self.T, self.system.n, self.system.p
        s0 = np.asarray(s0, float)
        Zst = self.Z.reshape(T * p, -1)
        z0 = self.Zs.reshape(T * p, n) @ s0
        G = self.G0 + self.st.S @ M @ Zst
        c = self.st.S @ (nu + M @ z0) + self.Hs @ s0
        return G, c

    def appendix_matrices(self) -> dict[str, np.ndarray]:
        """The Appendix's stacked matrices with the time-varying ``Φ_k`` of this reading.

        ``E`` (``A_i^k`` blocks, the core's ``S``), ``A`` (the core's ``J``),
        ``Gamma`` (``Φ_{t-1} ... Φ_{s+1}`` blocks), ``Phi`` (``Φ_{k-1} ... Φ_0``),
        ``C``, ``L`` (block diagonal of the measurement gains ``L_k``, zero at
        missing steps in ``"theorem2"`` and ``"masked_gain"``), ``W``, ``V``.
        """
        sys, T, n = self.system, self.T, self.system.n
        Gam = np.zeros(((T + 1) * n, T * n))
        Phibig = [np.eye(n)]
        for k in range(T):
            Phibig.append(self.Phi[k] @ Phibig[-1])
        for t in range(1, T + 1):
            P = np.eye(n)
            for s in range(t - 1, -1, -1):  # block (t, s) = Φ_{t-1} ... Φ_{s+1}
                Gam[t * n:(t + 1) * n, s * n:(s + 1) * n] = P
                P = P @ self.Phi[s]
        return {"E": self.st.S, "A": self.st.J, "Gamma": Gam, "Phi": np.vstack(Phibig),
                "C": np.hstack([sla.block_diag(*[sys.C_at(k) for k in range(T)]), np.zeros((T * sys.p, n))]),
                "L": sla.block_diag(*self.L_eff), "W": self.st.E_blk,
                "V": sla.block_diag(*[sys.V_at(k) for k in range(T)])}

    def paper_blocks(self, M: np.ndarray) -> dict[str, np.ndarray]:
        """Eq. (5) literally: ``Θ, Ψ, Ξ, Υ`` from the Appendix matrices with time-varying ``Φ_k``.

        ``C``, ``V`` and ``W`` are unmasked; missing data enters only through
        ``M Λ_i = 0`` and the block-diagonal ``L`` (zero at missing steps in
        ``"theorem2"`` and ``"masked_gain"``; the transition ``Φ_k`` keeps ``L``
        in ``"masked_gain"``).
        """
        m = self.appendix_matrices()
        Ebig, Abig, Gam, Phib, Cbig, Lbig, Wbig, Vbig = (m[k] for k in ("E", "A", "Gamma", "Phi", "C", "L", "W", "V"))
        I = np.eye(Abig.shape[0])
        ML = M + Lbig
        Theta = (I + Ebig @ ML @ Cbig) @ Gam @ Wbig
        Psi = (Ebig @ ML @ (np.eye(Cbig.shape[0]) - Cbig @ Gam @ Lbig) - Gam @ Lbig) @ Vbig
        Xi = (I + Ebig @ ML @ Cbig) @ Phib
        Ups = Abig - Xi
        return {"Theta": Theta, "Psi": Psi, "Xi": Xi, "Upsilon": Ups, "E": Ebig, "Gamma": Gam, "Phi": Phib}

    def _literal_maps(self) -> None:
        """``G = G0 + E M Z``, ``c = E ν - E M (CΦ) s0 + H s0`` read off the Appendix blocks (eq. (5)).

        For the consistent readings these equal the dynamics' open-loop and
        innovation maps (a test checks it); for ``"masked_gain"`` they are the
        definition of the reading.
        """
        m = self.appendix_matrices()
        Ebig, Abig, Gam, Phib, Cbig, Lbig, Wbig, Vbig = (m[k] for k in ("E", "A", "Gamma", "Phi", "C", "L", "W", "V"))
        T, n, p = self.T, self.system.n, self.system.p
        I = np.eye(Abig.shape[0])
        ELC = Ebig @ Lbig @ Cbig
        CGL = np.eye(T * p) - Cbig @ Gam @ Lbig
        self.G0 = np.hstack([(I + ELC) @ Gam @ Wbig, (Ebig @ Lbig @ CGL - Gam @ Lbig) @ Vbig, (I + ELC) @ Phib])
        self.Z = np.hstack([Cbig @ Gam @ Wbig, CGL @ Vbig, Cbig @ Phib]).reshape(T, p, -1)
        self.Zs = -(Cbig @ Phib).reshape(T, p, n)
        self.Hs = Abig - Phib - ELC @ Phib

# ---------------------------------------------------------------------------
# Conversion between augmented and time-based gains
# ---------------------------------------------------------------------------

def _masked_L(gains_L: np.ndarray, word: str, runtime: str) -> np.ndarray:
    return effective_L(gains_L, word, "theorem2" if runtime == "theorem2" else "hold")


def _innovation_recursion(system: AffineSystem, word: str, Lt: np.ndarray, s0: np.ndarray, injection):
    r"""Propagate ``s(k) = Sy ỹ + sc`` through eqs. (2)-(3) for an injection rule.

    At each step the innovation ``z(k) = q(k) ỹ(k) - C s(k)`` is affine in the
    stacked ``ỹ``: ``z = Z ỹ + zc`` (rows of step ``k`` filled here), and
    ``injection(k, Z, zc)`` returns the time-based gain row ``(F_k, u0_k)`` of
    ``ue(k) = u0_k + F_k ỹ``.  Shared by both conversion directions.

    Returns ``Z`` (``Tp x Tp``, unit block lower triangular on measured steps) and ``zc``.
    """
    T, n, p = len(word), system.n, system.p
    q = arrival_indicator(word)
    Sy = np.zeros((n, T * p))
    sc = np.asarray(s0, float).reshape(n).copy()
    Z = np.zeros((T * p, T * p))
    zc = np.zeros(T * p)
    for k in range(T):
        C = system.C_at(k)
        rows = slice(k * p, (k + 1) * p)
        Z[rows] = -C @ Sy
        if q[k]:
            Z[rows, rows] += np.eye(p)
        zc[rows] = -C @ sc
        Fk, uk = injection(k, Z, zc)
        # s(k+1) = A s + ue + L (q ỹ - C s)
        Ak = system.A_at(k)
        Sy_next = Ak @ Sy + Fk - Lt[k] @ C @ Sy
        if q[k]:
            Sy_next[:, rows] += Lt[k]
        sc = Ak @ sc + uk - Lt[k] @ C @ sc
        Sy = Sy_next
    return Z, zc


def augmented_to_time_based(system: AffineSystem, gains: AugmentedGains, runtime: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Time-based gains ``(F, u0)`` producing the same ``x̂`` as the augmented estimator.

    Propagates ``s(k) = Sy[k] ỹ + sc[k]`` (affine in the stacked ``ỹ``) through
    eqs. (2)-(3) with ``ỹ(k) = 0`` at missing steps, and reads
    ``ue = u0 + F ỹ``.

    Parameters
    ----------
    runtime
        ``"theorem2"`` or ``"hold"``: how the running estimator treats a
        missing step (default: the design mode, ``"hold"`` for ``"leak"``).

    Returns
    -------
    F : ndarray, shape (Tn, Tp)
        Block lower triangular, zero columns at missing steps.
    u0 : ndarray, shape (Tn,)
    """
    runtime = runtime or ("theorem2" if gains.mode == "theorem2" else "hold")
    check_mode(runtime, RUNTIME_MODES)
    word, T = gains.word, gains.T
    n, p = system.n, system.p
    L = _masked_L(as_time_varying_L(gains.L, T, n, p), word, runtime)
    q = arrival_indicator(word)
    F = np.zeros((T * n, T * p))
    u0 = np.zeros(T * n)

    def injection(k, Z, zc):
        Mk = gains.M[k * n:(k + 1) * n]
        F[k * n:(k + 1) * n] = Mk @ Z
        u0[k * n:(k + 1) * n] = gains.nu[k * n:(k + 1) * n] + Mk @ zc
        return F[k * n:(k + 1) * n], u0[k * n:(k + 1) * n]

    _innovation_recursion(system, word, L, gains.s0, injection)
    F[:, np.repeat(q == 0, p)] = 0.0  # ỹ is zero there: those columns are immaterial
    return F, u0


def time_based_to_augmented(system: AffineSystem, word: str, F: np.ndarray, u0: np.ndarray, L: np.ndarray,
                            s0: np.ndarray, runtime: str = "theorem2") -> AugmentedGains:
    """Inverse of :func:`augmented_to_time_based` for given ``L`` and ``s0``.

    With ``ue = u0 + F ỹ`` fixed, ``s`` and the innovation ``z = ỹ - C s``
    are affine in ``ỹ``: ``z_m = P ỹ_m + p0`` on the measured steps, with
    ``P`` unit block lower triangular.  Hence ``M_m = F_m P^{-1}`` and
    ``ν = u0 - M_m p0`` reproduce ``ue`` exactly.
    """
    word = missing_data_pattern(word).label
    check_mode(runtime, RUNTIME_MODES)
    T, n, p = len(word), system.n, system.p
    F = np.asarray(F, float)
    u0 = np.asarray(u0, float)
    if F.shape != (T * n, T * p) or u0.shape != (T * n,):
        raise InputError(f"F must be {(T * n, T * p)} and u0 ({T * n},), got {F.shape} and {u0.shape}")
    Lt = _masked_L(as_time_varying_L(L, T, n, p), word, runtime)
    q = arrival_indicator(word)
    P, p0 = _innovation_recursion(system, word, Lt, s0,
                                  lambda k, Z, zc: (F[k * n:(k + 1) * n], u0[k * n:(k + 1) * n]))
    meas = np.repeat(q == 1, p)
    Pm = P[np.ix_(meas, meas)]
    Mm = sla.solve_triangular(Pm.T, F[:, meas].T, lower=False, unit_diagonal=True).T  # F_m P_m^{-1}
    M = np.zeros((T * n, T * p))
    M[:, meas] = Mm
    nu = u0 - Mm @ p0[meas]
    return AugmentedGains(word=word, L=as_time_varying_L(L, T, n, p), s0=np.asarray(s0, float).reshape(n).copy(),
                          M=M, nu=nu, mode=runtime)


def schedule_from_augmented(system: AffineSystem, gains: AugmentedGains, runtime: str | None = None) -> GainSchedule:
    """The converted time-based :class:`GainSchedule` (``time_based=True``) of an augmented design."""
    F, u0 = augmented_to_time_based(system, gains, runtime)
    tree = PrefixTree([gains.word])
    return schedule_from_word_gains(tree, {gains.word: (F, u0)}, system.n, system.p, time_based=True)


# ---------------------------------------------------------------------------
# Runtime estimator
# ---------------------------------------------------------------------------

class AugmentedEstimator:
    """Causal augmented estimator running both recursions of eqs. (2)-(3).

    Parameters
    ----------
    system
        The model.
    gains
        Designed gains (the designed word fixes which measurements are used:
        like the time-based estimator it ignores measurements the designed
        word lacks).
    xhat0
        Initial estimate.
    runtime
        ``"theorem2"`` or ``"hold"`` treatment of missing steps.
    """

    def __init__(self, system: AffineSystem, gains: AugmentedGains, xhat0: np.ndarray, runtime: str | None = None):
        self.runtime = check_mode(runtime or ("theorem2" if gains.mode == "theorem2" else "hold"), RUNTIME_MODES)
        self.system, self.gains = system, gains
        T, n, p = gains.T, system.n, system.p
        self.L = _masked_L(as_time_varying_L(gains.L, T, n, p), gains.word, self.runtime)
        self.xhat = np.asarray(xhat0, float).reshape(n).copy()
        self.s = np.asarray(gains.s0, float).reshape(n).copy()
        self._k = 0
        self._z: list[np.ndarray] = []

    def step(self, y: np.ndarray | None, u: np.ndarray | None = None) -> np.ndarray:
        """Process time ``k`` (``y=None`` if missing); returns ``x̂(k+1)``."""
        sys, g, k = self.system, self.gains, self._k
        n, p = sys.n, sys.p
        if k >= g.T:
            raise InputError(f"the estimator's horizon T = {g.T} is over")
        C = sys.C_at(k)
        used = y is not None and g.word[k] == "1"
        ytil = (np.asarray(y, float).reshape(p) - C @ self.xhat) if used else np.zeros(p)
        self._z.append(ytil - C @ self.s)
        Mrow = g.M[k * n:(k + 1) * n, : (k + 1) * p]
        ue = g.nu[k * n:(k + 1) * n] + Mrow @ np.concatenate(self._z)
        u = np.zeros(sys.m) if u is None else np.asarray(u, float).reshape(-1)
        self.s = sys.A_at(k) @ self.s + ue + self.L[k] @ (ytil - C @ self.s)
        self.xhat = sys.A_at(k) @ self.xhat + sys.B_at(k) @ u - ue + sys.f
        self._k += 1
        return self.xhat.copy()
