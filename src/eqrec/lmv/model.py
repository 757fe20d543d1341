r"""Linear minimum-variance (LMV) estimation for systems with multiplicative noises.

One innovation recursion serves both compensation mechanisms of the companion
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

The recursion (general form of Theorem 1, eqs. (4)-(9))::

    q(t+1)   = A q A^T + sum_kl W_kl A_k q A_l^T + Qu                     (8)
    Qe(t)    = C P C^T + sum_kl W_kl C_k q C_l^T + R                       (7)
    L(t)     = (A P C^T + sum_kl W_kl A_k q C_l^T + S) Qe^{-1}             (6)
    xh(t+1|t)= A xh(t|t-1) + L(t) (y(t) - C xh(t|t-1))                     (4),(5)
    P(t+1|t) = A P A^T + sum_kl W_kl A_k q A_l^T + Qu - L Qe L^T           (9)

with ``P = P(t|t-1)``, ``q = q(t) = E[x(t) x(t)^T]`` (raw second moment: the
multiplicative terms see the whole state, not the error).  The N-step
predictor (Theorem 2) is ``xh(t+N|t) = A xh(t+N-1|t)``,
``P(t+N|t) = A P(t+N-1|t) A^T + sum W_kl A_k q(t+N-1) A_l^T + Qu``.  The
filter and N-step smoother (Theorem 3, eqs. (17)-(20))::

    xh(t|t+j) = xh(t|t+j-1) + K(t,j) e(t+j),   K(t,j) = M(t,j) C^T Qe(t+j)^{-1}
    M(t,0)    = P(t|t-1),   M(t,j+1) = M(t,j) (A - L(t+j) C)^T
    P(t|t+j)  = P(t|t+j-1) - K(t,j) Qe(t+j) K(t,j)^T

Findings about the printed formulas (checked by Monte Carlo in the tests and
in ``results/p4/``):

* eq. (9) as printed carries the factor ``eta_bar (1 - eta_bar) Q_lambda`` in
  front of ``L H_1 q H_1^T L^T``; the term comes from ``eta(t) lambda(t)``, whose
  variance is ``E[eta^2] Q_lambda = eta_bar Q_lambda`` (as eq. (7) correctly
  has).  The printed factor under-states the prediction error variance;
  :func:`theorem1_as_printed` reproduces the printed recursion so that the
  discrepancy can be measured.
* eq. (14) (and (23)) print ``+ eta lambda L H x`` where ``- eta lambda L H_1 x``
  is meant, and ``+ (eta - eta_bar) L H x`` for ``- (eta - eta_bar) L H x``:
  sign/index misprints that do not change second moments.
* eq. (15) prints ``Phi xh(t+N|t-1)``; the predictor is
  ``xh(t+N|t) = Phi xh(t+N-1|t)`` (index misprint).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from eqrec.errors import InputError, NotMeanSquareStable, SolverFailure

__all__ = [
    "Plant", "MultNoiseSystem", "LMVResult", "SmootherResult", "SteadyState",
    "zero_input_system", "hold_input_system", "second_moment_operator", "ms_spectral_radius",
    "check_ms_stable", "lmv_recursion", "filter_smoother", "n_step_predictor",
    "suboptimal_error_cov", "theorem1_as_printed", "steady_state", "apply_estimator",
]


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


def _check_psd(M: np.ndarray, name: str, source: str | None) -> None:
    if not np.allclose(M, M.T, atol=1e-12 * max(1.0, np.abs(M).max())):
        raise InputError("covariance matrix is not symmetric", source, name)
    if np.linalg.eigvalsh(M).min() < -1e-10 * max(1.0, np.abs(M).max()):
        raise InputError("covariance matrix is not positive semidefinite", source, name)


@dataclass(frozen=True)
class Plant:
    """The plant of eqs. (1)-(2) of the paper.

    ``x(t+1) = (Phi + xi(t) Phi1) x(t) + Gamma w(t)``,
    ``y(t) = (H + lambda(t) H1) x(t) + v(t)``, with scalar white ``xi``,
    ``lambda`` of variances ``Qxi``, ``Qlam``; ``E[w w^T] = Qw``,
    ``E[v v^T] = Qv``, ``E[w v^T] = S``; ``x(0)`` has mean ``sigma0`` and
    covariance ``Sigma0``.
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
            _check_psd(M, name, source)
        joint = np.block([[Qw, S], [S.T, Qv]])
        _check_psd(joint, "S", source)
        return cls(Phi, Phi1, Gamma, H, H1, Qw, Qv, S, Qxi, Qlam, sigma0, Sigma0, d.get("name", "plant"))

    def with_(self, **changes: Any) -> "Plant":
        """Copy with some fields replaced (e.g. ``Qxi``, ``Qlam``)."""
        fields = {k: getattr(self, k) for k in self.__dataclass_fields__}
        fields.update(changes)
        return Plant(**fields)

    @property
    def n(self) -> int:
        return self.Phi.shape[0]

    @property
    def m(self) -> int:
        return self.H.shape[0]


