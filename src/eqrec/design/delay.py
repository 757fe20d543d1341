r"""Equalized-recovery design with delayed and missing data (Theorem 1 / Proposition 1 of the delayed-data paper).

The delayed-data paper ("P3") designs, for a language of delay words, one gain
triplet per event sequence of the reduced event language ``L^{E'}``, shared
along common event prefixes (constraint (6)), zero on data not yet available
(constraint (7)), with a level ``μ2,k^α`` per sequence and time and the
recovery level ``μ1`` as a decision variable.

Engines
-------
* ``engine="classes"`` (default): the class engine of
  :mod:`eqrec.design.classes`.  The problem separates exactly into one small
  LP per (time, available data) class and state row (the separation theorem
  proved there); nodes of one class share their level.  Full languages
  ``{0..τ̄}^T`` are handled from the window rule without enumerating words
  (:func:`delay_classes`), so ``(30, 4)`` (9.3·10²⁰ words, 446 classes) is
  one LP of a few hundred thousand columns.
* ``engine="tree"``: the core's node-per-prefix LP
  (:func:`eqrec.design.prefix.build_prefix_lp`), one gain row per event-prefix
  node over the measurements available at its time (late ones included), one
  level per non-terminal node.  It stays as the independent cross-check (the
  tests compare the two node by node) and for the paper-comparison rows.

The cost (what exactly is counted)
----------------------------------
``cost="sum"`` is the paper's ``J = μ1 + Σ_{k=0}^{T} Σ_{α=1}^{|L^{E'}|} μ2,k^α``:

* the sum over ``α`` runs over the **reduced** language ``L^{E'}`` (distinct
  event sequences; the batch reactor's 243 words give 162), as printed;
* ``μ2,k^α`` bounds ``ξ(k)`` along ``α``; ``ξ(k)`` depends on the events
  ``0..k-1`` only, so its best level is that of the prefix node of depth
  ``k`` and every sequence through the node pays it: the node's weight is
  the number of sequences through it;
* ``k = 0``: ``‖ξ(0)‖ <= μ1`` and ``μ2,0 >= μ1``, so ``μ2,0^α = μ1`` at any
  optimum; ``k = T``: ``‖ξ(T)‖ <= μ1`` is imposed and ``μ2,T^α >= μ1``, so
  ``μ2,T^α = μ1``.  Each contributes ``|L^{E'}| μ1``:

  .. math:: J = (1 + 2|L^{E'}|)\,\mu_1 + \sum_{k=1}^{T-1}\sum_{\text{nodes } \nu,\ |\nu| = k} w_\nu\,\mu_{2,\nu}.

  :func:`cost_weights` returns this coefficient of ``μ1`` and the node
  weights; :func:`paper_cost` evaluates ``J`` from levels (a test checks it
  against the literal double sum).

``cost="max"``: the largest level ``max_{k,α} μ2,k^α`` (one common level, the
prefix-based paper's ``M2``), and ``J = μ1 + max μ2`` when ``μ1`` is free.

``μ1`` fixed: :func:`design_delay`.

``μ1`` free: the problem (10) is bilinear (the ``|G_ξ0| μ1`` terms).  Two routes:

* :func:`design_delay_global` — the global optimum by the μ1-free theorem of
  :mod:`eqrec.design.classes`: every class level is nondecreasing in ``μ1``,
  so ``J`` is, and the optimum is the smallest feasible ``μ1``, one
  Charnes–Cooper LP (:func:`eqrec.design.mu1_min.min_recovery_level`),
  certified by the ratio recomputed from the gains (upper end) and a dual
  point (lower end);
* :func:`eqrec.design.delay_ipopt.design_delay_ipopt` — the paper's: IPOPT through CasADi on (10) in
  the split robust form of the tree LP, started from an LP solution (a local
  method), kept for the comparison row.

Every returned design is certified from its gains alone: the class
certificate (worst case of ``E_d − K Z_S``) and, where node gains are derived,
:func:`eqrec.core.certify.certify_design` on every sequence.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from eqrec.core.certify import certify_design
from eqrec.core.classes import ClassSet, classes_of_full_language, classes_of_tree
from eqrec.core.lp import LPSolution
from eqrec.core.patterns import ArrivalPattern
from eqrec.core.prefix_tree import PrefixTree
from eqrec.core.words import as_language, full_delay_language, parse_delay_word
from eqrec.core.solvers import solve_lp, solver_info
from eqrec.core.systems import AffineSystem
from eqrec.design.classes import (MU1_LOWER_RTOL, _check_cost, check_terminal, class_cost,
                                  class_design, solve_classes)
from eqrec.design.mu1_min import MinRecoveryLevel
from eqrec.design.mu1_min import min_recovery_level as _class_min_recovery_level
from eqrec.design.prefix import PrefixLP, build_prefix_lp, read_schedule
from eqrec.design.result import Design
from eqrec.errors import InfeasibleDesign, InputError

ENGINES = ("classes", "tree")


# ---------------------------------------------------------------------------
# Languages and costs
# ---------------------------------------------------------------------------

def delay_language(words=None, *, max_delay: int | None = None, horizon: int | None = None,
                   source: str | None = None) -> tuple[ArrivalPattern, ...]:
    """The reduced event language ``L^{E'}`` of delay words, or of the full language ``{0..τ̄}^T``.

    Give either ``words`` (digit strings, patterns) or ``max_delay`` and
    ``horizon`` (all ``(τ̄+1)^T`` words).  A delay reaching past the horizon
    means missing.  Equal event sequences are merged (first word kept as label).
    """
    if words is None:
        if max_delay is None or horizon is None:
            raise InputError("give delay words, or both the maximum delay and the horizon", source, "delays")
        words = full_delay_language(int(horizon), int(max_delay))
    return as_language(words, kind="delay", max_delay=max_delay, length=horizon, source=source)


def delay_classes(*, max_delay: int, horizon: int) -> ClassSet:
    """The classes of the full language ``{0..τ̄}^T`` from the window rule (no word enumerated)."""
    return classes_of_full_language(int(horizon), int(max_delay))


def _check_engine(engine: str) -> str:
    if engine not in ENGINES:
        raise InputError(f"unknown engine {engine!r}; choose one of {list(ENGINES)}", field="engine")
    return engine


def _tree(patterns) -> PrefixTree:
    tree = patterns if isinstance(patterns, PrefixTree) else PrefixTree(
        patterns if not isinstance(patterns, (str, ArrivalPattern)) else [patterns], kind="delay")
    if len({p.T for p in tree.patterns}) != 1:
        raise InputError("the delayed-data design needs a fixed-length language", field="delays")
    return tree


def _classes(patterns) -> ClassSet:
    """Classes of a language given as words, patterns, a tree or already as classes."""
    if isinstance(patterns, ClassSet):
        return patterns
    return classes_of_tree(_tree(patterns))


def node_weights(tree: PrefixTree) -> dict[int, int]:
    """Number of sequences of the (reduced) language through each node."""
    return tree.sequences_through()


def cost_weights(tree: PrefixTree, cost: str = "sum") -> tuple[float, dict[int, float]]:
    """Coefficient of ``μ1`` in ``J`` and weight of each non-terminal node's level.

    ``"sum"``: ``(1 + 2|L^{E'}|, {node: sequences through it})`` (module
    docstring: ``k = 0`` and ``k = T`` contribute ``|L^{E'}| μ1`` each);
    ``"max"``: ``(1, {})`` (``J = μ1 + max level``).
    """
    _check_cost(cost)
    if cost == "max":
        return 1.0, {}
    w = node_weights(tree)
    return 1.0 + 2.0 * len(tree.patterns), {i: float(c) for i, c in w.items() if not tree.nodes[i].terminal}


def paper_cost(tree: PrefixTree, mu1: float, levels: dict[str, float], cost: str = "sum") -> float:
    """``J`` from node levels (keyed by node label; missing nodes count as ``μ1``)."""
    a, w = cost_weights(tree, cost)
    if cost == "max":
        return mu1 + max([mu1, *levels.values()])
    return a * mu1 + sum(wi * max(mu1, levels.get(tree.nodes[i].label, mu1)) for i, wi in w.items())


def literal_paper_cost(tree: PrefixTree, mu1: float, level_of) -> float:
    """``μ1 + Σ_{k=0}^{T} Σ_α μ2,k^α`` literally, with ``level_of(α, k)`` the level of sequence ``α`` at time ``k``."""
    T = tree.depth
    return mu1 + sum(level_of(pat, k) for pat in tree.patterns for k in range(T + 1))


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------

@dataclass
class FreeMu1Result:
    """A design with ``μ1`` free, and what certifies it.

    ``lower_bound`` (global route): ``J`` at the level ``mu1_min.lower``
    proven infeasible, with every class at its optimal level there; ``J`` is
    nondecreasing in ``μ1``, so no feasible ``μ1`` does better.
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
    extra: dict = field(default_factory=dict)

    @property
    def mu2(self) -> float:
        return self.design.mu2

    @property
    def gap(self) -> float:
        """Relative gap ``(J - lower_bound) / J``."""
        return float((self.J - self.lower_bound) / abs(self.J)) if np.isfinite(self.lower_bound) else np.nan


# ---------------------------------------------------------------------------
# Designs from LP solutions
# ---------------------------------------------------------------------------

def _design_from_solution(model: PrefixLP, tree: PrefixTree, system: AffineSystem, x: np.ndarray, mu1: float,
                          cost: str, sol: LPSolution, *, build_time: float = 0.0, certify: bool = True,
                          rtol: float = 1e-6, method: str = "delay") -> Design:
    schedule = read_schedule(model, LPSolution("optimal", x, np.nan, sol.solver, sol.iterations, sol.solve_time))
    if cost == "sum":
        levels = {tree.nodes[i].label: float(max(x[c], mu1)) for i, c in model.level_cols.items()}
        mu2 = max(levels.values(), default=mu1)
    else:
        levels = {}
        mu2 = float(max(x[model.mu2_col], mu1))
    design = Design(method=method, system=system, patterns=tree.patterns, T=model.stacking.T, mu1=float(mu1),
                    mu2=mu2, schedule=schedule, solution=sol, build_time=build_time, levels=levels)
    design.extra.update(engine="tree", cost=cost,
                        J=paper_cost(tree, mu1, levels if cost == "sum" else {"*": mu2}, cost),
                        sequences=len(tree.patterns), nodes=len(tree))
    if certify:
        cert = certify_design(design, rtol=rtol)
        design.extra["J_certified"] = certified_cost(design, tree, cost, cert)
    return design


def certified_cost(design: Design, tree: PrefixTree, cost: str, cert=None) -> float:
    """``J`` recomputed from the certificate: each node's level replaced by its worst case (at least ``μ1``)."""
    cert = cert or design.certificate
    mu1 = design.mu1
    node_bound: dict[str, float] = {}
    for wc in cert.words.values():
        pat = wc.pattern
        for t in range(1, pat.T):
            lab = pat.prefix(t).label
            node_bound[lab] = max(node_bound.get(lab, 0.0), float(wc.bounds[t].max()))
    if cost == "max":
        return mu1 + max(mu1, cert.mu2)
    return paper_cost(tree, mu1, node_bound, "sum")


def level_table(design: Design) -> list[dict]:
    """Per event prefix and time: designed level, certified worst case, number of sequences through it.

    Rows for ``k = 0`` (level ``μ1``), every non-terminal node (``k = 1..T-1``)
    and every sequence's end (``k = T``, level ``μ1``).
    """
    tree = _tree(design.patterns)
    w = node_weights(tree)
    cert = design.certificate
    bound: dict[str, float] = {}
    for wc in cert.words.values():
        for t in range(1, wc.pattern.T + 1):
            lab = wc.pattern.prefix(t).label
            bound[lab] = max(bound.get(lab, 0.0), float(wc.bounds[t].max()))
    rows = [{"prefix": "", "k": 0, "level": design.mu1, "certified": design.mu1, "sequences": len(tree.patterns)}]
    for node in tree:
        lvl = design.mu1 if node.terminal else design.levels.get(node.label, design.mu2)
        rows.append({"prefix": node.label, "k": node.depth, "level": float(lvl), "certified": bound[node.label],
                     "sequences": w[node.index]})
    return rows


def path_levels(design: Design, pattern) -> np.ndarray:
    """The guaranteed levels ``μ2,k^α``, ``k = 0..T``, along one pattern (``μ1`` at ``k = 0`` and ``k = T``).

    With per-node levels (cost ``"sum"``) each time's level is that of the
    prefix node; with one common level (``"max"``) it is ``mu2``.
    """
    pat = parse_delay_word(pattern) if isinstance(pattern, str) else pattern
    T = pat.T
    out = np.full(T + 1, design.mu1)
    for k in range(1, T):
        out[k] = node_level(design, pat.prefix(k))
    return out


def node_level(design: Design, prefix: ArrivalPattern) -> float:
    """The guaranteed level ``μ2,k^α`` on ``ξ(k)`` after the event prefix of length ``k`` (``0 < k < T``).

    With per-node levels (cost ``"sum"``) that of the prefix's node; with one
    common level (``"max"``) ``mu2`` (module docstring, "The cost").
    """
    return float(design.levels.get(prefix.label, design.mu2)) if design.levels else float(design.mu2)


def word_certificate(design: Design, word):
    """The certificate of the designed sequence equal to ``word`` (a delay word or pattern; any word of its class)."""
    pat = parse_delay_word(word) if isinstance(word, str) else word
    for p in design.patterns:
        if p == pat:
            return design.certificate.words[p.label]
    raise InputError(f"{pat.label!r} is not an event sequence of the designed language", field="pattern")


#: Largest reduced language (sequences) whose node gains ``to_json`` writes unless asked.
JSON_NODE_GAINS_LIMIT = 200


def class_table(design: Design) -> list[dict]:
    """Per (time, available data) class: its level, certified worst case, sum-cost weight and gain ``K``."""
    cc = design.class_certificate
    gains = design.class_gains
    levels = design.extra.get("class_levels")
    rows = []
    for i, cls in enumerate(gains.classes.classes):
        rows.append({"class": cls.label, "k": cls.depth, "data": list(cls.available), "terminal": cls.terminal,
                     "sequences": int(cls.weight), "nodes": int(cls.nodes),
                     "level": float(max(design.mu1, levels[i])) if cls.inner else float(levels[i]),
                     "certified": float(cc.levels[i]), "K": gains.K[i].tolist()})
    return rows


def to_json(design: Design, free: "FreeMu1Result | None" = None, node_gains: bool | None = None) -> dict:
    """What ``eqrec design --method delay`` writes.

    Always: ``μ1``, ``μ2``, ``J`` and the certified values; for the class
    engine the classes (level, certified worst case, ``K``).  Node gains,
    levels per event prefix and the event sequences: with ``node_gains``
    (default: when the reduced language has at most
    :data:`JSON_NODE_GAINS_LIMIT` sequences and node gains exist).  ``free``
    adds, for ``μ1`` free, the route, the lower bound of ``J`` that certifies
    it (global route) and the certified smallest ``μ1``.
    """
    cert = design.certificate
    ccert = design.class_certificate
    if node_gains is None:
        node_gains = design.schedule is not None and len(design.patterns) <= JSON_NODE_GAINS_LIMIT
    if node_gains and design.schedule is None:
        raise InputError("node gains were asked for but the design has none (a language too large for its prefix "
                         "tree: use the class gains K)", field="node-gains")
    certified = cert if cert is not None else ccert
    out = {"method": "delay", "engine": design.extra.get("engine", "tree"), "cost": design.extra.get("cost"),
           "mu1": design.mu1, "mu2": design.mu2, "J": design.extra.get("J"),
           "J_certified": design.extra.get("J_certified"),
           "certified_mu2": None if certified is None else certified.mu2,
           "certified_terminal": None if certified is None else certified.terminal,
           "sequences": design.extra.get("sequences"), "nodes": design.extra.get("nodes")}
    if design.class_gains is not None:
        out["classes"] = class_table(design)
    if node_gains:
        out["levels"] = level_table(design) if cert is not None else []
        out["event_sequences"] = {p.label: list(p.events()) for p in design.patterns}
        out["gains"] = design.schedule.to_json()
    if free is not None:
        out["mu1_free"] = {"route": free.route, "J": free.J, "lower_bound": free.lower_bound, "gap": free.gap,
                           "lps": free.lps, "time": free.time}
        if free.mu1_min is not None:
            out["mu1_free"]["mu1_min"] = {"upper": free.mu1_min.upper, "lower": free.mu1_min.lower,
                                          "binding": free.mu1_min.binding}
    return out


# ---------------------------------------------------------------------------
# μ1 fixed
# ---------------------------------------------------------------------------

def design_delay(system: AffineSystem, patterns, mu1: float, *, cost: str = "sum", solver: str = "highs",
                 form: str = "split", certify: bool = True, solver_options: dict | None = None,
                 engine: str = "classes", node_gains: bool | None = None) -> Design:
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
        Delay words (digit strings), arrival patterns or their tree (reduced
        to ``L^{E'}``), or the classes of a full language
        (:func:`delay_classes`, class engine only).  The language must have
        a fixed length.
    mu1 : float
        Recovery level ``μ1``, positive.
    cost : {"sum", "max"}, optional
        The paper's ``J`` (module docstring; default) or the largest level.
    solver : str, optional
        LP solver, a name of :data:`eqrec.core.solvers.SOLVER_NAMES`
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
        :func:`eqrec.design.classes.class_design`).

    Returns
    -------
    Design
        ``method="delay"``, ``mu2`` the largest level, ``levels`` per
        non-terminal event-prefix node (``"sum"``), ``extra["J"]`` the cost
        (``extra["J_certified"]`` from the certificate).

    Raises
    ------
    InputError
        Malformed words, a language of mixed lengths, a non-positive
        ``mu1``, or an unknown ``cost`` or ``engine``.
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
    """
    _check_cost(cost)
    _check_engine(engine)
    mu1 = float(mu1)
    rtol = 1e-6 + solver_info(solver).accuracy
    if engine == "classes":
        classes = _classes(patterns)
        design = class_design(system, classes, mu1, levels="sum" if cost == "sum" else "common", cost=cost,
                              solver=solver, solver_options=solver_options, method="delay", certify=certify,
                              node_gains=node_gains, rtol=rtol)
        if design.certificate is not None and classes.tree is not None:
            design.extra["J_certified"] = certified_cost(design, classes.tree, cost)
        elif design.class_certificate is not None:
            design.extra["J_certified"] = class_cost(classes, mu1, design.class_certificate.levels, cost)
        return design
    tree = _tree(patterns)
    model = _fixed_mu1_lp(system, tree, mu1, cost, form)
    sol = solve_lp(model.lp, solver, solver_options).require_optimal(f"delay design (mu1 = {mu1:g})")
    return _design_from_solution(model, tree, system, sol.x, mu1, cost, sol, build_time=model.build_time,
                                 certify=certify, rtol=rtol)


def design_lp_status(system: AffineSystem, patterns, mu1: float, cost: str = "sum", solver: str = "highs") -> str:
    """Whether a design at ``μ1`` exists: ``"optimal"``, or ``"infeasible"`` (no estimator recovers to ``mu1``).

    By the separation theorem, the design exists iff every terminal class
    reaches ``μ1`` (:func:`eqrec.design.classes.check_terminal`); never
    raises for an infeasible design.
    """
    _check_cost(cost)
    classes = _classes(patterns)
    try:
        check_terminal(classes, solve_classes(system, classes, float(mu1), solver=solver))
    except InfeasibleDesign:
        return "infeasible"
    return "optimal"


def _fixed_mu1_lp(system: AffineSystem, tree: PrefixTree, mu1: float, cost: str, form: str = "split") -> PrefixLP:
    # the tree LP at μ1 fixed: a level per node ("sum") or one common level ("max")
    return build_prefix_lp(system, tree, float(mu1), levels="sum" if cost == "sum" else "common", form=form)


# ---------------------------------------------------------------------------
# μ1 free: the global optimum (the μ1-free theorem of eqrec.design.classes)
# ---------------------------------------------------------------------------

def min_recovery_level(system: AffineSystem, patterns, *, solver: str = "highs",
                       rtol: float = MU1_LOWER_RTOL) -> MinRecoveryLevel:
    """The smallest ``μ1`` for which some estimator recovers (``‖ξ(T)‖ <= μ1`` for all ``‖ξ0‖ <= μ1``).

    See :func:`eqrec.design.mu1_min.min_recovery_level`: ``upper`` is
    attained by certified gains, ``lower = upper (1 - rtol)`` is proven
    infeasible by a dual point.
    """
    return _class_min_recovery_level(system, _classes(patterns), solver=solver, lower_rtol=rtol)


def design_delay_global(system: AffineSystem, patterns, *, cost: str = "sum", solver: str = "highs",
                        rtol: float = MU1_LOWER_RTOL, certify: bool = True,
                        node_gains: bool | None = None, engine: str = "classes") -> FreeMu1Result:
    """The global minimum of ``J`` over ``μ1`` and the gains: the design at ``μ1 = μ1,min``.

    The delayed-data paper's problem with ``μ1`` a decision variable
    (Theorem 1 / Proposition 1, eq. (10)), which is bilinear and which the
    paper solves locally with IPOPT.  By the μ1-free theorem
    (:mod:`eqrec.design.classes`) ``J`` is nondecreasing on the feasible set
    ``[μ1,min, ∞)``, so the global optimum is the design at ``μ1,min``,
    which comes from one Charnes–Cooper LP
    (:func:`eqrec.design.mu1_min.min_recovery_level`).  ``rtol`` places the
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
    cost : {"sum", "max"}, optional
        The paper's ``J`` (default) or ``μ1`` plus the largest level.
    solver : str, optional
        LP solver, a name of :data:`eqrec.core.solvers.SOLVER_NAMES`
        (default ``"highs"``).
    rtol : float, optional
        Relative distance below ``μ1,min`` of the level proven infeasible
        (default :data:`eqrec.design.classes.MU1_LOWER_RTOL`).
    certify : bool, optional
        Certify the design's gains independently (default).
    node_gains : bool or None, optional
        Class engine: derive node gains (default: small trees).
    engine : {"classes", "tree"}, optional
        Engine of the design at ``μ1,min`` (default the class engine; the
        tree LP needs the language's words).

    Returns
    -------
    FreeMu1Result
        ``design`` at ``μ1,min`` (certified), ``mu1`` (``= μ1,min``), ``J``,
        ``lower_bound`` and ``gap``, ``mu1_min`` (bracket, binding terminal
        class and row).  Not a :class:`Design` itself: the design is its
        ``design`` attribute.

    Raises
    ------
    InputError
        Malformed words, an unknown ``cost`` or ``engine``, or
        ``μ1,min = 0`` (no noise reaches the end of the horizon).
    InfeasibleDesign
        If no recovery level is feasible.
    SolverFailure
        If a solver stops without an optimum.
    CertificationFailure
        If the recovered gains do not achieve the optimal levels.

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
    _check_cost(cost)
    t_start = time.perf_counter()
    _check_engine(engine)
    classes = _classes(patterns)
    mm = _class_min_recovery_level(system, classes, solver=solver, lower_rtol=rtol)
    if engine == "tree":
        if classes.tree is None:
            raise InputError("the tree engine needs the language's words (a prefix tree)", field="engine")
        design = design_delay(system, classes.tree, mm.upper, cost=cost, solver=solver, certify=certify,
                              engine="tree")
    else:
        design = design_delay(system, classes, mm.upper, cost=cost, solver=solver, certify=certify,
                              node_gains=node_gains)
    lower_bound = np.nan
    if np.isfinite(mm.lower):
        low = solve_classes(system, classes, mm.lower, solver=solver)
        lower_bound = class_cost(classes, mm.lower, low.levels, cost)
    J = float(design.extra["J"])
    design.extra.update(mu1_free="global", lower_bound=lower_bound, mu1_min=mm.upper, mu1_min_lower=mm.lower,
                        mu1_binding=mm.binding)
    return FreeMu1Result(design=design, route="global", cost=cost, mu1=mm.upper, J=J, lower_bound=float(lower_bound),
                         lps=mm.lps + 2, time=time.perf_counter() - t_start, mu1_min=mm,
                         extra={"binding": mm.binding, "lower_margin": mm.lower_margin})
