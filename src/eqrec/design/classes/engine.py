r"""The class engine: every prefix-tree design as independent LPs per (time, available data) class.

Setting
-------
The prefix-based paper (Theorem 3) and the delayed-data paper (Theorem 1,
Proposition 1) design one gain row per node of the prefix tree of a
language.  With :math:`\delta = (w, v, \xi_0)` in the box of radii
:math:`\beta = (\eta_w, \eta_v, \mu_1)`, the error after the prefix of a node
of depth ``d`` is, in the Q-parametrisation (eq. (13) of the prefix-based
paper restricted to the prefix),

.. math:: \xi(d) = \Big(E_d + \sum_{s<d} \Phi(d, s{+}1)\, Q_s Z_{S_s}\Big)\delta,

where :math:`E_d` is the open-loop error map, :math:`Z_S` stacks the output
maps of the measurements in ``S``, :math:`S_s = \mathcal A(s)` is the data
available at time ``s`` along the prefix (nested: :math:`S_s \subseteq
S_{d-1} =: S`) and :math:`Q_s` the gain row of the ancestor of depth ``s+1``.
The pair ``(d, S)`` is the node's class (:mod:`eqrec.bounds.data_classes`).

Theorem (separation)
--------------------
*The set of error maps a node can attain is* :math:`\{E_d - K Z_S : K \in
\mathbb R^{n \times |S|p}\}`, *whatever its ancestors' gains.  Hence, for*
``μ1`` *fixed:*

1. *the smallest level of a node is that of its class,*

   .. math:: \ell(d, S) = \max_r \min_{k} \sum_c \beta_c\, \big|E_d[r, c] - (k^\top Z_S)[c]\big|,

   *one weighted least-absolute-deviations LP per (class, state row* ``r``\ *);*
2. *the tree LP's optimum is* :math:`\max(\mu_1, \max_{\text{inner}} \ell)`
   *(common level, the prefix-based paper's* ``M2``\ *) or*
   :math:`(1 + 2|\mathcal L^{E'}|)\mu_1 + \sum_{\text{inner}} w\,\max(\mu_1,
   \ell)` *(the delayed-data paper's sum, weights* ``w`` *the sequences
   through the class), and the design is feasible iff* :math:`\ell(T, S) \le
   \mu_1` *for every terminal class.*

*Proof.* The node's own gain :math:`Q_{d-1}` multiplies :math:`Z_{S}` and
each ancestor's :math:`Z_{S_s}` is a sub-block of rows of :math:`Z_S`, so
the sum is :math:`-K Z_S` for :math:`-K = Q_{d-1} + \sum_{s<d-1}\Phi(d,
s{+}1) Q_s P_s` (:math:`P_s` embedding ``S_s`` in ``S``).  For any ancestor
gains, every ``K`` is reached by :math:`Q_{d-1} = -K - \sum_{s<d-1}\dots`,
and every choice gives some ``K``.  The worst case of row ``r`` over the box
is :math:`\sum_c \beta_c |(E_d - K Z_S)[r, c]|` (a symmetric box, attained
at a vertex); rows of ``K`` are free independently, nodes independently
(each node's ``Q_{d-1}`` is its own variable).  Two nodes of one class have
the same :math:`E_d, Z_S`, hence the same minimum.  The tree LP's
constraints couple nodes only through the common level or the cost, both
monotone in each node's level, so the optimum takes each node at its
minimum.  ∎

Gains.  The **class-form estimator** :math:`\hat x(d) = \bar x(d) +
K_{(d,S)}(y_S - \bar y_S)` (:class:`eqrec.estimators.causal.ClassEstimator`)
has error :math:`(E_d - K Z_S)\delta` exactly, so it attains every class
level with one ``K`` per class and no prefix tree at run time; no causal
affine estimator does better (its error has this form).  Node gains for the
recursive estimator follow from the ``K``\ s (:func:`node_schedule`):
:math:`Q_{d-1} = -K_{(d,S)} + A(d-1)\,K_{(d-1,S')}P`, and then ``(F, u0)`` by
eqs. (1)-(2) of the prefix-based paper.

μ1 free.  Every class level is nondecreasing in ``μ1``, so the global optimum
over ``μ1`` and the gains is the smallest feasible ``μ1``: the μ1-free theorem
and its Charnes–Cooper LP are in :mod:`eqrec.design.classes.mu1_min`.

Which designs separate.  Prefix-tree designs only: a **time-based** design
shares one gain row among all words at a time, and an **augmented** one
shares ``L`` and its gains across words and times, so a gain there is not the
last to act on one node alone and the node-by-node argument fails.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from eqrec.checks import short_label
from eqrec.bounds.certify import CERT_RTOL, certify_design
from eqrec.bounds.data_classes import ClassGains, ClassSet, classes_of_tree
from eqrec.lp.model import LPSolution
from eqrec.lp.parallel import check_jobs, check_scheduler
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.lp.solvers import solve_lp, solver_info
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.blocks import choose_path
from eqrec.design.classes.chains import solve_levels
from eqrec.design.classes.gains import ClassCertificate, certify_classes, node_schedule
from eqrec.design.classes.block_lp import block_lp_options, block_objectives, build_class_lp, read_class_gains
from eqrec.design.cost import class_cost
from eqrec.design.classes.mu1_min import infeasible_at
from eqrec.design.result import Design
from eqrec.errors import CertificationFailure, InfeasibleDesign, InputError

# ---------------------------------------------------------------------------
# Fixed μ1
# ---------------------------------------------------------------------------

@dataclass
class ClassSolution:
    """The class engine's answer at one ``μ1``: gains, the LP's levels and the certificate.

    Parameters
    ----------
    mu1 : float
    gains : ClassGains
    lp_levels : numpy.ndarray
        ``(classes, n)`` level of each (class, row), at least its certified worst case.
    certificate : ClassCertificate
    solution : LPSolution or None
    model_shape : tuple of int
        ``(rows, columns)`` of the block LP.
    nonzeros : int
    build_time, solve_time : float
        Seconds spent building and solving the LP.
    """

    mu1: float
    gains: ClassGains
    lp_levels: np.ndarray  # (classes, n): each block's LP optimum
    certificate: ClassCertificate
    solution: LPSolution | None
    model_shape: tuple[int, int]
    nonzeros: int
    build_time: float
    solve_time: float

    @property
    def levels(self) -> np.ndarray:
        """Level of each class (its largest row, as the LPs found it)."""
        return self.lp_levels.max(axis=1) if self.lp_levels.size else np.zeros(0)


def solve_classes(system: "AffineSystem | Stacking", classes: ClassSet, mu1: float, *, solver: str = "highs",
                  solver_options: dict | None = None, rtol: float | None = None, n_jobs=None, scheduler=None,
                  path: str = "auto") -> ClassSolution:
    """Solve the LAD LP of every (class, row) at ``μ1`` and certify the gains from themselves.

    Small languages are one block-diagonal LP; large ones are solved per class, in batches on every core or a
    Dask cluster (:mod:`eqrec.design.classes.blocks`; the same bytes whatever the workers and the batching), and
    their large classes along a chain when they form one (:mod:`eqrec.design.classes.chains`: maximum delay 1).

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the classes' horizon (the LPs, the gains and the
        certificate read it; built here from a system).
    classes : ClassSet
    mu1 : float
        Recovery level ``μ1`` (positive).
    solver : str, optional
    solver_options : dict, optional
        LP solver and its options (default: HiGHS without presolve).
    rtol : float, optional
        Certificate tolerance (default ``CERT_RTOL`` + the solver's accuracy).
    n_jobs : int or None, optional
        Worker processes of the per-class solves (default every core; :func:`eqrec.lp.parallel.check_jobs`).
    scheduler : str, distributed.Client or None, optional
        A Dask scheduler (``"tcp://host:8786"`` or a client): the per-class solves run on its workers.
    path : {"auto", "monolithic", "blocks"}, optional
        One block LP, per class, or by size (default; :func:`eqrec.design.classes.blocks.choose_path`).

    Returns
    -------
    ClassSolution

    Raises
    ------
    SolverFailure
        If the block LP has no optimum (it is always feasible and bounded).
    CertificationFailure
        If a recomputed worst case exceeds the LP's level by more than ``rtol``.
    """
    return solve_classes_at(system, classes, [mu1], solver=solver, solver_options=solver_options, rtol=rtol,
                            n_jobs=n_jobs, scheduler=scheduler, path=path)[0]


def solve_classes_at(system: "AffineSystem | Stacking", classes: ClassSet, mu1s, *, solver: str = "highs",
                     solver_options: dict | None = None, rtol: float | None = None, n_jobs=None, scheduler=None,
                     path: str = "auto") -> list[ClassSolution]:
    """:func:`solve_classes` at several ``μ1`` (μ1 free: at ``μ1,min`` and at the level proven infeasible).

    Per class, the levels are solved one after the other on one model (:func:`eqrec.design.classes.blocks.level_task`,
    one pass over the classes); the one block LP is solved once per ``μ1``.

    Parameters
    ----------
    system : AffineSystem or Stacking
        As :func:`solve_classes`.
    classes : ClassSet
    mu1s : sequence of float
        Recovery levels (positive).
    solver : str, optional
    solver_options : dict, optional
    rtol : float, optional
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional
    path : {"auto", "monolithic", "blocks"}, optional
        As :func:`solve_classes`.

    Returns
    -------
    list of ClassSolution
        One per ``μ1``, in order.
    """
    mu1s = [float(mu1) for mu1 in mu1s]
    for mu1 in mu1s:
        if not np.isfinite(mu1) or mu1 <= 0:
            raise InputError(f"the recovery level mu1 must be positive, got {mu1}", field="mu1")
    check_jobs(n_jobs)
    scheduler = check_scheduler(scheduler)
    options = block_lp_options(solver) if solver_options is None else solver_options
    st = Stacking.of(system, classes.horizon)  # the one stacked model of these LPs, their gains and certificates
    system = st.system
    n, N = system.n, len(classes)
    if choose_path(path, classes, None, system) == "blocks":
        per_mu1, solve_time = solve_levels(st, classes, mu1s, solver=solver, options=options, n_jobs=n_jobs,
                                           scheduler=scheduler)
        out = []
        for mu1, blocks in zip(mu1s, per_mu1):
            lp_levels = np.array([b.levels for b in blocks]).reshape(N, n)
            sol = LPSolution("optimal", None, float(-lp_levels.sum()), solver, sum(b.iterations for b in blocks),
                             solve_time / len(mu1s))
            out.append(_certified(
                classes, mu1, ClassGains(classes=classes, K=[b.K for b in blocks], n=n, p=system.p), lp_levels,
                ClassCertificate(mu1=mu1, classes=classes, bounds=np.array([b.bounds for b in blocks]).reshape(N, n)),
                sol, (sum(b.rows for b in blocks), sum(b.cols for b in blocks)), sum(b.nonzeros for b in blocks),
                0.0, sol.solve_time, solver, rtol))
        return out
    out = []
    for mu1 in mu1s:
        model = build_class_lp(st, classes, mu1)
        t0 = time.perf_counter()
        sol = solve_lp(model.lp, solver, options).require_optimal(f"class LPs (mu1 = {mu1:g})")
        solve_time = time.perf_counter() - t0
        gains = read_class_gains(system, classes, model, sol)
        lp_levels = np.zeros((N, n))
        lp_levels[model.block_class, model.block_row] = block_objectives(model, sol)
        out.append(_certified(classes, mu1, gains, lp_levels, certify_classes(st, gains, mu1), sol,
                              model.lp.shape, int(model.lp.A.nnz), model.build_time, solve_time, solver, rtol))
    return out


def _certified(classes: ClassSet, mu1: float, gains: ClassGains, lp_levels: np.ndarray, cert: ClassCertificate,
               sol: LPSolution, shape, nnz: int, build_time: float, solve_time: float, solver: str,
               rtol: float | None) -> ClassSolution:
    """The :class:`ClassSolution`, its levels raised to the certified worst cases.

    ``rtol`` (relative to ``max(1, level, μ1)``, the scale of the LP's coefficients) only refuses gains that are
    not the LP's; a worst case above its LP level by less is the LP's round-off, and the level becomes it
    (exactly: no tolerance on the guarantee side, :mod:`eqrec.bounds.certify`).
    """
    rtol = CERT_RTOL + solver_info(solver).accuracy if rtol is None else rtol
    excess = cert.bounds - lp_levels
    scale = np.maximum(max(1.0, mu1), np.abs(lp_levels))
    if np.any(excess > rtol * scale):
        i, r = np.unravel_index(np.argmax(excess / scale), excess.shape)
        raise CertificationFailure(f"class {short_label(classes.classes[i].label)} row {r}: the gains give worst case "
                                   f"{cert.bounds[i, r]:.9g} > the LP's level {lp_levels[i, r]:.9g}")
    # the certified value is the level: never below what the gains really give
    return ClassSolution(mu1=mu1, gains=gains, lp_levels=np.maximum(lp_levels, cert.bounds), certificate=cert,
                         solution=sol, model_shape=tuple(shape), nonzeros=int(nnz), build_time=build_time,
                         solve_time=solve_time)


def check_terminal(classes: ClassSet, sol: ClassSolution, rtol: float = CERT_RTOL) -> None:
    """:class:`InfeasibleDesign` naming the class and row if a terminal class's level exceeds ``μ1``.

    Parameters
    ----------
    classes : ClassSet
    sol : ClassSolution
    rtol : float, optional
        Relative distance above ``μ1`` at which a terminal level shows infeasibility.  This is the infeasible
        side only: a level above ``μ1`` by less is accepted, and :func:`class_design` then raises ``μ1`` to the
        fixed point the gains certify (at most ``rtol`` above the request), never keeping a level below its
        certificate.
    """
    mu1 = sol.mu1
    for i, cls in enumerate(classes.classes):
        if cls.terminal and sol.levels[i] > mu1 * (1 + rtol):
            r = int(np.argmax(sol.lp_levels[i]))
            raise InfeasibleDesign(f"no estimator recovers to mu1 = {mu1:g}: terminal class {short_label(cls.label)} "
                                   f"(time {cls.depth}, data {short_label(list(cls.available))}) row {r} has smallest worst "
                                   f"case {sol.levels[i]:.9g} at this mu1 (it grows with mu1)")


#: Largest prefix tree (nodes) for which node gains are derived by default.
NODE_GAINS_LIMIT = 20000

LEVELS = ("common", "max", "sum")


def class_design(system: "AffineSystem | Stacking", language, mu1: float, *, levels: str = "common",
                 cost: str | None = None,
                 solver: str = "highs", solver_options: dict | None = None, method: str = "prefix",
                 certify: bool = True, node_gains: bool | None = None, time_based: bool = False,
                 rtol: float | None = None, n_jobs=None, scheduler=None, solved: ClassSolution | None = None):
    """A prefix-tree design at ``μ1`` by the class engine, as a :class:`eqrec.design.result.Design`.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the language's horizon: the class LPs, the node gains,
        the certificate and the fallback to ``μ1,min`` all read it (built here once from a system).
    language : PrefixTree or ClassSet
        The language's prefix tree, or its classes (a full language from the
        window rule: then no node gains, no words).
    mu1 : float
        Recovery level ``μ1``.
    levels : {"common", "max", "sum"}
        As :func:`eqrec.design.prefix.tree_lp.build_prefix_lp`: one ``μ2`` (``common``),
        or per-node levels (``max``, ``sum``; node ``levels`` filled).
    cost : {"sum", "max"} or None
        The delayed-data paper's ``J`` in :attr:`Design.J <eqrec.design.result.Design.J>` (``None``: not computed).
    solver : str, optional
    solver_options : dict, optional
        LP solver and its options (default: HiGHS without presolve).
    method : str, optional
        ``Design.method`` label.
    certify : bool, optional
        Certify the node gains (when derived) by :func:`eqrec.bounds.certify.certify_design`.
    node_gains : bool or None
        Derive node gains ``(F, u0)`` (``schedule``) and certify them by the
        independent recursion of :mod:`eqrec.bounds.certify`; default: when the
        tree has at most :data:`NODE_GAINS_LIMIT` nodes.
    time_based : bool, optional
        Node gains chosen by time only (:class:`~eqrec.bounds.gains.GainSchedule`).
    rtol : float, optional
        Certification tolerance (default ``CERT_RTOL`` + the solver's accuracy).
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional
        Where the class LPs of a large language run (:func:`solve_classes`).
    solved : ClassSolution or None, optional
        The class LPs already solved at ``mu1`` (:func:`solve_classes_at`): not solved again.

    Returns
    -------
    Design

    Raises
    ------
    InfeasibleDesign
        A terminal class cannot reach ``μ1`` (named, with the smallest
        feasible ``μ1``, :func:`eqrec.design.classes.mu1_min.infeasible_at`).
    CertificationFailure
        The gains do not give the levels.
    """
    if levels not in LEVELS:
        raise InputError(f"unknown level structure {levels!r}; choose one of {list(LEVELS)}", field="levels")
    t0 = time.perf_counter()
    classes = as_class_set(language)
    tree = classes.tree
    if solved is not None and (solved.gains.classes is not classes or solved.mu1 != float(mu1)):
        raise InputError("the given class solution is of other classes or another mu1", field="solved")
    st = Stacking.of(system, classes.horizon)  # handed down: LPs, node gains, certificate
    sol = solved or solve_classes(st, classes, mu1, solver=solver, solver_options=solver_options, rtol=rtol,
                                  n_jobs=n_jobs, scheduler=scheduler)
    try:
        check_terminal(classes, sol)
    except InfeasibleDesign as exc:  # name the true smallest feasible μ1, not a class's worst case at this μ1
        raise infeasible_at(st, classes, sol.mu1, exc, solver=solver, n_jobs=n_jobs,
                            scheduler=scheduler, method=method) from None
    mu1 = sol.mu1
    inner = np.array([c.inner for c in classes.classes], bool)
    mu2 = float(max(mu1, sol.levels[inner].max(initial=mu1)))
    node_levels: dict[str, float] = {}
    if levels != "common" and tree is not None:
        node_levels = {node.label: float(max(mu1, sol.levels[classes.node_class[node.index]]))
                       for node in tree if not node.terminal}
    if node_gains is None:
        node_gains = tree is not None and classes.nodes <= NODE_GAINS_LIMIT
    schedule = node_schedule(st, sol.gains, tree, time_based=time_based) if node_gains else None
    patterns = tree.patterns if tree is not None else ()
    design = Design(method=method, system=st.system, patterns=patterns, T=classes.horizon, mu1=mu1, mu2=mu2,
                    schedule=schedule, solution=sol.solution, build_time=sol.build_time, levels=node_levels,
                    class_gains=sol.gains, class_certificate=sol.certificate, engine="classes",
                    classes=len(classes), sequences=classes.sequences, nodes=classes.nodes,
                    lp_rows=sol.model_shape[0], lp_cols=sol.model_shape[1], lp_nonzeros=sol.nonzeros,
                    class_levels=sol.levels)
    # every stored level at least its certified worst case, exactly (μ1 raised to the terminal fixed point if the
    # LP's round-off left a terminal class above it; eqrec.bounds.certify); node gains certified when asked
    certify_design(design, rtol=CERT_RTOL + solver_info(solver).accuracy if rtol is None else rtol,
                   nodes=certify and schedule is not None, stacking=st)
    if design.mu1 > mu1 * (1 + CERT_RTOL):  # the gains recover only to a level well above the request
        exc = InfeasibleDesign(f"no estimator recovers to mu1 = {mu1:g}: the gains certify mu1 = {design.mu1:.9g}")
        raise infeasible_at(st, classes, mu1, exc, solver=solver, n_jobs=n_jobs, scheduler=scheduler,
                            method=method) from None
    if cost is not None:
        design.cost, design.J = cost, class_cost(classes, design.mu1, design.class_levels, cost)
    design.total_time = time.perf_counter() - t0
    return design


def as_class_set(language) -> ClassSet:
    """A :class:`ClassSet` from a class set or a prefix tree.

    Parameters
    ----------
    language : ClassSet or PrefixTree

    Returns
    -------
    ClassSet
    """
    if isinstance(language, ClassSet):
        return language
    if isinstance(language, PrefixTree):
        return classes_of_tree(language)
    raise TypeError(f"expected a ClassSet or a PrefixTree, got {type(language).__name__}")
