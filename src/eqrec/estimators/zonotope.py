r"""A zonotopic set-membership estimator: a guarantee on any arrival trace, with no language.

The plant is :class:`~eqrec.systems.affine.AffineSystem` (eq. (3) of the prefix-based paper with the noise gains
of its Remark 1; per-channel bounds are already folded into ``E`` and ``V``):

.. math::
    x(s+1) = A(s)x(s) + B(s)u(s) + f + E(s)w(s), \quad y(s) = C(s)x(s) + V(s)v(s),
    \quad \|w\|_\infty \le \eta_w,\ \|v\|_\infty \le \eta_v .

The estimator has two parts (Alamo, Bravo, Camacho, "Guaranteed state estimation by zonotopes", Automatica 41,
2005; Combastel, "Zonotopes and Kalman observers: Gain optimality under distinct uncertainty paradigms and robust
convergence", Automatica 55, 2015):

* **zonotope filters** (one per gain, below) that carry a zonotope
  :math:`Z = \langle c, G\rangle = \{c + G\xi : \|\xi\|_\infty \le 1\}` containing the state, ``L`` steps
  behind the present: at time ``t`` they hold the set of :math:`x(s_0)`, :math:`s_0 = t + 1 - L`;
* **the exact window** over the last :math:`L = \max(\text{window}, D + 1)` steps
  (:func:`eqrec.bounds.window.window_estimate`): per state, the best linear estimate of :math:`x_i(t+1)` given
  the filter's zonotope at :math:`s_0` and every packet of times :math:`s_0..t` received so far, found by
  iteratively reweighted least squares: solves whose weights all states share (one Kalman recursion over the
  window for all; with ``warm_start=True``, once the window is full, one solve from the weights where the last
  step's window ended), then
  solves one state at a time for the states whose bound is near the largest.  Its bound :math:`\beta_i = \|X_i - \lambda_i H\|_1` is the exact worst
  case of that estimate (:mod:`eqrec.bounds.window`).

Per state, the estimate and bound of the filter whose window is the tightest are reported
(:attr:`ZonotopeEstimator.state_bounds`); ``step`` returns the largest bound.

One filter step (time ``s``, prior set :math:`\langle c, G\rangle \ni x(s)`)
--------------------------------------------------------------------------
*Update and prediction in one.*  With a delivered :math:`y(s)`, write :math:`r = y - Cc`; every state consistent
with the data satisfies :math:`r = CG\xi + \eta_v V \nu` (:math:`\|\nu\|_\infty \le 1`: the exact form of the
strip :math:`|y - Cx| \le \eta_v |V|\mathbf 1`, which keeps the noise shared by several outputs).  For **any**
gain :math:`M` (``n × p``) the zero :math:`M(r - CG\xi - \eta_v V\nu)` may be added to the prediction, so

.. math::
    x(s+1) \in \big\langle\, Ac + Bu + f + Mr,\ \ [\,AG - MCG,\ \ -\eta_v MV,\ \ \eta_w E\,] \big\rangle,

valid whatever :math:`M` (Alamo et al. 2005, Property 2; Combastel 2015, eq. (9); :math:`M = A\Lambda` is the
familiar filter gain :math:`\Lambda` followed by the prediction).  The gain only decides how tight the set stays:

* ``"fradius"``: Combastel's F-radius-optimal gain (2015, Theorem 3),
  :math:`\Lambda = GG^\top C^\top (CGG^\top C^\top + \eta_v^2 VV^\top)^{-1}` (a Kalman gain with covariance
  :math:`GG^\top`).  It minimises the filtered :math:`G'G'^\top` in the Löwner order, so every weighted sum of
  *squared* generator entries; the interval hull is a sum of *absolute* entries.
* ``"reweighted"`` (default): the same formula with :math:`GG^\top` and :math:`VV^\top` replaced by
  :math:`GWG^\top`, :math:`VW_vV^\top`, each generator weighted by the inverse of its length,
  :math:`W = \operatorname{diag}(1/\|(g_j, Cg_j)\|_2)` (and :math:`1/\|v_j\|_2` for the measurement noise): the
  first iteratively-reweighted-least-squares step from the current set towards minimising
  :math:`\sum_j \|g'_j\|_2`, which bounds the interval hull (:math:`\sum_i \beta_i = \sum_j \|g_j\|_1 \le
  \sqrt n \sum_j \|g_j\|_2`) and counts the many small generators the process noise adds as much as they widen
  the hull.  The same closed form, at the same cost.

With several gains (``gain=("fradius", "reweighted")``) each filter carries its own zonotope on the same data
(their matrices stacked), the window runs on each, and per state the tightest is reported.

The window
----------
The filters' sets lose information in two ways: a gain is one matrix for all states, and the order reduction
(below) replaces small generators by a box.  The window recovers most of it for the last ``L`` steps: it is the
radius of information of :math:`x_i(t+1)` given the zonotope at :math:`s_0` (an ``L1`` problem, solved
approximately; any weights give a valid bound, exact for the estimate it goes with), so it is never below the
information limit of the whole trace (:func:`eqrec.bounds.information.information_limit`), and equals it when
the zonotope at :math:`s_0` is exact and the weights optimal.  Its weights depend on the arrivals and the
filter's generators only, never on the measured values, so the estimate is *linear* in the initial error and
the noise given the arrivals, as every other linear estimator of the project, and its bound is the exact worst
case of its own error (no reduction inside the window).  Up to rounding: the filters' rounding allowances (below)
grow with the size of the data, and the window's weighted least squares amplify that into the weights, so the
estimate is linear to about :math:`10^{-12}` relative (:math:`1.6\cdot 10^{-12}` measured on the played-back
worst cases of ``tests/test_planted_bugs.py``, against :math:`3.5\cdot 10^{-13}` without the window); the bound
holds for the weights each run uses, exactly.  Measured (``benchmarks/bench_zonotope.py``, bound /
information limit per step, two carts, 30 % loss, delays 0..2, order 40): without the window (the filters'
own sets, replayed for late packets) median 1.18, with a window of 20 steps 1.12, with the default window of 30
steps 1.055 (:mod:`eqrec.bounds.window` for the cost; ``benchmarks/bench_zonotope.py`` for the figures).

*The window's prior.*  The window's cost grows with the number of generators of its prior zonotope at
:math:`s_0` (two products with them per solve, :mod:`eqrec.bounds.window`), ``order · n`` for the filters' sets:
``n^3 · order``.  The window therefore starts from the filters' set reduced once more, to at most
``max(window_generators, 2n)`` generators (default :data:`DEFAULT_WINDOW_GENERATORS` = 400: the filters' sets
themselves up to ``n = 10`` at the default order 40), by the filters' own reduction from the same change of axes
(:func:`eqrec.bounds.zonotope.reduce_pca_pair`).  The reduced set contains the filters', so the bound stays a
guarantee; the filters keep ``order · n`` generators, so what the reduction loses is lost once, not once a step.
Measured on the tank chains of ``benchmarks/bench_zonotope.py --part scale`` (bound relative to the window on the
filters' set, median over 150 steps): ``n = 20`` (800 generators reduced to 400) +0.4 %, ``n = 30`` (1,200 to 400)
+5.9 % (600 generators: +2.8 %), for a window about 30 % cheaper at ``n = 30``; on the two carts (n = 4, 160
generators) nothing changes, and there a prior of 40 generators would loosen the bound by 5 %
(``window_generators=None``: the filters' sets at any ``n``).

Late packets: the window, ``L >= D + 1``
----------------------------------------
A packet stamped ``τ`` arriving at ``t`` with :math:`t - D \le \tau \le t` (``D = max_delay``) is stored in the
window and used at its own time by the next window estimate (counted in :attr:`ZonotopeEstimator.replays` when
``τ < t``).  A time leaves the window, and the filters take it in (its measurement if it arrived), only when no
packet of it can still come: ``L >= D + 1``.  So the filters never replay, and every delivered measurement is
used at its own time.  A packet older than ``D`` steps (or stamped before ``reset``) is **dropped** and counted
in :attr:`ZonotopeEstimator.dropped_packets`: ignoring a measurement never makes the set smaller than the true
consistent set, since the set before any update already contains the state (each update only intersects with
data that holds), so the estimator stays guaranteed; it only loses what that packet would have told.

Order reduction (outer only)
----------------------------
After a filter step, when a set has more than ``order · n`` generators, the generators with the smallest
:math:`\|g\|_1 - \|g\|_\infty` (the increase of the interval hull's perimeter when a segment is replaced by its
box) are replaced by the ``n`` generators of their interval hull, :math:`\operatorname{diag}(\sum_j |g_j|)`
(Girard, "Reachability of uncertain linear systems using zonotopes", HSCC 2005; Combastel's 2003 reduction
boxes the smallest in 2-norm instead): ``reduction="girard"``.  ``reduction="pca"`` (default; the axes computed
again every :data:`PCA_AXES_EVERY` steps from the set being reduced, in between those last computed: any
orthonormal axes give an outer reduction, and the principal ones move slowly) does the same in the orthonormal
principal axes ``U`` of :math:`GG^\top` (Kopetzki, Schürmann, Althoff, CDC 2017), a parallelotope
:math:`U\operatorname{diag}(\sum_j |U^\top g_j|)`; the same containment argument holds in the rotated axes.
Each removed segment :math:`[-g, g]` lies in its box, and a Minkowski sum of supersets is a superset, so the
reduced zonotope contains the original one: every support function
:math:`h(d) = d^\top c + \sum_j |d^\top g_j|` can only grow, since
:math:`\sum_{j\in S} |d^\top g_j| \le \sum_i |d_i| \sum_{j\in S} |g_{ij}|`.  The box sums are rounded outward;
in the axes ``U``, ``n`` more axis-aligned generators cover what the change of axes misses in floating point (the
computed ``U`` is not exactly orthogonal, ``U^T g`` and ``U diag(box)`` are rounded), with a bound proved in
:func:`eqrec.bounds.zonotope.reduce_pca`, so the reduction is outer by itself, whatever the axes; ``order · n``
generators are kept in all.

Floating point
--------------
The bound is a guarantee on the error computed in floating point, with no tolerance on the guarantee side.  A
filter step appends a rounding allowance :math:`\kappa\,u\,(|A|(|c| + \beta) + |Bu + f| + |Mr| + \text{row sums
of the products})` (``u`` the unit roundoff, :math:`\kappa` four times the number of columns: the one formula of
:func:`eqrec.bounds.rounding.rounding_allowance`) as ``n``
axis-aligned generators, which covers the rounding of the centre's and the generators' products and of a
simulated true state of the same size; the window adds its own (:mod:`eqrec.bounds.window`).  Both are a
relative :math:`10^{-13}`-order of the bound.  The three loops (filter step, reduction, window) are compiled
with Numba, without ``fastmath``; their products with the generators go through BLAS (``numpy.dot``), so the bytes
are the same on one machine, and the allowances hold for any order of the sums.

References: Alamo, Bravo, Camacho (Automatica 2005); Combastel (Automatica 2015); Girard (HSCC 2005); Scott,
Raimondo, Marseglia, Braatz, "Constrained zonotopes: A new tool for set-based estimation and fault detection",
Automatica 69, 2016 (the exact intersection, an LP per state and step, which the window approaches over its
last ``L`` steps at a fixed cost); CORA's ``observe`` methods and ZETA (MATLAB) implement the filter family.
"""

