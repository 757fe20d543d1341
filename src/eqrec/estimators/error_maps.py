r"""The error maps of the class form, for the exact run-time bound (:mod:`eqrec.bounds.zonotope`).

In a period that starts at absolute time ``s`` with the estimate
:math:`\hat x(s)`, the class estimate of depth ``d`` with the data ``S``
(:class:`eqrec.estimators.causal.ClassEstimator`) has the error

.. math:: \xi(s+d) = G_{d,S}\,\delta, \qquad G_{d,S} = E_d - K_{d,S} Z_S,
    \qquad \delta = (w, v, \xi(s)),

(:func:`eqrec.bounds.data_classes.class_error_map`).  Split into its columns,
this is an :class:`~eqrec.bounds.zonotope.ErrorMap` anchored at the period's
start: :math:`\Phi = G^{\xi_0}_{d,S}` and the noise columns
:math:`N = G^{w,v}_{d,S}\,\operatorname{diag}(r)` (``r`` the noise radii).  The
period's noise ``w(s..s+T-1)``, ``v(s..s+T-1)`` is independent of
:math:`\xi(s)`, and packets stamped before ``s`` are not used in the period, so
:class:`~eqrec.bounds.zonotope.ErrorSet` gives the exact error set of every
estimate, across periods, with no box reset.
"""

from __future__ import annotations

import numba
import numpy as np

from eqrec.bounds.data_classes import ClassGains, class_error_map
from eqrec.bounds.rounding_kernels import allowance_tail, injection_bound
from eqrec.bounds.stacking import Stacking
from eqrec.bounds.zonotope import ErrorMap
from eqrec.errors import InputError
from eqrec.systems.affine import AffineSystem


class ClassErrorMaps:
    r"""The :class:`~eqrec.bounds.zonotope.ErrorMap` of every class of a design, computed on first use (module docstring).

    Parameters
    ----------
    system : AffineSystem
        The model (its noise bounds give the radii).
    gains : ClassGains
        The design's class gains.
    """

    def __init__(self, system: AffineSystem, gains: ClassGains):
        self.system, self.gains = system, gains
        self.stacking = Stacking(system, gains.horizon)
        lay = self.stacking.layout
        self._cut = lay.xi0.start
        self.radius = lay.radius(system.eta_w, system.eta_v, 0.0)[: self._cut]
        self._parts: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @classmethod
    def of(cls, system: AffineSystem, gains: ClassGains) -> "ClassErrorMaps":
        """The maps of these gains on this system, built once and kept on the gains (every estimator of a
        design, every reset and every return to the design share them).

        Parameters
        ----------
        system : AffineSystem
            The model.
        gains : ClassGains
            The design's class gains.

        Returns
        -------
        ClassErrorMaps
            The shared maps.
        """
        return _kept_on(gains, "_error_maps", system, cls)

    def parts(self, depth: int, available: tuple[int, ...]) -> tuple[np.ndarray, np.ndarray]:
        r"""``(Φ, N)`` of the class ``(depth, available)``.

        Parameters
        ----------
        depth : int
            Period time of the estimate (``1..T``).
        available : tuple of int
            Period times of the measurements received.

        Returns
        -------
        state : ndarray, shape (n, n)
            :math:`G^{\xi_0}_{d,S}`.
        noise : ndarray, shape (n, T (nw + nv))
            :math:`G^{w,v}_{d,S}\operatorname{diag}(r)`, the columns of zero radius dropped.

        Raises
        ------
        InputError
            The design has no such class.
        """
        i = self.gains.classes.index(depth, available)
        if i not in self._parts:
            G = class_error_map(self.stacking, self.gains, i)
            live = self.radius > 0
            self._parts[i] = (G[:, self._cut:], G[:, : self._cut][:, live] * self.radius[live])
        return self._parts[i]

    def error_map(self, start: int, depth: int, available: tuple[int, ...]) -> ErrorMap:
        """The error map of the class estimate of a period that started at absolute time ``start``.

        Parameters
        ----------
        start : int
            Absolute time of the period's start (the anchor).
        depth : int
            Period time of the estimate.
        available : tuple of int
            Period times of the measurements received.

        Returns
        -------
        ErrorMap
            Anchored at ``start``.
        """
        state, noise = self.parts(depth, available)
        return ErrorMap(int(start), state, noise)


