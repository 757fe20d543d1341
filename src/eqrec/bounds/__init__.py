"""The bounded-error mathematics: stacked error maps over a horizon, gains from the Q-parametrisation, the data
classes of a language and their error maps, and the certificate computed from the gains alone.

:mod:`~eqrec.bounds.stacking`
    Stacked matrices over a finite horizon, shared by every design method.
:mod:`~eqrec.bounds.gains`
    Recovery of the gains from the Q-parametrisation; gain schedules ``(F, u0)`` per word.
:mod:`~eqrec.bounds.data_classes`
    The (time, available data) classes of a prefix tree and the class error map ``E_d − K Z_S``.
:mod:`~eqrec.bounds.certify`
    Worst cases recomputed from the gains alone (the independent certificate of every design).
:mod:`~eqrec.bounds.zonotope`
    The error set of a linear estimator carried online: error maps, the exact bound, outer order reduction.
:mod:`~eqrec.bounds.information`
    The information limit: per step, the smallest error bound any estimator can guarantee on an arrival trace.
:mod:`~eqrec.bounds.consistent`
    The exact consistent set: the interval hull of the states consistent with the measured data, per step.
:mod:`~eqrec.bounds.rounding`
    The rounding allowance: the one formula by which every reported bound covers the floating-point arithmetic.
:mod:`~eqrec.bounds.rounding_kernels`
    The same allowance compiled with Numba for the kernels (apart, so that the formula imports no Numba).
:mod:`~eqrec.bounds.window`
    The exact window: per state, the best linear estimate over the last steps given a zonotope at their start.
:mod:`~eqrec.bounds.window_lp`
    The window with its data: the interval hull of the consistent states, two LPs per state, bounded by duality.
"""
