"""The LMV companion study's mathematics: linear minimum-variance estimation for systems with multiplicative
noises and packet dropouts (zero- and hold-input compensation).  Imports only the core (the system description,
the arrival model, the packet forms of the estimator protocol).

:mod:`~eqrec.lmv.plant`
    The plant of eqs. (1)-(2), its loading from a configuration mapping, and the package's one system description
    (:class:`~eqrec.systems.noise.NoisySystem`) read and written in the paper's notation.
:mod:`~eqrec.lmv.model`
    The common description (a system with multiplicative noises), the two compensation mechanisms mapped
    onto it, mean-square stability.
:mod:`~eqrec.lmv.recursion`
    The recursion (Theorems 1-3, one Riccati-like step), the printed Theorem 1.
:mod:`~eqrec.lmv.estimator`
    The filter and one-step predictor in step form (the estimator protocol, zero- or hold-input compensation of a
    lost packet) and the batch run on measurements built on it.
:mod:`~eqrec.lmv.steady`
    The steady state of the recursion and the comparison of the mechanisms in it (the Figs. 5-6 sweeps).
:mod:`~eqrec.lmv.monte_carlo`
    Vectorised Monte Carlo of the plant and the statistical comparison with the theory.
"""
