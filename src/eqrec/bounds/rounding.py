r"""The rounding allowance: one formula by which every reported bound covers the floating-point arithmetic.

A bound of the package is a guarantee on the error computed in floating point, ``|x - x̂| <= bound`` with both
``x`` (a simulated true state) and ``x̂`` (the estimate) rounded, with no tolerance on the guarantee side.  The
exact-arithmetic bound of an estimator is therefore inflated by an *a priori* allowance for the rounding of

* the estimator's own arithmetic (its products, sums and recursions), and
* a simulated true state of the same size (``x(s+1) = A x(s) + B u + f + E w`` and ``y = C x + V v`` computed in
  floating point, as :func:`eqrec.simulate.loop.closed_loop` does): the simulation's rounding acts on the error as
  a small extra process and measurement noise, which the same magnitudes bound.

**The standard bound.**  A computation made of chained products and sums of length at most ``k`` per step, ``L``
steps deep, whose every intermediate quantity is bounded in magnitude by the same computation carried out on
absolute values, :math:`\mu` (``|A| |x|`` in place of ``A x``), has an error at most :math:`L\,\gamma_k\,\mu`,
:math:`\gamma_k = k u / (1 - k u)` (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., SIAM 2002,
eqs. (3.4)-(3.5), Lemma 3.5 and §3.5 for products of matrices; ``u`` the unit roundoff): each rounding error is
at most :math:`\gamma_k` times the magnitude of its operands, and it is carried to the result by the same linear
maps, whose absolute values carry the magnitudes.  :func:`rounding_allowance` adds
:math:`4\,\mathrm{terms}\cdot u\,(\mu + b)` to a bound ``b`` and rounds the sum up, with ``terms`` the product
``L · k`` of the caller: the factor 4 covers :math:`\gamma_k \le 2ku` (for :math:`ku \le 1/2`), the rounding of the
magnitudes themselves (computed forwards, they are within a relative :math:`\gamma_k` of their exact values) and
that of the simulated true state of the same size.

**Where it is used.**  The zonotope filters' rounding generators and the exact window's radius
(:mod:`eqrec.estimators.zonotope`, :mod:`eqrec.bounds.window`, compiled:
:func:`eqrec.bounds.rounding_kernels.rounding_allowance_compiled`), the
causal estimators' reported bound (the design's level plus the allowance, carried across periods by the
estimator's own error map: :mod:`eqrec.estimators.intake`) and the exact run-time bound of any linear estimator
(:mod:`eqrec.estimators.exact`).  Measured sizes, relative to the bound, are given there (about ``1e-13`` to
``1e-11``: the allowance is a few thousand unit roundoffs of the magnitudes, and the magnitudes are those of the
state, not of its error).
"""

from __future__ import annotations

import numpy as np

#: Unit roundoff of float64.
UNIT_ROUNDOFF = np.finfo(float).eps / 2


def rounding_allowance(bound, terms, magnitude):
    r"""``bound`` inflated by the rounding allowance :math:`4\,\mathrm{terms}\,u\,(\mu + b)`, rounded up (module
    docstring).

    Works on floats and on NumPy arrays (elementwise);
    :func:`eqrec.bounds.rounding_kernels.rounding_allowance_compiled` is the same formula for compiled loops (the
    same operations in the same order, so the same bytes).

    Parameters
    ----------
    bound : float or ndarray
        ``b``: the exact-arithmetic bound (``0.0`` for the allowance alone).
    terms : float
        The depth times the length of the computation (``L · k``, module docstring).
    magnitude : float or ndarray
        :math:`\mu`: the magnitude of every quantity of the computation (absolute values propagated).

    Returns
    -------
    float or ndarray
        ``nextafter(b + 4 · terms · u · (μ + b), +inf)``: at least the exact-arithmetic bound plus the rounding.
    """
    return np.nextafter(bound + 4.0 * terms * UNIT_ROUNDOFF * (magnitude + bound), np.inf)


# The compiled forms (rounding_allowance_compiled, injection_bound, allowance_tail) are in
# eqrec.bounds.rounding_kernels, which imports numba: this module does not (about 0.35 s of CPU in a job that
# calls no kernel).  rounding_allowance is compiled from here, so this file is hashed by eqrec.io.compiled_once.