class RoundingMaps:
    r"""The absolute class maps with identity noise gains: how a rounding injected into the state or a measurement
    reaches the class estimate's error (the rounding allowance of :mod:`eqrec.estimators.intake`).

    A rounding error of the prediction :math:`\bar x(j+1)` or of a simulated :math:`x(j+1)` enters the error
    :math:`\xi = x - \hat x` exactly as a process noise with ``E = I`` would, and one of a residual or of a
    simulated :math:`y(\tau)` as a measurement noise with ``V = I``; so the class map of the system with
    identity noise gains, :math:`G = E_d - K Z_S` over ``(w, v, ξ0)``, carries them (and the previous period's
    allowance through its :math:`\xi_0` columns) exactly.

    Parameters
    ----------
    system : AffineSystem
        The model.
    gains : ClassGains
        The design's class gains.
    """

    def __init__(self, system: AffineSystem, gains: ClassGains):
        n, p = system.n, system.p
        self.system = system
        unit = AffineSystem(A=system.A, C=system.C, E=np.eye(n), eta_w=1.0, eta_v=1.0, V=np.eye(p))
        self._maps = ClassErrorMaps(unit, gains)
        self._parts: dict = {}

    @classmethod
    def of(cls, system: AffineSystem, gains: ClassGains) -> "RoundingMaps":
        """The maps of these gains on this system, built once and kept on the gains.

        Parameters
        ----------
        system : AffineSystem
            The model.
        gains : ClassGains
            The design's class gains.

        Returns
        -------
        RoundingMaps
            The shared maps.
        """
        return _kept_on(gains, "_rounding_maps", system, cls)

    def absolute(self, depth: int, available: tuple[int, ...]) -> np.ndarray:
        """``|G|`` of the class ``(depth, available)`` with identity noise gains, columns ``(w, v, ξ0)``.

        Parameters
        ----------
        depth : int
            Period time of the estimate.
        available : tuple of int
            Period times of the measurements received.

        Returns
        -------
        ndarray, shape (n, T (n + p) + n)
            The absolute class map.
        """
        key = (depth, available)
        hit = self._parts.get(key)
        if hit is None:
            state, noise = self._maps.parts(depth, available)
            hit = self._parts[key] = np.abs(np.concatenate([noise, state], axis=1))
        return hit