@dataclass(frozen=True)
class MultNoiseSystem:
    """Common description: linear system with multiplicative and correlated additive noises.

    See the module docstring for the model.  ``Ak`` has shape ``(K, n, n)``,
    ``Ck`` ``(K, m, n)``, ``W`` ``(K, K)``; ``S = E[u r^T]`` is ``(n, m)``.
    ``n_x`` is the number of leading state components that are the plant
    state (the rest, for the hold-input augmentation, is the held output).
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
        _check_psd(self.W, "W", self.name)
        _check_psd(np.block([[self.Qu, self.S], [self.S.T, self.R]]), "Qu/S/R", self.name)

    @property
    def n(self) -> int:
        return self.A.shape[0]

    @property
    def m(self) -> int:
        return self.C.shape[0]

    def mult_A(self, X: np.ndarray) -> np.ndarray:
        """``sum_kl W_kl A_k X A_l^T``."""
        return np.einsum("kl,kij,jh,lgh->ig", self.W, self.Ak, X, self.Ak)

    def mult_C(self, X: np.ndarray) -> np.ndarray:
        """``sum_kl W_kl C_k X C_l^T``."""
        return np.einsum("kl,kij,jh,lgh->ig", self.W, self.Ck, X, self.Ck)

    def mult_AC(self, X: np.ndarray) -> np.ndarray:
        """``sum_kl W_kl A_k X C_l^T``."""
        return np.einsum("kl,kij,jh,lgh->ig", self.W, self.Ak, X, self.Ck)


def zero_input_system(plant: Plant, eta_bar: float) -> MultNoiseSystem:
    r"""Zero-input compensation, eq. (3), as a :class:`MultNoiseSystem`.

    ``y_z(t) = eta(t) y(t) = eta_bar H x + e(t) H x + eta(t) lambda(t) H1 x + eta(t) v(t)``
    with ``e = eta - eta_bar``.  Multiplicative noises
    ``a = (xi, e, eta lambda)`` are mutually uncorrelated with variances
    ``(Q_xi, eta_bar (1 - eta_bar), eta_bar Q_lambda)``; ``u = Gamma w``,
    ``r = eta v`` so ``R = eta_bar Qv`` and ``S = E[u r^T] = eta_bar Gamma S``.
    Inserted in the general recursion this gives exactly eqs. (6)-(8) of
    Theorem 1 and the *corrected* eq. (9) (factor ``eta_bar Q_lambda``).
    """
    eta_bar = _check_eta(eta_bar)
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
    """
    eta_bar = _check_eta(eta_bar)
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


def _check_eta(eta_bar: float) -> float:
    eta_bar = float(eta_bar)
    if not (0.0 < eta_bar <= 1.0):
        raise InputError(f"arrival probability must lie in (0, 1], got {eta_bar}", None, "eta_bar")
    return eta_bar


