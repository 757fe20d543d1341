"""The prefix-based paper (P1, Rutledge, Yong, Ozay, ACC 2019): ``config/p1.yaml`` -> ``workflow/rules/p1.smk`` -> here -> ``results/p1/``.

:mod:`~eqrec.studies.p1.steps`
    The computations (the steps the rules run).
:mod:`~eqrec.studies.p1.figures`, :mod:`~eqrec.studies.p1.claims`
    The figures, and the claims' evidence (the values step is in ``steps``).
"""
