r"""Equalized-recovery design with delayed and missing data (Theorem 1 / Proposition 1 of the delayed-data paper).

The delayed-data paper ("P3") designs, for a language of delay words, one gain
triplet per event sequence of the reduced event language ``L^{E'}``, shared
along common event prefixes (constraint (6)), zero on data not yet available
(constraint (7)), with a level ``μ2,k^α`` per sequence and time and the
recovery level ``μ1`` as a decision variable.  Here that problem is the
core's node-per-prefix LP (:func:`eqrec.design.prefix.build_prefix_lp`): one
gain row per event-prefix node over the measurements available at its time
(late ones included), one level per non-terminal node.

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

``μ1`` fixed: :func:`design_delay` (an LP).

``μ1`` free: the problem is bilinear (the ``|G_ξ0| μ1`` terms of (10)).  Two routes:

* :func:`design_delay_ipopt` — the paper's: IPOPT through CasADi on (10) in
  the split robust form, started from an LP solution (a local method);
* :func:`design_delay_global` — global within a stated tolerance:

  1. the smallest feasible ``μ1`` (:func:`min_recovery_level`): feasibility
     only involves the terminal rows ``f_i(x) + μ1 b_i(x) <= μ1`` (``f`` the
     noise part, ``b = |G_ξ0| 1``), i.e. ``μ1_min = min_x max_i f_i/(1 - b_i)``,
     a convex generalized fractional program.  Dinkelbach steps (LP at the
     current ``μ``, then ``μ <- max_i f_i/(1 - b_i)`` evaluated on the certified
     gains) decrease ``μ`` monotonically through feasible values; an LP at
     ``μ (1 - rtol)`` whose terminal rows cannot be met certifies the lower
     end (bisection is the fallback when a step stalls);
  2. branch and bound on intervals ``[lo, hi]`` of ``μ1``: the LP with the
     ξ0 box at radius ``lo`` and ``μ1 ∈ [lo, hi]`` elsewhere relaxes
     ``|G_ξ0| μ1 >= |G_ξ0| lo``, so its optimum is a lower bound of ``J`` on
     the interval (``mu1_range`` of the core); fixed-``μ1`` LPs give upper
     bounds; ``J >= c_min μ1`` (every level is at least ``μ1``) caps the
     search at ``UB / c_min``.  Intervals whose bound is within ``rtol`` of
     the incumbent are discarded; the result states the remaining gap.

  All LPs of one design share their sparsity pattern: the matrix is affine in
  the ξ0 radius (:class:`RadiusFamily`), so each is a vector update, and
  HiGHS is warm-started from the previous basis.

Every returned design is certified from its gains alone
(:func:`eqrec.core.certify.certify_design`).
"""

from __future__ import annotations

import heapq
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from eqrec.core.certify import certify_design, closed_loop_maps
from eqrec.core.lp import LinearProgram, LPSolution
from eqrec.core.patterns import ArrivalPattern, PrefixTree, as_language, full_delay_language, parse_delay_word
from eqrec.core.solvers import solve_lp, solver_info
from eqrec.core.systems import AffineSystem
from eqrec.design.prefix import PrefixLP, build_prefix_lp, read_schedule
from eqrec.design.result import Design
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure

COSTS = ("sum", "max")


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


def _check_cost(cost: str) -> str:
    if cost not in COSTS:
        raise InputError(f"unknown cost {cost!r}; choose one of {list(COSTS)}", field="cost")
    return cost


def _tree(patterns) -> PrefixTree:
    tree = patterns if isinstance(patterns, PrefixTree) else PrefixTree(
        patterns if not isinstance(patterns, (str, ArrivalPattern)) else [patterns], kind="delay")
    if len({p.T for p in tree.patterns}) != 1:
        raise InputError("the delayed-data design needs a fixed-length language", field="delays")
    return tree


def node_weights(tree: PrefixTree) -> dict[int, int]:
    """Number of sequences of the (reduced) language through each node."""
    through = {node.index: 0 for node in tree}
    for pat in tree.patterns:
        for anc in tree.path(pat):
            through[anc.index] += 1
    return through


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