# --------------------------------------------------------------------------- stability

def second_moment_operator(sys: MultNoiseSystem) -> np.ndarray:
    r"""Matrix of ``q -> A q A^T + sum_kl W_kl A_k q A_l^T`` acting on ``vec(q)`` (column-major).

    ``vec(X Q Y^T) = (Y kron X) vec(Q)``.
    """
    T = np.kron(sys.A, sys.A)
    for k in range(sys.W.shape[0]):
        for l in range(sys.W.shape[0]):
            if sys.W[k, l] != 0.0:
                T = T + sys.W[k, l] * np.kron(sys.Ak[l], sys.Ak[k])
    return T


def ms_spectral_radius(sys: MultNoiseSystem) -> float:
    """Spectral radius of the second-moment operator (< 1 iff mean-square stable)."""
    return float(np.max(np.abs(np.linalg.eigvals(second_moment_operator(sys)))))


def check_ms_stable(sys: MultNoiseSystem) -> float:
    """Return the spectral radius; raise :class:`NotMeanSquareStable` if it is >= 1."""
    rho = ms_spectral_radius(sys)
    if not rho < 1.0:
        raise NotMeanSquareStable(
            f"{sys.name or 'system'}: the state second moment q(t) = E[x x^T] diverges - the spectral radius "
            f"of q -> A q A^T + sum W_kl A_k q A_l^T is {rho:.6g} >= 1 (e.g. reduce the multiplicative "
            f"noise variances); steady-state variances do not exist")
    return rho


# --------------------------------------------------------------------------- recursion

@dataclass
class LMVResult:
    """Output of :func:`lmv_recursion` over ``t = 0..T`` (``T+1`` instants).

    ``q[t] = E[x(t) x(t)^T]``; ``P_pred[t] = P(t|t-1)``; ``L[t]``, ``Qe[t]``
    gain and innovation covariance at time ``t`` (``t = 0..T``);
    ``q``/``P_pred`` have ``T+2`` entries (the last is ``t = T+1``).
    """

    sys: MultNoiseSystem
    q: np.ndarray
    P_pred: np.ndarray
    L: np.ndarray
    Qe: np.ndarray

    @property
    def T(self) -> int:
        return self.L.shape[0] - 1


def lmv_recursion(sys: MultNoiseSystem, T: int, check_stability: bool = True) -> LMVResult:
    """One-step LMV predictor, general form of Theorem 1 (eqs. (4)-(9)).

    Parameters
    ----------
    sys
        The system in the common description.
    T
        Last measurement time; gains for ``t = 0..T``.
    check_stability
        Raise :class:`NotMeanSquareStable` if the system is not mean-square
        stable (the recursion itself is finite on a finite horizon).

    Initial values ``xh(0|-1) = E[x(0)]``, ``P(0|-1) = Cov x(0)``,
    ``q(0) = E x(0) E x(0)^T + Cov x(0)`` as in Theorem 1.
    """
    if int(T) != T or T < 0:
        raise InputError(f"horizon must be a non-negative integer, got {T}", None, "T")
    T = int(T)
    if check_stability:
        check_ms_stable(sys)
    n, m = sys.n, sys.m
    q = np.empty((T + 2, n, n))
    P = np.empty((T + 2, n, n))
    L = np.empty((T + 1, n, m))
    Qe = np.empty((T + 1, m, m))
    q[0] = np.outer(sys.x0_mean, sys.x0_mean) + sys.x0_cov
    P[0] = sys.x0_cov
    for t in range(T + 1):
        qt, Pt = q[t], P[t]
        Qe[t] = _sym(sys.C @ Pt @ sys.C.T + sys.mult_C(qt) + sys.R)
        cross = sys.A @ Pt @ sys.C.T + sys.mult_AC(qt) + sys.S
        L[t] = np.linalg.solve(Qe[t].T, cross.T).T
        q[t + 1] = _sym(sys.A @ qt @ sys.A.T + sys.mult_A(qt) + sys.Qu)
        P[t + 1] = _sym(sys.A @ Pt @ sys.A.T + sys.mult_A(qt) + sys.Qu - L[t] @ Qe[t] @ L[t].T)
    return LMVResult(sys, q, P, L, Qe)


