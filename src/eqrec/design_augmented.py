r"""Design of the state-augmented estimator (Proposition 1 / Theorem 2 of the augmented paper).

* **L and s0 fixed** (Remark 1): the robust problem (11) is an LP in
  ``(M, ν, μ2)``.  :class:`AugmentedLP` builds it once through the core
  layers (:class:`eqrec.lp.LPBuilder`, :func:`eqrec.robust.add_robust_rows`,
  ``form="abs"``) with a generic sparsity pattern, and :meth:`AugmentedLP.set_L`
  rewrites only the matrix values that depend on ``L`` (the heat map of
  Fig. 3 changes nothing else).  The uncertain rows are

  .. math:: \xi(t) = \mathrm{Ol}_t\delta + \sum_{s<t}\Phi(t,s{+}1)\Big(\nu_s
            + \sum_{i\le s,\ q_i = 1} M(s,i)\,(Z_i\delta + z^0_i)\Big),

  with the innovation maps ``Z_i`` of :class:`eqrec.augmented.AugmentedStacking`.
* **L and s0 free**: the nonconvex problem (11) (bilinear in ``M`` and the
  ``L``-dependent ``Z``, ``s0``) solved by IPOPT through CasADi
  (:func:`solve_free_ipopt`), started from the LP solution at a pole-placement ``L``.

Every design is certified from its converted time-based gains with
:func:`eqrec.certify.certify_schedule`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from .augmented import (AugmentedGains, AugmentedStacking, as_time_varying_L, check_mode,
                        schedule_from_augmented, time_based_to_augmented)
from .certify import CERT_RTOL, certify_schedule
from .design_prefix import Design
from .errors import CertificationFailure, InfeasibleDesign, InputError, SolverFailure
from .languages import validate_language, worst_case_word
from .lp import LinearProgram, LPBuilder, LPSolution, solve_lp
from .robust import UncertainAffineRows, add_robust_rows
from .stacking import Stacking
from .systems import AffineSystem


# ---------------------------------------------------------------------------
# Pole placement
# ---------------------------------------------------------------------------

@dataclass
class PolePlacement:
    """Result of placing the eigenvalues of ``A - L C``; ``L is None`` when it failed."""

    requested: np.ndarray
    L: np.ndarray | None
    achieved: np.ndarray | None
    ok: bool
    message: str = ""


def place_observer(A: np.ndarray, C: np.ndarray, poles, tol: float = 1e-6) -> PolePlacement:
    """Observer gain ``L`` with ``eig(A - L C) = poles`` (dual of state feedback, Yang-Tits method).

    Never raises for an unplaceable request (e.g. an eigenvalue repeated more
    often than ``rank C``): returns ``ok=False`` with the reason, so sweeps
    can mark the point instead of hiding it.
    """
    from scipy.signal import place_poles

    poles = np.asarray(poles, dtype=complex)
    try:
        res = place_poles(np.asarray(A).T, np.asarray(C).T, poles)
    except (ValueError, np.linalg.LinAlgError) as exc:
        return PolePlacement(poles, None, None, False, str(exc))
    L = np.asarray(res.gain_matrix).T
    ach = np.linalg.eigvals(A - L @ C)
    # match achieved to requested eigenvalues
    err = max(np.min(np.abs(ach - lam)) for lam in poles)
    err = max(err, max(np.min(np.abs(poles - mu)) for mu in ach))
    if not np.isfinite(err) or err > tol * max(1.0, np.abs(poles).max()):
        return PolePlacement(poles, None, ach, False, f"achieved eigenvalues off by {err:.2e}")
    return PolePlacement(poles, L, ach, True, "")


def heatmap_poles(r: float, theta: float) -> np.ndarray:
    """Fig. 3a: one eigenvalue at 0 and a pair at ``r e^{±jθ}``."""
    lam = r * np.exp(1j * theta)
    if abs(lam.imag) <= 1e-12 * max(r, 1.0):  # θ = 0 or π: a real double eigenvalue, not a rounding-error pair
        lam = complex(lam.real, 0.0)
    return np.array([0.0, lam, np.conj(lam)])


# ---------------------------------------------------------------------------
# The LP with L, s0 fixed
# ---------------------------------------------------------------------------

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

    def __init__(self, system: AffineSystem, word: str, M1: float, L: np.ndarray, s0: np.ndarray | None = None,
                 mode: str = "theorem2", strictly_causal: bool = False, pattern_seed: int = 12345):
        t0 = time.perf_counter()
        check_mode(mode, ("theorem2", "leak"))
        M1 = float(M1)
        if not np.isfinite(M1) or M1 <= 0:
            raise InputError(f"the recovery level M1 must be positive, got {M1}", field="mu1")
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
        Olflat = Ol.reshape(-1)  # index (t*n + a)*D + d
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
        self._builder_base = b.num_rows
        self.radius = lay.radius(system.eta_w, system.eta_v, M1)
        self._b = b
        self._E = E
        self.L = None
        self.lp = self._build(L)
        self.build_time = time.perf_counter() - t0
        # positions in the CSC data of the ±Gx entries (the "abs" form: rows base + j and base + k + j)
        A = self.lp.A
        nr = A.shape[0]
        has_var = np.zeros(E, bool)
        has_var[self._g_ent] = True
        var_entries = np.flatnonzero(has_var)
        k = var_entries.size
        local = np.searchsorted(var_entries, self._g_ent)
        colidx = np.repeat(np.arange(A.shape[1]), np.diff(A.indptr))
        keyA = colidx.astype(np.int64) * nr + A.indices
        if not np.all(np.diff(keyA) > 0):
            A.sort_indices()
            keyA = colidx.astype(np.int64) * nr + A.indices
        rows_plus = self._builder_base + local
        rows_minus = self._builder_base + k + local
        self._pos_plus = np.searchsorted(keyA, self._g_col.astype(np.int64) * nr + rows_plus)
        self._pos_minus = np.searchsorted(keyA, self._g_col.astype(np.int64) * nr + rows_minus)
        ok = (np.all(self._pos_plus < keyA.size) and np.all(self._pos_minus < keyA.size)
              and np.array_equal(keyA[self._pos_plus], self._g_col * nr + rows_plus)
              and np.array_equal(keyA[self._pos_minus], self._g_col * nr + rows_minus))
        if not ok:  # pragma: no cover - guards against a change of the core's row layout
            raise AssertionError("robust-row layout of eqrec.robust changed; AugmentedLP cannot update values")
        if np.any(self.s0):
            self.lp = self._exact_build(L)  # s0 ≠ 0: the certain part depends on L too
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
        add_robust_rows(self._b, rows, self.radius, level_const=meta["level_const"], level_col=self.mu2_col,
                        level_coef=meta["level_coef"], form="abs")
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
        self._builder_base = b.num_rows
        aug = AugmentedStacking(self.system, self.word, L, self.mode, self.st)
        meta = self._rows_meta
        cr, cc, cv = self._cx_fixed
        rows = UncertainAffineRows(
            entry_row=meta["entry_row"], entry_coord=meta["entry_coord"], G0=meta["G0"],
            Gx=sp.csr_matrix((self._gx_values(aug), (self._g_ent, self._g_col)), shape=(self._E, self._nx)),
            c0=np.zeros(meta["R"]), cx=self._cx_with_s0(aug, cr, cc, cv))
        add_robust_rows(b, rows, self.radius, level_const=meta["level_const"], level_col=self.mu2_col,
                        level_coef=meta["level_coef"], form="abs")
        self.L = as_time_varying_L(L, self.T, self.system.n, self.system.p)
        self.aug = aug
        return b.build()

    def _set_values(self, L, lp):
        aug = AugmentedStacking(self.system, self.word, L, self.mode, self.st)
        vals = self._gx_values(aug)
        lp.A.data[self._pos_plus] = -vals
        lp.A.data[self._pos_minus] = vals
        self.L = aug.L
        self.aug = aug

    def set_L(self, L: np.ndarray) -> LinearProgram:
        """Replace ``L`` by rewriting only the ``L``-dependent matrix values (requires ``s0 = 0``)."""
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


# ---------------------------------------------------------------------------
# Free L, s0: IPOPT through CasADi
# ---------------------------------------------------------------------------

@dataclass
class NLPResult:
    """Outcome of the IPOPT solve of Proposition 1."""

    gains: AugmentedGains
    mu2: float
    status: str
    success: bool
    iterations: int
    solve_time: float
    initial_mu2: float
    stats: dict = field(default_factory=dict)


def solve_free_ipopt(model: AugmentedLP, init: AugmentedGains, init_mu2: float, *, free_L: bool = True,
                     free_s0: bool = True, time_varying_L: bool = False, options: dict | None = None) -> NLPResult:
    """Solve the nonconvex problem (11) with IPOPT (CasADi), variables ``M, ν, μ2, L, s0`` and ``a >= |G|``.

    Parameters
    ----------
    model
        An :class:`AugmentedLP` giving the word, mode and structure.
    init
        Initial guess (e.g. the LP optimum at a pole-placement ``L``).
    free_L, free_s0
        Fix ``L`` / ``s0`` at the initial value when false (then the problem is the LP, solved by IPOPT).
    time_varying_L
        One ``L_k`` per step instead of a constant ``L`` (the paper prints one matrix).
    """
    import casadi as ca

    sysm, T, n, p, word = model.system, model.T, model.system.n, model.system.p, model.word
    lay = model.st.layout
    D = lay.size
    nL = (T if time_varying_L else 1) * n * p
    Lsym = ca.SX.sym("L", nL)
    s0 = ca.SX.sym("s0", n)
    msyms = {key: ca.SX.sym(f"M_{key[0]}_{key[1]}", n * p) for key in model.m_cols}
    nu = ca.SX.sym("nu", T * n)
    mu2 = ca.SX.sym("mu2")

    def Lk(k):
        if word[k] == "0" and model.mode == "theorem2":
            return ca.SX.zeros(n, p)
        off = (k if time_varying_L else 0) * n * p
        return ca.reshape(Lsym[off:off + n * p], p, n).T  # row-major n x p

    # e(k) = Ge[k] δ + He[k] s0 ; z(k) = C e + V v
    Ge = ca.SX(np.eye(n, D, k=lay.xi0.start))
    ec = -s0
    Z, z0 = [], []
    for k in range(T):
        C = sysm.C_at(k)
        Zk = ca.mtimes(ca.DM(C), Ge)
        Vsel = np.zeros((p, D))
        Vsel[:, lay.v(k)] = sysm.V_at(k)
        Z.append(Zk + ca.DM(Vsel))
        z0.append(ca.mtimes(ca.DM(C), ec))
        Ph = ca.DM(sysm.A_at(k)) - ca.mtimes(Lk(k), ca.DM(C))
        Wsel = np.zeros((n, D))
        Wsel[:, lay.w(k)] = sysm.E_at(k)
        Ge = ca.mtimes(Ph, Ge) + ca.DM(Wsel) - ca.mtimes(Lk(k), ca.DM(Vsel))
        ec = ca.mtimes(Ph, ec)
    phi = model.st.transition
    Ol = model.st.open_loop
    ue_G = [None] * T
    ue_c = [None] * T
    for s in range(T):
        g = ca.SX.zeros(n, D)
        c = nu[s * n:(s + 1) * n]
        for (ss, i), sym in msyms.items():
            if ss != s:
                continue
            Mi = ca.reshape(sym, p, n).T
            g = g + ca.mtimes(Mi, Z[i])
            c = c + ca.mtimes(Mi, z0[i])
        ue_G[s], ue_c[s] = g, c
    a_list, g_list = [], []
    rows_c, lev = [], []
    rad = model.radius
    for t in range(T + 1):
        G = ca.SX(Ol[t])
        c = ca.SX.zeros(n, 1)
        for s in range(t):
            P = ca.DM(phi[t][s + 1])
            G = G + ca.mtimes(P, ue_G[s])
            c = c + ca.mtimes(P, ue_c[s])
        level = model.M1 if t == T else mu2
        for a in range(n):
            key0 = (t * n + a) * D
            ks = model.entry_keys[(model.entry_keys >= key0) & (model.entry_keys < key0 + D)] - key0
            aux = ca.SX.sym(f"a_{t}_{a}", ks.size)
            a_list.append(aux)
            gvec = ca.vertcat(*[G[a, int(d)] for d in ks])
            g_list += [aux - gvec, aux + gvec]
            bsum = ca.dot(ca.DM(rad[ks]), aux)
            rows_c += [level - c[a] - bsum, level + c[a] - bsum]
    aux_all = ca.vertcat(*a_list)
    mvec = ca.vertcat(*[msyms[k] for k in model.m_cols])
    xvar = ca.vertcat(mu2, mvec, nu, Lsym, s0, aux_all)
    cons = ca.vertcat(*g_list, *rows_c)
    nlp = {"x": xvar, "f": mu2, "g": cons}
    opts = {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": 1e-9, "ipopt.max_iter": 3000,
            "ipopt.acceptable_tol": 1e-7}
    opts.update(options or {})
    solver = ca.nlpsol("augmented", "ipopt", nlp, opts)
    # initial point
    L0 = as_time_varying_L(init.L, T, n, p)
    Lvec0 = (L0.reshape(T, -1) if time_varying_L else L0[0].reshape(1, -1)).reshape(-1)
    mvec0 = np.concatenate([init.M[s * n:(s + 1) * n, i * p:(i + 1) * p].reshape(-1) for (s, i) in model.m_cols])
    aug0 = AugmentedStacking(sysm, word, init.L, model.mode, model.st)
    G0, _ = aug0.error_map(init.M, init.nu, init.s0)
    keys = model.entry_keys
    a0 = np.abs(G0.reshape(-1)[keys]) + 1e-6
    x0 = np.concatenate([[init_mu2 + 1e-6], mvec0, init.nu, Lvec0, init.s0, a0])
    nxv = x0.size
    lbx = np.full(nxv, -np.inf)
    ubx = np.full(nxv, np.inf)
    lbx[0] = model.M1
    off_L = 1 + mvec0.size + T * n
    if not free_L:
        lbx[off_L:off_L + nL] = ubx[off_L:off_L + nL] = Lvec0
    if not free_s0:
        lbx[off_L + nL:off_L + nL + n] = ubx[off_L + nL:off_L + nL + n] = init.s0
    lbx[off_L + nL + n:] = 0.0
    ng = cons.shape[0]
    t0 = time.perf_counter()
    sol = solver(x0=x0, lbx=lbx, ubx=ubx, lbg=np.zeros(ng), ubg=np.full(ng, np.inf))
    elapsed = time.perf_counter() - t0
    st = solver.stats()
    x = np.asarray(sol["x"]).reshape(-1)
    M = np.zeros((T * n, T * p))
    o = 1
    for (s, i) in model.m_cols:
        M[s * n:(s + 1) * n, i * p:(i + 1) * p] = x[o:o + n * p].reshape(n, p)
        o += n * p
    nuv = x[o:o + T * n]
    o += T * n
    Lv = x[o:o + nL]
    L = Lv.reshape(T, n, p) if time_varying_L else Lv.reshape(n, p)
    s0v = x[o + nL:o + nL + n]
    gains = AugmentedGains(word=word, L=as_time_varying_L(L, T, n, p), s0=s0v, M=M, nu=nuv, mode=model.mode)
    return NLPResult(gains=gains, mu2=float(x[0]), status=str(st.get("return_status")),
                     success=bool(st.get("success")), iterations=int(st.get("iter_count", -1)),
                     solve_time=elapsed, initial_mu2=float(init_mu2),
                     stats={"t_wall_total": float(st.get("t_wall_total", elapsed))})


# ---------------------------------------------------------------------------
# Certification and the CLI entry point
# ---------------------------------------------------------------------------

def certify_augmented(system: AffineSystem, gains: AugmentedGains, words, M1: float, runtime: str | None = None):
    """Certify the converted time-based schedule of ``gains`` (the estimator as it really runs)."""
    schedule = schedule_from_augmented(system, gains, runtime)
    return schedule, certify_schedule(system, schedule, list(words), M1)


def default_poles(T: int | None = None) -> np.ndarray:
    """Pole-placement default when ``L`` is not given: ``{0, 0.5, -0.5}`` (all inside the unit disc)."""
    return np.array([0.0, 0.5, -0.5])


def design_augmented(system: AffineSystem, words, M1: float, *, L=None, poles=None, s0=None,
                     solver: str = "highs", mode: str = "theorem2", certify: bool = True,
                     ipopt_options: dict | None = None) -> Design:
    """Design the augmented estimator of the augmented paper for the worst-case word of ``words``.

    Parameters
    ----------
    L
        ``None``: pole placement at ``poles`` (default ``{0, ±0.5}``), then the LP;
        an array: the LP with this ``L``;
        ``"free"``: IPOPT on Proposition 1 with ``L`` and ``s0`` free, started from the
        LP at the pole-placement ``L``.
    s0
        Fixed ``s0`` (default 0; the initial guess when ``L="free"``).
    solver
        LP solver (``"highs"``, ``"clarabel"``, ``"scipy"``) or ``"ipopt"`` (the LP solved by IPOPT).
    mode
        ``"theorem2"`` (default) or the ``"leak"`` reading; a leak design is certified as
        the actual (``"hold"``) estimator and its design ``μ2`` is not a guarantee.

    Returns
    -------
    Design
        ``method="augmented"``, ``schedule`` the converted time-based gains,
        ``certificate`` attached, ``extra`` with ``L, s0, M, nu`` and solver details.

    Raises
    ------
    InputError, InfeasibleDesign, SolverFailure, CertificationFailure
    """
    check_mode(mode, ("theorem2", "leak"))
    language = validate_language(words)
    wc = worst_case_word(language)
    T, n, p = len(wc), system.n, system.p
    extra: dict = {"language": language, "worst_case_word": wc, "mode": mode}
    free = isinstance(L, str)
    if free and L != "free":
        raise InputError(f"L must be None, an array or 'free', got {L!r}", field="L")
    if L is None or free:
        poles = default_poles() if poles is None else np.asarray(poles)
        pp = place_observer(system.A_at(0), system.C_at(0), poles)
        if not pp.ok:
            raise InputError(f"pole placement at {poles} failed: {pp.message}", field="poles")
        L_fixed = pp.L
        extra["poles"] = [complex(x) for x in poles]
    else:
        L_fixed = L
    s0v = np.zeros(n) if s0 is None else np.asarray(s0, float).reshape(n)
    model = AugmentedLP(system, wc, M1, L_fixed, s0=s0v, mode=mode)
    lp_solver = "highs" if (free or solver == "ipopt") else solver
    sol = model.solve(lp_solver).require_optimal(f"augmented design (M1 = {M1:g})")
    gains = model.gains(sol)
    mu2 = float(sol.x[model.mu2_col])
    solution = sol
    if free or solver == "ipopt":
        res = solve_free_ipopt(model, gains, mu2, free_L=free, free_s0=free, options=ipopt_options)
        if not res.success:
            raise SolverFailure(f"IPOPT stopped with status {res.status} after {res.iterations} iterations")
        gains, mu2 = res.gains, res.mu2
        solution = LPSolution("optimal", None, mu2, "ipopt", res.iterations, res.solve_time, {})
        extra.update(ipopt_status=res.status, ipopt_iterations=res.iterations, initial_mu2=res.initial_mu2,
                     initial_guess=f"LP ({lp_solver}) at the pole-placement L")
    extra.update(L=gains.L[0].tolist() if np.allclose(gains.L, gains.L[0]) else gains.L.tolist(),
                 s0=gains.s0.tolist(), M=gains.M.tolist(), nu=gains.nu.tolist(), gains=gains,
                 eig_A_minus_LC=[complex(x) for x in np.linalg.eigvals(system.A_at(0) - gains.L[0] @ system.C_at(0))])
    runtime = "hold" if mode == "leak" else "theorem2"
    schedule = schedule_from_augmented(system, gains, runtime)
    design = Design(method="augmented", system=system, words=(wc,), T=T, M1=float(M1), mu2=mu2,
                    schedule=schedule, solution=solution, build_time=model.build_time, extra=extra)
    if certify:
        cert_words = sorted(set(language) | {wc})
        cert = certify_schedule(system, schedule, cert_words, M1)
        design.certificate = cert
        if mode == "theorem2":
            tol2 = CERT_RTOL * max(1.0, mu2) + (1e-6 if (free or solver == "ipopt") else 0.0)
            if cert.mu2 > mu2 + tol2:
                raise CertificationFailure(f"augmented design: gains give worst-case error {cert.mu2:.9g} "
                                           f"> optimised M2 = {mu2:.9g}")
            if cert.terminal > M1 * (1 + CERT_RTOL) + (1e-6 if (free or solver == "ipopt") else 0.0):
                raise CertificationFailure(f"augmented design: terminal worst-case error {cert.terminal:.9g} > M1")
        else:
            extra["certified_runtime"] = runtime
    return design


__all__ = ["AugmentedLP", "NLPResult", "PolePlacement", "certify_augmented", "design_augmented", "heatmap_poles",
           "place_observer", "solve_free_ipopt", "time_based_to_augmented", "InfeasibleDesign"]
