"""Every estimator family on the same plant and the same packet traces (``eqrec compare``).

:mod:`~eqrec.compare.families`
    The settings (:class:`CompareSetup`), the traces, the families and the
    Monte Carlo (:func:`compare_families`), the table (:func:`write_table`), its violation count
    (:func:`count_violations`) and the class levels against the information limit (:func:`class_limit_identity`).
:mod:`~eqrec.compare.figure`
    The figure (:func:`compare_figure`).
:mod:`~eqrec.compare.command`
    The ``eqrec compare`` subcommand.
"""

from eqrec.compare.families import (COLUMNS, FAMILIES, CompareResult, CompareSetup, class_limit_identity,
                                    compare_families, count_violations, draw_trace, write_table)
from eqrec.compare.figure import compare_figure

__all__ = ["COLUMNS", "FAMILIES", "CompareResult", "CompareSetup", "class_limit_identity", "compare_families",
           "compare_figure",
           "count_violations", "draw_trace", "write_table"]
