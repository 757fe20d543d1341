r"""The scale table of the delayed-data design: one size of the full delay language per fresh process.

For the full language ``{0..τ̄}^T`` on a system (the scale table uses the
batch reactor of Section IV-A of the delayed-data paper; sum cost of
Theorem 1 / Proposition 1, ``μ1`` fixed, so an LP), :func:`measure_size` builds the node-per-prefix LP and solves it
with one HiGHS method, recording

* ``words`` ``(τ̄+1)^T``, ``sequences`` (the reduced event language
  ``L^{E'}``), ``nodes`` (event-prefix tree),
* the LP's ``rows``, ``cols``, ``nnz``,
* ``tree_time``, ``build_time``, ``solve_time``, ``iterations``, ``objective``,
* ``status`` (``"optimal"``, ``"time limit"``, ``"memory limit"``, ...),
* ``peak_mb``: the peak resident memory of the process (``ru_maxrss``).

:func:`run_size` runs it in a fresh Python process (``python -m
eqrec.design.scale_sweep``; the system travels as
:meth:`eqrec.core.systems.AffineSystem.to_dict`) so that ``peak_mb`` is that size's alone, with
an address-space limit (``RLIMIT_AS``; an allocation beyond it is reported
as ``"memory limit"``), HiGHS's ``time_limit`` (reported as ``"time
limit"``) and a wall-clock kill (``"wall-clock kill"``); a process that
dies otherwise is reported as ``"crashed (...)"`` with the end of its
error output.  ``benchmarks/bench_p3.py`` and the P3 scale steps call it.

HiGHS methods (:data:`METHODS`): ``simplex`` (dual simplex), ``ipm``
(interior point, crossover off), ``ipm-x`` (interior point + crossover),
``pdlp`` (first-order PDLP); ``-np``: presolve off; ``none``: build only.
Builders: ``core`` (:func:`eqrec.design.prefix.build_prefix_lp`) or
``recursive`` (:func:`eqrec.design.delay_scale.build_recursive_prefix_lp`).
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import time

from eqrec.core.systems import AffineSystem, system_from_mapping

#: HiGHS options of each method name.
METHODS: dict[str, dict] = {
    "simplex": {"solver": "simplex"},
    "ipm": {"solver": "ipm", "run_crossover": "off"},
    "ipm-x": {"solver": "ipm", "run_crossover": "on"},
    "pdlp": {"solver": "pdlp"},
    "pdlp-np": {"solver": "pdlp", "presolve": "off"},
    "ipm-np": {"solver": "ipm", "run_crossover": "off", "presolve": "off"},
    "none": {},
}
BUILDERS = ("core", "recursive")

#: Fields of a result, in table order.
FIELDS = ("T", "tau", "words", "sequences", "nodes", "builder", "rows", "cols", "nnz", "tree_time", "build_time",
          "method", "solve_time", "iterations", "objective", "peak_mb", "status", "mu1", "time_limit",
          "mem_limit_gb", "wall_time", "detail")

_MEMORY_MARKERS = ("MemoryError", "bad_alloc", "Cannot allocate memory", "out of memory", "failed to map segment")


def _check(method: str, builder: str) -> None:
    if method not in METHODS:
        raise ValueError(f"unknown HiGHS method {method!r}; choose one of {sorted(METHODS)}")
    if builder not in BUILDERS:
        raise ValueError(f"unknown builder {builder!r}; choose one of {list(BUILDERS)}")


def _status(raw: str) -> str:
    low = raw.lower()
    if "time limit" in low:
        return "time limit"
    if "memory" in low:
        return "memory limit"
    return raw


def peak_memory_mb() -> float:
    """Peak resident memory of this process in MB (``ru_maxrss``, kB on Linux)."""
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def measure_size(system: AffineSystem, T: int, tau: int, method: str = "ipm", mu1: float = 0.5,
                 time_limit: float = 600.0, builder: str = "core", options: dict | None = None,
                 out: dict | None = None) -> dict:
    """Build and solve the full-language LP of one size ``(T, τ̄)`` in this process.

    Parameters
    ----------
    system
        The plant (time-invariant, or time-varying over at least ``T`` steps).
    T, tau
        Horizon and largest delay: the language ``{0..τ̄}^T``.
    method
        A key of :data:`METHODS` (``"none"``: build only).
    mu1
        The fixed recovery level ``μ1``.
    time_limit
        HiGHS's time limit in seconds.
    builder
        ``"core"`` or ``"recursive"``.
    options
        Extra HiGHS options (override the method's).
    out
        A dict filled in as the measurement proceeds (so that the sizes and
        build time survive a later failure); a new one by default.

    Returns
    -------
    dict
        The fields of :data:`FIELDS` that apply (no ``peak_mb``: see :func:`run_size`).
    """
    _check(method, builder)
    from eqrec.core.patterns import PrefixTree
    from eqrec.core.solvers import solve_lp
    from eqrec.design.delay import delay_language
    from eqrec.design.delay_scale import build_recursive_prefix_lp
    from eqrec.design.prefix import build_prefix_lp

    build = build_recursive_prefix_lp if builder == "recursive" else build_prefix_lp
    out = {} if out is None else out
    out.update({"T": int(T), "tau": int(tau), "method": method, "builder": builder, "mu1": float(mu1),
                "time_limit": float(time_limit)})
    build(system, PrefixTree(delay_language(max_delay=1, horizon=2)), mu1, levels="sum")  # warm-up (imports)
    t0 = time.perf_counter()
    pats = delay_language(max_delay=int(tau), horizon=int(T))
    tree = PrefixTree(pats)
    t1 = time.perf_counter()
    out.update(words=(int(tau) + 1) ** int(T), sequences=len(pats), nodes=len(tree), tree_time=t1 - t0)
    model = build(system, tree, float(mu1), levels="sum")
    t2 = time.perf_counter()
    out.update(rows=int(model.lp.shape[0]), cols=int(model.lp.shape[1]), nnz=int(model.lp.A.nnz),
               build_time=t2 - t1)
    if method == "none":
        out["status"] = "built"
        return out
    opts = {**METHODS[method], **(options or {}), "time_limit": float(time_limit)}
    sol = solve_lp(model.lp, "highs", opts)
    out.update(status=_status(sol.status), solve_time=sol.solve_time, iterations=sol.iterations,
               objective=float(sol.objective))
    return out


def _import_all() -> None:
    """Load every module (and shared library) of a measurement before the memory limit is set."""
    import highspy  # noqa: F401
    import scipy.linalg  # noqa: F401
    import scipy.sparse  # noqa: F401

    from eqrec.core.solvers import solve_lp  # noqa: F401
    from eqrec.design.delay import delay_language  # noqa: F401
    from eqrec.design.delay_scale import build_recursive_prefix_lp  # noqa: F401
    from eqrec.design.prefix import build_prefix_lp  # noqa: F401


def _worker(args: dict) -> dict:
    _import_all()
    system, _ = system_from_mapping(args["system"], "scale worker")
    mem_gb = float(args.get("mem_limit_gb", 0.0))
    if mem_gb > 0:
        lim = int(mem_gb * 2**30)
        resource.setrlimit(resource.RLIMIT_AS, (lim, lim))
    out = {"T": args["T"], "tau": args["tau"], "method": args["method"], "builder": args["builder"]}
    try:
        measure_size(system, args["T"], args["tau"], args["method"], args["mu1"], args["time_limit"],
                     args["builder"], args.get("options"), out=out)
    except MemoryError as exc:
        out.update(status="memory limit", detail=f"MemoryError: {exc}")
    except Exception as exc:  # noqa: BLE001 - reported, never raised: the table records every size
        text = f"{type(exc).__name__}: {exc}"
        out.update(status="memory limit" if any(m in text for m in _MEMORY_MARKERS) else "error", detail=text)
    out["peak_mb"] = peak_memory_mb()
    return out


def run_size(system: AffineSystem, T: int, tau: int, method: str = "ipm", mu1: float = 0.5,
             time_limit: float = 600.0, mem_limit_gb: float = 16.0, builder: str = "core",
             options: dict | None = None, wall_margin: float = 300.0) -> dict:
    """:func:`measure_size` in a fresh process with memory and time limits; never raises for a size that fails.

    Parameters
    ----------
    mem_limit_gb
        Address-space limit of the worker (``0``: none).
    wall_margin
        The worker is killed after ``1.5 time_limit + wall_margin`` seconds.

    Returns
    -------
    dict
        The fields of :data:`FIELDS`; ``status`` is ``"optimal"``, ``"time
        limit"``, ``"memory limit"``, ``"wall-clock kill"``, another HiGHS
        status, or ``"crashed (...)"``.
    """
    _check(method, builder)
    args = {"system": system.to_dict(), "T": int(T), "tau": int(tau), "method": method, "mu1": float(mu1), "time_limit": float(time_limit),
            "mem_limit_gb": float(mem_limit_gb), "builder": builder, "options": dict(options or {})}
    base = {"T": int(T), "tau": int(tau), "method": method, "builder": builder, "mu1": float(mu1),
            "time_limit": float(time_limit), "mem_limit_gb": float(mem_limit_gb)}
    t0 = time.perf_counter()
    try:
        p = subprocess.run([sys.executable, "-m", "eqrec.design.scale_sweep", json.dumps(args)],
                           capture_output=True, text=True, timeout=1.5 * float(time_limit) + wall_margin,
                           env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    except subprocess.TimeoutExpired:
        return {**base, "status": "wall-clock kill", "wall_time": time.perf_counter() - t0}
    wall = time.perf_counter() - t0
    lines = [ln for ln in p.stdout.strip().splitlines() if ln.startswith("{")]
    if p.returncode == 0 and lines:
        return {**base, **json.loads(lines[-1]), "mem_limit_gb": float(mem_limit_gb), "wall_time": wall}
    tail = p.stderr.strip().splitlines()[-3:]
    if any(m in p.stderr for m in _MEMORY_MARKERS) or (mem_limit_gb > 0 and p.returncode == -signal.SIGABRT
                                                       and "alloc" in p.stderr):
        status = "memory limit"
    elif p.returncode < 0:
        status = f"crashed (signal {-p.returncode}): {' | '.join(tail)}"
    else:
        status = f"crashed (exit {p.returncode}): {' | '.join(tail)}"
    return {**base, "status": status, "wall_time": wall}


def main(argv: list[str] | None = None) -> None:
    """Worker entry: ``python -m eqrec.design.scale_sweep '{"system": {...}, "T": 5, "tau": 2, ...}'``; prints one JSON line."""
    argv = sys.argv[1:] if argv is None else argv
    print(json.dumps(_worker(json.loads(argv[0]))), flush=True)
    sys.stderr.flush()
    os._exit(0)  # no interpreter shutdown: threads left by a failed allocation must not keep the worker alive


if __name__ == "__main__":
    main()
