r"""μ1 free: the smallest feasible recovery level μ1,min in closed form, certified.

The class engine (:mod:`eqrec.design.classes.engine`) separates a prefix-tree design
at fixed ``μ1`` into one LP per (time, available data) class and state row,
whose optimum is the class level :math:`\ell(d, S)`, with ``δ`` in the box
of radii :math:`\beta = (\eta_w, \eta_v, \mu_1)`.

Theorem (μ1 free)
-----------------
Each class level is a minimum of functions affine and nondecreasing in
:math:`\beta`, hence concave and nondecreasing in :math:`\mu_1`; so are
both costs.  For one terminal (class, row) and a fixed ``k``, write
:math:`a(k) = \sum_{c \in \xi_0} |\cdot|` and :math:`b(k) = \sum_{c \in w,
v} \beta_c |\cdot|`: the row meets :math:`\ell \le \mu` iff some ``k`` has
:math:`b(k) \le \mu(1 - a(k))`, i.e. iff
:math:`\mu \ge m_r = \min_k b(k) / (1 - a(k))` (``a(k) < 1``).  The
feasible set of ``μ1`` is therefore :math:`[\mu_{1,\min}, \infty)` with
:math:`\mu_{1,\min} = \max_{\text{terminal } (c, r)} m_r`, and since the cost
is nondecreasing on it, **the global optimum over μ1 and the gains is
μ1 = μ1,min**, without search.  Each :math:`m_r` is a linear-fractional
program, one LP after the Charnes–Cooper change of variables
:math:`(y, t) = (k, 1)/(1 - a(k))`:

.. math:: m_r = \min_{y,\ t \ge 0} b(y, t) \quad\text{s.t.}\quad t - a(y, t) \ge 1,

with ``a, b`` evaluated on :math:`tE - y^\top Z` (:func:`build_ratio_lp`, :func:`min_recovery_level`).
No ``μ1`` is feasible iff :math:`\min_k a(k) \ge 1` for some terminal row
(the LP is then infeasible).  What certifies ``μ1,min``: the ratio
recomputed from the recovered ``k`` (upper end, attained), and a dual point
:math:`\lambda` (:math:`Z_S\lambda = 0`, :math:`|\lambda_c| \le \beta_c`) at
:math:`\mu_{lo} = (1 - 10^{-6})\mu_{1,\min}` with
:math:`E_d[r]\lambda > \mu_{lo}`: by LP duality the row's level exceeds
:math:`\mu_{lo}` there, so :math:`\mu_{lo}` is infeasible (lower end).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Iterable

import numpy as np
import scipy.sparse as sp

from eqrec.checks import short_label
from eqrec.bounds.data_classes import ClassGains, ClassSet, class_maps
from eqrec.lp.model import LinearProgram
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.lp.parallel import check_jobs, check_scheduler
from eqrec.lp.solvers import solve_lp
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.gains import box_radius
from eqrec.design.classes.blocks import choose_path, solve_ratio_blocks
from eqrec.design.classes.block_lp import block_lp_options, block_objectives, build_ratio_lp, read_class_gains
from eqrec.design.inputs import check_fraction, check_solver, check_system, language_classes
from eqrec.design.result import Design
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure

#: Relative distance below ``μ1,min`` at which the dual certificate shows infeasibility.
MU1_LOWER_RTOL = 1e-6


@dataclass
class MinRecoveryLevel:
    """The smallest feasible recovery level: ``lower < μ1_min <= upper``.

    Parameters
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
    ratios : numpy.ndarray
        ``m_r`` of every terminal (class, row) block, as the LP found them.
    gains : ClassGains or None, optional
        The class gains ``K`` recovered from the ratio LP (``y / t``).
    lps : int, optional
        Number of LPs solved.
    time : float, optional
        Wall-clock seconds of the whole computation.
    """

    upper: float
    lower: float
    lower_margin: float
    binding: dict
    ratios: np.ndarray
    gains: ClassGains | None = None
    lps: int = 0
    time: float = 0.0


@dataclass
class IpoptRoute:
    """What IPOPT did on problem (10) of the delayed-data paper, ``μ1`` a variable (the IPOPT route of a ``μ1``-free
    delay design, :func:`eqrec.design.delay.ipopt.design_delay_ipopt`).

    Parameters
    ----------
    status : str
        IPOPT's return status.
    iterations : int
        IPOPT's iterations.
    ipopt_time : float
        Seconds inside IPOPT.
    start_mu1, start_J : float
        The starting level and the LP's ``J`` there (the starting point).
    J_ipopt : float
        ``J`` at IPOPT's point.
    mu1_of_gains : float
        The smallest level IPOPT's gains recover to (their terminal fixed point).
    polished : dict or None, optional
        The LP at ``max(μ1, mu1_of_gains)``: ``mu1``, ``J`` and ``design`` (or ``J = nan``, ``status =
        "infeasible"``); ``None``: not asked.
    """

    status: str
    iterations: int
    ipopt_time: float
    start_mu1: float
    start_J: float
    J_ipopt: float
    mu1_of_gains: float
    polished: dict | None = None


@dataclass
class FreeMu1Result:
    """A design with ``μ1`` free, and what certifies it.

    Parameters
    ----------
    design : Design
    route, cost : str
        ``"global"`` or ``"ipopt"``; ``"sum"`` or ``"max"``.
    mu1, J : float
        The recovery level found and the cost ``J`` there.
    lower_bound : float
        Global route: ``J`` at the level ``mu1_min.lower`` proven infeasible, with every class at its
        optimal level there; ``J`` is nondecreasing in ``μ1``, so no feasible ``μ1`` does better.  IPOPT: ``nan``.
    lps : int
    time : float
        Number of LPs solved; wall-clock seconds.
    mu1_min : MinRecoveryLevel or None, optional
        Global route: the bracket of ``μ1,min`` and the terminal class that sets it.
    ipopt : IpoptRoute or None, optional
        IPOPT route: IPOPT's record.
    """

    design: Design
    route: str  # "global" or "ipopt"
    cost: str
    mu1: float
    J: float
    lower_bound: float  # global: valid lower bound of J over all μ1; ipopt: nan
    lps: int
    time: float
    mu1_min: MinRecoveryLevel | None = None
    ipopt: IpoptRoute | None = None

    @property
    def mu2(self) -> float:
        """The design's largest level ``μ2``."""
        return self.design.mu2

    @property
    def gap(self) -> float:
        """Relative gap ``(J - lower_bound) / J``."""
        return float((self.J - self.lower_bound) / abs(self.J)) if np.isfinite(self.lower_bound) else np.nan


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


