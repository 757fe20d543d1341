"""The rounding allowance of :mod:`eqrec.bounds.rounding` compiled with Numba, for the kernels.

:func:`rounding_allowance_compiled` is :func:`eqrec.bounds.rounding.rounding_allowance` itself compiled (the same
IEEE operations in the same order, no ``fastmath``: the same bytes); :func:`injection_bound` and
:func:`allowance_tail` are the allowance of one step's update and its carried tail in one compiled call each.  They
live apart from :mod:`eqrec.bounds.rounding` so that importing the formula does not import Numba.
"""

from __future__ import annotations

import numba
import numpy as np

from eqrec.bounds.rounding import UNIT_ROUNDOFF, rounding_allowance

#: :func:`eqrec.bounds.rounding.rounding_allowance` compiled with Numba (no ``fastmath``: the same IEEE
#: operations), for the kernels.
rounding_allowance_compiled = numba.njit(cache=True)(rounding_allowance)


@numba.njit(cache=True)
def injection_bound(M, a, scale, b, c, add, terms):  # pragma: no cover - compiled
    r"""The rounding allowance of one step's update, :func:`rounding_allowance` of its magnitude
    :math:`\mu = M(s|a| + b) + |c| + \mathrm{add}` (``M``, ``b``, ``add`` nonnegative), in one compiled call.

    Parameters
    ----------
    M : numpy.ndarray, shape (n, k)
        The absolute values of the update's matrix.
    a : numpy.ndarray, shape (k,)
        The vector it multiplies (its absolute values are taken).
    scale : float
        ``s``.
    b : numpy.ndarray, shape (k,)
        A nonnegative magnitude added to ``s |a|`` (e.g. the true state's).
    c : numpy.ndarray, shape (n,)
        A vector whose absolute values are added.
    add : numpy.ndarray, shape (n,)
        A nonnegative magnitude added.
    terms : float
        As in :func:`rounding_allowance`.

    Returns
    -------
    numpy.ndarray, shape (n,)
        ``nextafter(4 · terms · u · μ, +inf)``.
    """
    n, k = M.shape
    out = np.empty(n)
    for i in range(n):
        s = abs(c[i]) + add[i]
        for j in range(k):
            s += M[i, j] * (scale * abs(a[j]) + b[j])
        out[i] = np.nextafter(4.0 * terms * UNIT_ROUNDOFF * s, np.inf)
    return out


@numba.njit(cache=True)
def allowance_tail(carried, extra, factor):  # pragma: no cover - compiled
    r"""``ρ = nextafter((carried + extra) · factor, +inf)`` and ``max(0, max_i ρ_i)`` in one pass (the operations of
    :meth:`eqrec.estimators.intake.StampedEstimator._allowance` after its product, and of ``ρ.max(initial=0)``).

    Parameters
    ----------
    carried : numpy.ndarray, shape (n,)
        ``|G| z``: the injections carried to the estimate.
    extra : numpy.ndarray, shape (n,)
        The step's own injection.
    factor : float
        ``1 + (2n + 8) u``.

    Returns
    -------
    rho : numpy.ndarray, shape (n,)
        The allowance per state.
    top : float
        Its largest entry (``0`` at least).
    """
    n = carried.shape[0]
    rho = np.empty(n)
    top = 0.0
    for i in range(n):
        rho[i] = np.nextafter((carried[i] + extra[i]) * factor, np.inf)
        if rho[i] > top or np.isnan(rho[i]):
            top = rho[i]
    return rho, top
