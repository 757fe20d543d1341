r"""The augmented estimator (4) of the delayed-data paper with fixed ``L^α``, ``s0``, and its relation to the prefix design.

The estimator of eq. (4)-(5) carries ``x̂`` and an auxiliary ``s`` (an estimate of ``ξ = x − x̂``)::

    x̂(k+1) = A x̂(k) + B u(k) − u_e(k) + f
    s(k+1)  = A s(k) + u_e(k) + L_k z̃(k)           (L_k = 0 unless y(k) arrives at k: pattern (7))
    u_e(k)  = ν_k + Σ_{i ∈ A(k)} M(k, i) z̃(i),      z̃(i) = ỹ(i) − C s(i)

with ``ỹ(i) = y(i) − C x̂(i)``; a late ``y(i)`` enters through ``M(k, i)``
with the stored ``x̂(i)``, ``s(i)`` (the zero pattern (7) of ``M^α``), and the
gains ``(M, ν)`` are per event prefix (constraint (6)).

With ``e = ξ − s``: ``e(k+1) = (A − L_k C) e(k) + E w(k) − L_k V v(k)`` (``L_k = 0``
at steps whose measurement is not on time) and ``z̃(i) = C e(i) + V v(i)``:
for fixed ``L`` and ``s0`` the innovation does not depend on ``(M, ν)``, the
error ``ξ = Ol δ + S(ν + M z̃)`` is affine in ``(M, ν)``, and the design is an
LP (:func:`build_augmented_delay_lp`), as [15, Sec. IV-C] and the paper's
remark after Proposition 1 say.

Does the optimum depend on ``L`` and ``s0``?  No.  Along any prefix, ``s(i)``
is a causal affine function of the ``ỹ(j)``, ``j ∈ A(i−1)``, so the map from
the available ``ỹ`` to the available ``z̃`` is affine with unit block
lower-triangular linear part (in time-stamp order) and invertible: every
prefix-based gain schedule ``u_e = u0 + F ỹ`` has exactly one ``(M, ν)`` per
prefix for given ``L, s0`` (:func:`prefix_to_augmented`) and conversely
(:func:`augmented_to_prefix`).  The augmented gains are a
reparametrisation of the prefix-based (event-based) gains, so for every
``L^α`` and ``s0`` the optimum equals that of
:func:`eqrec.design.delay.design_delay` — the same conclusion as for the
augmented paper (P2, :mod:`eqrec.design.augmented_model`).  The tests check
it on the batch reactor with two pole placements and a nonzero ``s0``, by
the LP in ``(M, ν)`` and by conversion both ways.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.core.gains import GainRow, GainSchedule
from eqrec.core.lp import LPBuilder, LPSolution
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.prefix_tree import PrefixTree
from eqrec.core.robust import UncertainAffineRows, add_robust_rows
from eqrec.core.solvers import solve_lp
from eqrec.core.stacking import Stacking, UncertaintyLayout
from eqrec.core.systems import AffineSystem
from eqrec.errors import InputError


def _L_seq(L, T: int, n: int, p: int) -> np.ndarray:
    L = np.asarray(L, float)
    if L.shape == (n, p):
        return np.broadcast_to(L, (T, n, p)).copy()
    if L.shape == (T, n, p):
        return L.copy()
    raise InputError(f"L must have shape ({n}, {p}) or ({T}, {n}, {p}), got {L.shape}", field="L")


def innovation_maps(system: AffineSystem, pattern: ArrivalPattern, L, s0) -> tuple[np.ndarray, np.ndarray]:
    """``z̃(i) = Z[i] δ + z0[i]`` for ``i = 0..T-1`` along ``pattern`` (``L_i`` used iff ``y(i)`` is on time)."""
    T, n, p = pattern.T, system.n, system.p
    lay = UncertaintyLayout(T, system.nw, system.nv, n)
    Lt = _L_seq(L, T, n, p)
    Ge = np.zeros((n, lay.size))
    Ge[:, lay.xi0] = np.eye(n)
    he = -np.asarray(s0, float).reshape(n)  # e(0) = ξ0 − s0
    Z = np.zeros((T, p, lay.size))
    z0 = np.zeros((T, p))
    for k in range(T):
        C = system.C_at(k)
        Z[k] = C @ Ge
        Z[k][:, lay.v(k)] += system.V_at(k)
        z0[k] = C @ he
        Lk = Lt[k] if pattern.arrivals[k] == k else np.zeros((n, p))
        Ge = (system.A_at(k) - Lk @ C) @ Ge
        Ge[:, lay.w(k)] += system.E_at(k)
        Ge[:, lay.v(k)] -= Lk @ system.V_at(k)
        he = (system.A_at(k) - Lk @ C) @ he
    return Z, z0


@dataclass
class AugmentedDelayGains:
    """``(M, ν)`` per prefix node (``M`` over the measurements available at the node's time), ``L``, ``s0``."""

    rows: dict[ArrivalPattern, tuple[np.ndarray, np.ndarray]]  # prefix -> (M: n x |A(t)| p, ν: n)
    L: np.ndarray  # (T, n, p)
    s0: np.ndarray


def _innovation_affine_in_ytilde(system, pattern: ArrivalPattern, L, s0, ue_rule):
    """Propagate ``s`` as an affine function of the stacked ``ỹ`` along ``pattern``.

    ``ue_rule(t, prefix, Zy, zc)`` gets the affine maps ``z̃(i) = Zy[i] ỹ + zc[i]``
    (``i <= t``) and returns ``(F_row over ỹ (n x Tp), u0 (n))``.
    """
    T, n, p = pattern.T, system.n, system.p
    Lt = _L_seq(L, T, n, p)
    Sy = np.zeros((n, T * p))
    sc = np.asarray(s0, float).reshape(n).copy()
    Zy = np.zeros((T, p, T * p))
    zc = np.zeros((T, p))
    for t in range(T):
        C = system.C_at(t)
        Zy[t] = -C @ Sy
        Zy[t][:, t * p:(t + 1) * p] += np.eye(p)
        zc[t] = -C @ sc
        F, u0 = ue_rule(t, pattern.prefix(t + 1), Zy, zc)
        on_time = pattern.arrivals[t] == t
        Lk = Lt[t] if on_time else np.zeros((n, p))
        Sy = system.A_at(t) @ Sy + F + Lk @ Zy[t]
        sc = system.A_at(t) @ sc + u0 + Lk @ zc[t]
    return Zy, zc


def augmented_to_prefix(system: AffineSystem, tree: PrefixTree, gains: AugmentedDelayGains) -> GainSchedule:
    """The prefix-based schedule ``u_e = u0 + F ỹ`` that produces the same ``x̂`` as the augmented estimator."""
    n, p = system.n, system.p
    rows: dict[ArrivalPattern, GainRow] = {}
    for pat in tree.patterns:
        def rule(t, pre, Zy, zc):
            M, nu = gains.rows[pre]
            taus = list(pre.available(t))
            Zsel = Zy[taus].reshape(len(taus) * p, -1) if taus else np.zeros((0, Zy.shape[-1]))
            F = M @ Zsel
            u0 = nu + (M @ zc[taus].reshape(-1) if taus else 0.0)
            rows[pre] = GainRow(F[:, : (t + 1) * p].copy(), np.asarray(u0, float).copy())
            return F, u0

        _innovation_affine_in_ytilde(system, pat, gains.L, gains.s0, rule)
    return GainSchedule(rows=rows, n=n, p=p, designed=tree.patterns)


def prefix_to_augmented(system: AffineSystem, tree: PrefixTree, schedule: GainSchedule, L, s0) -> AugmentedDelayGains:
    """The unique ``(M, ν)`` per prefix reproducing ``schedule`` for given ``L`` and ``s0`` (inverse of the above)."""
    n, p = system.n, system.p
    T = tree.depth
    out: dict[ArrivalPattern, tuple[np.ndarray, np.ndarray]] = {}
    for pat in tree.patterns:
        def rule(t, pre, Zy, zc):
            g = schedule.row(pre)
            taus = list(pre.available(t))
            F = np.zeros((n, T * p))
            F[:, : (t + 1) * p] = g.F
            if pre not in out:
                if taus:
                    cols = np.concatenate([np.arange(tau * p, (tau + 1) * p) for tau in taus])
                    P = Zy[taus].reshape(len(taus) * p, -1)[:, cols]  # unit block lower triangular
                    M = np.linalg.solve(P.T, F[:, cols].T).T
                    nu = g.u0 - M @ zc[taus].reshape(-1)
                else:
                    M, nu = np.zeros((n, 0)), g.u0.copy()
                out[pre] = (M, nu)
            return F, g.u0

        _innovation_affine_in_ytilde(system, pat, L, s0, rule)
    return AugmentedDelayGains(rows=out, L=_L_seq(L, T, n, p), s0=np.asarray(s0, float).reshape(n).copy())


class AugmentedDelayEstimator:
    """The estimator (4)-(5) on time-stamped packets (``step(packets) -> x̂(t+1)``)."""

    def __init__(self, system: AffineSystem, gains: AugmentedDelayGains, xhat0):
        self.system, self.gains = system, gains
        n = system.n
        self.xhat = np.asarray(xhat0, float).reshape(n).copy()
        self.s = gains.s0.copy()
        self._t = 0
        self._arrivals: list[int | None] = []
        self._xh: list[np.ndarray] = []
        self._s: list[np.ndarray] = []
        self._z: dict[int, np.ndarray] = {}

    def step(self, packets, u=None) -> np.ndarray:
        sysm, t = self.system, self._t
        n, p = sysm.n, sysm.p
        self._xh.append(self.xhat.copy())
        self._s.append(self.s.copy())
        self._arrivals.append(None)
        for tau, y in packets:
            self._arrivals[tau] = t
            self._z[tau] = np.asarray(y, float) - sysm.C_at(tau) @ (self._xh[tau] + self._s[tau])
        pre = ArrivalPattern(tuple(self._arrivals))
        M, nu = self.gains.rows[pre]
        taus = list(pre.available(t))
        zvec = np.concatenate([self._z[tau] for tau in taus]) if taus else np.zeros(0)
        ue = nu + M @ zvec
        Lk = self.gains.L[t] if self._arrivals[t] == t else np.zeros((n, p))
        zt = self._z.get(t, np.zeros(p)) if self._arrivals[t] == t else np.zeros(p)
        u = np.zeros(sysm.m) if u is None else np.asarray(u, float)
        self.s = sysm.A_at(t) @ self.s + ue + Lk @ zt
        self.xhat = sysm.A_at(t) @ self.xhat + sysm.B_at(t) @ u - ue + sysm.f
        self._t += 1
        return self.xhat.copy()


@dataclass
class AugmentedDelayLP:
    lp: object
    tree: PrefixTree
    m_cols: dict[int, np.ndarray]
    nu_cols: dict[int, np.ndarray]
    mu2_col: int
    level_cols: dict[int, int]
    build_time: float


def build_augmented_delay_lp(system: AffineSystem, tree: PrefixTree, mu1: float, L, s0, *,
                             levels: str = "common", form: str = "split") -> AugmentedDelayLP:
    """The LP of Theorem 1 / Proposition 1 in ``(M^α, ν^α)`` per prefix node, for fixed ``L`` and ``s0``.

    ``levels``: ``"common"`` (minimise the largest level) or ``"sum"`` (the
    paper's ``Σ_k Σ_α μ2,k^α``, node levels weighted by the sequences through them).
    """
    t0 = time.perf_counter()
    T = tree.depth
    st = Stacking(system, T)
    n, p = system.n, system.p
    lay = st.layout
    D = lay.size
    phi, Ol = st.transition, st.open_loop
    b = LPBuilder()
    mu2 = int(b.add_variables(1, lower=mu1, name="mu2")[0])
    b.set_cost(mu2, 1.0 if levels == "common" else 0.0)
    m_cols, nu_cols, measured, zmaps = {}, {}, {}, {}
    for node in tree:
        taus = list(node.available)
        measured[node.index] = taus
        m_cols[node.index] = b.add_variables(n * p * len(taus), name=f"M[{node.label}]")
        nu_cols[node.index] = b.add_variables(n, name=f"nu[{node.label}]")
    through = tree.sequences_through()
    level_cols = {}
    for node in tree:
        if not node.terminal and levels == "sum":
            col = int(b.add_variables(1, lower=mu1)[0])
            level_cols[node.index] = col
            b.set_cost(col, float(through[node.index]))
    er, ec, G0, gr, gc, gv, cr, cc, cv, lconst, lcol = [], [], [], [], [], [], [], [], [], [], []
    row0 = ent0 = 0
    for node in tree:
        t = node.depth
        # innovation maps along this node's prefix (determined by the events 0..t-1)
        key = node.prefix
        if key not in zmaps:  # the prefix padded to the horizon (later arrivals unknown: not used here)
            zmaps[key] = innovation_maps(system, ArrivalPattern(key.arrivals + (None,) * (T - t)), L, s0)
        Z, z0 = zmaps[key]
        blocks, cblocks = [], []
        for s, anc in enumerate(tree.path(node.prefix)):
            taus = measured[anc.index]
            P = phi[t][s + 1]
            if taus:
                Zs = Z[taus].reshape(len(taus) * p, D)
                blocks.append((m_cols[anc.index],
                               (P[:, None, :, None] * Zs.T[None, :, None, :]).reshape(n * D, n * Zs.shape[0])))
                zs = z0[taus].reshape(-1)
                cblocks.append((m_cols[anc.index], (P[:, :, None] * zs[None, None, :]).reshape(n, -1)))
            cblocks.append((nu_cols[anc.index], P))
        const = Ol[t].reshape(-1)
        K = np.hstack([k for _, k in blocks]) if blocks else np.zeros((n * D, 0))
        cols = np.concatenate([c for c, _ in blocks]) if blocks else np.zeros(0, int)
        idx = np.flatnonzero((const != 0) | np.any(K != 0, axis=1))
        er.append(row0 + idx // D)
        ec.append(idx % D)
        G0.append(const[idx])
        Ki = K[idx]
        kr, kc = np.nonzero(Ki)
        gr.append(kr + ent0)
        gc.append(cols[kc])
        gv.append(Ki[kr, kc])
        ent0 += idx.size
        Kc = np.hstack([k for _, k in cblocks])
        ccols = np.concatenate([c for c, _ in cblocks])
        rr, ccx = np.nonzero(Kc)
        cr.append(row0 + rr)
        cc.append(ccols[ccx])
        cv.append(Kc[rr, ccx])
        if node.terminal:
            lconst.append(np.full(n, float(mu1)))
            lcol.append(np.full(n, -1))
        else:
            lconst.append(np.zeros(n))
            lcol.append(np.full(n, level_cols.get(node.index, mu2)))
        row0 += n
    nx = b.num_variables
    rows = UncertainAffineRows(
        entry_row=np.concatenate(er), entry_coord=np.concatenate(ec), G0=np.concatenate(G0),
        Gx=sp.csr_matrix((np.concatenate(gv), (np.concatenate(gr), np.concatenate(gc))), shape=(ent0, nx)),
        c0=np.zeros(row0),
        cx=sp.csr_matrix((np.concatenate(cv), (np.concatenate(cr), np.concatenate(cc))), shape=(row0, nx)))
    add_robust_rows(b, rows, lay.radius(system.eta_w, system.eta_v, mu1), level_const=np.concatenate(lconst),
                    level_cols=np.concatenate(lcol), level_coef=1.0, form=form)
    if levels == "sum":
        for col in level_cols.values():  # the largest level is reported through mu2
            b.add_rows(np.array([0, 0]), np.array([col, mu2]), np.array([1.0, -1.0]), lower=-np.inf, upper=0.0,
                       count=1)
    return AugmentedDelayLP(lp=b.build(), tree=tree, m_cols=m_cols, nu_cols=nu_cols, mu2_col=mu2,
                            level_cols=level_cols, build_time=time.perf_counter() - t0)


def solve_augmented_delay(system: AffineSystem, patterns, mu1: float, L, s0, *, levels: str = "common",
                          solver: str = "highs") -> tuple[AugmentedDelayGains, LPSolution, AugmentedDelayLP]:
    """Solve :func:`build_augmented_delay_lp` and read the gains per prefix node."""
    tree = patterns if isinstance(patterns, PrefixTree) else PrefixTree(patterns, kind="delay")
    model = build_augmented_delay_lp(system, tree, mu1, L, s0, levels=levels)
    sol = solve_lp(model.lp, solver).require_optimal("augmented delay design")
    n, p = system.n, system.p
    rows = {}
    for node in tree:
        k = len(node.available)
        rows[node.prefix] = (sol.x[model.m_cols[node.index]].reshape(n, k * p), sol.x[model.nu_cols[node.index]])
    gains = AugmentedDelayGains(rows=rows, L=_L_seq(L, tree.depth, n, p), s0=np.asarray(s0, float).reshape(n))
    return gains, sol, model
