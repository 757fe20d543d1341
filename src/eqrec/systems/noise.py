r"""Noise descriptions of one system: the box, Gaussian second moments, multiplicative terms.

The deterministic part of every plant of the package is an
:class:`~eqrec.systems.affine.AffineSystem`,

.. math::
    x(t+1) = A(t) x(t) + B(t) u(t) + f + E(t) w(t), \qquad y(t) = C(t) x(t) + V(t) v(t);

what is known about the noise depends on the estimator family:

* **a box** (bounded-error designs): :math:`\|w\|_\infty \le \eta_w`,
  :math:`\|v\|_\infty \le \eta_v`, carried by the system itself
  (``system.eta_w``, ``system.eta_v``) with the initial-error level ``μ1`` of a design;
* **Gaussian second moments** (Kalman-type filters, LMV estimators):
  :class:`GaussianNoise` in the noise coordinates (``E[w wᵀ] = Qw``,
  ``E[v vᵀ] = Qv``, ``E[w vᵀ] = S``, the law of ``x(0)``), and
  :class:`GaussianDesign`, the same moments in the state and output
  coordinates a filter is designed with (``P0``, ``Q = E Qw Eᵀ``, ``R = V Qv Vᵀ``);
  :meth:`GaussianNoise.from_box` and :meth:`GaussianDesign.from_box` read
  a box as Gaussian statistics with the bound at ``5σ`` (the delayed-data
  paper's Fig. 1);
* **multiplicative terms** (the LMV companion study):
  :class:`MultiplicativeNoise`, ``A + ξ(t) A1`` and ``C + λ(t) C1`` with
  scalar white ``ξ``, ``λ``.

:class:`NoisySystem` puts the system and its noise descriptions together, so
that one plant runs under every family; the LMV study's
:class:`~eqrec.lmv.plant.Plant` is a loader of it in the paper's notation
(:meth:`~eqrec.lmv.plant.Plant.description`).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from eqrec.checks import positive
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


def check_psd(M: np.ndarray, name: str, source: str | None) -> None:
    """Raise :class:`~eqrec.errors.InputError` unless ``M`` is a symmetric positive semidefinite covariance.

    Parameters
    ----------
    M : numpy.ndarray
        Square matrix.
    name : str
        Field named in the error.
    source : str or None
        Where ``M`` came from (a file, a system name), named in the error.
    """
    if M.size == 0:  # no noise of this kind (e.g. a plant without process noise)
        return
    if not np.allclose(M, M.T, atol=1e-12 * max(1.0, np.abs(M).max())):
        raise InputError("covariance matrix is not symmetric", source, name)
    if np.linalg.eigvalsh(M).min() < -1e-10 * max(1.0, np.abs(M).max()):
        raise InputError("covariance matrix is not positive semidefinite", source, name)


def _array(value: Any, name: str, shape: tuple[int, ...], source: str | None = None) -> np.ndarray:
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"not a numeric array ({exc})", source, name) from None
    if arr.shape != shape:
        raise InputError(f"shape {arr.shape}, expected {shape}", source, name)
    if not np.all(np.isfinite(arr)):
        raise InputError("contains NaN or infinite entries", source, name)
    return arr


def _box_scale(system: Any, mu1: Any, sigmas: Any) -> tuple[float, float]:
    """``(mu1, sigmas)`` of a ``from_box`` checked (the system an :class:`AffineSystem`, the field named)."""
    if not isinstance(system, AffineSystem):
        raise InputError(f"expected an AffineSystem, got {type(system).__name__}", field="system")
    return positive(mu1, "mu1", zero_ok=True), positive(sigmas, "sigmas")


def _square(value: Any, name: str) -> np.ndarray:
    """A finite square matrix (a number is a 1x1 matrix)."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"not a numeric matrix ({exc})", None, name) from None
    arr = arr.reshape(1, 1) if arr.ndim == 0 else arr
    if arr.ndim != 2 or arr.shape[0] != arr.shape[1]:
        raise InputError(f"expected a square matrix, got shape {arr.shape}", None, name)
    return _array(arr, name, arr.shape)