class ClassStep:
    r"""What the class form needs at a step of the class ``(depth, available)``, each computed on first use and
    kept (:class:`ClassSteps`): the gain ``K``, its absolute values, the rounding allowance's absolute map and the
    error map's parts.  Functions of the class alone, never of a measured value, so keeping them changes no number.

    Parameters
    ----------
    steps : ClassSteps
        The cache it belongs to.
    depth : int
        Period time of the estimate.
    available : tuple of int
        Period times of the measurements received (increasing).
    index : int
        Position of the class in the design's classes.

    Attributes
    ----------
    index : int
        Position of the class.
    gain : numpy.ndarray, shape (n, |S| p)
        ``K`` of the class.
    data : numpy.ndarray of int64
        ``S``, the period times of the class's data (increasing), as the compiled step takes them.
    """

    __slots__ = ("_steps", "key", "index", "gain", "data", "_abs_gain", "_rounding", "_parts", "_kernel")

    def __init__(self, steps: "ClassSteps", depth: int, available: tuple[int, ...], index: int):
        self._steps, self.key, self.index = steps, (depth, available), index
        self.gain = blas_ready(steps.gains.K[index])
        self.data = np.array(available, dtype=np.int64)
        self._abs_gain = self._rounding = self._parts = self._kernel = None

    @property
    def kernel(self) -> tuple:
        """What the compiled steps take of the class, in their order: ``K``, ``|K|``, ``S`` (:attr:`data`), the
        rounding map, and the error map's parts ``(Φ, N)`` (:func:`class_step` takes the first four)."""
        if self._kernel is None:
            self._kernel = (self.gain, self.abs_gain, self.data, self.rounding_map) + self.parts
        return self._kernel

    @property
    def abs_gain(self) -> np.ndarray:
        """``|K|`` of the class."""
        if self._abs_gain is None:
            self._abs_gain = np.abs(self.gain)
        return self._abs_gain

    @property
    def rounding_map(self) -> np.ndarray:
        """:meth:`RoundingMaps.absolute` of the class."""
        if self._rounding is None:
            self._rounding = self._steps.rounding.absolute(*self.key)
        return self._rounding

    @property
    def parts(self) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`ClassErrorMaps.parts` of the class, ``(Φ, N)``."""
        if self._parts is None:
            state, noise = self._steps.maps.parts(*self.key)
            # Φ is a column block of the class map: a copy in C order for the compiled product (BLAS computes the
            # same numbers from a row-major block with a longer row stride, so nothing changes)
            self._parts = (blas_ready(state), blas_ready(noise))
        return self._parts


def _per_rule(store: dict, rule) -> dict:
    """The dictionary ``store`` keeps for ``rule`` (made empty on first use; past 8 rules all are forgotten and
    the count starts again), or a new one not kept if ``rule`` cannot be hashed."""
    try:
        kept = store.get(rule)
        if kept is None:
            if len(store) >= 8:  # a bounded number of rules per design
                store.clear()
            kept = store[rule] = {}
    except TypeError:
        return {}
    return kept


class ClassSteps:
    r"""Per class of a design, its :class:`ClassStep`, made on first use and kept (a design has finitely many
    classes, so the cache is bounded by their number); one lookup per step instead of one per quantity.

    Parameters
    ----------
    system : AffineSystem
        The model.
    gains : ClassGains
        The design's class gains.
    """

    def __init__(self, system: AffineSystem, gains: ClassGains):
        self.system, self.gains = system, gains
        self._entries: dict = {}
        self._maps: "ClassErrorMaps | None" = None
        self._rounding: "RoundingMaps | None" = None
        self._levels: dict = {}
        self._prefixes: dict = {}

    @classmethod
    def of(cls, system: AffineSystem, gains: ClassGains) -> "ClassSteps":
        """The cache of these gains on this system, built once and kept on the gains.

        Parameters
        ----------
        system : AffineSystem
            The model.
        gains : ClassGains
            The design's class gains.

        Returns
        -------
        ClassSteps
            The shared cache.
        """
        return _kept_on(gains, "_class_steps", system, cls)

    @property
    def maps(self) -> ClassErrorMaps:
        """The design's :class:`ClassErrorMaps` (shared)."""
        if self._maps is None:
            self._maps = ClassErrorMaps.of(self.system, self.gains)
        return self._maps

    @property
    def rounding(self) -> RoundingMaps:
        """The design's :class:`RoundingMaps` (shared)."""
        if self._rounding is None:
            self._rounding = RoundingMaps.of(self.system, self.gains)
        return self._rounding

    def levels(self, rule) -> dict:
        """The levels looked up with ``rule`` (observed prefix -> level), kept here for every estimator of these
        gains whose rule is equal (:class:`eqrec.design.result.ClassLevels` of one design are), so that a new
        estimator of a design does not look them up again (:meth:`eqrec.estimators.intake.StampedEstimator._level`).

        Parameters
        ----------
        rule : callable
            The estimator's ``bound_of``.

        Returns
        -------
        dict
            The shared levels of ``rule`` (a new dict if ``rule`` cannot be hashed).
        """
        return _per_rule(self._levels, rule)

    def prefixes(self, rule) -> dict:
        """Per observed arrival prefix of a period (a tuple), its class and level, kept here for every estimator of
        these gains with an equal rule (``None`` included): one lookup per step for both
        (:meth:`eqrec.estimators.causal.ClassEstimator._lookup`).  Functions of the prefix alone, so keeping them
        changes no number; a period has finitely many prefixes.

        Parameters
        ----------
        rule : callable or None
            The estimator's ``bound_of``.

        Returns
        -------
        dict
            The shared prefixes of ``rule`` (a new dict if ``rule`` cannot be hashed).
        """
        return _per_rule(self._prefixes, rule)

    def get(self, depth: int, available: tuple[int, ...]) -> "ClassStep | None":
        """The class ``(depth, available)`` (``available`` increasing), or ``None`` if the design has none.

        Parameters
        ----------
        depth : int
            Period time of the estimate.
        available : tuple of int
            Period times of the measurements received, increasing.

        Returns
        -------
        ClassStep or None
            The kept entry.
        """
        key = (depth, available)
        hit = self._entries.get(key)
        if hit is None:
            try:
                index = self.gains.classes.index(depth, available)
            except InputError:  # no such class: data outside the design (not kept: the language is what is kept)
                return None
            hit = self._entries[key] = ClassStep(self, depth, available, index)
        return hit


