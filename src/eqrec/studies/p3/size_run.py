r"""The scale table of the delayed-data design: one size of the full delay language per fresh process.

For the full language ``{0..τ̄}^T`` on a system (the scale table uses the
batch reactor of Section IV-A of the delayed-data paper; sum cost of
Theorem 1 / Proposition 1, ``μ1`` fixed, so an LP), :func:`measure_size`
solves the design with one of two engines (:data:`ENGINES`) and one HiGHS
method:

* ``engine="tree"``: the node-per-prefix LP
  (:func:`eqrec.design.prefix.tree_lp.build_prefix_lp`, builder ``core``) on the
  prefix tree of the enumerated event sequences;
* ``engine="classes"``: the class engine (:func:`eqrec.design.classes.engine.solve_classes`)
  on the (time, available data) classes of the language built by the window
  rule (:func:`eqrec.bounds.data_classes.classes_of_full_language`): no word, sequence
  or node is enumerated, their numbers come in closed form
  (:func:`eqrec.bounds.data_classes.full_language_counts`).

Recorded (:data:`FIELDS`, in table order):

* ``engine``; ``words`` ``(τ̄+1)^T``, ``sequences`` (the reduced event
  language ``L^{E'}``), ``nodes`` (event-prefix tree), ``classes`` (the
  language's (time, data) classes, ``Σ_d 2^min(τ̄, d)``, for both engines);
* the LP's ``rows``, ``cols``, ``nnz``;
* ``tree_time`` (tree: enumerate the language and build its prefix tree),
  ``classes_time`` (classes: the class set by the window rule),
  ``build_time``, ``solve_time``, ``iterations``;
* ``objective``: the solved LP's own optimum (tree: ``Σ w μ2`` over the inner
  nodes, without the constant ``(1 + 2|L^{E'}|) μ1``; classes: the sum of the
  (class, row) LAD optima); ``J``: the paper's sum cost (the same for both
  engines at the optimum, by the separation theorem of :mod:`eqrec.design.classes.engine`);
  ``max_level``: the largest level ``max μ2`` (classes: certified from the
  gains, :class:`eqrec.design.classes.gains.ClassCertificate`; tree: the LP's);
  ``terminal_level`` (classes: largest certified terminal level, ``<= μ1``);
* ``status`` (``"optimal"``, ``"infeasible"``, ``"time limit"``, ``"memory limit"``, ...),
* ``peak_mb``: the peak resident memory of the process (``ru_maxrss``).

:func:`run_size` runs it in a fresh Python process (``python -m
eqrec.studies.p3.size_run '<json>' [--engine tree|classes]``; the system travels as
:meth:`eqrec.systems.affine.AffineSystem.to_dict`) so that ``peak_mb`` is that size's alone, with
an address-space limit (``RLIMIT_AS``; an allocation beyond it is reported
as ``"memory limit"``), HiGHS's ``time_limit`` (reported as ``"time
limit"``) and a wall-clock kill (``"wall-clock kill"``); a process that
dies otherwise is reported as ``"crashed (...)"`` with the end of its
error output.  ``benchmarks/bench_p3.py``, ``benchmarks/bench_classes.py`` and the P3 scale steps call it.

HiGHS methods (:data:`METHODS`): ``simplex`` (dual simplex), ``ipm``
(interior point, crossover off), ``ipm-x`` (interior point + crossover),
``pdlp`` (first-order PDLP); ``-np``: presolve off; ``auto``: HiGHS's
choice; ``none``: build only (tree engine only).
Builder (tree engine): ``core`` (:func:`eqrec.design.prefix.tree_lp.build_prefix_lp`;
the scenario-tree form that preceded the class engine is gone: the tree LP
separates, :mod:`eqrec.design.classes.engine`); the class engine records
``builder = "classes"``.
"""

from __future__ import annotations

import importlib
import json
import os
import resource
import signal
import subprocess
import sys
import time

from eqrec.checks import peak_memory_mb
from eqrec.systems.files import system_from_mapping
from eqrec.systems.affine import AffineSystem

#: HiGHS options of each method name.
METHODS: dict[str, dict] = {
    "simplex": {"solver": "simplex"}, "ipm": {"solver": "ipm", "run_crossover": "off"},
    "ipm-x": {"solver": "ipm", "run_crossover": "on"}, "pdlp": {"solver": "pdlp"},
    "pdlp-np": {"solver": "pdlp", "presolve": "off"},
    "ipm-np": {"solver": "ipm", "run_crossover": "off", "presolve": "off"}, "auto": {}, "none": {}}
BUILDERS = ("core",)
#: ``tree``: the node-per-prefix LP; ``classes``: the class engine (module docstring).
ENGINES = ("tree", "classes")