def min_cost_slope(tree: PrefixTree, cost: str = "sum") -> float:
    """``c_min`` with ``J >= c_min μ1`` (every level is at least ``μ1``)."""
    a, w = cost_weights(tree, cost)
    return a + (sum(w.values()) if cost == "sum" else 1.0)


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
class MinRecoveryLevel:
    """The smallest feasible recovery level: ``lower < μ1_min <= upper``.

    ``upper`` is attained by certified gains; ``lower`` is a level at which
    an LP shows the terminal rows cannot be met (``lower_margin`` > 0 is that
    LP's smallest violation).
    """

    upper: float
    lower: float
    lower_margin: float
    iterations: list[dict] = field(default_factory=list)
    lps: int = 0
    time: float = 0.0

    @property
    def value(self) -> float:
        return self.upper


@dataclass
class FreeMu1Result:
    """A design with ``μ1`` free, and what certifies it."""

    design: Design
    route: str  # "global" or "ipopt"
    cost: str
    mu1: float
    J: float
    lower_bound: float  # global: valid lower bound of J over all μ1; ipopt: nan
    lps: int
    time: float
    mu1_min: MinRecoveryLevel | None = None
    history: list[dict] = field(default_factory=list)
    extra: dict = field(default_factory=dict)

    @property
    def mu2(self) -> float:
        return self.design.mu2

    @property
    def gap(self) -> float:
        """Relative gap ``(J - lower_bound) / J``."""
        return float((self.J - self.lower_bound) / abs(self.J)) if np.isfinite(self.lower_bound) else np.nan


# ---------------------------------------------------------------------------
# The LP family (matrix affine in the ξ0 radius) and warm-started HiGHS
# ---------------------------------------------------------------------------

class RadiusFamily:
    r"""The design LPs of one language and cost, as functions of the ξ0 radius ``r`` and the range of ``μ1``.

    Built twice by :func:`build_prefix_lp` (radii ``r_a``, ``r_b``, with
    ``μ1`` a column): the coefficients and row bounds are affine in ``r``
    (the radius multiplies the ξ0 entries of the robust rows), so
    ``A(r) = A0 + r dA`` with one sparsity pattern.  :meth:`lp` returns

    * ``lp(μ, μ, μ)``: the design LP at ``μ1 = μ`` fixed;
    * ``lp(lo, lo, hi)``: the relaxation of the bilinear problem on ``[lo, hi]``;
    * ``lp(μ, 0, inf, objective="terminal")``: ``min`` of the largest terminal
      worst case at radius ``μ`` (the Dinkelbach subproblem).

    :meth:`bilinear` gives ``A0, dA, ...`` for the IPOPT route.
    """

    def __init__(self, system: AffineSystem, tree: PrefixTree, cost: str = "sum", *, form: str = "split",
                 r_a: float = 1.0, r_b: float = 2.0):
        _check_cost(cost)
        self.system, self.tree, self.cost = system, tree, cost
        t0 = time.perf_counter()
        levels = "sum" if cost == "sum" else "common"
        mu1_cost, _ = cost_weights(tree, cost)
        kw = dict(levels=levels, mu1_range=(1.0, 1.0), mu1_cost=mu1_cost, form=form)
        ma = build_prefix_lp(system, tree, r_a, **kw)
        mb = build_prefix_lp(system, tree, r_b, **kw)
        Aa, Ab = ma.lp.A, mb.lp.A
        if not (np.array_equal(Aa.indptr, Ab.indptr) and np.array_equal(Aa.indices, Ab.indices)):
            raise AssertionError("the design LP's sparsity pattern depends on the radius")
        self.model: PrefixLP = ma
        self.base = ma.lp
        dr = r_b - r_a
        self.dA = (Ab.data - Aa.data) / dr
        self.A0 = Aa.data - r_a * self.dA
        self.dU, self.U0 = self._affine(ma.lp.row_upper, mb.lp.row_upper, r_a, dr)
        self.dL, self.L0 = self._affine(ma.lp.row_lower, mb.lp.row_lower, r_a, dr)
        self.mu1_col = ma.mu1_col
        self.level_cols = np.array([ma.mu2_col, *ma.level_cols.values()], dtype=np.int64)
        # terminal level rows (pattern order x component) and the positions of their μ1 coefficient
        n = system.n
        lr = ma.robust_index.level_rows
        k = np.concatenate([tree.node(p).index * n + np.arange(n) for p in tree.patterns])
        self.terminal_rows = np.stack([rows[k] for rows in lr])  # (signs, patterns * n)
        A = ma.lp.A
        lo, hi = A.indptr[self.mu1_col], A.indptr[self.mu1_col + 1]
        where = dict(zip(A.indices[lo:hi].tolist(), range(lo, hi)))
        self.terminal_pos = np.vectorize(where.__getitem__, otypes=[np.int64])(self.terminal_rows)
        self.build_time = time.perf_counter() - t0
        self.lps = 0

    @staticmethod
    def _affine(a: np.ndarray, b: np.ndarray, r_a: float, dr: float) -> tuple[np.ndarray, np.ndarray]:
        fin = np.isfinite(a)
        if not np.array_equal(fin, np.isfinite(b)):
            raise AssertionError("row bounds change finiteness with the radius")
        d = np.zeros_like(a)
        d[fin] = (b[fin] - a[fin]) / dr
        base = a.copy()
        base[fin] = a[fin] - r_a * d[fin]
        return d, base

    @property
    def shape(self) -> tuple[int, int]:
        return self.base.shape

    def lp(self, radius: float, lo: float, hi: float, objective: str = "cost",
           terminal_scale: np.ndarray | None = None) -> LinearProgram:
        """The LP at ξ0 radius ``radius`` with ``μ1 ∈ [lo, hi]`` (see the class docstring).

        ``terminal_scale`` (with ``objective="terminal"``): the terminal rows
        become ``worst_i <= radius + t g_i`` with the column ``t`` in place of
        ``μ1`` (the scaled Dinkelbach subproblem).
        """
        b = self.base
        data = self.A0 + radius * self.dA
        row_upper = self.U0 + radius * self.dU
        if terminal_scale is not None:
            g = np.broadcast_to(np.asarray(terminal_scale, float), self.terminal_pos.shape[1:])
            for s in range(self.terminal_pos.shape[0]):
                data[self.terminal_pos[s]] = -g
                row_upper[self.terminal_rows[s]] += radius
        A = sp.csc_matrix((data, b.A.indices, b.A.indptr), shape=b.A.shape)
        col_lower = b.col_lower.copy()
        col_upper = b.col_upper.copy()
        col_lower[self.mu1_col], col_upper[self.mu1_col] = lo, hi
        col_lower[self.level_cols] = lo
        c = b.c
        if objective == "terminal":
            c = np.zeros_like(b.c)
            c[self.mu1_col] = 1.0
        elif objective != "cost":
            raise ValueError(objective)
        return LinearProgram(c=c, A=A, row_lower=self.L0 + radius * self.dL, row_upper=row_upper,
                             col_lower=col_lower, col_upper=col_upper, blocks=b.blocks)

    def bilinear(self) -> dict:
        """Data of problem (10): ``L0 + μ dL <= (A0 + μ dA) x <= U0 + μ dU`` with ``μ = x[mu1_col]``."""
        both = np.isfinite(self.L0) & np.isfinite(self.U0)
        if np.any(both & (self.dL != self.dU) & (self.L0 != self.U0)):
            raise AssertionError("a ranged row's bounds move differently with the radius")
        return dict(A0=sp.csc_matrix((self.A0, self.base.A.indices, self.base.A.indptr), shape=self.base.A.shape),
                    dA=sp.csc_matrix((self.dA, self.base.A.indices, self.base.A.indptr), shape=self.base.A.shape),
                    L0=self.L0, U0=self.U0, dL=self.dL, dU=self.dU)