def _kept_on(gains: ClassGains, key: str, system: AffineSystem, make):
    """``make(system, gains)``, built once per system and kept on the gains under ``key``."""
    kept = gains.__dict__.get(key)
    if kept is None or kept.system is not system:
        kept = gains.__dict__[key] = make(system, gains)
    return kept


def blas_ready(M: np.ndarray) -> np.ndarray:
    """``M`` as the compiled products take it (C or Fortran order) with the numbers NumPy's product of ``M`` gives.

    NumPy hands BLAS a matrix with one unit stride as it is (row- or column-major, with its leading dimension);
    a C- or Fortran-ordered copy of the same orientation is multiplied by the same BLAS kernel in the same order,
    so :func:`class_step`'s products equal NumPy's ``M @ x`` bit for bit (``tests/test_class_step_cache.py``).

    Parameters
    ----------
    M : numpy.ndarray, shape (n, k)
        A float matrix.

    Returns
    -------
    numpy.ndarray
        ``M`` itself when C- or Fortran-contiguous, else a copy in the order of its unit stride (C otherwise).
    """
    M = np.asarray(M, dtype=float)
    if M.flags.c_contiguous or M.flags.f_contiguous:
        return M
    if M.ndim == 2 and M.strides[0] == M.itemsize and M.shape[0] > 1:
        return np.asfortranarray(M)
    return np.ascontiguousarray(M)


@numba.njit(cache=True)
def matrix_vector(M, x):  # pragma: no cover - compiled
    """``M @ x`` with NumPy's numbers: BLAS ``gemv`` (as NumPy's matmul), the one row's ``dot`` for one row (as
    NumPy), zeros for no column."""
    n, k = M.shape
    if k == 0:
        return np.zeros(n)
    if n == 1:
        out = np.empty(1)
        out[0] = np.dot(np.ascontiguousarray(M[0]), x)  # a row of a Fortran matrix: typed non-contiguous
        return out
    return np.dot(M, x)


def period_layout(T: int, n: int, p: int) -> tuple[int, int, int, int]:
    """The lengths of the parts of a class estimator's period buffer, in order: the reference states ``(T, n)``, the
    residuals ``(T, p)``, the record's injections ``z`` (``T (n + p) + n``) and the true state's magnitudes
    ``(T, n)`` (:func:`period_views`).

    Parameters
    ----------
    T, n, p : int
        Period, state and output dimensions.

    Returns
    -------
    tuple of int
        The four lengths.
    """
    return T * n, T * p, T * (n + p) + n, T * n


@numba.njit(cache=True)
def period_views(period, T, n, p):  # pragma: no cover - compiled
    """The parts of a period buffer (:func:`period_layout`) as views: ``refs (T, n)``, ``res (T, p)``, ``z`` and
    ``true (T, n)``."""
    a = T * n
    b = a + T * p
    c = b + T * (n + p) + n
    return period[:a].reshape((T, n)), period[a:b].reshape((T, p)), period[b:c], period[c:c + T * n].reshape((T, n))