from __future__ import annotations

from typing import Any

import numba
import numpy as np

from eqrec.arrivals.packets import is_stamp, as_packets, check_estimate, check_input
from eqrec.bounds.rounding_kernels import rounding_allowance_compiled
from eqrec.bounds.window import COLD, accumulate_product, add_abs_rows, sparse_columns, sparse_rows, spd_solve, \
    weighted_products, window_estimate, window_estimate_sparse
from eqrec.bounds.zonotope import check_order, hull_pad, outer_row_sums, principal_axes, reduce_girard, \
    reduce_pca, reduce_pca_pair
from eqrec.checks import radii
from eqrec.errors import InputError
from eqrec.estimators.protocol import StateSet
from eqrec.systems.affine import AffineSystem

#: The gains offered (module docstring); the estimator runs one filter per gain named.
GAINS = ("fradius", "reweighted")

#: The default: the reweighted form of Combastel's F-radius gain (module docstring).
DEFAULT_GAINS = ("reweighted",)

#: The default length of the exact window (steps; module docstring).
DEFAULT_WINDOW = 30

#: The default largest number of generators of the window's prior (module docstring, *The window*): the filters'
#: sets themselves up to n = 10 at the default order 40, reduced beyond.
DEFAULT_WINDOW_GENERATORS = 400

#: The default number of per-state reweighted solves of the window (module docstring) on a plant of at most
#: :data:`LARGE_PLANT_STATES` states.
DEFAULT_ITERATIONS = 2

#: The default number of per-state reweighted solves on a plant of more than :data:`LARGE_PLANT_STATES` states.  The
#: second reweighted solve of a state costs about the same share of a step at every size (a step 0.86-0.92 times the
#: cost with one, tank chains of ``benchmarks/bench_zonotope.py --part scale``, 2026-11-30) but buys less on large
#: plants: the largest bound +0.2 % at the median at n = 10, 20 and 30 with one (at most +1.0 % at a step), while
#: on the compare study's plants (n = 4) one solve loosens the zonotope's bound / limit by +0.5 to +1.1 % at the
#: median.  On a small plant a step takes at most about 0.3 ms either way; at n = 30 one solve brings it from 1.05 to
#: 0.95 ms (issue 45 §4's 1 ms).
DEFAULT_ITERATIONS_LARGE = 1

#: The size from which the default per-state solves drop to :data:`DEFAULT_ITERATIONS_LARGE`: more states than this
#: (the size beyond which the filters' sets, ``order · n`` = 40 n generators, are larger than the window's prior,
#: :data:`DEFAULT_WINDOW_GENERATORS`, and a step costs more than about 0.3 ms).
LARGE_PLANT_STATES = 10

