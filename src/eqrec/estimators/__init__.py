"""Estimators: one protocol (``reset``, then ``step(y, u) -> (x̂, bound or covariance)``) for every estimator.

:mod:`~eqrec.estimators.protocol`
    The estimator protocol and the on-time-only adapter.
:mod:`~eqrec.estimators.intake`
    The packet intake, the period clock and the protocol of the causal estimators (all-or-nothing steps).
:mod:`~eqrec.estimators.causal`
    The causal equalized-recovery estimators on time-stamped packets (class and node gains).
:mod:`~eqrec.estimators.switching`
    The switching strategy of the delayed-data paper (Section III-B3).
:mod:`~eqrec.estimators.augmented`
    The augmented estimator as it runs (P2 eqs. (2)-(3), P3 eqs. (4)-(5)), on the shared intake.
:mod:`~eqrec.estimators.error_maps`
    The error maps of the class form, carried by the exact run-time bound (``strict=False``).
:mod:`~eqrec.estimators.guaranteed`
    :class:`~eqrec.estimators.guaranteed.GuaranteedEstimator`: each step returns the estimate and its guarantee.
:mod:`~eqrec.estimators.kalman`
    Kalman-type filters for delayed and missing measurements (time-stamped, delay-unaware, random-delay LMV).
:mod:`~eqrec.estimators.exact`
    :func:`~eqrec.estimators.exact.exact_bound`: the exact worst-case bound of any linear estimator, per step.
:mod:`~eqrec.estimators.zonotope`
    :class:`~eqrec.estimators.zonotope.ZonotopeEstimator`: set-membership by zonotopes, guaranteed on any trace.
:mod:`~eqrec.estimators.exact_set`
    :class:`~eqrec.estimators.exact_set.ExactSetEstimator`: the interval hull of the set consistent with the data.
"""