def _sym(X: np.ndarray) -> np.ndarray:
    return 0.5 * (X + np.swapaxes(X, -1, -2))


@dataclass
class SmootherResult:
    """Filter (``j = 0``) and fixed-lag smoothers ``j = 1..N`` (Theorem 3).

    ``K[t, j]`` gain of ``e(t+j)`` in ``xh(t|t+j)``; ``P[t, j] = P(t|t+j)``;
    entries with ``t + j > T`` are NaN.
    """

    K: np.ndarray
    P: np.ndarray

    @property
    def P_filt(self) -> np.ndarray:
        return self.P[:, 0]


def filter_smoother(res: LMVResult, N: int) -> SmootherResult:
    """Filter and ``N``-step smoother, Theorem 3, eqs. (17)-(20), general form."""
    if int(N) != N or N < 0:
        raise InputError(f"smoothing lag must be a non-negative integer, got {N}", None, "N")
    sys, T = res.sys, res.T
    n, m = sys.n, sys.m
    K = np.full((T + 1, N + 1, n, m), np.nan)
    P = np.full((T + 1, N + 1, n, n), np.nan)
    for t in range(T + 1):
        M = res.P_pred[t].copy()
        Pj = res.P_pred[t].copy()
        for j in range(min(N, T - t) + 1):
            s = t + j
            Kj = np.linalg.solve(res.Qe[s].T, (M @ sys.C.T).T).T
            Pj = _sym(Pj - Kj @ res.Qe[s] @ Kj.T)
            K[t, j], P[t, j] = Kj, Pj
            M = M @ (sys.A - res.L[s] @ sys.C).T
    return SmootherResult(K, P)


def n_step_predictor(res: LMVResult, N: int) -> np.ndarray:
    """Covariances ``P(t+N|t)`` for ``t = 0..T`` (Theorem 2, eq. (16), general form).

    Returned array ``Pn[t] = P(t+N|t)``, shape ``(T+1, n, n)``.  ``N = 1`` is
    the one-step predictor.  Needs ``q`` up to ``t+N-1``, which is extended
    here beyond the horizon of ``res`` by eq. (8).
    """
    if int(N) != N or N < 1:
        raise InputError(f"prediction horizon must be an integer >= 1, got {N}", None, "N")
    sys, T = res.sys, res.T
    q = list(res.q)
    while len(q) < T + N + 1:
        q.append(_sym(sys.A @ q[-1] @ sys.A.T + sys.mult_A(q[-1]) + sys.Qu))
    out = np.empty((T + 1, sys.n, sys.n))
    for t in range(T + 1):
        Pk = res.P_pred[t + 1]
        for k in range(2, N + 1):
            Pk = _sym(sys.A @ Pk @ sys.A.T + sys.mult_A(q[t + k - 1]) + sys.Qu)
        out[t] = Pk
    return out


def suboptimal_error_cov(sys: MultNoiseSystem, L: np.ndarray, q: np.ndarray) -> np.ndarray:
    r"""True one-step prediction error covariance of ``xh(t+1) = A xh + L(t)(y - C xh)`` for *any* gains.

    Joseph form: with ``xt = x - xh``,
    ``xt(t+1) = (A - L C) xt + sum_k a_k (A_k - L C_k) x + u - L r``, so::

        P(t+1) = (A - LC) P (A - LC)^T + sum W_kl (A_k - L C_k) q (A_l - L C_l)^T
                 + Qu - L S^T - S L^T + L R L^T.

    Used to measure what an estimator with the gains of the *printed*
    Theorem 1 really achieves.  ``q`` must hold ``E[x x^T]`` for ``t = 0..T``.
    """
    T = L.shape[0] - 1
    P = np.empty((T + 2, sys.n, sys.n))
    P[0] = sys.x0_cov
    for t in range(T + 1):
        Lt = L[t]
        F = sys.A - Lt @ sys.C
        Bk = sys.Ak - np.einsum("ij,kjh->kih", Lt, sys.Ck)
        mult = np.einsum("kl,kij,jh,lgh->ig", sys.W, Bk, q[t], Bk)
        P[t + 1] = _sym(F @ P[t] @ F.T + mult + sys.Qu - Lt @ sys.S.T - sys.S @ Lt.T + Lt @ sys.R @ Lt.T)
    return P


