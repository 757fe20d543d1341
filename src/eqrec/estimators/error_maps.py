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
from eqrec.bounds.rounding import allowance_tail, injection_bound
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
    """

    __slots__ = ("_steps", "key", "index", "gain", "_abs_gain", "_rounding", "_parts")

    def __init__(self, steps: "ClassSteps", depth: int, available: tuple[int, ...], index: int):
        self._steps, self.key, self.index = steps, (depth, available), index
        self.gain = blas_ready(steps.gains.K[index])
        self._abs_gain = self._rounding = self._parts = None

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
        try:
            kept = self._levels.get(rule)
            if kept is None:
                if len(self._levels) >= 8:  # a bounded number of rules per design
                    self._levels.clear()
                kept = self._levels[rule] = {}
        except TypeError:
            return {}
        return kept

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


@numba.njit(cache=True)
def class_step(A, xbar0, B, u, f, K, r, has_data, xhat, radius, t, true, taus, references, residuals, absC, v,
               output_terms, v_record, absA, absB, e, absf, drift, has_input, state_terms, w_record, absK, data_terms,
               rounding_map, z, factor, out):  # pragma: no cover - compiled
    r"""One step of the class form (:class:`eqrec.estimators.causal.ClassEstimator`) in one compiled call: the
    estimate and its rounding allowance, by the operations of the uncompiled step (BLAS products as NumPy's
    ``@``, :func:`eqrec.bounds.rounding.injection_bound` and :func:`eqrec.bounds.rounding.allowance_tail`), so the
    same numbers.

    .. math:: \bar x(t+1) = A\bar x_0 + B u + f, \qquad \hat x(t+1) = \bar x(t+1) + K r,
        \qquad \rho = |G| z + \iota, \text{ rounded up},

    with ``z`` the period's injections (:mod:`eqrec.estimators.intake`): this step enters the true state's
    magnitude ``|x̂(t)| + radius``, the output injections of its new packets and its state update's injection,
    and :math:`\iota` is that of ``x̄ + K r``.

    Parameters
    ----------
    A, xbar0, B, u, f : numpy.ndarray
        The prediction :math:`A\bar x_0 + B u + f` (``A``, ``B`` as :func:`blas_ready` gives them).
    K, r : numpy.ndarray
        The class gain and the stacked residuals of its data (used when ``has_data``).
    has_data : bool
        Whether the class has data.
    xhat : numpy.ndarray, shape (n,)
        The estimate of the step's time.
    radius : float
        The true error's size assumed by the magnitudes.
    t : int
        The period time of the step.
    true : numpy.ndarray, shape (T, n)
        The record's magnitudes of the true state (row ``t`` written).
    taus, references, residuals : numpy.ndarray
        The period times of the packets first received at this step, their reference states ``(k, n)`` and
        residuals ``(k, p)``.
    absC, v : numpy.ndarray
        ``|C(τ)|`` and ``|V(τ)| η_v 1`` per period time (``(T, p, n)``, ``(T, p)``).
    output_terms : int
        The ``terms`` of an output injection.
    v_record : numpy.ndarray, shape (T, p)
        The record's output injections (rows ``taus`` written).
    absA, absB, e, absf, drift : numpy.ndarray
        ``|A|``, ``|B|``, ``|E| η_w 1``, ``|f|`` and ``e + 2 |f|`` (the magnitude without input).
    has_input : bool
        Whether the model has inputs (then a nonzero ``u`` enters the magnitude).
    state_terms, data_terms : int
        The ``terms`` of the state update's and of ``x̄ + K r``'s injections.
    w_record : numpy.ndarray, shape (T, n)
        The record's state-update injections (row ``t`` written).
    absK : numpy.ndarray
        ``|K|``.
    rounding_map : numpy.ndarray, shape (n, len(z))
        ``|G|`` of the class with identity noise gains (:class:`RoundingMaps`).
    z : numpy.ndarray
        The period's injections, ``w``, ``v``, ``ρ(s)`` (:class:`eqrec.estimators.intake.RoundingRecord`).
    factor : float
        ``1 + (2n + 8) u``.
    out : numpy.ndarray, shape (3, n)
        Where ``x̄(t+1)``, ``x̂(t+1)`` and ``ρ`` are written (rows; one new array per step: its rows are what the
        estimator keeps, and returning three arrays from a compiled call costs more than writing them).

    Returns
    -------
    float
        ``max(0, max ρ)``.
    """
    n = xbar0.shape[0]
    for i in range(n):
        true[t, i] = abs(xhat[i]) + radius  # |x(t)| <= |x̂(t)| + bound
    for j in range(taus.shape[0]):
        tau = taus[j]
        v_record[tau] = injection_bound(absC[tau], references[j], 2.0, true[tau], residuals[j], v[tau],
                                        output_terms)
    xbar = matrix_vector(A, xbar0) + matrix_vector(B, u) + f
    if has_data:
        xhat_new = xbar + matrix_vector(K, r)
    else:
        xhat_new = xbar.copy()
    use_u = False
    if has_input:
        for j in range(u.shape[0]):
            if u[j] != 0.0:  # u.any()
                use_u = True
    if use_u:
        add = e + 2.0 * (matrix_vector(absB, np.abs(u)) + absf)
    else:  # without input (u = 0: |B| |u| = 0 exactly) the magnitude is e + 2 |f|: the same numbers
        add = drift
    zeros_n = np.zeros(n)
    # the state update's reference is x̄0 itself (the reference state of the step's time, ClassEstimator._reference)
    w_record[t] = injection_bound(absA, xbar0, 1.0, true[t], zeros_n, add, state_terms)
    if has_data:
        extra = injection_bound(absK, r, 1.0, np.zeros(r.shape[0]), xbar, zeros_n, data_terms)
    else:
        extra = np.zeros(n)
    rho, top = allowance_tail(matrix_vector(rounding_map, z), extra, factor)
    out[0] = xbar
    out[1] = xhat_new
    out[2] = rho
    return top
