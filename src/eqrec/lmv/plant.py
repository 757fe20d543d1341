"""The plant of the LMV companion study, eqs. (1)-(2) of the paper: a loader of the package's one system description.

:class:`Plant` holds the matrices and variances in the paper's notation; :meth:`Plant.from_dict`
builds it from a configuration mapping (``config/p4.yaml``; :func:`plant_of` picks
a named example) and checks shapes, finiteness and positive semidefiniteness.  :meth:`Plant.description` is
the same plant as the package's one description, a :class:`~eqrec.systems.noise.NoisySystem` (the
:class:`~eqrec.systems.affine.AffineSystem` ``A = Φ``, ``C = H``, ``E = Γ``, ``V = I`` with Gaussian and
multiplicative noise), and :meth:`Plant.from_description` reads any such description (an affine system with
Gaussian noise, e.g. a bounded-error plant with ``5σ`` = bound) as a plant, so that the LMV estimators run on
the plants of the other families.  The mathematics on the plant (its two compensated systems, the recursion) is
in :mod:`eqrec.lmv.model` and :mod:`eqrec.lmv.recursion`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from eqrec.systems.noise import GaussianNoise, MultiplicativeNoise, NoisySystem, check_psd
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

__all__ = ["Plant", "check_psd", "plant_of"]


def _mat(value: Any, name: str, shape: tuple[int | None, int | None] | None = None,
         source: str | None = None) -> np.ndarray:
    """A finite 2-D float array (scalars -> 1x1, vectors -> columns for gains)."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"not a numeric matrix ({exc})", source, name) from None
    if arr.ndim == 0:
        arr = arr.reshape(1, 1)
    elif arr.ndim == 1:
        arr = arr.reshape(-1, 1) if name in ("Gamma", "sigma0") else arr.reshape(1, -1)
    if arr.ndim != 2:
        raise InputError(f"expected a matrix, got {arr.ndim} dimensions", source, name)
    if not np.all(np.isfinite(arr)):
        raise InputError("contains NaN or infinite entries", source, name)
    if shape is not None:
        for got, want in zip(arr.shape, shape):
            if want is not None and got != want:
                raise InputError(f"shape {arr.shape} does not fit, expected {shape}", source, name)
    return arr


