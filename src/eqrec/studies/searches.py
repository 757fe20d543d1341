"""Sweeps over design problems: searches and parameter scans built on the single designs.

* :func:`lower_bound_probe` — the prefix LP with ``M2 <= optimum - gap``
  must be infeasible (Theorem 3 of the prefix-based paper is necessary and
  sufficient, so this proves no estimator of the class does better);
* :func:`min_feasible_mu1` — the smallest recovery level, exactly (the
  μ1-free theorem of :mod:`eqrec.design.classes.mu1_min`: one Charnes–Cooper LP),
  where the paper suggests "an optimal M1 through line search" (Section V of
  the prefix-based paper);
* :func:`min_recovery_time` — the shortest horizon at which a language,
  extended by measurements, admits recovery to ``M1``;
* :func:`mu2_curve` — the optimal ``M2`` against ``M1`` (μ2 against μ1) (``None`` where infeasible);
* :func:`fixed_L_sweep` — the augmented LP with ``s0 = 0`` over a list of
  pole sets (Figs. 3a/3b of the augmented paper): one LP, built once, whose
  ``L``-dependent entries are rewritten per point; an undecided solve is
  re-solved by a second solver, an all-zero pole set gets a nilpotent ``L``.
"""

from __future__ import annotations

import time
from typing import Callable, Iterable, Sequence

import numpy as np

from eqrec.bounds.certify import certify_schedule
from eqrec.bounds.data_classes import classes_of_tree
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_language, extend_word, worst_case_pattern
from eqrec.lp.solvers import solve_lp, solve_lp_warm
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.runtime import schedule_from_augmented
from eqrec.design.classes.mu1_min import MinRecoveryLevel, min_recovery_level
from eqrec.design.observers import PolePlacement, deadbeat_observer, place_observer
from eqrec.design.prefix.design import design_prefix
from eqrec.design.prefix.tree_lp import build_prefix_lp
from eqrec.design.prefix.time_based import design_time_based
from eqrec.errors import InfeasibleDesign, InputError

DESIGNS = {"prefix": design_prefix, "time": design_time_based}


def lower_bound_probe(system: AffineSystem, words, mu1: float, mu2_opt: float, gap: float,
                      solvers: Sequence[str] = ("highs", "clarabel")) -> dict[str, str]:
    """Solver status of the prefix LP with the ``M2`` column bounded by ``mu2_opt - gap``, per solver.

    ``infeasible`` from every solver proves that no estimator of the class
    reaches ``mu2_opt - gap`` (Theorem 3 of the prefix-based paper is necessary and sufficient).

    Parameters
    ----------
    system : AffineSystem
        The system.
    words : sequence of str or ArrivalPattern
        The language.
    mu1 : float
        Recovery level ``M1``.
    mu2_opt : float
        The optimal ``M2`` found by a design.
    gap : float
        How far below ``mu2_opt`` the ``M2`` column is bounded.
    solvers : sequence of str, optional
        LP solvers to ask.

    Returns
    -------
    dict of str to str
        Solver name -> LP status (``"infeasible"`` expected from each).
    """
    model = build_prefix_lp(system, words, mu1)
    model.lp.col_upper[model.mu2_col] = mu2_opt - gap
    return {s: solve_lp(model.lp, s).status for s in solvers}


def min_feasible_mu1(system: AffineSystem, words, method: str = "prefix") -> MinRecoveryLevel:
    """The smallest recovery level ``M1`` of a prefix- or time-based estimator on ``words``, with its bracket.

    Feasibility is monotone in ``M1`` (gains recovering from ``M1`` recover
    from any larger level) and, by the separation theorem, a prefix design is
    feasible iff every terminal class reaches ``M1``: the smallest level is
    :func:`eqrec.design.classes.mu1_min.min_recovery_level` on the language's classes.
    The time-based design is the prefix design on the worst-case word alone.

    Parameters
    ----------
    system : AffineSystem
        The system.
    words : sequence of str or ArrivalPattern
        The language (0/1 words or patterns).
    method : {"prefix", "time"}, optional
        Prefix-based estimator, or time-based (the worst-case word only).

    Returns
    -------
    MinRecoveryLevel
        ``upper`` attained by certified gains, ``lower`` proven infeasible,
        the binding terminal class and row.

    Raises
    ------
    InputError
        If ``method`` is not ``"prefix"`` or ``"time"`` (field ``method``).
    """
    if method not in DESIGNS:
        raise InputError(f"unknown method {method!r}; choose one of {list(DESIGNS)}", None, "method")
    language = as_language(words, kind="missing")
    if method == "time":
        language = [worst_case_pattern(language)]
    return min_recovery_level(system, classes_of_tree(PrefixTree(language)))


