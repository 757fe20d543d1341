r"""The tree LP of the prefix-based design (Theorem 3 of the prefix-based paper): build and read.

Decision variables: one block per prefix-tree node.  The node of prefix
``q(0..t)`` owns the gain row of time ``t`` of the Q-parametrisation,
``Q(t, τ)`` for the measured ``τ <= t`` of the prefix, and ``r(t)``.  Words
that share a prefix therefore share these rows by construction, which is the
polyhedral set :math:`\mathcal Q(\mathcal L)` of eq. (11) without any equality
constraint between copies (:mod:`tests.test_design_prefix` checks it against
the paper's copy-per-word form).  ``Q(t, τ)`` for a missing ``τ`` multiplies
:math:`y_\xi(\tau) = 0` and is omitted (it is set to zero).

The error at time ``t`` depends only on the prefix ``q(0..t-1)`` (eq. (13)
restricted to its first ``t`` blocks, a consequence of Lemma 1), so the
robust constraints are written once per node:

.. math:: \xi(t) = \mathrm{Ol}_t\,\delta + \sum_{s<t} \Phi(t, s{+}1)
          \Big(\sum_{\tau \le s,\ q(\tau) = 1} Q(s,\tau) Y_\tau \delta + r(s)\Big),

where :math:`\mathrm{Ol}_t` is the open-loop error map and :math:`Y_\tau` the
output-error map of :class:`eqrec.bounds.stacking.Stacking`.  Nodes where a word
ends get level ``M1``, the others the variable ``M2`` (eq. (12b)); ``M2 >=
M1`` covers ``t = 0``.

Offsets ``r`` (hence ``u0``) are fixed to zero by default.  This loses no
optimality: the error has no constant term except ``S r`` and the box is
symmetric, so if ``(Q, r)`` is feasible then so is ``(Q, -r)`` and, by
convexity, ``(Q, 0)``.  Without it a simplex solver returns a vertex with an
arbitrary bias that drives every run to the same extreme error (certified,
but not what a user wants); ``zero_offset=False`` keeps the paper's free ``r``
(tests check both optima agree).  The design itself (solve, certify) is :func:`eqrec.design.prefix.design.design_prefix`.
"""

from __future__ import annotations

import numbers
import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from eqrec.bounds.gains import GainSchedule, q_to_f, schedule_from_word_gains
from eqrec.lp.model import LinearProgram, LPBuilder
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_pattern
from eqrec.lp.robust import RobustRowsIndex, UncertainAffineRows, add_robust_rows
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

#: The robust-counterpart forms of :func:`eqrec.lp.robust.add_robust_rows`.
FORMS = ("split", "abs", "dual")


@dataclass
class PrefixLP:
    """The built LP of a prefix-based design and where its variables are.

    Parameters
    ----------
    lp : LinearProgram
        The LP (Theorem 3 of the prefix-based paper, one variable block per tree node).
    stacking : Stacking
        The stacked maps of the horizon.
    tree : PrefixTree
        The language's prefix tree.
    mu1 : float
        Recovery level ``M1`` (radius of the initial-error box).
    mu2_col : int
        Column of the common level ``M2``.
    q_cols, r_cols : dict of int to numpy.ndarray
        Node index -> columns of its ``Q`` row (``n x k p``, row-major) and of ``r(t)``.
    measured : dict of int to list of int
        Node index -> available measurement times ``A(t)``.
    build_time : float, optional
        Seconds spent building.
    level_cols : dict of int to int, optional
        Node index -> column of its own level ``μ2`` (per-node levels).
    robust_index : RobustRowsIndex or None, optional
        Where the robust rows are (:func:`eqrec.lp.robust.add_robust_rows`).
    mu1_col : int or None, optional
        Column of ``μ1`` as a variable (``mu1_range``), else ``None``.
    levels : str, optional
        The level structure (:func:`build_prefix_lp`).
    """

    lp: LinearProgram
    stacking: Stacking
    tree: PrefixTree
    mu1: float
    mu2_col: int
    q_cols: dict[int, np.ndarray]  # node index -> columns of Q row (n x k p, row-major)
    r_cols: dict[int, np.ndarray]  # node index -> columns of r(t)
    measured: dict[int, list[int]]  # node index -> available measurement times A(t)
    build_time: float = 0.0
    level_cols: dict[int, int] = field(default_factory=dict)  # node index -> its own level μ2 (per-node levels)
    robust_index: RobustRowsIndex | None = None
    mu1_col: int | None = None  # the recovery level as a variable (mu1_range)
    levels: str = "common"  # the level structure (build_prefix_lp)


