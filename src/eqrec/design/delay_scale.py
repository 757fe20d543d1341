r"""A recursive (scenario-tree) form of the node-per-prefix LP, for large delay languages.

*A proposal for the core builder* (:func:`eqrec.design.prefix.build_prefix_lp`,
owned elsewhere), kept here as a separate helper with the same variables
and optimum so that it can be measured.

The core LP writes the error map of node ``ν`` (depth ``t``) in closed form,

.. math:: G_\nu = \mathrm{Ol}_t + \sum_{s<t} \Phi(t, s+1)\, Q_{\nu_s} Y_{\mathcal A(s)},

so each robust row carries the gain variables of *every ancestor*: about
``n · Σ_s |A(s)| p`` nonzeros per ξ0 entry, growing with the depth.  The
same map satisfies the recursion

.. math:: G_\nu = A_{t-1} G_{\mathrm{parent}(\nu)} + E_{t-1} e_{w(t-1)} + Q_\nu Y_{\mathcal A(t-1)},

and with the split robust form ``G_ν = P_ν − M_ν`` (``P, M >= 0``) already
present as variables, the recursion is one equality row per structural entry
of ``G_ν`` touching only the node's own ``Q_ν, P_ν, M_ν`` and its parent's
``P, M``: the staircase structure of a scenario tree (as in multistage
stochastic programming).  It is exact — ``P − M`` is the error map — and at
an optimum ``P + M = |G|`` as in the core's split form; so the two LPs have
the same optimum (a test checks it) while the nonzeros drop several-fold
for long horizons (the benchmark's scale table, ``--builder recursive``).

Structural entries of ``G_ν``: ``ξ0`` (all), ``w(s)`` for ``s < t`` and
``v(τ)`` for ``τ ∈ A(t-1)`` (availability is nested).
"""

from __future__ import annotations

import time

import numpy as np

from eqrec.core.lp import LPBuilder
from eqrec.core.patterns import PrefixTree
from eqrec.core.stacking import Stacking
from eqrec.core.systems import AffineSystem
from eqrec.design.prefix import PrefixLP
from eqrec.errors import InputError


def _structural(lay, t: int, avail: tuple[int, ...]) -> np.ndarray:
    parts = [np.arange(lay.xi0.start, lay.xi0.stop)]
    parts += [np.arange(lay.w(s).start, lay.w(s).stop) for s in range(t)]
    parts += [np.arange(lay.v(tau).start, lay.v(tau).stop) for tau in avail]
    return np.sort(np.concatenate(parts))