def _monolithic_ratios(st: Stacking, classes: ClassSet, term: list[int], solver: str) -> tuple:
    """The terminal ratio LPs as one block LP: gains, ratios, recomputed ratios, LPs solved, block class and row."""
    system = st.system
    model = build_ratio_lp(system, classes, term, st)
    sol = solve_lp(model.lp, solver, block_lp_options(solver))
    lps = 1
    if sol.status == "infeasible":
        for i in term:  # name a terminal class that no gain contracts (its LP holds all its rows)
            one = build_ratio_lp(system, classes, [i], st)
            lps += 1
            if solve_lp(one.lp, solver, block_lp_options(solver)).status == "infeasible":
                cls = classes.classes[i]
                raise InfeasibleDesign(f"no recovery level is feasible: along the terminal class {short_label(cls.label)} "
                                       f"(time {cls.depth}, data {short_label(list(cls.available))}) no gain makes the "
                                       "initial error contract (min_k a(k) >= 1)")
        raise InfeasibleDesign("no recovery level is feasible (the terminal ratio LP is infeasible)")
    sol.require_optimal("the smallest recovery level (Charnes-Cooper LP)")
    gains = read_class_gains(system, classes, model, sol)
    # recompute each block's ratio from its k alone
    xi0 = np.zeros(st.layout.size, bool)
    xi0[st.layout.xi0] = True
    noise_beta = np.where(xi0, 0.0, box_radius(st, 1.0))
    recomputed = np.zeros(model.blocks)
    for b in range(model.blocks):
        i, r = model.block_class[b], model.block_row[b]
        E, Z = class_maps(st, classes.classes[i])
        resid = np.abs(E[r] - gains.K[i][r] @ Z)
        a = resid[xi0].sum()
        recomputed[b] = resid @ noise_beta / (1.0 - a) if a < 1 else np.inf
    return gains, block_objectives(model, sol), recomputed, lps, model.block_class, model.block_row


def _check_size(system: AffineSystem, classes, n_jobs, scheduler, force: bool) -> None:
    """The size check of a call from Python: estimated from the class sizes, refused past the limits."""
    from eqrec.design.inputs import check_flags, estimate_classes, report_size

    check_flags(force=force)
    if len(classes) < 200:  # seconds at most (the design's SIZE_CHECK_CLASSES)
        return
    workers = 1 if scheduler is not None else check_jobs(n_jobs)
    report_size(estimate_classes(system, classes, mu1_free=False, workers=workers), force=force, field="classes",
                advice="a shorter horizon or a smaller language")


