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

import numpy as np

from eqrec.bounds.data_classes import ClassGains, class_error_map
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
        self.gain = steps.gains.K[index]
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
            self._parts = self._steps.maps.parts(*self.key)
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
