r"""The level LPs of a chain of large classes, in state-space form, each warm-started from the one before.

The level LP of class :math:`(d, S)` and state row ``r`` (the dual of the LAD LP of
:mod:`eqrec.design.classes.engine`, as :func:`eqrec.design.classes.blocks.level_task` solves it) is

.. math:: \ell_r(d, S) = \max_\delta\ E_d[r]\,\delta \quad\text{s.t.}\quad Z_S\,\delta = 0,\ |\delta_c| \le \beta_c,

with :math:`\delta = (w, v, \xi_0)` in the box of radii :math:`\beta = (\eta_w, \eta_v, \mu_1)`.  Since
:math:`E_d\delta = x_d` and :math:`Z_S\delta = (C(\tau) x_\tau + V(\tau) v_\tau)_{\tau\in S}` along the error
trajectory :math:`x_0 = \xi_0,\ x_{t+1} = A(t) x_t + E(t) w_t` (:attr:`eqrec.bounds.stacking.Stacking.open_loop`,
:attr:`~eqrec.bounds.stacking.Stacking.output_maps`), it is the same LP as its **state-space form**

.. math::

    \max\ x_d[r] \quad\text{s.t.}\quad x_{t+1} - A(t) x_t - E(t) w_t = 0\ (t < d), \qquad
    C(\tau) x_\tau + V(\tau) v_\tau = 0\ (\tau \in S),

with ``x_1 .. x_d`` free columns, ``x_0 = ξ0`` and the box on ``(w, v, ξ0)``: about ``d (n + nw) + |S| (p + nv)``
nonzeros where the dense form has ``|S| p`` rows full of ``d (nw + nv)`` columns.  Eliminating the states by
their dynamics rows gives back the dense LP with the same reduced costs of ``δ``, so the multipliers ``y`` of
the output rows are row multipliers of :math:`Z_S\delta = 0`: the gain row is :math:`K[r] = -y`, as in
:func:`~eqrec.design.classes.blocks.level_task`, and the certificate :math:`\sum_c \beta_c |(E_d - K Z_S)[r, c]|`
is recomputed from ``K`` by the same formula (:func:`eqrec.bounds.certify.class_bounds`, :func:`bounds_task`).

**Chains.**  When the classes ``(d_1, S_1), (d_2, S_2), ...`` satisfy :math:`d_k \le d_{k+1}` and
:math:`S_k \subseteq S_{k+1}`, with the columns and rows in the order they appear, each class's LP is a leading
block of the next one's: :math:`(d, S) \to (d+1, S)` appends ``w_d``, ``x_{d+1}`` and the dynamics row of
``d``, :math:`S \to S \cup \{\tau\}` appends ``v_τ`` and the output rows of ``τ``.  One HiGHS model per (row,
``μ1``) grows along the chain and keeps its basis (:func:`eqrec.lp.solvers.solve_lp_chain`): tens of simplex
iterations per LP instead of hundreds, on a sparse basis.  With maximum delay 1 every class is on one chain
:math:`(d-1, S) \to (d, S) \to (d, S \cup \{d-1\})`; for a larger delay the classes of a time branch (a tree),
and :func:`chain_classes` leaves them to the per-class solves.

Which classes: only those above :data:`eqrec.design.classes.blocks.LARGE_CLASS_WORK` (:func:`chain_classes`),
above every class of the papers' studies and of the example plants up to ``T = 100``, so that their stored
results keep their bytes; and HiGHS only.  The LPs are solved to the tolerances :data:`CHAIN_OPTIONS` (at
HiGHS's defaults the certificate of a ``T = 1000`` design stood ``6e-6`` above its level, past the
certificate's tolerance).  The levels stay those the gains certify: the certificate is recomputed from ``K``
and a level below it is raised to it (:func:`eqrec.design.classes.engine.solve_classes_at`), so a looser LP
costs tightness only.  Each chain is one task (a row, every ``μ1``) and the certificates are computed per class,
so the results are the same bytes whatever the number of workers.

A delay above 1 keeps the per-class solves (its classes branch; following a tree would need the basis saved and
restored between the branches).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from eqrec.checks import short_label
from eqrec.bounds.data_classes import ClassGains, ClassSet, DataClass, class_error_map
from eqrec.bounds.stacking import Stacking
from eqrec.design.classes import blocks
from eqrec.design.classes.block_lp import level_and_gain
from eqrec.design.classes.gains import box_radius
from eqrec.systems.affine import AffineSystem
from eqrec.lp.model import LinearProgram, LPBuilder
from eqrec.lp.parallel import Progress, check_jobs, pool_ready, run_tasks
from eqrec.lp.solvers import record_retries, solve_lp_chain

#: HiGHS settings of the chain LPs, over :data:`eqrec.design.classes.blocks.LARGE_CLASS_OPTIONS`: feasibility
#: tolerances 1e-9 (HiGHS's 1e-7 left certificates 6e-6 above the levels of a two-cart ``T = 1000`` design), and no
#: scaling (the state-space rows have unit and plant coefficients; measured on the two-cart plant at ``T = 400``:
#: 47 instead of 75 simplex iterations per LP, 1.9 s instead of 2.6 s a chain).
CHAIN_OPTIONS = {"primal_feasibility_tolerance": 1e-9, "dual_feasibility_tolerance": 1e-9,
                 "simplex_scale_strategy": 0}


def chain_classes(classes: ClassSet, system: AffineSystem, solver: str) -> list[int]:
    """The classes above :data:`~eqrec.design.classes.blocks.LARGE_CLASS_WORK`, if they form one chain, else none.

    Parameters
    ----------
    classes : ClassSet
    system : AffineSystem
    solver : str
        Only HiGHS solves chains.

    Returns
    -------
    list of int
        Indices (increasing) of the large classes when each is nested in the next (``d`` nondecreasing,
        ``S`` growing: every maximum delay 1 design); ``[]`` otherwise (a delay above 1, another solver).
    """
    if solver != "highs":
        return []
    idx = [i for i, c in enumerate(classes.classes) if blocks.class_work(c, system) > blocks.LARGE_CLASS_WORK]
    for a, b in zip(idx, idx[1:]):
        first, then = classes.classes[a], classes.classes[b]
        if then.depth < first.depth or not set(first.available) <= set(then.available):
            return []
    return idx


@dataclass
class ChainLP:
    """The state-space LP of the last class of a chain, whose leading blocks are the LPs of the others.

    Parameters
    ----------
    lp : LinearProgram
        Columns and rows in the order they appear along the chain (objective zero).
    prefixes : list of tuple of int
        ``(rows, cols)`` of each class's LP, a leading block of ``lp``.
    state : list of numpy.ndarray
        Per class ``(d, S)``: the ``n`` columns of ``x_d``.
    outputs : list of numpy.ndarray
        Per class: the ``|S| p`` rows :math:`C(\\tau) x_\\tau + V(\\tau) v_\\tau = 0` in the order of ``S``, then
        of the outputs (the columns of ``Z_S`` and ``K``).
    xi0 : numpy.ndarray
        The ``n`` columns of ``ξ0 = x_0`` (bounds ``±μ1``).
    """

    lp: LinearProgram
    prefixes: list[tuple[int, int]]
    state: list[np.ndarray]
    outputs: list[np.ndarray]
    xi0: np.ndarray

    def bounds_at(self, mu1: float) -> tuple[np.ndarray, np.ndarray]:
        """``(col_lower, col_upper)`` of :attr:`lp` with the radius of ``ξ0`` set to ``mu1``.

        Parameters
        ----------
        mu1 : float

        Returns
        -------
        tuple of numpy.ndarray
        """
        lo, hi = self.lp.col_lower.copy(), self.lp.col_upper.copy()
        lo[self.xi0], hi[self.xi0] = -mu1, mu1
        return lo, hi


def build_chain_lp(stacking: Stacking, chain: list[DataClass], mu1: float) -> ChainLP:
    """The state-space level LPs (module docstring) of the classes ``chain`` (each nested in the next), at ``μ1``.

    Parameters
    ----------
    stacking : Stacking
        The design's stacked model (its system and the layout of the box radii).
    chain : list of DataClass
        Classes with nondecreasing time and growing data.
    mu1 : float
        Radius of ``ξ0``.

    Returns
    -------
    ChainLP
    """
    system, lay = stacking.system, stacking.layout
    n = system.n
    beta = box_radius(stacking, mu1)
    b = LPBuilder()
    x = [b.add_variables(n, -beta[lay.xi0], beta[lay.xi0])]  # x_0 = ξ0
    out_rows: dict[int, np.ndarray] = {}
    prefixes, state, outputs = [], [], []

    def add_rows(M: np.ndarray, cols: np.ndarray) -> np.ndarray:  # rows M @ x[cols] = 0
        rr, cc = np.nonzero(M)
        return b.add_rows(rr, cols[cc], M[rr, cc], 0.0, 0.0, count=M.shape[0])

    for cls in chain:
        while len(x) <= cls.depth:  # step t: x_{t+1} - A(t) x_t - E(t) w_t = 0
            t = len(x) - 1
            w = b.add_variables(system.nw, -beta[lay.w(t)], beta[lay.w(t)])
            x.append(b.add_variables(n))
            add_rows(np.hstack([np.eye(n), -system.A_at(t), -system.E_at(t)]), np.concatenate([x[t + 1], x[t], w]))
        for tau in cls.available:  # arrival of y(τ): C(τ) x_τ + V(τ) v_τ = 0
            if tau not in out_rows:
                v = b.add_variables(system.nv, -beta[lay.v(tau)], beta[lay.v(tau)])
                out_rows[tau] = add_rows(np.hstack([system.C_at(tau), system.V_at(tau)]), np.concatenate([x[tau], v]))
        prefixes.append((b.num_rows, b.num_variables))
        state.append(x[cls.depth])
        outputs.append(np.concatenate([out_rows[tau] for tau in cls.available]) if cls.available
                       else np.zeros(0, np.int64))
    return ChainLP(lp=b.build(), prefixes=prefixes, state=state, outputs=outputs, xi0=x[0])


def chain_task(stacking: Stacking, chain: list[DataClass], row: int, mu1s: list[float], solver: str,
               options: dict) -> tuple[np.ndarray, list[list[np.ndarray]], np.ndarray]:
    """The level LP of state row ``row`` of every class of ``chain`` at every ``μ1``, along the chain.

    One model (:func:`eqrec.lp.solvers.solve_lp_chain`): per class the objective :math:`\\max x_d[r]`, solved at
    each ``μ1`` in turn (only the bounds of ``ξ0`` change: for the two close levels of μ1 free the second run
    takes no iteration).

    Parameters
    ----------
    stacking : Stacking
    chain : list of DataClass
        Classes each nested in the next (:func:`chain_classes`).
    row : int
        State row ``r``.
    mu1s : list of float
    solver : str
    options : dict
        HiGHS settings (:data:`CHAIN_OPTIONS` added by the caller).

    Returns
    -------
    tuple
        The levels ``(len(mu1s), len(chain))``; per ``μ1``, per class, the gain row ``K[r]`` ``(|S| p,)``; the
        simplex iterations ``(len(mu1s), len(chain))``.

    Raises
    ------
    SolverFailure
        An LP without an optimum or without row multipliers.
    """
    model = build_chain_lp(stacking, chain, mu1s[0])  # build
    costs = []
    for (_, cols), x_d in zip(model.prefixes, model.state):
        c = np.zeros(cols)
        c[x_d[row]] = -1.0  # max x_d[r]
        costs.append(c)
    sols = solve_lp_chain(model.lp, model.prefixes, costs, [model.bounds_at(mu1) for mu1 in mu1s], solver,
                          options)  # solve
    levels, iters = np.zeros((len(mu1s), len(chain))), np.zeros((len(mu1s), len(chain)), np.int64)
    gains: list[list[np.ndarray]] = [[] for _ in mu1s]
    for i, (cls, per_mu1) in enumerate(zip(chain, sols)):  # read
        for j, sol in enumerate(per_mu1):
            levels[j, i], K_row = level_and_gain(sol, f"class {short_label(cls.label)} row {row} (mu1 = {mu1s[j]:g}, chain)")
            iters[j, i] = sol.iterations
            gains[j].append(K_row[model.outputs[i]])  # the multipliers of the output rows (module docstring)
    return levels, gains, iters


def bounds_task(stacking: Stacking, chunk: list[DataClass], gains: list[list[np.ndarray]],
                mu1s: list[float]) -> list[np.ndarray]:
    """The certificate :math:`\\sum_c \\beta_c |(E_d - K Z_S)[r, c]|` of each class of ``chunk`` at each ``μ1``.

    The formula of :func:`eqrec.bounds.certify.class_bounds` (the same bytes), with the error map
    :func:`eqrec.bounds.data_classes.class_error_map` formed once per class for the ``μ1`` whose gains are equal
    (the two close levels of μ1 free end on one basis, hence one ``K``).

    Parameters
    ----------
    stacking : Stacking
    chunk : list of DataClass
    gains : list of list of numpy.ndarray
        Per ``μ1``, the gain ``K`` ``(n, |S| p)`` of each class of ``chunk``.
    mu1s : list of float

    Returns
    -------
    list of numpy.ndarray
        Per ``μ1``, ``(len(chunk), n)``.
    """
    system = stacking.system
    one = ClassSet(classes=tuple(chunk), horizon=stacking.T, words=0, sequences=0, nodes=0, source="window")
    per_mu1 = [ClassGains(classes=one, K=K, n=system.n, p=system.p) for K in gains]
    betas = [box_radius(stacking, mu1) for mu1 in mu1s]
    out = [np.zeros((len(chunk), system.n)) for _ in mu1s]
    for i in range(len(chunk)):
        done: list[tuple[np.ndarray, np.ndarray]] = []  # (K, |E_d - K Z_S|) formed so far
        for j, g in enumerate(per_mu1):
            G = next((G for K, G in done if np.array_equal(K, g.K[i])), None)
            if G is None:
                G = np.abs(class_error_map(stacking, g, i))
                done.append((g.K[i], G))
            out[j][i] = G @ betas[j]
    return out


def solve_chain_blocks(stacking: Stacking, classes: ClassSet, which: list[int], mu1s: list[float], *, solver: str,
                       options: dict, n_jobs=None, scheduler=None) -> list[list["blocks.LevelBlock"]]:
    """The level LPs of the classes ``which`` (one chain, :func:`chain_classes`), as ``level_task`` gives them.

    One task per state row along the whole chain (:func:`chain_task`), then the certificates in
    batches of consecutive classes (:func:`bounds_task`), through :func:`eqrec.lp.parallel.run_tasks`; local
    when the work is below :data:`~eqrec.design.classes.blocks.POOL_MIN_WORK` and no pool runs.

    Parameters
    ----------
    stacking : Stacking
    classes : ClassSet
    which : list of int
        The chain.
    mu1s : list of float
    solver : str
    options : dict
        The caller's LP options (:data:`~eqrec.design.classes.blocks.LARGE_CLASS_OPTIONS` and
        :data:`CHAIN_OPTIONS` are added).
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional

    Returns
    -------
    list of list of LevelBlock
        Per class of ``which``, one per ``μ1``.
    """
    system, n = stacking.system, stacking.system.n
    chain = [classes.classes[i] for i in which]
    work = [n * blocks.class_work(c, system) for c in chain]
    local = scheduler is None and sum(work) < blocks.POOL_MIN_WORK and not pool_ready(n_jobs)
    workers = 1 if local else check_jobs(n_jobs)
    opts = {**options, **blocks.LARGE_CLASS_OPTIONS, **CHAIN_OPTIONS}
    mu1s = [float(mu) for mu in mu1s]
    progress = Progress(n, "eqrec: class chains solved") if sum(work) >= blocks.POOL_MIN_WORK else None
    tasks = [(chain_task, stacking, chain, r, mu1s, solver, opts) for r in range(n)]
    levels = np.zeros((len(mu1s), len(chain), n))
    K = [[np.zeros((n, len(c.available) * system.p)) for c in chain] for _ in mu1s]
    iters = np.zeros((len(mu1s), len(chain)), np.int64)
    for r, (res, retried) in enumerate(run_tasks(blocks._logged, tasks, n_jobs=workers, scheduler=scheduler,
                                                 progress=progress)):
        record_retries(retried)
        levels[:, :, r], iters = res[0], iters + res[2]
        for j in range(len(mu1s)):
            for i, k in enumerate(res[1][j]):
                K[j][i][r] = k
    runs = blocks.plan_batches(work, workers)
    tasks = [(bounds_task, stacking, [chain[i] for i in run], [[K[j][i] for i in run] for j in range(len(mu1s))],
              mu1s) for run in runs]
    bounds = np.zeros((len(mu1s), len(chain), n))
    for run, (res, retried) in zip(runs, run_tasks(blocks._logged, tasks, n_jobs=workers, scheduler=scheduler)):
        for j in range(len(mu1s)):
            bounds[j, run] = res[j]
    sizes = build_chain_lp(stacking, chain, mu1s[0])  # the size of each class's LP
    indptr = sizes.lp.A.tocsr().indptr  # a class's rows touch its own columns only: its nonzeros are its rows'
    return [[blocks.LevelBlock(K=K[j][i], levels=levels[j, i], bounds=bounds[j, i], iterations=int(iters[j, i]),
                               rows=n * rows, cols=n * cols, nonzeros=n * int(indptr[rows]))
             for j in range(len(mu1s))] for i, (rows, cols) in enumerate(sizes.prefixes)]


def solve_levels(stacking: Stacking, classes: ClassSet, mu1s: list[float], *, solver: str, options: dict,
                 n_jobs=None, scheduler=None) -> tuple[list[list["blocks.LevelBlock"]], float]:
    """The level LPs of every class: the large ones along their chain (:func:`chain_classes`), the others per class.

    The classes off the chain (all of them when the large ones form no chain, e.g. a delay above 1) go to
    :func:`eqrec.design.classes.blocks.solve_level_blocks` unchanged; the chain to :func:`solve_chain_blocks`.

    Parameters
    ----------
    stacking : Stacking
        The design's stacked model over the classes' horizon.
    classes : ClassSet
    mu1s : list of float
    solver : str
    options : dict
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional

    Returns
    -------
    tuple
        Per ``μ1``, the :class:`~eqrec.design.classes.blocks.LevelBlock` of each class in order (as
        :func:`~eqrec.design.classes.blocks.solve_level_blocks`); and the wall-clock seconds.
    """
    t0 = time.perf_counter()
    mu1s = [float(mu) for mu in mu1s]
    chain = chain_classes(classes, stacking.system, solver)
    if not chain:
        return blocks.solve_level_blocks(stacking, classes, mu1s, solver=solver, options=options, n_jobs=n_jobs,
                                         scheduler=scheduler)
    on_chain = set(chain)
    rest = [i for i in range(len(classes)) if i not in on_chain]
    per_class: list = [None] * len(classes)
    if rest:
        per_mu1, _ = blocks.solve_level_blocks(stacking, classes, mu1s, solver=solver, options=options,
                                               n_jobs=n_jobs, scheduler=scheduler, which=rest)
        for k, i in enumerate(rest):
            per_class[i] = [per_mu1[j][k] for j in range(len(mu1s))]
    for i, b in zip(chain, solve_chain_blocks(stacking, classes, chain, mu1s, solver=solver, options=options,
                                              n_jobs=n_jobs, scheduler=scheduler)):
        per_class[i] = b
    return [[b[j] for b in per_class] for j in range(len(mu1s))], time.perf_counter() - t0
