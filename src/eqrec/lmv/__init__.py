"""The LMV companion study's mathematics: linear minimum-variance estimation for systems with multiplicative
noises and packet dropouts (zero- and hold-input compensation).  Imports nothing from the other layers.

:mod:`~eqrec.lmv.plant`
    The plant of eqs. (1)-(2) and its loading from a configuration mapping.
:mod:`~eqrec.lmv.model`
    The common description (a system with multiplicative noises), the two compensation mechanisms mapped
    onto it, mean-square stability.
:mod:`~eqrec.lmv.recursion`
    The recursion (Theorems 1-3, one Riccati-like step), the printed Theorem 1, the estimator run on
    measurements.
:mod:`~eqrec.lmv.steady`
    The steady state of the recursion and the comparison of the mechanisms in it (the Figs. 5-6 sweeps).
:mod:`~eqrec.lmv.simulate`
    Vectorised Monte Carlo of the plant and the statistical comparison with the theory.
"""