class WarmSolver:
    """Solve a sequence of LPs of one sparsity pattern, HiGHS warm-started from the previous optimal basis.

    Other solvers of the registry are called cold.  ``warm=False`` disables
    the warm start (for the benchmark's comparison).
    """

    def __init__(self, solver: str = "highs", options: dict | None = None, warm: bool = True):
        solver_info(solver)
        self.solver, self.options, self.warm = solver, dict(options or {}), warm
        self._basis = None
        self.count = 0
        self.time = 0.0

    def solve(self, lp: LinearProgram) -> LPSolution:
        self.count += 1
        if self.solver != "highs":
            sol = solve_lp(lp, self.solver, self.options)
            self.time += sol.solve_time
            return sol
        import highspy

        h = highspy.Highs()
        h.setOptionValue("output_flag", False)
        for key, val in self.options.items():
            h.setOptionValue(key, val)
        model = highspy.HighsLp()
        nr, nc = lp.A.shape
        model.num_col_, model.num_row_ = nc, nr
        model.col_cost_, model.col_lower_, model.col_upper_ = lp.c, lp.col_lower, lp.col_upper
        model.row_lower_, model.row_upper_ = lp.row_lower, lp.row_upper
        model.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        model.a_matrix_.start_, model.a_matrix_.index_, model.a_matrix_.value_ = lp.A.indptr, lp.A.indices, lp.A.data
        model.a_matrix_.num_col_, model.a_matrix_.num_row_ = nc, nr
        h.passModel(model)
        if self.warm and self._basis is not None:
            h.setBasis(self._basis)
        t0 = time.perf_counter()
        h.run()
        elapsed = time.perf_counter() - t0
        self.time += elapsed
        ms = h.getModelStatus()
        info = h.getInfo()
        iters = int(info.simplex_iteration_count) + int(max(info.ipm_iteration_count, 0))
        if ms == highspy.HighsModelStatus.kOptimal:
            x = np.asarray(h.getSolution().col_value)
            if self.warm:
                self._basis = h.getBasis()
            return LPSolution("optimal", x, float(lp.c @ x), "highs", iters, elapsed, lp.blocks)
        if ms in (highspy.HighsModelStatus.kInfeasible, highspy.HighsModelStatus.kUnboundedOrInfeasible):
            return LPSolution("infeasible", None, np.inf, "highs", iters, elapsed, lp.blocks)
        return LPSolution(h.modelStatusToString(ms), None, np.nan, "highs", iters, elapsed, lp.blocks)


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
    design = Design(method=method, system=system, patterns=tree.patterns, T=model.stacking.T, M1=float(mu1),
                    mu2=mu2, schedule=schedule, solution=sol, build_time=build_time, levels=levels)
    design.extra.update(cost=cost, J=paper_cost(tree, mu1, levels if cost == "sum" else {"*": mu2}, cost),
                        sequences=len(tree.patterns), nodes=len(tree))
    if certify:
        cert = certify_design(design, rtol=rtol)
        design.extra["J_certified"] = certified_cost(design, tree, cost, cert)
    return design


