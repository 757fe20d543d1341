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

The augmented LP over a list of pole sets (Figs. 3a/3b of the augmented paper) is
:func:`eqrec.design.augmented.sweep.fixed_L_sweep`.
"""

from __future__ import annotations

from typing import Callable, Iterable, Sequence

from eqrec.bounds.data_classes import classes_of_tree
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_language, extend_word, worst_case_pattern
from eqrec.lp.solvers import solve_lp
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.mu1_min import MinRecoveryLevel, min_recovery_level
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