#: Fields of a result, in table order.
FIELDS = ("engine", "T", "tau", "words", "sequences", "nodes", "classes", "builder", "rows", "cols", "nnz",
          "tree_time", "classes_time", "build_time", "method", "solve_time", "iterations", "objective", "J",
          "max_level", "terminal_level", "peak_mb", "status", "mu1", "time_limit", "mem_limit_gb", "wall_time",
          "detail")

_MEMORY_MARKERS = ("MemoryError", "bad_alloc", "Cannot allocate memory", "out of memory", "failed to map segment")


def _check(method: str, builder: str, engine: str = "tree") -> None:
    for name, value, allowed in (("engine", engine, ENGINES), ("HiGHS method", method, METHODS),
                                 ("builder", builder, BUILDERS)):
        if value not in allowed:
            raise ValueError(f"unknown {name} {value!r}; choose one of {sorted(allowed)}")
    if engine == "classes" and method == "none":
        raise ValueError("the class engine has no build-only method: choose a HiGHS method")


def _size_fields(engine: str, T: int, tau: int, method: str, builder: str, mu1: float, time_limit: float) -> dict:
    """The fields that name a measurement, known before it runs (the class engine records ``builder = "classes"``)."""
    return {"engine": engine, "T": int(T), "tau": int(tau), "classes": class_count(T, tau), "method": method,
            "builder": "classes" if engine == "classes" else builder, "mu1": float(mu1),
            "time_limit": float(time_limit)}


def _status(raw: str) -> str:
    low = raw.lower()
    return "time limit" if "time limit" in low else "memory limit" if "memory" in low else raw


def class_count(T: int, tau: int) -> int:
    """Classes of ``{0..τ̄}^T`` (``Σ_{d=1}^{T} 2^min(τ̄, d)``), from the window rule of :mod:`eqrec.bounds.data_classes`.

    Parameters
    ----------
    T, tau : int
        Horizon ``T`` and largest delay ``τ̄``.

    Returns
    -------
    int
        The number of (time, available data) classes.
    """
    from eqrec.bounds.data_classes import classes_of_full_language

    return len(classes_of_full_language(int(T), int(tau)))


def tree_J(objective: float, sequences: int, mu1: float) -> float:
    """The paper's cost ``J`` of a tree LP's optimum with levels per node (``levels="sum"``).

    Every level column is bounded below by ``μ1`` and costs its weight, so ``J`` adds the
    ``(1 + 2 |L^E'|) μ1`` of ``k = 0`` and ``k = T`` (:func:`eqrec.design.cost.cost_weights`).

    Parameters
    ----------
    objective : float
        The LP's optimal objective.
    sequences : int
        Number ``|L^E'|`` of event sequences.
    mu1 : float
        Recovery level ``μ1``.

    Returns
    -------
    float
    """
    return float(objective) + (1.0 + 2.0 * int(sequences)) * float(mu1)


def _measure_tree(system: AffineSystem, T: int, tau: int, method: str, mu1: float, opts: dict, out: dict) -> dict:
    from eqrec.arrivals.prefix_tree import PrefixTree
    from eqrec.lp.solvers import solve_lp
    from eqrec.design.delay.design import delay_language
    from eqrec.design.prefix.tree_lp import build_prefix_lp

    build_prefix_lp(system, PrefixTree(delay_language(max_delay=1, horizon=2)), mu1, levels="sum")  # warm-up
    t0 = time.perf_counter()
    pats = delay_language(max_delay=int(tau), horizon=int(T))
    tree = PrefixTree(pats)
    t1 = time.perf_counter()
    out.update(words=(int(tau) + 1) ** int(T), sequences=len(pats), nodes=len(tree), tree_time=t1 - t0)
    model = build_prefix_lp(system, tree, float(mu1), levels="sum")
    t2 = time.perf_counter()
    out.update(rows=int(model.lp.shape[0]), cols=int(model.lp.shape[1]), nnz=int(model.lp.A.nnz),
               build_time=t2 - t1)
    if method == "none":
        out["status"] = "built"
        return out
    sol = solve_lp(model.lp, "highs", opts)
    out.update(status=_status(sol.status), solve_time=sol.solve_time, iterations=sol.iterations,
               objective=float(sol.objective))
    if sol.optimal:
        out["J"] = tree_J(sol.objective, len(pats), mu1)
        cols = list(getattr(model, "level_cols", {}).values())
        out["max_level"] = float(max([float(mu1), *(float(sol.x[c]) for c in cols)]))
    return out


