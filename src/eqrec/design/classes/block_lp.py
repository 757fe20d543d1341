r"""The class LPs: one block LP holding the LP of every (time, available data) class and state row.

The separation theorem of :mod:`eqrec.design.classes.engine` makes a prefix-tree design one weighted
least-absolute-deviations LP per (class, state row ``r``),

.. math:: \ell(d, S) = \max_r \min_{k} \sum_c \beta_c\, \big|E_d[r, c] - (k^\top Z_S)[c]\big|,

and :func:`build_class_lp` writes them as independent blocks of one LP (``kind="level"``; the
Charnes–Cooper ratio LP of μ1 free, :mod:`eqrec.design.classes.mu1_min`, is :func:`build_ratio_lp`, on the same blocks).
Building and reading are separate steps; :func:`eqrec.design.classes.engine.solve_classes` solves it.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.bounds.data_classes import ClassGains, ClassSet, class_maps
from eqrec.lp.model import LinearProgram, LPSolution
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.gains import box_radius
from eqrec.errors import SolverFailure


# ---------------------------------------------------------------------------
# The class LPs (build / read; solved by eqrec.design.classes.engine.solve_classes)
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
    * ``"ratio"``: the Charnes–Cooper LP of :func:`build_ratio_lp`; the
      gain row is ``y / t`` with ``y`` in columns ``gain_index[b]`` and ``t``
      in ``t_col[b]``.

    Parameters
    ----------
    lp : LinearProgram
        The block-diagonal LP.
    kind : str
    block_class, block_row : numpy.ndarray
        ``(blocks,)`` class index and state row of each block.
    gain_index : list of numpy.ndarray
    block_cols : numpy.ndarray
        ``(blocks + 1,)`` column ranges of the blocks.
    t_col : numpy.ndarray or None, optional
    build_time : float, optional
        Seconds spent building the LP.
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


def active_maps(stacking: Stacking, cls) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``E_d`` and ``Z_S`` of a class on the uncertain coordinates either touches, and those coordinates.

    The other coordinates add nothing to any row's worst case.

    Parameters
    ----------
    stacking : Stacking
    cls : DataClass
        A (time, available data) class of :mod:`eqrec.bounds.data_classes`.

    Returns
    -------
    tuple of numpy.ndarray
        ``E`` ``(n, k)``, ``Z`` ``(|S| p, k)`` on the ``k`` active coordinates, and their ``(k,)`` indices.
    """
    E, Z = class_maps(stacking, cls)
    act = active_columns(E, Z)
    return E[:, act], Z[:, act], act


def active_columns(E: np.ndarray, Z: np.ndarray) -> np.ndarray:
    """The uncertain coordinates that ``E_d`` or ``Z_S`` touches (a column with a nonzero in either).

    Parameters
    ----------
    E : numpy.ndarray
        ``(n, D)`` open-loop error map of the class's time.
    Z : numpy.ndarray
        ``(|S| p, D)`` output maps of its data.

    Returns
    -------
    numpy.ndarray
        Increasing column indices.
    """
    return np.flatnonzero(np.any(E != 0, axis=0) | np.any(Z != 0, axis=0))


class ClassBlocks:
    """The coordinate triplets, costs and bounds of a block-diagonal LP, one block per (class, row), in order."""

    def __init__(self):
        self.tri_r, self.tri_c, self.tri_v, self.cost, self.clo, self.chi, self.rlo, self.rhi = ([] for _ in range(8))
        self.gain_index, self.bcls, self.brow, self.tcols, self.bstart = [], [], [], [], [0]
        self.nrow = self.ncol = 0

    def model(self, kind: str, t0: float) -> ClassLP:
        """The :class:`ClassLP` of the blocks added.

        Parameters
        ----------
        kind : str
            ``"level"`` or ``"ratio"`` (:class:`ClassLP`).
        t0 : float
            ``time.perf_counter()`` when the build started (for ``build_time``).

        Returns
        -------
        ClassLP
        """
        cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)  # noqa: E731
        A = sp.csc_matrix((cat(self.tri_v), (cat(self.tri_r).astype(np.int64), cat(self.tri_c).astype(np.int64))),
                          shape=(self.nrow, self.ncol))
        lp = LinearProgram(c=cat(self.cost), A=A, row_lower=cat(self.rlo), row_upper=cat(self.rhi),
                           col_lower=cat(self.clo), col_upper=cat(self.chi))
        return ClassLP(lp=lp, kind=kind, block_class=np.asarray(self.bcls, np.int64),
                       block_row=np.asarray(self.brow, np.int64), gain_index=self.gain_index,
                       block_cols=np.asarray(self.bstart, np.int64),
                       t_col=np.asarray(self.tcols, np.int64) if kind == "ratio" else None,
                       build_time=time.perf_counter() - t0)


