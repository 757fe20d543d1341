r"""Equalized-recovery design with delayed and missing data (Theorem 1 / Proposition 1 of the delayed-data paper).

The delayed-data paper ("P3") designs, for a language of delay words, one gain
triplet per event sequence of the reduced event language ``L^{E'}``, shared
along common event prefixes (constraint (6)), zero on data not yet available
(constraint (7)), with a level ``μ2,k^α`` per sequence and time and the
recovery level ``μ1`` as a decision variable.

Engines
-------
* ``engine="classes"`` (default): the class engine of
  :mod:`eqrec.design.classes.engine`.  The problem separates exactly into one small
  LP per (time, available data) class and state row (the separation theorem
  proved there); nodes of one class share their level.  Full languages
  ``{0..τ̄}^T`` are handled from the window rule without enumerating words
  (:func:`delay_classes`), so ``(30, 4)`` (9.3·10²⁰ words, 446 classes) is
  one LP of a few hundred thousand columns.
* ``engine="tree"``: the node-per-prefix LP (:func:`eqrec.design.prefix.tree_lp.build_prefix_lp`), one gain
  row per event-prefix node over the measurements available at its time (late ones included), one level
  per non-terminal node.  It stays as the independent cross-check (the tests compare the two node by node)
  and for the paper-comparison rows.

The cost
--------
``cost="sum"`` is the paper's ``J = μ1 + Σ_{k=0}^{T} Σ_{α=1}^{|L^{E'}|} μ2,k^α``
over the reduced language, each node's level paid by the sequences through
it and ``k = 0``, ``k = T`` at ``μ1`` (counted in :mod:`eqrec.design.cost`);
``cost="max"``: the largest level (the prefix-based paper's ``M2``).

``μ1`` fixed: :func:`design_delay`.

``μ1`` free: the problem (10) is bilinear (the ``|G_ξ0| μ1`` terms).  Two routes:

* :func:`design_delay_global` — the global optimum by the μ1-free theorem of
  :mod:`eqrec.design.classes.mu1_min`: every class level is nondecreasing in ``μ1``,
  so ``J`` is, and the optimum is the smallest feasible ``μ1``, one
  Charnes–Cooper LP (:func:`eqrec.design.classes.mu1_min.min_recovery_level`),
  certified by the ratio recomputed from the gains (upper end) and a dual
  point (lower end);
* :func:`eqrec.design.delay.ipopt.design_delay_ipopt` — the paper's: IPOPT through CasADi on (10) in
  the split robust form of the tree LP, started from an LP solution (a local
  method), kept for the comparison row.

Every returned design is certified from its gains alone: the class
certificate (worst case of ``E_d − K Z_S``) and, where node gains are derived,
:func:`eqrec.bounds.certify.certify_design` on every sequence.  Reading a design
(levels per prefix, certificates per word, the CLI's JSON): :mod:`eqrec.design.report`.
"""

from __future__ import annotations

import contextlib
import time

import numpy as np

from eqrec.bounds.certify import certify_design
from eqrec.checks import instance
from eqrec.bounds.data_classes import classes_of_tree
from eqrec.lp.model import LPSolution
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.lp.parallel import check_jobs, check_scheduler, connected, settle
from eqrec.lp.solvers import solver_info
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.blocks import choose_path, prestart_workers
from eqrec.design.classes.engine import check_terminal, class_design, solve_classes, solve_classes_at
from eqrec.design.cost import certified_cost, check_cost, class_cost, paper_cost
from eqrec.design.delay.languages import delay_classes, delay_language  # noqa: F401 (re-exported)
from eqrec.design.delay.languages import patterns_classes, patterns_tree
from eqrec.design.inputs import check_flags, check_fraction, check_mu1, check_solver, check_system, growth_hint
from eqrec.design.classes.mu1_min import MU1_LOWER_RTOL, FreeMu1Result, MinRecoveryLevel, infeasible_at
from eqrec.design.classes.mu1_min import min_recovery_level as _class_min_recovery_level
from eqrec.design.prefix.design import check_engine, solve_tree_lp, tree_design
from eqrec.design.prefix.tree_lp import PrefixLP, build_prefix_lp
from eqrec.design.result import Design, Mu1Free
from eqrec.design.weighted import weigh
from eqrec.errors import CertificationFailure, InfeasibleDesign, InputError, SolverFailure