def model_buffer(absA: np.ndarray, vecs: np.ndarray, absC: np.ndarray, v: np.ndarray, Cs: np.ndarray,
                 output_terms: int, state_terms: int, factor: float) -> np.ndarray:
    """The parts of the model :func:`class_step` reads, end to end in one array (one argument of the compiled call
    instead of eight; :func:`model_views` reads them back): the period ``T``, the outputs ``p``, the ``terms`` of
    an output and of a state injection and the allowance's factor, then ``|A|``, the rows ``vecs``, ``|C(τ)|``,
    ``|V(τ)| η_v 1`` and ``C(τ)``, each row-major (the same numbers; ``C(τ)`` row-major as given, so its product
    is NumPy's).

    Parameters
    ----------
    absA : numpy.ndarray, shape (n, n)
        ``|A(t)|``.
    vecs : numpy.ndarray, shape (4, n)
        The rows of :func:`class_step`'s ``vecs``.
    absC, v, Cs : numpy.ndarray
        ``|C(τ)|``, ``|V(τ)| η_v 1`` and ``C(τ)`` per period time (``(T, p, n)``, ``(T, p)``, ``(T, p, n)``).
    output_terms, state_terms : int
        The ``terms`` of an output injection and of the state update's.
    factor : float
        The allowance's factor.

    Returns
    -------
    numpy.ndarray, shape (5 + n² + 4n + T p (2n + 1),)
        The buffer (the integers are exact in floating point).
    """
    T, p = v.shape
    head = np.array([T, p, output_terms, state_terms, factor], dtype=float)
    return np.concatenate([head] + [np.ascontiguousarray(M, dtype=float).ravel() for M in (absA, vecs, absC, v, Cs)])


@numba.njit(cache=True)
def model_views(fixed, n):  # pragma: no cover - compiled
    """The parts of a :func:`model_buffer` as views: ``absA (n, n)``, ``vecs (4, n)``, ``absC (T, p, n)``,
    ``v (T, p)``, ``Cs (T, p, n)``, and ``output_terms``, ``state_terms``, ``factor``."""
    T, p = int(fixed[0]), int(fixed[1])
    a = 5 + n * n
    b = a + 4 * n
    c = b + T * p * n
    d = c + T * p
    return (fixed[5:a].reshape((n, n)), fixed[a:b].reshape((4, n)), fixed[b:c].reshape((T, p, n)),
            fixed[c:d].reshape((T, p)), fixed[d:d + T * p * n].reshape((T, p, n)), int(fixed[2]), int(fixed[3]),
            fixed[4])


