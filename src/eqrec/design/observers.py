"""Observer gains by pole placement (used by the augmented estimator, whose ``L`` is an observer gain)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class PolePlacement:
    """Result of placing the eigenvalues of ``A - L C``; ``L is None`` when it failed."""

    requested: np.ndarray
    L: np.ndarray | None
    achieved: np.ndarray | None
    ok: bool
    message: str = ""


def place_observer(A: np.ndarray, C: np.ndarray, poles, tol: float = 1e-6) -> PolePlacement:
    """Observer gain ``L`` with ``eig(A - L C) = poles`` (dual of state feedback, Yang-Tits method).

    Never raises for an unplaceable request (e.g. an eigenvalue repeated more
    often than ``rank C``): returns ``ok=False`` with the reason, so sweeps
    can mark the point instead of hiding it.
    """
    from scipy.signal import place_poles

    poles = np.asarray(poles, dtype=complex)
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
    """
    if n == 1:
        return np.array([0.0])
    if n == 3:
        return np.array([0.0, 0.5, -0.5])
    return np.linspace(-0.5, 0.5, n)