# ---------------------------------------------------------------------------
# Designs from LP solutions
# ---------------------------------------------------------------------------

def design_from_solution(model: PrefixLP, tree: PrefixTree, x: np.ndarray, mu1: float, cost: str, sol: LPSolution,
                         *, build_time: float = 0.0, certify: bool = True, rtol: float = 1e-6,
                         method: str = "delay") -> Design:
    """The delayed-data design of a tree-LP point ``x`` (levels at least ``μ1``), its ``J`` and certificate.

    Certification raises any level (``μ1`` included) that the gains exceed to their worst case
    (:func:`eqrec.bounds.certify.certify_design`); ``J`` is counted at the levels as stored.  Shared by the LP
    route (:func:`design_delay`, engine ``tree``) and the IPOPT route (:mod:`eqrec.design.delay.ipopt`).

    Parameters
    ----------
    model : PrefixLP
        The tree LP (or NLP) whose variables ``x`` holds; its stacked model holds the system.
    tree : PrefixTree
        The language's prefix tree (the cost counts its sequences).
    x : numpy.ndarray
        The solver's point: gains and levels.
    mu1 : float
        The recovery level (the floor of every level).
    cost : {"sum", "max"}
        The cost ``J`` (:func:`eqrec.design.cost.paper_cost`).
    sol : LPSolution
        The solver's answer (status, timings), kept in the design.
    build_time : float, optional
        Seconds spent building the model.
    certify : bool, optional
        Certify the gains (default ``True``).
    rtol : float, optional
        Relative tolerance of the certificate.
    method : str, optional
        The design's method name.

    Returns
    -------
    Design
        The design, with its cost ``J`` (and ``J_certified`` when certified), sequences and nodes.
    """
    design = tree_design(model, x, sol, mu1=mu1, method=method, floor=True, build_time=build_time)
    cert = certify_design(design, rtol=rtol) if certify else None
    levels = design.levels if cost == "sum" else {"*": design.mu2}
    design.cost, design.J = cost, paper_cost(tree, design.mu1, levels, cost)
    design.sequences, design.nodes = len(tree.patterns), len(tree)
    if cert is not None:
        design.J_certified = certified_cost(design, tree, cost, cert)
    return design


@contextlib.contextmanager
def _horizon_hint(system: AffineSystem, horizon: int):
    """A solver or certification failure of an unstable plant over a long horizon says why
    (:func:`eqrec.design.inputs.growth_hint`); so does an infeasibility past what an LP resolves (``ρ^T`` over
    :data:`~eqrec.design.inputs.RESOLVED_GROWTH`), which may be the solver's and not the plant's."""
    try:
        yield
    except (SolverFailure, CertificationFailure) as exc:
        hint = growth_hint(system, horizon)
        if not hint or hint in str(exc):
            raise
        raise type(exc)(f"{exc}; {hint}") from exc
    except InfeasibleDesign as exc:  # past what an LP resolves, "infeasible" may be the solver's verdict, not the plant's
        hint = growth_hint(system, horizon, suspect=True)
        if not hint or hint in str(exc):
            raise
        raise InfeasibleDesign(f"{exc}; {hint}", mu1_min=exc.mu1_min) from exc