@dataclass(frozen=True)
class Plant:
    """The plant of eqs. (1)-(2) of the paper.

    ``x(t+1) = (Phi + xi(t) Phi1) x(t) + Gamma w(t)``,
    ``y(t) = (H + lambda(t) H1) x(t) + v(t)``, with scalar white ``xi``,
    ``lambda`` of variances ``Qxi``, ``Qlam``; ``E[w w^T] = Qw``,
    ``E[v v^T] = Qv``, ``E[w v^T] = S``; ``x(0)`` has mean ``sigma0`` and
    covariance ``Sigma0``.  Built and checked by :meth:`from_dict`.

    Parameters
    ----------
    Phi : numpy.ndarray
        State matrix ``Phi``, ``(n, n)``.
    Phi1 : numpy.ndarray
        Multiplicative-noise state matrix ``Phi_1`` (scaled by ``xi(t)``), ``(n, n)``.
    Gamma : numpy.ndarray
        Process-noise gain, ``(n, r)``.
    H : numpy.ndarray
        Output matrix, ``(m, n)``.
    H1 : numpy.ndarray
        Multiplicative-noise output matrix ``H_1`` (scaled by ``lambda(t)``), ``(m, n)``.
    Qw : numpy.ndarray
        ``E[w w^T]``, ``(r, r)``.
    Qv : numpy.ndarray
        ``E[v v^T]``, ``(m, m)``.
    S : numpy.ndarray
        ``E[w v^T]``, ``(r, m)``.
    Qxi : float
        Variance ``Q_xi`` of the scalar white noise ``xi(t)``.
    Qlam : float
        Variance ``Q_lambda`` of the scalar white noise ``lambda(t)``.
    sigma0 : numpy.ndarray
        ``E[x(0)]``, ``(n,)``.
    Sigma0 : numpy.ndarray
        ``Cov x(0)``, ``(n, n)``.
    name : str, optional
        Label used in messages and system names (default ``"plant"``).
    """

    Phi: np.ndarray
    Phi1: np.ndarray
    Gamma: np.ndarray
    H: np.ndarray
    H1: np.ndarray
    Qw: np.ndarray
    Qv: np.ndarray
    S: np.ndarray
    Qxi: float
    Qlam: float
    sigma0: np.ndarray
    Sigma0: np.ndarray
    name: str = "plant"

    @classmethod
    def from_dict(cls, d: dict, source: str | None = None) -> "Plant":
        """Build and check a plant from a config mapping.

        Keys: ``Phi, Phi1, Gamma, H, H1, Qxi, Qlam, sigma0, Sigma0`` and either
        ``Qw, Qv, S`` or the paper's construction ``v = c w + zeta``
        (``Qw, c, Qzeta``: ``Qv = c^2 Qw + Qzeta``, ``S = c Qw``; scalar w, v).
        ``sigma0`` defaults to zero, ``Sigma0`` to the identity, ``Qzeta`` to 1.

        Parameters
        ----------
        d : dict
            The mapping (numbers or nested lists); an optional ``name`` key names the plant.
        source : str or None, optional
            Where the mapping came from (a file, a config path), named in the errors.

        Returns
        -------
        Plant
            The checked plant.

        Raises
        ------
        InputError
            On a missing key, a wrong shape, a non-finite entry, a negative variance or a covariance (also the
            joint one of ``(w, v)``) that is not positive semidefinite.
        """
        try:
            Phi = _mat(d["Phi"], "Phi", source=source)
            n = Phi.shape[0]
            Phi = _mat(d["Phi"], "Phi", (n, n), source)
            Phi1 = _mat(d["Phi1"], "Phi1", (n, n), source)
            Gamma = _mat(d["Gamma"], "Gamma", (n, None), source)
            r = Gamma.shape[1]
            H = _mat(d["H"], "H", (None, n), source)
            m = H.shape[0]
            H1 = _mat(d["H1"], "H1", (m, n), source)
            Qw = _mat(d["Qw"], "Qw", (r, r), source)
            if "c" in d:
                c = float(d["c"])
                if r != 1 or m != 1:
                    raise InputError("the v = c w + zeta construction needs scalar w and v", source, "c")
                Qzeta = _mat(d.get("Qzeta", 1.0), "Qzeta", (1, 1), source)
                Qv = c * c * Qw + Qzeta
                S = c * Qw
            else:
                Qv = _mat(d["Qv"], "Qv", (m, m), source)
                S = _mat(d["S"], "S", (r, m), source)
            sigma0 = _mat(d.get("sigma0", np.zeros(n)), "sigma0", (n, 1), source).ravel()
            Sigma0 = _mat(d.get("Sigma0", np.eye(n)), "Sigma0", (n, n), source)
            Qxi, Qlam = float(d["Qxi"]), float(d["Qlam"])
        except KeyError as exc:
            raise InputError("missing key", source, str(exc.args[0])) from None
        for name, val in (("Qxi", Qxi), ("Qlam", Qlam)):
            if not np.isfinite(val) or val < 0:
                raise InputError(f"variance must be finite and >= 0, got {val}", source, name)
        for name, M in (("Qw", Qw), ("Qv", Qv), ("Sigma0", Sigma0)):
            check_psd(M, name, source)
        joint = np.block([[Qw, S], [S.T, Qv]])
        check_psd(joint, "S", source)
        return cls(Phi, Phi1, Gamma, H, H1, Qw, Qv, S, Qxi, Qlam, sigma0, Sigma0, d.get("name", "plant"))

    def with_(self, **changes: Any) -> "Plant":
        """Copy with some fields replaced (e.g. ``Qxi``, ``Qlam``).

        Parameters
        ----------
        **changes : numpy.ndarray, float or str
            New values of fields, by field name (not checked as :meth:`from_dict` would).

        Returns
        -------
        Plant
            The modified copy.
        """
        fields = {k: getattr(self, k) for k in self.__dataclass_fields__}
        fields.update(changes)
        return Plant(**fields)

    def description(self) -> NoisySystem:
        """The plant as the package's one system description (module docstring).

        ``x(t+1) = Φ x + Γ w``, ``y = H x + v`` is the affine system ``A = Φ``,
        ``C = H``, ``E = Γ``, ``V = I`` (no input, ``f = 0``); its noise is
        Gaussian (``Qw``, ``Qv``, ``S``, ``x(0) ~ (σ0, Σ0)``), not bounded, so the
        box of the system is empty (``eta_w = eta_v = 0``: no bounded-error
        guarantee is claimed); the multiplicative terms are ``A1 = Φ1``,
        ``C1 = H1`` with variances ``Qξ``, ``Qλ``.

        Returns
        -------
        NoisySystem
            The system, its Gaussian noise and its multiplicative terms.
        """
        system = AffineSystem(A=self.Phi, C=self.H, E=self.Gamma, V=np.eye(self.m), eta_w=0.0, eta_v=0.0,
                              name=self.name)
        gauss = GaussianNoise(Qw=self.Qw, Qv=self.Qv, S=self.S, x0_mean=self.sigma0, x0_cov=self.Sigma0)
        return NoisySystem(system, gauss, MultiplicativeNoise(A1=self.Phi1, C1=self.H1, Qxi=self.Qxi, Qlam=self.Qlam))

    @classmethod
    def from_description(cls, desc: NoisySystem, name: str | None = None) -> "Plant":
        """Read a system description as a plant of eqs. (1)-(2) (the inverse of :meth:`description`).

        ``y = C x + V v`` gives the plant's output noise ``V v`` (covariance
        ``V Qv Vᵀ``, cross-covariance ``S Vᵀ`` with ``w``); without
        multiplicative terms ``Φ1 = 0``, ``H1 = 0``.  The input and ``f`` of the
        system are not part of the plant (a step-form estimator adds the
        known ``B u + f``, :class:`~eqrec.lmv.estimator.LMVEstimator`).

        Parameters
        ----------
        desc : NoisySystem
            A time-invariant system with a Gaussian description.
        name : str or None, optional
            The plant's name (default: the system's).

        Returns
        -------
        Plant
            The plant, checked as :meth:`from_dict` checks one.

        Raises
        ------
        InputError
            A time-varying system or no Gaussian description.
        """
        sysm, g, mult = desc.system, desc.gaussian, desc.multiplicative
        if sysm.is_time_varying:
            raise InputError("the LMV plant of eqs. (1)-(2) is time-invariant", sysm.name, "system")
        if g is None:
            raise InputError("the LMV estimators need second moments (a Gaussian description)", sysm.name,
                             "gaussian")
        if sysm.nw == 0:
            raise InputError("the plant needs a process noise (nw >= 1)", sysm.name, "E")
        n, p = sysm.n, sysm.p
        V = sysm.V
        mapping = {"name": name or sysm.name, "Phi": sysm.A, "Gamma": sysm.E, "H": sysm.C, "Qw": g.Qw,
                   "Qv": V @ g.Qv @ V.T, "S": g.S @ V.T, "sigma0": g.x0_mean, "Sigma0": g.x0_cov,
                   "Phi1": np.zeros((n, n)) if mult is None else mult.A1,
                   "H1": np.zeros((p, n)) if mult is None else mult.C1,
                   "Qxi": 0.0 if mult is None else mult.Qxi, "Qlam": 0.0 if mult is None else mult.Qlam}
        return cls.from_dict(mapping, sysm.name)

    @property
    def n(self) -> int:
        """State dimension ``n``."""
        return self.Phi.shape[0]

    @property
    def m(self) -> int:
        """Output dimension ``m``."""
        return self.H.shape[0]


def plant_of(cfg: dict, example: str) -> Plant:
    """The plant of a named example of a configuration section (``cfg["examples"][example]``, as in
    ``config/p4.yaml``).

    Parameters
    ----------
    cfg : dict
        A section with an ``examples`` mapping of plant mappings (:meth:`Plant.from_dict`; keys that are not
        plant fields, such as ``mc_mult_dist``, are ignored).
    example : str
        The example's key; also the plant's name unless the mapping gives one.

    Returns
    -------
    Plant
        The checked plant.
    """
    if example not in cfg["examples"]:
        raise InputError(f"unknown example {example!r}", None, "examples")
    return Plant.from_dict({"name": example, **cfg["examples"][example]}, f"examples.{example}")
