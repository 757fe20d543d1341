"""The LMV companion study (P4, Zhao et al.): ``config/p4.yaml`` -> ``workflow/rules/p4.smk`` -> here -> ``results/p4/``.

:mod:`~eqrec.studies.p4.steps`
    The computations (the steps the rules run).
:mod:`~eqrec.studies.p4.values`, :mod:`~eqrec.studies.p4.figures`, :mod:`~eqrec.studies.p4.claims`
    Our value of every published number, the figures, and the claims' evidence.
"""