def check_design_size(system: AffineSystem, classes, *, mu1_free: bool, n_jobs, scheduler, force: bool) -> None:
    """The size check of a class-engine design from Python, the model and the answer of ``eqrec design``.

    Parameters
    ----------
    system : AffineSystem
        The plant (in the design's coordinates).
    classes : ClassSet
        The classes to design for.
    mu1_free : bool
        A μ1-free design (level LPs at two μ1).
    n_jobs : int or None
        Worker processes (``None``: every core).
    scheduler : object or None
        A Dask scheduler (the estimate then assumes one core here).
    force : bool
        Run past the documented size anyway.

    Raises
    ------
    InputError
        Past the documented size without ``force`` (field ``patterns``; nothing started).
    """
    from eqrec.design.inputs import check_flags, estimate_classes, report_size, size_checked
    from eqrec.lp.parallel import check_jobs

    check_flags(force=force)
    if size_checked():  # the command line checked this design already (and printed its estimate)
        return
    if len(classes) < SIZE_CHECK_CLASSES:  # small designs: seconds at most, no estimate needed
        return
    workers = 1 if scheduler is not None else check_jobs(n_jobs)
    report_size(estimate_classes(system, classes, mu1_free=mu1_free, workers=workers), force=force,
                field="patterns", advice="design a shorter horizon or a smaller language")


#: Classes below which a design is not estimated (seconds at most on every plant of the project).
SIZE_CHECK_CLASSES = 200


# -------- μ1 fixed