def _measure_classes(system: AffineSystem, T: int, tau: int, mu1: float, opts: dict, out: dict) -> dict:
    from eqrec.bounds.data_classes import classes_of_full_language, full_language_counts
    from eqrec.design.classes.engine import solve_classes
    from eqrec.design.cost import class_cost
    from eqrec.errors import SolverFailure

    # the scale table measures the one block LP (its rows, columns, iterations); per class: engine "blocks"
    solve_classes(system, classes_of_full_language(2, 1), float(mu1), solver_options=opts,
                  path="monolithic")  # warm-up (imports)
    t0 = time.perf_counter()
    classes = classes_of_full_language(int(T), int(tau))
    t1 = time.perf_counter()
    counts = full_language_counts(int(T), int(tau))
    out.update(words=int(counts["words"]), sequences=int(counts["sequences"]), nodes=int(counts["nodes"]),
               classes=len(classes), classes_time=t1 - t0)
    try:
        sol = solve_classes(system, classes, float(mu1), solver="highs", solver_options=opts, path="monolithic")
    except SolverFailure as exc:
        out.update(status=_status(str(exc)), detail=f"SolverFailure: {exc}")
        return out
    (rows, cols), cert, lp = sol.model_shape, sol.certificate, sol.solution
    out.update(rows=int(rows), cols=int(cols), nnz=int(sol.nonzeros), build_time=float(sol.build_time),
               solve_time=float(sol.solve_time), iterations=int(lp.iterations) if lp is not None else None,
               objective=float(lp.objective) if lp is not None else None,
               J=float(class_cost(classes, float(mu1), sol.levels, "sum")), max_level=float(cert.mu2),
               terminal_level=float(cert.terminal))
    # the design exists iff every terminal class reaches μ1 (separation theorem)
    out["status"] = "optimal" if cert.terminal <= float(mu1) * (1 + 1e-6) else "infeasible"
    return out


def measure_size(system: AffineSystem, T: int, tau: int, method: str = "ipm", mu1: float = 0.5,
                 time_limit: float = 600.0, builder: str = "core", options: dict | None = None,
                 out: dict | None = None, engine: str = "tree") -> dict:
    """Build and solve the full-language design of one size ``(T, τ̄)`` in this process.

    Parameters
    ----------
    system : AffineSystem
        The plant (time-invariant, or time-varying over at least ``T`` steps).
    T, tau : int
        Horizon and largest delay: the language ``{0..τ̄}^T``.
    method : str, optional
        A key of :data:`METHODS` (``"none"``: build only, tree engine).
    mu1 : float, optional
        The fixed recovery level ``μ1``.
    time_limit : float, optional
        HiGHS's time limit in seconds.
    builder : str, optional
        Tree engine: ``"core"`` (recorded as ``"classes"`` for the class engine).
    options : dict or None, optional
        Extra HiGHS options (override the method's).
    out : dict or None, optional
        A dict filled in as the measurement proceeds (so that the sizes and
        build time survive a later failure); a new one by default.
    engine : {"tree", "classes"}, optional
        ``"tree"`` (the node-per-prefix LP on the enumerated language) or
        ``"classes"`` (the class engine on the window-rule classes; no word
        enumerated).

    Returns
    -------
    dict
        The fields of :data:`FIELDS` that apply (no ``peak_mb``: see :func:`run_size`).
    """
    _check(method, builder, engine)
    out = {} if out is None else out
    out.update(_size_fields(engine, T, tau, method, builder, mu1, time_limit))
    opts = {**METHODS[method], **(options or {}), "time_limit": float(time_limit)}
    if engine == "classes":
        return _measure_classes(system, T, tau, float(mu1), opts, out)
    return _measure_tree(system, T, tau, method, float(mu1), opts, out)


def _worker(args: dict) -> dict:
    for module in ("highspy", "scipy.linalg", "scipy.sparse", "eqrec.bounds.data_classes", "eqrec.lp.solvers",
                   "eqrec.design.classes.engine", "eqrec.design.delay.design", "eqrec.design.prefix.tree_lp"):
        importlib.import_module(module)  # every module (and shared library) loaded before the memory limit is set
    system, _ = system_from_mapping(args["system"], "scale worker")
    mem_gb = float(args.get("mem_limit_gb", 0.0))
    if mem_gb > 0:
        resource.setrlimit(resource.RLIMIT_AS, (int(mem_gb * 2**30),) * 2)
    out: dict = {}
    try:
        measure_size(system, args["T"], args["tau"], args["method"], args["mu1"], args["time_limit"],
                     args["builder"], args.get("options"), out=out, engine=args.get("engine", "tree"))
    except Exception as exc:  # noqa: BLE001 - reported, never raised: the table records every size (MemoryError too)
        text = f"{type(exc).__name__}: {exc}"
        out.update(status="memory limit" if any(m in text for m in _MEMORY_MARKERS) else "error", detail=text)
    out["peak_mb"] = peak_memory_mb()
    return out


