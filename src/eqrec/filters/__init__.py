"""Stochastic (Kalman-type) estimators for delayed and missing data, and their exact worst cases over a noise box.

Used for the comparison of the delayed-data paper (Fig. 1): every estimator
here is linear in the data with gains that do not depend on the data, so on a
fixed arrival pattern its error is affine in ``δ = (w, v, ξ0)``
(:mod:`eqrec.filters.affine`) and its worst case over the box is exact.
Each follows the estimator protocol (:mod:`eqrec.core.protocol`: ``reset``,
``step(y, u) -> (x̂(t+1|I_t), P(t+1|I_t))``) and runs in the one simulation
loop, :func:`eqrec.core.simulate.closed_loop`.
"""

from eqrec.filters.affine import (ErrorMaps, compare_with_bounds, error_maps, simulate_filter,
                                  truncated_normal_deltas)
from eqrec.filters.kalman import (DelayUnawareKalman, GaussianDesign, RandomDelayLMV, TimestampedKalman,
                                  make_filter, FILTERS)

__all__ = ["ErrorMaps", "compare_with_bounds", "error_maps", "simulate_filter", "truncated_normal_deltas", "TimestampedKalman",
           "DelayUnawareKalman", "RandomDelayLMV", "GaussianDesign", "make_filter", "FILTERS"]
