"""The augmented LP over a list of observer gains (Figs. 3a/3b of the augmented paper).

:func:`fixed_L_sweep` solves the augmented LP with ``s0 = 0`` for each pole set: one LP, built once, whose
``L``-dependent entries are rewritten per point (:meth:`eqrec.design.augmented.word_lp.AugmentedLP.set_L`),
warm-started along runs of neighbouring points if asked; an undecided solve is re-solved by a second solver,
an all-zero pole set gets a nilpotent ``L`` (:func:`observer_for`).
"""

from __future__ import annotations

import time
from typing import Callable, Iterable, Sequence

import numpy as np

from eqrec.bounds.certify import certify_schedule
from eqrec.design.augmented.runtime import schedule_from_augmented
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.observers import PolePlacement, deadbeat_observer, place_observer
from eqrec.errors import InputError
from eqrec.lp.solvers import solve_lp_warm
from eqrec.systems.affine import AffineSystem

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