@numba.njit(cache=True)
def class_step(A, B, absB, fixed, period, K, absK, S, rounding_map, u, rows, radius, t, taus, ys,
               out):  # pragma: no cover - compiled
    r"""One step of the class form (:class:`eqrec.estimators.causal.ClassEstimator`) in one compiled call, from the
    packets as they arrived: the residuals of the new packets, the stacked data of the class, the estimate and its
    rounding allowance, by the operations of the uncompiled step (BLAS products as NumPy's ``@``,
    :func:`eqrec.bounds.rounding_kernels.injection_bound` and :func:`eqrec.bounds.rounding_kernels.allowance_tail`), so the same
    numbers.

    .. math:: r_\tau = y(\tau) - C(\tau)\,\mathrm{ref}(\tau), \qquad \bar x(t+1) = A\bar x_0 + B u + f,
        \qquad \hat x(t+1) = \bar x(t+1) + K (r_\tau)_{\tau \in S}, \qquad \rho = |G| z + \iota, \text{ rounded up},

    with ``z`` the period's injections (:mod:`eqrec.estimators.intake`): this step enters the true state's
    magnitude ``|x̂(t)| + radius``, the output injections of its new packets and its state update's injection,
    and :math:`\iota` is that of ``x̄ + K r``.  Called only for a step that commits (its class is known): it writes
    the period's arrays in place (the reference of time ``t``, the residuals of the new packets, the record).

    Parameters
    ----------
    A, B : numpy.ndarray
        ``A(t)``, ``B(t)`` as :func:`blas_ready` gives them.
    absB : numpy.ndarray
        ``|B(t)|`` (in its own memory order: NumPy's product of it).
    fixed : numpy.ndarray
        The rest of the model (:func:`model_buffer`): ``|A(t)|``; the rows ``vecs`` = ``f``, ``|E| η_w 1``,
        ``|f|`` and ``|E| η_w 1 + 2 |f|`` (the magnitude without input); ``|C(τ)|``, ``|V(τ)| η_v 1`` and
        ``C(τ)`` per period time (``(T, p, n)``, ``(T, p)``, ``(T, p, n)``); the ``terms`` of an output injection
        and of the state update's; the allowance's factor ``1 + (2n + 8) u``.
    period : numpy.ndarray
        The period's state end to end (:func:`period_layout`): the reference states ``(T, n)`` (row ``t``
        written), the residuals ``(T, p)`` (rows ``taus`` written) and the record
        (:class:`eqrec.estimators.intake.RoundingRecord`): its injections ``w``, ``v``, ``ρ(s)`` (``z``) and the
        magnitudes of the true state ``(T, n)`` (started again when ``t = 0``).
    K, absK : numpy.ndarray
        The class gain and ``|K|``.
    S : numpy.ndarray of int64
        The period times of the class's data, increasing.
    rounding_map : numpy.ndarray, shape (n, len(z))
        ``|G|`` of the class with identity noise gains (:class:`RoundingMaps`).
    u : numpy.ndarray, shape (m,)
        The checked input.
    rows : numpy.ndarray, shape (3, n)
        ``x̄(t)``, ``x̂(t)`` and the allowance ``ρ`` of ``x̂(t)`` (the ``out`` of the step before, or made at a reset).
        The reference state of time ``t`` is ``x̄(t)``, or ``x̂(t)`` at a period's start (``t = 0``); ``ρ`` starts a
        new period's record.
    radius : float
        The true error's size assumed by the magnitudes.
    t : int
        The period time of the step.
    taus : numpy.ndarray of int64
        The period times of the packets first received at this step.
    ys : numpy.ndarray, shape (len(taus) p,)
        Their measurements end to end.
    out : numpy.ndarray, shape (3, n)
        Where ``x̄(t+1)``, ``x̂(t+1)`` and ``ρ`` are written (rows; one new array per step: its rows are what the
        estimator keeps, and returning three arrays from a compiled call costs more than writing them).

    Returns
    -------
    float
        ``max(0, max ρ)``.
    """
    n = rows.shape[1]
    absA, vecs, absC, v, Cs, output_terms, state_terms, factor = model_views(fixed, n)
    T, p = absC.shape[0], absC.shape[1]
    xhat = rows[1]
    xbar0 = xhat if t == 0 else rows[0]
    refs, res, z, true = period_views(period, T, n, p)
    if t == 0:  # a new period's record: no injection yet, ρ(s) the allowance of the estimate it starts from
        z[:] = 0.0
        z[T * (n + p):] = rows[2]
        true[:] = 0.0
    w_record = z[:T * n].reshape((T, n))
    v_record = z[T * n:T * (n + p)].reshape((T, p))
    refs[t] = xbar0  # the state whose predicted output the measurements of time t are compared with
    for i in range(n):
        true[t, i] = abs(xhat[i]) + radius  # |x(t)| <= |x̂(t)| + bound
    for j in range(taus.shape[0]):
        tau = taus[j]
        res[tau] = ys[j * p:(j + 1) * p] - matrix_vector(Cs[tau], refs[tau])  # y(τ) − C(τ) ref(τ), as NumPy's
        v_record[tau] = injection_bound(absC[tau], refs[tau], 2.0, true[tau], res[tau], v[tau], output_terms)
    xbar = matrix_vector(A, xbar0) + matrix_vector(B, u) + vecs[0]
    k = S.shape[0]
    has_data = k > 0
    if has_data:
        r = np.empty(k * p)  # the class's data stacked in time order (NumPy's concatenate: copies)
        for i in range(k):
            r[i * p:(i + 1) * p] = res[S[i]]
        xhat_new = xbar + matrix_vector(K, r)
    else:
        r = np.zeros(0)
        xhat_new = xbar.copy()
    use_u = False
    for j in range(absB.shape[1]):
        if u[j] != 0.0:  # u.any()
            use_u = True
    if use_u:
        add = vecs[1] + 2.0 * (matrix_vector(absB, np.abs(u)) + vecs[2])
    else:  # without input (u = 0: |B| |u| = 0 exactly) the magnitude is e + 2 |f|: the same numbers
        add = vecs[3]
    zeros_n = np.zeros(n)
    # the state update's reference is x̄0 itself (the reference state of the step's time, ClassEstimator._reference)
    w_record[t] = injection_bound(absA, xbar0, 1.0, true[t], zeros_n, add, state_terms)
    if has_data:
        extra = injection_bound(absK, r, 1.0, np.zeros(r.shape[0]), xbar, zeros_n, k * p + 2)
    else:
        extra = np.zeros(n)
    rho, top = allowance_tail(matrix_vector(rounding_map, z), extra, factor)
    out[0] = xbar
    out[1] = xhat_new
    out[2] = rho
    return top
