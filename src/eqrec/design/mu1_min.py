"""μ1 free: the smallest feasible recovery level μ1,min in closed form, certified (the μ1-free theorem).

The μ1-free theorem of :mod:`eqrec.design.classes` says that the cost of a
prefix-tree design increases with μ1, so the global optimum with μ1 free is
at the smallest μ1 for which every terminal class can recover.  Each terminal
class and state row gives that level as a linear-fractional program, turned
into one LP by the Charnes–Cooper transformation; :func:`min_recovery_level`
solves them, recomputes the ratio from the gains (the upper end) and proves
``(1 - rtol) μ1,min`` infeasible by a dual point (the lower end).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.core.classes import ClassGains, ClassSet, class_maps
from eqrec.core.lp import LinearProgram
from eqrec.core.solvers import solve_lp
from eqrec.core.stacking import Stacking
from eqrec.core.systems import AffineSystem
from eqrec.design.classes import (MU1_LOWER_RTOL, _default_options, _radius, block_objectives, build_class_lp,
                                  class_cost, read_class_gains, solve_classes)
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure


@dataclass
class MinRecoveryLevel:
    """The smallest feasible recovery level: ``lower < μ1_min <= upper``.

    Attributes
    ----------
    upper : float
        ``μ1,min`` as attained by the recovered gains (the largest terminal
        ratio ``b(k) / (1 - a(k))`` recomputed from them).
    lower : float
        A level proven infeasible by a dual point (module docstring).
    lower_margin : float
        ``E_d[r] λ - lower > 0`` of that dual point (``nan`` if not certified).
    binding : dict
        The terminal class (label, time, data) and row that set ``μ1,min``.
    ratios : ndarray
        ``m_r`` of every terminal (class, row) block, as the LP found them.
    """

    upper: float
    lower: float
    lower_margin: float
    binding: dict
    ratios: np.ndarray
    gains: ClassGains | None = None
    lps: int = 0
    time: float = 0.0

    @property
    def value(self) -> float:
        return self.upper


def _dual_lower_certificate(E_row: np.ndarray, Z: np.ndarray, beta: np.ndarray, solver: str) -> float:
    r"""``E_row λ`` for a ``λ`` with ``Z λ = 0`` and ``|λ| <= β`` (a lower bound of the row's level), or ``nan``.

    The LP :math:`\max E\lambda` s.t. :math:`Z\lambda = 0`, :math:`|\lambda| \le \beta`
    (the dual of the LAD LP) is solved, its point projected exactly onto
    :math:`\ker Z` and scaled back into the box, so the bound holds for the
    returned point whatever the solver's tolerances.
    """
    D = E_row.size
    A = sp.csc_matrix(Z) if Z.size else sp.csc_matrix((0, D))
    lp = LinearProgram(c=-E_row, A=A, row_lower=np.zeros(A.shape[0]), row_upper=np.zeros(A.shape[0]),
                       col_lower=-beta, col_upper=beta)
    sol = solve_lp(lp, solver)
    if not sol.optimal:
        return np.nan
    lam = sol.x
    if Z.size:
        lam = lam - Z.T @ np.linalg.lstsq(Z @ Z.T, Z @ lam, rcond=None)[0]
    big = np.abs(lam) > beta
    if np.any(big):
        lam = lam * np.min(beta[big] / np.abs(lam[big]))
    return float(E_row @ lam)


def min_recovery_level(system: AffineSystem, classes: ClassSet, *, solver: str = "highs",
                       lower_rtol: float = MU1_LOWER_RTOL) -> MinRecoveryLevel:
    r"""``μ1,min``: the smallest recovery level any estimator on the language reaches (module docstring).

    The smallest ``μ1`` for which some prefix-tree estimator recovers,
    ``‖ξ(T)‖∞ <= μ1`` for all ``‖ξ(0)‖∞ <= μ1`` and noise in the box, along
    every sequence of the language: the lower end of the feasible set
    ``[μ1,min, ∞)`` of the delayed-data paper's problem with ``μ1`` a
    decision variable (Theorem 1 / Proposition 1).  By the μ1-free theorem
    of this module,

    .. math:: \mu_{1,\min} = \max_{\text{terminal } (c, r)}\ \min_k \frac{b(k)}{1 - a(k)},

    with ``a(k)`` the row's initial-error gain and ``b(k)`` its noise part.
    One block LP (the Charnes–Cooper LP of every terminal class and row), the
    ratio recomputed from the gains, and a dual certificate of the lower end.

    Parameters
    ----------
    system : AffineSystem
        The system.
    classes : ClassSet
        The language's (time, available data) classes:
        :func:`eqrec.core.classes.classes_of_tree` of its
        :class:`~eqrec.core.prefix_tree.PrefixTree`, or
        :func:`eqrec.design.delay.delay_classes` for a full delay language.
        (:func:`eqrec.design.delay.min_recovery_level` takes the words.)
    solver : str, optional
        LP solver, a name of :data:`eqrec.core.solvers.SOLVER_NAMES`
        (default ``"highs"``).
    lower_rtol : float, optional
        Relative distance below ``μ1,min`` of the level to prove infeasible
        by a dual point (default :data:`MU1_LOWER_RTOL`).

    Returns
    -------
    MinRecoveryLevel
        ``upper`` (``μ1,min`` attained by the recovered gains, also
        ``value``), ``lower`` (proven infeasible, ``nan`` if not certified),
        the binding terminal class and row, and the class gains.

    Raises
    ------
    InfeasibleDesign
        No ``μ1`` is feasible (some terminal row has ``min_k a(k) >= 1``),
        naming the class and row.
    InputError
        ``μ1,min = 0`` (no noise reaches the end of the horizon): fix ``μ1``.
    SolverFailure
        If the LP has no optimum or its gains do not contract the initial error.

    Examples
    --------
    >>> import eqrec
    >>> from eqrec.core.classes import classes_of_tree
    >>> tree = eqrec.PrefixTree(["060000", "006000", "000600", "000060"], kind="delay")
    >>> level = eqrec.min_recovery_level(eqrec.acc_system(), classes_of_tree(tree))
    >>> round(level.upper, 4), level.lower < level.upper
    (0.2493, True)
    """
    t_start = time.perf_counter()
    st = Stacking(system, classes.horizon)
    term = [i for i, c in enumerate(classes.classes) if c.terminal]
    model = build_class_lp(system, classes, None, kind="ratio", which=term, stacking=st)
    sol = solve_lp(model.lp, solver, _default_options(solver))
    lps = 1
    if sol.status == "infeasible":
        for i in term:  # name a terminal class that no gain contracts (its LP holds all its rows)
            one = build_class_lp(system, classes, None, kind="ratio", which=[i], stacking=st)
            lps += 1
            if solve_lp(one.lp, solver, _default_options(solver)).status == "infeasible":
                cls = classes.classes[i]
                raise InfeasibleDesign(f"no recovery level is feasible: along the terminal class {cls.label} "
                                       f"(time {cls.depth}, data {list(cls.available)}) no gain makes the "
                                       "initial error contract (min_k a(k) >= 1)")
        raise InfeasibleDesign("no recovery level is feasible (the terminal ratio LP is infeasible)")
    sol.require_optimal("the smallest recovery level (Charnes-Cooper LP)")
    gains = read_class_gains(system, classes, model, sol)
    ratios = block_objectives(model, sol)
    # recompute each block's ratio from its k alone
    xi0 = np.zeros(st.layout.size, bool)
    xi0[st.layout.xi0] = True
    noise_beta = np.where(xi0, 0.0, _radius(st, 1.0))
    recomputed = np.zeros(model.blocks)
    for b in range(model.blocks):
        i, r = model.block_class[b], model.block_row[b]
        E, Z = class_maps(st, classes.classes[i])
        resid = np.abs(E[r] - gains.K[i][r] @ Z)
        a = resid[xi0].sum()
        recomputed[b] = resid @ noise_beta / (1.0 - a) if a < 1 else np.inf
    if not np.all(np.isfinite(recomputed)):
        raise SolverFailure("the ratio LP returned gains that do not contract the initial error")
    bmax = int(np.argmax(recomputed))
    upper = float(recomputed[bmax])
    scale = max(1.0, float(np.max(np.abs(_radius(st, 1.0)))))
    if upper <= 1e-12 * scale:
        raise InputError("the smallest recovery level is 0 (no noise reaches the end of the horizon); "
                         "fix mu1 instead", field="mu1")
    i, r = int(model.block_class[bmax]), int(model.block_row[bmax])
    cls = classes.classes[i]
    lower = upper * (1.0 - lower_rtol)
    E, Z = class_maps(st, cls)
    dual = _dual_lower_certificate(E[r], Z, _radius(st, lower), solver)
    lps += 1
    margin = dual - lower
    if not (margin > 0):
        lower, margin = np.nan, np.nan
    binding = {"class": cls.label, "time": cls.depth, "data": list(cls.available), "row": r}
    return MinRecoveryLevel(upper=upper, lower=float(lower), lower_margin=float(margin), binding=binding,
                            ratios=ratios, gains=gains, lps=lps, time=time.perf_counter() - t_start)


def cost_along_mu1(system: AffineSystem, classes: ClassSet, grid, cost: str = "sum",
                   solver: str = "highs") -> np.ndarray:
    """``J(μ1)`` on a grid of feasible levels (the monotonicity the μ1-free theorem rests on, for tests and figures)."""
    out = []
    for mu in grid:
        s = solve_classes(system, classes, float(mu), solver=solver)
        out.append(class_cost(classes, float(mu), s.levels, cost))
    return np.asarray(out)
