r"""The LP of the augmented estimator with gains per event prefix of a delay language, fixed ``L`` and
``s0`` (form (4) of the delayed-data paper, its Theorem 1 / Proposition 1).

The same model as :mod:`eqrec.design.augmented.word_lp` (one innovation recursion,
:func:`eqrec.design.augmented.model.innovation_maps`): for fixed ``L`` and ``s0`` the error is affine in the
gains ``(M^α, ν^α)`` of each prefix node, and :func:`build_augmented_delay_lp` writes the robust problem
node by node, ``form="split"``, with a common level or a level per node.  Its column and row orders are
those of the stored P3 results (an LP solver may pick another optimal vertex of a reordered LP).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from eqrec.lp.model import LPBuilder, LPSolution
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.lp.robust import add_robust_rows
from eqrec.lp.solvers import solve_lp
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.model import (AugmentedPrefixGains, as_time_varying_L, effective_L, innovation_maps,
                                          transitions)
from eqrec.design.prefix.tree_lp import NodeRows


@dataclass
class AugmentedDelayLP:
    """The LP of :func:`build_augmented_delay_lp` and where its columns are (per prefix-tree node index).

    Parameters
    ----------
    lp : LinearProgram
    tree : PrefixTree
    m_cols, nu_cols : dict of int to numpy.ndarray
        Node index -> columns of its ``M^α`` (row-major) and ``ν^α``.
    mu2_col : int
        Column of the common level ``μ2``.
    level_cols : dict of int to int
        Node index -> column of its level (``levels="sum"``).
    build_time : float
        Seconds spent building the LP.
    """

    lp: object
    tree: PrefixTree
    m_cols: dict[int, np.ndarray]
    nu_cols: dict[int, np.ndarray]
    mu2_col: int
    level_cols: dict[int, int]
    build_time: float


def build_augmented_delay_lp(system: AffineSystem, tree: PrefixTree, mu1: float, L, s0, *,
                             levels: str = "common", form: str = "split") -> AugmentedDelayLP:
    """The LP of P3 Theorem 1 / Proposition 1 in ``(M^α, ν^α)`` per prefix node, for fixed ``L`` and ``s0``.

    Parameters
    ----------
    system : AffineSystem
        The model.
    tree : PrefixTree
        The delay language's prefix tree.
    mu1 : float
        Recovery level ``μ1``.
    L : array_like, shape (n, p) or (T, n, p)
        Observer gain ``L^α`` (used at steps whose measurement arrives on time, pattern (7)).
    s0 : array_like, shape (n,)
        Initial auxiliary state.
    levels : {"common", "sum"}, optional
        Minimise the largest level, or the paper's ``Σ_k Σ_α μ2,k^α`` (node levels
        weighted by the sequences through them).
    form : str, optional
        Robust-counterpart form of :func:`eqrec.lp.robust.add_robust_rows`.

    Returns
    -------
    AugmentedDelayLP
    """
    t0 = time.perf_counter()
    T = tree.depth
    st = Stacking(system, T)
    n, p = system.n, system.p
    lay = st.layout
    D = lay.size
    phi, Ol = st.transition, st.open_loop
    Lt, h0 = as_time_varying_L(L, T, n, p), -np.asarray(s0, float).reshape(n)
    b = LPBuilder()
    mu2 = int(b.add_variables(1, lower=mu1, name="mu2")[0])
    b.set_cost(mu2, 1.0 if levels == "common" else 0.0)
    m_cols, nu_cols, measured = {}, {}, {}
    for node in tree:
        taus = list(node.available)
        measured[node.index] = taus
        m_cols[node.index] = b.add_variables(n * p * len(taus), name=f"M[{node.label}]")
        nu_cols[node.index] = b.add_variables(n, name=f"nu[{node.label}]")
    through = tree.sequences_through()
    level_cols = {}
    for node in tree:
        if not node.terminal and levels == "sum":
            col = int(b.add_variables(1, lower=mu1)[0])
            level_cols[node.index] = col
            b.set_cost(col, float(through[node.index]))
    rows = NodeRows(D)  # the prefix LP's node-by-node assembly of the robust rows
    lconst, lcol = [], []
    maps: dict[tuple[bool, ...], tuple[np.ndarray, np.ndarray]] = {}  # per on-time mask: nodes share them
    for node in tree:
        t = node.depth
        # innovation maps along this node's prefix, padded to the horizon (later arrivals are not used here);
        # they depend on the prefix only through the steps whose measurement arrives on time (pattern (7))
        padded = ArrivalPattern(node.prefix.arrivals + (None,) * (T - t))
        on_time = tuple(a == k for k, a in enumerate(padded.arrivals))
        if on_time not in maps:
            Lm = effective_L(Lt, padded, "theorem2")
            maps[on_time] = tuple(map(np.stack, innovation_maps(system, transitions(system, Lm), Lm, h0)))
        Z, z0 = maps[on_time]
        blocks, cblocks = [], []
        for s, anc in enumerate(tree.path(node.prefix)):
            taus = measured[anc.index]
            P = phi[t][s + 1]
            if taus:
                blocks.append((m_cols[anc.index], NodeRows.gain_block(P, Z[taus].reshape(len(taus) * p, D))))
                zs = z0[taus].reshape(-1)
                cblocks.append((m_cols[anc.index], (P[:, :, None] * zs[None, None, :]).reshape(n, -1)))
            cblocks.append((nu_cols[anc.index], P))
        row0 = rows.add_uncertain(Ol[t].reshape(-1), blocks, n)
        # the certain part of every ancestor's (M, ν) in one block, in the order of the columns above
        rows.add_certain(row0, np.hstack([k for _, k in cblocks]), np.concatenate([c for c, _ in cblocks]))
        if node.terminal:
            lconst.append(np.full(n, float(mu1)))
            lcol.append(np.full(n, -1))
        else:
            lconst.append(np.zeros(n))
            lcol.append(np.full(n, level_cols.get(node.index, mu2)))
    rows = rows.build(b.num_variables)
    add_robust_rows(b, rows, lay.radius(system.eta_w, system.eta_v, mu1), level_const=np.concatenate(lconst),
                    level_cols=np.concatenate(lcol), level_coef=1.0, form=form)
    if levels == "sum":
        for col in level_cols.values():  # the largest level is reported through mu2
            b.add_rows(np.array([0, 0]), np.array([col, mu2]), np.array([1.0, -1.0]), lower=-np.inf, upper=0.0,
                       count=1)
    return AugmentedDelayLP(lp=b.build(), tree=tree, m_cols=m_cols, nu_cols=nu_cols, mu2_col=mu2,
                            level_cols=level_cols, build_time=time.perf_counter() - t0)


def solve_augmented_delay(system: AffineSystem, patterns, mu1: float, L, s0, *, levels: str = "common",
                          solver: str = "highs") -> tuple[AugmentedPrefixGains, LPSolution, AugmentedDelayLP]:
    """Solve :func:`build_augmented_delay_lp` and read the gains per prefix node.

    Parameters
    ----------
    system : AffineSystem
        The model.
    patterns : PrefixTree or sequence of str or ArrivalPattern
        The delay language.
    mu1 : float
        Recovery level ``μ1``.
    L : array_like, shape (n, p) or (T, n, p)
        Observer gain.
    s0 : array_like, shape (n,)
        Initial auxiliary state.
    levels : {"common", "sum"}, optional
        Cost of :func:`build_augmented_delay_lp`.
    solver : str, optional
        LP solver of the registry.

    Returns
    -------
    gains : AugmentedPrefixGains
    solution : LPSolution
    model : AugmentedDelayLP
    """
    tree = patterns if isinstance(patterns, PrefixTree) else PrefixTree(patterns, kind="delay")
    model = build_augmented_delay_lp(system, tree, mu1, L, s0, levels=levels)
    sol = solve_lp(model.lp, solver).require_optimal("augmented delay design")
    n, p = system.n, system.p
    rows = {}
    for node in tree:
        k = len(node.available)
        rows[node.prefix] = (sol.x[model.m_cols[node.index]].reshape(n, k * p), sol.x[model.nu_cols[node.index]])
    gains = AugmentedPrefixGains(rows=rows, L=as_time_varying_L(L, tree.depth, n, p),
                                 s0=np.asarray(s0, float).reshape(n))
    return gains, sol, model