def design_delay(system: AffineSystem, patterns, mu1: float, *, kind: str | None = None, cost: str = "sum",
                 solver: str = "highs", form: str = "split", certify: bool = True, solver_options: dict | None = None,
                 engine: str = "classes", node_gains: bool | None = None, state_weights=None, n_jobs=None,
                 scheduler=None, solved=None, force: bool = False) -> Design:
    r"""The delayed-data design with ``μ1`` fixed (Theorem 1 / Proposition 1 of the delayed-data paper).

    For a language of delay words (eq. (1) of the delayed-data paper,
    Hassaan, Shen, Yong), reduced to its distinct event sequences
    ``L^{E'}`` (Definitions 2-4, eq. (2)), one gain block per event-prefix
    node: gains shared along common event prefixes (constraint (6)), zero on
    data not yet available (constraint (7)), with a level ``μ2,k^α`` per
    sequence and time.  With the recovery level ``μ1`` fixed, as in
    Section IV-B of the paper, the problem (8) of Theorem 1, robustified in
    Proposition 1 / eq. (10), is a linear program; it minimises

    .. math:: J = \mu_1 + \sum_{k=0}^{T} \sum_{\alpha=1}^{|L^{E'}|} \mu_{2,k}^\alpha

    (``cost="sum"``, the paper's cost, counted as in the module docstring)
    or the largest level :math:`\max_{k,\alpha} \mu_{2,k}^\alpha`
    (``cost="max"``, the prefix-based paper's common ``M2``).  For ``μ1``
    free see :func:`design_delay_global`.

    Parameters
    ----------
    system : AffineSystem
        The system.
    patterns : sequence of str or ArrivalPattern, PrefixTree or ClassSet
        Words (read as ``kind`` says), arrival patterns (e.g.
        :func:`eqrec.delay_words`, :func:`eqrec.missing_words`) or their tree
        (reduced to ``L^{E'}``), or the classes of a full language
        (:func:`delay_classes`, class engine only).  The language must have
        a fixed length.
    mu1 : float
        Recovery level ``μ1``, positive.  The design's ``mu1`` may be raised
        above it by the LP's round-off, to the level its gains certify
        (``mu1_requested`` keeps the request; every level is at least
        its certified worst case, exactly: :func:`eqrec.bounds.certify.certify_design`).
    kind : {"missing", "delay"} or None, optional
        Reading of string words: delay words (digits, eq. (1)) or 0/1
        missing-data words.  ``None`` (default): delay words when a word has a
        digit ``2-9``; a list of 0/1 strings is refused as ambiguous
        (:mod:`eqrec.arrivals.words`).
    cost : {"sum", "max"}, optional
        The paper's ``J`` (module docstring; default) or the largest level.
    solver : str, optional
        LP solver, a name of :data:`eqrec.lp.solvers.SOLVER_NAMES`
        (default ``"highs"``).
    form : str, optional
        Robust counterpart of the tree LP (``engine="tree"`` only):
        ``"split"`` (default), ``"abs"`` or the Π-dual ``"dual"``.
    certify : bool, optional
        Certify the gains independently (default).
    solver_options : dict or None, optional
        Options passed to the LP solver (``None``: the engine's defaults).
    engine : {"classes", "tree"}, optional
        The class engine (default) or the tree LP (module docstring).
    node_gains : bool or None, optional
        Class engine: derive node gains (default: small trees, see
        :func:`eqrec.design.classes.engine.class_design`).
    state_weights : array_like or None, optional
        ``n`` positive per-state weights ``w``: the levels then bound
        ``max_i w_i |x_i − x̂_i|`` (designed on ``z = W x``,
        :mod:`eqrec.design.weighted`).  ``None`` (default): ``‖x − x̂‖∞``.
    n_jobs : int or None, optional
        Worker processes of the class engine's per-class solves (large languages; default every core).
    scheduler : str, distributed.Client or None, optional
        A Dask scheduler (``"tcp://host:8786"`` or a client) running those solves instead
        (:mod:`eqrec.design.classes.blocks`; the same result as on this machine).
    solved : ClassSolution or None, optional
        Class engine: the class LPs already solved at ``mu1`` (:func:`eqrec.design.classes.engine.solve_classes_at`).
    force : bool, optional
        Class engine: run a design past the documented size anyway.  The size model of ``eqrec design``
        (:func:`eqrec.design.inputs.estimate_classes`) estimates its time and memory first: printed from
        :data:`~eqrec.design.inputs.ESTIMATE_PRINT_SECONDS` on, refused past
        :data:`~eqrec.design.inputs.MAX_ESTIMATED_SECONDS` or the memory limit unless ``force``.

    Returns
    -------
    Design
        ``method="delay"``, ``mu2`` the largest level, ``levels`` per
        non-terminal event-prefix node (``"sum"``), ``J`` the cost
        (``J_certified`` from the certificate).

    Raises
    ------
    InputError
        Malformed or ambiguous words, a language of mixed lengths, a
        non-positive ``mu1``, an unknown ``cost``, ``engine`` or ``solver``, or
        a design past the documented size without ``force`` (field ``patterns``).
    InfeasibleDesign
        If no estimator recovers to ``mu1``.
    SolverFailure
        If the solver stops without an optimum.
    CertificationFailure
        If the recovered gains do not achieve the optimal levels.

    Examples
    --------
    The adaptive-cruise-control comparison of Section IV-B: the missing-data
    language ``L1`` written as delay words (``6`` = beyond the horizon) gives
    the prefix-based design of the same words (claim row ``P3-ACC``):

    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> design = eqrec.design_delay(acc, ["060000", "006000", "000600", "000060"], mu1=1.0)
    >>> prefix = eqrec.design_prefix(acc, ["101111", "110111", "111011", "111101"], mu1=1.0)
    >>> abs(design.mu2 - prefix.mu2) < 1e-9
    True

    0/1 words read two ways, so they need ``kind`` (or typed patterns):

    >>> missing = eqrec.design_delay(acc, ["101111", "110111", "111011", "111101"], 1.0, kind="missing")
    >>> missing.mu2 == design.mu2
    True
    """
    system, weights = weigh(check_system(system), state_weights)
    check_cost(cost)
    check_engine(engine)
    check_flags(certify=certify, node_gains=node_gains)
    instance(solver_options, (dict, type(None)), "solver_options", "a dict or None")
    mu1 = check_mu1(mu1)
    language = patterns_classes(patterns, kind) if engine == "classes" else patterns_tree(patterns, kind)
    if engine == "classes" and solved is None:
        check_design_size(system, language, mu1_free=False, n_jobs=n_jobs, scheduler=scheduler, force=force)
    st = Stacking(system, language.horizon if engine == "classes" else language.depth)  # the design's one stacking
    with _horizon_hint(system, st.T):
        design = _design_on(st, language, mu1, cost=cost, solver=solver, form=form, certify=certify,
                            solver_options=solver_options, engine=engine, node_gains=node_gains, n_jobs=n_jobs,
                            scheduler=scheduler, solved=solved)
    design.state_weights = weights
    return design


