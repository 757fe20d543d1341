r"""The error set of a linear estimator carried online: a zonotope, its exact bound and its outer reduction.

Given the arrivals, every estimator of the package is linear in the initial
error, the process noise and the measurement noise: its error is
:math:`\xi(t) = G(t)\,\varepsilon` with :math:`\varepsilon` in the unit box
(each column of ``G`` one noise variable scaled by its radius), a centred
zonotope.  Its exact worst case per state is the row sum
:math:`\beta_i(t) = \sum_j |G_{ij}(t)|`, attained at the vertex
:math:`\varepsilon = \operatorname{sign}(G_{i\cdot})`.

**One representation of an estimator's error.**  After a step, an estimator
says how the error of its new estimate :math:`\hat x(t+1)` depends on the
error of an earlier estimate, its *anchor* ``s``, and on the noise that entered
since (:class:`ErrorMap`):

.. math:: \xi(t+1) = \Phi\,\xi(s) + N\,\varepsilon_{s..t},

where the variables :math:`\varepsilon_{s..t}` (the process noise ``w(s..t)``
and the measurement noise of the packets stamped ``s..t``, each in its box) are
independent of those of :math:`\xi(s)`.  A Kalman-type recursion anchors at
the previous step; the class form of the equalized-recovery estimator anchors
at the start of its period (its map is the class map :math:`E_d - K Z_S` of
:func:`eqrec.bounds.data_classes.class_error_map`).  :class:`ErrorSet` keeps the
zonotope of every anchor still in use and forms

.. math:: G(t+1) = [\,\Phi\, G(s)\;\; N\,],

the exact error set, carried across period boundaries with no box reset: the
zonotope at a period's end is the next period's initial set, so what the
earlier periods told is kept.

**Order reduction** (:func:`reduce_order`, only when ``order`` is given)
replaces the smallest generators by the box that contains them (Girard,
*Reachability of uncertain linear systems using zonotopes*, HSCC 2005,
:func:`reduce_girard`), or by the box in the principal axes of the set
(:func:`reduce_pca`): the reduced zonotope contains the original one, so the
bound stays a guarantee and is exact up to the reduction.  These are the one
implementation of the reductions, also used by the set-membership estimator
(:mod:`eqrec.estimators.zonotope`).

**Floating point.**  The row sums are rounded outward
(:func:`outer_row_sums`): the computed value is at least the exact sum of the
stored generators, so no tolerance is needed on the guarantee side.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from eqrec.errors import InputError

#: Unit roundoff of float64.
_U = np.finfo(float).eps / 2


@dataclass(frozen=True)
class ErrorMap:
    r"""How an estimate's error depends on an earlier error and on the noise since (module docstring).

    :math:`\xi(t+1) = \Phi\,\xi(s) + N\,\varepsilon` with ``s = anchor`` and
    :math:`\varepsilon` in the unit box, independent of :math:`\xi(s)`.

    Parameters
    ----------
    anchor : int
        Absolute time ``s`` of the estimate whose error the map starts from.
    state : ndarray, shape (n, n)
        :math:`\Phi`.
    noise : ndarray, shape (n, q)
        :math:`N`: one column per noise variable entered since ``s``, scaled by its radius.
    """

    anchor: int
    state: np.ndarray
    noise: np.ndarray


def outer_row_sums(G: np.ndarray) -> np.ndarray:
    r"""Per row, :math:`\sum_j |G_{ij}|` rounded outward: never below the exact sum of the stored entries.

    A floating-point sum of ``q`` non-negative terms is within a relative
    :math:`(q-1)u` of the exact one (Higham, *Accuracy and Stability of
    Numerical Algorithms*, eq. (4.4)); the result is multiplied by
    :math:`1 + (q+1)u` and rounded up once more.

    Parameters
    ----------
    G : ndarray, shape (n, q) or (K, n, q)
        Generators (or a stack of them).

    Returns
    -------
    ndarray, shape (n,) or (K, n)
        Upper bounds of the exact row sums of ``|G|``.
    """
    q = G.shape[-1]
    s = np.abs(G).sum(axis=-1)
    return np.nextafter(s * (1.0 + (q + 2) * _U), np.inf)


def hull_pad(G: np.ndarray, bounds: np.ndarray) -> np.ndarray:
    r"""The radii of the ``n`` axis-aligned generators that bring the interval hull of ``G ε`` up to ``bounds``:
    :math:`\mathrm{nextafter}(\max(b_i - \sum_j |G_{ij}|, 0), +\infty)` (an estimator's reported set, ``[G,
    diag(pad)]``, whose pad covers what its bound holds beyond ``G``: the rounding allowance).

    Parameters
    ----------
    G : ndarray, shape (n, q)
        Generators.
    bounds : ndarray, shape (n,)
        Per-state bounds.

    Returns
    -------
    ndarray, shape (n,)
        The pad, rounded up (zero or more).
    """
    return np.nextafter(np.maximum(bounds - np.abs(G).sum(axis=1), 0.0), np.inf)


#: Longest row :func:`outer_row_sums_of_parts` sums compiled (NumPy reduces a longer one in buffered chunks).
PARTS_LIMIT = 4096


@numba.njit(cache=True)
def _block(a, lo, n):  # pragma: no cover - compiled
    """NumPy's pairwise sum of ``a[lo:lo+n]`` for ``n <= 128``: plainly below 8 terms, else 8 accumulators."""
    if n < 8:
        res = 0.0
        for i in range(n):
            res += a[lo + i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    m = n - n % 8
    while i < m:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


@numba.njit(cache=True)
def _pairwise(a, lo, n):  # pragma: no cover - compiled
    """NumPy's pairwise summation of ``a[lo:lo+n]`` (``pairwise_sum`` of its ``loops_utils``): blocks of at most
    128 (:func:`_block`), longer runs halved at a multiple of 8 and the halves' sums added; the same additions in
    the same order.  The recursion is unrolled on an explicit stack (a cached compiled function must not call
    itself)."""
    los = np.empty(128, np.int64)
    ns = np.empty(128, np.int64)
    stage = np.zeros(128, np.int64)
    vals = np.empty(128)
    los[0], ns[0], stage[0] = lo, n, 0
    sp, vp = 1, 0
    while sp > 0:
        f = sp - 1
        if ns[f] <= 128:
            vals[vp] = _block(a, los[f], ns[f])
            vp += 1
            sp -= 1
            continue
        half = ns[f] // 2
        half -= half % 8
        if stage[f] == 0:  # the first half
            stage[f] = 1
            los[sp], ns[sp], stage[sp] = los[f], half, 0
            sp += 1
        elif stage[f] == 1:  # the second half
            stage[f] = 2
            los[sp], ns[sp], stage[sp] = los[f] + half, ns[f] - half, 0
            sp += 1
        else:  # both done: their sum, first + second
            vals[vp - 2] = vals[vp - 2] + vals[vp - 1]
            vp -= 1
            sp -= 1
    return vals[0]


@numba.njit(cache=True)
def row_sums_of_parts_compiled(P, N):  # pragma: no cover - compiled
    """:func:`outer_row_sums` of ``[P, N]`` without forming it: per row the absolute values end to end, summed as
    NumPy's ``sum`` does (from ``0.0``, pairwise), then rounded outward with the same factor (rows of at most
    :data:`PARTS_LIMIT` entries; called by compiled code too, an estimator's compiled step)."""
    n, qp = P.shape
    qn = N.shape[1]
    q = qp + qn
    row = np.empty(q)
    out = np.empty(n)
    factor = 1.0 + (q + 2) * _U
    for i in range(n):
        for j in range(qp):
            row[j] = abs(P[i, j])
        for j in range(qn):
            row[qp + j] = abs(N[i, j])
        out[i] = np.nextafter((0.0 + _pairwise(row, 0, q)) * factor, np.inf)
    return out


def outer_row_sums_of_parts(P: np.ndarray, N: np.ndarray) -> np.ndarray:
    """``outer_row_sums(np.concatenate([P, N], axis=1))``, the same numbers, without the concatenation.

    Compiled for rows of at most :data:`PARTS_LIMIT` (4096) entries (the same additions in the same order as
    NumPy's ``sum``, ``tests/test_class_step_cache.py``); longer rows are concatenated and summed by NumPy.

    Parameters
    ----------
    P, N : numpy.ndarray, shapes (n, q1) and (n, q2)
        The two blocks of generators.

    Returns
    -------
    numpy.ndarray, shape (n,)
        The outward-rounded row sums of ``|[P, N]|``.
    """
    if P.shape[1] + N.shape[1] > PARTS_LIMIT:
        return outer_row_sums(np.concatenate([P, N], axis=1))
    return row_sums_of_parts_compiled(P, N)


def reduce_girard(G: np.ndarray, limit: int) -> np.ndarray:
    """An outer reduction to at most ``limit`` generators: Girard's box of the smallest (module docstring).

    Parameters
    ----------
    G : numpy.ndarray, shape (n, q) or (K, n, q)
        Generators of a centred zonotope, or a stack of ``K`` of them with as many generators each (reduced one
        by one, in one pass; the stack keeps the ``n`` box columns even when some are zero, so that all ``K``
        keep one shape).
    limit : int
        Largest number of generators kept, ``>= n``.

    Returns
    -------
    numpy.ndarray, shape (n, q') or (K, n, q')
        ``G`` itself when ``q <= limit``, else the kept generators followed by the diagonal box
        (``q' <= limit``); the zonotope it spans contains that of ``G``.
    """
    if G.ndim == 3 or G.shape[1] <= limit:
        return _reduce(G, limit, principal=False) if G.ndim == 3 else G
    return _girard_one(np.ascontiguousarray(G, dtype=float), int(limit))


def principal_axes(G: np.ndarray) -> np.ndarray:
    r"""The orthonormal eigenvectors of :math:`GG^\top` (columns), per member of a stack ``(K, n, q)`` too.

    Parameters
    ----------
    G : numpy.ndarray, shape (n, q) or (K, n, q)
        Generators.

    Returns
    -------
    numpy.ndarray, shape (n, n) or (K, n, n)
        The axes :func:`reduce_pca` boxes in.
    """
    return np.linalg.eigh(G @ np.swapaxes(G, -1, -2))[1]


def reduce_pca(G: np.ndarray, limit: int, axes: "np.ndarray | None" = None) -> np.ndarray:
    r"""An outer reduction to at most ``limit`` generators: the smallest boxed in the principal axes of ``G``.

    As :func:`reduce_girard`, in the orthonormal basis ``U`` of the eigenvectors of :math:`GG^\top` (Kopetzki,
    Schürmann, Althoff, "Methods for order reduction of zonotopes", CDC 2017): the removed generators are
    replaced by ``U diag(sum_j |U^T g_j|)``, a parallelotope that contains their zonotope, plus an axis-aligned
    box that covers the floating point of the change of axes (the computed ``U`` is not exactly orthogonal, the
    computed coordinates ``U^T g`` are rounded, and so are the products ``U diag(box)``): ``2n`` new generators.

    **Why the result contains the zonotope of** ``G``, **in floating point.**  Write :math:`T = \mathrm{fl}(U^\top
    G)` for the computed coordinates and, for each boxed generator, :math:`e_j = g_j - U T_j` (exact) for what
    :math:`U T_j` misses.  Then :math:`\sum_j \varepsilon_j g_j = U \sum_j \varepsilon_j T_j + \sum_j
    \varepsilon_j e_j` exactly, for any ``U``.  The first term lies in :math:`U\operatorname{diag}(b)[-1,1]^n` with
    :math:`b_a \ge \sum_j |T_{aj}|` (the sum of the stored coordinates, rounded up), the second in the box of
    radius :math:`\sum_j |e_j|`.  With :math:`E = I - UU^\top`,
    :math:`e_j = E g_j + U(U^\top g_j - T_j)` and :math:`|U^\top g_j - T_j| \le \gamma_n |U|^\top |g_j|` for any
    order of the sums (Higham, *Accuracy and Stability of Numerical Algorithms*, 2nd ed., eq. (3.13)), so

    .. math:: \sum_j |e_j| \le (|E| + \gamma_n |U||U|^\top)\, s, \qquad s = \sum_j |g_j| .

    :math:`|E|` is bounded from the computed :math:`\hat D = \mathrm{fl}(I - \mathrm{fl}(UU^\top))`:
    :math:`|E| \le (1 + 2u)|\hat D| + \gamma_n |U||U|^\top`.  Finally the stored generators are
    :math:`P_{ea} = \mathrm{fl}(U_{ea} b_a)`, within :math:`2u|P_{ea}|` of :math:`U_{ea} b_a`, so
    :math:`U\operatorname{diag}(b)[-1,1]^n \subseteq P[-1,1]^n \oplus` the box of radius :math:`2u|P|\mathbf 1`.
    The ``n`` axis-aligned generators added have radius

    .. math:: d = \big(|\hat D| + 4(n+1)u\,|U||U|^\top\big)\, s + 2u\,|P|\mathbf 1 ,

    each product and sum of nonnegative terms inflated by :math:`1 + (4n + 8)u` and rounded up (:math:`2\gamma_n
    \le 4nu` for :math:`nu \le 1/2`).  So any ``axes`` give an outer reduction (a far from orthogonal ``U`` only a
    looser one); for the computed eigenvectors :math:`|\hat D| \approx nu` and ``d`` is a relative
    :math:`10^{-14}`-order of the boxed generators' hull.

    Parameters
    ----------
    G : numpy.ndarray, shape (n, q) or (K, n, q)
        Generators of a centred zonotope, or a stack of ``K`` of them with as many generators each.
    limit : int
        Largest number of generators kept, ``>= n``.
    axes : numpy.ndarray, shape (n, n) or (K, n, n), optional
        Orthonormal axes to box in instead of :func:`principal_axes` of ``G`` (say, those of a recent set: any
        orthonormal ``U`` gives an outer reduction, the principal ones the tightest).

    Returns
    -------
    numpy.ndarray, shape (n, q') or (K, n, q')
        ``G`` itself when ``q <= limit``, else the ``max(limit - 2n, 0)`` kept generators followed by the ``n`` new
        ones in the axes and the ``n`` axis-aligned ones of the rounding (``q' = max(limit, 2n)``).
    """
    if G.ndim == 3 or G.shape[1] <= limit:
        return _reduce(G, limit, principal=True, axes=axes) if G.ndim == 3 else G
    return _reduce(G[None], limit, principal=True, axes=None if axes is None else axes[None])[0]


def reduce_pca_pair(G: np.ndarray, limit: int, limit2: int,
                    axes: "np.ndarray | None" = None) -> tuple[np.ndarray, np.ndarray]:
    """:func:`reduce_pca` of a stack to two orders at once, from one change of axes (its products with ``G`` once).

    Parameters
    ----------
    G : numpy.ndarray, shape (K, n, q)
        A stack of ``K`` centred zonotopes.
    limit, limit2 : int
        The two largest numbers of generators kept (each ``>= n``).
    axes : numpy.ndarray, shape (K, n, n), optional
        As in :func:`reduce_pca`.

    Returns
    -------
    reduced : numpy.ndarray, shape (K, n, q')
        ``reduce_pca(G, limit, axes)`` (``G`` itself when ``q <= limit``), the same numbers.
    reduced2 : numpy.ndarray, shape (K, n, q'')
        ``reduce_pca(G, limit2, axes)`` (``G`` itself when ``q <= limit2``), the same numbers.
    """
    K, n, q = G.shape
    if q <= limit and q <= limit2:
        return G, G
    U = principal_axes(G) if axes is None else np.asarray(axes, dtype=float)
    a, b = _reduce_stack(np.ascontiguousarray(G, dtype=float), int(min(limit, q + 2 * n)), True,
                         np.ascontiguousarray(U), int(min(limit2, q + 2 * n)))
    return (G if q <= limit else a), (G if q <= limit2 else b)


def _reduce(G: np.ndarray, limit: int, principal: bool, axes: "np.ndarray | None" = None) -> np.ndarray:
    r""":func:`reduce_girard` (or :func:`reduce_pca`) on each of a stack ``(K, n, q)`` of zonotopes, in one pass
    (the one implementation: a single zonotope is a stack of one).

    Per member, the ``q - (limit - n)`` generators of smallest :math:`\|g\|_1 - \|g\|_\infty` in the axes (the
    state axes, or ``U``) are boxed; the box sums run over the boxed entries and are rounded outward.
    """
    K, n, q = G.shape
    if q <= limit:
        return G
    U = (principal_axes(G) if axes is None else np.asarray(axes, dtype=float)) if principal else np.zeros((K, n, n))
    return _reduce_stack(np.ascontiguousarray(G, dtype=float), int(limit), bool(principal), np.ascontiguousarray(U),
                         0)[0]


@numba.njit(cache=True)
def _sums_over(X, idx, absolute, out):  # pragma: no cover - compiled
    """Per row ``a``, ``out[a] = 0.0 + X[a, idx[0]] + X[a, idx[1]] + ...`` (of ``|X|`` when ``absolute``), the terms
    in the order of ``idx`` (the same numbers as that loop per row); four rows at a time, so that four independent
    sums advance together."""
    n = X.shape[0]
    a = 0
    while a + 4 <= n:
        r0 = r1 = r2 = r3 = 0.0
        for j in idx:
            if absolute:
                r0 += abs(X[a, j])
                r1 += abs(X[a + 1, j])
                r2 += abs(X[a + 2, j])
                r3 += abs(X[a + 3, j])
            else:
                r0 += X[a, j]
                r1 += X[a + 1, j]
                r2 += X[a + 2, j]
                r3 += X[a + 3, j]
        out[a], out[a + 1], out[a + 2], out[a + 3] = r0, r1, r2, r3
        a += 4
    while a < n:
        r0 = 0.0
        for j in idx:
            r0 += abs(X[a, j]) if absolute else X[a, j]
        out[a] = r0
        a += 1


@numba.njit(cache=True)
def _smallest(cost, nbox):  # pragma: no cover - compiled
    """The ``nbox`` smallest of ``cost`` as a mask, the lower index first on a tie: the first ``nbox`` of a stable
    sort (``np.argsort(cost, kind="mergesort")[:nbox]``), found by a selection (``np.partition``, linear time) of the
    ``nbox``-th smallest value instead of the sort."""
    q = cost.shape[0]
    boxed = np.zeros(q, dtype=np.bool_)
    if nbox <= 0:
        return boxed
    if nbox >= q:
        boxed[:] = True
        return boxed
    top = np.partition(cost, nbox - 1)[nbox - 1]
    if top != top:  # a NaN cost (sorted last by the sort): the sort itself
        order = np.argsort(cost, kind="mergesort")
        for j in range(nbox):
            boxed[order[j]] = True
        return boxed
    ties = nbox
    for j in range(q):
        if cost[j] < top:
            boxed[j] = True
            ties -= 1
    for j in range(q):  # the ties at the threshold, lowest index first
        if ties == 0:
            break
        if cost[j] == top:
            boxed[j] = True
            ties -= 1
    return boxed


@numba.njit(cache=True)
def _box_into(G, U, principal, absT, boxed, nbox, out):  # pragma: no cover - compiled
    """One reduction of :func:`_reduce_stack` into ``out`` (``(n, keep + n)``, or ``(n, keep + 2n)`` in the axes):
    the ``nbox`` generators of the mask ``boxed`` (of ``G``, ``(n, q)``, coordinates ``absT`` in the axes ``U``)
    boxed, the others kept in their order; in the axes, the box of the change of axes' rounding
    (:func:`reduce_pca`)."""
    n, q = G.shape
    nnew = 2 * n if principal else n
    keep = out.shape[1] - nnew
    slack = nbox + 2  # the box's sum of nbox nonnegative terms, rounded up (outer_row_sums)
    idx = np.empty(nbox, dtype=np.int64)  # the boxed generators in increasing order: the box sums run over them in it
    kept = np.empty(q - nbox, dtype=np.int64)  # the kept ones, in their order
    bi = ki = 0
    for j in range(q):
        if boxed[j]:
            idx[bi] = j
            bi += 1
        else:
            kept[ki] = j
            ki += 1
    for a in range(n):  # the kept generators, in their order (row by row)
        for col in range(q - nbox):
            out[a, col] = G[a, kept[col]]
    sums = np.empty(n)
    _sums_over(absT, idx, False, sums)
    for a in range(n):
        box = np.nextafter(sums[a] * (1.0 + slack * _U), np.inf)
        for e in range(n):
            out[e, keep + a] = (U[e, a] if principal else (1.0 if e == a else 0.0)) * box
    if principal:  # the box of what the change of axes misses in floating point (reduce_pca's docstring)
        grow = 1.0 + (4 * n + 8) * _U  # the rounding of the sums of nonnegative terms of the bound
        UU = np.dot(U, np.ascontiguousarray(U.T))
        s = np.empty(n)
        _sums_over(G, idx, True, s)
        for e in range(n):  # s: the boxed generators' absolute row sums, rounded up
            s[e] = np.nextafter(s[e] * (1.0 + slack * _U), np.inf)
        v = np.zeros(n)  # |U|^T s
        for e in range(n):
            for a in range(n):
                v[a] += abs(U[e, a]) * s[e]
        for e in range(n):
            z = 0.0  # (|D| s)_e, D = fl(I - fl(U U^T))
            w = 0.0  # (|U| |U|^T s)_e
            p = 0.0  # (|P| 1)_e
            for f in range(n):
                z += abs((1.0 if e == f else 0.0) - UU[e, f]) * s[f]
                w += abs(U[e, f]) * v[f]
                p += abs(out[e, keep + f])
            d = (z + 4.0 * (n + 1) * _U * w) * grow
            d = np.nextafter(np.nextafter(d, np.inf) + np.nextafter(2.0 * _U * p * grow, np.inf), np.inf)
            for f in range(n):
                out[f, keep + n + e] = d if f == e else 0.0


@numba.njit(cache=True)
def _reduce_stack(G, limit, principal, U, limit2):  # pragma: no cover - compiled
    """The loop of :func:`_reduce` (compiled): per member, the generators' absolute coordinates in the axes, the
    cost, the boxed ones (the smallest costs, the lower index first on a tie: :func:`_smallest`) and the box; in the
    axes ``U`` (``principal``), the box of the rounding of the change of axes besides (:func:`reduce_pca`).  With
    ``limit2 > 0``, the reduction to ``limit2`` too, from the same coordinates (else an empty second result)."""
    K, n, q = G.shape
    nnew = 2 * n if principal else n  # the box, and (in the axes U) the box of the change of axes' rounding
    keep = max(limit - nnew, 0)
    keep2 = max(limit2 - nnew, 0)
    out = np.empty((K, n, keep + nnew))
    out2 = np.empty((K, n, keep2 + nnew if limit2 > 0 else 0))
    absT = np.empty((n, q))
    cost = np.empty(q)
    csum = np.empty(q)
    cbig = np.empty(q)
    for k in range(K):
        Uk = np.ascontiguousarray(U[k])
        T = np.dot(np.ascontiguousarray(Uk.T), np.ascontiguousarray(G[k])) if principal else G[k]  # U^T G: in the axes
        # per generator j: sum_a |T[a, j]| from 0.0, a in increasing order, minus the largest (row by row over
        # the contiguous rows: the same sums in the same order per j), in the pass that stores |T|
        for j in range(q):
            csum[j] = 0.0
            cbig[j] = 0.0
        for a in range(n):
            for j in range(q):
                x = abs(T[a, j])
                absT[a, j] = x
                csum[j] += x
                cbig[j] = max(cbig[j], x)
        for j in range(q):
            cost[j] = csum[j] - cbig[j]
        Gk = G[k]
        _box_into(Gk, Uk, principal, absT, _smallest(cost, q - keep), q - keep, out[k])
        if limit2 > 0:
            _box_into(Gk, Uk, principal, absT, _smallest(cost, q - keep2), q - keep2, out2[k])
    return out, out2


@numba.njit(cache=True)
def _girard_one(G, limit):  # pragma: no cover - compiled
    """:func:`reduce_girard` of one zonotope ``(n, q)`` with ``q > limit``: the stack's reduction of a stack of one,
    in one compiled call (about a fifth of the cost of the Python around the stack's path at ``n = 4``: the designed
    error set's reduction at every period start, issue 40 §3).  Every box column is kept: each is rounded up
    (``nextafter`` towards +inf), so none is zero."""
    n, q = G.shape
    return _reduce_stack(G.reshape((1, n, q)), limit, False, np.zeros((1, n, n)), 0)[0][0]


def reduce_order(G: np.ndarray, order: float | None) -> np.ndarray:
    r"""An outer reduction of the zonotope ``G ε`` to at most ``order · n`` generators (:func:`reduce_girard`).

    Parameters
    ----------
    G : ndarray, shape (n, q)
        Generators.
    order : float or None
        The largest ratio ``columns / n`` kept (``>= 1``); ``None``: no reduction.

    Returns
    -------
    ndarray, shape (n, q')
        ``G`` itself when it is small enough, else the reduced generators (``q' <= order · n``).
    """
    if order is None:
        return G
    n = G.shape[0]
    return reduce_girard(G, max(n, int(np.floor(order * n))))


def check_order(order: "float | None") -> "float | None":
    """Check ``order`` (``None`` or a number ``>= 1``).

    Parameters
    ----------
    order : float or None
        The reduction order.

    Returns
    -------
    float or None
        ``order`` as a float.

    Raises
    ------
    InputError
        Not ``None`` and not a finite number ``>= 1`` (field ``order``).
    """
    if order is None:
        return None
    if isinstance(order, (bool, np.bool_)) or not isinstance(order, (int, float, np.integer, np.floating)) \
            or not np.isfinite(order) or order < 1:
        raise InputError(f"order is None or a number >= 1 (generators per state), got {order!r}", field="order")
    return float(order)


class ErrorSet:
    r"""The zonotope of an estimator's error, advanced by the estimator's error maps (module docstring).

    Parameters
    ----------
    generators : ndarray, shape (n, q)
        The initial error set at time ``t0`` (e.g. ``radius · I`` for a box).
    t0 : int
        Its absolute time.
    order : float or None, optional
        Outer reduction of every stored set to ``order · n`` generators (``None``: exact).

    Attributes
    ----------
    time : int
        Absolute time of the current set.
    generators : ndarray
        The current set's generators.
    """

    def __init__(self, generators: np.ndarray, t0: int, order: "float | None" = None):
        self.order = check_order(order)
        G = np.asarray(generators, float)
        self.time = int(t0)
        # sets by time, reduced on first use as an anchor (:meth:`at`): a class map anchors at its period's start,
        # so the sets of the steps in between are never reduced
        self._stored: dict[int, np.ndarray] = {self.time: reduce_order(G, self.order)}
        self._reduced: set[int] = {self.time}

    @property
    def generators(self) -> np.ndarray:
        """The current set's generators (reduced to the order)."""
        return self.at(self.time)

    @property
    def current(self) -> np.ndarray:
        """The current set's generators as the last step made them (not reduced unless used as an anchor)."""
        return self._formed(self.time)

    def _formed(self, time: int) -> np.ndarray:
        """The stored set of ``time``, its blocks ``[Φ G(s), N]`` concatenated on first use (:meth:`advance`)."""
        G = self._stored[time]
        if type(G) is tuple:
            G = self._stored[time] = np.concatenate(G, axis=1)
        return G

    @classmethod
    def box(cls, radius: "float | np.ndarray", n: int, t0: int, order: "float | None" = None) -> "ErrorSet":
        """The set ``|ξ_i| <= radius_i`` at ``t0``.

        Parameters
        ----------
        radius : float or ndarray, shape (n,)
            Per-state radius.
        n : int
            State dimension.
        t0 : int
            Absolute time.
        order : float or None, optional
            Reduction order.

        Returns
        -------
        ErrorSet
            The box as a zonotope of ``n`` generators.
        """
        return cls(np.diag(np.broadcast_to(np.asarray(radius, float), (n,)).copy()), t0, order)

    def at(self, time: int) -> np.ndarray:
        """The stored set of an earlier time (an anchor).

        Parameters
        ----------
        time : int
            Absolute time.

        Returns
        -------
        ndarray
            Its generators.

        Raises
        ------
        InputError
            No set is kept for that time.
        """
        time = int(time)
        try:
            G = self._formed(time)
        except KeyError:
            raise InputError(f"no error set is kept for time {time} (kept: {sorted(self._stored)})",
                             field="anchor") from None
        if time not in self._reduced:
            G = self._stored[time] = reduce_order(G, self.order)
            self._reduced.add(time)
        return G

    def propose(self, emap: ErrorMap) -> np.ndarray:
        """The exact set after a step with this map (nothing changes).

        Parameters
        ----------
        emap : ErrorMap
            The step's map.

        Returns
        -------
        ndarray
            ``[Φ G(s), N]``.
        """
        return np.concatenate([emap.state @ self.at(emap.anchor), emap.noise], axis=1)

    def advance(self, emap: ErrorMap, generators: "np.ndarray | None" = None) -> np.ndarray:
        """Move to the next time: the set ``[Φ G(s), N]`` (or ``generators``, from :meth:`propose`).

        Sets older than the map's anchor are dropped (an estimator's anchor never moves back).

        Parameters
        ----------
        emap : ErrorMap
            The step's map.
        generators : ndarray or None, optional
            The result of :meth:`propose` for this map, if already computed.

        Returns
        -------
        ndarray, shape (n,)
            The exact per-state bound of the new set (before reduction), rounded outward.
        """
        if generators is None:  # the blocks, summed without forming [Φ G(s), N] (formed when asked for)
            G = (emap.state @ self.at(emap.anchor), emap.noise)
            bounds = outer_row_sums_of_parts(*G)
        else:
            G = generators
            bounds = outer_row_sums(G)
        self.enter(emap.anchor, G)
        return bounds

    def enter(self, anchor: int, generators: "np.ndarray | tuple[np.ndarray, np.ndarray]") -> None:
        """Move to the next time with its set formed elsewhere (:meth:`advance` without the product and the sums).

        Parameters
        ----------
        anchor : int
            The step's map's anchor (sets older than it are dropped).
        generators : ndarray or tuple
            The new set, or its blocks ``(Φ G(s), N)`` (concatenated when first asked for).
        """
        self.time += 1
        self._stored = {s: g for s, g in self._stored.items() if s >= anchor}
        self._reduced = {s for s in self._reduced if s >= anchor}
        self._stored[self.time] = generators  # reduced when first used as an anchor (:meth:`at`)

    def replace(self, generators: np.ndarray) -> None:
        """Set the current set (a set-membership update made elsewhere, e.g. a fallback estimator's).

        Parameters
        ----------
        generators : ndarray, shape (n, q)
            The new generators of the current time.
        """
        self._stored = {self.time: reduce_order(np.asarray(generators, float), self.order)}
        self._reduced = {self.time}

    @property
    def state_bounds(self) -> np.ndarray:
        """Per-state bounds of the current set (rounded outward)."""
        return outer_row_sums(self.generators)