@dataclass(frozen=True)
class GaussianDesign:
    """Second moments used to design the filters: ``P0`` (initial error), ``Q = E Qw Eᵀ``, ``R = V Rv Vᵀ``.

    Parameters
    ----------
    P0 : numpy.ndarray
        Covariance of the initial estimation error, ``(n, n)``.
    Q : numpy.ndarray
        Covariance of the process noise ``E w``, ``(n, n)``.
    R : numpy.ndarray
        Covariance of the measurement noise ``V v``, ``(p, p)``.
    """

    P0: np.ndarray
    Q: np.ndarray
    R: np.ndarray

    @classmethod
    def from_box(cls, system: AffineSystem, mu1: float, sigmas: float = 5.0) -> "GaussianDesign":
        """Standard deviations ``bound / sigmas`` for ``ξ0`` (``μ1``), ``w`` (``ηw``) and ``v`` (``ηv``).

        The delayed-data paper's Fig. 1 draws its noises so (``sigmas = 5``: a bound is five standard deviations).

        Parameters
        ----------
        system : AffineSystem
            The system: ``eta_w``, ``eta_v`` and the noise gains ``E``, ``V`` at time 0.
        mu1 : float
            Bound ``μ1`` of ``‖ξ0‖_∞``.
        sigmas : float, optional
            Number of standard deviations in a bound (default 5).

        Returns
        -------
        GaussianDesign
            Independent components: ``P0 = (mu1/sigmas)² I``, ``Q = (ηw/sigmas)² E Eᵀ``,
            ``R = (ηv/sigmas)² V Vᵀ``.

        Raises
        ------
        InputError
            A ``system`` that is not an :class:`AffineSystem`, ``mu1`` not a finite number >= 0, ``sigmas``
            not a positive one.
        """
        mu1, sigmas = _box_scale(system, mu1, sigmas)
        n = system.n
        E, V = system.E_at(0), system.V_at(0)
        return cls(P0=(mu1 / sigmas) ** 2 * np.eye(n), Q=(system.eta_w / sigmas) ** 2 * E @ E.T,
                   R=(system.eta_v / sigmas) ** 2 * V @ V.T)


@dataclass(frozen=True, eq=False)
class GaussianNoise:
    """Gaussian (second-moment) description of the noise of a system, in its noise coordinates.

    ``w(t)``, ``v(t)`` zero-mean and white with ``E[w wᵀ] = Qw``,
    ``E[v vᵀ] = Qv``, ``E[w vᵀ] = S``; ``x(0)`` of mean ``x0_mean`` and
    covariance ``x0_cov``, independent of the noise.

    Parameters
    ----------
    Qw : array_like, shape (nw, nw)
        Covariance of ``w``.
    Qv : array_like, shape (nv, nv)
        Covariance of ``v``.
    x0_cov : array_like, shape (n, n)
        Covariance of ``x(0)`` (of the initial error for an estimator started at the mean).
    x0_mean : array_like, shape (n,), optional
        Mean of ``x(0)`` (default zero).
    S : array_like, shape (nw, nv), optional
        Cross-covariance ``E[w vᵀ]`` (default zero).

    Raises
    ------
    InputError
        Wrong shapes, non-finite entries, or covariances (the joint one of ``(w, v)`` included) that are
        not symmetric positive semidefinite, naming the field.
    """

    Qw: np.ndarray
    Qv: np.ndarray
    x0_cov: np.ndarray
    x0_mean: np.ndarray | None = None
    S: np.ndarray | None = None

    def __post_init__(self) -> None:
        Qw, Qv, x0_cov = _square(self.Qw, "Qw"), _square(self.Qv, "Qv"), _square(self.x0_cov, "x0_cov")
        nw, nv, n = Qw.shape[0], Qv.shape[0], x0_cov.shape[0]
        fields = {"Qw": Qw, "Qv": Qv, "x0_cov": x0_cov,
                  "x0_mean": _array(np.zeros(n) if self.x0_mean is None else self.x0_mean, "x0_mean", (n,)),
                  "S": _array(np.zeros((nw, nv)) if self.S is None else self.S, "S", (nw, nv))}
        check_psd(x0_cov, "x0_cov", None)
        check_psd(Qw, "Qw", None)
        check_psd(Qv, "Qv", None)
        check_psd(np.block([[Qw, fields["S"]], [fields["S"].T, Qv]]), "S", None)
        for key, val in fields.items():
            val.flags.writeable = False
            object.__setattr__(self, key, val)

    @classmethod
    def from_box(cls, system: AffineSystem, mu1: float, sigmas: float = 5.0) -> "GaussianNoise":
        """Independent components with standard deviations ``bound / sigmas`` (``5σ`` = bound, as in P3's Fig. 1).

        Parameters
        ----------
        system : AffineSystem
            The system: its box ``eta_w``, ``eta_v`` and dimensions.
        mu1 : float
            Bound ``μ1`` of the initial error ``‖ξ0‖∞``.
        sigmas : float, optional
            Number of standard deviations in a bound (default 5).

        Returns
        -------
        GaussianNoise
            ``Qw = (ηw/σ)² I``, ``Qv = (ηv/σ)² I``, ``x0_cov = (μ1/σ)² I``, zero mean.
        """
        mu1, sigmas = _box_scale(system, mu1, sigmas)
        return cls(Qw=(system.eta_w / sigmas) ** 2 * np.eye(system.nw), Qv=(system.eta_v / sigmas) ** 2 * np.eye(system.nv),
                   x0_cov=(mu1 / sigmas) ** 2 * np.eye(system.n))

    def check(self, system: AffineSystem) -> None:
        """Raise :class:`~eqrec.errors.InputError` unless the dimensions fit ``system`` (``nw``, ``nv``, ``n``).

        Parameters
        ----------
        system : AffineSystem
            The system the noise drives.
        """
        for name, got, want in (("Qw", self.Qw.shape[0], system.nw), ("Qv", self.Qv.shape[0], system.nv),
                                ("x0_cov", self.x0_cov.shape[0], system.n)):
            if got != want:
                raise InputError(f"dimension {got} does not fit the system's {want}", system.name, name)

    def design(self, system: AffineSystem, t: int = 0) -> GaussianDesign:
        """The same moments in the state and output coordinates of ``system`` at time ``t``.

        Parameters
        ----------
        system : AffineSystem
            The system (its ``E(t)``, ``V(t)``).
        t : int, optional
            Time of the noise gains (default 0).

        Returns
        -------
        GaussianDesign
            ``P0 = x0_cov``, ``Q = E Qw Eᵀ``, ``R = V Qv Vᵀ``.
        """
        self.check(system)
        E, V = system.E_at(t), system.V_at(t)
        return GaussianDesign(P0=self.x0_cov.copy(), Q=E @ self.Qw @ E.T, R=V @ self.Qv @ V.T)