def theorem1_as_printed(plant: Plant, eta_bar: float, T: int) -> dict[str, np.ndarray]:
    """Theorem 1 exactly as printed, eqs. (6)-(9), including the factor of eq. (9).

    Returns ``{"q", "P", "L", "Qe"}`` (``P[t] = P_z(t|t-1)`` as the paper
    would report it).  The only difference from the zero-input instance of
    :func:`lmv_recursion` is the factor ``eta_bar (1 - eta_bar) Q_lambda``
    (printed) instead of ``eta_bar Q_lambda`` (derived) in eq. (9).
    """
    eb = _check_eta(eta_bar)
    Phi, Phi1, G, H, H1 = plant.Phi, plant.Phi1, plant.Gamma, plant.H, plant.H1
    n, m = plant.n, plant.m
    q = np.empty((T + 2, n, n))
    P = np.empty((T + 2, n, n))
    L = np.empty((T + 1, n, m))
    Qe = np.empty((T + 1, m, m))
    q[0] = np.outer(plant.sigma0, plant.sigma0) + plant.Sigma0
    P[0] = plant.Sigma0
    GQG = G @ plant.Qw @ G.T
    for t in range(T + 1):
        qt, Pt = q[t], P[t]
        Qe[t] = (eb * (1 - eb) * H @ qt @ H.T + eb * plant.Qv + eb ** 2 * H @ Pt @ H.T
                 + eb * plant.Qlam * H1 @ qt @ H1.T)                                          # (7)
        Lt = eb * (Phi @ Pt @ H.T + G @ plant.S) @ np.linalg.inv(Qe[t])                        # (6)
        q[t + 1] = Phi @ qt @ Phi.T + plant.Qxi * Phi1 @ qt @ Phi1.T + GQG                      # (8)
        F = Phi - eb * Lt @ H
        P[t + 1] = (F @ Pt @ F.T + plant.Qxi * Phi1 @ qt @ Phi1.T                               # (9)
                    + eb * (1 - eb) * Lt @ H @ qt @ H.T @ Lt.T
                    + eb * (1 - eb) * plant.Qlam * Lt @ H1 @ qt @ H1.T @ Lt.T
                    + eb * Lt @ plant.Qv @ Lt.T + GQG
                    - eb * Lt @ plant.S.T @ G.T - eb * G @ plant.S @ Lt.T)
        L[t] = Lt
    return {"q": q, "P": P, "L": L, "Qe": Qe}


# --------------------------------------------------------------------------- steady state

@dataclass
class SteadyState:
    """Limits of the recursion: ``q``, ``P(t+1|t)``, ``P(t|t)``, ``P(t|t+j)`` (``j = 1..N``), gains."""

    q: np.ndarray
    P_pred: np.ndarray
    P_filt: np.ndarray
    P_smooth: np.ndarray
    L: np.ndarray
    Qe: np.ndarray
    iterations: int
    rho: float


