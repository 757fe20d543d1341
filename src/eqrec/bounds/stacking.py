r"""Stacked matrices over a finite horizon, shared by every design method.

Notation of the prefix-based paper (eqs. (10), (13)-(15)), with the noise
gains of its Remark 1 and time-varying matrices as in the augmented paper.
Over a horizon ``T`` the error :math:`\xi = [\xi(0); \dots; \xi(T)]` of any
estimator of the form (5) with output injection :math:`u_e` is

.. math:: \xi = J\xi_0 + S(\bar E w + u_e), \qquad y_\xi = \bar C \xi + N v,

where ``S`` is the block lower-triangular transition matrix of eq. (10),
``J`` the free response of eq. (15), ``C̄ = [diag(λ) ⊗ C, 0]`` and
``N = diag(λ) ⊗ V`` (eq. (14)).

The uncertainty is collected in one vector
:math:`\delta = [w(0); \dots; w(T-1); v(0); \dots; v(T-1); \xi_0]` whose box
radii are :math:`(\eta_w, \eta_v, M_1)`; :class:`UncertaintyLayout` gives its
index ranges.

A design builds one :class:`Stacking` and hands it down: its LPs, gains, certificate and cost read the
maps from there, each computed once (:meth:`Stacking.of` takes a stacking or builds one from a bare
system; a worker process receives the system and the horizon and rebuilds the maps it needs).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np
import scipy.linalg as sla

from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_pattern
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


@dataclass(frozen=True)
class UncertaintyLayout:
    """Index layout of ``δ = [w(0..T-1); v(0..T-1); ξ0]``.

    Parameters
    ----------
    T : int
        Horizon (number of noise samples of each kind).
    nw : int
        Process-noise dimension (columns of ``E``).
    nv : int
        Measurement-noise dimension (columns of ``V``).
    n : int
        State dimension (length of ``ξ0``).
    """

    T: int
    nw: int
    nv: int
    n: int

    @property
    def size(self) -> int:
        """Length ``D = T (nw + nv) + n`` of ``δ``."""
        return self.T * (self.nw + self.nv) + self.n

    def w(self, t: int) -> slice:
        """Indices of ``w(t)`` in ``δ``.

        Parameters
        ----------
        t : int
            Time, ``0 <= t < T``.

        Returns
        -------
        slice
            The ``nw`` entries of ``w(t)``.
        """
        return slice(t * self.nw, (t + 1) * self.nw)

    def v(self, t: int) -> slice:
        """Indices of ``v(t)`` in ``δ``.

        Parameters
        ----------
        t : int
            Time, ``0 <= t < T``.

        Returns
        -------
        slice
            The ``nv`` entries of ``v(t)``.
        """
        o = self.T * self.nw
        return slice(o + t * self.nv, o + (t + 1) * self.nv)

    @property
    def xi0(self) -> slice:
        """Indices of ``ξ0`` in ``δ`` (the last ``n``)."""
        o = self.T * (self.nw + self.nv)
        return slice(o, o + self.n)

    def radius(self, eta_w: float, eta_v: float, mu1: float) -> np.ndarray:
        """Box radii ``b`` of ``δ`` (the bounds of the robust constraint (12b) of the prefix-based paper).

        Parameters
        ----------
        eta_w : float
            Bound of ``‖w(t)‖_∞``.
        eta_v : float
            Bound of ``‖v(t)‖_∞``.
        mu1 : float
            Bound of ``‖ξ0‖_∞`` (the recovery level μ1).

        Returns
        -------
        ndarray, shape (size,)
            ``eta_w`` on the ``w`` entries, ``eta_v`` on the ``v`` entries, ``mu1`` on ``ξ0``.
        """
        return np.concatenate([np.full(self.T * self.nw, eta_w), np.full(self.T * self.nv, eta_v),
                               np.full(self.n, mu1)])

    def split(self, delta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``δ`` (or ``δ`` batches along the last axis) into ``w (T, nw)``, ``v (T, nv)``, ``ξ0 (n,)``.

        Parameters
        ----------
        delta : ndarray, shape (..., size)
            One ``δ`` or a batch of them.

        Returns
        -------
        w : ndarray, shape (..., T, nw)
        v : ndarray, shape (..., T, nv)
        xi0 : ndarray, shape (..., n)
        """
        w = delta[..., : self.T * self.nw].reshape(*delta.shape[:-1], self.T, self.nw)
        v = delta[..., self.T * self.nw: self.T * (self.nw + self.nv)].reshape(*delta.shape[:-1], self.T, self.nv)
        return w, v, delta[..., self.xi0]


