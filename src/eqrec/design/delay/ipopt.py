"""μ1 free by the delayed-data paper's route: IPOPT through CasADi on the bilinear problem (10).

Problem (10) makes the initial-error radius μ1 a variable, so the robust rows
``|G_ξ0| μ1`` are bilinear.  :func:`bilinear_problem` writes the tree LP of
:mod:`eqrec.design.delay.design` with the radius as data (coefficients and bounds
affine in it, one sparsity pattern); :func:`design_delay_ipopt` solves it with
IPOPT from an LP solution (a local method: its point is certified as is and,
polished, at the level its gains reach); :func:`compare_free_routes` judges it
against the global optimum of :func:`eqrec.design.delay.design.design_delay_global`
(the μ1-free theorem of :mod:`eqrec.design.classes.mu1_min`).  Kept for the
comparison row of the batch-reactor example (P3-BR).
"""

from __future__ import annotations

import time

import numpy as np
import scipy.sparse as sp

from eqrec.bounds.certify import closed_loop_maps
from eqrec.lp.model import LinearProgram, LPSolution
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.lp.solvers import ipopt_options, solve_lp, solver_info
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.cost import check_cost, cost_weights
from eqrec.design.delay.design import design_delay, design_from_solution
from eqrec.design.delay.languages import patterns_tree
from eqrec.design.classes.mu1_min import FreeMu1Result, IpoptRoute
from eqrec.design.result import Mu1Free
from eqrec.design.prefix.tree_lp import build_prefix_lp
from eqrec.errors import InfeasibleDesign, SolverFailure


