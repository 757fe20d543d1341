r"""The class LPs one class at a time: independent solves, in batches, on every core or a Dask cluster.

By the separation theorem of :mod:`eqrec.design.classes.engine` the LP of every (class, state row) is
independent of the others.  :func:`eqrec.design.classes.block_lp.build_class_lp` writes them all as one
block-diagonal LP; past a few hundred classes one simplex run over that LP costs several times the sum
of the blocks (a (4, 40) reactor design: 3.5 s against 0.5 s) and uses one core.  This module solves
them **per class**:

* the level LPs of a class (:func:`level_task`): its maps :math:`E_d, Z_S` built from the class
  alone (:func:`eqrec.bounds.data_classes.class_maps`; nothing of the other classes is held), one LP per
  state row on the shared constraints :math:`Z_S\lambda = 0`, :math:`|\lambda| \le \beta`, solved in row
  order with HiGHS keeping its basis from one row to the next (only the objective changes:
  :func:`eqrec.lp.solvers.solve_lp_grid`; the same for a second ``μ1``, e.g. the lower end of
  μ1 free, with the bounds changed), then the class certificate
  :math:`\sum_c \beta_c |(E_d - K Z_S)[r, c]|` recomputed from the gains; the maps are released;
* the Charnes–Cooper LPs of μ1 free (:func:`ratio_task`), one per terminal (class, row), and the
  ratio recomputed from each gain row.

The classes are cut into batches of consecutive classes of about equal estimated work
(:func:`plan_batches`), so that small classes do not pay the cost of a task each, and the batches run
through :func:`eqrec.lp.parallel.run_tasks` (joblib: local processes or a Dask cluster).  A class is
always solved whole by one task, from its own data only, so the results are the same bytes whatever the
number of workers, the batching or the backend.

Which path (:func:`choose_path`): the per-class solves give other optimal vertices than the one block
LP (a degenerate LP has several; last digits of a level may move), so the choice depends on the size
only, never on the number of workers: ``"auto"`` keeps the one block LP up to
:data:`MONOLITHIC_MAX_WORK` (every language of the papers' studies, whose stored results it wrote) and
solves per class beyond, where that is measured faster (``benchmarks/bench_classes.py``, part d).  Below
:data:`POOL_MIN_WORK` the per-class solves run in this process unless the workers are already up
(:func:`eqrec.lp.parallel.pool_ready`).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.checks import short_label
from eqrec.bounds.data_classes import ClassSet, DataClass, class_maps
from eqrec.lp.model import LinearProgram
from eqrec.lp.parallel import Progress, check_jobs, pool_ready, prestart, run_tasks
from eqrec.lp.solvers import record_retries, retry_log, solve_lp, solve_lp_grid
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.classes.gains import box_radius
from eqrec.design.inputs import LARGE_CLASS_WORK
from eqrec.design.classes.block_lp import active_columns, block_lp_options, build_ratio_lp, level_and_gain
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure

#: The ways to solve the class LPs: by size, the one block LP, or per class.
PATHS = ("auto", "monolithic", "blocks")
#: Largest estimated work (:func:`class_work` summed over the LPs) solved as one block LP by ``path="auto"``.
#: Measured on the batch reactor, one core: the one LP is faster up to (τ̄, T) = (4, 16) (work 3.2e5, 0.18 s
#: either way), the per-class solves beyond ((4, 20): 0.23 s against 0.29 s; (4, 40): 0.6 s against 2.9 s).
#: Every language of the papers' studies is far below (the reactor's (2, 5): 3.4e3; the scale table measures the
#: one LP by name), so their stored results keep the one LP's bytes.
MONOLITHIC_MAX_WORK = 400_000
#: Estimated work below which the per-class solves stay in this process, ``n_jobs`` whatever, unless the pool
#: of workers is already running (starting it costs 0.3-1 s; one core does about 1.5e7 units a second).
POOL_MIN_WORK = 8_000_000
#: Batches per worker (load balance) and smallest work of a batch (task overhead).
BATCHES_PER_WORKER, MIN_BATCH_WORK = 6, 400_000
#: Fixed cost of a class's LPs in the batches' work units (``n`` times :func:`class_work`), added to each class's
#: weight: a HiGHS model per class and a run per row and ``μ1`` cost about 1.1 ms, its maps and certificate
#: 0.3 ms, where a unit costs about 3.5e-8 s (fit on the reactor's (4, 60), one core, μ1 free).
CLASS_OVERHEAD = 40_000
# LARGE_CLASS_WORK (imported above from eqrec.design.inputs, which estimates the time with it): the work
# (:func:`class_work`) above which a class's level LPs run HiGHS's primal simplex without presolve
# (:data:`LARGE_CLASS_OPTIONS`), or follow one chain (:mod:`eqrec.design.classes.chains`).
#: The HiGHS settings of a class above :data:`LARGE_CLASS_WORK`.
LARGE_CLASS_OPTIONS = {"presolve": "off", "simplex_strategy": 4}


def check_path(path: str) -> str:
    """``path`` if it is one of :data:`PATHS`, else :class:`~eqrec.errors.InputError` (field ``path``).

    Parameters
    ----------
    path : str

    Returns
    -------
    str
    """
    if path not in PATHS:
        raise InputError(f"unknown path {path!r}; choose one of {list(PATHS)}", field="path")
    return path


def class_work(data_class: DataClass, system: AffineSystem) -> int:
    """Estimated work of a class's LP: its rows ``|S| p`` times its columns (the coordinates it touches).

    Parameters
    ----------
    data_class : DataClass
    system : AffineSystem

    Returns
    -------
    int
        ``|S| p (d nw + |S| nv + n)``, at least 1.
    """
    m = len(data_class.available) * system.p
    return max(1, m * (data_class.depth * system.nw + len(data_class.available) * system.nv + system.n))


def choose_path(path: str, classes: ClassSet, which, system: AffineSystem) -> str:
    """``"monolithic"`` or ``"blocks"`` for the classes ``which`` (default all): ``path`` unless ``"auto"``.

    Parameters
    ----------
    path : {"auto", "monolithic", "blocks"}
    classes : ClassSet
    which : list of int or None
    system : AffineSystem

    Returns
    -------
    str
        ``"auto"`` resolves by size: the one block LP up to :data:`MONOLITHIC_MAX_WORK`, per class beyond.
    """
    if check_path(path) != "auto":
        return path
    idx = range(len(classes)) if which is None else which
    work = system.n * sum(class_work(classes.classes[i], system) for i in idx)
    return "monolithic" if work <= MONOLITHIC_MAX_WORK else "blocks"


def plan_batches(weights, workers: int) -> list[list[int]]:
    """Runs of consecutive indices of about equal total weight, heaviest run first.

    Parameters
    ----------
    weights : sequence of int
        Work of each item.
    workers : int
        Worker processes: about :data:`BATCHES_PER_WORKER` runs each, none lighter than
        :data:`MIN_BATCH_WORK` unless it is the last.

    Returns
    -------
    list of list of int
        The runs, in decreasing order of weight (the order they are handed out in; results are put back
        by index, so it does not change them).
    """
    weights = [int(w) for w in weights]
    target = max(MIN_BATCH_WORK, sum(weights) / max(1, BATCHES_PER_WORKER * workers))
    runs, cur, acc = [], [], 0
    for i, w in enumerate(weights):
        cur.append(i)
        acc += w
        if acc >= target:
            runs.append(cur)
            cur, acc = [], 0
    if cur:
        runs.append(cur)
    return sorted(runs, key=lambda r: -sum(weights[i] for i in r))


@dataclass
class LevelBlock:
    """What :func:`level_task` returns for one class.

    Parameters
    ----------
    K : numpy.ndarray
        ``(n, |S| p)`` gain (minus the row multipliers of each row's LP).
    levels, bounds : numpy.ndarray
        ``(n,)`` each row's LP optimum and its worst case recomputed from ``K``.
    iterations, rows, cols, nonzeros : int
        Simplex iterations of the class's LPs and their total size.
    """

    K: np.ndarray
    levels: np.ndarray
    bounds: np.ndarray
    iterations: int
    rows: int
    cols: int
    nonzeros: int


def level_task(stacking: Stacking, chunk: list[DataClass], mu1s: list[float], solver: str,
               options: dict) -> list[list[LevelBlock]]:
    """Solve the level LP of every state row of each class of ``chunk`` at each ``μ1`` and certify its gains.

    Per class one model (module docstring): the rows in order at ``mu1s[0]``, then at ``mu1s[1]`` (only the
    radii of ``ξ0`` change), ...

    Parameters
    ----------
    stacking : Stacking
        The design's stacked model over the classes' horizon (rebuilt from its system in a worker process).
    chunk : list of DataClass
        The classes of this task.
    mu1s : list of float
        Recovery levels.
    solver : str
    options : dict
        LP solver and its options.

    Returns
    -------
    list of list of LevelBlock
        Per class of ``chunk``, one per ``μ1``, in order.

    Raises
    ------
    SolverFailure
        A row's LP without an optimum, or without row multipliers.
    """
    st, system = stacking, stacking.system
    betas = [box_radius(st, float(mu1)) for mu1 in mu1s]
    out = []
    for cls in chunk:
        E, Z = class_maps(st, cls)  # full width: the LPs read the active columns, the certificate all of them
        act = active_columns(E, Z)
        m, C = Z.shape[0], act.size
        K = [np.zeros((system.n, m)) for _ in mu1s]
        levels, iters = np.zeros((len(mu1s), system.n)), np.zeros(len(mu1s), np.int64)
        if C:
            Ea = E[:, act]
            lp = LinearProgram(c=np.zeros(C), A=_csc(Z[:, act]), row_lower=np.zeros(m), row_upper=np.zeros(m),
                               col_lower=-betas[0][act], col_upper=betas[0][act])
            large = solver == "highs" and class_work(cls, system) > LARGE_CLASS_WORK
            grid = solve_lp_grid(lp, [-Ea[r] for r in range(system.n)], [(-b[act], b[act]) for b in betas], solver,
                                 {**options, **LARGE_CLASS_OPTIONS} if large else options)
            for j, sols in enumerate(grid):
                for r, sol in enumerate(sols):
                    levels[j, r], K[j][r] = level_and_gain(sol, f"class {short_label(cls.label)} row {r} (mu1 = {mu1s[j]:g})")
                    iters[j] += sol.iterations
        size = {"rows": system.n * m, "cols": system.n * C, "nonzeros": system.n * int(np.count_nonzero(Z))}
        out.append([LevelBlock(K=K[j], levels=levels[j], iterations=int(iters[j]), **size,
                               bounds=np.abs(E - K[j] @ Z) @ betas[j])
                    for j in range(len(mu1s))])
    return out


def _csc(Z: np.ndarray) -> sp.csc_matrix:
    """``Z`` (dense) as a CSC matrix, built from its nonzeros column by column (faster than SciPy's converter)."""
    cols, rows = np.nonzero(Z.T)
    indptr = np.zeros(Z.shape[1] + 1, np.int64)
    np.cumsum(np.bincount(cols, minlength=Z.shape[1]), out=indptr[1:])
    return sp.csc_matrix((Z[rows, cols], rows, indptr), shape=Z.shape)


def ratio_task(stacking: Stacking, chunk: list[DataClass], solver: str, options: dict) -> list[list[tuple]]:
    """The Charnes–Cooper LP of every state row of each terminal class of ``chunk``, and its ratio recomputed.

    Parameters
    ----------
    stacking : Stacking
        The design's stacked model over the classes' horizon (rebuilt from its system in a worker process).
    chunk : list of DataClass
        Terminal classes.
    solver : str
    options : dict

    Returns
    -------
    list of list of tuple
        Per class, per row: ``(status, ratio, k, recomputed, iterations)``; ``ratio`` is the LP's optimum,
        ``k`` the gain row ``y / t`` and ``recomputed`` the ratio :math:`b(k) / (1 - a(k))` from ``k``
        alone (``inf`` if ``a(k) >= 1``); ``k`` and the ratios are ``None`` when the LP has no optimum.
    """
    st, system, horizon = stacking, stacking.system, stacking.T
    xi0 = np.zeros(st.layout.size, bool)
    xi0[st.layout.xi0] = True
    noise_beta = np.where(xi0, 0.0, box_radius(st, 1.0))
    out = []
    for cls in chunk:
        one = ClassSet(classes=(cls,), horizon=horizon, words=0, sequences=0, nodes=0, source="window")
        E, Z = class_maps(st, cls)
        rows = []
        for r in range(system.n):
            model = build_ratio_lp(system, one, [0], st, rows=[r])
            sol = solve_lp(model.lp, solver, options)
            if not sol.optimal:
                rows.append((sol.status, None, None, None, sol.iterations))
                continue
            k = sol.x[model.gain_index[0]] / sol.x[model.t_col[0]]
            resid = np.abs(E[r] - k @ Z)  # no data (Z empty): k @ Z is zero
            a = resid[xi0].sum()
            rows.append(("optimal", float(sol.objective), k, resid @ noise_beta / (1.0 - a) if a < 1 else np.inf,
                         sol.iterations))
        out.append(rows)
    return out


def _run(task, stacking: Stacking, classes: ClassSet, which: list[int], args: tuple, *, n_jobs, scheduler,
         label: str) -> list:
    """``task`` over the classes ``which`` in batches; its per-class results in the order of ``which``.

    Each batch carries the design's stacking (to a worker process as its system and horizon, the maps rebuilt
    there: :meth:`eqrec.bounds.stacking.Stacking.__reduce__`)."""
    system = stacking.system
    work = [system.n * class_work(classes.classes[i], system) for i in which]  # n LPs per class
    total = sum(work)
    weights = [CLASS_OVERHEAD + w for w in work]  # what a batch costs
    local = scheduler is None and total < POOL_MIN_WORK and not pool_ready(n_jobs)  # no pool to start for this
    workers = 1 if local else check_jobs(n_jobs)
    runs = plan_batches(weights, workers)
    tasks = [(task, stacking, [classes.classes[which[j]] for j in run], *args) for run in runs]
    progress = Progress(len(which), label) if total >= POOL_MIN_WORK else None
    results = run_tasks(_logged, tasks, n_jobs=workers, scheduler=scheduler, progress=progress,
                        units=[len(run) for run in runs])
    per_class: list = [None] * len(which)
    for run, (res, retried) in zip(runs, results):
        record_retries(retried)  # the solves a worker had to retry, into this process's log
        for j, r in zip(run, res):
            per_class[j] = r
    return per_class


def _logged(task, *args) -> tuple:
    """``task(*args)`` and the LP solves it had to retry (:func:`eqrec.lp.solvers.retry_log`)."""
    with retry_log() as retried:
        return task(*args), list(retried)


def prestart_workers(system: AffineSystem, classes: ClassSet, n_jobs=None, scheduler=None) -> bool:
    """Start the local workers ahead (:func:`eqrec.lp.parallel.prestart`) if the level LPs will need them.

    That is: solved per class, with more work than :data:`POOL_MIN_WORK`, more than one worker and no scheduler.

    Parameters
    ----------
    system : AffineSystem
    classes : ClassSet
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional

    Returns
    -------
    bool
        Whether they were started (then call :func:`eqrec.lp.parallel.settle` when done).
    """
    if scheduler is not None or check_jobs(n_jobs) <= 1 or choose_path("auto", classes, None, system) != "blocks":
        return False
    if system.n * sum(class_work(c, system) for c in classes.classes) < POOL_MIN_WORK:
        return False
    prestart(level_task, n_jobs)
    return True


def solve_level_blocks(system: "AffineSystem | Stacking", classes: ClassSet, mu1s: list[float], *, solver: str,
                       options: dict, n_jobs=None, scheduler=None,
                       which: list[int] | None = None) -> tuple[list[list[LevelBlock]], float]:
    """:func:`level_task` over every class, in batches (:func:`eqrec.lp.parallel.run_tasks`).

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the classes' horizon.
    classes : ClassSet
    mu1s : list of float
        Recovery levels, solved one after the other per class.
    solver : str
    options : dict
    n_jobs : int or None, optional
        Worker processes (default every core).
    scheduler : str, distributed.Client or None, optional
        A Dask scheduler.
    which : list of int or None, optional
        Only these classes (default all; :func:`eqrec.design.classes.chains.solve_levels` leaves out a chain).

    Returns
    -------
    tuple
        Per ``μ1``, the :class:`LevelBlock` of each class of ``which`` in order; and the wall-clock seconds.
    """
    t0 = time.perf_counter()
    per_class = _run(level_task, Stacking.of(system, classes.horizon), classes,
                     list(range(len(classes))) if which is None else list(which),
                     ([float(mu) for mu in mu1s], solver, dict(options)), n_jobs=n_jobs, scheduler=scheduler,
                     label="eqrec: classes solved")
    return [[blocks[j] for blocks in per_class] for j in range(len(mu1s))], time.perf_counter() - t0


def solve_ratio_blocks(system: "AffineSystem | Stacking", classes: ClassSet, which: list[int], *, solver: str,
                       n_jobs=None, scheduler=None) -> dict:
    """:func:`ratio_task` over the terminal classes ``which``; :class:`InfeasibleDesign` names one without a ratio.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the classes' horizon.
    classes : ClassSet
    which : list of int
        The terminal classes.
    solver : str
    n_jobs : int or None, optional
    scheduler : str, distributed.Client or None, optional

    Returns
    -------
    dict
        ``block_class``, ``block_row`` (per (class, row) LP), ``ratios``, ``recomputed``, ``gains`` (per class
        index, ``(n, |S| p)``), ``lps`` (LPs solved) and ``iterations``.
    """
    st = Stacking.of(system, classes.horizon)
    system = st.system
    per_class = _run(ratio_task, st, classes, which, (solver, block_lp_options(solver)), n_jobs=n_jobs,
                     scheduler=scheduler, label="eqrec: terminal classes solved")
    bc, br, ratios, recomputed, gains, iters = [], [], [], [], {}, 0
    for i, rows in zip(which, per_class):
        cls = classes.classes[i]
        K = np.zeros((system.n, len(cls.available) * system.p))
        for r, (status, ratio, k, rec, it) in enumerate(rows):
            iters += it
            if status == "infeasible":
                raise InfeasibleDesign(f"no recovery level is feasible: along the terminal class {short_label(cls.label)} "
                                       f"(time {cls.depth}, data {short_label(list(cls.available))}) no gain makes the "
                                       "initial error contract (min_k a(k) >= 1)")
            if status != "optimal":
                raise SolverFailure(f"the smallest recovery level (Charnes-Cooper LP of class {short_label(cls.label)} row {r}): "
                                    f"solver status {status!r}")
            K[r] = k
            bc.append(i)
            br.append(r)
            ratios.append(ratio)
            recomputed.append(rec)
        gains[i] = K
    return {"block_class": np.asarray(bc, np.int64), "block_row": np.asarray(br, np.int64),
            "ratios": np.asarray(ratios, float), "recomputed": np.asarray(recomputed, float), "gains": gains,
            "lps": len(bc), "iterations": iters}