class NodeRows:
    r"""The uncertain affine rows of the node-per-prefix LPs, assembled node by node.

    Each node adds ``n`` rows :math:`\xi(t) = (G_0 + G_x x)\,\delta + c_x x`
    (:class:`eqrec.lp.robust.UncertainAffineRows`): ``G_0`` the open-loop
    map of its depth, ``G_x`` the blocks of its ancestors' gain columns, ``c_x``
    their offsets.  Only the structural entries of ``G`` are kept (those that a
    constant or a column touches).

    Parameters
    ----------
    coords : int
        Number ``D`` of uncertain coordinates ``δ``.
    """

    def __init__(self, coords: int):
        self.D = coords
        self.rows = self.entries = 0
        self.er, self.ec, self.G0, self.gr, self.gc, self.gv = [], [], [], [], [], []
        self.cr, self.cc, self.cv = [], [], []

    @staticmethod
    def gain_block(P: np.ndarray, Y: np.ndarray) -> np.ndarray:
        r"""The coefficients of ``vec_r(Φ Q Y)`` in ``vec_r(Q)``: :math:`\Phi \otimes Y^T`, a block of ``vec G``.

        Parameters
        ----------
        P : numpy.ndarray
            ``Φ``, shape ``(n, n)``.
        Y : numpy.ndarray
            The maps ``Y`` the gain ``Q`` multiplies, shape ``(k, D)``.

        Returns
        -------
        numpy.ndarray
            Shape ``(n D, n k)``, written as a broadcast outer product.
        """
        return (P[:, None, :, None] * Y.T[None, :, None, :]).reshape(P.shape[0] * Y.shape[1], P.shape[1] * Y.shape[0])

    def add_uncertain(self, const: np.ndarray, blocks: list, n: int) -> int:
        """Add ``n`` uncertain rows of ``G``.

        Parameters
        ----------
        const : numpy.ndarray
            ``vec G_0``, shape ``(n D,)`` (row-major).
        blocks : list of (numpy.ndarray, numpy.ndarray)
            ``(columns, coefficients)``: the columns and their ``(n D, len(columns))`` part of ``vec G``.
        n : int
            Number of rows.

        Returns
        -------
        int
            Index of the first added row.
        """
        D = self.D
        K = np.hstack([blk for _, blk in blocks]) if blocks else np.zeros((n * D, 0))
        cols = np.concatenate([c for c, _ in blocks]) if blocks else np.zeros(0, int)
        idx = np.flatnonzero((const != 0) | np.any(K != 0, axis=1))
        row0 = self.rows
        self.er.append(row0 + idx // D)
        self.ec.append(idx % D)
        self.G0.append(const[idx])
        Ki = K[idx]
        kr, kc = np.nonzero(Ki)  # row-major, the order of a COO conversion
        self.gr.append(kr + self.entries)
        self.gc.append(cols[kc])
        self.gv.append(Ki[kr, kc])
        self.entries += idx.size
        self.rows += n
        return row0

    def add_certain(self, row0: int, P: np.ndarray, cols: np.ndarray) -> None:
        """Add ``P`` times the columns ``cols`` to the certain part of the rows from ``row0``.

        Parameters
        ----------
        row0 : int
            First row (from :meth:`add_uncertain`).
        P : numpy.ndarray
            Coefficients, shape ``(rows, len(cols))``.
        cols : numpy.ndarray
            Decision-variable columns.
        """
        rr, cc = np.nonzero(P)
        self.cr.append(row0 + rr)
        self.cc.append(cols[cc])
        self.cv.append(P[rr, cc])

    def build(self, nx: int) -> UncertainAffineRows:
        """The rows over ``nx`` decision variables.

        Parameters
        ----------
        nx : int
            Number of decision variables.

        Returns
        -------
        UncertainAffineRows
            The rows ``(G_0 + G_x x) δ + c_x x``.
        """
        cat = np.concatenate
        return UncertainAffineRows(
            entry_row=cat(self.er), entry_coord=cat(self.ec), G0=cat(self.G0),
            Gx=sp.csr_matrix((cat(self.gv), (cat(self.gr), cat(self.gc))), shape=(self.entries, nx)),
            c0=np.zeros(self.rows),
            cx=sp.csr_matrix((cat(self.cv or [np.zeros(0)]), (cat(self.cr or [np.zeros(0, int)]),
                                                              cat(self.cc or [np.zeros(0, int)]))),
                             shape=(self.rows, nx)))


def build_prefix_lp(system: "AffineSystem | Stacking", words, mu1: float, *, T: int | None = None,
                    form: str = "split", zero_offset: bool = True, levels: str = "common",
                    mu1_range: tuple[float, float] | None = None, mu1_cost: float = 1.0) -> PrefixLP:
    """Build the LP of Theorem 3 (minimise ``M2`` for given ``M1``) over a prefix tree.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The affine system, or the design's stacked model over the horizon (kept as ``PrefixLP.stacking``,
        which the gains and the certificate then read; built here from a system).
    words : sequence of str or ArrivalPattern, or PrefixTree
        The language (words may differ in length: Section V extension; the
        recovery level ``M1`` is then imposed at each word's end).
    mu1 : float
        Equalized recovery level.
    T : int or None, optional
        Horizon for the stacked matrices (default: the longest word).
    form : str, optional
        Robust counterpart (:func:`eqrec.lp.robust.add_robust_rows`): ``"split"``,
        ``"abs"`` or the paper's Π-dual ``"dual"``.
    zero_offset : bool, optional
        Fix ``r = 0`` (no loss of optimality, see the module docstring).
    levels : {"common", "sum", "max"}, optional
        ``"common"``: one intermediate level ``M2`` for every node (the
        prefix-based paper; minimised).  ``"sum"``: a level ``μ2`` per
        non-terminal node, ``μ2 >= M1``, minimising ``Σ_node w_node μ2,node`` with
        ``w_node`` the number of patterns through the node (the cost
        ``Σ_k Σ_α μ2,k^α`` of the delayed-data paper counts each pattern);
        ``"max"``: per-node levels and the largest one minimised (same optimum
        as ``"common"``).  With ``"sum"`` the column ``mu2_col`` is unused (the
        largest level is read from the node levels).
    mu1_range : tuple of float or None, optional
        Make the recovery level a variable ``μ1 ∈ [lo, hi]`` (cost ``mu1_cost μ1``):
        terminal rows are bounded by it and every level by ``>= μ1``, while the
        initial-error box keeps the radius ``M1``.  With ``M1 = lo`` the LP is a
        relaxation of the bilinear problem (10) of the delayed-data paper over
        ``μ1 ∈ [lo, hi]`` (``|G_ξ0| μ1 >= |G_ξ0| lo``): its optimum is a lower
        bound of the cost on that interval.
    mu1_cost : float, optional
        Cost coefficient of the ``μ1`` column (with ``mu1_range``).

    Returns
    -------
    PrefixLP
        The LP and where its variables are.
    """
    t_start = time.perf_counter()
    if form not in FORMS:
        raise InputError(f"unknown robust-counterpart form {form!r}; choose one of {list(FORMS)}", field="form")
    if T is not None and (isinstance(T, bool) or not isinstance(T, numbers.Integral) or T < 1):
        raise InputError(f"the horizon must be a positive integer, got {T!r}", field="T")
    tree = words if isinstance(words, PrefixTree) else PrefixTree(words)
    T = tree.depth if T is None else int(T)
    if tree.depth > T:
        raise InputError(f"words of length {tree.depth} exceed the horizon T = {T}", field="T")
    mu1 = float(mu1)
    if not np.isfinite(mu1) or mu1 <= 0:
        raise InputError(f"the recovery level mu1 must be positive, got {mu1}", field="mu1")
    st = Stacking.of(system, T)
    system = st.system
    n, p = system.n, system.p
    lay = st.layout
    phi, Ol, Y = st.transition, st.open_loop, st.output_maps

    if levels not in ("common", "sum", "max"):
        raise InputError(f"unknown level structure {levels!r}; choose 'common', 'sum' or 'max'", field="levels")
    b = LPBuilder()
    level_lower = mu1 if mu1_range is None else float(mu1_range[0])
    mu2 = int(b.add_variables(1, lower=level_lower, name="mu2")[0])
    b.set_cost(mu2, 1.0 if levels != "sum" else 0.0)
    mu1_col = None
    if mu1_range is not None:
        lo, hi = map(float, mu1_range)
        if not (0 < lo <= hi and np.isfinite(hi)):
            raise InputError(f"the range of mu1 must satisfy 0 < lo <= hi < inf, got {mu1_range}", field="mu1")
        mu1_col = int(b.add_variables(1, lower=lo, upper=hi, name="mu1")[0])
        b.set_cost(mu1_col, float(mu1_cost))
    q_cols: dict[int, np.ndarray] = {}
    r_cols: dict[int, np.ndarray] = {}
    measured: dict[int, list[int]] = {}
    for node in tree:
        taus = list(node.available)  # A(t): for delays, includes earlier times that arrived late
        measured[node.index] = taus
        q_cols[node.index] = b.add_variables(n * p * len(taus), name=f"Q[{node.label}]")
        bound = 0.0 if zero_offset else np.inf
        r_cols[node.index] = b.add_variables(n, lower=-bound, upper=bound, name=f"r[{node.label}]")

    # Robust rows of ξ(t) for every node of depth t (the error after that prefix).
    D = lay.size
    rows = NodeRows(D)
    level_const, level_coef, row_level_col = [], [], []
    node_level: dict[int, int] = {}
    if levels != "common":
        through = tree.sequences_through()
        for node in tree:
            if node.terminal:
                continue  # its rows are bounded by M1
            col = int(b.add_variables(1, lower=level_lower, name=f"mu2[{node.label}]")[0])
            node_level[node.index] = col
            if levels == "sum":
                b.set_cost(col, float(through[node.index]))
            else:  # max: the common mu2 bounds every node level
                b.add_rows(np.array([0, 0]), np.array([col, mu2]), np.array([1.0, -1.0]), lower=-np.inf, upper=0.0,
                           count=1)
    for node in tree:
        t = node.depth
        path = tree.path(node.prefix)  # ancestors at depths 1..t (times 0..t-1)
        blocks = []  # (columns, coefficient matrix of vec(G_t) (nD x len(columns)))
        for s, anc in enumerate(path):
            taus = measured[anc.index]
            if taus:
                blocks.append((q_cols[anc.index], NodeRows.gain_block(phi[t][s + 1], Y[taus].reshape(len(taus) * p, D))))
        row0 = rows.add_uncertain(Ol[t].reshape(-1), blocks, n)
        # certain part c_t = Σ_s Φ(t, s+1) r(s) (identically zero when r is fixed to zero)
        for s, anc in enumerate(path if not zero_offset else []):
            rows.add_certain(row0, phi[t][s + 1], r_cols[anc.index])
        fixed = node.terminal and mu1_col is None  # a terminal row bounded by the constant mu1
        level_const.append(np.full(n, mu1 if fixed else 0.0))
        level_coef.append(np.full(n, 0.0 if fixed else 1.0))
        if node.terminal and mu1_col is not None:
            row_level_col.append(np.full(n, mu1_col))
        else:
            row_level_col.append(np.full(n, mu2 if levels == "common" else node_level.get(node.index, -1)))
    if mu1_col is not None:  # every level is at least mu1
        for col in [mu2, *node_level.values()]:
            b.add_rows(np.array([0, 0]), np.array([mu1_col, col]), np.array([1.0, -1.0]), lower=-np.inf, upper=0.0,
                       count=1)
    radius = lay.radius(system.eta_w, system.eta_v, mu1)
    robust_index = add_robust_rows(b, rows.build(b.num_variables), radius, level_const=np.concatenate(level_const),
                                   level_cols=np.concatenate(row_level_col), level_coef=np.concatenate(level_coef),
                                   form=form)
    lp = b.build()
    return PrefixLP(lp=lp, stacking=st, tree=tree, mu1=mu1, mu2_col=mu2, q_cols=q_cols, r_cols=r_cols,
                    level_cols=node_level, robust_index=robust_index, mu1_col=mu1_col, levels=levels,
                    measured=measured, build_time=time.perf_counter() - t_start)


def word_Q_r(model: PrefixLP, x: np.ndarray, word: "ArrivalPattern | str") -> tuple[np.ndarray, np.ndarray]:
    """Assemble the stacked ``Q (Tn x Tp)`` and ``r`` of one pattern from the node variables.

    Parameters
    ----------
    model : PrefixLP
        The built LP.
    x : numpy.ndarray
        A point of the LP (its solution).
    word : ArrivalPattern or str
        A pattern of the language.

    Returns
    -------
    Q : numpy.ndarray
        Shape ``(T n, T p)``, block lower triangular.
    r : numpy.ndarray
        Shape ``(T n,)``.
    """
    sys = model.stacking.system
    word = as_pattern(word)
    n, p, T = sys.n, sys.p, word.T
    Q = np.zeros((T * n, T * p))
    r = np.zeros(T * n)
    for node in model.tree.path(word):
        t = node.depth - 1
        taus = model.measured[node.index]
        vals = x[model.q_cols[node.index]].reshape(n, len(taus) * p) if taus else np.zeros((n, 0))
        for j, tau in enumerate(taus):
            Q[t * n:(t + 1) * n, tau * p:(tau + 1) * p] = vals[:, j * p:(j + 1) * p]
        r[t * n:(t + 1) * n] = x[model.r_cols[node.index]]
    return Q, r


def read_schedule(model: PrefixLP, solution, *, time_based: bool = False) -> GainSchedule:
    """Recover the gains ``(F, u0)`` of every prefix from an optimal solution or its point (eqs. (1), (2)).

    Parameters
    ----------
    model : PrefixLP
        The built LP.
    solution : LPSolution or numpy.ndarray
        An optimal solution, or its point ``x``.
    time_based : bool, optional
        Build a time-based schedule (one gain per time).

    Returns
    -------
    GainSchedule
        The node gains.
    """
    st = model.stacking
    sys = st.system
    x = getattr(solution, "x", solution)
    word_gains = {}
    for word in model.tree.patterns:
        Q, r = word_Q_r(model, x, word)
        word_gains[word] = q_to_f(Q, r, st.word_CS(word))
    return schedule_from_word_gains(model.tree, word_gains, sys.n, sys.p, time_based=time_based)