#: Longest window (steps) the estimator takes, ``max(window, max_delay + 1)``: its matrices are stored once per
#: step of the window and its solve is linear in its length (about 4 µs a step of the window on the two-cart plant).
MAX_WINDOW = 10_000

#: Most reweighted solves of the window after the first (each costs about a first solve).
MAX_ITERATIONS = 100

#: Largest first prediction ``|A| (|x̂0| + radius)`` a run starts from: the window's products stay finite in floating
#: point far above any physical state (a larger one is refused by :meth:`ZonotopeEstimator.reset`).
MAX_SET_REACH = 1e300

#: Relative floor of the window's reweighting residuals (:mod:`eqrec.bounds.window`).
_IRLS_FLOOR = 1e-2

#: After its ``iterations`` reweighted solves, the window solves again while the last solve tightened a state's bound
#: by more than :data:`WINDOW_SOLVE_GAIN` (relative), at most this many more times (:mod:`eqrec.bounds.window`).
WINDOW_EXTRA_SOLVES = 2

#: The relative tightening that earns another solve of the window (see :data:`WINDOW_EXTRA_SOLVES`).
WINDOW_SOLVE_GAIN = 0.03


#: Reweighted solves of the window shared by all states (one Kalman recursion each) after the first, then at most
#: :data:`WINDOW_EXTRA_SOLVES` more while the largest bound tightens by more than :data:`WINDOW_SOLVE_GAIN`
#: (:mod:`eqrec.bounds.window`).
SHARED_SOLVES = 1

#: Shared solves of a window that starts from the weights carried from the last step (``warm_start=True``, once the
#: window is full; :mod:`eqrec.bounds.window`, *Warm start*): none after the first, then at most
#: :data:`WINDOW_EXTRA_SOLVES` more while the largest bound tightens by more than :data:`WINDOW_SOLVE_GAIN`.
SHARED_SOLVES_WARM = 0

#: After the shared solves, states are solved one by one, the largest bound first, while the unsolved state of
#: largest bound is within this relative margin of the largest (0: while it is the largest; ``iterations``
#: reweighted solves each, then more while they tighten; :mod:`eqrec.bounds.window`).
PER_STATE_MARGIN = 0.0

#: At most this many states are solved one by one per step and filter (the cost of a per-state solve is about that
#: of a shared one, which solves all states).
PER_STATE_STATES = 2


_REDUCTIONS = {"girard": reduce_girard, "pca": reduce_pca}

#: The flag of the time appended to the window (its packet not yet known).
_NOT_KNOWN = np.zeros(1, dtype=bool)

#: With ``reduction="pca"``, the principal axes are computed again every this many steps (module docstring).
PCA_AXES_EVERY = 4


@numba.njit(cache=True)
def filter_step(A, C, Ew, Vn, drive, y, has_y, c, G, alpha):  # pragma: no cover - compiled
    """One step of the zonotope filters (:mod:`eqrec.estimators.zonotope`): the sets of ``x(s+1)`` from those of
    ``x(s)``, one per gain, with the rounding allowance appended (not reduced).

    Parameters
    ----------
    A, C, Ew, Vn : ndarray, shapes (n, n), (p, n), (n, nw), (p, nv)
        The plant at time ``s`` (noise gains scaled by their bounds).
    drive : ndarray, shape (n,)
        ``B u + f``.
    y : ndarray, shape (p,)
        The measurement (read when ``has_y``).
    has_y : bool
        Whether ``y(s)`` is known.
    c : ndarray, shape (K, n)
        Centres of the ``K`` filters.
    G : ndarray, shape (K, n, q)
        Their generators.
    alpha : ndarray, shape (K,)
        Per filter, 0 for the F-radius gain (unit generator weights) or 1 for the reweighted one (weights
        ``1/‖(g, Cg)‖₂``).

    Returns
    -------
    c1 : ndarray, shape (K, n)
        The centres of the predicted sets.
    G1 : ndarray, shape (K, n, q + nv + nw + n) with a measurement, (K, n, q + nw + n) without
        Their generators ``[A G − M C G, −M V, E, diag(pad)]`` (``M = A Λ`` the gain, ``pad`` the rounding
        allowance; module docstring).
    """
    K, n, q = G.shape
    p, nw, nv = C.shape[0], Ew.shape[1], Vn.shape[1]
    extra = nv if has_y else 0
    width = q + extra + nw + n
    c1 = np.empty((K, n))
    G1 = np.zeros((K, n, width))
    CG = np.empty((p, q))
    wq = np.empty(q)
    num = np.empty((n, p))
    S = np.empty((p, p))
    CWC = np.empty((p, p))
    Lam = np.empty((n, p))
    ALam = np.empty((n, p))
    r = np.empty(p)
    mag = np.empty(n)
    rowabs = np.empty(n)
    for k in range(K):
        rowabs[:] = 0.0  # A G, A c + drive, and the magnitudes
        add_abs_rows(G[k], q, rowabs)
        accumulate_product(A, G[k], G1[k])
        for a in range(n):
            s = drive[a]
            sm = abs(drive[a])
            for e in range(n):
                f = A[a, e]
                s += f * c[k, e]
                sm += abs(f) * (abs(c[k, e]) + rowabs[e])
            c1[k, a] = s
            mag[a] = sm
        if has_y:
            for b in range(p):
                s = y[b]
                for e in range(n):
                    s -= C[b, e] * c[k, e]
                r[b] = s
            CG[:, :] = 0.0
            accumulate_product(C, G[k], CG)
            # generator weights (module docstring of the estimator): the squared lengths summed row by row (per
            # generator the same terms in the same order from 0.0, over contiguous rows)
            for j in range(q):
                wq[j] = 0.0
            for a in range(n):
                for j in range(q):
                    wq[j] += G[k, a, j] * G[k, a, j]
            for b in range(p):
                for j in range(q):
                    wq[j] += CG[b, j] * CG[b, j]
            for j in range(q):
                ln = np.sqrt(wq[j])
                wq[j] = 1.0 if alpha[k] == 0.0 or ln == 0.0 else 1.0 / ln
            weighted_products(G[k], wq, CG, num)  # G W (CG)^T
            weighted_products(CG, wq, CG, CWC)  # CG W CG^T
            for b in range(p):  # S = CG W CG^T + V Wv V^T
                for d in range(b + 1):
                    s = CWC[b, d]
                    for j in range(nv):
                        ln = 0.0
                        for e in range(p):
                            ln += Vn[e, j] * Vn[e, j]
                        ln = np.sqrt(ln)
                        wv = 1.0 if alpha[k] == 0.0 or ln == 0.0 else 1.0 / ln
                        s += Vn[b, j] * wv * Vn[d, j]
                    S[b, d] = s
            # Lam = num S^-1 (a zero gain where nothing is measured; any gain keeps the set valid)
            if p == 1:
                for a in range(n):
                    Lam[a, 0] = num[a, 0] / S[0, 0] if S[0, 0] > 0.0 else 0.0
            else:
                scale = 0.0
                for b in range(p):
                    scale = max(scale, S[b, b])
                for b in range(p):
                    S[b, b] += 1e-14 * scale + 1e-300
                for a in range(n):
                    M = S.copy()
                    out = np.empty(p)
                    spd_solve(M, num[a].copy(), out)
                    for b in range(p):
                        Lam[a, b] = out[b]
            for a in range(n):
                for b in range(p):
                    s = 0.0
                    for e in range(n):
                        s += A[a, e] * Lam[e, b]
                    ALam[a, b] = s
            sCG = np.zeros(p)
            for b in range(p):
                for j in range(q):
                    sCG[b] += abs(CG[b, j])
            for a in range(n):
                s = c1[k, a]
                for b in range(p):
                    f = ALam[a, b]
                    s += f * r[b]
                    mag[a] += abs(f) * (abs(r[b]) + abs(y[b]) + sCG[b])
                    if f != 0.0:
                        for j in range(q):
                            G1[k, a, j] -= f * CG[b, j]
                    for j in range(nv):
                        G1[k, a, q + j] -= f * Vn[b, j]
                c1[k, a] = s
                for e in range(n):  # |A| |Lam| sCG
                    s2 = 0.0
                    for b in range(p):
                        s2 += abs(Lam[e, b]) * sCG[b]
                    mag[a] += abs(A[a, e]) * s2
        # process noise and the rounding allowance
        for a in range(n):
            rowabs[a] = abs(c1[k, a])
        add_abs_rows(G1[k], q + extra, rowabs)
        for a in range(n):
            s = rowabs[a]
            for j in range(nw):
                G1[k, a, q + extra + j] = Ew[a, j]
                s += abs(Ew[a, j])
            G1[k, a, q + extra + nw + a] = rounding_allowance_compiled(0.0, width + 4, mag[a] + s)
    return c1, G1