def certified_cost(design: Design, tree: PrefixTree, cost: str, cert=None) -> float:
    """``J`` recomputed from the certificate: each node's level replaced by its worst case (at least ``μ1``)."""
    cert = cert or design.certificate
    mu1 = design.M1
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
    rows = [{"prefix": "", "k": 0, "level": design.M1, "certified": design.M1, "sequences": len(tree.patterns)}]
    for node in tree:
        lvl = design.M1 if node.terminal else design.levels.get(node.label, design.mu2)
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
    out = np.full(T + 1, design.M1)
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


def to_json(design: Design, free: "FreeMu1Result | None" = None) -> dict:
    """What ``eqrec design --method delay`` writes: levels per event prefix and time, ``J``, the gains per sequence.

    ``free`` adds, for ``μ1`` free, the route, the lower bound of ``J`` that
    certifies it (global route) and the certified smallest ``μ1``.
    """
    cert = design.certificate
    out = {"method": "delay", "cost": design.extra.get("cost"), "mu1": design.M1, "mu2": design.mu2,
           "J": design.extra.get("J"), "J_certified": design.extra.get("J_certified"),
           "certified_mu2": None if cert is None else cert.mu2,
           "certified_terminal": None if cert is None else cert.terminal,
           "levels": level_table(design) if cert is not None else [],
           "event_sequences": {p.label: list(p.events()) for p in design.patterns},
           "gains": design.schedule.to_json()}
    if free is not None:
        out["mu1_free"] = {"route": free.route, "J": free.J, "lower_bound": free.lower_bound, "gap": free.gap,
                           "lps": free.lps, "time": free.time}
        if free.mu1_min is not None:
            out["mu1_free"]["mu1_min"] = {"upper": free.mu1_min.upper, "lower": free.mu1_min.lower}
    return out


def _fixed_mu1_lp(system: AffineSystem, tree: PrefixTree, mu1: float, cost: str, form: str = "split") -> PrefixLP:
    # Theorem 1 / Proposition 1 at μ1 fixed: a level per node ("sum") or one common level ("max")
    return build_prefix_lp(system, tree, float(mu1), levels="sum" if cost == "sum" else "common", form=form)


def design_lp_status(system: AffineSystem, patterns, mu1: float, cost: str = "sum", solver: str = "highs") -> str:
    """The solver's status of the LP :func:`design_delay` solves (Theorem 1 / Proposition 1, ``μ1`` fixed).

    ``"optimal"`` or ``"infeasible"`` (no estimator recovers to ``mu1``), or
    another status of the solver; never raises for an infeasible design.
    """
    _check_cost(cost)
    return solve_lp(_fixed_mu1_lp(system, _tree(patterns), mu1, cost).lp, solver).status


