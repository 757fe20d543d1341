r"""A zonotopic set-membership estimator: a guarantee on any arrival trace, with no language.

The plant is :class:`~eqrec.systems.affine.AffineSystem` (eq. (3) of the prefix-based paper with the noise gains
of its Remark 1; per-channel bounds are already folded into ``E`` and ``V``):

.. math::
    x(s+1) = A(s)x(s) + B(s)u(s) + f + E(s)w(s), \quad y(s) = C(s)x(s) + V(s)v(s),
    \quad \|w\|_\infty \le \eta_w,\ \|v\|_\infty \le \eta_v .

The estimator carries a zonotope :math:`Z = \langle c, G\rangle = \{c + G\xi : \|\xi\|_\infty \le 1\}` that
contains the state for every noise in its box (set-membership estimation by zonotopes: Alamo, Bravo, Camacho,
"Guaranteed state estimation by zonotopes", Automatica 41, 2005; Combastel, "Zonotopes and Kalman observers: Gain
optimality under distinct uncertainty paradigms and robust convergence", Automatica 55, 2015), one per gain
(below).  The radius of a zonotope's interval hull is :math:`\beta_i = \sum_j |G_{ij}|`; per state, the
estimate is the centre of the filter with the smallest radius and that radius the bound
(:attr:`ZonotopeEstimator.state_bounds`); ``step`` returns the largest.

One step (time ``s``, prior set :math:`\langle c, G\rangle \ni x(s)`)
------------------------------------------------------------------------
*Update and prediction in one.*  With a delivered :math:`y(s)`, write :math:`r = y - Cc`; every state consistent
with the data satisfies :math:`r = CG\xi + \eta_v V \nu` (:math:`\|\nu\|_\infty \le 1`: the exact form of the
strip :math:`|y - Cx| \le \eta_v |V|\mathbf 1`, which keeps the noise shared by several outputs).  For **any**
gain :math:`M` (``n × p``) the zero :math:`M(r - CG\xi - \eta_v V\nu)` may be added to the prediction, so

.. math::
    x(s+1) \in \big\langle\, Ac + Bu + f + Mr,\ \ [\,AG - MCG,\ \ -\eta_v MV,\ \ \eta_w E\,] \big\rangle,

valid whatever :math:`M` (Alamo et al. 2005, Property 2; Combastel 2015, eq. (9); :math:`M = A\Lambda` is the
familiar filter gain :math:`\Lambda` followed by the prediction, but :math:`M` need not be of that form).

*The gains.*  Any :math:`M` keeps the set valid; the gain only decides how tight it stays.  The estimator runs
one filter per gain named in ``gain`` on the same data, each carrying its own zonotope, and reports per state
the tighter one (next section).

* ``"fradius"``: Combastel's F-radius-optimal gain (2015, Theorem 3),
  :math:`\Lambda = GG^\top C^\top (CGG^\top C^\top + \eta_v^2 VV^\top)^{-1}` (a Kalman gain with covariance
  :math:`GG^\top`), applied to the filtered set, then the prediction (:math:`M = A\Lambda`).  It minimises the
  filtered :math:`G'G'^\top` in the Löwner order, so every weighted sum of *squared* generator entries; the
  interval hull is a sum of *absolute* entries.
* ``"reweighted"``: the same formula with :math:`GG^\top` and :math:`VV^\top` replaced by :math:`GWG^\top`,
  :math:`VW_vV^\top`, where each generator is weighted by the inverse of its length,
  :math:`W = \operatorname{diag}(1/\|(g_j, Cg_j)\|_2)` (and :math:`1/\|v_j\|_2` for the measurement noise).
  With these weights, :math:`\sum_j w_j\|g'_j\|_2^2` is the first iteratively-reweighted-least-squares step from
  the current set towards minimising :math:`\sum_j \|g'_j\|_2`, the sum of the generators' lengths, which bounds
  the interval hull (:math:`\sum_i \beta_i = \sum_j \|g_j\|_1 \le \sqrt n \sum_j \|g_j\|_2`) and, unlike the
  squared sum, counts the many small generators the process noise adds as much as they widen the hull.  A
  weighted least-squares problem has the same closed form, so the step costs the same.
* ``"interval"``: per row, the weighted-median gain.  Row ``i`` of the new generator matrix depends on row ``i``
  of :math:`M` only, so every row of the *predicted* interval hull is minimised at once.  For one scalar output,
  with :math:`g = (AG)_{i\cdot}` extended by zeros on the noise columns and :math:`h = [CG,\ \eta_v V]`,
  :math:`\beta_i(\mu) = \|g - \mu h\|_1 = \sum_{k:\,h_k\ne 0} |h_k|\,|g_k/h_k - \mu| + \sum_{k:\,h_k = 0}
  |g_k|`, minimised by the weighted median of the ratios :math:`g_k/h_k` with weights :math:`|h_k|` (a sort and a
  cumulative sum).  By LP duality this is the one-step radius of information given the prior zonotope, in the
  worst case over the measured value; with ``p > 1`` outputs the rows are applied one after the other.  It is
  greedy: its zeros throw away the shape of the set in the directions a later measurement or ``A`` needs.

*The default* ``gain=("fradius", "reweighted")``.  Measured (``benchmarks/bench_zonotope.py``, bound / information
limit per step, order 40): on the two-cart plant at 30 % loss and delays 0..2, the F-radius gain alone ends at
median 1.24, maximum 1.53, the reweighted one alone at 1.2 / 1.4, the weighted-median one at 2.4 / 4.0; the
reweighted gain is not better everywhere (on the batch reactor, two outputs and an unstable mode, it is worse
than the F-radius gain, 2.1 against 1.5 at the median).  Both side by side take the better of the two, state by
state and step by step: 1.18 / 1.23 on the two carts, 1.43 / 1.80 on the reactor, for about the cost of one
filter (the two filters' matrices are stacked, so one NumPy call serves both).

The reported estimate: per state, the tighter filter
---------------------------------------------------
Each filter's zonotope contains the state, so for every state ``i`` each filter's centre is within its hull
radius :math:`\beta_{k,i}`.  The estimator reports, state by state, the centre and radius of the filter with the
smallest radius.  The radii do not depend on the measured values (only on the arrivals), so the choice does not
either: given the arrivals the estimate stays *linear* in the initial error and the noise, its bound is the exact
worst case of its own error (with no reduction), and never below the information limit, as for every other
linear estimator of the project (:func:`eqrec.estimators.exact.exact_bound`).  (The intersection of the hulls
would be narrower by a few per cent more, but its midpoint depends on the data: measured, 1.169 against 1.175 at
the median on the two carts; the linear choice is kept.)

Late packets: a buffer of the last ``D`` steps and replay
--------------------------------------------------------
The estimator keeps, for the last ``D = max_delay`` steps, the prior set of that time (before its measurement
update), the known drive :math:`B u + f` and the measurement received for it.  A packet stamped ``τ`` arriving at
``t`` with :math:`t - D \le \tau < t` is stored with its time and the steps ``τ..t`` are run again from the
stored prior of ``τ`` (the later updates re-applied, the later priors replaced), so every delivered measurement
is used at its own time.  A packet older than the buffer (``τ < t − D``, or stamped before ``reset``) is
**dropped** and counted in :attr:`ZonotopeEstimator.dropped_packets`: ignoring a measurement never makes the
set smaller than the true consistent set, since the set before any update already contains the state (each
update only intersects with data that holds), so the estimator stays guaranteed; it only loses what that packet
would have told.  Replay is exact up to the order reduction.  Only the set of the newest time is reduced: a replayed step and
the priors it stores in the buffer keep all their generators (at most ``D`` steps more than ``order · n``), so
a late packet costs no extra reduction and loses nothing to one.

Order reduction (outer only)
----------------------------
At the end of every step, when a set has more than ``order · n`` generators, the generators with the smallest
:math:`\|g\|_1 - \|g\|_\infty` (the increase of the interval hull's perimeter when a segment is replaced by its
box) are replaced by the ``n`` generators of their interval hull, :math:`\operatorname{diag}(\sum_j |g_j|)`
(Girard, "Reachability of uncertain linear systems using zonotopes", HSCC 2005; Combastel's 2003 reduction
boxes the smallest in 2-norm instead): ``reduction="girard"``.  ``reduction="pca"`` (default; the axes computed
again every :data:`PCA_AXES_EVERY` steps from the set being reduced, in between those last computed: any
orthonormal axes give an outer reduction, and the principal ones move slowly) does the same in the orthonormal principal axes ``U``
of :math:`GG^\top` (Kopetzki, Schürmann, Althoff, CDC 2017), a parallelotope :math:`U\operatorname{diag}(\sum_j
|U^\top g_j|)`; the same containment argument holds in the rotated axes.  Each removed segment :math:`[-g, g]` lies in its box, and a Minkowski
sum of supersets is a superset, so the reduced zonotope contains the original one: every support function
:math:`h(d) = d^\top c + \sum_j |d^\top g_j|` can only grow, since
:math:`\sum_{j\in S} |d^\top g_j| \le \sum_i |d_i| \sum_{j\in S} |g_{ij}|`, and the interval hull is unchanged
at the moment of reduction (the looseness appears only once ``A`` rotates the box).  The box sums are rounded
outward.

Floating point
--------------
The bound is a guarantee on the error computed in floating point, with no tolerance on the guarantee side:
the row sums are rounded outward (Higham, *Accuracy and Stability of Numerical Algorithms*, eq. (4.4): a sum of
``q`` non-negative terms is within :math:`(q-1)u` of the exact one), and each step appends a rounding allowance
:math:`\kappa\,u\,(|A|(|c| + \beta) + |Bu + f| + |Mr| + \text{row sums of the products})` (``u`` the unit
roundoff, :math:`\kappa` a few times the length of the dot products) as ``n`` axis-aligned generators, which
covers the rounding of the centre's and the generators' products and of a simulated true state of the same
size.  It adds a relative :math:`10^{-14}`-order to the bound.

References: Alamo, Bravo, Camacho (Automatica 2005); Combastel (Automatica 2015); Girard (HSCC 2005); Scott,
Raimondo, Marseglia, Braatz, "Constrained zonotopes: A new tool for set-based estimation and fault detection",
Automatica 69, 2016 (the exact intersection this estimator over-approximates by one zonotope); CORA's
``observe`` methods and ZETA (MATLAB) implement the same family.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from eqrec.arrivals.packets import is_stamp, as_packets, check_estimate, check_input
from eqrec.bounds.zonotope import check_order, outer_row_sums, principal_axes, reduce_girard, reduce_pca
from eqrec.checks import radii
from eqrec.errors import InputError
from eqrec.systems.affine import AffineSystem

#: Unit roundoff of float64.
_U = np.finfo(float).eps / 2

#: The gains offered (module docstring); the estimator runs one filter per gain named and intersects them.
GAINS = ("fradius", "reweighted", "interval")

#: The default: Combastel's F-radius gain and its reweighted form, side by side.
DEFAULT_GAINS = ("fradius", "reweighted")


class _Entry(NamedTuple):
    """One buffered step: the prior sets of time ``s`` (one per gain), its drive ``B u + f`` and its measurement."""

    s: int
    c: np.ndarray
    G: np.ndarray
    drive: np.ndarray
    y: "np.ndarray | None"


_REDUCTIONS = {"girard": reduce_girard, "pca": reduce_pca}

#: With ``reduction="pca"``, the principal axes are computed again every this many steps (module docstring).
PCA_AXES_EVERY = 4


def _row_gains(P: np.ndarray, h: np.ndarray) -> np.ndarray:
    """Per row ``i``, a minimiser of ``||P_i - mu h||_1``: the weighted median of ``P_ik / h_k``, weights ``|h_k|``."""
    nz = h != 0
    if not nz.any():
        return np.zeros(P.shape[0])
    hz = h[nz]
    z = P[:, nz] / hz
    w = np.abs(hz)
    order = np.argsort(z, axis=1)
    cw = np.cumsum(w[order], axis=1)
    k = np.argmax(cw >= 0.5 * cw[:, -1:], axis=1)  # first index where the cumulative weight reaches half
    rows = np.arange(P.shape[0])
    return z[rows, order[rows, k]]


def _interval_update(AG: np.ndarray, Ac: np.ndarray, CG: np.ndarray, Vn: np.ndarray, r: np.ndarray,
                     y: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The predicted generators and centre with the per-row weighted-median gains, and a rounding magnitude."""
    n = AG.shape[0]
    H = np.concatenate([CG, Vn], axis=1)
    P = np.concatenate([AG, np.zeros((n, Vn.shape[1]))], axis=1)
    cp = Ac
    mag = np.zeros(n)
    for j in range(H.shape[0]):
        mu = _row_gains(P, H[j])
        P = P - np.outer(mu, H[j])
        cp = cp + mu * r[j]
        mag = mag + np.abs(mu) * (np.abs(H[j]).sum() + np.abs(r[j]) + np.abs(y[j]))
    return P, cp, mag


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
        ``D >= 0``: packets up to ``D`` steps late are used at their own time (replay); older ones are dropped
        and counted (default 0).
    order : float or None, optional
        At most ``order · n`` generators are kept per filter at the end of a step (``>= 1``; default 40);
        ``None``: no reduction (exact sets, growing without limit).
    gain : str or tuple of str, optional
        One filter per gain named, each of ``"fradius"`` (Combastel's F-radius gain, the Kalman-shaped
        reference), ``"reweighted"`` (the same with generators weighted by their inverse length) and
        ``"interval"`` (the per-row weighted-median gain; greedy, loose over time); per state the filter with
        the smallest radius is reported.  Default ``("fradius", "reweighted")`` (module docstring).
    reduction : {"pca", "girard"}, optional
        The outer order reduction: the box in the principal axes of the generators (default,
        :func:`reduce_pca`) or Girard's axis-aligned box (:func:`reduce_girard`).

    Attributes
    ----------
    kind : str
        ``"guaranteed"``.
    name : str
        ``"set-membership, zonotope"``.
    dropped_packets : int
        Packets dropped since :meth:`reset` because they were older than the buffer.
    replays : int
        Late packets used by replaying the buffer since :meth:`reset`.

    Raises
    ------
    InputError
        A ``system`` that is not an :class:`AffineSystem`, a negative, non-finite or wrongly sized
        ``x0_radius``, ``max_delay`` not an integer ``>= 0``, ``order`` not ``None`` nor a number ``>= 1``, an
        unknown ``gain`` (the field is named).

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> carts = eqrec.two_mass()
    >>> est = eqrec.ZonotopeEstimator(carts, x0_radius=0.5, max_delay=2, order=20).reset(np.zeros(4))
    >>> xhat, bound = est.step(np.array([0.1]))       # y(0) on time
    >>> xhat, bound = est.step(None)                  # y(1) not (yet) arrived
    >>> xhat, bound = est.step([eqrec.Packet(1, np.array([0.12]))])  # y(1) one step late: replayed
    >>> est.time, est.state_bounds.shape, bool(bound == est.state_bounds.max()), est.replays
    (3, (4,), True, 1)
    """

    kind = "guaranteed"
    name = "set-membership, zonotope"

    def __init__(self, system: AffineSystem, x0_radius: Any = 1.0, max_delay: int = 0, order: "float | None" = 40,
                 gain: "str | tuple[str, ...]" = DEFAULT_GAINS, reduction: str = "pca"):
        if not isinstance(system, AffineSystem):
            raise InputError(f"expected an AffineSystem, got {type(system).__name__}", field="system")
        n = system.n
        r0 = radii(x0_radius, n)
        if not is_stamp(max_delay) or max_delay < 0:
            raise InputError(f"the largest delay is an integer >= 0, got {max_delay!r}", field="max_delay")
        order = check_order(order)
        gains = _gain_names(gain)
        if reduction not in _REDUCTIONS:
            raise InputError(f"unknown reduction {reduction!r}; choose one of {list(_REDUCTIONS)}", field="reduction")
        self.reduction = reduction
        self.system, self.x0_radius, self.max_delay = system, r0, int(max_delay)
        self.order = None if order is None else float(order)
        self.gain = gains
        # per filter: weight exponent of the gain's generator weights (0: F-radius, 1: reweighted); interval apart
        self._alpha = np.array([1.0 if g == "reweighted" else 0.0 for g in gains])
        self._interval = [k for k, g in enumerate(gains) if g == "interval"]
        self._models: dict[int, tuple] = {}
        self._eye = np.eye(n)
        self._limit = None if order is None else max(n, int(np.floor(self.order * n)))
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
            A non-finite or wrongly sized ``xhat0``, a ``t0`` that is not an integer (nothing changes).
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
            Non-finite or wrongly shaped ``xhat0`` or ``generators``, a non-integer ``t0`` (nothing changes).
        """
        n = self.system.n
        c = check_estimate(xhat0, n)
        G = np.asarray(generators, dtype=float)
        if G.ndim != 2 or G.shape[0] != n or not np.all(np.isfinite(G)):
            raise InputError(f"generators need shape ({n}, q) and finite entries, got {G.shape}", field="generators")
        if not is_stamp(t0):
            raise InputError(f"the start time is an integer, got {t0!r}", field="t0")
        G = G[:, np.any(G != 0, axis=0)]
        if self._limit is not None:
            G = _REDUCTIONS[self.reduction](G, self._limit)
        K = len(self.gain)
        self._c = np.tile(c, (K, 1))  # every filter starts from the same set
        self._G = np.tile(G, (K, 1, 1))
        self._xhat, self._beta = c, outer_row_sums(G)  # one set for all: its centre and radius
        self._axes: "np.ndarray | None" = None  # the principal axes last computed (reduction="pca")
        self._buffer = ()
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
            stamped in the future or received twice, a time past a time-varying system's data (the estimator
            is left unchanged).
        """
        t = self.time
        sysm = self.system
        packets = as_packets(y, t, (sysm.p,))
        u = check_input(u, sysm.m)
        lim = sysm.horizon_limit
        if lim is not None and self._model_time(t) >= lim:
            raise InputError(f"time-varying data covers times 0..{lim - 1}, not {t}", field="system")
        drive = sysm.B_at(self._model_time(t)) @ u + sysm.f
        entries = list(self._buffer) + [_Entry(t, self._c, self._G, drive, None)]
        first = entries[0].s
        dropped = 0
        start = t
        for pk in packets:
            if pk.time < first:
                dropped += 1  # older than the buffer (or than the run): ignoring it stays guaranteed
                continue
            i = pk.time - first
            if entries[i].y is not None:
                raise InputError(f"a second packet stamped {pk.time} received at time {t}", field="y")
            entries[i] = entries[i]._replace(y=pk.y)
            start = min(start, pk.time)
        c, G = entries[start - first].c, entries[start - first].G
        for s in range(start, t + 1):
            e = entries[s - first]
            if s > start:
                entries[s - first] = e = e._replace(c=c, G=G)
            c, G = self._advance(s, e.c, e.G, e.drive, e.y)
        G, axes = self._reduced(G, (t - self._t0) % PCA_AXES_EVERY == 0)  # only the newest set is reduced
        keep = tuple(entries[len(entries) - self.max_delay:]) if self.max_delay else ()
        xhat, beta = self._report(c, G)
        # commit
        self._c, self._G, self._xhat, self._beta = c, G, xhat, beta
        self._buffer = keep
        self._axes = axes
        self._time = t + 1
        self.dropped_packets += dropped
        self.replays += sum(1 for pk in packets if first <= pk.time < t)
        return xhat.copy(), float(beta.max()) if beta.size else 0.0

    # -- one step of the set recursion (module docstring) ------------------------------------------------------
    def _model(self, s: int) -> tuple:
        """The model's matrices at time ``s`` and what the step derives from them (cached: one entry when the
        plant is time-invariant, one per model time otherwise)."""
        m = self._model_time(s)
        key = m if self.system.is_time_varying else 0
        hit = self._models.get(key)
        if hit is None:
            sysm = self.system
            A, C = sysm.A_at(m), sysm.C_at(m)
            Ew, Vn = sysm.eta_w * sysm.E_at(m), sysm.eta_v * sysm.V_at(m)
            vlen = np.sqrt((Vn * Vn).sum(axis=0))
            wv = np.where(vlen > 0, vlen, 1.0) ** -self._alpha[:, None]  # (K, nv)
            hit = (A, A.T.copy(), np.abs(A).T.copy(), C, C.T.copy(), np.tile(Ew, (len(self.gain), 1, 1)),
                   np.abs(Ew).sum(axis=1), Vn, (Vn * wv[:, None, :]) @ Vn.T)
            self._models[key] = hit
        return hit

    def _advance(self, s: int, c: np.ndarray, G: np.ndarray, drive: np.ndarray,
                 y: "np.ndarray | None") -> tuple[np.ndarray, np.ndarray]:
        """The sets of ``x(s+1)`` (one per gain, stacked, not reduced) from the priors of ``x(s)``."""
        A, At, absAt, C, Ct, Ew, sEw, Vn, VWV = self._model(s)  # Ew stacked: (K, n, nw)
        AG = A @ G  # (K, n, q): every filter at once
        Ac = c @ At + drive
        absG = np.abs(G)
        mag = (np.abs(c) + absG.sum(axis=2)) @ absAt + np.abs(drive)
        if y is None:
            return self._finish(AG, Ac, Ew, sEw, mag)
        r = y - c @ Ct  # (K, p)
        CG = C @ G  # (K, p, q)
        CGt = CG.transpose(0, 2, 1)
        # generator weights (module docstring): 1 for the F-radius gain, 1/|(g_j, C g_j)|_2 for the reweighted one
        lengths = np.sqrt((G * G).sum(axis=1) + (CG * CG).sum(axis=1))  # (K, q)
        wq = np.where(lengths > 0, lengths, 1.0) ** -self._alpha[:, None]
        CGw = CG * wq[:, None, :]
        num = G @ CGw.transpose(0, 2, 1)  # (K, n, p): G W (CG)^T
        S = CGw @ CGt + VWV  # (K, p, p): H W H^T
        if S.shape[1] == 1:
            s00 = S[:, 0, :]
            Lam = num / np.where(s00 > 0, s00, np.inf)[:, None, :]  # a zero gain where nothing is measured
        else:  # S symmetric, positive definite when V has full row rank; least squares when singular
            try:
                Lam = np.linalg.solve(S, num.transpose(0, 2, 1)).transpose(0, 2, 1)
            except np.linalg.LinAlgError:
                Lam = np.stack([np.linalg.lstsq(S[k], num[k].T, rcond=None)[0].T for k in range(S.shape[0])])
        ALam = A @ Lam  # (K, n, p)
        P = np.concatenate([AG - ALam @ CG, -ALam @ Vn], axis=2)
        cp = Ac + (ALam @ r[:, :, None])[:, :, 0]
        sCG = np.abs(CG).sum(axis=2)  # (K, p)
        mag += (np.abs(ALam) @ (np.abs(r) + np.abs(y) + sCG)[:, :, None])[:, :, 0] \
            + (np.abs(Lam) @ sCG[:, :, None])[:, :, 0] @ absAt
        for k in self._interval:  # the per-row weighted-median gain (greedy; module docstring)
            P[k], cp[k], m2 = _interval_update(AG[k], Ac[k], CG[k], Vn, r[k], y)
            mag[k] = (np.abs(c[k]) + absG[k].sum(axis=1)) @ absAt + np.abs(drive) + m2
        return self._finish(P, cp, Ew, sEw, mag)

    def _finish(self, P: np.ndarray, cp: np.ndarray, Ew: np.ndarray, sEw: np.ndarray,
                mag: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Append the process noise and the rounding allowance (module docstring)."""
        K, n, k = P.shape
        q = k + Ew.shape[2] + n + 4
        mag = mag + np.abs(cp) + np.abs(P).sum(axis=2) + sEw
        pad = np.nextafter(4.0 * q * _U * mag, np.inf)  # (K, n)
        return cp, np.concatenate([P, Ew, pad[:, :, None] * self._eye], axis=2)

    def _reduced(self, G: np.ndarray, new_axes: bool) -> tuple[np.ndarray, "np.ndarray | None"]:
        """``G`` reduced to ``order · n`` generators per filter, and the principal axes used (``reduction="pca"``:
        computed again from ``G`` when ``new_axes`` or none yet, else those last computed; module docstring)."""
        if self._limit is None or G.shape[2] <= self._limit:
            return G, self._axes
        if self.reduction == "girard":
            return reduce_girard(G, self._limit), self._axes
        axes = principal_axes(G) if new_axes or self._axes is None else self._axes
        return reduce_pca(G, self._limit, axes=axes), axes

    def _report(self, c: np.ndarray, G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The estimate and per-state bound: per state, the centre and hull radius of the filter whose radius is
        the smallest (the first on a tie); module docstring."""
        beta = outer_row_sums(G)
        if c.shape[0] == 1:
            return c[0], beta[0]
        k, states = np.argmin(beta, axis=0), np.arange(c.shape[1])
        return c[k, states], beta[k, states]

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
        """One carried set, ``c + G ε`` with ``|ε| <= 1`` (copies): it contains ``x`` of the current time.

        Of the sets the filters carry (one per gain), the one with the smallest largest row sum (the first on a
        tie): the set to hand over to another estimator
        (:class:`eqrec.estimators.guaranteed.GuaranteedEstimator`).  The reported :attr:`x` and
        :attr:`state_bounds` take per state the tightest of them, which is never wider.
        """
        self.time  # noqa: B018 - raises before reset
        k = int(np.argmin(np.abs(self._G).sum(axis=2).max(axis=1)))
        return self._c[k].copy(), self._G[k].copy()

    @property
    def generators(self) -> np.ndarray:
        """A copy of the generators of every filter, shape ``(K, n, q)`` (``K`` gains, ``q <= order · n``)."""
        self.time  # noqa: B018 - raises before reset
        return self._G.copy()
