r"""The LMV model: systems with multiplicative noises (one common description), the two compensation
mechanisms of the companion study mapped onto it, and mean-square stability.

One innovation recursion (:mod:`eqrec.lmv.recursion`) serves both compensation mechanisms of the companion
study (Zhao, Wang, Jin, Ma, *Zero-input compensation mechanism-based linear
estimation for systems with multiple packet dropouts and multiplicative
noises*; "the paper" below):

* **zero-input** compensation, eq. (3), Theorems 1-3 of the paper;
* **hold-input** compensation, the augmented-state estimator of the paper's
  ref. [15] (Ma & Sun, IET Signal Processing 2012), which the paper uses in
  Figs. 7-8 but does not write down; derived in :func:`hold_input_system`.

Both are mapped onto one common description, :class:`MultNoiseSystem`::

    x(t+1) = (A + sum_k a_k(t) A_k) x(t) + u(t)
    y(t)   = (C + sum_k a_k(t) C_k) x(t) + r(t)

where ``a(t) = (a_1(t), ..., a_K(t))`` is a zero-mean white vector with
covariance ``W`` that is independent of ``x(t)`` (the same ``a_k(t)`` may
perturb both ``A`` and ``C`` at the same instant), and ``(u(t), r(t))`` is a
zero-mean white additive noise with ``E[u u^T] = Qu``, ``E[r r^T] = R``,
``E[u r^T] = S``, uncorrelated with ``x(t)`` and with every product
``a_k(t) x(t)``.  Bernoulli arrivals enter as *mean plus zero-mean part*,
``eta(t) = eta_bar + e(t)``, ``E[e^2] = eta_bar (1 - eta_bar)``.

The recursion on this description is :mod:`eqrec.lmv.recursion`; the plant and its
loading :mod:`eqrec.lmv.plant`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from eqrec.errors import InputError, NotMeanSquareStable
from eqrec.lmv.plant import Plant, check_psd

__all__ = ["MECHANISMS", "MECHANISM_KEYS", "MultNoiseSystem", "multiplicative_term", "zero_input_system", "hold_input_system", "system_of", "check_eta",
           "second_moment_operator", "ms_spectral_radius", "check_ms_stable"]

#: The two compensation mechanisms (:func:`system_of`).
MECHANISMS = ("zero-input", "hold-input")
#: The short key of each mechanism in the realisations (``y_<key>``) and the arrays the study writes.
MECHANISM_KEYS = {"zero-input": "zero", "hold-input": "hold"}


def multiplicative_term(W: np.ndarray, left: np.ndarray, X: np.ndarray, right: np.ndarray) -> np.ndarray:
    """``sum_kl W_kl left_k X right_l^T``: the multiplicative-noise terms of eqs. (6)-(9).

    Parameters
    ----------
    W : numpy.ndarray
        ``(K, K)`` covariance of the multiplicative noises.
    left : numpy.ndarray
        ``(K, a, n)``: the matrices the noises multiply on the left.
    X : numpy.ndarray
        ``(n, n)`` second moment.
    right : numpy.ndarray
        ``(K, b, n)``: the matrices on the right (transposed).

    Returns
    -------
    numpy.ndarray
        ``(a, b)``.
    """
    return np.einsum("kl,kij,jh,lgh->ig", W, left, X, right)


@dataclass(frozen=True)
class MultNoiseSystem:
    """Common description: linear system with multiplicative and correlated additive noises.

    See the module docstring for the model (the description Theorems 1-3 of the paper are written for in
    their general form, :mod:`eqrec.lmv.recursion`).

    Parameters
    ----------
    A : numpy.ndarray
        Mean state matrix, ``(n, n)``.
    Ak : numpy.ndarray
        Multiplicative-noise state matrices ``A_k``, ``(K, n, n)``.
    C : numpy.ndarray
        Mean output matrix, ``(m, n)``.
    Ck : numpy.ndarray
        Multiplicative-noise output matrices ``C_k``, ``(K, m, n)``.
    W : numpy.ndarray
        Covariance ``E[a a^T]`` of the multiplicative noises, ``(K, K)``, positive semidefinite.
    Qu : numpy.ndarray
        ``E[u u^T]``, ``(n, n)``.
    R : numpy.ndarray
        ``E[r r^T]``, ``(m, m)``.
    S : numpy.ndarray
        ``E[u r^T]``, ``(n, m)`` (``[[Qu, S], [S^T, R]]`` must be positive semidefinite).
    x0_mean : numpy.ndarray
        ``E[x(0)]``, ``(n,)``.
    x0_cov : numpy.ndarray
        ``Cov x(0)``, ``(n, n)``.
    n_x : int
        Number of leading state components that are the plant state (the rest, for the hold-input
        augmentation, is the held output).
    name : str, optional
        Label used in messages (default ``""``).
    meta : dict, optional
        Free-form information, e.g. ``{"mechanism": ..., "eta_bar": ...}`` (default empty).
    """

    A: np.ndarray
    Ak: np.ndarray
    C: np.ndarray
    Ck: np.ndarray
    W: np.ndarray
    Qu: np.ndarray
    R: np.ndarray
    S: np.ndarray
    x0_mean: np.ndarray
    x0_cov: np.ndarray
    n_x: int
    name: str = ""
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        n, m, K = self.A.shape[0], self.C.shape[0], self.W.shape[0]
        expect = {"A": (n, n), "Ak": (K, n, n), "C": (m, n), "Ck": (K, m, n), "W": (K, K),
                  "Qu": (n, n), "R": (m, m), "S": (n, m), "x0_mean": (n,), "x0_cov": (n, n)}
        for key, shp in expect.items():
            if getattr(self, key).shape != shp:
                raise InputError(f"shape {getattr(self, key).shape}, expected {shp}", self.name, key)
        check_psd(self.W, "W", self.name)
        check_psd(np.block([[self.Qu, self.S], [self.S.T, self.R]]), "Qu/S/R", self.name)

    @property
    def n(self) -> int:
        """State dimension ``n``."""
        return self.A.shape[0]

    @property
    def m(self) -> int:
        """Output dimension ``m``."""
        return self.C.shape[0]

    def mult_A(self, X: np.ndarray) -> np.ndarray:
        """``sum_kl W_kl A_k X A_l^T``: the multiplicative term of eqs. (8)-(9) (general form).

        Parameters
        ----------
        X : numpy.ndarray
            ``(n, n)``, the raw second moment ``q(t)`` in the recursion.

        Returns
        -------
        numpy.ndarray
            ``(n, n)``.
        """
        return multiplicative_term(self.W, self.Ak, X, self.Ak)

    def mult_C(self, X: np.ndarray) -> np.ndarray:
        """``sum_kl W_kl C_k X C_l^T``: the multiplicative term of eq. (7) (general form).

        Parameters
        ----------
        X : numpy.ndarray
            ``(n, n)``, the raw second moment ``q(t)`` in the recursion.

        Returns
        -------
        numpy.ndarray
            ``(m, m)``.
        """
        return multiplicative_term(self.W, self.Ck, X, self.Ck)

    def mult_AC(self, X: np.ndarray) -> np.ndarray:
        """``sum_kl W_kl A_k X C_l^T``: the cross term of the gain, eq. (6) (general form).

        Parameters
        ----------
        X : numpy.ndarray
            ``(n, n)``, the raw second moment ``q(t)`` in the recursion.

        Returns
        -------
        numpy.ndarray
            ``(n, m)``.
        """
        return multiplicative_term(self.W, self.Ak, X, self.Ck)


def zero_input_system(plant: Plant, eta_bar: float) -> MultNoiseSystem:
    r"""Zero-input compensation, eq. (3), as a :class:`MultNoiseSystem`.

    ``y_z(t) = eta(t) y(t) = eta_bar H x + e(t) H x + eta(t) lambda(t) H1 x + eta(t) v(t)``
    with ``e = eta - eta_bar``.  Multiplicative noises
    ``a = (xi, e, eta lambda)`` are mutually uncorrelated with variances
    ``(Q_xi, eta_bar (1 - eta_bar), eta_bar Q_lambda)``; ``u = Gamma w``,
    ``r = eta v`` so ``R = eta_bar Qv`` and ``S = E[u r^T] = eta_bar Gamma S``.
    Inserted in the general recursion this gives exactly eqs. (6)-(8) of
    Theorem 1 and the *corrected* eq. (9) (factor ``eta_bar Q_lambda``).

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    eta_bar : float
        Arrival probability ``E[eta(t)]``, ``0 < eta_bar <= 1``.

    Returns
    -------
    MultNoiseSystem
        State ``x`` (dimension ``n``, ``n_x = n``), output ``y_z``, ``K = 3`` multiplicative noises.
    """
    eta_bar = check_eta(eta_bar)
    n, m = plant.n, plant.m
    Z_nn, Z_mn = np.zeros((n, n)), np.zeros((m, n))
    return MultNoiseSystem(
        A=plant.Phi.copy(), Ak=np.stack([plant.Phi1, Z_nn, Z_nn]),
        C=eta_bar * plant.H, Ck=np.stack([Z_mn, plant.H, plant.H1]),
        W=np.diag([plant.Qxi, eta_bar * (1 - eta_bar), eta_bar * plant.Qlam]),
        Qu=plant.Gamma @ plant.Qw @ plant.Gamma.T, R=eta_bar * plant.Qv, S=eta_bar * plant.Gamma @ plant.S,
        x0_mean=plant.sigma0.copy(), x0_cov=plant.Sigma0.copy(), n_x=n,
        name=f"{plant.name}/zero-input/eta={eta_bar:g}", meta={"mechanism": "zero-input", "eta_bar": eta_bar})


def hold_input_system(plant: Plant, eta_bar: float, yh0_mean: np.ndarray | None = None,
                      yh0_cov: np.ndarray | None = None) -> MultNoiseSystem:
    r"""Hold-input compensation (ref. [15] of the paper) as a :class:`MultNoiseSystem`.

    Derivation.  The estimator receives
    ``y_h(t) = eta(t) y(t) + (1 - eta(t)) y_h(t-1)``: the last received
    measurement is held when the packet is lost.  ``y_h(t)`` depends on
    ``y_h(t-1)``, so the state is augmented to ``X(t) = [x(t); y_h(t-1)]``
    (dimension ``n + m``).  With ``y(t) = (H + lambda H1) x(t) + v(t)`` and
    ``eta = eta_bar + e``::

        X(t+1) = [ Phi + xi Phi1          0              ] X(t) + [ Gamma w(t)  ]
                 [ eta (H + lambda H1)    (1 - eta) I_m  ]        [ eta(t) v(t) ]
        y_h(t) = [ eta (H + lambda H1)    (1 - eta) I_m  ] X(t) + eta(t) v(t)

    Splitting every random coefficient into mean and zero-mean part::

        A  = [[Phi, 0], [eta_bar H, (1 - eta_bar) I]],   C = [eta_bar H, (1 - eta_bar) I]
        a1 = xi       : A_1 = [[Phi1, 0], [0, 0]],  C_1 = 0,            var Q_xi
        a2 = e        : A_2 = [[0, 0], [H, -I]],    C_2 = [H, -I],      var eta_bar (1 - eta_bar)
        a3 = eta*lam  : A_3 = [[0, 0], [H1, 0]],    C_3 = [H1, 0],      var eta_bar Q_lambda

    The three are mutually uncorrelated (``E[e eta lambda] = E[e eta] E[lambda] = 0``)
    and independent of ``X(t)``, which is a function of the past only.
    Note that ``a2, a3`` act on ``A`` *and* ``C`` at the same instant (the
    measurement ``y_h(t)`` is also the second block of ``X(t+1)``): this is
    why the general gain carries the cross term ``sum W_kl A_k q C_l^T``.
    The additive noises are ``u(t) = [Gamma w; eta v]`` and ``r(t) = eta v``;
    ``E[eta^2] = eta_bar`` gives::

        Qu = [[Gamma Qw Gamma^T, eta_bar Gamma S], [eta_bar S^T Gamma^T, eta_bar Qv]]
        S_ur = E[u r^T] = [eta_bar Gamma S; eta_bar Qv],   R = eta_bar Qv.

    They are uncorrelated with ``X(t)`` and with ``a_k(t) X(t)``
    (e.g. ``E[e X (eta v)^T] = E[e eta] E[X v^T] = 0`` since ``v(t)`` is
    independent of ``X(t)``).  Hence the model satisfies every assumption of
    the common recursion.  The plant-state estimate and its error covariance
    are the first ``n`` components / the leading ``n x n`` block.

    The held output before the first measurement, ``y_h(-1)``, is not given
    in the paper; by default it is deterministic zero (mean ``yh0_mean = 0``,
    covariance ``yh0_cov = 0``), i.e. nothing is held before the first
    arrival.

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    eta_bar : float
        Arrival probability ``E[eta(t)]``, ``0 < eta_bar <= 1``.
    yh0_mean : numpy.ndarray or None, optional
        Mean of ``y_h(-1)``, ``(m,)``; ``None``: zero.
    yh0_cov : numpy.ndarray or None, optional
        Covariance of ``y_h(-1)``, ``(m, m)``; ``None``: zero.

    Returns
    -------
    MultNoiseSystem
        Augmented state ``X = [x; y_h(t-1)]`` (dimension ``n + m``, ``n_x = n``), output ``y_h``, ``K = 3``.
    """
    eta_bar = check_eta(eta_bar)
    n, m = plant.n, plant.m
    I, Z_mn, Z_nm, Z_mm = np.eye(m), np.zeros((m, n)), np.zeros((n, m)), np.zeros((m, m))
    A = np.block([[plant.Phi, Z_nm], [eta_bar * plant.H, (1 - eta_bar) * I]])
    C = np.hstack([eta_bar * plant.H, (1 - eta_bar) * I])
    A1 = np.block([[plant.Phi1, Z_nm], [Z_mn, Z_mm]])
    A2 = np.block([[np.zeros((n, n)), Z_nm], [plant.H, -I]])
    A3 = np.block([[np.zeros((n, n)), Z_nm], [plant.H1, Z_mm]])
    C1 = np.zeros((m, n + m))
    C2 = np.hstack([plant.H, -I])
    C3 = np.hstack([plant.H1, Z_mm])
    GS = plant.Gamma @ plant.S
    Qu = np.block([[plant.Gamma @ plant.Qw @ plant.Gamma.T, eta_bar * GS], [eta_bar * GS.T, eta_bar * plant.Qv]])
    S_ur = np.vstack([eta_bar * GS, eta_bar * plant.Qv])
    yh0_mean = np.zeros(m) if yh0_mean is None else np.asarray(yh0_mean, float).reshape(m)
    yh0_cov = np.zeros((m, m)) if yh0_cov is None else np.asarray(yh0_cov, float).reshape(m, m)
    return MultNoiseSystem(
        A=A, Ak=np.stack([A1, A2, A3]), C=C, Ck=np.stack([C1, C2, C3]),
        W=np.diag([plant.Qxi, eta_bar * (1 - eta_bar), eta_bar * plant.Qlam]),
        Qu=Qu, R=eta_bar * plant.Qv, S=S_ur,
        x0_mean=np.concatenate([plant.sigma0, yh0_mean]),
        x0_cov=np.block([[plant.Sigma0, Z_nm], [Z_mn, yh0_cov]]), n_x=n,
        name=f"{plant.name}/hold-input/eta={eta_bar:g}", meta={"mechanism": "hold-input", "eta_bar": eta_bar})


def check_eta(eta_bar: float) -> float:
    """The arrival probability as a float; :class:`~eqrec.errors.InputError` unless ``0 < eta_bar <= 1``.

    Parameters
    ----------
    eta_bar : float
        ``E[eta(t)]``, the probability that a packet arrives.

    Returns
    -------
    float
        ``eta_bar``.
    """
    eta_bar = float(eta_bar)
    if not (0.0 < eta_bar <= 1.0):
        raise InputError(f"arrival probability must lie in (0, 1], got {eta_bar}", None, "eta_bar")
    return eta_bar


def system_of(plant: Plant, mechanism: str, eta_bar: float) -> MultNoiseSystem:
    """The compensated system of one mechanism in the common description.

    Parameters
    ----------
    plant : Plant
        The plant, eqs. (1)-(2).
    mechanism : str
        ``"zero-input"`` (eq. (3), :func:`zero_input_system`) or ``"hold-input"``
        (ref. [15], :func:`hold_input_system`).
    eta_bar : float
        Arrival probability, ``0 < eta_bar <= 1``.

    Returns
    -------
    MultNoiseSystem
        The system the recursion of :mod:`eqrec.lmv.recursion` runs on.
    """
    if mechanism == "zero-input":
        return zero_input_system(plant, eta_bar)
    if mechanism == "hold-input":
        return hold_input_system(plant, eta_bar)
    raise InputError(f"unknown mechanism {mechanism!r} (zero-input or hold-input)", None, "mechanism")


# --------------------------------------------------------------------------- stability

def second_moment_operator(sys: MultNoiseSystem) -> np.ndarray:
    r"""Matrix of ``q -> A q A^T + sum_kl W_kl A_k q A_l^T`` acting on ``vec(q)`` (column-major).

    ``vec(X Q Y^T) = (Y kron X) vec(Q)``.  The map is eq. (8) without ``Qu`` (general form).

    Parameters
    ----------
    sys : MultNoiseSystem
        The system.

    Returns
    -------
    numpy.ndarray
        The ``(n^2, n^2)`` matrix ``Op`` with ``vec(q(t+1)) = Op vec(q(t)) + vec(Qu)``.
    """
    T = np.kron(sys.A, sys.A)
    for k in range(sys.W.shape[0]):
        for l in range(sys.W.shape[0]):
            if sys.W[k, l] != 0.0:
                T = T + sys.W[k, l] * np.kron(sys.Ak[l], sys.Ak[k])
    return T


def ms_spectral_radius(sys: MultNoiseSystem) -> float:
    """Spectral radius of the second-moment operator (< 1 iff mean-square stable).

    Parameters
    ----------
    sys : MultNoiseSystem
        The system.

    Returns
    -------
    float
        Spectral radius of :func:`second_moment_operator` (``< 1``: ``q(t)`` of eq. (8) converges).
    """
    return float(np.max(np.abs(np.linalg.eigvals(second_moment_operator(sys)))))


def check_ms_stable(sys: MultNoiseSystem) -> float:
    """Return the spectral radius; raise :class:`NotMeanSquareStable` if it is >= 1.

    Parameters
    ----------
    sys : MultNoiseSystem
        The system.

    Returns
    -------
    float
        :func:`ms_spectral_radius`, known to be ``< 1``.
    """
    rho = ms_spectral_radius(sys)
    if not rho < 1.0:
        raise NotMeanSquareStable(
            f"{sys.name or 'system'}: the state second moment q(t) = E[x x^T] diverges - the spectral radius "
            f"of q -> A q A^T + sum W_kl A_k q A_l^T is {rho:.6g} >= 1 (e.g. reduce the multiplicative "
            f"noise variances); steady-state variances do not exist")
    return rho