def min_recovery_time(system: AffineSystem, words, mu1: float, T_max: int) -> int | None:
    """Minimum horizon ``T`` at which ``words`` (extended by measurements) admit recovery to ``M1``.

    Parameters
    ----------
    system : AffineSystem
        The system.
    words : sequence of str
        The 0/1 words, extended with ``1`` (measured) up to each tried ``T``.
    mu1 : float
        Recovery level ``M1``.
    T_max : int
        Largest horizon tried (from the longest word's length).

    Returns
    -------
    int or None
        The smallest feasible ``T``, or ``None`` if none up to ``T_max``.
    """
    for T in range(max(len(w) for w in words), T_max + 1):
        try:
            design_prefix(system, [extend_word(w, T) for w in words], mu1, certify=False)
            return T
        except InfeasibleDesign:
            continue
    return None


def mu2_curve(system: AffineSystem, words, mu1_values: Iterable[float], method: str = "prefix",
             on_point: Callable[[int, float], None] | None = None) -> list[float | None]:
    """Optimal ``M2`` for each ``M1`` (``None`` where the design is infeasible).

    Parameters
    ----------
    system : AffineSystem
        The system.
    words : sequence of str or ArrivalPattern
        The language.
    mu1_values : iterable of float
        The recovery levels ``M1`` to design at.
    method : {"prefix", "time"}, optional
        :func:`~eqrec.design.prefix.design.design_prefix` or :func:`~eqrec.design.prefix.time_based.design_time_based`.
    on_point : callable or None, optional
        Called as ``on_point(k, mu1)`` before the ``k``-th design (progress).

    Returns
    -------
    list of float or None
        The optimal ``M2`` per ``M1``, ``None`` where infeasible.
    """
    fn = DESIGNS[method]
    out: list[float | None] = []
    for k, mu1 in enumerate(mu1_values):
        if on_point is not None:
            on_point(k, float(mu1))
        try:
            out.append(fn(system, words, float(mu1)).mu2)
        except InfeasibleDesign:
            out.append(None)
    return out


#: LP statuses that settle a point (anything else is re-solved by the second solver).
DEFINITIVE = ("optimal", "infeasible")


def observer_for(system: AffineSystem, poles: np.ndarray, seed: int = 0):
    """Observer gain for a pole set and how it was made.

    ``place_poles``, or for an all-zero request (which ``place_poles`` refuses when a pole repeats more
    than ``rank C`` times) the exact nilpotent ``L`` of :func:`eqrec.design.observers.deadbeat_observer`.

    Parameters
    ----------
    system : AffineSystem
        The system (its ``A`` and ``C``).
    poles : numpy.ndarray
        The ``n`` requested eigenvalues of ``A - L C``.
    seed : int, optional
        Seed of the deadbeat construction (picks which nilpotent ``L``: it is not unique).

    Returns
    -------
    placement : PolePlacement
        The gain ``L`` (or why it failed).
    how : str
        ``"place_poles"`` or ``"deadbeat"``.
    """
    pp = place_observer(system.A, system.C, poles)
    if pp.ok or not np.allclose(np.asarray(poles, complex), 0.0):
        return pp, "place_poles"
    return deadbeat_observer(system.A, system.C, seed=seed), "deadbeat"