def build_recursive_prefix_lp(system: AffineSystem, words, M1: float, *, levels: str = "sum") -> PrefixLP:
    """The node-per-prefix LP (``r = 0``, split form) with the error maps as recursively linked variables.

    ``levels``: ``"sum"`` (a level per non-terminal node weighted by the
    sequences through it) or ``"common"`` (one ``M2``).  Returns a
    :class:`eqrec.design.prefix.PrefixLP` whose ``q_cols`` / ``measured``
    are those of the core builder, so :func:`eqrec.design.prefix.read_schedule`
    recovers the gains.
    """
    t_start = time.perf_counter()
    if levels not in ("sum", "common"):
        raise InputError(f"levels must be 'sum' or 'common', got {levels!r}", field="levels")
    tree = words if isinstance(words, PrefixTree) else PrefixTree(words)
    T = tree.depth
    M1 = float(M1)
    st = Stacking(system, T)
    n, p = system.n, system.p
    lay = st.layout
    Y = st.output_maps
    radius = lay.radius(system.eta_w, system.eta_v, M1)
    b = LPBuilder()
    mu2 = int(b.add_variables(1, lower=M1, name="mu2")[0])
    b.set_cost(mu2, 1.0 if levels == "common" else 0.0)
    zero = b.add_variables(n, lower=0.0, upper=0.0, name="r")  # r = 0 (shared, for read_schedule)
    through = {node.index: 0 for node in tree}
    for pat in tree.patterns:
        for anc in tree.path(pat):
            through[anc.index] += 1
    q_cols, r_cols, measured, level_cols = {}, {}, {}, {}
    pm: dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]] = {}  # node -> (coords, P cols (n, k), M cols (n, k))
    I0 = np.zeros((n, lay.size))
    I0[:, lay.xi0] = np.eye(n)
    for node in tree:
        t = node.depth
        taus = list(node.available)
        measured[node.index] = taus
        q = b.add_variables(n * p * len(taus), name=f"Q[{node.label}]")
        q_cols[node.index], r_cols[node.index] = q, zero
        coords = _structural(lay, t, tuple(taus))
        k = coords.size
        P = b.add_variables(n * k, lower=0.0).reshape(n, k)
        Mc = b.add_variables(n * k, lower=0.0).reshape(n, k)
        pm[node.index] = (coords, P, Mc)
        A = system.A_at(t - 1)
        # rows (a, j): P - M - A (P_par - M_par) - Q Y = const   (row-major over a, j)
        rr, cc, vv = [np.arange(n * k), np.arange(n * k)], [P.ravel(), Mc.ravel()], [np.ones(n * k), -np.ones(n * k)]
        const = np.zeros((n, lay.size))
        const[:, lay.w(t - 1)] = system.E_at(t - 1)
        if node.parent is None:
            const += A @ I0
        else:
            pc, PP, PM = pm[node.parent]
            pos = np.searchsorted(coords, pc)  # parent's coordinates inside the child's
            a_idx, b_idx = np.nonzero(A)
            # row (a, pos[j]) gets -A[a, b] P_par[b, j] and +A[a, b] M_par[b, j]
            rows = (a_idx[:, None] * k + pos[None, :]).ravel()
            for cols, sgn in ((PP, -1.0), (PM, 1.0)):
                rr.append(rows)
                cc.append(cols[b_idx].ravel())
                vv.append(np.repeat(sgn * A[a_idx, b_idx], pc.size))
        if taus:
            Ys = Y[taus].reshape(len(taus) * p, lay.size)[:, coords]  # (|A| p, k)
            jj, kk = np.nonzero(Ys)
            qmat = q.reshape(n, len(taus) * p)
            for a in range(n):
                rr.append(a * k + kk)
                cc.append(qmat[a, jj])
                vv.append(-Ys[jj, kk])
        c = const[:, coords].ravel()
        b.add_rows(np.concatenate(rr), np.concatenate(cc), np.concatenate(vv), lower=c, upper=c, count=n * k)
        # level rows: Σ_j b_j (P + M)[a, j] <= level (M1 at the end of a sequence)
        bj = radius[coords]
        lr = [np.repeat(np.arange(n), k), np.repeat(np.arange(n), k)]
        lc = [P.ravel(), Mc.ravel()]
        lv = [np.tile(bj, n), np.tile(bj, n)]
        if node.terminal:
            b.add_rows(np.concatenate(lr), np.concatenate(lc), np.concatenate(lv), lower=-np.inf, upper=M1, count=n)
        else:
            col = mu2
            if levels == "sum":
                col = int(b.add_variables(1, lower=M1)[0])
                level_cols[node.index] = col
                b.set_cost(col, float(through[node.index]))
                b.add_rows(np.array([0, 0]), np.array([col, mu2]), np.array([1.0, -1.0]), lower=-np.inf, upper=0.0,
                           count=1)
            lr.append(np.arange(n))
            lc.append(np.full(n, col))
            lv.append(-np.ones(n))
            b.add_rows(np.concatenate(lr), np.concatenate(lc), np.concatenate(lv), lower=-np.inf, upper=0.0, count=n)
    lp = b.build()
    return PrefixLP(lp=lp, stacking=st, tree=tree, M1=M1, mu2_col=mu2, q_cols=q_cols, r_cols=r_cols,
                    measured=measured, build_time=time.perf_counter() - t_start, level_cols=level_cols)


def lp_size(model: PrefixLP) -> dict:
    """Rows, columns and nonzeros of a built LP."""
    r, c = model.lp.shape
    return {"rows": int(r), "cols": int(c), "nnz": int(model.lp.A.nnz)}

