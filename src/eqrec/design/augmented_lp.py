r"""LP of the state-augmented estimator for fixed ``L`` and ``s0`` (Remark 1 / Theorem 2 of the augmented paper).

The robust problem (11) is an LP in ``(M, ν, μ2)``.  :class:`AugmentedLP`
builds it once through the core layers (:class:`eqrec.core.lp.LPBuilder`,
:func:`eqrec.core.robust.add_robust_rows`, ``form="abs"``) with a generic
sparsity pattern, and :meth:`AugmentedLP.set_L` rewrites only the matrix
values that depend on ``L`` (the heat map of Fig. 3 changes nothing else).
The uncertain rows are

.. math:: \xi(t) = \mathrm{Ol}_t\delta + \sum_{s<t}\Phi(t,s{+}1)\Big(\nu_s
          + \sum_{i\le s,\ q_i = 1} M(s,i)\,(Z_i\delta + z^0_i)\Big),

with the innovation maps ``Z_i`` of :class:`eqrec.design.augmented_model.AugmentedStacking`.
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from eqrec.core.lp import LinearProgram, LPBuilder, LPSolution
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.solvers import solve_lp
from eqrec.core.robust import UncertainAffineRows, add_robust_rows
from eqrec.core.stacking import Stacking
from eqrec.core.systems import AffineSystem
from eqrec.design.augmented_model import (DESIGN_MODES, AugmentedGains, AugmentedStacking, as_time_varying_L, check_mode,
                                          missing_data_pattern)
from eqrec.errors import InputError


class AugmentedLP:
    """LP of Proposition 1 / Theorem 2 for fixed ``L`` and ``s0`` on one word, with value updates.

    Parameters
    ----------
    system, word, M1
        Problem data (``word`` is the worst-case word).
    L
        Observer gain (``n x p`` or ``T x n x p``).
    s0
        Initial auxiliary state (default 0).  :meth:`set_L` requires ``s0 = 0``.
    mode
        ``"theorem2"`` or ``"leak"`` (see :mod:`eqrec.augmented`).
    strictly_causal
        Reading check: ``M(k, k) = 0`` (injection without the current measurement).
    pattern_seed
        Seed of the generic ``L`` that fixes the sparsity pattern.
    """

    def __init__(self, system: AffineSystem, word: "str | ArrivalPattern", M1: float, L: np.ndarray, s0: np.ndarray | None = None,
                 mode: str = "theorem2", strictly_causal: bool = False, pattern_seed: int = 12345):
        t0 = time.perf_counter()
        check_mode(mode, DESIGN_MODES)
        M1 = float(M1)
        if not np.isfinite(M1) or M1 <= 0:
            raise InputError(f"the recovery level M1 must be positive, got {M1}", field="mu1")
        word = missing_data_pattern(word).label
        self.system, self.word, self.M1, self.mode = system, word, M1, mode
        self.strictly_causal = strictly_causal
        self.T = T = len(word)
        n, p = system.n, system.p
        self.st = Stacking(system, T)
        self.s0 = np.zeros(n) if s0 is None else np.asarray(s0, float).reshape(n)
        lay = self.st.layout
        D = self.D = lay.size
        phi = self.st.transition
        Ol = self.st.open_loop
        rng = np.random.default_rng(pattern_seed)
        generic = AugmentedStacking(system, word, rng.normal(size=(T, n, p)), mode, self.st)
        zpat = generic.Z != 0  # (T, p, D)

        b = LPBuilder()
        self.mu2_col = int(b.add_variables(1, lower=M1, name="mu2")[0])
        b.set_cost(self.mu2_col, 1.0)
        # M(s, i) blocks (n x p, row-major) for measured i <= s
        self.m_cols: dict[tuple[int, int], np.ndarray] = {}
        for s in range(T):
            for i in range(s + 1):
                if word[i] == "1" and not (strictly_causal and i == s):
                    self.m_cols[(s, i)] = b.add_variables(n * p, name=f"M[{s},{i}]")
        self.nu_cols = b.add_variables(T * n, name="nu")

        # Structural entries of G: key = (t*n + a)*D + d.
        keys, cols, phis, zidx = [], [], [], []
        ar_n, ar_p, ar_D = np.arange(n), np.arange(p), np.arange(D)
        for t in range(T + 1):
            for (s, i), mc in self.m_cols.items():
                if s >= t:
                    continue
                P = phi[t][s + 1]
                # entry (a, d), variable (bb, pi): P[a, bb] * Z_i[pi, d]
                a, bb, pi, d = np.meshgrid(ar_n, ar_n, ar_p, ar_D, indexing="ij")
                mask = (P[a, bb] != 0) & zpat[i][pi, d]
                a, bb, pi, d = a[mask], bb[mask], pi[mask], d[mask]
                keys.append((t * n + a) * D + d)
                cols.append(mc[bb * p + pi])
                phis.append(P[a, bb])
                zidx.append((i * p + pi) * D + d)
        keys = np.concatenate(keys) if keys else np.zeros(0, int)
        cols = np.concatenate(cols) if cols else np.zeros(0, int)
        phis = np.concatenate(phis) if phis else np.zeros(0)
        zidx = np.concatenate(zidx) if zidx else np.zeros(0, int)
        # constant part of G: the open-loop map, or (the "masked_gain" reading) the L-dependent literal G0,
        # whose generic pattern fixes the structure; such LPs are rebuilt at every L
        self._rebuild = mode == "masked_gain"
        Olflat = (generic.G0 if self._rebuild else Ol).reshape(-1)  # index (t*n + a)*D + d
        ent_keys = np.union1d(np.flatnonzero(Olflat), keys)
        ent_of = np.searchsorted(ent_keys, keys)
        order = np.lexsort((cols, ent_of))  # canonical CSR order: by entry, then column
        self._g_ent, self._g_col = ent_of[order], cols[order]
        self._g_phi, self._g_zidx = phis[order], zidx[order]
        E = ent_keys.size
        self.entry_keys = ent_keys
        entry_row = ent_keys // D
        entry_coord = ent_keys % D
        G0 = Olflat[ent_keys]
        nx = b.num_variables
        self._nx = nx
        # certain part: c_t = Σ_s Φ(t,s+1) (ν_s + Σ_i M(s,i) z0_i)
        c_r, c_c, c_v = [], [], []
        for t in range(1, T + 1):
            for s in range(t):
                P = phi[t][s + 1]
                rr, cc = np.nonzero(P)
                c_r.append(t * n + rr)
                c_c.append(self.nu_cols[s * n + cc])
                c_v.append(P[rr, cc])
        self._cx_fixed = (np.concatenate(c_r), np.concatenate(c_c), np.concatenate(c_v))
        R = (T + 1) * n
        level_const = np.zeros(R)
        level_coef = np.ones(R)
        level_const[T * n:] = M1
        level_coef[T * n:] = 0.0
        self._rows_meta = dict(entry_row=entry_row, entry_coord=entry_coord, G0=G0, R=R,
                               level_const=level_const, level_coef=level_coef)
        self.radius = lay.radius(system.eta_w, system.eta_v, M1)
        self._b = b
        self._E = E
        self.L = None
        self.lp = self._build(L)
        self.build_time = time.perf_counter() - t0
        # the robust layer says where the L-dependent coefficients are; order them as ours
        idx = self._robust_index
        keys_ours = self._g_ent.astype(np.int64) * self._nx + self._g_col
        keys_lp = idx.gx_entries.astype(np.int64) * self._nx + idx.gx_cols
        self._gx_order = np.searchsorted(keys_ours, keys_lp)
        if not np.array_equal(keys_ours[np.minimum(self._gx_order, keys_ours.size - 1)], keys_lp):
            raise AssertionError("the robust layer placed coefficients AugmentedLP did not create")  # pragma: no cover
        if np.any(self.s0) or self._rebuild:
            self.lp = self._exact_build(L)  # s0 ≠ 0 or the literal reading: more than Gx depends on L
        else:
            self._set_values(L, self.lp)

    def _gx_values(self, aug: AugmentedStacking) -> np.ndarray:
        return self._g_phi * aug.Z.reshape(-1)[self._g_zidx]

    def _build(self, L: np.ndarray) -> LinearProgram:
        """Build the template with a generic ``L`` (so no structural zero is lost); values set later."""
        sysm, T, n, p = self.system, self.T, self.system.n, self.system.p
        rng = np.random.default_rng(99)
        aug = AugmentedStacking(sysm, self.word, rng.normal(size=(T, n, p)), self.mode, self.st)
        meta = self._rows_meta
        vals = self._gx_values(aug)
        if np.any(vals == 0):  # pragma: no cover
            raise AssertionError("generic pattern produced an exact zero")
        cr, cc, cv = self._cx_fixed
        rows = UncertainAffineRows(
            entry_row=meta["entry_row"], entry_coord=meta["entry_coord"], G0=meta["G0"],
            Gx=sp.csr_matrix((vals, (self._g_ent, self._g_col)), shape=(self._E, self._nx)),
            c0=np.zeros(meta["R"]), cx=sp.csr_matrix((cv, (cr, cc)), shape=(meta["R"], self._nx)))
        self._robust_index = add_robust_rows(self._b, rows, self.radius, level_const=meta["level_const"],
                                             level_col=self.mu2_col, level_coef=meta["level_coef"], form="abs",
                                             track_gx=True)
        return self._b.build()

    def _cx_with_s0(self, aug, cr, cc, cv):
        n, p, T = self.system.n, self.system.p, self.T
        phi = self.st.transition
        z0 = aug.Zs.reshape(T * p, n) @ self.s0
        r_, c_, v_ = [cr], [cc], [cv]
        for t in range(1, T + 1):
            for (s, i), mc in self.m_cols.items():
                if s >= t:
                    continue
                P = phi[t][s + 1]
                coef = np.kron(P, z0[i * p:(i + 1) * p][None, :])  # (n, n p): P[a,b] z0[pi]
                rr, kk = np.nonzero(coef)
                r_.append(t * n + rr)
                c_.append(mc[kk])
                v_.append(coef[rr, kk])
        return sp.csr_matrix((np.concatenate(v_), (np.concatenate(r_), np.concatenate(c_))),
                             shape=(self._rows_meta["R"], self._nx))

    def _exact_build(self, L):
        # Rebuild the LP from scratch at L (used when s0 ≠ 0).
        b = LPBuilder()
        b.add_variables(1, lower=self.M1, name="mu2")
        b.set_cost(0, 1.0)
        for (s, i), mc in self.m_cols.items():
            b.add_variables(mc.size, name=f"M[{s},{i}]")
        b.add_variables(self.T * self.system.n, name="nu")
        aug = AugmentedStacking(self.system, self.word, L, self.mode, self.st)
        meta = self._rows_meta
        cr, cc, cv = self._cx_fixed
        G0 = aug.G0.reshape(-1)[self.entry_keys] if self._rebuild else meta["G0"]
        rows = UncertainAffineRows(
            entry_row=meta["entry_row"], entry_coord=meta["entry_coord"], G0=G0,
            Gx=sp.csr_matrix((self._gx_values(aug), (self._g_ent, self._g_col)), shape=(self._E, self._nx)),
            c0=aug.Hs @ self.s0, cx=self._cx_with_s0(aug, cr, cc, cv))
        add_robust_rows(b, rows, self.radius, level_const=meta["level_const"], level_col=self.mu2_col,
                        level_coef=meta["level_coef"], form="abs")
        self.L = as_time_varying_L(L, self.T, self.system.n, self.system.p)
        self.aug = aug
        return b.build()

    def _set_values(self, L, lp):
        aug = AugmentedStacking(self.system, self.word, L, self.mode, self.st)
        vals = self._gx_values(aug)
        self._robust_index.update_gx(lp, vals[self._gx_order])
        self.L = aug.L
        self.aug = aug

    def set_L(self, L: np.ndarray) -> LinearProgram:
        """Replace ``L`` by rewriting only the ``L``-dependent matrix values (requires ``s0 = 0``).

        In the ``"masked_gain"`` reading the constant part depends on ``L`` too: the LP is rebuilt.
        """
        if self._rebuild:
            self.lp = self._exact_build(L)
            return self.lp
        if np.any(self.s0):
            raise InputError("fast L updates need s0 = 0; build a new AugmentedLP for s0 ≠ 0", field="s0")
        self._set_values(L, self.lp)
        return self.lp

    def gains(self, solution: LPSolution) -> AugmentedGains:
        """Read ``(M, ν)`` from an optimal solution."""
        n, p, T = self.system.n, self.system.p, self.T
        M = np.zeros((T * n, T * p))
        for (s, i), mc in self.m_cols.items():
            M[s * n:(s + 1) * n, i * p:(i + 1) * p] = solution.x[mc].reshape(n, p)
        return AugmentedGains(word=self.word, L=self.L.copy(), s0=self.s0.copy(), M=M,
                              nu=solution.x[self.nu_cols].copy(), mode=self.mode)

    def solve(self, solver: str = "highs", options: dict | None = None) -> LPSolution:
        return solve_lp(self.lp, solver, options)
