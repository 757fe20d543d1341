r"""The augmented estimator's prefix-based form and its error maps (P2 eqs. (2)-(3); P3 eqs. (4)-(5)).

What runs is :class:`eqrec.estimators.augmented.AugmentedEstimator`; this module converts its gains to and from
gain schedules and gives its error as affine maps of the uncertainty.

Equivalence with the prefix-based (time-based) estimator
--------------------------------------------------------
``s`` is a causal affine function of the available ``ỹ`` and ``s0``, hence so is
``ue``: every augmented estimator *is* a prefix-based one ``ue = u0 + F ỹ``
(:func:`augmented_to_prefix`); for given ``L`` and ``s0`` the map ``ỹ -> z`` is
affine with unit block lower-triangular linear part, so every ``(F, u0)`` has a
unique ``(M, ν)`` (:func:`prefix_to_augmented`).  Hence for every ``L`` and ``s0``
the optimum equals that of the prefix-based (time-based for one word) design.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from eqrec.bounds.gains import GainRow, GainSchedule, schedule_from_word_gains
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.bounds.stacking import UncertaintyLayout
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.model import (RUNTIME_MODES, AugmentedGains, AugmentedPrefixGains, arrival_indicator,
                                          as_time_varying_L, check_mode, default_runtime, effective_L,
                                          missing_data_pattern)


def _innovation_recursion(system: AffineSystem, pattern: ArrivalPattern, L: np.ndarray, s0, injection) -> None:
    r"""Propagate ``s(k) = Sy ỹ + sc`` (affine in the stacked ``ỹ``) along ``pattern``.

    At step ``k`` the innovation rows ``z(k) = Z[k] ỹ + zc[k]`` are filled (``ỹ(k)``
    enters iff ``y(k)`` ever arrives) and ``injection(k, Z, zc)`` returns the gain row
    ``(F_k, u0_k)`` of ``ue(k) = u0_k + F_k ỹ``; ``s(k+1) = A s + ue + L_k z(k)`` with ``L``
    as the runtime uses it (zero where it ignores the step; ``z(k) = -C s(k)`` at a missing step).
    Shared by both conversion directions and both parametrisations.
    """
    T, n, p = pattern.T, system.n, system.p
    Sy = np.zeros((n, T * p))
    sc = np.asarray(s0, float).reshape(n).copy()
    Z = np.zeros((T * p, T * p))
    zc = np.zeros(T * p)
    for k in range(T):
        C = system.C_at(k)
        rows = slice(k * p, (k + 1) * p)
        Z[rows] = -C @ Sy
        if pattern.arrivals[k] is not None:
            Z[rows, rows] += np.eye(p)
        zc[rows] = -C @ sc
        Fk, uk = injection(k, Z, zc)
        zk = Z[rows] if pattern.arrivals[k] in (k, None) else -C @ Sy  # ỹ(k) not there yet: 0 at time k
        Sy = system.A_at(k) @ Sy + Fk + L[k] @ zk
        sc = system.A_at(k) @ sc + uk + L[k] @ zc[rows]


def _columns(pre: ArrivalPattern, t: int, p: int) -> np.ndarray:
    return np.array([tau * p + j for tau in pre.available(t) for j in range(p)], dtype=np.int64)


def runtime_L(L: np.ndarray, T: int, n: int, p: int, pattern: "ArrivalPattern | str", runtime: str) -> np.ndarray:
    """The gains ``L_k`` (shape ``(T, n, p)``) as the runtime ``runtime`` uses them along ``pattern``: the
    design's ``L`` (constant or per step), zero at the steps the runtime ignores
    (:func:`eqrec.design.augmented.model.effective_L`).

    Parameters
    ----------
    L : numpy.ndarray
        The design's observer gain, ``(n, p)`` or ``(T, n, p)``.
    T, n, p : int
        Horizon, state and output dimensions.
    pattern : ArrivalPattern or str
        The arrival pattern (or 0/1 word) run along.
    runtime : {"theorem2", "hold"}
        Treatment of missing steps.

    Returns
    -------
    numpy.ndarray, shape (T, n, p)
    """
    return effective_L(as_time_varying_L(L, T, n, p), pattern, check_mode(runtime, RUNTIME_MODES))


def _to_prefix(system: AffineSystem, tree: PrefixTree, gains, runtime: str | None):
    """Rows ``(F over all Tp columns, u0)`` per prefix of :func:`augmented_to_prefix`; one word's gains multiply
    their stored rows ``M(k, .)`` (zero columns included), prefix gains the available measurements."""
    word = isinstance(gains, AugmentedGains)
    runtime = runtime or (default_runtime(gains.mode) if word else "theorem2")
    n, p, T = system.n, system.p, tree.depth
    out: dict[ArrivalPattern, tuple[np.ndarray, np.ndarray]] = {}
    for pat in tree.patterns:
        def injection(t, Z, zc, pat=pat):
            pre = pat.prefix(t + 1)
            if word:
                M, nu = gains.M[t * n:(t + 1) * n], gains.nu[t * n:(t + 1) * n]
                out[pre] = (M @ Z, nu + M @ zc)
            else:
                (M, nu), cols = gains.rows[pre], _columns(pre, t, p)
                out[pre] = (M @ Z[cols], nu + M @ zc[cols])
            return out[pre]

        _innovation_recursion(system, pat, runtime_L(gains.L, T, n, p, pat, runtime), gains.s0, injection)
    return out


def augmented_to_prefix(system: AffineSystem, tree: PrefixTree, gains: AugmentedPrefixGains,
                        runtime: str = "theorem2") -> GainSchedule:
    """The prefix-based schedule ``ue = u0 + F ỹ`` producing the same ``x̂`` as the augmented estimator.

    Parameters
    ----------
    system : AffineSystem
        The model.
    tree : PrefixTree
        The patterns.
    gains : AugmentedPrefixGains
        Gains per prefix.
    runtime : {"theorem2", "hold"}, optional
        How the running estimator treats a step whose measurement is not on time.

    Returns
    -------
    GainSchedule
        Rows ``F(t, 0..t)``, ``u0(t)`` per prefix (the form of P3 eq. (7)).
    """
    out = _to_prefix(system, tree, gains, runtime)
    rows = {pre: GainRow(F[:, : pre.T * system.p].copy(), np.asarray(u0, float).copy()) for pre, (F, u0) in out.items()}
    return GainSchedule(rows=rows, n=system.n, p=system.p, designed=tree.patterns)


def prefix_to_augmented(system: AffineSystem, tree: PrefixTree, schedule: GainSchedule, L, s0,
                        runtime: str = "theorem2") -> AugmentedPrefixGains:
    """The unique ``(M, ν)`` per prefix reproducing ``schedule`` for given ``L`` and ``s0`` (inverse of
    :func:`augmented_to_prefix`).

    Parameters
    ----------
    system : AffineSystem
        The model.
    tree : PrefixTree
        The patterns of ``schedule``.
    schedule : GainSchedule
        Prefix-based (or time-based) gains ``ue = u0 + F ỹ``.
    L : array_like, shape (n, p) or (T, n, p)
        Observer gain.
    s0 : array_like, shape (n,)
        Initial auxiliary state.
    runtime : {"theorem2", "hold"}, optional
        Treatment of steps whose measurement is not on time.

    Returns
    -------
    AugmentedPrefixGains
        ``M = F P^{-1}``, ``ν = u0 - M p0`` on the available measurements, with
        ``z = P ỹ + p0`` (``P`` unit block lower triangular).
    """
    n, p, T = system.n, system.p, tree.depth
    Lt = as_time_varying_L(L, T, n, p)
    out: dict[ArrivalPattern, tuple[np.ndarray, np.ndarray]] = {}
    for pat in tree.patterns:
        def injection(t, Z, zc, pat=pat):
            pre = pat.prefix(t + 1)
            g = schedule.row(pre)
            cols = _columns(pre, t, p)
            F = np.zeros((n, T * p))
            F[:, : (t + 1) * p] = g.F
            if pre not in out:
                P = Z[np.ix_(cols, cols)]
                M = sla.solve_triangular(P.T, F[:, cols].T, lower=False, unit_diagonal=True).T if cols.size \
                    else np.zeros((n, 0))
                out[pre] = (M, g.u0 - M @ zc[cols])
            return F, g.u0

        _innovation_recursion(system, pat, effective_L(Lt, pat, check_mode(runtime, RUNTIME_MODES)), s0, injection)
    return AugmentedPrefixGains(rows=out, L=Lt, s0=np.asarray(s0, float).reshape(n).copy())


def augmented_to_time_based(system: AffineSystem, gains: AugmentedGains,
                            runtime: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Stacked time-based gains of one word's augmented gains (:func:`augmented_to_prefix` along the word).

    Parameters
    ----------
    system : AffineSystem
        The model.
    gains : AugmentedGains
        Gains along the designed word.
    runtime : {"theorem2", "hold"} or None, optional
        Treatment of missing steps (default: ``"theorem2"`` for a ``"theorem2"`` design, else ``"hold"``).

    Returns
    -------
    F : ndarray, shape (Tn, Tp)
        Block lower triangular, zero columns at missing steps.
    u0 : ndarray, shape (Tn,)
    """
    pattern = missing_data_pattern(gains.word)
    out = _to_prefix(system, PrefixTree([pattern]), gains, runtime)
    pres = [pattern.prefix(k + 1) for k in range(pattern.T)]
    F = np.vstack([out[pre][0] for pre in pres])
    F[:, np.repeat(arrival_indicator(pattern) == 0, system.p)] = 0.0  # ỹ is zero there: immaterial columns
    return F, np.concatenate([out[pre][1] for pre in pres])


