r"""Prefix-based equalized-recovery design (Theorem 3 of the prefix-based paper): the design entry point.

:func:`design_prefix` designs by the class engine (:mod:`eqrec.design.classes.engine`, the default) or by the
node-per-prefix tree LP of :mod:`eqrec.design.prefix.tree_lp` (``engine="tree"``), and certifies the gains
from the gains alone (:func:`eqrec.bounds.certify.certify_design`).  :func:`tree_design` turns a solved
tree LP into a :class:`~eqrec.design.result.Design`.  The time-based estimator of the authors' earlier
work is the special case of a single (worst-case) word.
"""

from __future__ import annotations

import numpy as np

from eqrec.bounds.certify import certify_design
from eqrec.bounds.data_classes import classes_of_tree
from eqrec.lp.model import LPSolution
from eqrec.lp.solvers import solve_lp
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.engine import class_design
from eqrec.design.inputs import FREE, check_flags, check_mu1, check_solver, check_system, language_tree
from eqrec.design.classes.mu1_min import infeasible_at, min_recovery_level
from eqrec.design.prefix.tree_lp import PrefixLP, build_prefix_lp, read_schedule
from eqrec.design.result import Design, Mu1Free
from eqrec.design.weighted import weigh
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure


#: The class engine (:mod:`eqrec.design.classes.engine`) or this module's tree LP.
ENGINES = ("classes", "tree")


def check_engine(engine: str) -> str:
    """``engine`` if it is one of :data:`ENGINES`, else :class:`~eqrec.errors.InputError`.

    Parameters
    ----------
    engine : str
        The engine name to check.

    Returns
    -------
    str
        ``engine`` unchanged.
    """
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {list(ENGINES)}", field="engine")
    return engine


def solve_tree_lp(model: PrefixLP, solver: str, what: str, options: dict | None = None) -> LPSolution:
    """Solve a built tree LP; its optimum, else :class:`InfeasibleDesign` or :class:`~eqrec.errors.SolverFailure`.

    The tree LP is bounded (every level is at least ``μ1 > 0``), so a solver's "unbounded" is numerical trouble:
    with ``μ1`` many orders above the noise bounds the robust rows mix coefficients ``μ1`` and ``η`` (HiGHS
    stops so at ``μ1 = 3e11`` on ``examples/two_mass.yaml``).  That is a :class:`~eqrec.errors.SolverFailure`
    naming the class engine, which solves each class row on its own and takes ``μ1`` up to ``1e12``.

    Parameters
    ----------
    model : PrefixLP
        The built LP (:func:`eqrec.design.prefix.tree_lp.build_prefix_lp`).
    solver : str
        LP solver.
    what : str
        What is solved, for the messages.
    options : dict or None, optional
        Solver options.

    Returns
    -------
    LPSolution
        The optimal solution.

    Raises
    ------
    InfeasibleDesign
        If the LP is infeasible.
    SolverFailure
        If the solver stops without an optimum, or calls the LP unbounded.
    """
    sol = solve_lp(model.lp, solver, options)
    if sol.status == "unbounded":
        raise SolverFailure(f"{what}: {solver} calls the tree LP unbounded, which it is not (every level is at least "
                            f"mu1): numerical trouble with mu1 = {model.mu1:g} far above the noise bounds; the class "
                            "engine (the default: engine='classes', --engine classes) solves this design")
    return sol.require_optimal(what)


def tree_design(model: PrefixLP, x: np.ndarray, solution: LPSolution, *, mu1: float,
                method: str, floor: bool = False, build_time: float | None = None) -> Design:
    """The :class:`Design` of a tree-LP point ``x``: node gains, node levels and the largest level ``mu2``.

    Parameters
    ----------
    model : PrefixLP
        The built LP (its stacked model holds the system the design is for).
    x : numpy.ndarray
        The LP point.
    solution : LPSolution
        The solver's record.
    mu1 : float
        Recovery level.
    method : str
        Label stored in :attr:`Design.method` (``"time"``: time-based node gains).
    floor : bool, optional
        Levels at least ``mu1`` (the delayed-data paper's ``μ2 >= μ1``,
        exact where the LP's bound is met only to the solver's tolerance).
    build_time : float or None, optional
        Seconds of building (default ``model.build_time``).

    Returns
    -------
    Design
        Uncertified (``engine = "tree"``).
    """
    lv = (lambda v: float(max(v, mu1))) if floor else float
    levels = {model.tree.nodes[i].label: lv(x[c]) for i, c in model.level_cols.items()}
    mu2 = max(levels.values(), default=mu1) if model.levels == "sum" else lv(x[model.mu2_col])
    design = Design(method=method, system=model.stacking.system, patterns=model.tree.patterns, T=model.stacking.T,
                    mu1=float(mu1),
                    mu2=mu2, schedule=read_schedule(model, x, time_based=(method == "time")), solution=solution,
                    build_time=model.build_time if build_time is None else build_time, levels=levels)
    return design