def design_delay(system: AffineSystem, patterns, mu1: float, *, cost: str = "sum", solver: str = "highs",
                 form: str = "split", certify: bool = True, solver_options: dict | None = None) -> Design:
    """The delayed-data design with ``μ1`` fixed (an LP).

    Parameters
    ----------
    patterns
        Arrival patterns, delay words (digit strings) or a :class:`PrefixTree`;
        reduced to ``L^{E'}``.
    mu1
        Recovery level ``μ1``.
    cost
        ``"sum"`` (the paper's ``J``, module docstring) or ``"max"`` (largest level).

    Returns
    -------
    Design
        ``method="delay"``, ``mu2`` the largest level, ``levels`` per
        non-terminal event-prefix node (``"sum"``), ``extra["J"]`` the cost
        (``extra["J_certified"]`` from the certificate).

    Raises
    ------
    InfeasibleDesign
        If no estimator recovers to ``mu1``.
    """
    _check_cost(cost)
    tree = _tree(patterns)
    mu1 = float(mu1)
    model = _fixed_mu1_lp(system, tree, mu1, cost, form)
    sol = solve_lp(model.lp, solver, solver_options).require_optimal(f"delay design (mu1 = {mu1:g})")
    rtol = 1e-6 + solver_info(solver).accuracy
    return _design_from_solution(model, tree, system, sol.x, mu1, cost, sol, build_time=model.build_time,
                                 certify=certify, rtol=rtol)


# ---------------------------------------------------------------------------
# The smallest feasible μ1
# ---------------------------------------------------------------------------