class Stacking:
    """Horizon-``T`` stacked quantities of a system (word-independent parts).

    Parameters
    ----------
    system : AffineSystem
        The (possibly time-varying) system.
    T : int
        Horizon (recovery time).
    """

    def __init__(self, system: AffineSystem, T: int):
        system.check_horizon(T)
        self.system = system
        self.T = T
        self.layout = UncertaintyLayout(T, system.nw, system.nv, system.n)

    @classmethod
    def of(cls, source: "AffineSystem | Stacking", T: int) -> "Stacking":
        """The stacked model of ``source`` over the horizon ``T``: ``source`` itself when it is one of that horizon.

        A design builds its :class:`Stacking` once and hands it down (the LPs, the gains, the certificate and
        the cost read it from there, with its maps computed once); a function called with a bare system
        builds its own here.  A stacking of another horizon is rebuilt on its system: the layout of ``δ``,
        hence every map, depends on ``T``.

        Parameters
        ----------
        source : AffineSystem or Stacking
            The system, or a stacked model of it.
        T : int
            Horizon.

        Returns
        -------
        Stacking
            ``source`` if it is a stacking of horizon ``T``, else a new one.
        """
        if isinstance(source, Stacking):
            return source if source.T == T else cls(source.system, T)
        return cls(source, T)

    def __reduce__(self):
        """Pickled as its system and horizon: a worker process rebuilds the cached maps it needs."""
        return (type(self), (self.system, self.T))

    # -- transitions ---------------------------------------------------------
    @cached_property
    def transition(self) -> list[list[np.ndarray | None]]:
        """``Φ[t][s] = A(t-1) ... A(s)`` for ``0 <= s <= t <= T`` (``Φ[t][t] = I``)."""
        n, T = self.system.n, self.T
        phi: list[list[np.ndarray | None]] = [[None] * (T + 1) for _ in range(T + 1)]
        for s in range(T + 1):
            phi[s][s] = np.eye(n)
            for t in range(s + 1, T + 1):
                phi[t][s] = self.system.A_at(t - 1) @ phi[t - 1][s]
        return phi

    @cached_property
    def open_loop(self) -> np.ndarray:
        """Open-loop error maps ``Ol[t]`` (shape ``(T+1, n, D)``): ``ξ(t) = Ol[t] δ`` when ``u_e = 0``."""
        sys, lay, T = self.system, self.layout, self.T
        out = np.zeros((T + 1, sys.n, lay.size))
        out[0][:, lay.xi0] = np.eye(sys.n)
        for t in range(T):
            out[t + 1] = sys.A_at(t) @ out[t]
            out[t + 1][:, lay.w(t)] += sys.E_at(t)
        return out

    @cached_property
    def output_maps(self) -> np.ndarray:
        """``Y[τ] = C(τ) Ol[τ] + V(τ) e_v(τ)`` (shape ``(T, p, D)``): output error at τ when measured."""
        sys, lay = self.system, self.layout
        out = np.einsum("tpn,tnd->tpd", np.stack([sys.C_at(t) for t in range(self.T)]), self.open_loop[: self.T])
        for t in range(self.T):
            out[t][:, lay.v(t)] += sys.V_at(t)
        return out

    # -- the paper's block matrices ------------------------------------------
    @cached_property
    def S(self) -> np.ndarray:
        """Eq. (10): ``(T+1)n x Tn`` with block ``(t, s) = Φ(t, s+1)`` for ``s < t``."""
        n, T = self.system.n, self.T
        S = np.zeros(((T + 1) * n, T * n))
        for t in range(1, T + 1):
            for s in range(t):
                S[t * n:(t + 1) * n, s * n:(s + 1) * n] = self.transition[t][s + 1]
        return S

    @cached_property
    def J(self) -> np.ndarray:
        """Eq. (15): ``[I; Φ(1,0); ...; Φ(T,0)]``."""
        return np.vstack([self.transition[t][0] for t in range(self.T + 1)])

    @cached_property
    def E_blk(self) -> np.ndarray:
        """``blkdiag(E(0), ..., E(T-1))`` (identity in the paper's eq. (13))."""
        return sla.block_diag(*[self.system.E_at(t) for t in range(self.T)])

    def arrival_indicator(self, pattern: "ArrivalPattern | str") -> np.ndarray:
        """``q(t)`` of eq. (10): 1 if the measurement of time ``t`` arrives within the horizon.

        Parameters
        ----------
        pattern : ArrivalPattern or str
            Arrival pattern (or 0/1 word) of length ``T``.

        Returns
        -------
        ndarray, shape (T,)
            ``q(0..T-1)`` as floats 0/1.
        """
        pattern = as_pattern(pattern)
        if pattern.T != self.T:
            raise InputError(f"pattern {pattern.label!r} has length {pattern.T}, the stacking has T = {self.T}")
        return np.array([1.0 if pattern.arrives(t) else 0.0 for t in range(self.T)])

    def C_bar(self, pattern: "ArrivalPattern | str") -> np.ndarray:
        """Eq. (10): ``[blkdiag(q(t) C(t)), 0]`` of size ``Tp x (T+1)n``.

        For delayed data ``q(t)`` says whether ``y(t)`` arrives at all; *when*
        it arrives is carried by the causality pattern of the gains (their
        availability mask), which is nested in time, so the Q-parametrisation
        keeps that pattern (see :mod:`eqrec.design.prefix.design`).

        Parameters
        ----------
        pattern : ArrivalPattern or str
            Arrival pattern (or 0/1 word) of length ``T``.

        Returns
        -------
        ndarray, shape (T p, (T+1) n)
            ``C̄`` of the pattern.
        """
        n, p = self.system.n, self.system.p
        q = self.arrival_indicator(pattern)
        out = np.zeros((self.T * p, (self.T + 1) * n))
        for t in range(self.T):
            if q[t]:
                out[t * p:(t + 1) * p, t * n:(t + 1) * n] = self.system.C_at(t)
        return out

    def word_CS(self, pattern: "ArrivalPattern | str") -> np.ndarray:
        """``C̄ S`` of eqs. (1)-(2) for a pattern of length ``T_w <= T`` (padded with missing measurements),
        restricted to its ``T_w p x T_w n`` block: what :func:`eqrec.bounds.gains.q_to_f` needs.

        Parameters
        ----------
        pattern : ArrivalPattern or str
            Arrival pattern (or 0/1 word) of length ``T_w <= T``.

        Returns
        -------
        ndarray, shape (T_w p, T_w n)
            The leading block of ``C̄ S``.
        """
        pattern = as_pattern(pattern)
        Tw, n, p = pattern.T, self.system.n, self.system.p
        padded = ArrivalPattern(pattern.arrivals + (None,) * (self.T - Tw))
        return (self.C_bar(padded) @ self.S)[: Tw * p, : Tw * n]

    def N(self, pattern: "ArrivalPattern | str") -> np.ndarray:
        """Eq. (14): ``blkdiag(q(t) V(t))``.

        Parameters
        ----------
        pattern : ArrivalPattern or str
            Arrival pattern (or 0/1 word) of length ``T``.

        Returns
        -------
        ndarray, shape (T p, T nv)
            ``N`` of the pattern.
        """
        q = self.arrival_indicator(pattern)
        p, nv = self.system.p, self.system.nv
        out = np.zeros((self.T * p, self.T * nv))
        for t in range(self.T):
            if q[t]:
                out[t * p:(t + 1) * p, t * nv:(t + 1) * nv] = self.system.V_at(t)
        return out

    def error_map_from_Q(self, word: "ArrivalPattern | str", Q: np.ndarray, r: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Eq. (13): ``ξ = G δ + c`` for a block lower-triangular ``Q`` and ``r``.

        Parameters
        ----------
        word : ArrivalPattern or str
            Arrival pattern (or 0/1 word) of length ``T``.
        Q : ndarray, shape (T n, T p)
            Block lower-triangular ``Q = F (I - C̄ S F)^{-1}`` of eq. (1).
        r : ndarray, shape (T n,)
            Affine term ``r = (I + Q C̄ S) u0`` of eq. (2).

        Returns
        -------
        G : ndarray, shape ((T+1) n, D)
            Map from ``δ`` to ``ξ`` (columns ordered as ``δ``).
        c : ndarray, shape ((T+1) n,)
            Constant term ``S r``.
        """
        S, Cb, J = self.S, self.C_bar(word), self.J
        I = np.eye(S.shape[0])
        G = np.hstack([(S + S @ Q @ Cb @ S) @ self.E_blk, S @ Q @ self.N(word), (I + S @ Q @ Cb) @ J])
        return G, S @ r
