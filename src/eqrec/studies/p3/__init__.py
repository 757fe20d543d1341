"""The delayed/missing-data paper (P3, Hassaan, Shen, Yong, journal): ``config/p3.yaml`` -> ``workflow/rules/p3.smk`` -> here -> ``results/p3/``.

:mod:`~eqrec.studies.p3.steps`
    The computations (the steps the rules run).
:mod:`~eqrec.studies.p3.values`, :mod:`~eqrec.studies.p3.figures`, :mod:`~eqrec.studies.p3.claims`
    Our value of every published number, the figures, and the claims' evidence.
:mod:`~eqrec.studies.p3.strategy`
    The implementation strategies (periodic reuse, switching) on long runs.
:mod:`~eqrec.studies.p3.scale_table`, :mod:`~eqrec.studies.p3.size_run`
    The scale table: one size of the full delay language per fresh process.
:mod:`~eqrec.studies.p3.free_table`, :mod:`~eqrec.studies.p3.free_size_run`
    The μ1-free designs of full delay languages at scale, one fresh process per (size, configuration).
"""