@numba.njit(cache=True)
def _finite(values):  # pragma: no cover - compiled
    """Whether every entry of a flat array is finite."""
    for v in values:
        if not np.isfinite(v):
            return False
    return True


@numba.njit(cache=True)
def _all_finite(xhat, beta, c, G, P):  # pragma: no cover - compiled
    """Whether every entry of the step's results and sets is finite (one compiled call: the check of every step)."""
    return (_finite(xhat.ravel()) and _finite(beta.ravel()) and _finite(c.ravel()) and _finite(G.ravel())
            and _finite(P.ravel()))


def _gain_names(gain: Any) -> tuple[str, ...]:
    """The gains asked for, as a tuple of known names (raises naming the field ``gain``)."""
    names = (gain,) if isinstance(gain, str) else tuple(gain) if isinstance(gain, (tuple, list)) else None
    if not names or any(not isinstance(g, str) or g not in GAINS for g in names) or len(set(names)) != len(names):
        raise InputError(f"gain is one of {list(GAINS)} or a tuple of distinct ones, got {gain!r}", field="gain")
    return names


class ZonotopeEstimator:
    r"""Set-membership estimator carrying a zonotope; guaranteed on any arrival trace (module docstring).

    Follows the estimator protocol (:mod:`eqrec.estimators.protocol`): :meth:`reset`, then one :meth:`step` per
    time with what arrived and the input, returning the centre :math:`\hat x(t+1)` and the bound
    :math:`\max_i \beta_i(t+1) \ge \|x(t+1) - \hat x(t+1)\|_\infty` for every noise in the box.

    Parameters
    ----------
    system : AffineSystem
        The plant (also the model; time-varying matrices are read at the absolute time).
    x0_radius : float or array_like, shape (n,)
        Radius of the initial box around ``xhat0`` (one number, or one per state; finite, ``>= 0``).
    max_delay : int, optional
        ``D >= 0``: packets up to ``D`` steps late are used at their own time (by the window); older ones are
        dropped and counted (default 0).
    order : float or None, optional
        At most ``order · n`` generators are kept per filter after each filter step (``>= 1``; default 40);
        ``None``: no reduction (exact sets, growing without limit).
    gain : str or tuple of str, optional
        One filter per gain named: ``"fradius"`` (Combastel's F-radius gain, the Kalman-shaped reference) and
        ``"reweighted"`` (the same with generators weighted by their inverse length; default); with both, per
        state the tightest is reported (module docstring).
    reduction : {"pca", "girard"}, optional
        The outer order reduction: the box in the principal axes of the generators (default,
        :func:`reduce_pca`) or Girard's axis-aligned box (:func:`reduce_girard`).
    window : int, optional
        Length of the exact window in steps (``>= 1``; default 30); the window used is
        ``max(window, max_delay + 1)`` steps (module docstring).
    iterations : int or None, optional
        Reweighted solves of the window per state after its first (``>= 0``; default ``None``:
        :data:`DEFAULT_ITERATIONS` = 2 up to :data:`LARGE_PLANT_STATES` = 10 states, :data:`DEFAULT_ITERATIONS_LARGE`
        = 1 beyond, where the second costs about 0.1 ms a step at n = 30 for about 0.2 % on the bound; the value
        used is the attribute ``iterations``), after the shared solves,
        for the state of the largest bound and, while the largest is not yet solved so, the next (at most
        :data:`PER_STATE_STATES` states; :mod:`eqrec.bounds.window`); then, per state, at most
        :data:`WINDOW_EXTRA_SOLVES` more while each tightens the bound by more than :data:`WINDOW_SOLVE_GAIN`.
    window_generators : int or None, optional
        The most generators of the window's prior zonotope (``>= 1``; at least ``2n`` are kept; default
        :data:`DEFAULT_WINDOW_GENERATORS` = 400); ``None``: the filters' sets themselves (module docstring, *The
        window's prior*).
    warm_start : bool, optional
        ``True``: once the window is full, start its shared solve from the weights of the last step's window and
        solve it once (:data:`SHARED_SOLVES_WARM`; :mod:`eqrec.bounds.window`, *Warm start*): about 0.8 times the
        cost of a step, the largest bound the same at the median, but the states whose bound is far below the
        largest lose the cold start's first solve, and their hull becomes noisier (on the two carts up to 2.5
        times the cold start's at some steps).  Default ``False``: every window starts from the inverse column
        lengths and solves :data:`SHARED_SOLVES` + 1 times.  The fast setting of the scale benchmark
        (:mod:`eqrec.bounds.window`, *Cost*).

    Attributes
    ----------
    kind : str
        ``"guaranteed"``.
    name : str
        ``"set-membership, zonotope"``.
    dropped_packets : int
        Packets dropped since :meth:`reset` because they were more than ``max_delay`` steps late.
    replays : int
        Late packets used at their own time (by the window) since :meth:`reset`.

    Raises
    ------
    InputError
        A ``system`` that is not an :class:`AffineSystem`, a negative, non-finite or wrongly sized
        ``x0_radius``, ``max_delay`` not an integer ``0..MAX_WINDOW - 1``, ``order`` not ``None`` nor a number
        ``>= 1``, an unknown ``gain`` or ``reduction``, ``window`` not an integer ``1..``:data:`MAX_WINDOW`,
        ``iterations`` not an integer ``0..``:data:`MAX_ITERATIONS`, ``window_generators`` not ``None`` nor an integer
        ``>= 1``, ``warm_start`` not a bool (the field is named).

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> carts = eqrec.two_mass()
    >>> est = eqrec.ZonotopeEstimator(carts, x0_radius=0.5, max_delay=2, order=20).reset(np.zeros(4))
    >>> xhat, bound = est.step(np.array([0.1]))       # y(0) on time
    >>> xhat, bound = est.step(None)                  # y(1) not (yet) arrived
    >>> xhat, bound = est.step([eqrec.Packet(1, np.array([0.12]))])  # y(1) one step late: used at time 1
    >>> est.time, est.state_bounds.shape, bool(bound == est.state_bounds.max()), est.replays
    (3, (4,), True, 1)
    """

    kind = "guaranteed"
    name = "set-membership, zonotope"

    def __init__(self, system: AffineSystem, x0_radius: Any = 1.0, max_delay: int = 0, order: "float | None" = 40,
                 gain: "str | tuple[str, ...]" = DEFAULT_GAINS, reduction: str = "pca", window: int = DEFAULT_WINDOW,
                 iterations: "int | None" = None, window_generators: "int | None" = DEFAULT_WINDOW_GENERATORS,
                 warm_start: bool = False):
        if not isinstance(system, AffineSystem):
            raise InputError(f"expected an AffineSystem, got {type(system).__name__}", field="system")
        n = system.n
        r0 = radii(x0_radius, n)
        if not is_stamp(max_delay) or max_delay < 0:
            raise InputError(f"the largest delay is an integer >= 0, got {max_delay!r}", field="max_delay")
        if max_delay >= MAX_WINDOW:  # the window holds max_delay + 1 steps (module docstring)
            raise InputError(f"the largest delay is at most {MAX_WINDOW - 1} steps (the window holds max_delay + 1 "
                             f"steps, at most MAX_WINDOW = {MAX_WINDOW}), got {max_delay!r}; a packet later than "
                             "max_delay is dropped and counted, which stays guaranteed", field="max_delay")
        order = check_order(order)
        if window_generators is not None and (not is_stamp(window_generators) or window_generators < 1):
            raise InputError(f"window_generators is None or an integer >= 1 (the most generators of the window's "
                             f"prior), got {window_generators!r}", field="window_generators")
        self.window_generators = None if window_generators is None else int(window_generators)
        gains = _gain_names(gain)
        if reduction not in _REDUCTIONS:
            raise InputError(f"unknown reduction {reduction!r}; choose one of {list(_REDUCTIONS)}", field="reduction")
        if not is_stamp(window) or not 1 <= window <= MAX_WINDOW:
            raise InputError(f"the window is an integer 1..{MAX_WINDOW} (steps; its matrices are stored per step and "
                             f"its solve is linear in its length), got {window!r}", field="window")
        if iterations is None:  # the size's default (DEFAULT_ITERATIONS_LARGE)
            iterations = DEFAULT_ITERATIONS if n <= LARGE_PLANT_STATES else DEFAULT_ITERATIONS_LARGE
        if not is_stamp(iterations) or not 0 <= iterations <= MAX_ITERATIONS:
            raise InputError(f"iterations is None (the size's default) or an integer 0..{MAX_ITERATIONS} (each a "
                             f"solve of the window per step), got {iterations!r}", field="iterations")
        self.window, self.iterations = int(window), int(iterations)
        if not isinstance(warm_start, (bool, np.bool_)):
            raise InputError(f"warm_start is True or False, got {warm_start!r}", field="warm_start")
        self.warm_start = bool(warm_start)
        # the window's length: every packet up to max_delay late reaches it before its time leaves (module docstring)
        self._W = max(self.window, int(max_delay) + 1)
        self.reduction = reduction
        self.system, self.x0_radius, self.max_delay = system, r0, int(max_delay)
        self.order = None if order is None else float(order)
        self.gain = gains
        # per filter: the exponent of the gain's generator weights (0: F-radius, 1: reweighted)
        self._alpha = np.array([1.0 if g == "reweighted" else 0.0 for g in gains])
        self._models: dict[int, tuple] = {}
        self._horizon = system.horizon_limit  # the time-varying data's length (None: time-invariant), read once
        self._tiles: "tuple[np.ndarray, ...] | None" = None  # a time-invariant plant's matrices, W times over
        self._sparse: "tuple[np.ndarray, ...] | None" = None  # the nonzeros of the tiles' A and E (:meth:`_window`)
        self._tiles_at: dict = {}  # views of the tiles' first L times, by L (:meth:`_window_model`)
        self._sparse_at: dict = {}  # views of the nonzeros' first L times, by L (:meth:`_window`)
        self._no_y = np.zeros(system.p)
        self._one_pick = np.zeros(n, dtype=np.int64)  # with one filter, every state is taken from it
        self._limit = None if order is None else max(n, int(np.floor(self.order * n)))
        # the window's prior: at most max(window_generators, 2n) generators (not more than the filters' sets)
        self._wlimit = None if self.window_generators is None else max(2 * n, self.window_generators)
        if self._limit is not None and self._wlimit is not None and self._wlimit >= self._limit:
            self._wlimit = None  # the filters' sets themselves
        self._time: int | None = None
        self.dropped_packets = 0
        self.replays = 0
        self._period: tuple[int, int] | None = None  # (T, start): a T-periodic model read at the period time

    def periodic_model(self, period: int, start: int = 0) -> "ZonotopeEstimator":
        """Read a time-varying model at the period time ``(t − start) mod period`` (as the designs do).

        Parameters
        ----------
        period : int
            ``T >= 1``: the model describes one period of a ``T``-periodic plant.
        start : int, optional
            An absolute time at which a period starts.

        Returns
        -------
        ZonotopeEstimator
            ``self``.

        Raises
        ------
        InputError
            ``period`` not an integer ``>= 1`` (field ``period``).
        """
        if not is_stamp(period) or period < 1:
            raise InputError(f"the period is an integer >= 1, got {period!r}", field="period")
        self._period = (int(period), int(start))
        return self

    def _model_time(self, t: int) -> int:
        """The time at which the model's matrices are read (the absolute time, or the period time)."""
        return t if self._period is None else (t - self._period[1]) % self._period[0]

    # -- protocol ---------------------------------------------------------------------------------------------
    def reset(self, xhat0: Any, t0: int = 0) -> "ZonotopeEstimator":
        """Start a run: the set is the box of radius ``x0_radius`` around ``xhat0`` at time ``t0``.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            Initial estimate (finite).
        t0 : int, optional
            Absolute time of the first step (default 0).

        Returns
        -------
        ZonotopeEstimator
            ``self``.

        Raises
        ------
        InputError
            A non-finite or wrongly sized ``xhat0``, a ``t0`` that is not an integer or outside a time-varying
            plant's data, an estimate whose first prediction overflows (nothing changes).
        """
        return self.start_from(xhat0, np.diag(self.x0_radius), t0)

    def start_from(self, xhat0: Any, generators: Any, t0: int = 0) -> "ZonotopeEstimator":
        """Start a run from a given set: centre ``xhat0``, error zonotope ``generators ε``, ``|ε| <= 1``.

        :meth:`reset` starts here from the box of radius ``x0_radius``; another estimator's exact error set
        can be handed over the same way.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            Centre (the estimate).
        generators : array_like, shape (n, q)
            Generators of the error set (finite).
        t0 : int, optional
            Absolute time of the first step.

        Returns
        -------
        ZonotopeEstimator
            ``self``.

        Raises
        ------
        InputError
            Non-finite or wrongly shaped ``xhat0`` or ``generators``, a non-integer ``t0``, a ``t0`` outside a
            time-varying plant's data (read at the period time after :meth:`periodic_model`), a set whose first
            prediction overflows (nothing changes).
        """
        n = self.system.n
        c = check_estimate(xhat0, n)
        G = np.asarray(generators, dtype=float)
        if G.ndim != 2 or G.shape[0] != n or not np.all(np.isfinite(G)):
            raise InputError(f"generators need shape ({n}, q) and finite entries, got {G.shape}", field="generators")
        if not is_stamp(t0):
            raise InputError(f"the start time is an integer, got {t0!r}", field="t0")
        lim = self.system.horizon_limit
        if lim is not None and not 0 <= self._model_time(int(t0)) < lim:  # no wrap-around into A[-3]
            raise InputError(f"the time-varying data covers times 0..{lim - 1}, not the start time {t0} (for a "
                             "periodic plant: periodic_model(T) first)", field="t0")
        with np.errstate(over="ignore", invalid="ignore"):  # the first prediction must stay finite
            reach = np.abs(self.system.A_at(self._model_time(int(t0)))) @ (np.abs(c) + np.abs(G).sum(axis=1))
        if not np.all(reach <= MAX_SET_REACH):
            raise InputError(f"the set's first prediction |A| (|xhat0| + radius) exceeds {MAX_SET_REACH:g} (the "
                             "window's products would overflow in floating point): scale the state, or give a "
                             "smaller estimate or set", field="xhat0")
        G = G[:, np.any(G != 0, axis=0)]
        if self._limit is not None:
            G = _REDUCTIONS[self.reduction](G, self._limit)
        K, sysm = len(self.gain), self.system
        self._c = np.tile(c, (K, 1))  # every filter starts from the same set, at the window's start
        self._G = np.ascontiguousarray(np.tile(G, (K, 1, 1)))
        P = G if self._wlimit is None or G.shape[1] <= self._wlimit else _REDUCTIONS[self.reduction](G, self._wlimit)
        self._P = np.ascontiguousarray(np.tile(P, (K, 1, 1)))  # the window's prior (module docstring)
        self._xhat, self._beta = c, outer_row_sums(G)  # one set for all: its centre and radius
        self._R, self._pick = None, np.zeros(n, dtype=int)  # the window's error maps (none yet), its picks
        self._carry = None  # the last window's weights: its relative residuals, T(0), radii, measured times
        self._filtered: "StateSet | None" = None  # the filtered set, computed on demand
        self._axes: "np.ndarray | None" = None  # the principal axes last computed (reduction="pca")
        # the window, times t0 .. time-1 (at most W of them): drives, which outputs are known, their values
        self._drive, self._known, self._y = np.zeros((0, n)), np.zeros(0, dtype=bool), np.zeros((0, sysm.p))
        self._time = self._t0 = int(t0)
        self.dropped_packets = 0
        self.replays = 0
        return self

    def step(self, y: Any = None, u: Any = None) -> tuple[np.ndarray, float]:
        """Process time ``t``: what arrived and the input; return ``(x̂(t+1), bound)``.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            ``y(t)`` on time, time-stamped packets ``(τ, y(τ))`` with ``τ <= t``, or ``None``.
        u : array_like or None, optional
            The input ``u(t)`` (``None``: zero).

        Returns
        -------
        xhat : numpy.ndarray, shape (n,)
            The centre of the set of ``x(t+1)``.
        bound : float
            The infinity norm of the interval hull's radius, :math:`\\max_i \\beta_i(t+1)`.

        Raises
        ------
        InputError
            Before :meth:`reset`; a measurement or input of the wrong shape or with NaN/inf entries, a packet
            stamped in the future or received twice, a time past a time-varying system's data, data whose
            propagation overflows in floating point (the estimator is left unchanged).
        """
        t = self.time  # (raises before reset)
        self._step_checked(as_packets(y, t, (self.system.p,)), check_input(u, self.system.m))
        beta = self._beta
        return self._xhat.copy(), float(beta.max()) if beta.size else 0.0

    def _step_checked(self, packets: list, u: np.ndarray) -> None:
        """:meth:`step` from packets and an input already checked (the call path of an estimator that runs this one
        beside its own and has checked them once for both, :class:`eqrec.estimators.guaranteed.GuaranteedEstimator`):
        ``packets`` as :func:`eqrec.arrivals.packets.as_packets` returns them for the current time and ``(p,)``,
        ``u`` as :func:`eqrec.arrivals.packets.check_input` returns it (read only).  The estimate and the bounds are
        then ``_xhat`` and ``_beta`` (not copied).  Raises :class:`InputError` as :meth:`step` does for what the
        window refuses (a second packet of one time, a time past a time-varying system's data, an overflow);
        nothing changes then."""
        t = self._time
        intake = self._intake(packets, u)
        xhat, beta, extra = self._estimate(intake)
        sets = intake["carried"]
        P = sets["P"] if sets["P"] is not sets["G"] else sets["c"]  # (the filters' set itself: checked once)
        if not _all_finite(xhat, beta, sets["c"], sets["G"], P):  # refuse data whose propagation overflows

            raise InputError(f"the data of time {t} overflow in floating point (the estimate or its bound is not "
                             "finite): a measurement or input too large for the plant's scale; the estimator is "
                             "left unchanged", field="y" if intake["packets"] else "u" if np.any(intake["u"])
                             else "xhat0")
        self._commit(intake, xhat, beta, extra)

    def _intake(self, packets: list, u: np.ndarray) -> dict:
        """Store the checked packets of time ``t`` in the window (:meth:`_step_checked`) and let the filters take
        in the time that leaves it: the proposed new state, nothing changed (raises on what the window refuses)."""
        t = self._time
        sysm = self.system
        lim = self._horizon
        if lim is not None and self._model_time(t) >= lim:
            raise InputError(f"time-varying data covers times 0..{lim - 1}, not {t}", field="system")
        first = t - self._drive.shape[0]  # the window's start, time t appended
        drive = np.concatenate([self._drive, (sysm.B_at(self._model_time(t)) @ u + sysm.f)[None]])
        known = np.concatenate((self._known, _NOT_KNOWN))
        ys = np.concatenate((self._y, self._no_y[None]))  # (a new array: the row of zeros is not written)
        dropped = late = 0
        for pk in packets:
            if pk.time < max(first, t - self.max_delay):
                dropped += 1  # later than max_delay (or stamped before the run): ignoring it stays guaranteed
                continue
            i = pk.time - first
            if known[i]:
                raise InputError(f"a second packet stamped {pk.time} received at time {t}", field="y")
            known[i], ys[i] = True, pk.y
            late += pk.time < t
        carried = self._carried()
        if drive.shape[0] > self._W:  # the oldest time leaves the window: the filters take it in
            carried = self._take_in(first, drive[0], ys[0] if known[0] else None)
            drive, known, ys, first = drive[1:], known[1:], ys[1:], first + 1
        return {"t": t, "carried": carried, "drive": drive, "known": known, "ys": ys, "first": first,
                "dropped": dropped, "late": late, "packets": len(packets), "u": u}

    def _carried(self) -> dict:
        """The sets carried at the window's start, by attribute name (without the leading underscore)."""
        return {"c": self._c, "G": self._G, "axes": self._axes, "P": self._P}

    def _take_in(self, s: int, drive: np.ndarray, y: "np.ndarray | None") -> dict:
        """The carried sets after time ``s`` leaves the window (filter step and reduction; nothing changed)."""
        c, G = self._advance(s, self._c, self._G, drive, y)
        G, axes, P = self._reduced(G, (s - self._t0) % PCA_AXES_EVERY == 0)
        return {"c": c, "G": np.ascontiguousarray(G), "axes": axes, "P": np.ascontiguousarray(P)}

    def _estimate(self, intake: dict) -> tuple[np.ndarray, np.ndarray, dict]:
        """The window's estimate of ``x(t+1)`` and its per-state bound from the proposed state (nothing
        changed), with what :meth:`_commit` keeps besides."""
        first, drive = intake["first"], intake["drive"]
        A, C, E, V = self._window_model(first, drive.shape[0])
        sets = intake["carried"]
        known = intake["known"]
        # the weights carried from the last window, once the window is full (the same length as the last one) and
        # unless this window measures a time and the last measured none (then the window starts cold too)
        last = self._carry
        carry = (last if last is not None and last[3].shape[0] == known.shape[0] and (last[3].any() or not known.any())
                 else COLD)
        xs, radii_, _, R, *kept = self._window(A, C, E, V, drive, known, intake["ys"], sets["c"], sets["P"],
                                               self.iterations, PER_STATE_MARGIN, PER_STATE_STATES, carry)
        extra = {"_R": R, "_pick": self._one_pick, "_carry": (*kept, known) if self.warm_start else None}
        if xs.shape[0] == 1:  # one filter: its window's estimate
            return xs[0], radii_[0], extra
        extra["_pick"] = pick = np.argmin(radii_, axis=0)  # per state, the filter whose window is the tightest
        states = np.arange(self.system.n)  # (the first on a tie)
        return xs[pick, states], radii_[pick, states], extra

    def _commit(self, intake: dict, xhat: np.ndarray, beta: np.ndarray, extra: dict) -> None:
        """Make the proposed state the estimator's (the only place a step changes it: atomic steps)."""
        for key, val in intake["carried"].items():
            setattr(self, "_" + key, val)
        self._drive, self._known, self._y = intake["drive"], intake["known"], intake["ys"]
        self._xhat, self._beta = xhat, beta
        for key, val in extra.items():
            setattr(self, key, val)
        self._filtered = None  # computed on demand (:attr:`filtered`)
        self._time = intake["t"] + 1
        self.dropped_packets += intake["dropped"]
        self.replays += intake["late"]

    def _window(self, A: np.ndarray, C: np.ndarray, E: np.ndarray, V: np.ndarray, drive: np.ndarray,
                known: np.ndarray, ys: np.ndarray, c: np.ndarray, P: np.ndarray, iterations: int, margin: float,
                states: int, carry: tuple) -> tuple[np.ndarray, ...]:
        """:func:`eqrec.bounds.window.window_estimate` on the window's plant as :meth:`_window_model` gives it, with
        the nonzeros of ``A`` and ``E`` found once for a time-invariant plant (the same numbers); ``carry``: the
        last window's weights (:data:`eqrec.bounds.window.COLD`: none), one shared solve fewer with them."""
        shared = SHARED_SOLVES_WARM if carry[3].size else SHARED_SOLVES
        if self._tiles is None:  # a time-varying plant: found in each window
            return window_estimate(A, C, E, V, drive, known, ys, c, P, shared, _IRLS_FLOOR, WINDOW_EXTRA_SOLVES,
                                   WINDOW_SOLVE_GAIN, iterations, margin, states, *carry, self.warm_start)
        if self._sparse is None:
            A_, E_ = self._tiles[0], self._tiles[2]
            self._sparse = sparse_rows(A_) + sparse_columns(E_) + sparse_columns(A_)
        L = A.shape[0]
        sparse = self._sparse_at.get(L)
        if sparse is None:  # the nonzeros of the first L times (views, kept per length)
            sparse = self._sparse_at[L] = tuple(M[:L] for M in self._sparse)
        return window_estimate_sparse(A, C, E, V, drive, known, ys, c, P, shared, _IRLS_FLOOR, WINDOW_EXTRA_SOLVES,
                                      WINDOW_SOLVE_GAIN, iterations, margin, states, *sparse, *carry,
                                      self.warm_start)

    def _window_model(self, first: int, length: int) -> tuple[np.ndarray, ...]:
        """The plant over the window ``first .. first + length - 1``: ``A``, ``C``, ``η_w E``, ``η_v V`` stacked
        by time (C-contiguous, as the compiled window expects; cached for a time-invariant plant)."""
        if self._horizon is None:  # time-invariant
            if self._tiles is None:
                self._tiles = tuple(np.broadcast_to(M, (self._W,) + M.shape).copy()  # writable: one compile
                                    for M in self._model(0))
            tiles = self._tiles_at.get(length)
            if tiles is None:  # views of the first `length` times, kept per length
                tiles = self._tiles_at[length] = tuple(M[:length] for M in self._tiles)
            return tiles
        parts = [self._model(s) for s in range(first, first + length)]
        return tuple(np.ascontiguousarray(np.stack([p[k] for p in parts])) for k in range(4))

    # -- one step of the set recursion (module docstring) ------------------------------------------------------
    def _model(self, s: int) -> tuple:
        """The model's matrices at time ``s``: ``A``, ``C``, ``η_w E``, ``η_v V`` (C-contiguous; cached: one entry
        when the plant is time-invariant, one per model time otherwise)."""
        m = self._model_time(s)
        key = 0 if self._horizon is None else m
        hit = self._models.get(key)
        if hit is None:
            sysm = self.system
            hit = tuple(np.ascontiguousarray(M, dtype=float) for M in
                        (sysm.A_at(m), sysm.C_at(m), sysm.eta_w * sysm.E_at(m), sysm.eta_v * sysm.V_at(m)))
            self._models[key] = hit
        return hit

    def _advance(self, s: int, c: np.ndarray, G: np.ndarray, drive: np.ndarray,
                 y: "np.ndarray | None") -> tuple[np.ndarray, np.ndarray]:
        """The sets of ``x(s+1)`` (one per gain, stacked, not reduced) from the priors of ``x(s)``
        (:func:`eqrec.bounds.window.filter_step`)."""
        A, C, Ew, Vn = self._model(s)
        has_y = y is not None
        return filter_step(A, C, Ew, Vn, drive, y if has_y else self._no_y, has_y, c, G, self._alpha)

    def _reduced(self, G: np.ndarray, new_axes: bool) -> tuple[np.ndarray, "np.ndarray | None", np.ndarray]:
        """``G`` reduced to ``order · n`` generators per filter, the principal axes used (``reduction="pca"``:
        computed again from ``G`` when ``new_axes`` or none yet, else those last computed; module docstring), and
        ``G`` reduced to ``max(window_generators, 2n)`` generators, the window's prior (both from one change of axes;
        ``G`` itself when the filters' sets are not larger)."""
        lim, wlim, q = self._limit, self._wlimit, G.shape[2]
        if wlim is None:  # the window's prior is the filters' set
            if lim is None or q <= lim:
                return G, self._axes, G
            if self.reduction == "girard":
                Gr = reduce_girard(G, lim)
                return Gr, self._axes, Gr
            axes = principal_axes(G) if new_axes or self._axes is None else self._axes
            Gr = reduce_pca(G, lim, axes=axes)
            return Gr, axes, Gr
        if q <= wlim:  # (then wlim < lim: nothing to reduce)
            return G, self._axes, G
        lim = q if lim is None else lim
        if self.reduction == "girard":
            return reduce_girard(G, lim), self._axes, reduce_girard(G, wlim)
        axes = principal_axes(G) if new_axes or self._axes is None else self._axes
        Gr, P = reduce_pca_pair(G, lim, wlim, axes=axes)
        return Gr, axes, P

    # -- reading ----------------------------------------------------------------------------------------------
    @property
    def time(self) -> int:
        """Absolute time of the current estimate (raises before :meth:`reset`)."""
        if self._time is None:
            raise InputError("call reset(xhat0) before running the estimator")
        return self._time

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate, the centre of the reported set."""
        self.time  # noqa: B018 - raises before reset
        return self._xhat.copy()

    @property
    def state_bounds(self) -> np.ndarray:
        """Per-state radius of the interval hull, ``β_i >= |x_i - x̂_i|`` (a copy, shape ``(n,)``)."""
        self.time  # noqa: B018 - raises before reset
        return self._beta.copy()

    @property
    def carried_set(self) -> tuple[np.ndarray, np.ndarray]:
        """The reported set, ``x̂ + G ε`` with ``|ε| <= 1`` (copies): it contains ``x`` of the current time.

        Its interval hull is :attr:`state_bounds`.  State ``i`` is the window's estimate from the zonotope of the
        filter it was taken from (module docstring), so the generators are, per filter, the window's error maps
        on the generators of that filter's window prior (module docstring, *The window's prior*; on the rows of the states taken from it, zero elsewhere; the filters'
        zonotopes are different parametrisations of the same state), then the window's noise (shared), then
        the rounding allowance as ``n`` axis-aligned generators.  The set to hand over to another estimator
        (:class:`eqrec.estimators.guaranteed.GuaranteedEstimator`).
        """
        self.time  # noqa: B018 - raises before reset
        if self._R is None:  # right after reset: the filters' common set
            return self._xhat.copy(), self._G[0].copy()
        return self._xhat.copy(), self._window_generators(self._R, self._pick, self._beta)

    @property
    def predicted(self) -> StateSet:
        """The set of ``x(t+1)`` given the data received up to ``t`` (:class:`~eqrec.estimators.protocol.StateSet`):
        centre :attr:`x`, radius :attr:`state_bounds`, zonotope :attr:`carried_set` (right after :meth:`reset`,
        the initial set of ``x(t0)``)."""
        c, G = self.carried_set
        return StateSet.around(self.time, c, self._beta, G)

    @property
    def filtered(self) -> StateSet:
        r"""The set of ``x(t)`` given the data received up to ``t`` (:class:`~eqrec.estimators.protocol.StateSet`).

        The window of the last step again, ending one step earlier: the same prior zonotope at :math:`s_0` and
        the same packets, with the last step's dynamics replaced by the identity, its drive and process noise by
        zero, so that the window's "next state" is :math:`x(t)` itself, estimated from every packet of times
        :math:`s_0..t` (:func:`eqrec.bounds.window.window_estimate`: per state the best of the filters, its bound
        the exact worst case of its estimate, rounding included), with every state solved one by one (not only the
        largest, as in :meth:`step`: each state's hull is then as tight as the largest's).  Computed on the first
        request after a step (the cost of one more window and ``n`` states' own solves) and kept until the next
        step.  The zonotope: the window's error maps on the generators of the window's prior and the noise, as
        :attr:`carried_set`.

        Raises
        ------
        InputError
            Before :meth:`reset`, or right after it (no step: there is no data yet).
        """
        t1 = self.time
        if self._R is None:
            raise InputError("no step since reset: the filtered set needs the data of one step", field="filtered")
        if self._filtered is None:
            A, C, E, V = (np.array(M) for M in self._window_model(self._time - self._drive.shape[0],
                                                                   self._drive.shape[0]))
            A[-1], E[-1] = np.eye(self.system.n), 0.0
            drive = self._drive.copy()
            drive[-1] = 0.0
            xs, radii_, _, R = window_estimate(A, C, E, V, drive, self._known, self._y, self._c, self._P,
                                               SHARED_SOLVES, _IRLS_FLOOR, WINDOW_EXTRA_SOLVES, WINDOW_SOLVE_GAIN,
                                               self.iterations, 1.0, self.system.n, *COLD, False)[:4]  # each alone
            pick = np.argmin(radii_, axis=0)
            states = np.arange(self.system.n)
            xhat, beta = xs[pick, states], radii_[pick, states]
            self._filtered = StateSet.around(t1 - 1, xhat, beta, self._window_generators(R, pick, beta))
        return self._filtered

    def _window_generators(self, R: np.ndarray, pick: np.ndarray, beta: np.ndarray) -> np.ndarray:
        """The zonotope of a window's estimate: per state, the error map of the filter it was taken from, then the
        window's noise, then an axis-aligned pad up to the bound (:attr:`carried_set`)."""
        n, q0 = self.system.n, self._P.shape[2]
        states = np.arange(n)
        blocks = [np.where((pick == k)[:, None], R[k, :, :q0], 0.0) for k in range(R.shape[0])]
        G = np.concatenate(blocks + [R[pick, states, q0:]], axis=1)
        return np.concatenate([G, np.diag(hull_pad(G, beta))], axis=1)

    def linear_error_model(self) -> np.ndarray:
        """The generators of the error set of the current estimate (:attr:`carried_set`): what
        :func:`eqrec.exact_bound` reads (:meth:`eqrec.estimators.guaranteed.GuaranteedEstimator.linear_error_model`).

        Returns
        -------
        numpy.ndarray, shape (n, q)
            ``x − x̂ = G ε`` for some ``|ε| <= 1``; the row sums are at least :attr:`state_bounds`.
        """
        return self.carried_set[1]

    @property
    def generators(self) -> np.ndarray:
        """A copy of the generators of every filter at the window's start, shape ``(K, n, q)`` (``K`` gains,
        ``q <= order · n``)."""
        self.time  # noqa: B018 - raises before reset
        return self._G.copy()