def fixed_L_sweep(system: AffineSystem, word: str, mu1: float, mode: str, poles_list: Iterable[np.ndarray],
                  solver: str = "highs", on_point: Callable[[], None] | None = None,
                  second_solver: str | None = "clarabel", certify_runtime: str | None = None,
                  deadbeat_seed: int = 0, observers: Sequence[tuple[PolePlacement, str]] | None = None,
                  warm_start: int = 0) -> list[dict]:
    """Optimal ``μ2`` of the augmented LP (``s0 = 0``, ``L`` by pole placement) for each pole set.

    Each record has ``status`` (``optimal``, ``infeasible``, ``placement_failed``
    or ``solver_failed``), ``mu2`` (``inf`` if infeasible, ``nan`` if not
    solved), ``message``, ``observer`` (``place_poles`` / ``deadbeat``, see
    :func:`observer_for`), ``solver`` (whose answer the status is),
    ``status_first`` and ``status_second`` (the second solver's status, empty
    when the first was definitive: ``optimal`` or ``infeasible``) and ``solve_time`` (seconds: LP and certificate).
    A point the first solver leaves undecided (e.g. HiGHS ``Unknown``) is
    re-solved with ``second_solver``; ``solver_failed`` means neither decided.

    With ``certify_runtime`` (``"theorem2"`` or ``"hold"``) the optimal gains are
    also certified as the estimator that runs (:func:`eqrec.bounds.certify.certify_schedule`
    on ``word``): ``certified_mu2`` and ``certified_terminal`` (``nan`` when not optimal).

    ``observers``: the :func:`observer_for` result of each pole set, when the
    caller has them already (a sweep of several words or readings over the same
    pole sets places each ``L`` once).

    ``warm_start``: the pole sets come in runs of that many consecutive ones (e.g. one θ line of the heat map,
    ``L`` moving a little from point to point), and with HiGHS each LP of a run starts from the optimal basis of
    the run's previous point (:func:`eqrec.lp.solvers.solve_lp_warm`; the first of each run, and the point after
    one that is not optimal, from scratch).  The optimum is each LP's own; where it is not unique the vertex (and
    so the certified gains, or the last bits of ``μ2``) may differ from a cold solve's, and depends on the order
    within a run only, never on how the runs are split into jobs.  About five times fewer simplex iterations on
    the augmented paper's sweeps.

    Parameters
    ----------
    system : AffineSystem
        The system.
    word : str
        The 0/1 word (the augmented paper's worst-case language ``{100111}`` in Fig. 3).
    mu1 : float
        Recovery level ``μ1``.
    mode : {"theorem2", "leak", "masked_gain"}
        Reading of the missing steps (:class:`eqrec.design.augmented.word_lp.AugmentedLP`).
    poles_list : iterable of numpy.ndarray
        The pole sets, each of ``n`` eigenvalues of ``A - L C``.
    solver : str, optional
        First LP solver.
    on_point : callable or None, optional
        Called with no argument after each point (progress).
    second_solver : str or None, optional
        Solver for a point the first leaves undecided (``None``: none).
    certify_runtime : str or None, optional
        ``"theorem2"`` or ``"hold"``: also certify the gains as the estimator that runs.
    deadbeat_seed : int, optional
        Seed of :func:`observer_for` for all-zero pole sets.
    observers : sequence of (PolePlacement, str) or None, optional
        Precomputed :func:`observer_for` results, one per pole set.
    warm_start : int, optional
        Length of the runs of warm-started LPs (``0``, the default: every LP from scratch; HiGHS only).

    Returns
    -------
    list of dict
        One record per pole set (keys above).
    """
    model = None
    rows = []
    poles_list = list(poles_list)
    if observers is None:
        observers = [observer_for(system, poles, deadbeat_seed) for poles in poles_list]
    if len(observers) != len(poles_list):
        raise InputError(f"{len(observers)} observers for {len(poles_list)} pole sets", None, "observers")
    if warm_start < 0:
        raise InputError(f"warm_start = {warm_start} < 0", None, "warm_start")
    warm = warm_start > 0 and solver == "highs"
    basis = None  # the optimal basis of the run's previous point
    for k, (pp, how) in enumerate(observers):
        t0 = time.perf_counter()
        if warm and k % warm_start == 0:
            basis = None
        rec = {"status": "placement_failed", "mu2": np.nan, "message": pp.message, "observer": how,
               "solver": "", "status_first": "", "status_second": ""}
        if certify_runtime:
            rec.update(certified_mu2=np.nan, certified_terminal=np.nan)
        if pp.ok:
            if model is None:
                model = AugmentedLP(system, word, mu1, pp.L, mode=mode)
            else:
                model.set_L(pp.L)
            if warm:
                sol, basis = solve_lp_warm(model.lp, basis)
            else:
                sol = model.solve(solver)
            rec.update(solver=solver, status_first=sol.status)
            if sol.status not in DEFINITIVE and second_solver:
                sol2 = model.solve(second_solver)
                rec["status_second"] = sol2.status
                if sol2.status in DEFINITIVE:
                    sol = sol2
                    rec["solver"] = second_solver
            rec.update(status=sol.status if sol.status in DEFINITIVE else "solver_failed",
                       mu2=float(sol.objective) if sol.optimal else (np.inf if sol.status == "infeasible" else np.nan),
                       message=pp.message if sol.optimal else sol.status)
            if certify_runtime and sol.optimal:
                cert = certify_schedule(system, schedule_from_augmented(system, model.gains(sol), certify_runtime),
                                        [word], mu1)
                rec.update(certified_mu2=cert.mu2, certified_terminal=cert.terminal)
        else:
            basis = None
        rec["solve_time"] = time.perf_counter() - t0
        rows.append(rec)
        if on_point is not None:
            on_point()
    return rows