def build_class_lp(system: "AffineSystem | Stacking", classes: ClassSet, mu1: float, *, which: list[int] | None = None,
                   stacking: Stacking | None = None) -> ClassLP:
    r"""Assemble the level LPs of the classes ``which`` (default all) and every state row as one block-diagonal LP.

    The dual LAD LP of :class:`ClassLP` (``kind="level"``) at ``μ1``, over the
    uncertain coordinates ``c`` that ``E_d`` or ``Z_S`` touch
    (:func:`active_maps`): per class, ``n`` blocks sharing ``Z_S`` (rows: data,
    columns: coordinates), costs ``-E_d[r]`` per row ``r``, ``|λ_c| <= β_c``.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the classes' horizon.
    classes : ClassSet
    mu1 : float
        Recovery level ``μ1`` (radius of ``ξ0``).
    which : list of int, optional
        Indices of the classes to include (default all).
    stacking : Stacking, optional
        Stacked maps over the classes' horizon (as ``system`` may be); built when neither is one.

    Returns
    -------
    ClassLP
    """
    t0 = time.perf_counter()
    st = Stacking.of(stacking or system, classes.horizon)
    n = st.system.n
    beta = box_radius(st, float(mu1))
    bl = ClassBlocks()
    for ci in range(len(classes)) if which is None else which:
        E, Z, act = active_maps(st, classes.classes[ci])
        m, C = Z.shape
        zr, zc = np.nonzero(Z)
        off = np.arange(n)[:, None]
        bl.tri_r.append((bl.nrow + off * m + zr).ravel())
        bl.tri_c.append((bl.ncol + off * C + zc).ravel())
        bl.tri_v.append(np.broadcast_to(Z[zr, zc], (n, zr.size)).ravel())
        bl.cost.append(-E.ravel())
        box = np.broadcast_to(beta[act], (n, C)).ravel()
        bl.clo.append(-box)
        bl.chi.append(box)
        bl.rlo.append(np.zeros(n * m))  # Z_S λ = 0
        bl.rhi.append(np.zeros(n * m))
        bl.gain_index.extend(bl.nrow + np.arange(n * m).reshape(n, m))
        bl.bstart.extend((bl.ncol + C * np.arange(1, n + 1)).tolist())
        bl.bcls += [ci] * n
        bl.brow += list(range(n))
        bl.nrow += n * m
        bl.ncol += n * C
    return bl.model("level", t0)


def build_ratio_lp(system: AffineSystem, classes: ClassSet, which: list[int], stacking: Stacking, *,
                   rows: list[int] | None = None) -> ClassLP:
    r"""The Charnes–Cooper LPs of the classes ``which`` and state rows, as one block-diagonal LP (μ1 free).

    Per (class, row ``r``), over the coordinates of :func:`active_maps`:
    columns ``y`` (``|S| p``), ``t``, ``s^+``, ``s^-``; rows
    :math:`Z_S^\top y - t E_d[r] + s^+ - s^- = 0` and
    :math:`\sum_{c \in \xi_0} (s^+_c + s^-_c) - t \le -1`; cost the noise
    coordinates' radii times :math:`s^+ + s^-` (:mod:`eqrec.design.classes.mu1_min`).  The
    optimum of a block is its ratio ``m_r``, its gain row ``y / t``.

    Parameters
    ----------
    system : AffineSystem
        The system (``system.n`` state rows per class).
    classes : ClassSet
        The language's (time, available data) classes.
    which : list of int
        Indices into ``classes.classes`` of the classes to include (the terminal ones).
    stacking : Stacking
        The stacked variables of the horizon (:class:`eqrec.bounds.stacking.Stacking`).
    rows : list of int, optional
        The state rows of each class (default all, in order).

    Returns
    -------
    ClassLP
        The block-diagonal LP with its block-to-(class, row) bookkeeping.
    """
    t0 = time.perf_counter()
    xi0 = np.zeros(stacking.layout.size, bool)
    xi0[stacking.layout.xi0] = True
    beta = box_radius(stacking, 1.0)
    bl = ClassBlocks()
    for ci in which:
        E, Z, act = active_maps(stacking, classes.classes[ci])
        m, C = Z.shape
        zr, zc = np.nonzero(Z)
        zv = Z[zr, zc]
        x_act = xi0[act]
        xa = np.flatnonzero(x_act)
        noise_cost = np.where(x_act, 0.0, beta[act])
        eye = np.arange(C)
        for r in range(system.n) if rows is None else rows:
            e = E[r]
            ez = np.flatnonzero(e)
            # columns y (m), t, s+ (C), s- (C); rows: C equalities Z^T y - t e + s+ - s- = 0, then the x̃0 row
            t_c, sp_c, sm_c = bl.ncol + m, bl.ncol + m + 1, bl.ncol + m + 1 + C
            nrow = bl.nrow
            bl.tri_r += [nrow + zc, nrow + ez, nrow + eye, nrow + eye, np.full(2 * xa.size + 1, nrow + C)]
            bl.tri_c += [bl.ncol + zr, np.full(ez.size, t_c), sp_c + eye, sm_c + eye,
                         np.concatenate([sp_c + xa, sm_c + xa, [t_c]])]
            bl.tri_v += [zv, -e[ez], np.ones(C), -np.ones(C), np.concatenate([np.ones(2 * xa.size), [-1.0]])]
            bl.rlo.append(np.concatenate([np.zeros(C), [-np.inf]]))
            bl.rhi.append(np.concatenate([np.zeros(C), [-1.0]]))
            bl.cost.append(np.concatenate([np.zeros(m + 1), noise_cost, noise_cost]))
            bl.clo.append(np.concatenate([np.full(m, -np.inf), np.zeros(1 + 2 * C)]))
            bl.chi.append(np.full(m + 1 + 2 * C, np.inf))
            bl.gain_index.append(bl.ncol + np.arange(m))
            bl.tcols.append(t_c)
            bl.ncol += m + 1 + 2 * C
            bl.nrow += C + 1
            bl.bstart.append(bl.ncol)
            bl.bcls.append(ci)
            bl.brow.append(r)
    return bl.model("ratio", t0)