def run_fresh(module: str, payload: dict, timeout: float, *flags: str, env: dict | None = None,
              limited: bool = False) -> dict:
    """``python -m module '<payload as JSON>' *flags`` in a fresh process (its own peak memory).

    Parameters
    ----------
    module : str
        The worker module (prints its result as a JSON line).
    payload : dict
        The worker's arguments, sent as one JSON argument.
    timeout : float
        Wall-clock seconds before the process is killed.
    *flags : str
        Further command-line arguments.
    env : dict or None, optional
        The process's environment (default: this one's).
    limited : bool, optional
        The worker runs under an address-space limit: an abort that names an allocation is that limit.

    Returns
    -------
    dict
        The last output line that is a JSON object of a process that exited normally; otherwise ``{"status": s}``
        with ``s`` ``"wall-clock kill"`` (killed at ``timeout``), ``"memory limit"`` (an allocation failed) or
        ``"crashed (exit n | signal n): <the end of its error output>"``.
    """
    try:
        proc = subprocess.run([sys.executable, "-m", module, json.dumps(payload), *flags], capture_output=True,
                              text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"status": "wall-clock kill"}
    lines = [ln for ln in proc.stdout.strip().splitlines() if ln.startswith("{")]
    err, code = proc.stderr, proc.returncode
    if code == 0 and lines:
        return json.loads(lines[-1])
    if any(m in err for m in _MEMORY_MARKERS) or (limited and code == -signal.SIGABRT and "alloc" in err):
        return {"status": "memory limit"}
    how = f"signal {-code}" if code < 0 else f"exit {code}"
    return {"status": f"crashed ({how}): {' | '.join(err.strip().splitlines()[-3:])}"}


def run_size(system: AffineSystem, T: int, tau: int, method: str = "ipm", mu1: float = 0.5,
             time_limit: float = 600.0, mem_limit_gb: float = 16.0, builder: str = "core",
             options: dict | None = None, wall_margin: float = 300.0, engine: str = "tree") -> dict:
    """:func:`measure_size` in a fresh process with memory and time limits; never raises for a size that fails.

    Parameters
    ----------
    system : AffineSystem
        The plant (sent to the worker as :meth:`~eqrec.systems.affine.AffineSystem.to_dict`).
    T, tau : int
        Horizon and largest delay: the language ``{0..τ̄}^T``.
    method : str, optional
        A key of :data:`METHODS`.
    mu1 : float, optional
        The fixed recovery level ``μ1``.
    time_limit : float, optional
        HiGHS's time limit in seconds.
    mem_limit_gb : float, optional
        Address-space limit of the worker (``0``: none).
    builder : str, optional
        Tree engine: ``"core"``.
    options : dict or None, optional
        Extra HiGHS options.
    wall_margin : float, optional
        The worker is killed after ``1.5 time_limit + wall_margin`` seconds.
    engine : {"tree", "classes"}, optional
        ``"tree"`` or ``"classes"`` (:func:`measure_size`).

    Returns
    -------
    dict
        The fields of :data:`FIELDS`; ``status`` is ``"optimal"``, ``"time
        limit"``, ``"memory limit"``, ``"wall-clock kill"``, another HiGHS
        status, or ``"crashed (...)"``.
    """
    _check(method, builder, engine)
    base = {**_size_fields(engine, T, tau, method, builder, mu1, time_limit), "mem_limit_gb": float(mem_limit_gb)}
    args = {"system": system.to_dict(), **base, "builder": builder, "options": dict(options or {})}
    t0 = time.perf_counter()
    result = run_fresh("eqrec.studies.p3.size_run", args, 1.5 * float(time_limit) + wall_margin, "--engine", engine,
                       env={**os.environ, "OPENBLAS_NUM_THREADS": "1"}, limited=mem_limit_gb > 0)
    return {**base, **result, "wall_time": time.perf_counter() - t0}


def main(argv: list[str] | None = None) -> None:
    """Worker entry: ``python -m eqrec.studies.p3.size_run '{"system": {...}, "T": 5, ...}' [--engine classes]``.

    Prints one JSON line (:func:`measure_size`'s fields and ``peak_mb``).
    ``--engine`` overrides the JSON's ``engine`` (default ``tree``).

    Parameters
    ----------
    argv : list of str or None, optional
        Command-line arguments (default ``sys.argv[1:]``).
    """
    argv = sys.argv[1:] if argv is None else argv
    args = json.loads(argv[0])  # system (AffineSystem.to_dict), T, tau, method, mu1, time_limit, mem_limit_gb, ...
    if "--engine" in argv:
        args["engine"] = argv[argv.index("--engine") + 1]
    print(json.dumps(_worker(args)), flush=True)
    sys.stderr.flush()
    os._exit(0)  # no interpreter shutdown: threads left by a failed allocation must not keep the worker alive


if __name__ == "__main__":
    main()
