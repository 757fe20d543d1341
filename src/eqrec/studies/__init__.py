"""The studies: one folder per paper, orchestration, values, figures and claims only (the mathematics is in the
rooms below: :mod:`eqrec.systems` ... :mod:`eqrec.design`, :mod:`eqrec.lmv`).

``config/pN.yaml`` -> ``workflow/rules/pN.smk`` -> :mod:`eqrec.studies.pN <eqrec.studies.p1>` -> ``results/pN/``.

:mod:`~eqrec.studies.p1`, :mod:`~eqrec.studies.p2`, :mod:`~eqrec.studies.p3`, :mod:`~eqrec.studies.p4`
    One folder per paper: steps, values, figures, claims.
:mod:`~eqrec.studies.compare`
    Every estimator family on the same packet traces.
:mod:`~eqrec.studies.claims`
    The published numbers beside ours (``results/claims.csv``, ``results/REPRODUCTION.md``).
:mod:`~eqrec.studies.notebooks`
    The executed notebooks and their offline HTML.
:mod:`~eqrec.studies.pipeline`
    What every job shares: the harness, the configuration, outputs, chunks, logs.
:mod:`~eqrec.studies.plotting`, :mod:`~eqrec.studies.searches`
    The figures' common style; searches and scans over single designs (used by P1 and P2).
"""
