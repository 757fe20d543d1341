"""The delayed-data engine (P3): Theorem 1 / Proposition 1 of the delayed/missing-data paper.

:mod:`~eqrec.design.delay.design`
    The designs, μ1 fixed or free (class engine or prefix tree), and the delay classes.
:mod:`~eqrec.design.delay.horizon`
    The longest horizon that solves after a failed design (an unstable plant): a bisection bounded in time.
:mod:`~eqrec.design.delay.ipopt`
    The paper's own μ1-free route: IPOPT through CasADi on the bilinear problem (10).
:mod:`~eqrec.design.delay.languages`
    Delay words, their reduced event language, the full language's classes.
"""
