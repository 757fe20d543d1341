r"""The class engine at scale with ``μ1`` free (issue 27): time against the number of classes, per class on 1 and
2 workers and as one block LP, in the target ``p3_scale`` (outside the default run).

Step ``scale_free``: for each ``(τ̄, T)`` of :data:`FREE_SIZES`, the batch reactor's μ1-free design on the full
language ``{0..τ̄}^T`` (:func:`eqrec.design.delay.design.design_delay_global`) in a fresh process per configuration of
:data:`eqrec.studies.p3.free_size_run.CONFIGS` (:func:`eqrec.studies.p3.free_size_run.run_free`; the one block LP only up to
:data:`FREE_MONOLITHIC_MAX_CLASSES` classes: it takes minutes beyond).  Writes

* ``results/p3/scale_free.csv``: ``μ1``, ``J``, ``μ2`` and the lower bound of ``J`` per size and configuration
  (1 and 2 workers: the same bytes; the one block LP: the same optimum to the last digits);
* ``results/timings/p3/scale_free.csv`` and ``.md``: the wall time and peak memory of each (measurements);
(the figure, time against classes, is drawn from these by :func:`eqrec.studies.p3.figures.step_scale_free_figure`).

``cfg``: the ``p3`` section; ``scale.time_limit`` bounds each process (three times it, wall clock).
"""

from __future__ import annotations

import pandas as pd

from eqrec.studies.p3.free_size_run import CONFIGS, run_free
from eqrec.studies.p3.scale_table import md_table
from eqrec.studies.p3.size_run import class_count
from eqrec.systems.examples import batch_reactor
from eqrec.studies.pipeline.logs import get_logger
from eqrec.studies.pipeline.outputs import write_csv, write_text

log = get_logger("p3")

#: ``(τ̄, T)`` of the μ1-free scale runs, in increasing number of classes.
FREE_SIZES = [(4, 20), (4, 30), (4, 40), (5, 30), (4, 60), (4, 100), (5, 60), (5, 100), (6, 60)]
#: The one block LP only up to this many classes.
FREE_MONOLITHIC_MAX_CLASSES = 1000
#: Columns of ``scale_free.csv`` (then the measured ``wall_time`` and ``peak_mb``, split off to the timings).
FREE_FIELDS = ("tau", "T", "classes", "config", "status", "mu1", "J", "mu2", "lower_bound", "wall_time", "peak_mb")


def step_scale_free(cfg, inputs, outputs, wildcards) -> pd.DataFrame:
    """The μ1-free scale runs, their table (values; times and memory in the timings) and the figure."""
    timeout = 3 * float(cfg["scale"]["time_limit"])
    system = batch_reactor()
    rows = []
    for tau, T in FREE_SIZES:
        n_classes = class_count(T, tau)
        for config in CONFIGS:
            if config == "monolithic" and n_classes > FREE_MONOLITHIC_MAX_CLASSES:
                continue
            r = run_free(system, tau, T, config, timeout=timeout)
            r.setdefault("classes", n_classes)
            log.info("scale free (tau, T) = (%d, %d), %d classes, %s: %s, %.2f s, %.0f MB, mu1 = %s", tau, T, n_classes,
                     config, r["status"], r.get("wall_time", float("nan")), r.get("peak_mb", float("nan")),
                     r.get("mu1"))
            rows.append(r)
    frame = pd.DataFrame(rows).reindex(columns=list(FREE_FIELDS))
    write_csv(outputs.csv, frame, timings=outputs.timings_csv, keys=["tau", "T", "config"])
    write_text(outputs.timings_md, free_markdown(frame))
    return frame


def free_markdown(frame: pd.DataFrame) -> str:
    """The μ1-free scale runs as a Markdown table, times and memory included.

    Parameters
    ----------
    frame : pandas.DataFrame
        Columns :data:`FREE_FIELDS`.

    Returns
    -------
    str
    """
    head = ["τ̄", "T", "classes", "configuration", "time [s]", "peak [MB]", "μ1", "J", "max μ2", "status"]
    rows = ([r.tau, r.T, r.classes, r.config, f"{r.wall_time:.2f}", f"{r.peak_mb:.0f}", f"{r.mu1:.9g}", f"{r.J:.9g}",
             f"{r.mu2:.6f}", r.status] for r in frame.itertuples(index=False))
    return ("# P3 scale, mu1 free (class engine per class vs one block LP)\n\nBatch reactor, full language {0..τ̄}^T, "
            "mu1 free (design_delay_global), one fresh process per row; wall time from the window rule to the "
            "certified design, worker start included; peak memory of the process or its largest worker.\n\n"
            + md_table(head, rows))
