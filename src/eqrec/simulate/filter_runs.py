r"""Exact worst cases of linear filters on a fixed arrival pattern, and sampled runs.

On a fixed pattern, a filter whose gains do not depend on the data (every
filter of :mod:`eqrec.estimators.kalman`) produces estimates that are affine in
the uncertainty ``δ = [w; v; ξ0]`` (the core's
:class:`eqrec.bounds.stacking.UncertaintyLayout`), with a constant part that
may depend on the true initial state ``x0`` and the inputs (a filter that
mistakes ``y(τ)`` for a measurement of ``x(t)`` sees ``C (x(τ) − x(t))``).
:func:`error_maps` runs the filter *once* on affine data — arrays whose
``1 + D`` columns are the constant and the coefficients of ``δ`` — and
returns ``e(t) = x(t) − x̂(t) = c_t + G_t δ``; the worst case over the box is
``|c_t| + |G_t| b`` per component (:func:`eqrec.lp.robust.worst_case_abs`),
attained at the vertex :meth:`ErrorMaps.worst_vertex`.

:func:`simulate_filter` runs the same filter on numbers (the true system
simulated step by step), which the tests use to check that a vertex attains
the bound.  Both run in the package's one simulation loop,
:func:`eqrec.simulate.loop.closed_loop` (affine runs carry the columns on a
last axis).  The initial estimate is ``x̂(0) = x0 − ξ0`` as in
:func:`eqrec.simulate.loop.simulate_run`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.arrivals.draws import ArrivalTrace
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_pattern
from eqrec.lp.robust import worst_case_abs, worst_case_vertex
from eqrec.simulate.loop import closed_loop
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.systems.affine import AffineSystem


@dataclass
class ErrorMaps:
    """``e(t) = c[t] + G[t] δ`` for the prediction ``x̂(t|I_{t-1})`` (``t = 0..T``) and the filter ``x̂(t|I_t)`` (``t < T``).

    Built by :func:`error_maps`; ``D`` is the length of ``δ = [w; v; ξ0]``.

    Parameters
    ----------
    G : numpy.ndarray
        Coefficients of ``δ`` in the prediction errors, ``(T+1, n, D)``.
    c : numpy.ndarray
        Constant part of the prediction errors, ``(T+1, n)``.
    G_filt : numpy.ndarray
        Coefficients of ``δ`` in the filtered errors, ``(T, n, D)``.
    c_filt : numpy.ndarray
        Constant part of the filtered errors, ``(T, n)``.
    layout : UncertaintyLayout
        Index layout of ``δ``.
    radius : numpy.ndarray
        Box radii ``b`` of ``δ`` (``|δ| <= b`` componentwise), ``(D,)``.
    pattern : ArrivalPattern
        The arrival pattern the maps hold for.
    name : str, optional
        The filter's name (default ``""``).
    """

    G: np.ndarray
    c: np.ndarray
    G_filt: np.ndarray
    c_filt: np.ndarray
    layout: UncertaintyLayout
    radius: np.ndarray
    pattern: ArrivalPattern
    name: str = ""

    def _pick(self, estimate: str):
        if estimate == "prediction":
            return self.G, self.c
        if estimate == "filtered":
            return self.G_filt, self.c_filt
        raise ValueError(f"estimate must be 'prediction' or 'filtered', got {estimate!r}")

    def bounds(self, estimate: str = "prediction") -> np.ndarray:
        """Exact ``max |e_i(t)|`` over the box, ``|c| + |G| b`` (:func:`~eqrec.lp.robust.worst_case_abs`).

        Parameters
        ----------
        estimate : str, optional
            ``"prediction"`` (default, ``x̂(t|I_{t-1})``) or ``"filtered"`` (``x̂(t|I_t)``).

        Returns
        -------
        numpy.ndarray
            Worst cases per time and component, ``(T+1, n)`` (``(T, n)`` filtered).
        """
        G, c = self._pick(estimate)
        return np.stack([worst_case_abs(G[t], c[t], self.radius) for t in range(G.shape[0])])

    def worst_vertex(self, t: int, i: int, estimate: str = "prediction") -> np.ndarray:
        """A box vertex at which ``|e_i(t)|`` equals its bound.

        Parameters
        ----------
        t : int
            Time index into the maps.
        i : int
            State component.
        estimate : str, optional
            ``"prediction"`` (default) or ``"filtered"``.

        Returns
        -------
        numpy.ndarray
            ``δ*``, ``(D,)``, with every entry ``±b``.
        """
        G, c = self._pick(estimate)
        return worst_case_vertex(G[t, i], c[t, i], self.radius)

    def errors(self, deltas: np.ndarray, estimate: str = "prediction") -> np.ndarray:
        """Errors ``c[t] + G[t] δ`` for samples of ``δ``.

        Parameters
        ----------
        deltas : numpy.ndarray
            Samples, ``(N, D)`` (or one sample ``(D,)``).
        estimate : str, optional
            ``"prediction"`` (default) or ``"filtered"``.

        Returns
        -------
        numpy.ndarray
            ``(N, T+1, n)`` (``(N, T, n)`` filtered).
        """
        G, c = self._pick(estimate)
        return np.einsum("tnd,kd->ktn", G, np.atleast_2d(deltas)) + c[None]


def _run(filt, system: AffineSystem, pattern: ArrivalPattern, x0: np.ndarray, inputs, delta: np.ndarray | None):
    """Run ``filt`` in the one loop (:func:`~eqrec.simulate.loop.closed_loop`) on affine (``delta is None``)
    or numeric data; returns ``(x, pred, filtered, layout)`` arrays with a last axis of columns."""
    T, n = pattern.T, system.n
    lay = UncertaintyLayout(T, system.nw, system.nv, n)
    D = lay.size
    if delta is None:  # columns: [1, δ_1..δ_D]
        K = 1 + D
        one = np.zeros(K)
        one[0] = 1.0
        basis = np.eye(D, K, k=1)  # δ_j -> column j+1
    else:
        K = 1
        one = np.ones(1)
        basis = np.asarray(delta, float).reshape(D, 1)
    w = np.stack([basis[lay.w(t)] for t in range(T)]).reshape(T, system.nw, K)
    v = np.stack([basis[lay.v(t)] for t in range(T)]).reshape(T, system.nv, K)
    fil = np.zeros((T, n, K))

    def keep_filtered(k: int) -> None:
        fil[k] = filt.filtered

    u_at = None if inputs is None else (lambda k, _xhat: np.asarray(inputs, float)[k])
    run = closed_loop(system, filt, ArrivalTrace.from_pattern(pattern), np.outer(np.asarray(x0, float), one),
                      basis[lay.xi0], w, v, u_at, keep_filtered, one=one)
    return run.x, run.xhat, fil, lay


def error_maps(filt, system: AffineSystem, pattern: "ArrivalPattern | str", x0, mu1: float, *,
               inputs=None) -> ErrorMaps:
    """Affine error maps of ``filt`` along ``pattern`` (true ``x(0) = x0``, ``‖ξ0‖ <= mu1``).

    The filter runs once on affine data (module docstring); used for the comparison of Fig. 1 of the
    delayed-data paper.

    Parameters
    ----------
    filt : TimestampedKalman, DelayUnawareKalman or RandomDelayLMV
        A filter of :mod:`eqrec.estimators.kalman` (built for the same ``system`` and ``inputs``); it is reset.
    system : AffineSystem
        The true system.
    pattern : ArrivalPattern or str
        The arrival pattern, or a delay word (digits).
    x0 : numpy.ndarray
        True initial state ``x(0)``, ``(n,)``; the filter starts at ``x0 - ξ0``.
    mu1 : float
        Bound ``μ1`` of ``‖ξ0‖_∞`` (radius of the ``ξ0`` coordinates).
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``; ``None``: zero.

    Returns
    -------
    ErrorMaps
        Prediction and filtered error maps and the box radii.
    """
    pattern = as_pattern(pattern, kind="delay") if isinstance(pattern, str) else pattern
    x, pred, fil, lay = _run(filt, system, pattern, x0, inputs, None)
    e = x - pred
    ef = x[:-1] - fil
    return ErrorMaps(G=e[..., 1:], c=e[..., 0], G_filt=ef[..., 1:], c_filt=ef[..., 0], layout=lay,
                     radius=lay.radius(system.eta_w, system.eta_v, mu1), pattern=pattern,
                     name=getattr(filt, "name", ""))


def simulate_filter(filt, system: AffineSystem, pattern: "ArrivalPattern | str", delta: np.ndarray, x0, *,
                    inputs=None) -> tuple[np.ndarray, np.ndarray]:
    """Errors of one numeric run: prediction ``(T+1, n)`` and filtered ``(T, n)``.

    Parameters
    ----------
    filt : TimestampedKalman, DelayUnawareKalman or RandomDelayLMV
        A filter of :mod:`eqrec.estimators.kalman`; it is reset.
    system : AffineSystem
        The true system.
    pattern : ArrivalPattern or str
        The arrival pattern, or a delay word (digits).
    delta : numpy.ndarray
        The uncertainty ``δ = [w; v; ξ0]``, ``(D,)``.
    x0 : numpy.ndarray
        True initial state, ``(n,)``; the filter starts at ``x0 - ξ0``.
    inputs : numpy.ndarray or None, optional
        Known inputs ``u(t)``, ``(T, m)``; ``None``: zero.

    Returns
    -------
    tuple of numpy.ndarray
        ``x(t) - x̂(t|I_{t-1})``, ``(T+1, n)``, and ``x(t) - x̂(t|I_t)``, ``(T, n)``.
    """
    pattern = as_pattern(pattern, kind="delay") if isinstance(pattern, str) else pattern
    x, pred, fil, _ = _run(filt, system, pattern, x0, inputs, np.asarray(delta, float))
    return (x - pred)[..., 0], (x[:-1] - fil)[..., 0]


def truncated_normal_deltas(layout: UncertaintyLayout, radius: np.ndarray, rng: np.random.Generator, size: int,
                            sigmas: float = 5.0) -> np.ndarray:
    """``size`` draws of ``δ``: zero-mean normal with ``σ = radius / sigmas``, truncated at ``±radius``.

    Coordinates with zero radius are zero.  With the default, ``5σ`` = bound as in the delayed-data paper's
    Fig. 1.

    Parameters
    ----------
    layout : UncertaintyLayout
        Index layout of ``δ`` (its length ``D``).
    radius : numpy.ndarray
        Box radii ``b``, ``(D,)``.
    rng : numpy.random.Generator
        Random source.
    size : int
        Number of draws.
    sigmas : float, optional
        Truncation in standard deviations (default 5).

    Returns
    -------
    numpy.ndarray
        ``(size, D)``.
    """
    from scipy.stats import truncnorm

    z = truncnorm.rvs(-sigmas, sigmas, size=(size, layout.size), random_state=rng)
    return z * (np.asarray(radius, float) / sigmas)[None, :]


def compare_with_bounds(maps: ErrorMaps, bounds: np.ndarray, levels: np.ndarray | None = None,
                        deltas: np.ndarray | None = None, estimate: str = "prediction", rtol: float = 1e-9) -> dict:
    """Check whether the filter stays within another estimator's guarantees on this pattern.

    Parameters
    ----------
    maps : ErrorMaps
        The filter's error maps on the pattern (:func:`error_maps`).
    bounds : numpy.ndarray
        Per time and component guarantees ``(T+1, n)`` (e.g. the proposed
        estimator's certified worst cases on the same pattern); cut to the estimate's length.
    levels : numpy.ndarray or None, optional
        Per-time ``∞``-norm levels ``(T+1,)`` (the ``μ2,k`` along the pattern).
    deltas : numpy.ndarray or None, optional
        Samples ``(N, D)`` (e.g. :func:`truncated_normal_deltas`).
    estimate : str, optional
        ``"prediction"`` (default) or ``"filtered"``.
    rtol : float, optional
        Relative tolerance: exceeding means ``> bound (1 + rtol)`` (default ``1e-9``).

    Returns
    -------
    dict
        ``worst`` (the filter's exact worst case per time and component),
        ``exceeds`` (boolean mask, exact), ``max_ratio`` (largest
        ``worst / bound``), the same against ``levels`` and, with ``deltas``,
        the number of samples that leave the bounds (``sampled_exceed``) and the
        largest sampled ``|e| / bound``.
    """
    worst = maps.bounds(estimate)
    ref = np.asarray(bounds, float)[: worst.shape[0]]
    out = {"worst": worst, "exceeds": worst > ref * (1 + rtol), "max_ratio": float(np.max(worst / ref))}
    if levels is not None:
        lv = np.asarray(levels, float)[: worst.shape[0]]
        wn = worst.max(axis=1)
        out.update(worst_norm=wn, exceeds_levels=wn > lv * (1 + rtol), max_ratio_levels=float(np.max(wn / lv)))
    if deltas is not None:
        errs = np.abs(maps.errors(deltas, estimate))
        out.update(sampled_exceed=int(np.any(errs > ref[None] * (1 + rtol), axis=(1, 2)).sum()),
                   sampled_max_ratio=float(np.max(errs / ref[None])), samples=int(errs.shape[0]))
        if levels is not None:
            out["sampled_exceed_levels"] = int(np.any(errs.max(axis=2) > lv[None] * (1 + rtol), axis=1).sum())
    return out