def min_recovery_level(system: "AffineSystem | Stacking", classes: "ClassSet | PrefixTree | Iterable", *,
                       kind: str | None = None, solver: str = "highs", lower_rtol: float = MU1_LOWER_RTOL,
                       n_jobs=None, scheduler=None, path: str = "auto", force: bool = False) -> MinRecoveryLevel:
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
    system : AffineSystem or Stacking
        The system, or a design's stacked model over the classes' horizon (read from there; built here from a
        system).
    classes : ClassSet, PrefixTree or sequence of str or ArrivalPattern
        The language's (time, available data) classes:
        :func:`eqrec.bounds.data_classes.classes_of_tree` of its
        :class:`~eqrec.arrivals.prefix_tree.PrefixTree`, or
        :func:`eqrec.design.delay.design.delay_classes` for a full delay language;
        or the tree itself, or the language's patterns or words (of any lengths).
    kind : {"missing", "delay"} or None, optional
        Reading of string words (:mod:`eqrec.arrivals.words`): ``None`` reads a
        word with a digit ``2-9`` as a delay word and refuses 0/1 strings.
    solver : str, optional
        LP solver, a name of :data:`eqrec.lp.solvers.SOLVER_NAMES`
        (default ``"highs"``).
    lower_rtol : float, optional
        Relative distance below ``μ1,min`` of the level to prove infeasible
        by a dual point (default :data:`MU1_LOWER_RTOL`).
    n_jobs : int or None, optional
        Worker processes of the per-(class, row) LPs of a large language (default every core).
    scheduler : str, distributed.Client or None, optional
        A Dask scheduler running them instead (:mod:`eqrec.design.classes.blocks`).
    path : {"auto", "monolithic", "blocks"}, optional
        One block LP, one LP per terminal (class, row), or by size (default;
        :func:`eqrec.design.classes.blocks.choose_path`).

    force : bool, optional
        Run past the documented size anyway (the estimate is printed either way).

    Returns
    -------
    MinRecoveryLevel
        ``upper`` (``μ1,min`` attained by the recovered gains), ``lower`` (proven infeasible, ``nan`` if not certified),
        the binding terminal class and row, and the class gains.

    Raises
    ------
    InfeasibleDesign
        No ``μ1`` is feasible (some terminal row has ``min_k a(k) >= 1``),
        naming the class and row.
    InputError
        ``μ1,min = 0`` (no noise reaches the end of the horizon): fix ``μ1``; a class set estimated past the
        documented size without ``force`` (field ``classes``, nothing solved; the design's size model,
        :func:`eqrec.design.inputs.report_size`, which errs upward here: it counts every class's LPs).
    SolverFailure
        If the LP has no optimum or its gains do not contract the initial error.

    Examples
    --------
    >>> import eqrec
    >>> from eqrec.bounds.data_classes import classes_of_tree
    >>> tree = eqrec.PrefixTree(["060000", "006000", "000600", "000060"], kind="delay")
    >>> level = eqrec.min_recovery_level(eqrec.acc_system(), classes_of_tree(tree))
    >>> round(level.upper, 4), level.lower < level.upper
    (0.2493, True)
    >>> words = ["101111", "110111", "111011", "111101"]  # the same language as missing-data words
    >>> round(eqrec.min_recovery_level(eqrec.acc_system(), words, kind="missing").upper, 4)
    0.2493
    """
    t_start = time.perf_counter()
    stacked = system if isinstance(system, Stacking) else None  # a design's stacked model, handed down
    system = stacked.system if stacked is not None else check_system(system)
    check_solver(solver)
    lower_rtol = check_fraction(lower_rtol, "lower_rtol")
    classes = language_classes(classes, kind=kind, fixed_length=False, field_name="classes")
    check_jobs(n_jobs)
    scheduler = check_scheduler(scheduler)
    if stacked is None:  # a call from Python (a design hands down its stacked model, already size-checked)
        _check_size(system, classes, n_jobs, scheduler, force)
    st = Stacking.of(stacked or system, classes.horizon)
    term = [i for i, c in enumerate(classes.classes) if c.terminal]
    if choose_path(path, classes, term, system) == "blocks":
        res = solve_ratio_blocks(st, classes, term, solver=solver, n_jobs=n_jobs, scheduler=scheduler)
        K = [res["gains"].get(i, np.zeros((system.n, len(c.available) * system.p)))
             for i, c in enumerate(classes.classes)]
        gains = ClassGains(classes=classes, K=K, n=system.n, p=system.p)
        ratios, recomputed, lps = res["ratios"], res["recomputed"], res["lps"]
        block_class, block_row = res["block_class"], res["block_row"]
    else:
        gains, ratios, recomputed, lps, block_class, block_row = _monolithic_ratios(st, classes, term, solver)
    if not np.all(np.isfinite(recomputed)):
        raise SolverFailure("the ratio LP returned gains that do not contract the initial error")
    bmax = int(np.argmax(recomputed))
    upper = float(recomputed[bmax])
    scale = max(1.0, float(np.max(np.abs(box_radius(st, 1.0)))))
    if upper <= 1e-12 * scale:
        raise InputError("the smallest recovery level is 0 (no noise reaches the end of the horizon); "
                         "fix mu1 instead", field="mu1")
    i, r = int(block_class[bmax]), int(block_row[bmax])
    cls = classes.classes[i]
    lower = upper * (1.0 - lower_rtol)
    E, Z = class_maps(st, cls)
    dual = _dual_lower_certificate(E[r], Z, box_radius(st, lower), solver)
    lps += 1
    margin = dual - lower
    if not (margin > 0):
        lower, margin = np.nan, np.nan
    binding = {"class": cls.label, "time": cls.depth, "data": list(cls.available), "row": r}
    return MinRecoveryLevel(upper=upper, lower=float(lower), lower_margin=float(margin), binding=binding,
                            ratios=ratios, gains=gains, lps=lps, time=time.perf_counter() - t_start)


def round_up(value: float, digits: int = 6) -> float:
    """``value`` rounded up to ``digits`` significant digits (a printed level that is never below the true one).

    Parameters
    ----------
    value : float
        A positive number.
    digits : int, optional
        Significant digits kept (default 6).

    Returns
    -------
    float
        The smallest number of ``digits`` significant digits at least ``value``.
    """
    scale = 10.0 ** (digits - 1 - math.floor(math.log10(value)))
    return math.ceil(value * scale) / scale


#: What to retry with in Python, per design method (the μ1-free entry each method has).
FREE_HINTS = {"prefix": "design_prefix(..., mu1='free')", "time": "design_time_based(..., mu1='free')",
              "delay": "design_delay_global(...)"}


def infeasible_at(system: "AffineSystem | Stacking", classes: ClassSet, mu1: float, error: InfeasibleDesign, *,
                  solver: str = "highs", n_jobs=None, scheduler=None, method: str = "prefix") -> InfeasibleDesign:
    """The error to raise for a design infeasible at ``mu1``: it names the true smallest feasible ``μ1``.

    A terminal class's worst case at the requested ``mu1`` is not the level to
    retry at (it grows with ``μ1``); ``μ1,min`` of :func:`min_recovery_level`
    is.  It is printed rounded up (:func:`round_up`), so retrying at the
    printed value succeeds.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system designed for, or the design's stacked model (:func:`min_recovery_level` reads it).
    classes : ClassSet
        The language's classes.
    mu1 : float
        The recovery level that was infeasible.
    error : InfeasibleDesign
        The infeasibility found at ``mu1`` (its text is kept as the detail).
    solver : str, optional
        LP solver of the Charnes–Cooper LP.
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional
        Where its LPs run (:func:`min_recovery_level`).
    method : str, optional
        The design method that failed (``Design.method``): the hint names its own
        μ1-free entry (:data:`FREE_HINTS`; ``--mu1 free`` on the command line).

    Returns
    -------
    InfeasibleDesign
        ``error`` itself if ``μ1,min`` cannot be computed or does not exceed
        ``mu1``; the error of :func:`min_recovery_level` if no ``μ1`` is
        feasible; else a new error naming ``μ1,min``, with it as
        :attr:`InfeasibleDesign.mu1_min` (the printed value, a float).
    """
    try:
        mm = min_recovery_level(system, classes, solver=solver, n_jobs=n_jobs, scheduler=scheduler)
    except InfeasibleDesign as none_feasible:
        return none_feasible
    except (InputError, SolverFailure):
        return error
    if not mm.upper > mu1:
        return error
    shown = f"{round_up(mm.upper):.6g}"
    hint = FREE_HINTS.get(method, "mu1='free'")
    return InfeasibleDesign(f"{error}; the smallest feasible mu1 is {shown} (retry with mu1 >= {shown} or --mu1 free; "
                            f"in Python {hint})", mu1_min=float(shown))
