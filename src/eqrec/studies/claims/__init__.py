"""The claims: every published number beside ours (``config/claims.yaml`` -> ``results/claims.csv`` and
``results/REPRODUCTION.md``).

:mod:`~eqrec.studies.claims.published`
    The claims file, the only place published numbers live.
:mod:`~eqrec.studies.claims.table`
    The comparison table and the reproduction report.
:mod:`~eqrec.studies.claims.reasons`
    The reasons of the differences found.
"""
