r"""The state-augmented estimator: one model for the augmented paper (P2) and form (4) of the delayed-data paper (P3).

The estimator carries ``x̂`` and an auxiliary state ``s`` (a Luenberger-like
estimate of the error :math:`\xi = x - \hat x`)::

    x̂(k+1) = A x̂(k) + B u(k) - ue(k) + f
    s(k+1)  = A s(k) + ue(k) + L_k (ỹ(k) - C s(k))              (P2 eq. (7), its eq. (2) misprints ŷ; P3 eq. (4))
    ue(k)   = ν_k + Σ_{i ∈ A(k)} M(k, i) z(i),   z(i) = ỹ(i) - C s(i)   (P2 eq. (3); P3 eq. (5))

with :math:`\tilde y = y - C\hat x` and ``A(k)`` the measurements available at
``k``.  A missing-data word is a delay word whose measurements arrive on time or
never, so one model serves both papers; gains are per event prefix (a word's
gains are its path, :class:`AugmentedGains`).  With :math:`e = \xi - s`,
:math:`\Phi_k = A_k - L_k C_k` and :math:`z_k = C e_k + V v_k` (P2 eq. (9)):

.. math:: e_{k+1} = \Phi_k e_k + W w_k - L_k V v_k, \qquad
          \xi = \mathrm{Ol}\,\delta + S(\nu + M z),

so for fixed ``L`` and ``s0`` the error is affine in ``(M, ν)``
(:func:`innovation_maps`; the LPs of :mod:`eqrec.design.augmented.word_lp`).  What runs, and its
equivalence with the prefix-based estimator: :mod:`eqrec.estimators.augmented` and
:mod:`eqrec.design.augmented.runtime`.

Readings of a missing step (``mode``)
-------------------------------------
``"theorem2"``: P2's Theorem 2 and P3's pattern (7): ``L_k = 0`` unless ``y(k)``
arrives at ``k`` (implementable).  ``"hold"``: a constant ``L`` kept at missing
steps with ``ỹ(k) = 0`` (implementable; ``e`` then depends on ``M``, no LP of its
own).  ``"leak"``: the stacked formulas (5) with only ``M Λ_i = 0`` and a constant
``L``: ``s`` receives the missing measurement (design only; its gains run in
``"hold"``).  ``"masked_gain"``: the Appendix's matrices with ``Φ_k = A - L C_k`` at
every step and the measurement gain zeroed at missing steps (design only; its gains
run in ``"hold"`` or ``"theorem2"``).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_pattern
from eqrec.bounds.stacking import Stacking, UncertaintyLayout
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError
# what the running estimator needs lives with it, one layer down (re-exported here)
from eqrec.estimators.augmented import RUNTIME_MODES, as_time_varying_L, default_runtime  # noqa: F401

MODES = ("theorem2", "hold", "leak", "masked_gain")
#: Readings whose error ``e`` of ``s`` does not depend on ``M`` (an LP for fixed ``L``).
DESIGN_MODES = ("theorem2", "leak", "masked_gain")


def check_mode(mode: str, allowed: tuple[str, ...] = MODES) -> str:
    """Validate a missing-step reading (see the module docstring).

    Parameters
    ----------
    mode : str
        The reading.
    allowed : tuple of str, optional
        The accepted readings (default :data:`MODES`).

    Returns
    -------
    str
        ``mode`` unchanged (else :class:`~eqrec.errors.InputError`).
    """
    if mode not in allowed:
        raise InputError(f"unknown augmented-estimator mode {mode!r}; choose one of {list(allowed)}", field="mode")
    return mode


def effective_L(L: np.ndarray, word: "ArrivalPattern | str", mode: str) -> np.ndarray:
    """``L_k`` multiplying the measurement: zero unless ``y(k)`` arrives at ``k`` in ``"theorem2"``
    (P2 eq. (12), P3 pattern (7)) and ``"masked_gain"``; ``L`` (shape ``(T, n, p)``) kept otherwise.

    Parameters
    ----------
    L : numpy.ndarray
        ``(T, n, p)`` observer gains.
    word : ArrivalPattern or str
        The word (pattern) whose arrivals decide the zeroed steps.
    mode : str
        The missing-step reading.

    Returns
    -------
    numpy.ndarray
        ``(T, n, p)`` measurement gains ``L_k``.
    """
    L = np.array(L, dtype=float)
    if mode in ("theorem2", "masked_gain"):
        for k, a in enumerate(as_pattern(word).arrivals):
            if a != k:
                L[k] = 0.0
    return L


def missing_data_pattern(word: "ArrivalPattern | str") -> ArrivalPattern:
    """The pattern of ``word``, which must be a missing-data pattern (each measurement on time or never).

    The readings of the augmented paper (P2) concern missing data; delay words
    go through the prefix gains of :func:`eqrec.design.augmented.tree_lp.solve_augmented_delay`.

    Parameters
    ----------
    word : ArrivalPattern or str
        A 0/1 word or an arrival pattern.

    Returns
    -------
    ArrivalPattern
        Its pattern (else :class:`~eqrec.errors.InputError`).
    """
    pattern = as_pattern(word)
    if not pattern.is_missing_data:
        raise InputError(f"pattern {pattern.label!r} has delayed measurements; the augmented estimator of the "
                         "augmented paper handles missing data only (use the prefix-based design for delays)",
                         field="words")
    return pattern


def arrival_indicator(word: "ArrivalPattern | str") -> np.ndarray:
    """``q(k)`` (1 if the measurement of step ``k`` arrives) of a missing-data pattern.

    Parameters
    ----------
    word : ArrivalPattern or str
        A missing-data word.

    Returns
    -------
    numpy.ndarray
        ``(T,)`` 0/1 indicators ``q(k)``.
    """
    pattern = missing_data_pattern(word)
    return np.array([1 if pattern.arrives(k) else 0 for k in range(pattern.T)])


def innovation_maps(system: AffineSystem, Phi, L_meas, h0, const=np.asarray) -> tuple[list, list]:
    r"""The innovations ``z(k) = Z[k] δ + Zh[k]`` of the error ``e = ξ - s`` (P2 eq. (9)), ``k = 0..T-1``.

    Parameters
    ----------
    system : AffineSystem
        The model (time-varying allowed).
    Phi : sequence of T matrices (n, n)
        Transitions ``Φ_k`` of ``e`` (``A_k - L_k C_k`` with the reading's ``L_k``).
    L_meas : sequence of T matrices (n, p)
        Gains on the measurement noise: ``e(k+1) = Φ_k e(k) + E w(k) - L_meas[k] V v(k)``.
    h0 : array_like, shape (n,) or (n, m)
        ``e(0) - ξ0``: ``-s0``, or ``-I`` for the maps per unit ``s0``.
    const : callable, optional
        Wraps the system's constant matrices (``casadi.DM`` to build the maps of a symbolic ``L``, ``s0``).

    Returns
    -------
    Z : list of T matrices (p, D)
        Linear part in the uncertainty ``δ`` (core layout).
    Zh : list of T matrices (p,) or (p, m)
        Part from ``h0``.
    """
    T, n, p = len(Phi), system.n, system.p
    lay = UncertaintyLayout(T, system.nw, system.nv, n)
    Ge, h = const(np.eye(n, lay.size, k=lay.xi0.start)), h0
    Z, Zh = [], []
    for k in range(T):
        C, Vsel, Wsel = const(system.C_at(k)), np.zeros((p, lay.size)), np.zeros((n, lay.size))
        Vsel[:, lay.v(k)] = system.V_at(k)
        Wsel[:, lay.w(k)] = system.E_at(k)
        Z.append(C @ Ge + const(Vsel))
        Zh.append(C @ h)
        Ge = Phi[k] @ Ge + const(Wsel) - L_meas[k] @ const(Vsel)
        h = Phi[k] @ h
    return Z, Zh


def transitions(system: AffineSystem, L: np.ndarray) -> np.ndarray:
    """``Φ_k = A_k - L_k C_k`` for an ``L`` sequence of shape ``(T, n, p)``.

    Parameters
    ----------
    system : AffineSystem
        The system (time-varying allowed).
    L : numpy.ndarray
        ``(T, n, p)`` observer gains.

    Returns
    -------
    numpy.ndarray
        ``(T, n, n)`` transitions of ``e = ξ - s``.
    """
    return np.stack([system.A_at(k) - L[k] @ system.C_at(k) for k in range(L.shape[0])])


@dataclass
class AugmentedGains:
    """Gains ``(M, ν, L, s0)`` of the augmented estimator along one word (P2 eq. (3)).

    Parameters
    ----------
    word : str
        The designed (worst-case) word; ``M`` has zero columns at its missing steps.
    L : ndarray, shape (T, n, p)
        Observer gains ``L_k``.
    s0 : ndarray, shape (n,)
        Initial auxiliary state ``s(0)``.
    M : ndarray, shape (Tn, Tp)
        Block lower-triangular injection gains ``M(k, i)``.
    nu : ndarray, shape (Tn,)
        Offsets ``ν_k``.
    mode : str, optional
        Missing-step reading used by the design (default ``"theorem2"``).
    extra : dict, optional
        Free-form details of the design.
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
        """Horizon: the length of :attr:`word`."""
        return len(self.word)


@dataclass
class AugmentedPrefixGains:
    """``(M, ν)`` per event prefix (``M`` over the measurements available at the prefix's time), ``L``, ``s0``
    (P3 eq. (5), constraint (6)).

    Parameters
    ----------
    rows : dict of ArrivalPattern to tuple of numpy.ndarray
        Prefix -> ``(M, ν)``: ``M`` of shape ``(n, |A(k)| p)``, ``ν`` of shape ``(n,)`` at its last step ``k``.
    L : numpy.ndarray
        ``(T, n, p)`` observer gains.
    s0 : numpy.ndarray
        ``(n,)`` initial auxiliary state.
    """

    rows: dict[ArrivalPattern, tuple[np.ndarray, np.ndarray]]
    L: np.ndarray  # (T, n, p)
    s0: np.ndarray


class AugmentedStacking:
    """Stacked matrices of a P2 reading on one word (eqs. (9)-(10), Appendix), on :class:`eqrec.bounds.stacking.Stacking`.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system (time-varying allowed), or the design's stacked model over ``T`` (read from there).
    word : str
        Missing-data word of length ``T`` (``q_k``).
    L : numpy.ndarray
        Observer gain, ``n x p`` (constant) or ``T x n x p``.
    mode : str, optional
        One of :data:`DESIGN_MODES` (the readings whose ``e`` is independent of ``M``).
    stacking : Stacking, optional
        Core stacking to reuse (when its horizon is ``T``; as ``system`` may be).
    """

    def __init__(self, system: "AffineSystem | Stacking", word: str, L: np.ndarray, mode: str = "theorem2",
                 stacking: Stacking | None = None):
        word = missing_data_pattern(word).label
        check_mode(mode, DESIGN_MODES)
        T = len(word)
        st = Stacking.of(stacking if stacking is not None and stacking.T == T else system, T)
        system = st.system
        self.system, self.word, self.mode = system, word, mode
        self.T, self.st = T, st
        n, p = system.n, system.p
        self.L = as_time_varying_L(L, T, n, p)
        self.L_eff = effective_L(self.L, word, mode)
        # the transition keeps L at every step in the "masked_gain" reading
        L_phi = self.L if mode == "masked_gain" else self.L_eff
        self.Phi = transitions(system, L_phi)
        if mode == "masked_gain":  # the Appendix's literal maps define this reading
            self._literal_maps()
        else:
            # z(k) = Z[k] δ + Zs[k] s0 (innovation, eq. (9))
            self.Z, self.Zs = map(np.stack, innovation_maps(system, self.Phi, self.L_eff, -np.eye(n)))
            self.G0 = self.st.open_loop.reshape((T + 1) * n, -1)  # constant part of G
            self.Hs = np.zeros(((T + 1) * n, n))  # constant part of c per unit s0

    # -- the error as a function of (M, ν, s0) ---------------------------------
    def error_map(self, M: np.ndarray, nu: np.ndarray, s0: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Eq. (10): ``ξ = G δ + c`` with ``G`` of shape ``((T+1)n, D)`` in the core δ layout.

        Parameters
        ----------
        M : numpy.ndarray
            ``(Tn, Tp)`` injection gains.
        nu : numpy.ndarray
            ``(Tn,)`` offsets ``ν``.
        s0 : array_like
            ``(n,)`` initial auxiliary state.

        Returns
        -------
        G : numpy.ndarray
            ``((T+1)n, D)`` linear part in ``δ = (w, v, ξ0)``.
        c : numpy.ndarray
            ``((T+1)n,)`` constant part.
        """
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

        Returns
        -------
        dict of str to numpy.ndarray
            The matrices by name.
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

    def _literal_maps(self) -> None:
        """``G = G0 + E M Z``, ``c = E ν - E M (CΦ) s0 + H s0`` read off the Appendix blocks (eq. (5)).

        For the consistent readings these equal the dynamics' open-loop and
        innovation maps (tests/test_augmented.py checks eq. (5) literally); for ``"masked_gain"`` they are the
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