def schedule_from_augmented(system: AffineSystem, gains: AugmentedGains, runtime: str | None = None) -> GainSchedule:
    """The converted time-based :class:`GainSchedule` (``time_based=True``) of one word's augmented gains.

    Parameters
    ----------
    system : AffineSystem
        The model.
    gains : AugmentedGains
        Gains along the designed word.
    runtime : {"theorem2", "hold"} or None, optional
        Treatment of missing steps (default: ``"theorem2"`` for a ``"theorem2"`` design, else ``"hold"``).

    Returns
    -------
    GainSchedule
        The gains ``(F, u0)`` of :func:`augmented_to_time_based`, chosen by time only.
    """
    F, u0 = augmented_to_time_based(system, gains, runtime)
    return schedule_from_word_gains(PrefixTree([gains.word]), {gains.word: (F, u0)}, system.n, system.p,
                                    time_based=True)


def running_error_maps(system: AffineSystem, gains: AugmentedGains, runtime: str | None = None
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    r"""The error and the innovations of the running estimator (P2 eqs. (2)-(3), (6)-(8)) as affine maps of ``δ``.

    Along the designed word (``q_k``: 1 if ``y(k)`` arrives), with ``ξ = x - x̂``, ``e = ξ - s``, ``L_k`` the
    runtime's gain (:func:`eqrec.design.augmented.model.effective_L`) and ``δ = (w, v, ξ0)``:

    .. math:: \xi(k+1) = A_k\xi(k) + E_k w(k) + u_e(k), \qquad
              u_e(k) = \nu_k + \textstyle\sum_{i \le k} M(k, i)\, z(i),

    .. math:: e(k+1) = A_k e(k) + E_k w(k) - L_k z(k), \qquad
              z(k) = \begin{cases} C_k e(k) + V_k v(k) & q_k = 1 \\
                                   -C_k s(k) = C_k e(k) - C_k \xi(k) & q_k = 0, \end{cases}

    from ``ξ(0) = ξ0``, ``e(0) = ξ0 - s0`` (``u_e`` cancels in ``e``; it enters ``e`` only through
    ``-L_k z(k)`` at a missing step with ``L_k ≠ 0``: the ``"hold"`` runtime).  The same estimator as
    :class:`eqrec.estimators.augmented.AugmentedEstimator` and, through :func:`schedule_from_augmented`, as
    :func:`eqrec.bounds.certify.closed_loop_maps` (equal up to rounding).

    Parameters
    ----------
    system : AffineSystem
        The model.
    gains : AugmentedGains
        Gains along the designed word.
    runtime : {"theorem2", "hold"} or None, optional
        Treatment of missing steps (default: the design mode's runtime).

    Returns
    -------
    G : numpy.ndarray, shape (T+1, n, D)
        ``ξ(t) = G[t] δ + c[t]``.
    c : numpy.ndarray, shape (T+1, n)
    Z : numpy.ndarray, shape (T, p, D)
        ``z(k) = Z[k] δ + zc[k]``.
    zc : numpy.ndarray, shape (T, p)
    """
    runtime = check_mode(runtime or default_runtime(gains.mode), RUNTIME_MODES)
    q = arrival_indicator(gains.word)
    T, n, p = q.size, system.n, system.p
    L = runtime_L(gains.L, T, n, p, missing_data_pattern(gains.word), runtime)
    lay = UncertaintyLayout(T, system.nw, system.nv, n)
    G = np.zeros((T + 1, n, lay.size))
    c = np.zeros((T + 1, n))
    Z = np.zeros((T, p, lay.size))
    zc = np.zeros((T, p))
    G[0][:, lay.xi0] = np.eye(n)
    Ge, ce = G[0].copy(), -np.asarray(gains.s0, float).reshape(n)
    for k in range(T):
        A, C = system.A_at(k), system.C_at(k)
        if q[k]:
            Z[k], zc[k] = C @ Ge, C @ ce
            Z[k][:, lay.v(k)] += system.V_at(k)
        else:
            Z[k], zc[k] = C @ (Ge - G[k]), C @ (ce - c[k])
        Mk = gains.M[k * n:(k + 1) * n, : (k + 1) * p]
        G[k + 1] = A @ G[k] + Mk @ Z[: k + 1].reshape(-1, lay.size)
        G[k + 1][:, lay.w(k)] += system.E_at(k)
        c[k + 1] = A @ c[k] + gains.nu[k * n:(k + 1) * n] + Mk @ zc[: k + 1].reshape(-1)
        Ge = A @ Ge - L[k] @ Z[k]
        Ge[:, lay.w(k)] += system.E_at(k)
        ce = A @ ce - L[k] @ zc[k]
    return G, c, Z, zc