def design_prefix(system: AffineSystem, words, mu1: float, *, solver: str = "highs", T: int | None = None,
                  form: str = "split", certify: bool = True, method: str = "prefix",
                  zero_offset: bool = True, levels: str = "common", engine: str = "classes",
                  node_gains: bool = True, fixed_length: bool = True, state_weights=None, n_jobs=None,
                  scheduler=None) -> Design:
    r"""Minimise ``M2`` for a prefix-based estimator (Remark 2 / Theorem 3 of the prefix-based paper).

    The estimator (5) with the prefix-based output injection (7) of the
    prefix-based paper (Rutledge, Yong, Ozay, ACC 2019),

    .. math:: u_e(t) = u_0(t, q_{0:t}) + \sum_{\tau \le t} F(t, \tau, q_{0:t})\, y_\xi(\tau),

    has one gain row per prefix of the language, shared by the words through
    it (the set :math:`\mathcal Q(\mathcal L)` of Theorem 1 / eq. (11)).
    For a given recovery level ``M1 = mu1`` the design minimises the
    intermediate level ``M2`` subject to equalized recovery (eq. (12b)):
    ``‖ξ(t)‖∞ <= M2`` along every word and ``‖ξ(end)‖∞ <= M1``, for every
    ``‖ξ(0)‖∞ <= M1`` and noise in the box.  This is the LP of Remark 2 /
    Theorem 3 (eq. (16)), built per prefix-tree node instead of per word
    (the tree LP, :func:`build_prefix_lp`), or the equivalent class
    engine (:mod:`eqrec.design.classes.engine`).  With ``fixed_length=False``
    words may differ in length (Section V): ``M1`` is imposed at each
    word's end.

    Parameters
    ----------
    system : AffineSystem
        The system.
    words : sequence of str or ArrivalPattern, or PrefixTree
        0/1 missing-data words (strings are always read so: see
        :mod:`eqrec.arrivals.words`) or arrival patterns; delay patterns
        (:func:`eqrec.delay_words`) give the event-based design of the
        delayed-data paper (one gain block per event-prefix node).
    mu1 : float or "free"
        Recovery level ``μ1`` (``M1`` in the prefix-based paper), positive;
        ``"free"``: the smallest feasible ``μ1`` (``μ1,min`` of the class
        engine's μ1-free theorem, :func:`eqrec.min_recovery_level`, which
        covers every prefix tree).  Every level is nondecreasing in ``μ1``,
        so the design there also has the smallest ``M2`` over all ``μ1``;
        ``mu1_free`` (a :class:`~eqrec.design.result.Mu1Free`) records
        ``mu1_min``, ``mu1_min_lower`` (proven infeasible) and the binding class.  Where the LP meets the recovery
        constraint only to its tolerance, the returned ``mu1`` is raised to the
        smallest level its gains certify (a few ulps up, or up to ``1e-6``
        relative for a request just below ``μ1,min``; ``mu1_requested``
        keeps the request), and every other level to its certified worst case
        (:func:`eqrec.bounds.certify.certify_design`): the estimator reports
        these levels, which its error never exceeds.
    solver : str, optional
        LP solver, a name of :data:`eqrec.lp.solvers.SOLVER_NAMES`
        (default ``"highs"``).
    T : int or None, optional
        Tree LP only: horizon of the stacking (default: the longest word).
        The class engine designs on the words' own horizon and accepts only
        ``None`` or that horizon.
    form : str, optional
        Tree LP only: robust counterpart, ``"split"`` (default), ``"abs"`` or
        the paper's Π-dual ``"dual"`` of eq. (16).
    certify : bool, optional
        Certify the gains independently (:func:`eqrec.bounds.certify.certify_design`;
        default).
    method : str, optional
        Label stored in :attr:`Design.method` (default ``"prefix"``);
        ``"time"`` also makes the node gains time-based (as
        :func:`design_time_based` uses it).
    zero_offset : bool, optional
        Tree LP only: fix the offsets ``r`` (hence ``u0``) to zero (default;
        no loss of optimality, see the module docstring); ``False`` keeps
        the paper's free ``r``.  The class engine has no offsets.
    levels : {"common", "sum", "max"}, optional
        One common ``M2`` (default) or per-node levels (:func:`build_prefix_lp`);
        with per-node levels :attr:`Design.levels` holds them and ``mu2`` is
        the largest.
    engine : {"classes", "tree"}, optional
        The class engine (:mod:`eqrec.design.classes.engine`: one LP per (time,
        available data) class and row; default) or this module's tree LP.
    node_gains : bool, optional
        Class engine: also derive the node gains ``(F, u0)`` (``schedule``)
        and certify them by the independent recursion (default); without
        them the design holds the class gains ``K`` and their certificate
        (the estimator in class form).
    fixed_length : bool, optional
        Refuse words of different lengths, with the message of ``eqrec
        design`` (default); ``False`` designs a finite-length language
        (Section V of the prefix-based paper).
    state_weights : array_like or None, optional
        ``n`` positive per-state weights ``w``: every level and certificate
        then bounds ``max_i w_i |x_i − x̂_i|`` (the design is made on
        ``z = W x``, :meth:`AffineSystem.scaled`; :meth:`Design.estimator`
        runs in the original state).  ``None`` (default): ``‖x − x̂‖∞``.
    n_jobs : int or None, optional
        Class engine: worker processes of the per-class solves of a large language (default every core).
    scheduler : str, distributed.Client or None, optional
        Class engine: a Dask scheduler (``"tcp://host:8786"`` or a client) running them instead
        (:mod:`eqrec.design.classes.blocks`).

    Returns
    -------
    Design
        ``mu2`` the optimal ``M2``; its gains certified independently
        (:func:`eqrec.bounds.certify.certify_design`) unless ``certify=False``.

    Raises
    ------
    InputError
        Malformed words, words of mixed lengths (unless ``fixed_length=False``),
        a non-positive ``mu1``, an unknown ``engine`` or ``solver``, or
        tree-LP options (``T``, ``form``, ``zero_offset``) with the class engine.
    InfeasibleDesign
        If no prefix-based estimator achieves recovery level ``mu1``.
    SolverFailure
        If the solver stops without an optimum.
    CertificationFailure
        If the recovered gains do not achieve the optimum.

    Examples
    --------
    The language ``L1`` of Section VI of the prefix-based paper (one missing
    measurement among times 1-4), ``M1 = 1`` (the paper's value is compared in
    the claim row ``P1-M2:prefix-L1``); the intermediate level exceeds ``M1``:

    >>> import eqrec
    >>> design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111", "111011", "111101"], mu1=1.0)
    >>> design.mu2 > design.mu1
    True
    >>> design.certificate.terminal <= 1.0 + 1e-6
    True

    With ``μ1`` free, the smallest recovery level any prefix-based estimator reaches:

    >>> free = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111", "111011", "111101"], mu1="free")
    >>> round(free.mu1, 4), free.mu2 < design.mu2
    (0.2493, True)
    """
    system, weights = weigh(check_system(system), state_weights)
    check_engine(engine)
    check_solver(solver)
    check_flags(certify=certify, zero_offset=zero_offset, node_gains=node_gains, fixed_length=fixed_length)
    tree = language_tree(words, kind="missing", fixed_length=fixed_length, field_name="words")
    mu1 = check_mu1(mu1, allow_free=True)
    if engine == "classes":
        if T is not None and T != tree.depth:
            raise InputError(f"the class engine designs on the words' own horizon {tree.depth}, got T = {T}",
                             field="T")
        if form != "split" or not zero_offset:
            raise InputError("form and zero_offset choose the tree LP's formulation: use engine='tree'",
                             field="engine")
    # the design's one stacked model, over the words' horizon: μ1,min, the LPs, the gains and the certificate read
    # it (the tree LP on a longer horizon T builds its own: eqrec.bounds.stacking.Stacking.of)
    st = Stacking(system, tree.depth)
    mm = None
    if mu1 == FREE:  # the class engine's global optimum over μ1 (eqrec.design.classes.mu1_min), then the design there
        mm = min_recovery_level(st, classes_of_tree(tree), solver=solver, n_jobs=n_jobs, scheduler=scheduler)
        mu1 = mm.upper
    if engine == "classes":
        design = class_design(st, classes_of_tree(tree), mu1, levels=levels, solver=solver, method=method,
                              certify=certify, node_gains=node_gains, time_based=(method == "time"), n_jobs=n_jobs,
                              scheduler=scheduler)
    else:
        model = build_prefix_lp(st, tree, mu1, T=T, form=form, zero_offset=zero_offset, levels=levels)
        try:
            sol = solve_tree_lp(model, solver, f"{method} design (mu1 = {mu1:g})")
        except InfeasibleDesign as exc:
            raise infeasible_at(st, classes_of_tree(tree), mu1, exc, solver=solver, method=method) from None
        design = tree_design(model, sol.x, sol, mu1=model.mu1, method=method)
        if certify:
            certify_design(design)
    if mm is not None:
        design.mu1_free = Mu1Free("global", mu1_min=mm.upper, mu1_min_lower=mm.lower, binding=mm.binding)
    design.state_weights = weights
    return design