def bilinear_problem(system: AffineSystem, tree: PrefixTree, cost: str = "sum", *, form: str = "split",
                     r_a: float = 1.0, r_b: float = 2.0) -> dict:
    r"""Problem (10) as data: ``L0 + μ dL <= (A0 + μ dA) x <= U0 + μ dU`` with ``μ = x[mu1_col]``.

    The tree LP is built at two ξ0 radii ``r_a, r_b`` with ``μ1`` a column:
    coefficients and row bounds are affine in the radius (it multiplies the
    ξ0 entries of the robust rows), with one sparsity pattern.

    Parameters
    ----------
    system : AffineSystem
        The system.
    tree : PrefixTree
        The event-prefix tree of the reduced language.
    cost : str, optional
        ``"sum"`` (the paper's cost, per-node levels) or ``"max"`` (one common level).
    form : str, optional
        Robust counterpart of :func:`eqrec.design.prefix.tree_lp.build_prefix_lp` (``"split"``, ``"abs"``, ``"dual"``).
    r_a, r_b : float, optional
        The two ξ0 radii the LP is built at (distinct).

    Returns
    -------
    dict
        ``A0, dA`` (sparse, one pattern), ``L0, U0, dL, dU`` (row bounds), the
        :class:`~eqrec.design.prefix.tree_lp.PrefixLP` ``model`` and its LP ``base``,
        ``mu1_col`` and the level columns ``level_cols``.
    """
    levels = "sum" if cost == "sum" else "common"
    mu1_cost, _ = cost_weights(tree, cost)
    kw = dict(levels=levels, mu1_range=(1.0, 1.0), mu1_cost=mu1_cost, form=form)
    st = Stacking.of(system, tree.depth)  # one stacked model for both LPs (they differ in the radius only)
    ma = build_prefix_lp(st, tree, r_a, **kw)
    mb = build_prefix_lp(st, tree, r_b, **kw)
    Aa, Ab = ma.lp.A, mb.lp.A
    if not (np.array_equal(Aa.indptr, Ab.indptr) and np.array_equal(Aa.indices, Ab.indices)):
        raise AssertionError("the design LP's sparsity pattern depends on the radius")
    dr = r_b - r_a

    def affine(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        fin = np.isfinite(a)
        if not np.array_equal(fin, np.isfinite(b)):
            raise AssertionError("row bounds change finiteness with the radius")
        d = np.zeros_like(a)
        d[fin] = (b[fin] - a[fin]) / dr
        base = a.copy()
        base[fin] = a[fin] - r_a * d[fin]
        return d, base

    dA = (Ab.data - Aa.data) / dr
    A0 = Aa.data - r_a * dA
    dU, U0 = affine(ma.lp.row_upper, mb.lp.row_upper)
    dL, L0 = affine(ma.lp.row_lower, mb.lp.row_lower)
    both = np.isfinite(L0) & np.isfinite(U0)
    if np.any(both & (dL != dU) & (L0 != U0)):
        raise AssertionError("a ranged row's bounds move differently with the radius")
    mat = lambda data: sp.csc_matrix((data, Aa.indices, Aa.indptr), shape=Aa.shape)  # noqa: E731
    return dict(A0=mat(A0), dA=mat(dA), L0=L0, U0=U0, dL=dL, dU=dU, model=ma, base=ma.lp, mu1_col=ma.mu1_col,
                level_cols=np.array([ma.mu2_col, *ma.level_cols.values()], dtype=np.int64))


def terminal_ratios(system: AffineSystem, schedule, tree: PrefixTree) -> tuple[np.ndarray, np.ndarray]:
    """``f_i`` (noise and offset part) and ``b_i`` (``|G_ξ0| 1``) of every terminal error component, from the gains.

    The terminal worst case at radius ``μ`` is ``f_i + μ b_i``; the gains
    recover to every ``μ >= max_i f_i / (1 - b_i)`` (all ``b_i < 1``).

    Parameters
    ----------
    system : AffineSystem
        The system.
    schedule : GainSchedule
        The node gains ``(F, u0)``.
    tree : PrefixTree
        The event-prefix tree whose sequences are evaluated.

    Returns
    -------
    f : numpy.ndarray
        Shape ``(n |sequences|,)``: the noise/offset part per terminal component.
    b : numpy.ndarray
        Shape ``(n |sequences|,)``: the initial-error gain per terminal component.
    """
    fs, bs = [], []
    for pat in tree.patterns:
        G, c, lay = closed_loop_maps(system, schedule, pat)
        rad = lay.radius(system.eta_w, system.eta_v, 0.0)
        GT = G[-1]
        xi = np.zeros(lay.size, bool)
        xi[lay.xi0] = True
        fs.append(np.abs(c[-1]) + np.abs(GT[:, ~xi]) @ rad[~xi])
        bs.append(np.abs(GT[:, xi]).sum(axis=1))
    return np.concatenate(fs), np.concatenate(bs)


def _fixed_point(f: np.ndarray, b: np.ndarray) -> float:
    if np.any(b >= 1.0):
        return np.inf
    return float(np.max(f / (1.0 - b)))


def design_delay_ipopt(system: AffineSystem, patterns, *, kind: str | None = None, cost: str = "sum",
                       start_mu1: float = 1.0,
                       form: str = "split", options: dict | None = None, polish: bool = True,
                       certify: bool = True, solver: str = "highs") -> FreeMu1Result:
    """Problem (10) with ``μ1`` a variable, by IPOPT through CasADi, started from the LP at ``start_mu1``.

    The robust rows at ξ0 radius ``μ1`` are ``(A0 + μ1 dA) x`` within bounds
    affine in ``μ1`` (:func:`bilinear_problem`): exactly the bilinear
    ``|G_ξ0| μ1`` terms of (10) (in the split form ``G = p - m``; the paper's
    Π-dual form has the same feasible gains).  ``start_mu1`` is doubled until
    the start LP is feasible.  IPOPT is a local method: its point is certified
    as is (tolerance widened by IPOPT's accuracy) and, with ``polish``, the
    design at IPOPT's ``μ1`` gives the exact optimum for that ``μ1``
    (``ipopt.polished``).

    Parameters
    ----------
    system : AffineSystem
        The system.
    patterns : sequence of str or ArrivalPattern, or PrefixTree
        The delay language (or its reduced event-prefix tree).
    kind : {"missing", "delay"} or None, optional
        Reading of string words, as for :func:`eqrec.design.delay.design.design_delay`.
    cost : str, optional
        ``"sum"`` (the paper's ``J``) or ``"max"``.
    start_mu1 : float, optional
        ``μ1`` of the starting LP (doubled until feasible).
    form : str, optional
        Robust counterpart of the tree LP (:func:`bilinear_problem`).
    options : dict or None, optional
        IPOPT options (:func:`eqrec.lp.solvers.ipopt_options`).
    polish : bool, optional
        Also solve the LP at the level IPOPT's gains reach (``ipopt.polished``).
    certify : bool, optional
        Certify the gains independently.
    solver : str, optional
        LP solver of the start and polish LPs.

    Returns
    -------
    FreeMu1Result
        Route ``"ipopt"``: ``mu1`` and ``J`` as IPOPT reports them (accurate to its tolerance only, kept for
        the route comparison); ``design`` with its levels raised to what its gains certify
        (:func:`eqrec.bounds.certify.certify_design`: ``design.mu1`` may exceed IPOPT's ``μ1`` by that
        tolerance); no lower bound (``nan``).

    Raises
    ------
    InfeasibleDesign
        If no starting level is feasible.
    SolverFailure
        If IPOPT stops without success.
    """
    import casadi as ca

    check_cost(cost)
    t_start = time.perf_counter()
    tree = patterns_tree(patterns, kind)
    t_build = time.perf_counter()
    bl = bilinear_problem(system, tree, cost, form=form)
    build_time = time.perf_counter() - t_build
    base, mu1_col = bl["base"], bl["mu1_col"]
    lps = 0

    def fixed_lp(mu: float):
        col_lower, col_upper = base.col_lower.copy(), base.col_upper.copy()
        col_lower[mu1_col] = col_upper[mu1_col] = mu
        col_lower[bl["level_cols"]] = mu
        return LinearProgram(c=base.c, A=bl["A0"] + mu * bl["dA"], row_lower=bl["L0"] + mu * bl["dL"],
                             row_upper=bl["U0"] + mu * bl["dU"], col_lower=col_lower, col_upper=col_upper)

    mu0 = float(start_mu1)
    for _ in range(40):
        sol0 = solve_lp(fixed_lp(mu0), solver)
        lps += 1
        if sol0.optimal:
            break
        mu0 *= 2.0
    else:
        raise InfeasibleDesign("no feasible starting level for IPOPT")
    nc = base.shape[1]
    x = ca.MX.sym("x", nc)
    mu = x[mu1_col]

    def dm(M):
        M = M.tocsc()
        M.sort_indices()
        return ca.DM(ca.Sparsity(M.shape[0], M.shape[1], M.indptr.tolist(), M.indices.tolist()), M.data)

    # rows: A0 x + μ (dA x - dU) within [L0, U0] (lower bounds move only where they are finite: dL == dU there)
    shift = np.where(np.isfinite(bl["U0"]), bl["dU"], bl["dL"])
    g = ca.mtimes(dm(bl["A0"]), x) + mu * (ca.mtimes(dm(bl["dA"]), x) - ca.DM(shift))
    lbg = np.where(np.isfinite(bl["L0"]), bl["L0"], -np.inf)
    ubg = bl["U0"]
    c = base.c
    nlp = {"x": x, "f": ca.dot(ca.DM(c), x), "g": g}
    nlpsol = ca.nlpsol("delay10", "ipopt", nlp, ipopt_options(options, **{"ipopt.acceptable_tol": 1e-7}))
    lbx = base.col_lower.copy()
    ubx = base.col_upper.copy()
    lbx[mu1_col], ubx[mu1_col] = 1e-9, np.inf
    lbx[bl["level_cols"]] = 0.0
    t0 = time.perf_counter()
    out = nlpsol(x0=sol0.x, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    t_ip = time.perf_counter() - t0
    stats = nlpsol.stats()
    status = str(stats.get("return_status"))
    xv = np.asarray(out["x"]).reshape(-1)
    if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
        raise SolverFailure(f"IPOPT on problem (10) stopped with status {status}")
    mu1 = float(xv[mu1_col])
    sol = LPSolution("optimal", xv, float(c @ xv), "ipopt", int(stats.get("iter_count", 0)), t_ip, base.blocks)
    rtol = 1e-6 + solver_info("ipopt").accuracy
    design = design_from_solution(bl["model"], tree, xv, mu1, cost, sol, build_time=build_time,
                                  certify=certify, rtol=rtol)
    f, b = terminal_ratios(system, design.schedule, tree)
    record = IpoptRoute(status=status, iterations=sol.iterations, ipopt_time=t_ip, start_mu1=mu0,
                        start_J=float(sol0.objective), J_ipopt=float(c @ xv),
                        mu1_of_gains=_fixed_point(f, b))  # the smallest level IPOPT's gains recover to
    if polish:  # the exact optimum at a level IPOPT's gains certainly reach
        mu_p = max(mu1, record.mu1_of_gains)
        try:
            pol = design_delay(system, tree, mu_p, cost=cost, solver=solver, certify=certify)
            record.polished = {"mu1": mu_p, "J": float(pol.J), "design": pol}
        except InfeasibleDesign:
            record.polished = {"mu1": mu_p, "J": np.nan, "status": "infeasible"}
    design.mu1_free = Mu1Free("ipopt")
    return FreeMu1Result(design=design, route="ipopt", cost=cost, mu1=mu1, J=float(c @ xv), lower_bound=np.nan,
                         lps=lps, time=time.perf_counter() - t_start, ipopt=record)


def compare_free_routes(global_result: FreeMu1Result, ipopt_result: FreeMu1Result) -> dict:
    """Which route found the lower ``J``, judged on what each route's gains certainly reach.

    IPOPT's own ``J`` is accurate to its constraint tolerance only: its ``μ1``
    may sit slightly below the level its gains reach (and below the certified
    infeasible level).  So the routes are compared on IPOPT's polished ``J``
    (the exact optimum at the ``μ1`` its gains reach) when there is one,
    ``"tie"`` within ``max(gap, 1e-6)``; the raw values are reported beside it.

    Parameters
    ----------
    global_result : FreeMu1Result
        Of :func:`eqrec.design.delay.design.design_delay_global`.
    ipopt_result : FreeMu1Result
        Of :func:`design_delay_ipopt`.

    Returns
    -------
    dict
        Both ``J`` and ``μ1``, the lower bound, ``better`` (``"global"``, ``"ipopt"`` or
        ``"tie"``), the times and IPOPT's gap to the bound.
    """
    Jg, Ji = global_result.J, ipopt_result.J
    Jc = (ipopt_result.ipopt.polished or {}).get("J", np.nan)
    Jcmp = Jc if np.isfinite(Jc) else Ji
    lb = global_result.lower_bound
    rtol = max(global_result.gap, 1e-6) if np.isfinite(global_result.gap) else 1e-6
    return {"J_global": Jg, "J_ipopt": Ji, "J_ipopt_polished": Jc, "mu1_global": global_result.mu1,
            "mu1_ipopt": ipopt_result.mu1, "mu1_of_ipopt_gains": ipopt_result.ipopt.mu1_of_gains,
            "lower_bound": lb, "tolerance": rtol,
            "better": ("global" if Jg < Jcmp - rtol * abs(Jg) else
                       ("ipopt" if Jcmp < Jg - rtol * abs(Jg) else "tie")),
            "global_s": global_result.time, "ipopt_s": ipopt_result.time,
            "ipopt_gap_to_bound": (Ji - lb) / abs(Ji) if np.isfinite(lb) else np.nan,
            "ipopt_consistent_with_bound": bool(Ji >= lb * (1 - 1e-6))}
