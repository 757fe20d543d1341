"""The state-augmented paper (P2, Hassaan, Shen, Yong, ACC 2019): ``config/p2.yaml`` -> ``workflow/rules/p2.smk`` -> here -> ``results/p2/``.

:mod:`~eqrec.studies.p2.steps`
    The computations (the steps the rules run).
:mod:`~eqrec.studies.p2.values`, :mod:`~eqrec.studies.p2.figures`, :mod:`~eqrec.studies.p2.claims`
    Our value of every published number, the figures, and the claims' evidence.
:mod:`~eqrec.studies.p2.sweeps`, :mod:`~eqrec.studies.p2.grids`, :mod:`~eqrec.studies.p2.readings`
    The pole and level sweeps (chunked), their grids, the design readings of the paper's words.
"""