@dataclass(frozen=True, eq=False)
class MultiplicativeNoise:
    """Multiplicative terms: ``A + ξ(t) A1`` in the dynamics and ``C + λ(t) C1`` in the output.

    ``ξ`` and ``λ`` are scalar zero-mean white noises of variances ``Qxi`` and
    ``Qlam``, independent of each other and of ``w``, ``v`` (eqs. (1)-(2) of
    the LMV companion paper, whose ``Φ1``, ``H1`` are ``A1``, ``C1``).

    Parameters
    ----------
    A1 : array_like, shape (n, n)
        State matrix multiplied by ``ξ(t)``.
    C1 : array_like, shape (p, n)
        Output matrix multiplied by ``λ(t)``.
    Qxi : float
        Variance of ``ξ``.
    Qlam : float
        Variance of ``λ``.

    Raises
    ------
    InputError
        Wrong shapes, non-finite entries or negative variances, naming the field.
    """

    A1: np.ndarray
    C1: np.ndarray
    Qxi: float
    Qlam: float

    def __post_init__(self) -> None:
        A1 = _square(self.A1, "A1")
        n = A1.shape[0]
        try:
            C1 = np.atleast_2d(np.array(self.C1, dtype=float))
        except (TypeError, ValueError) as exc:
            raise InputError(f"not a numeric matrix ({exc})", None, "C1") from None
        C1 = _array(C1, "C1", (C1.shape[0] if C1.ndim == 2 else -1, n))
        for name in ("Qxi", "Qlam"):
            try:
                val = float(getattr(self, name))
            except (TypeError, ValueError):
                raise InputError("must be a number", None, name) from None
            if not np.isfinite(val) or val < 0:
                raise InputError(f"variance must be finite and >= 0, got {val}", None, name)
            object.__setattr__(self, name, val)
        object.__setattr__(self, "A1", A1)
        object.__setattr__(self, "C1", C1)


@dataclass(frozen=True, eq=False)
class NoisySystem:
    """One plant for every estimator family: the deterministic system with its noise descriptions.

    Parameters
    ----------
    system : AffineSystem
        The deterministic part ``A, B, C, E, V, f`` (possibly time-varying) and the box ``eta_w``, ``eta_v``.
    gaussian : GaussianNoise or None, optional
        Second moments of ``w``, ``v``, ``x(0)`` (``None``: none given).
    multiplicative : MultiplicativeNoise or None, optional
        Multiplicative terms (``None``: none).

    Raises
    ------
    InputError
        A description whose dimensions do not fit the system.
    """

    system: AffineSystem
    gaussian: GaussianNoise | None = None
    multiplicative: MultiplicativeNoise | None = None

    def __post_init__(self) -> None:
        sysm = self.system
        if self.gaussian is not None:
            self.gaussian.check(sysm)
        mult = self.multiplicative
        if mult is not None and (mult.A1.shape != (sysm.n, sysm.n) or mult.C1.shape != (sysm.p, sysm.n)):
            raise InputError(f"multiplicative terms of shapes {mult.A1.shape}, {mult.C1.shape} do not fit "
                             f"n = {sysm.n}, p = {sysm.p}", sysm.name, "multiplicative")

    def design(self, t: int = 0) -> GaussianDesign:
        """The Gaussian statistics a Kalman-type filter is designed with (:meth:`GaussianNoise.design`).

        Parameters
        ----------
        t : int, optional
            Time of the noise gains (default 0).

        Returns
        -------
        GaussianDesign
            ``P0``, ``Q``, ``R``.

        Raises
        ------
        InputError
            When the description has no Gaussian part.
        """
        if self.gaussian is None:
            raise InputError("no Gaussian description (give covariances, or GaussianNoise.from_box)",
                             self.system.name, "gaussian")
        return self.gaussian.design(self.system, t)
