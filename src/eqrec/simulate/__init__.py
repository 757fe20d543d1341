"""Simulation: the one closed loop that runs any protocol estimator on the true system, long runs, and the exact
worst cases and sampled runs of linear filters.

:mod:`~eqrec.simulate.loop`
    The one simulation loop (:func:`~eqrec.simulate.loop.closed_loop`), runs within a horizon and Monte Carlo.
:mod:`~eqrec.simulate.long_runs`
    Long runs: one design's gains reused period after period, and the switching scheme.
:mod:`~eqrec.simulate.filter_runs`
    Exact worst cases of linear filters on a fixed arrival pattern (their error is affine in the noise), and
    sampled runs.
"""
