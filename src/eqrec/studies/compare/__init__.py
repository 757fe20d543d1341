"""The compare study: every estimator family on the same packet traces (``config/compare.yaml``,
``workflow/rules/compare.smk``, ``results/compare/``).

:mod:`~eqrec.studies.compare.steps`
    One setting per job, the table and the summary.
"""
