r"""The LP of the augmented estimator for one missing-data word, fixed ``L`` and ``s0`` (P2 Remark 1 /
Theorem 2).

For fixed ``L`` and ``s0`` the innovation does not depend on the gains
(:func:`eqrec.design.augmented.model.innovation_maps`), so the robust problem is
an LP in ``(M, ν, μ2)``, assembled through :class:`eqrec.lp.model.LPBuilder` and
:func:`eqrec.lp.robust.add_robust_rows`.  Its uncertain rows are

.. math:: \xi(t) = \mathrm{Ol}_t\delta + \sum_{s<t}\Phi(t,s{+}1)\Big(\nu_s
          + \sum_{i \in A(s)} M(s,i)\,(Z_i\delta + z^0_i)\Big).

:class:`AugmentedLP`: one missing-data word and a reading of its missing steps (P2), ``form="abs"``, with
in-place ``L`` updates for the sweeps of Fig. 3.  The same model with gains per event prefix of a delay
language (P3 form (4)) is :mod:`eqrec.design.augmented.tree_lp`.  The two keep their own column and row
orders (the stored results of each study come from them; an LP solver may pick another optimal vertex of
a reordered LP).
"""

from __future__ import annotations

import time
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from eqrec.lp.model import LinearProgram, LPBuilder, LPSolution
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.lp.robust import UncertainAffineRows, add_robust_rows
from eqrec.lp.solvers import solve_lp
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.model import DESIGN_MODES, AugmentedGains, AugmentedStacking, check_mode, missing_data_pattern
from eqrec.errors import InputError


