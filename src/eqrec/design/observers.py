"""Observer gains by pole placement (used by the augmented estimator, whose ``L`` is an observer gain)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class PolePlacement:
    """Result of placing the eigenvalues of ``A - L C``; ``L is None`` when it failed.

    Parameters
    ----------
    requested : numpy.ndarray
        The requested eigenvalues, shape ``(n,)`` (complex).
    L : numpy.ndarray or None
        The observer gain, shape ``(n, p)``, or ``None`` on failure.
    achieved : numpy.ndarray or None
        The eigenvalues of ``A - L C`` obtained, when computed.
    ok : bool
        Whether the placement succeeded within tolerance.
    message : str, optional
        Why it failed (or a note on success).
    """

    requested: np.ndarray
    L: np.ndarray | None
    achieved: np.ndarray | None
    ok: bool
    message: str = ""


def observability_rank(A: np.ndarray, C: np.ndarray, tol: float | None = None) -> int:
    """Rank of the observability matrix ``[C; C A; ...; C A^{n-1}]`` (``n`` when ``(A, C)`` is observable).

    Parameters
    ----------
    A : numpy.ndarray
        State matrix, shape ``(n, n)``.
    C : numpy.ndarray
        Output matrix, shape ``(p, n)``.
    tol : float or None, optional
        Singular-value threshold of :func:`numpy.linalg.matrix_rank` (its default when ``None``).

    Returns
    -------
    int
        The rank, between 0 and ``n``.
    """
    A = np.asarray(A, float)
    C = np.asarray(C, float)
    blocks, M = [], C
    for _ in range(A.shape[0]):
        blocks.append(M)
        M = M @ A
    return int(np.linalg.matrix_rank(np.vstack(blocks), tol=tol))


def place_observer(A: np.ndarray, C: np.ndarray, poles, tol: float = 1e-6) -> PolePlacement:
    """Observer gain ``L`` with ``eig(A - L C) = poles`` (dual of state feedback, Yang-Tits method).

    Never raises for an unplaceable request (e.g. an eigenvalue repeated more
    often than ``rank C``): returns ``ok=False`` with the reason, so sweeps
    can mark the point instead of hiding it.

    Parameters
    ----------
    A : numpy.ndarray
        State matrix, shape ``(n, n)``.
    C : numpy.ndarray
        Output matrix, shape ``(p, n)``.
    poles : array_like
        The ``n`` requested eigenvalues of ``A - L C`` (complex allowed).
    tol : float, optional
        Relative tolerance on the achieved eigenvalues.

    Returns
    -------
    PolePlacement
        ``ok=True`` with ``L`` of shape ``(n, p)``, or ``ok=False`` with the reason.
    """
    from scipy.signal import place_poles

    poles = np.asarray(poles, dtype=complex)
    rank = observability_rank(A, C)
    if rank < np.asarray(A).shape[0]:  # scipy, placing the dual's poles, would speak of controllability
        return PolePlacement(poles, None, None, False, f"(A, C) is not observable (rank {rank} of the "
                             f"observability matrix < n = {np.asarray(A).shape[0]})")
    try:
        res = place_poles(np.asarray(A).T, np.asarray(C).T, poles)
    except (ValueError, np.linalg.LinAlgError) as exc:
        return PolePlacement(poles, None, None, False, str(exc))
    L = np.asarray(res.gain_matrix).T
    ach = np.linalg.eigvals(A - L @ C)
    # match achieved to requested eigenvalues
    err = max(np.min(np.abs(ach - lam)) for lam in poles)
    err = max(err, max(np.min(np.abs(poles - mu)) for mu in ach))
    if not np.isfinite(err) or err > tol * max(1.0, np.abs(poles).max()):
        return PolePlacement(poles, None, ach, False, f"achieved eigenvalues off by {err:.2e}")
    return PolePlacement(poles, L, ach, True, "")


def default_poles(n: int) -> np.ndarray:
    """Pole-placement default when ``L`` is not given: ``n`` distinct real poles spread in ``[-0.5, 0.5]``.

    For ``n = 3`` this is ``{0, 0.5, -0.5}`` (the augmented paper's ACC example).

    Parameters
    ----------
    n : int
        State dimension (number of poles).

    Returns
    -------
    numpy.ndarray
        Shape ``(n,)``: the poles.
    """
    if n == 1:
        return np.array([0.0])
    if n == 3:
        return np.array([0.0, 0.5, -0.5])
    return np.linspace(-0.5, 0.5, n)


def deadbeat_observer(A: np.ndarray, C: np.ndarray, seed: int = 0, tol: float = 1e-9) -> PolePlacement:
    r"""An observer gain with ``A - L C`` nilpotent (all eigenvalues at 0), also when ``rank C < n``.

    ``scipy.signal.place_poles`` refuses a pole repeated more often than
    ``rank C``; a deadbeat observer still exists for an observable pair.
    Dual construction: pick a nilpotent Jordan block ``F`` and a generic
    ``G``; the Sylvester equation :math:`A^\top X - X F = C^\top G` gives
    :math:`A^\top - C^\top G X^{-1} = X F X^{-1}`, so :math:`L = (G X^{-1})^\top`
    makes ``A - L C`` similar to ``F^T``.  Checked by :math:`\|(A - LC)^n\| \le` ``tol`` (scaled).

    Parameters
    ----------
    A : numpy.ndarray
        State matrix, shape ``(n, n)``.
    C : numpy.ndarray
        Output matrix, shape ``(p, n)``.
    seed : int, optional
        Seed of the random generic ``G``.
    tol : float, optional
        Largest accepted relative norm of ``(A - L C)^n``.

    Returns
    -------
    PolePlacement
        ``ok=True`` with a deadbeat ``L`` of shape ``(n, p)``, or ``ok=False`` with the reason.
    """
    import scipy.linalg as sla

    A = np.asarray(A, float)
    C = np.asarray(C, float)
    n = A.shape[0]
    F = np.eye(n, k=1)  # one nilpotent Jordan block
    G = np.random.default_rng(seed).normal(size=(C.shape[0], n))
    requested = np.zeros(n, dtype=complex)
    try:
        X = sla.solve_sylvester(A.T, -F, C.T @ G)
        L = np.linalg.solve(X.T, G.T)  # (G X^{-1})^T = X^{-T} G^T
    except (np.linalg.LinAlgError, ValueError) as exc:
        return PolePlacement(requested, None, None, False, f"deadbeat construction failed: {exc}")
    Phi = A - L @ C
    residual = np.linalg.norm(np.linalg.matrix_power(Phi, n)) / max(1.0, np.linalg.norm(Phi) ** n)
    if not np.isfinite(residual) or residual > tol:
        return PolePlacement(requested, None, None, False, f"(A - LC)^n is not zero (relative {residual:.1e})")
    return PolePlacement(requested, L, np.linalg.eigvals(Phi), True, "nilpotent A - LC (deadbeat observer)")