def _design_on(st: Stacking, language, mu1: float, *, cost: str, solver: str, form: str, certify: bool,
               solver_options: dict | None, engine: str, node_gains: bool | None, n_jobs, scheduler,
               solved) -> Design:
    """:func:`design_delay` on the design's stacked model ``st``, its inputs checked.

    ``language`` is the class set (class engine) or the prefix tree (tree LP) over the horizon of ``st``; the LPs,
    the gains, the certificate and the fallback to ``μ1,min`` read ``st``, and the cost reads the design.
    """
    rtol = 1e-6 + solver_info(solver).accuracy
    if engine == "classes":
        classes = language
        design = class_design(st, classes, mu1, levels="sum" if cost == "sum" else "common", cost=cost,
                              solver=solver, solver_options=solver_options, method="delay", certify=certify,
                              node_gains=node_gains, rtol=rtol, n_jobs=n_jobs, scheduler=scheduler, solved=solved)
        if design.certificate is not None and classes.tree is not None:
            design.J_certified = certified_cost(design, classes.tree, cost)
        elif design.class_certificate is not None:
            design.J_certified = class_cost(classes, design.mu1, design.class_certificate.levels, cost)
    else:
        tree = language
        model = build_prefix_lp(st, tree, mu1, levels="sum" if cost == "sum" else "common", form=form)
        try:
            sol = solve_tree_lp(model, solver, f"delay design (mu1 = {mu1:g})", solver_options)
        except InfeasibleDesign as exc:
            raise infeasible_at(st, classes_of_tree(tree), mu1, exc, solver=solver, method="delay") from None
        design = design_from_solution(model, tree, sol.x, mu1, cost, sol, build_time=model.build_time,
                                      certify=certify, rtol=rtol)
    return design


def design_lp_status(system: AffineSystem, patterns, mu1: float, cost: str = "sum", solver: str = "highs", *,
                     kind: str | None = None, n_jobs=None, scheduler=None) -> str:
    """Whether a design at ``μ1`` exists: ``"optimal"``, or ``"infeasible"`` (no estimator recovers to ``mu1``).

    Parameters
    ----------
    system : AffineSystem
    patterns : sequence of str or ArrivalPattern, PrefixTree or ClassSet
        The language, as for :func:`design_delay`.
    mu1 : float
    cost : str, optional
    solver : str, optional
        Recovery level, cost (checked only) and LP solver.
    kind : {"missing", "delay"} or None, optional
        Reading of string words, as for :func:`design_delay`.
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional
        Where the class LPs run, as for :func:`design_delay`.

    Returns
    -------
    str
        ``"optimal"`` iff every terminal class reaches ``μ1`` (separation theorem,
        :func:`eqrec.design.classes.engine.check_terminal`), else ``"infeasible"`` (never raised).
    """
    check_cost(cost)
    classes = patterns_classes(patterns, kind)
    try:
        check_terminal(classes, solve_classes(check_system(system), classes, check_mu1(mu1), solver=solver,
                                              n_jobs=n_jobs, scheduler=scheduler))
    except InfeasibleDesign:
        return "infeasible"
    return "optimal"


# -------- μ1 free: the global optimum (the μ1-free theorem of eqrec.design.classes.mu1_min)

def min_recovery_level(system: AffineSystem, patterns, *, kind: str | None = None, solver: str = "highs",
                       rtol: float = MU1_LOWER_RTOL, n_jobs=None, scheduler=None) -> MinRecoveryLevel:
    """The smallest ``μ1`` for which some estimator recovers (``‖ξ(T)‖ <= μ1`` for all ``‖ξ0‖ <= μ1``).

    Parameters
    ----------
    system : AffineSystem
    patterns : sequence of str or ArrivalPattern, PrefixTree or ClassSet
        The language, as for :func:`design_delay`.
    kind : {"missing", "delay"} or None, optional
        Reading of string words, as for :func:`design_delay`.
    solver : str, optional
    rtol : float, optional
        LP solver; relative distance below ``μ1,min`` of the level proven infeasible.
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional
        Where the Charnes–Cooper LPs run, as for :func:`design_delay`.

    Returns
    -------
    MinRecoveryLevel
        ``upper`` attained by certified gains, ``lower = upper (1 - rtol)`` infeasible (:mod:`eqrec.design.classes.mu1_min`).
    """
    return _class_min_recovery_level(system, patterns_classes(patterns, kind), solver=solver, lower_rtol=rtol, n_jobs=n_jobs,
                                     scheduler=scheduler)