class AugmentedLP:
    """LP of P2 Proposition 1 / Theorem 2 for fixed ``L`` and ``s0`` on one word, with ``L`` updates.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The model, or the design's stacked model over the word's length (the LP and every
        :class:`~eqrec.design.augmented.model.AugmentedStacking` it builds read it).
    word : str or ArrivalPattern
        The worst-case missing-data word.
    mu1 : float
        Recovery level ``μ1``, positive.
    L : array_like, shape (n, p) or (T, n, p)
        Observer gain.
    s0 : array_like or None, optional
        Initial auxiliary state (default 0).  :meth:`set_L` updates in place only for ``s0 = 0``.
    mode : {"theorem2", "leak", "masked_gain"}, optional
        Reading of the missing steps (:mod:`eqrec.design.augmented.model`).
    strictly_causal : bool, optional
        Reading check: ``M(k, k) = 0`` (injection without the current measurement).
    pattern_seed : int, optional
        Seed of the random ``L`` whose nonzeros fix the sparsity pattern (valid for every ``L``).

    Attributes
    ----------
    mu2_col, m_cols, nu_cols
        Columns of ``μ2``, of the blocks ``M(s, i)`` (row-major ``n x p``) and of ``ν``.
    num_columns : int
        Number of decision columns (``μ2, M, ν``; the LP adds auxiliary ones).
    level_const, level_coef : ndarray, shape ((T+1)n,)
        Level of the robust rows ``ξ(t)``: ``level_const + level_coef μ2`` (``μ1`` at ``t = T``).
    radius : ndarray
        Radii of the uncertainty box.
    """

    def __init__(self, system: "AffineSystem | Stacking", word: "str | ArrivalPattern", mu1: float, L: np.ndarray,
                 s0: np.ndarray | None = None, mode: str = "theorem2", strictly_causal: bool = False,
                 pattern_seed: int = 12345):
        t0 = time.perf_counter()
        check_mode(mode, DESIGN_MODES)
        mu1 = float(mu1)
        if not np.isfinite(mu1) or mu1 <= 0:
            raise InputError(f"the recovery level mu1 must be positive, got {mu1}", field="mu1")
        word = missing_data_pattern(word).label
        T = len(word)
        self.st = Stacking.of(system, T)  # the one stacked model of the LP and its augmented maps
        system = self.st.system
        self.system, self.word, self.mu1, self.mode = system, word, mu1, mode
        self.strictly_causal = strictly_causal
        self.T = T
        n, p = system.n, system.p
        self.s0 = np.zeros(n) if s0 is None else np.asarray(s0, float).reshape(n)
        lay = self.st.layout
        D = lay.size
        phi = self.st.transition
        # The sparsity pattern must hold for every L (set_L rewrites values only): take that of a random L.  A
        # structural (boolean) propagation would also count entries that cancel in the products of A, so it may
        # differ from the pattern the stored results were computed with.
        rng = np.random.default_rng(pattern_seed)
        generic = AugmentedStacking(self.st, word, rng.normal(size=(T, n, p)), mode)
        zpat = generic.Z != 0  # (T, p, D)
        self.mu2_col = 0
        self.m_cols: dict[tuple[int, int], np.ndarray] = {}
        col = 1
        for s in range(T):  # M(s, i) blocks (n x p, row-major) for measured i <= s
            for i in range(s + 1):
                if word[i] == "1" and not (strictly_causal and i == s):
                    self.m_cols[(s, i)] = np.arange(col, col + n * p)
                    col += n * p
        self.nu_cols = np.arange(col, col + T * n)
        self.num_columns = col + T * n
        # structural entries of G: key = (t*n + a)*D + d; entry (a, d), variable (bb, pi): Φ(t,s+1)[a, bb] Z_i[pi, d]
        keys, cols, phis, zidx = [], [], [], []
        ar_n, ar_p, ar_D = np.arange(n), np.arange(p), np.arange(D)
        for t in range(T + 1):
            for (s, i), mc in self.m_cols.items():
                if s >= t:
                    continue
                P = phi[t][s + 1]
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
        # whose generic pattern fixes the structure (its row bounds are rewritten at every L)
        self._g0_moves = mode == "masked_gain"
        Olflat = (generic.G0 if self._g0_moves else self.st.open_loop).reshape(-1)  # index (t*n + a)*D + d
        ent_keys = np.union1d(np.flatnonzero(Olflat), keys)
        ent_of = np.searchsorted(ent_keys, keys)
        order = np.lexsort((cols, ent_of))  # canonical CSR order: by entry, then column
        self._g_ent, self._g_col = ent_of[order], cols[order]
        self._g_phi, self._g_zidx = phis[order], zidx[order]
        self.entry_keys = ent_keys
        self._G0 = Olflat[ent_keys]
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
        self.level_const = np.zeros(R)
        self.level_coef = np.ones(R)
        self.level_const[T * n:] = mu1
        self.level_coef[T * n:] = 0.0
        self.radius = lay.radius(system.eta_w, system.eta_v, mu1)
        # in-place L updates when s0 = 0: the coefficients Gx (and, in the literal reading, the row bounds of G0)
        self.updatable = not np.any(self.s0)
        self.lp = self._assemble(L)
        self.build_time = time.perf_counter() - t0

    def _gx_values(self, aug: AugmentedStacking) -> np.ndarray:
        return self._g_phi * aug.Z.reshape(-1)[self._g_zidx]

    def _assemble(self, L: np.ndarray) -> LinearProgram:
        b = LPBuilder()
        self.add_decision_variables(b)
        rows, self.aug = self.robust_rows(L)
        index = add_robust_rows(b, rows, self.radius, level_const=self.level_const, level_col=self.mu2_col,
                                level_coef=self.level_coef, form="abs", track_gx=self.updatable)
        self.L = self.aug.L
        if self.updatable:  # where the robust layer put the L-dependent coefficients, in our order
            keys_ours = self._g_ent.astype(np.int64) * self.num_columns + self._g_col
            keys_lp = index.gx_entries.astype(np.int64) * self.num_columns + index.gx_cols
            self._gx_order = np.searchsorted(keys_ours, keys_lp)
            if not np.array_equal(keys_ours[np.minimum(self._gx_order, keys_ours.size - 1)], keys_lp):
                raise AssertionError("the robust layer placed coefficients AugmentedLP did not create")  # pragma: no cover
            self._robust_index, self._rows = index, rows
        return b.build()

    def add_decision_variables(self, b: LPBuilder, cost: bool = True) -> int:
        """Add ``(μ2, M, ν)`` to an empty builder in this LP's column order.

        Parameters
        ----------
        b : LPBuilder
            An empty builder.
        cost : bool, optional
            Minimise ``μ2`` (default).

        Returns
        -------
        int
            The ``μ2`` column.  Two :class:`AugmentedLP` on the same word (any modes) share these
            columns, so the rows of both can be stacked in one LP.
        """
        if b.num_variables:
            raise ValueError("add_decision_variables needs an empty builder")
        mu2 = int(b.add_variables(1, lower=self.mu1, name="mu2")[0])
        if cost:
            b.set_cost(mu2, 1.0)
        for (s, i), mc in self.m_cols.items():
            b.add_variables(mc.size, name=f"M[{s},{i}]")
        b.add_variables(self.T * self.system.n, name="nu")
        return mu2

    def robust_rows(self, L: np.ndarray) -> tuple[UncertainAffineRows, AugmentedStacking]:
        """The uncertain rows ``ξ(t) = G(M) δ + c(M, ν)`` of this reading at ``L`` (any ``s0``).

        Parameters
        ----------
        L : array_like, shape (n, p) or (T, n, p)
            Observer gain.

        Returns
        -------
        rows : UncertainAffineRows
            Row ``t n + a`` is component ``a`` of ``ξ(t)``, in this LP's columns; its level is
            ``level_const + level_coef μ2``.
        aug : AugmentedStacking
            The stacked maps at ``L``.
        """
        aug = AugmentedStacking(self.st, self.word, L, self.mode)
        n, p, T = self.system.n, self.system.p, self.T
        R = (T + 1) * n
        cr, cc, cv = self._cx_fixed
        z0 = aug.Zs.reshape(T * p, n) @ self.s0
        r_, c_, v_ = [cr], [cc], [cv]
        for t in range(1, T + 1):
            for (s, i), mc in self.m_cols.items():
                if s >= t:
                    continue
                coef = np.kron(self.st.transition[t][s + 1], z0[i * p:(i + 1) * p][None, :])  # P[a,b] z0[pi]
                rr, kk = np.nonzero(coef)
                r_.append(t * n + rr)
                c_.append(mc[kk])
                v_.append(coef[rr, kk])
        cx = sp.csr_matrix((np.concatenate(v_), (np.concatenate(r_), np.concatenate(c_))), shape=(R, self.num_columns))
        G0 = aug.G0.reshape(-1)[self.entry_keys] if self._g0_moves else self._G0
        D = self.st.layout.size
        rows = UncertainAffineRows(
            entry_row=self.entry_keys // D, entry_coord=self.entry_keys % D, G0=G0,
            Gx=sp.csr_matrix((self._gx_values(aug), (self._g_ent, self._g_col)),
                             shape=(self.entry_keys.size, self.num_columns)),
            c0=aug.Hs @ self.s0, cx=cx)
        return rows, aug

    def set_L(self, L: np.ndarray) -> LinearProgram:
        """Replace ``L`` (P2 Fig. 3): the ``L``-dependent values are rewritten in place when ``s0 = 0``.

        Parameters
        ----------
        L : array_like, shape (n, p) or (T, n, p)
            The new observer gain.

        Returns
        -------
        LinearProgram
            The LP at ``L`` (rebuilt in the ``"masked_gain"`` reading with ``s0 ≠ 0``, whose certain part depends
            on ``L``).
        """
        if self._g0_moves and not self.updatable:  # the literal reading with s0 ≠ 0: its certain part moves too
            self.lp = self._assemble(L)
            return self.lp
        if not self.updatable:
            raise InputError("fast L updates need s0 = 0; build a new AugmentedLP for s0 ≠ 0", field="s0")
        self.aug = AugmentedStacking(self.st, self.word, L, self.mode)
        self._robust_index.update_gx(self.lp, self._gx_values(self.aug)[self._gx_order])
        if self._g0_moves:  # the literal reading: G0 depends on L too (c0 = Hs s0 = 0), the bounds of its rows
            self._rows = replace(self._rows, G0=self.aug.G0.reshape(-1)[self.entry_keys])
            self._robust_index.update_g0(self.lp, self._rows, self.radius, self.level_const)
        self.L = self.aug.L
        return self.lp

    def gains(self, solution: LPSolution) -> AugmentedGains:
        """``(M, ν)`` of an optimal solution (:meth:`gains_from_x`).

        Parameters
        ----------
        solution : LPSolution
            An optimal solution of :attr:`lp`.

        Returns
        -------
        AugmentedGains
        """
        return self.gains_from_x(solution.x)

    def gains_from_x(self, x: np.ndarray) -> AugmentedGains:
        """``(M, ν)`` of a vector ``x`` in this LP's columns (the first :attr:`num_columns` entries are read).

        Parameters
        ----------
        x : numpy.ndarray
            Values of the LP's columns.

        Returns
        -------
        AugmentedGains
        """
        n, p, T = self.system.n, self.system.p, self.T
        M = np.zeros((T * n, T * p))
        for (s, i), mc in self.m_cols.items():
            M[s * n:(s + 1) * n, i * p:(i + 1) * p] = x[mc].reshape(n, p)
        return AugmentedGains(word=self.word, L=self.L.copy(), s0=self.s0.copy(), M=M,
                              nu=np.asarray(x)[self.nu_cols].copy(), mode=self.mode)

    def solve(self, solver: str = "highs", options: dict | None = None) -> LPSolution:
        """Solve the LP with a solver of the registry (:func:`eqrec.lp.solvers.solve_lp`).

        Parameters
        ----------
        solver : str, optional
            LP solver name (default ``"highs"``).
        options : dict, optional
            Solver options.

        Returns
        -------
        LPSolution
        """
        return solve_lp(self.lp, solver, options)