def terminal_ratios(system: AffineSystem, schedule, tree: PrefixTree) -> tuple[np.ndarray, np.ndarray]:
    """``f_i`` (noise and offset part) and ``b_i`` (``|G_ξ0| 1``) of every terminal error component, from the gains.

    The terminal worst case at radius ``μ`` is ``f_i + μ b_i``; the gains
    recover to every ``μ >= max_i f_i / (1 - b_i)`` (all ``b_i < 1``).
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


def min_recovery_level(system: AffineSystem, patterns, *, start: float = 1.0, rtol: float = 1e-5,
                       max_iter: int = 50, solver: str = "highs", family: RadiusFamily | None = None,
                       warm: WarmSolver | None = None) -> MinRecoveryLevel:
    """The smallest ``μ1`` for which some estimator recovers (``‖ξ(T)‖ <= μ1`` for all ``‖ξ0‖ <= μ1``).

    ``μ1_min = min_x max_i f_i(x) / g_i(x)`` with ``f_i`` the terminal noise
    part and ``g_i = 1 - |G_ξ0,i| 1`` (convex over concave): the
    Dinkelbach-type method of Crouzeix, Ferland and Schaible (1985, the
    scaled variant, superlinear) — at ``θ_k`` solve the LP
    ``min_x max_i (f_i(x) - θ_k g_i(x)) / g_i(x_{k-1})`` and set
    ``θ_{k+1} = max_i f_i(x_k) / g_i(x_k)`` from the certified gains (a
    feasible level, decreasing).  The lower end is certified by an LP at
    ``upper (1 - rtol)`` whose terminal rows cannot be met.

    Parameters
    ----------
    start
        First level tried; doubled until feasible.
    rtol
        Relative width of the certified bracket ``(lower, upper]``.
    """
    t_start = time.perf_counter()
    tree = _tree(patterns)
    fam = family or RadiusFamily(system, tree, "max")
    ws = warm or WarmSolver(solver)
    n0 = ws.count
    hist: list[dict] = []

    def terminal_lp(mu, scale=None):
        sol = ws.solve(fam.lp(mu, -np.inf if scale is not None else 0.0, np.inf, objective="terminal",
                              terminal_scale=scale))
        if not sol.optimal:
            raise SolverFailure(f"terminal LP at mu1 = {mu:g}: {sol.status}")
        return sol, float(sol.x[fam.mu1_col])

    mu = float(start)
    lower, margin = 0.0, np.nan
    for _ in range(60):  # find a feasible level
        sol, t = terminal_lp(mu)
        hist.append({"mu": mu, "value": t - mu, "step": "probe"})
        if t <= mu:
            break
        lower, margin = mu, t - mu
        mu *= 2.0
    else:
        raise InfeasibleDesign("no recovery level up to 2^60 is feasible")
    upper = np.inf
    for _ in range(max_iter):
        f, b = terminal_ratios(system, read_schedule(fam.model, sol), tree)
        g = 1.0 - b
        nxt = _fixed_point(f, b)
        if not np.isfinite(nxt):
            raise SolverFailure("the terminal LP returned gains that do not contract the initial error")
        if nxt <= 1e-12 * max(1.0, mu):
            raise InputError("the smallest recovery level is 0 (no noise reaches the end of the horizon); "
                             "fix mu1 instead", field="mu1")
        hist.append({"mu": mu, "next": nxt, "step": "dinkelbach"})
        upper = min(upper, nxt)
        if nxt > mu * (1 - rtol / 4):  # stalled: certify the lower end (or continue below)
            probe = max(lower, upper * (1 - rtol))
            sol_p, t = terminal_lp(probe)
            hist.append({"mu": probe, "value": t - probe, "step": "certify"})
            if t > probe:
                lower, margin = probe, t - probe
                break
            mu, sol = probe, sol_p  # still feasible below: continue from there
            continue
        mu = upper
        sol, _ = terminal_lp(mu, scale=g)
    else:
        raise SolverFailure(f"the smallest recovery level did not converge in {max_iter} steps "
                            f"(bracket {lower:g} .. {upper:g})")
    return MinRecoveryLevel(upper=float(upper), lower=float(lower), lower_margin=float(margin), iterations=hist,
                            lps=ws.count - n0, time=time.perf_counter() - t_start)


# ---------------------------------------------------------------------------
# μ1 free: global route (branch and bound on intervals of μ1)
# ---------------------------------------------------------------------------

def design_delay_global(system: AffineSystem, patterns, *, cost: str = "sum", rtol: float = 1e-4,
                        mu1_rtol: float = 1e-5, solver: str = "highs", solver_options: dict | None = None,
                        form: str = "split", warm_start: bool = True, max_lps: int = 400,
                        certify: bool = True) -> FreeMu1Result:
    """Globally minimise ``J`` over ``μ1`` and the gains, within relative tolerance ``rtol``.

    Steps (module docstring): the smallest feasible ``μ1`` by certified
    Dinkelbach steps; the LP at that ``μ1`` as first incumbent; then branch
    and bound on ``[μ1_lower, UB / c_min]`` with relaxation LPs (lower
    bounds) and fixed-``μ1`` LPs (incumbents), until every interval's bound
    is within ``rtol`` of the incumbent.

    Returns
    -------
    FreeMu1Result
        ``design`` certified at the best ``μ1``; ``lower_bound`` a valid lower
        bound of ``J`` over every ``μ1 > 0`` (up to LP tolerances), so
        ``gap <= rtol``; ``history`` lists every LP (kind, interval, value).
    """
    _check_cost(cost)
    t_start = time.perf_counter()
    tree = _tree(patterns)
    fam = RadiusFamily(system, tree, cost, form=form)
    ws = WarmSolver(solver, solver_options, warm=warm_start)
    # the smallest μ1 (its family: common level, any cost works for the terminal LP)
    mm = min_recovery_level(system, tree, rtol=mu1_rtol, family=fam, warm=WarmSolver(solver, solver_options,
                                                                                        warm=warm_start))
    hist: list[dict] = []
    best = {"J": np.inf, "mu1": np.nan, "sol": None}

    def incumbent(mu: float) -> float:
        sol = ws.solve(fam.lp(mu, mu, mu))
        val = sol.objective if sol.optimal else np.inf
        hist.append({"kind": "fixed", "lo": mu, "hi": mu, "value": val})
        if val < best["J"]:
            best.update(J=val, mu1=mu, sol=sol)
        return val

    def relaxation(lo: float, hi: float) -> tuple[float, float]:
        sol = ws.solve(fam.lp(lo, lo, hi))
        if sol.status == "infeasible":
            val, at = np.inf, np.nan
        elif not sol.optimal:
            raise SolverFailure(f"relaxation LP on [{lo:g}, {hi:g}]: {sol.status}")
        else:
            val, at = sol.objective, float(sol.x[fam.mu1_col])
        hist.append({"kind": "relaxation", "lo": lo, "hi": hi, "value": val, "at": at})
        return val, at

    for k in range(6):  # the LP at the smallest level sits on the feasibility boundary: nudge up if needed
        if np.isfinite(incumbent(mm.upper * (1 + (0.0 if k == 0 else 10.0 ** (k - 9))))):
            break
    else:
        raise SolverFailure(f"the LP at the certified smallest level {mm.upper:g} is infeasible")
    c_min = min_cost_slope(tree, cost)
    top = best["J"] / c_min  # J >= c_min μ1: no better μ1 above
    heap: list[tuple[float, float, float]] = []  # (bound, lo, hi)
    if top > mm.lower:
        heapq.heappush(heap, (-np.inf, mm.lower, top))
    done_bound = np.inf  # smallest bound of the discarded intervals
    while heap:
        if ws.count >= max_lps:
            break
        parent_bound, lo, hi = heapq.heappop(heap)
        if parent_bound >= best["J"] * (1 - rtol):
            done_bound = min(done_bound, parent_bound)
            continue
        val, at = relaxation(lo, hi)
        if val >= best["J"] * (1 - rtol):
            done_bound = min(done_bound, val)
            continue
        # incumbent candidate: where the relaxation put μ1 (inside the feasible range)
        cand = min(max(at if np.isfinite(at) else 0.5 * (lo + hi), mm.upper), hi)
        if cand > lo and not any(h["kind"] == "fixed" and h["lo"] == cand for h in hist):
            incumbent(cand)
        mid = 0.5 * (lo + hi)
        if np.isfinite(at) and lo + 0.1 * (hi - lo) < at < hi - 0.1 * (hi - lo):
            mid = at
        heapq.heappush(heap, (val, lo, mid))
        heapq.heappush(heap, (val, mid, hi))
    open_bound = min((b for b, _, _ in heap), default=np.inf)  # -inf if an interval was never bounded
    lower_bound = float(min(done_bound, open_bound, best["J"]))
    mu1 = float(best["mu1"])
    design = _design_from_solution(fam.model, tree, system, best["sol"].x, mu1, cost, best["sol"],
                                   build_time=fam.build_time, certify=certify)
    design.extra.update(mu1_free="global", lower_bound=lower_bound, mu1_min=mm.upper, mu1_min_lower=mm.lower)
    return FreeMu1Result(design=design, route="global", cost=cost, mu1=mu1, J=float(best["J"]),
                         lower_bound=lower_bound, lps=ws.count + mm.lps, time=time.perf_counter() - t_start,
                         mu1_min=mm, history=hist, extra={"interval_top": top, "c_min": c_min,
                                                          "open_intervals": len(heap)})


# ---------------------------------------------------------------------------
# μ1 free: the paper's route (IPOPT on the bilinear problem (10))
# ---------------------------------------------------------------------------

def design_delay_ipopt(system: AffineSystem, patterns, *, cost: str = "sum", start_mu1: float = 1.0,
                       form: str = "split", options: dict | None = None, polish: bool = True,
                       certify: bool = True, solver: str = "highs") -> FreeMu1Result:
    """Problem (10) with ``μ1`` a variable, by IPOPT through CasADi, started from the LP at ``start_mu1``.

    The robust rows at ξ0 radius ``μ1`` are ``(A0 + μ1 dA) x`` within bounds
    affine in ``μ1`` (:meth:`RadiusFamily.bilinear`): exactly the bilinear
    ``|G_ξ0| μ1`` terms of (10) (in the split form ``G = p - m``; the paper's
    Π-dual form has the same feasible gains).  ``start_mu1`` is doubled until
    the start LP is feasible.  IPOPT is a local method: its point is certified
    as is (tolerance widened by IPOPT's accuracy) and, with ``polish``, the LP
    at IPOPT's ``μ1`` gives the exact optimum for that ``μ1``
    (``extra["polished"]``).
    """
    import casadi as ca

    _check_cost(cost)
    t_start = time.perf_counter()
    tree = _tree(patterns)
    fam = RadiusFamily(system, tree, cost, form=form)
    ws = WarmSolver(solver)
    mu0 = float(start_mu1)
    for _ in range(40):
        sol0 = ws.solve(fam.lp(mu0, mu0, mu0))
        if sol0.optimal:
            break
        mu0 *= 2.0
    else:
        raise InfeasibleDesign("no feasible starting level for IPOPT")
    bl = fam.bilinear()
    nr, nc = fam.shape
    A0, dA = bl["A0"], bl["dA"]
    x = ca.MX.sym("x", nc)
    mu = x[fam.mu1_col]

    def dm(M):
        M = M.tocsc()
        M.sort_indices()
        return ca.DM(ca.Sparsity(M.shape[0], M.shape[1], M.indptr.tolist(), M.indices.tolist()), M.data)

    # rows: A0 x + μ (dA x - dU) within [L0, U0] (lower bounds move only where they are finite: dL == dU there)
    shift = np.where(np.isfinite(bl["U0"]), bl["dU"], bl["dL"])
    g = ca.mtimes(dm(A0), x) + mu * (ca.mtimes(dm(dA), x) - ca.DM(shift))
    lbg = np.where(np.isfinite(bl["L0"]), bl["L0"] + (bl["dL"] - shift) * 0.0, -np.inf)
    ubg = bl["U0"]
    c = fam.base.c
    nlp = {"x": x, "f": ca.dot(ca.DM(c), x), "g": g}
    opts = {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": 1e-9,
            "ipopt.acceptable_tol": 1e-7, "ipopt.max_iter": 3000}
    opts.update({k if "." in k else f"ipopt.{k}": v for k, v in (options or {}).items()})
    nlpsol = ca.nlpsol("delay10", "ipopt", nlp, opts)
    lbx = fam.base.col_lower.copy()
    ubx = fam.base.col_upper.copy()
    lbx[fam.mu1_col], ubx[fam.mu1_col] = 1e-9, np.inf
    lbx[fam.level_cols] = 0.0
    t0 = time.perf_counter()
    out = nlpsol(x0=sol0.x, lbx=lbx, ubx=ubx, lbg=lbg, ubg=ubg)
    t_ip = time.perf_counter() - t0
    stats = nlpsol.stats()
    status = str(stats.get("return_status"))
    xv = np.asarray(out["x"]).reshape(-1)
    if status not in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
        raise SolverFailure(f"IPOPT on problem (10) stopped with status {status}")
    mu1 = float(xv[fam.mu1_col])
    sol = LPSolution("optimal", xv, float(c @ xv), "ipopt", int(stats.get("iter_count", 0)), t_ip, fam.base.blocks)
    rtol = 1e-6 + solver_info("ipopt").accuracy
    design = _design_from_solution(fam.model, tree, system, xv, mu1, cost, sol, build_time=fam.build_time,
                                   certify=certify, rtol=rtol)
    extra = {"status": status, "iterations": sol.iterations, "ipopt_time": t_ip, "start_mu1": mu0,
             "start_J": float(sol0.objective), "J_ipopt": float(c @ xv)}
    f, b = terminal_ratios(system, design.schedule, tree)
    extra["mu1_of_gains"] = _fixed_point(f, b)  # the smallest level IPOPT's gains recover to
    if polish:  # the exact LP optimum at a level IPOPT's gains certainly reach
        mu_p = max(mu1, extra["mu1_of_gains"])
        pol = ws.solve(fam.lp(mu_p, mu_p, mu_p))
        if pol.optimal:
            extra["polished"] = {"mu1": mu_p, "J": float(pol.objective), "design": _design_from_solution(
                fam.model, tree, system, pol.x, mu_p, cost, pol, build_time=fam.build_time, certify=certify)}
        else:
            extra["polished"] = {"mu1": mu_p, "J": np.nan, "status": pol.status}
    design.extra.update(mu1_free="ipopt")
    return FreeMu1Result(design=design, route="ipopt", cost=cost, mu1=mu1, J=float(c @ xv), lower_bound=np.nan,
                         lps=ws.count, time=time.perf_counter() - t_start, history=[], extra=extra)


def compare_free_routes(global_result: FreeMu1Result, ipopt_result: FreeMu1Result) -> dict:
    """Which route found the lower ``J``: ``"tie"`` when they agree within ``rtol`` (IPOPT's ``J`` is
    accurate to its constraint tolerance only: its ``μ1`` may sit that far below what its gains reach).
    """
    Jg, Ji = global_result.J, ipopt_result.J
    lb = global_result.lower_bound
    rtol = max(global_result.gap, 1e-6) if np.isfinite(global_result.gap) else 1e-6
    return {"J_global": Jg, "J_ipopt": Ji, "mu1_global": global_result.mu1, "mu1_ipopt": ipopt_result.mu1,
            "mu1_of_ipopt_gains": ipopt_result.extra.get("mu1_of_gains", np.nan),
            "lower_bound": lb, "tolerance": rtol,
            "better": "global" if Jg < Ji - rtol * abs(Jg) else ("ipopt" if Ji < Jg - rtol * abs(Jg) else "tie"),
            "global_s": global_result.time, "ipopt_s": ipopt_result.time,
            "ipopt_gap_to_bound": (Ji - lb) / abs(Ji) if np.isfinite(lb) else np.nan,
            "ipopt_consistent_with_bound": bool(Ji >= lb * (1 - 1e-6))}