@contextlib.contextmanager
def _workers_ahead(system: AffineSystem, classes, n_jobs, scheduler):
    """The local workers of the level LPs started while μ1,min is computed, and settled on exit."""
    started = prestart_workers(system, classes, n_jobs, scheduler)
    try:
        yield
    finally:
        if started:
            settle()


def design_delay_global(system: AffineSystem, patterns, *, kind: str | None = None, cost: str = "sum",
                        solver: str = "highs", rtol: float = MU1_LOWER_RTOL, certify: bool = True,
                        node_gains: bool | None = None, engine: str = "classes", state_weights=None,
                        n_jobs=None, scheduler=None, force: bool = False) -> FreeMu1Result:
    """The global minimum of ``J`` over ``μ1`` and the gains: the design at ``μ1 = μ1,min``.

    The delayed-data paper's problem with ``μ1`` a decision variable
    (Theorem 1 / Proposition 1, eq. (10)), which is bilinear and which the
    paper solves locally with IPOPT.  By the μ1-free theorem
    (:mod:`eqrec.design.classes.mu1_min`) ``J`` is nondecreasing on the feasible set
    ``[μ1,min, ∞)``, so the global optimum is the design at ``μ1,min``,
    which comes from one Charnes–Cooper LP
    (:func:`eqrec.design.classes.mu1_min.min_recovery_level`).  ``rtol`` places the
    certified infeasible level ``lower = μ1,min (1 - rtol)``;
    ``lower_bound`` is ``J`` with every class at its optimum there (no
    feasible ``μ1`` gives less).  ``engine`` designs at ``μ1,min`` with the
    class engine or the tree LP (same optimum, possibly other optimal gains;
    ``μ1,min`` and the bound always come from the classes).

    Parameters
    ----------
    system : AffineSystem
        The system.
    patterns : sequence of str or ArrivalPattern, PrefixTree or ClassSet
        The language, as for :func:`design_delay`.
    kind : {"missing", "delay"} or None, optional
        Reading of string words, as for :func:`design_delay` (0/1 strings need it).
    cost : {"sum", "max"}, optional
        The paper's ``J`` (default) or ``μ1`` plus the largest level.
    solver : str, optional
        LP solver, a name of :data:`eqrec.lp.solvers.SOLVER_NAMES`
        (default ``"highs"``).
    rtol : float, optional
        Relative distance below ``μ1,min`` of the level proven infeasible
        (default :data:`eqrec.design.classes.mu1_min.MU1_LOWER_RTOL`).
    certify : bool, optional
        Certify the design's gains independently (default).
    node_gains : bool or None, optional
        Class engine: derive node gains (default: small trees).
    engine : {"classes", "tree"}, optional
        Engine of the design at ``μ1,min`` (default the class engine; the
        tree LP needs the language's words).
    state_weights : array_like or None, optional
        ``n`` positive per-state weights ``w``: the levels then bound
        ``max_i w_i |x_i − x̂_i|`` (designed on ``z = W x``,
        :mod:`eqrec.design.weighted`).  ``None`` (default): ``‖x − x̂‖∞``.
    n_jobs : int or None, optional
        Worker processes of the class engine's per-class solves (large languages; default every core).
    scheduler : str, distributed.Client or None, optional
        A Dask scheduler (``"tcp://host:8786"`` or a client) running those solves instead
        (:mod:`eqrec.design.classes.blocks`; the same result as on this machine).
    force : bool, optional
        Run a design past the documented size anyway (the size model of :func:`design_delay`, at both ``μ1``
        of the μ1-free route: printed, then refused past the limits unless ``force``).

    Returns
    -------
    FreeMu1Result
        ``design`` at ``μ1,min`` (certified), ``mu1`` (the design's: ``μ1,min``, or a few ulps above
        it where the LP's round-off left a terminal worst case above ``μ1,min``), ``J``,
        ``lower_bound`` and ``gap``, ``mu1_min`` (bracket, binding terminal
        class and row).  Not a :class:`Design` itself: the design is its
        ``design`` attribute.

    Raises
    ------
    InputError
        Malformed words, an unknown ``cost`` or ``engine``,
        ``μ1,min = 0`` (no noise reaches the end of the horizon), or a design past the documented size
        without ``force`` (field ``patterns``).
    InfeasibleDesign
        If no recovery level is feasible.
    SolverFailure, CertificationFailure
        As :func:`design_delay` (also for the Charnes–Cooper LP of ``μ1,min``).

    Examples
    --------
    The batch reactor of Section IV-A (``T = 5``, delays up to 2); the paper's
    values are compared in the claim rows ``P3-BR``:

    >>> import eqrec
    >>> result = eqrec.design_delay_global(eqrec.batch_reactor(), eqrec.full_delay_language(5, 2))
    >>> round(result.mu1, 4), round(result.mu2, 4)
    (0.3293, 0.6897)
    >>> result.design.mu1 == result.mu1
    True
    """
    check_cost(cost)
    t_start = time.perf_counter()
    check_engine(engine)
    system, weights = weigh(check_system(system), state_weights)
    check_solver(solver)
    check_flags(certify=certify, node_gains=node_gains)
    rtol = check_fraction(rtol, "rtol")
    classes = patterns_classes(patterns, kind)
    check_jobs(n_jobs)
    scheduler = check_scheduler(scheduler)
    check_design_size(system, classes, mu1_free=True, n_jobs=n_jobs, scheduler=scheduler, force=force)
    st = Stacking(system, classes.horizon)  # the one stacked model of μ1,min, both level LPs and the design
    large = choose_path("auto", classes, None, system) == "blocks"  # else no class LP runs on the scheduler
    with _horizon_hint(system, classes.horizon), connected(scheduler if large else None) as client, \
            _workers_ahead(system, classes, n_jobs, client):
        par = {"n_jobs": n_jobs, "scheduler": client}  # one connection, one pool, for the three steps
        mm = _class_min_recovery_level(st, classes, solver=solver, lower_rtol=rtol, **par)
        # the levels at μ1,min (the design) and at the level proven infeasible (the bound), in one pass per class
        at = [mm.upper] + ([mm.lower] if np.isfinite(mm.lower) else [])
        if engine == "tree":
            if classes.tree is None:
                raise InputError("the tree engine needs the language's words (a prefix tree)", field="engine")
            sols = [None, *solve_classes_at(st, classes, at[1:], solver=solver, **par)]
            design = _design_on(st, classes.tree, mm.upper, cost=cost, solver=solver, form="split", certify=certify,
                                solver_options=None, engine="tree", node_gains=None, n_jobs=None, scheduler=None,
                                solved=None)
        else:
            sols = solve_classes_at(st, classes, at, solver=solver, **par)
            design = _design_on(st, classes, mm.upper, cost=cost, solver=solver, form="split", certify=certify,
                                solver_options=None, engine="classes", node_gains=node_gains, solved=sols[0], **par)
        lower_bound = class_cost(classes, mm.lower, sols[1].levels, cost) if len(at) > 1 else np.nan
    J = float(design.J)
    design.state_weights = weights
    design.mu1_free = Mu1Free("global", mu1_min=mm.upper, mu1_min_lower=mm.lower, binding=mm.binding,
                              lower_bound=lower_bound)
    return FreeMu1Result(design=design, route="global", cost=cost, mu1=design.mu1, J=J, lower_bound=float(lower_bound),
                         lps=mm.lps + 2, time=time.perf_counter() - t_start, mu1_min=mm)
