r"""μ1-free designs of full delay languages at scale: one fresh process per (size, configuration).

The delayed-data paper's problem with ``μ1`` free on the full language ``{0..τ̄}^T``
(:func:`eqrec.design.delay.design.design_delay_global` on :func:`eqrec.design.delay.design.delay_classes`), by the class
engine in one of :data:`CONFIGS`:

* ``monolithic``: every (class, row) LP as one block-diagonal LP (the engine before issue 27);
* ``blocks-1``, ``blocks-2``: one LP per class, in batches, on 1 or 2 worker processes
  (:mod:`eqrec.design.classes.blocks`; the same bytes either way).

:func:`run_free` runs :func:`measure_free` in a fresh Python process (``python -m eqrec.studies.p3.free_size_run
'<json>'``) so that the peak memory is that size's: ``peak_mb`` is the largest of the process's own peak and
its workers' (``VmHWM``).  The target ``p3_scale`` tabulates and plots them
(:func:`eqrec.studies.p3.free_table.step_scale_free`).
"""

from __future__ import annotations

import contextlib
import json
import sys
import time

from eqrec.studies.p3.size_run import peak_memory_mb, run_fresh
from eqrec.systems.files import system_from_mapping
from eqrec.systems.affine import AffineSystem

#: Configurations: name -> (one block LP, worker processes).
CONFIGS: dict[str, tuple[bool, int]] = {"monolithic": (True, 1), "blocks-1": (False, 1), "blocks-2": (False, 2)}


def _peak_mb_of_children() -> float:
    """Largest ``VmHWM`` (MB) of this process's descendants (the worker processes), 0 without psutil."""
    try:
        import psutil
    except ImportError:  # pragma: no cover - psutil comes with joblib's loky here
        return 0.0
    peak = 0.0
    for child in psutil.Process().children(recursive=True):
        with contextlib.suppress(OSError), open(f"/proc/{child.pid}/status") as f:  # a worker may have ended
            peak = max([peak, *(int(line.split()[1]) / 1024 for line in f if line.startswith("VmHWM:"))])
    return peak


def measure_free(system: AffineSystem, tau: int, T: int, config: str) -> dict:
    """The μ1-free design of ``{0..τ̄}^T`` in this process, by the configuration ``config``.

    Parameters
    ----------
    system : AffineSystem
    tau, T : int
        Largest delay ``τ̄`` and horizon ``T``.
    config : str
        A key of :data:`CONFIGS`.

    Returns
    -------
    dict
        ``tau``, ``T``, ``config``, ``classes``, ``mu1``, ``J``, ``mu2``, ``lower_bound``, ``wall_time`` (the
        design from the window rule on, worker start included), ``peak_mb`` and ``status`` (``"optimal"``).
    """
    from eqrec.design.classes import blocks as class_blocks
    from eqrec.design.delay.design import delay_classes, design_delay_global

    monolithic, n_jobs = CONFIGS[config]
    if monolithic:
        class_blocks.MONOLITHIC_MAX_WORK = float("inf")
    design_delay_global(system, delay_classes(max_delay=1, horizon=3), n_jobs=1)  # imports
    t0 = time.perf_counter()
    classes = delay_classes(max_delay=int(tau), horizon=int(T))
    res = design_delay_global(system, classes, n_jobs=n_jobs)
    wall = time.perf_counter() - t0
    peak = max(peak_memory_mb(), _peak_mb_of_children())
    return {"tau": int(tau), "T": int(T), "config": config, "classes": len(classes), "mu1": float(res.mu1),
            "J": float(res.J), "mu2": float(res.mu2), "lower_bound": float(res.lower_bound), "wall_time": wall,
            "peak_mb": peak, "status": "optimal"}


def run_free(system: AffineSystem, tau: int, T: int, config: str, timeout: float = 1800.0) -> dict:
    """:func:`measure_free` in a fresh process (its own peak memory); a failure is reported in ``status``.

    Parameters
    ----------
    system : AffineSystem
    tau, T : int
    config : str
        As :func:`measure_free`.
    timeout : float, optional
        Wall-clock seconds before the process is killed.

    Returns
    -------
    dict
        :func:`measure_free`'s fields, or ``tau``, ``T``, ``config`` and the ``status`` of a failure
        (:func:`eqrec.studies.p3.size_run.run_fresh`).
    """
    base = {"tau": int(tau), "T": int(T), "config": config}
    return {**base, **run_fresh("eqrec.studies.p3.free_size_run", {"system": system.to_dict(), **base}, timeout)}


def main(argv: list[str] | None = None) -> None:
    """Entry point of the fresh process: the JSON of :func:`measure_free` on stdout.

    Parameters
    ----------
    argv : list of str, optional
        ``[json]`` with ``system`` (:meth:`AffineSystem.to_dict`), ``tau``, ``T`` and ``config``.
    """
    args = json.loads((sys.argv[1:] if argv is None else argv)[0])
    system, _ = system_from_mapping(args["system"], "scale_free worker")
    print(json.dumps(measure_free(system, args["tau"], args["T"], args["config"])))


if __name__ == "__main__":
    main()
