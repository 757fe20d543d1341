"""Every estimator family on the same plant and the same packet traces (``eqrec compare``).

:mod:`~eqrec.compare.families`
    The settings (:class:`CompareSetup`), the traces, the families and the
    Monte Carlo (:func:`compare_families`), the table (:func:`write_table`).
:mod:`~eqrec.compare.figure`
    The figure (:func:`compare_figure`).
:mod:`~eqrec.compare.command`
    The ``eqrec compare`` subcommand.
"""

from eqrec.compare.families import (COLUMNS, FAMILIES, CompareResult, CompareSetup, compare_families, draw_trace,
                                    write_table)
from eqrec.compare.figure import compare_figure

__all__ = ["COLUMNS", "FAMILIES", "CompareResult", "CompareSetup", "compare_families", "compare_figure",
           "draw_trace", "write_table"]
