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
The pair ``(d, S)`` is the node's class (:mod:`eqrec.core.classes`).

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
K_{(d,S)}(y_S - \bar y_S)` (:class:`eqrec.core.estimator.ClassEstimator`)
has error :math:`(E_d - K Z_S)\delta` exactly, so it attains every class
level with one ``K`` per class and no prefix tree at run time; no causal
affine estimator does better (its error has this form).  Node gains for the
recursive estimator follow from the ``K``\ s (:func:`node_schedule`):
:math:`Q_{d-1} = -K_{(d,S)} + A(d-1)\,K_{(d-1,S')}P`, and then ``(F, u0)`` by
eqs. (1)-(2) of the prefix-based paper.

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

with ``a, b`` evaluated on :math:`tE - y^\top Z` (:func:`min_recovery_level`).
No ``μ1`` is feasible iff :math:`\min_k a(k) \ge 1` for some terminal row
(the LP is then infeasible).  What certifies ``μ1,min``: the ratio
recomputed from the recovered ``k`` (upper end, attained), and a dual point
:math:`\lambda` (:math:`Z_S\lambda = 0`, :math:`|\lambda_c| \le \beta_c`) at
:math:`\mu_{lo} = (1 - 10^{-6})\mu_{1,\min}` with
:math:`E_d[r]\lambda > \mu_{lo}`: by LP duality the row's level exceeds
:math:`\mu_{lo}` there, so :math:`\mu_{lo}` is infeasible (lower end).

Which designs separate.  Prefix-tree designs only: a **time-based** design
shares one gain row among all words at a time, and an **augmented** one
shares ``L`` and its gains across words and times, so a gain there is not the
last to act on one node alone and the node-by-node argument fails.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.core.certify import CERT_RTOL
from eqrec.core.classes import ClassGains, ClassSet, DataClass, class_maps, classes_of_tree
from eqrec.core.gains import q_to_f, schedule_from_word_gains, GainSchedule
from eqrec.core.lp import LinearProgram, LPSolution
from eqrec.core.prefix_tree import PrefixTree
from eqrec.core.solvers import solve_lp, solver_info
from eqrec.core.stacking import Stacking
from eqrec.core.systems import AffineSystem
from eqrec.errors import CertificationFailure, InfeasibleDesign, InputError, SolverFailure

COSTS = ("sum", "max")

#: Relative distance below ``μ1,min`` at which the dual certificate shows infeasibility.
MU1_LOWER_RTOL = 1e-6


# ---------------------------------------------------------------------------
# The class LPs (build / solve / read)
# ---------------------------------------------------------------------------

@dataclass
class ClassLP:
    r"""One block LP holding the LP of every (class, state row), and where its gains are.

    Block ``b`` is (class ``block_class[b]``, row ``block_row[b]``).  ``kind``:

    * ``"level"``: the dual of the LAD LP at fixed ``μ1``,
      :math:`\max E_d[r]\lambda` s.t. :math:`Z_S\lambda = 0`,
      :math:`|\lambda| \le \beta` (written as a minimisation of
      :math:`-E_d[r]\lambda`); its optimum is the row's level and the gain row
      is minus the multipliers of its rows ``gain_index[b]`` (LP duality with
      :math:`\min_k \sum_c \beta_c|E_d[r,c] - (k^\top Z_S)[c]|`).  It has
      ``|S| p`` rows per block, where the LAD LP has one per uncertain
      coordinate: about twice as fast with HiGHS on the papers' systems.
    * ``"ratio"``: the Charnes–Cooper LP of :func:`min_recovery_level`; the
      gain row is ``y / t`` with ``y`` in columns ``gain_index[b]`` and ``t``
      in ``t_col[b]``.
    """

    lp: LinearProgram
    kind: str
    block_class: np.ndarray
    block_row: np.ndarray
    gain_index: list[np.ndarray]  # level: rows of the block; ratio: columns of y
    block_cols: np.ndarray  # (blocks + 1,) column ranges of each block
    t_col: np.ndarray | None = None
    build_time: float = 0.0

    @property
    def blocks(self) -> int:
        return int(self.block_class.size)


def _radius(stacking: Stacking, mu1: float) -> np.ndarray:
    sys = stacking.system
    return stacking.layout.radius(sys.eta_w, sys.eta_v, mu1)


def build_class_lp(system: AffineSystem, classes: ClassSet, mu1: float | None, *, kind: str = "level",
                   which: list[int] | None = None, stacking: Stacking | None = None) -> ClassLP:
    r"""Assemble the LPs of the classes ``which`` (default all) and every state row as one block-diagonal LP.

    Only the uncertain coordinates ``c`` that ``E_d`` or ``Z_S`` touch enter
    (the others add nothing to any row).  ``kind="level"`` (``μ1`` given):
    the dual LAD LP of :class:`ClassLP`.  ``kind="ratio"`` (``μ1`` not used):
    the Charnes–Cooper LP of the module docstring,
    :math:`Z_S^\top y - t E_d[r] + s^+ - s^- = 0`,
    :math:`\sum_{c \in \xi_0} (s^+_c + s^-_c) - t \le -1`, cost the noise
    coordinates' radii times :math:`s^+ + s^-`.
    """
    t0 = time.perf_counter()
    st = stacking or Stacking(system, classes.horizon)
    n = system.n
    lay = st.layout
    xi0 = np.zeros(lay.size, bool)
    xi0[lay.xi0] = True
    beta = _radius(st, 1.0 if mu1 is None else float(mu1))
    which = list(range(len(classes))) if which is None else list(which)
    tri_r, tri_c, tri_v = [], [], []  # coordinate triplets of the block-diagonal matrix
    cost, clo, chi, rlo, rhi = [], [], [], [], []
    gain_index, bcls, brow, tcols, bstart = [], [], [], [], [0]
    nrow = ncol = 0
    for ci in which:
        E, Z = class_maps(st, classes.classes[ci])
        m = Z.shape[0]
        act = np.flatnonzero(np.any(E != 0, axis=0) | np.any(Z != 0, axis=0))
        C = act.size
        Za = Z[:, act]
        zr, zc = np.nonzero(Za)
        zv = Za[zr, zc]
        b_act = beta[act]
        if kind == "level":
            # n blocks sharing Z_S (rows: data, columns: coordinates), costs -E_d[r] per row r
            off = np.arange(n)[:, None]
            tri_r.append((nrow + off * m + zr).ravel())
            tri_c.append((ncol + off * C + zc).ravel())
            tri_v.append(np.broadcast_to(zv, (n, zv.size)).ravel())
            cost.append(-E[:, act].ravel())
            box = np.broadcast_to(b_act, (n, C)).ravel()
            clo.append(-box)
            chi.append(box)
            rows = nrow + np.arange(n * m).reshape(n, m)
            gain_index.extend(rows)
            bstart.extend((ncol + C * np.arange(1, n + 1)).tolist())
            bcls += [ci] * n
            brow += list(range(n))
            nrow += n * m
            ncol += n * C
        elif kind == "ratio":
            x_act = xi0[act]
            xa = np.flatnonzero(x_act)
            noise_cost = np.where(x_act, 0.0, b_act)
            eye = np.arange(C)
            for r in range(n):
                e = E[r, act]
                ez = np.flatnonzero(e)
                # columns y (m), t, s+ (C), s- (C); rows: C equalities Z^T y - t e + s+ - s- = 0, then the x̃0 row
                t_c, sp_c, sm_c = ncol + m, ncol + m + 1, ncol + m + 1 + C
                tri_r += [nrow + zc, nrow + ez, nrow + eye, nrow + eye,
                          np.full(2 * xa.size + 1, nrow + C)]
                tri_c += [ncol + zr, np.full(ez.size, t_c), sp_c + eye, sm_c + eye,
                          np.concatenate([sp_c + xa, sm_c + xa, [t_c]])]
                tri_v += [zv, -e[ez], np.ones(C), -np.ones(C),
                          np.concatenate([np.ones(2 * xa.size), [-1.0]])]
                rlo.append(np.concatenate([np.zeros(C), [-np.inf]]))
                rhi.append(np.concatenate([np.zeros(C), [-1.0]]))
                cost.append(np.concatenate([np.zeros(m + 1), noise_cost, noise_cost]))
                clo.append(np.concatenate([np.full(m, -np.inf), np.zeros(1 + 2 * C)]))
                chi.append(np.full(m + 1 + 2 * C, np.inf))
                gain_index.append(ncol + np.arange(m))
                tcols.append(t_c)
                ncol += m + 1 + 2 * C
                nrow += C + 1
                bstart.append(ncol)
                bcls.append(ci)
                brow.append(r)
        else:
            raise ValueError(f"unknown class LP kind {kind!r}")
    cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)  # noqa: E731
    A = sp.csc_matrix((cat(tri_v), (cat(tri_r).astype(np.int64), cat(tri_c).astype(np.int64))), shape=(nrow, ncol))
    row_lower = cat(rlo) if kind == "ratio" else np.zeros(nrow)  # the level LP's rows are Z_S λ = 0
    row_upper = cat(rhi) if kind == "ratio" else np.zeros(nrow)
    lp = LinearProgram(c=cat(cost), A=A, row_lower=row_lower, row_upper=row_upper, col_lower=cat(clo),
                       col_upper=cat(chi))
    return ClassLP(lp=lp, kind=kind, block_class=np.asarray(bcls, np.int64), block_row=np.asarray(brow, np.int64),
                   gain_index=gain_index, block_cols=np.asarray(bstart, np.int64),
                   t_col=np.asarray(tcols, np.int64) if kind == "ratio" else None,
                   build_time=time.perf_counter() - t0)


def read_class_gains(system: AffineSystem, classes: ClassSet, model: ClassLP, solution: LPSolution) -> ClassGains:
    """The gains ``K`` per class from an optimal solution: minus the row multipliers (``"level"``) or
    ``y / t`` (``"ratio"``)."""
    n, p = system.n, system.p
    K = [np.zeros((n, len(c.available) * p)) for c in classes.classes]
    if model.kind == "level" and solution.row_dual is None:
        raise SolverFailure(f"solver {solution.solver} returned no row multipliers (the class gains are read "
                            "from them)")
    for b in range(model.blocks):
        if model.kind == "level":
            k = -solution.row_dual[model.gain_index[b]]
        else:
            k = solution.x[model.gain_index[b]] / solution.x[model.t_col[b]]
        K[model.block_class[b]][model.block_row[b]] = k
    return ClassGains(classes=classes, K=K, n=n, p=p)


def block_objectives(model: ClassLP, solution: LPSolution) -> np.ndarray:
    """The optimum of each block: its level (``"level"``) or its ratio ``m_r`` (``"ratio"``)."""
    if not model.blocks:
        return np.zeros(0)
    cx = np.concatenate([model.lp.c * solution.x, [0.0]])
    sums = np.add.reduceat(cx, model.block_cols[:-1])
    sums[np.diff(model.block_cols) == 0] = 0.0  # a block with no uncertain coordinate
    return -sums if model.kind == "level" else sums


# ---------------------------------------------------------------------------
# Certificate from the gains alone
# ---------------------------------------------------------------------------

@dataclass
class ClassCertificate:
    """Worst case of every state row of every class, recomputed from the ``K``\\ s alone.

    ``bounds[i, r] = Σ_c β_c |(E_d - K Z_S)[r, c]|`` is the exact worst case of
    :math:`\\xi_r(d)` for the class-form estimator (and for the node gains
    derived from it) over the box at ``mu1``.
    """

    mu1: float
    classes: ClassSet
    bounds: np.ndarray  # (classes, n)

    @property
    def levels(self) -> np.ndarray:
        """Certified level of each class (largest row)."""
        return self.bounds.max(axis=1) if self.bounds.size else np.zeros(0)

    @property
    def terminal(self) -> float:
        """Largest certified level of a terminal class (at most ``μ1`` for a valid design)."""
        lv = [lv for lv, c in zip(self.levels, self.classes) if c.terminal]
        return float(max(lv, default=0.0))

    @property
    def mu2(self) -> float:
        """Largest certified level of an inner class, at least ``μ1``."""
        return float(max([self.mu1, *(lv for lv, c in zip(self.levels, self.classes) if c.inner)]))

    def to_json(self) -> dict:
        return {"mu1": self.mu1, "certified_mu2": self.mu2, "certified_terminal": self.terminal,
                "levels": {c.label: float(v) for c, v in zip(self.classes, self.levels)}}


def certify_classes(system: AffineSystem, gains: ClassGains, mu1: float,
                    stacking: Stacking | None = None) -> ClassCertificate:
    """Exact worst case of every class row from the gains ``K`` alone (no LP, no solver)."""
    classes = gains.classes
    st = stacking or Stacking(system, classes.horizon)
    beta = _radius(st, mu1)
    bounds = np.zeros((len(classes), system.n))
    for i, (cls, K) in enumerate(zip(classes.classes, gains.K)):
        E, Z = class_maps(st, cls)
        bounds[i] = np.abs(E - K @ Z) @ beta
    return ClassCertificate(mu1=float(mu1), classes=classes, bounds=bounds)


# ---------------------------------------------------------------------------
# Costs
# ---------------------------------------------------------------------------

def _check_cost(cost: str) -> str:
    if cost not in COSTS:
        raise InputError(f"unknown cost {cost!r}; choose one of {list(COSTS)}", field="cost")
    return cost


def class_cost(classes: ClassSet, mu1: float, levels: np.ndarray, cost: str = "sum") -> float:
    r"""``J`` from class levels: :math:`(1 + 2|\mathcal L^{E'}|)\mu_1 + \sum_{\text{inner}} w \max(\mu_1, \ell)`
    (``"sum"``, :mod:`eqrec.design.delay`) or :math:`\mu_1 + \max(\mu_1, \max_{\text{inner}}\ell)` (``"max"``)."""
    _check_cost(cost)
    inner = [(c.weight, float(lv)) for c, lv in zip(classes.classes, levels) if c.inner]
    if cost == "max":
        return mu1 + max([mu1, *(lv for _, lv in inner)])
    return (1.0 + 2.0 * classes.sequences) * mu1 + sum(float(w) * max(mu1, lv) for w, lv in inner)


# ---------------------------------------------------------------------------
# Node gains from class gains
# ---------------------------------------------------------------------------

def node_schedule(system: AffineSystem, gains: ClassGains, tree: PrefixTree | None = None,
                  time_based: bool = False) -> GainSchedule:
    r"""Node gains ``(F, u0 = 0)`` per prefix of ``tree`` that realise the class-form errors.

    Along a word, the gain row of time ``d-1`` in the Q-parametrisation is
    :math:`Q_{d-1} = -K_{(d,S)} + A(d-1) K_{(d-1,S')}` (``S' ⊆ S`` embedded;
    ``K = 0`` before any data), so that
    :math:`\sum_{s<d}\Phi(d, s{+}1) Q_s Z_{S_s} = -K_{(d,S)} Z_S`; then
    ``F`` by eq. (2) of the prefix-based paper.  Tested equal in effect (same
    estimates) to the class form.
    """
    classes = gains.classes
    tree = tree or classes.tree
    if tree is None:
        raise InputError("node gains need the prefix tree of the language (a small language); this class set "
                         "was built from the window rule")
    n, p = system.n, system.p
    st = Stacking(system, tree.depth)
    word_gains = {}
    for word in tree.patterns:
        Tw = word.T
        Q = np.zeros((Tw * n, Tw * p))
        prev = np.zeros((n, Tw * p))  # K of the parent class, embedded over all times
        for node in tree.path(word):
            t = node.depth - 1
            K = gains.K[classes.node_class[node.index]]
            cur = np.zeros((n, Tw * p))
            for j, tau in enumerate(node.available):
                cur[:, tau * p:(tau + 1) * p] = K[:, j * p:(j + 1) * p]
            Q[t * n:(t + 1) * n] = -cur + system.A_at(t) @ prev
            prev = cur
        word_gains[word] = q_to_f(Q, np.zeros(Tw * n), st.word_CS(word))
    return schedule_from_word_gains(tree, word_gains, n, p, time_based=time_based)


# ---------------------------------------------------------------------------
# Fixed μ1
# ---------------------------------------------------------------------------

def _default_options(solver: str) -> dict:
    # HiGHS's presolve finds nothing to remove in independent blocks; without it the block LP solves 10-20% faster
    return {"presolve": "off"} if solver == "highs" else {}


@dataclass
class ClassSolution:
    """The class engine's answer at one ``μ1``: gains, the LP's levels and the certificate."""

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


def solve_classes(system: AffineSystem, classes: ClassSet, mu1: float, *, solver: str = "highs",
                  solver_options: dict | None = None, rtol: float | None = None) -> ClassSolution:
    """Solve the LAD LP of every (class, row) at ``μ1`` and certify the gains from themselves.

    Raises
    ------
    SolverFailure
        If the block LP has no optimum (it is always feasible and bounded).
    CertificationFailure
        If a recomputed worst case exceeds the LP's level by more than ``rtol``.
    """
    mu1 = float(mu1)
    if not np.isfinite(mu1) or mu1 <= 0:
        raise InputError(f"the recovery level mu1 must be positive, got {mu1}", field="mu1")
    st = Stacking(system, classes.horizon)
    model = build_class_lp(system, classes, mu1, stacking=st)
    t0 = time.perf_counter()
    options = _default_options(solver) if solver_options is None else solver_options
    sol = solve_lp(model.lp, solver, options).require_optimal(f"class LPs (mu1 = {mu1:g})")
    solve_time = time.perf_counter() - t0
    gains = read_class_gains(system, classes, model, sol)
    lp_levels = np.zeros((len(classes), system.n))
    lp_levels[model.block_class, model.block_row] = block_objectives(model, sol)
    cert = certify_classes(system, gains, mu1, st)
    rtol = CERT_RTOL + solver_info(solver).accuracy if rtol is None else rtol
    excess = cert.bounds - lp_levels
    scale = np.maximum(1.0, np.abs(lp_levels))
    if np.any(excess > rtol * scale):
        i, r = np.unravel_index(np.argmax(excess / scale), excess.shape)
        raise CertificationFailure(f"class {classes.classes[i].label} row {r}: the gains give worst case "
                                   f"{cert.bounds[i, r]:.9g} > the LP's level {lp_levels[i, r]:.9g}")
    # the certified value is the level: never below what the gains really give
    return ClassSolution(mu1=mu1, gains=gains, lp_levels=np.maximum(lp_levels, cert.bounds), certificate=cert,
                         solution=sol, model_shape=model.lp.shape, nonzeros=int(model.lp.A.nnz),
                         build_time=model.build_time, solve_time=solve_time)


def check_terminal(classes: ClassSet, sol: ClassSolution, rtol: float = CERT_RTOL) -> None:
    """:class:`InfeasibleDesign` naming the class and row if a terminal class's level exceeds ``μ1``."""
    mu1 = sol.mu1
    for i, cls in enumerate(classes.classes):
        if cls.terminal and sol.levels[i] > mu1 * (1 + rtol):
            r = int(np.argmax(sol.lp_levels[i]))
            raise InfeasibleDesign(f"no estimator recovers to mu1 = {mu1:g}: terminal class {cls.label} "
                                   f"(time {cls.depth}, data {list(cls.available)}) row {r} has smallest worst "
                                   f"case {sol.levels[i]:.9g}")


#: Largest prefix tree (nodes) for which node gains are derived by default.
NODE_GAINS_LIMIT = 20000

LEVELS = ("common", "max", "sum")


def class_design(system: AffineSystem, language, mu1: float, *, levels: str = "common", cost: str | None = None,
                 solver: str = "highs", solver_options: dict | None = None, method: str = "prefix",
                 certify: bool = True, node_gains: bool | None = None, time_based: bool = False,
                 rtol: float | None = None):
    """A prefix-tree design at ``μ1`` by the class engine, as a :class:`eqrec.design.result.Design`.

    Parameters
    ----------
    system : AffineSystem
    language : PrefixTree or ClassSet
        The language's prefix tree, or its classes (a full language from the
        window rule: then no node gains, no words).
    mu1 : float
        Recovery level ``μ1``.
    levels : {"common", "max", "sum"}
        As :func:`eqrec.design.prefix.build_prefix_lp`: one ``μ2`` (``common``),
        or per-node levels (``max``, ``sum``; node ``levels`` filled).
    cost : {"sum", "max"} or None
        The delayed-data paper's ``J`` in ``extra["J"]`` (``None``: not computed).
    node_gains : bool or None
        Derive node gains ``(F, u0)`` (``schedule``) and certify them by the
        independent recursion of :mod:`eqrec.core.certify`; default: when the
        tree has at most :data:`NODE_GAINS_LIMIT` nodes.

    Raises
    ------
    InfeasibleDesign
        A terminal class cannot reach ``μ1`` (named).
    CertificationFailure
        The gains do not give the levels.
    """
    from eqrec.design.result import Design

    if levels not in LEVELS:
        raise InputError(f"unknown level structure {levels!r}; choose one of {list(LEVELS)}", field="levels")
    t0 = time.perf_counter()
    classes = as_class_set(language)
    tree = classes.tree
    sol = solve_classes(system, classes, mu1, solver=solver, solver_options=solver_options, rtol=rtol)
    check_terminal(classes, sol)
    mu1 = sol.mu1
    inner = np.array([c.inner for c in classes.classes], bool)
    mu2 = float(max(mu1, sol.levels[inner].max(initial=mu1)))
    node_levels: dict[str, float] = {}
    if levels != "common" and tree is not None:
        node_levels = {node.label: float(max(mu1, sol.levels[classes.node_class[node.index]]))
                       for node in tree if not node.terminal}
    if node_gains is None:
        node_gains = tree is not None and classes.nodes <= NODE_GAINS_LIMIT
    schedule = node_schedule(system, sol.gains, tree, time_based=time_based) if node_gains else None
    patterns = tree.patterns if tree is not None else ()
    design = Design(method=method, system=system, patterns=patterns, T=classes.horizon, mu1=mu1, mu2=mu2,
                    schedule=schedule, solution=sol.solution, build_time=sol.build_time, levels=node_levels,
                    class_gains=sol.gains, class_certificate=sol.certificate)
    design.extra.update(engine="classes", classes=len(classes), sequences=classes.sequences, nodes=classes.nodes,
                        lp_rows=sol.model_shape[0], lp_cols=sol.model_shape[1], lp_nonzeros=sol.nonzeros,
                        class_levels=sol.levels)
    if cost is not None:
        design.extra.update(cost=cost, J=class_cost(classes, mu1, sol.levels, cost))
    if certify and schedule is not None:
        from eqrec.core.certify import certify_design

        certify_design(design, rtol=CERT_RTOL + solver_info(solver).accuracy if rtol is None else rtol)
    design.extra["total_time"] = time.perf_counter() - t0
    return design


def as_class_set(language) -> ClassSet:
    """A :class:`ClassSet` from a class set or a prefix tree."""
    if isinstance(language, ClassSet):
        return language
    if isinstance(language, PrefixTree):
        return classes_of_tree(language)
    raise TypeError(f"expected a ClassSet or a PrefixTree, got {type(language).__name__}")


__all__ = ["ClassLP", "ClassCertificate", "ClassSolution", "DataClass", "build_class_lp", "read_class_gains",
           "certify_classes", "class_cost", "node_schedule", "solve_classes", "check_terminal", "as_class_set",
           "class_design"]