def steady_state(sys: MultNoiseSystem, N_smooth: int = 1, tol: float = 1e-12,
                 max_iter: int = 100_000) -> SteadyState:
    """Iterate the Riccati-like recursion (8)-(9) to convergence.

    Raises :class:`NotMeanSquareStable` if ``q`` cannot converge and
    :class:`~eqrec.errors.SolverFailure` if ``P`` has not converged (relative
    change ``< tol``) within ``max_iter`` iterations.  Filter and smoother
    limits follow from Theorem 3 with the limiting ``P``, ``L``, ``Qe``.
    """
    rho = check_ms_stable(sys)
    # q converges geometrically; its limit solves a linear (Lyapunov-like) equation.
    n = sys.n
    Top = second_moment_operator(sys)
    q = np.linalg.solve(np.eye(n * n) - Top, sys.Qu.reshape(-1, order="F")).reshape(n, n, order="F")
    q = _sym(q)
    P = sys.x0_cov.copy()
    for it in range(1, max_iter + 1):
        Qe = _sym(sys.C @ P @ sys.C.T + sys.mult_C(q) + sys.R)
        L = np.linalg.solve(Qe.T, (sys.A @ P @ sys.C.T + sys.mult_AC(q) + sys.S).T).T
        Pn = _sym(sys.A @ P @ sys.A.T + sys.mult_A(q) + sys.Qu - L @ Qe @ L.T)
        done = np.max(np.abs(Pn - P)) <= tol * max(1.0, np.max(np.abs(Pn)))
        P = Pn
        if done:
            break
    else:
        raise SolverFailure(f"{sys.name}: P(t+1|t) did not converge in {max_iter} iterations")
    Qe = _sym(sys.C @ P @ sys.C.T + sys.mult_C(q) + sys.R)
    L = np.linalg.solve(Qe.T, (sys.A @ P @ sys.C.T + sys.mult_AC(q) + sys.S).T).T
    M, Pj, Ps = P.copy(), P.copy(), []
    F = sys.A - L @ sys.C
    for j in range(N_smooth + 1):
        K = np.linalg.solve(Qe.T, (M @ sys.C.T).T).T
        Pj = _sym(Pj - K @ Qe @ K.T)
        Ps.append(Pj)
        M = M @ F.T
    return SteadyState(q, P, Ps[0], np.array(Ps[1:]).reshape(N_smooth, n, n), L, Qe, it, rho)


# --------------------------------------------------------------------------- estimator

def apply_estimator(res: LMVResult, y: np.ndarray, sm: SmootherResult | None = None) -> dict[str, np.ndarray]:
    """Run the estimator on measurements ``y[..., t, :]`` (``t = 0..T``), vectorised over leading axes.

    Returns ``pred[..., t, :] = xh(t|t-1)`` (``t = 0..T+1``), the innovations
    ``eps[..., t, :]`` and, if ``sm`` is given, ``smooth[..., t, j, :] =
    xh(t|t+j)`` (NaN where ``t + j > T``; ``j = 0`` is the filter).
    """
    sys, T = res.sys, res.T
    y = np.asarray(y, float)
    if y.shape[-2:] != (T + 1, sys.m):
        raise InputError(f"measurements have shape {y.shape}, expected (..., {T + 1}, {sys.m})", None, "y")
    lead = y.shape[:-2]
    pred = np.empty(lead + (T + 2, sys.n))
    eps = np.empty(lead + (T + 1, sys.m))
    pred[..., 0, :] = sys.x0_mean
    for t in range(T + 1):
        eps[..., t, :] = y[..., t, :] - pred[..., t, :] @ sys.C.T
        pred[..., t + 1, :] = pred[..., t, :] @ sys.A.T + eps[..., t, :] @ res.L[t].T
    out = {"pred": pred, "eps": eps}
    if sm is not None:
        N = sm.K.shape[1] - 1
        smooth = np.full(lead + (T + 1, N + 1, sys.n), np.nan)
        acc = pred[..., : T + 1, :].copy()
        for j in range(N + 1):
            valid = T + 1 - j
            acc[..., :valid, :] = acc[..., :valid, :] + np.einsum(
                "tij,...tj->...ti", sm.K[:valid, j], eps[..., j: j + valid, :])
            smooth[..., :valid, j, :] = acc[..., :valid, :]
        out["smooth"] = smooth
    return out
