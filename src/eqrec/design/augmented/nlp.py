"""The nonconvex augmented design with ``L`` and ``s0`` free (Proposition 1 of the augmented paper), by IPOPT through CasADi.

Problem (11) is bilinear in ``M`` and the ``L``-dependent innovation maps
``Z`` (and ``s0``); IPOPT is started from the LP optimum at a pole-placement ``L``.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from eqrec.lp.solvers import ipopt_options
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.model import AugmentedGains, AugmentedStacking, as_time_varying_L, innovation_maps
from eqrec.errors import InputError


@dataclass
class NLPResult:
    """Outcome of the IPOPT solve of Proposition 1.

    Parameters
    ----------
    gains : AugmentedGains
        The gains found (one constant ``L``).
    mu2 : float
        Their optimised level ``μ2``.
    status : str
        IPOPT's return status.
    success : bool
        Whether IPOPT reports success.
    iterations : int
        IPOPT iterations.
    solve_time : float
        Wall-clock seconds of the solve.
    initial_mu2 : float
        ``μ2`` of the initial guess.
    stats : dict, optional
        Further solver statistics (``t_wall_total``).
    """

    gains: AugmentedGains
    mu2: float
    status: str
    success: bool
    iterations: int
    solve_time: float
    initial_mu2: float
    stats: dict = field(default_factory=dict)


def solve_free_ipopt(model: AugmentedLP, init: AugmentedGains, init_mu2: float, *, free_L: bool = True,
                     free_s0: bool = True, options: dict | None = None) -> NLPResult:
    """Solve the nonconvex problem (11) with IPOPT (CasADi), variables ``M, ν, μ2, L, s0`` and ``a >= |G|``.

    The innovation maps are :func:`eqrec.design.augmented.model.innovation_maps` on CasADi expressions of
    the symbolic ``L`` and ``s0``.

    Parameters
    ----------
    model : AugmentedLP
        Gives the word, mode, columns and structure.
    init : AugmentedGains
        Initial guess (e.g. the LP optimum at a pole-placement ``L``).
    init_mu2 : float
        ``μ2`` of the initial guess.
    free_L, free_s0 : bool, optional
        Fix ``L`` / ``s0`` at the initial value when false (then the problem is the LP, solved by IPOPT).
    options : dict or None, optional
        IPOPT options (:func:`eqrec.lp.solvers.ipopt_options`).

    Returns
    -------
    NLPResult
        Gains with one constant ``L`` (the paper prints one matrix), ``μ2``, IPOPT status and statistics.
    """
    import casadi as ca

    if model.mode == "masked_gain":
        raise InputError("the IPOPT design supports the 'theorem2' and 'leak' readings", field="mode")

    sysm, T, n, p, word = model.system, model.T, model.system.n, model.system.p, model.word
    lay = model.st.layout
    D = lay.size
    nL = n * p  # one constant L (the paper prints one matrix)
    Lsym = ca.SX.sym("L", nL)
    s0 = ca.SX.sym("s0", n)
    msyms = {key: ca.SX.sym(f"M_{key[0]}_{key[1]}", n * p) for key in model.m_cols}
    nu = ca.SX.sym("nu", T * n)
    mu2 = ca.SX.sym("mu2")

    def Lk(k):
        if word[k] == "0" and model.mode == "theorem2":
            return ca.SX.zeros(n, p)
        return ca.reshape(Lsym[0:n * p], p, n).T  # row-major n x p

    # z(k) = Z[k] δ + z0[k] (eq. (9)) as expressions of the symbolic L and s0
    Ls = [Lk(k) for k in range(T)]
    Phi = [ca.DM(sysm.A_at(k)) - ca.mtimes(Ls[k], ca.DM(sysm.C_at(k))) for k in range(T)]
    Z, z0 = innovation_maps(sysm, Phi, Ls, -s0, const=ca.DM)
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
    rows_c = []
    rad = model.radius
    for t in range(T + 1):
        G = ca.SX(Ol[t])
        c = ca.SX.zeros(n, 1)
        for s in range(t):
            P = ca.DM(phi[t][s + 1])
            G = G + ca.mtimes(P, ue_G[s])
            c = c + ca.mtimes(P, ue_c[s])
        level = model.mu1 if t == T else mu2
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
    solver = ca.nlpsol("augmented", "ipopt", nlp,
                       ipopt_options(options, prefix=False, **{"ipopt.acceptable_tol": 1e-7}))
    # initial point
    L0 = as_time_varying_L(init.L, T, n, p)
    Lvec0 = L0[0].reshape(-1)
    mvec0 = np.concatenate([init.M[s * n:(s + 1) * n, i * p:(i + 1) * p].reshape(-1) for (s, i) in model.m_cols])
    aug0 = AugmentedStacking(sysm, word, init.L, model.mode, model.st)
    G0, _ = aug0.error_map(init.M, init.nu, init.s0)
    keys = model.entry_keys
    a0 = np.abs(G0.reshape(-1)[keys]) + 1e-6
    x0 = np.concatenate([[init_mu2 + 1e-6], mvec0, init.nu, Lvec0, init.s0, a0])
    nxv = x0.size
    lbx = np.full(nxv, -np.inf)
    ubx = np.full(nxv, np.inf)
    lbx[0] = model.mu1
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
    L = Lv.reshape(n, p)
    s0v = x[o + nL:o + nL + n]
    gains = AugmentedGains(word=word, L=as_time_varying_L(L, T, n, p), s0=s0v, M=M, nu=nuv, mode=model.mode)
    return NLPResult(gains=gains, mu2=float(x[0]), status=str(st.get("return_status")),
                     success=bool(st.get("success")), iterations=int(st.get("iter_count", -1)),
                     solve_time=elapsed, initial_mu2=float(init_mu2),
                     stats={"t_wall_total": float(st.get("t_wall_total", elapsed))})