def row_multipliers(solution: LPSolution) -> np.ndarray:
    """The row multipliers of a level LP's solution, which the class gains are read from.

    Parameters
    ----------
    solution : LPSolution

    Returns
    -------
    numpy.ndarray
        ``solution.row_dual``.

    Raises
    ------
    SolverFailure
        The solver returned none.
    """
    if solution.row_dual is None:
        raise SolverFailure(f"solver {solution.solver} returned no row multipliers (the class gains are read "
                            "from them)")
    return solution.row_dual


def level_and_gain(solution: LPSolution, what: str) -> tuple[float, np.ndarray]:
    r"""The level (minus the optimum) and the gain row (minus the row multipliers) of one row's level LP.

    Parameters
    ----------
    solution : LPSolution
        The solution of :math:`\max E_d[r]\delta` s.t. :math:`Z_S\delta = 0` in the box (as a minimum of the
        negated objective).
    what : str
        The LP, for the error message.

    Returns
    -------
    tuple of (float, numpy.ndarray)

    Raises
    ------
    InfeasibleDesign, SolverFailure
        No optimum (:meth:`eqrec.lp.model.LPSolution.require_optimal`), or no row multipliers.
    """
    solution.require_optimal(what)
    return -solution.objective, -row_multipliers(solution)


def read_class_gains(system: AffineSystem, classes: ClassSet, model: ClassLP, solution: LPSolution) -> ClassGains:
    """The gains ``K`` per class from an optimal solution: minus the row multipliers (``"level"``) or
    ``y / t`` (``"ratio"``).

    Parameters
    ----------
    system : AffineSystem
    classes : ClassSet
    model : ClassLP
    solution : LPSolution
        Optimal solution of ``model`` (with row multipliers for ``"level"``).

    Returns
    -------
    ClassGains
    """
    n, p = system.n, system.p
    K = [np.zeros((n, len(c.available) * p)) for c in classes.classes]
    if model.kind == "level":
        row_multipliers(solution)
    for b in range(model.blocks):
        if model.kind == "level":
            k = -solution.row_dual[model.gain_index[b]]
        else:
            k = solution.x[model.gain_index[b]] / solution.x[model.t_col[b]]
        K[model.block_class[b]][model.block_row[b]] = k
    return ClassGains(classes=classes, K=K, n=n, p=p)


def block_objectives(model: ClassLP, solution: LPSolution) -> np.ndarray:
    """The optimum of each block: its level (``"level"``) or its ratio ``m_r`` (``"ratio"``).

    Parameters
    ----------
    model : ClassLP
    solution : LPSolution

    Returns
    -------
    numpy.ndarray
        ``(blocks,)`` optimum of each block.
    """
    if not model.blocks:
        return np.zeros(0)
    cx = np.concatenate([model.lp.c * solution.x, [0.0]])
    sums = np.add.reduceat(cx, model.block_cols[:-1])
    sums[np.diff(model.block_cols) == 0] = 0.0  # a block with no uncertain coordinate
    return -sums if model.kind == "level" else sums


def block_lp_options(solver: str) -> dict:
    """Solver options for a block LP of independent (class, row) blocks.

    Parameters
    ----------
    solver : str
        A solver of :mod:`eqrec.lp.solvers`.

    Returns
    -------
    dict
        ``{"presolve": "off"}`` for HiGHS (its presolve finds nothing to remove in independent blocks, and the
        block LP solves 10-20 % faster without it), else no option.
    """
    return {"presolve": "off"} if solver == "highs" else {}
