"""P2 grids: the heat map's ``(r, θ)`` grid, the real axis of Fig. 3b, and the interval read off it.

NumPy only: the figure and values steps read these without importing the LP sweeps of
:mod:`eqrec.studies.p2.sweeps` (so a figure's rule lists no solver among its code inputs).
"""

from __future__ import annotations

import numpy as np


def heatmap_grid(cfg: dict) -> tuple[np.ndarray, np.ndarray]:
    """``(r, θ)`` grids of the heat map."""
    h = cfg["heatmap"]
    return np.linspace(0.0, float(h["r_max"]), int(h["n_r"])), np.linspace(0.0, np.pi, int(h["n_theta"]))


def realaxis_grid(cfg: dict) -> np.ndarray:
    """Real double eigenvalues ``λ`` of Fig. 3b: ``n`` points on ``[-lam_max, lam_max]``, plus
    ``k / grid_denominator``."""
    ra = cfg["realaxis"]
    lam_max = float(ra["lam_max"])
    lam = np.linspace(-lam_max, lam_max, int(ra["n"]))
    den = ra["grid_denominator"]
    if den:  # the grid k / den as well (exact points, e.g. the paper's -10/14 and 13/14)
        k = np.arange(-int(np.floor(lam_max * den)), int(np.floor(lam_max * den)) + 1)
        lam = np.unique(np.concatenate([lam, k / den]))
    return lam


def constant_interval(lam: np.ndarray, mu2: np.ndarray, tol: float) -> list[float] | None:
    """Largest interval of ``λ`` (grid points, failures breaking it) on which ``μ2`` equals its minimum."""
    finite = np.isfinite(mu2)
    if not finite.any():
        return None
    at_min = finite & (np.abs(mu2 - mu2[finite].min()) <= tol)
    edges = np.diff(np.concatenate([[0], at_min.astype(int), [0]]))  # +1 where a run starts, -1 after it ends
    starts, ends = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1) - 1
    k = np.argmax(lam[ends] - lam[starts])  # the widest run (the first of equally wide ones)
    return [float(lam[starts[k]]), float(lam[ends[k]])]
