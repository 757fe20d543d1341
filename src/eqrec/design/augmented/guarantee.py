r"""The best guarantee, as the estimator that runs, among the optima of a P2 design reading.

A reading analysis of the augmented paper's Fig. 2 (``printed`` step of the P2
study), not a design method: the design LP of a reading (:class:`AugmentedLP`)
has many optimal gains, and the estimator that runs with them has different
worst cases; :func:`best_guarantee_among_optima` computes the solver-independent
best one.  Built on the public interface of :class:`AugmentedLP` (its columns,
robust rows and levels) and :mod:`eqrec.design.augmented.runtime`.

With the ``"hold"`` runtime the running error is affine in the later gains only
once the earlier ones are fixed.  Its coefficients come exactly from the model of
the running estimator (:func:`eqrec.design.augmented.runtime.running_error_maps`):
P2 eqs. (2)-(3) with the observer as in eq. (7) (``s(k+1) = A s + u_e + L z(k)``, ``z(k) = -C s(k)``
at a missing step in ``"hold"``; ``u_e(k) = ν_k + Σ_i M(k, i) z(i)``), propagated as the error
``ξ`` of eq. (6) and ``e = ξ - s`` of eq. (8).  ``u_e`` cancels in ``e`` and enters it only at a
missing step, so with the gains before the last missing step fixed the innovations
``z(i) = Z_i δ + z_i`` are fixed and, over the free gains,
``ξ(t) = G⁰_t δ + c⁰_t + Σ_{s<t} Φ(t, s+1) (ν_s + Σ_i M(s, i) (Z_i δ + z_i))``,
``Φ(t, s+1) = A_{t-1} ... A_{s+1}``: each coefficient is one product of an entry of ``Φ`` and one of
``Z_i`` or ``z_i`` (no finite differences; tests/test_exact_hold_rows.py checks them against
:func:`eqrec.bounds.certify.closed_loop_maps` of the converted gains).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from eqrec.lp.model import LPBuilder
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.lp.robust import UncertainAffineRows, add_robust_rows
from eqrec.lp.solvers import solve_lp
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.augmented.model import (DESIGN_MODES, RUNTIME_MODES, AugmentedGains, arrival_indicator,
                                          check_mode)
from eqrec.design.augmented.runtime import running_error_maps, runtime_L
from eqrec.errors import InputError

#: Default tolerance of "optimal for the design LP": ``μ2 <= μ2* (1 + rel) + abs``.
OPTIMUM_RTOL, OPTIMUM_ATOL = 1e-7, 1e-9
#: Lower and upper bounds closer than this (relative) make the value exact.
BOUNDS_RTOL = 1e-6


@dataclass
class GuaranteeAmongOptima:
    """Result of :func:`best_guarantee_among_optima`.

    :attr:`exact`: ``upper <= lower (1 + BOUNDS_RTOL) + 1e-9``, the value is known.

    Parameters
    ----------
    lower, upper : float
        Bounds of the smallest worst case of the running estimator over the design LP's
        optimal gains (equal for an affine runtime: ``lower`` is then the LP value and
        ``upper`` the same LP's solution).
    bound : str
        ``"all"`` (every time) or ``"terminal"`` (``t = T`` only).
    runtime : str
        The running estimator, ``"theorem2"`` or ``"hold"``.
    design_mode : str
        The design reading whose optima were searched.
    design_optimum : float
        The design LP's optimum ``μ2*`` (solved first, with the same solver).
    optimum_bound : float
        ``μ2* (1 + rel_tol) + abs_tol``: the design level every admitted gain attains.
    gains : AugmentedGains
        Gains ``(M, ν)`` (mode: the design reading) attaining ``upper``; certify them independently.
    design_mu2 : float
        The design ``μ2`` of ``gains`` (at most ``optimum_bound``).
    agree_until : int
        Last time ``t`` up to which the ``"hold"`` and ``"theorem2"`` running errors coincide
        for every gain (:func:`runtimes_agree_until`).
    solver : str
        The LP solver used.
    """

    lower: float
    upper: float
    bound: str
    runtime: str
    design_mode: str
    design_optimum: float
    optimum_bound: float
    gains: AugmentedGains
    design_mu2: float
    agree_until: int
    solver: str

    @property
    def exact(self) -> bool:
        """Whether the bounds meet: ``upper <= lower (1 + BOUNDS_RTOL) + 1e-9``."""
        return bool(self.upper <= self.lower * (1.0 + BOUNDS_RTOL) + 1e-9)

    @property
    def value(self) -> float | None:
        """The best guarantee when :attr:`exact` (``upper``), else ``None``."""
        return self.upper if self.exact else None


def runtimes_agree_until(word: "str | ArrivalPattern") -> int:
    """Last time ``t`` such that ``ξ(0..t)`` is the same in the ``"hold"`` and ``"theorem2"`` runtimes for all gains.

    The two runtimes first differ in ``s(k0 + 1)`` (``k0`` the first missing step), hence in
    the innovation of the first measured step ``k1 > k0``, in ``ue(k1)`` and in ``ξ(k1 + 1)``;
    so ``t = k1`` (``T`` when no measured step follows a missing one).

    Parameters
    ----------
    word : str or ArrivalPattern
        A missing-data word.

    Returns
    -------
    int
        The time ``t`` (``0..T``).
    """
    q = arrival_indicator(word)
    measured_after_missing = [k for k in range(q.size) if q[k] and not q[:k].all()]
    return measured_after_missing[0] if measured_after_missing else q.size


def _select_rows(rows: UncertainAffineRows, keep: np.ndarray) -> UncertainAffineRows:
    """The rows ``keep`` (sorted row indices) of ``rows``, renumbered from 0."""
    new_index = np.full(rows.num_rows, -1, dtype=np.int64)
    new_index[keep] = np.arange(keep.size)
    ent = np.flatnonzero(new_index[rows.entry_row] >= 0)
    return UncertainAffineRows(entry_row=new_index[rows.entry_row[ent]], entry_coord=rows.entry_coord[ent],
                               G0=rows.G0[ent], Gx=rows.Gx.tocsr()[ent], c0=rows.c0[keep],
                               cx=rows.cx.tocsr()[keep])


def _running_rows(system: AffineSystem, design: AugmentedLP, x_base: np.ndarray, cols: np.ndarray, runtime: str,
                  keep: np.ndarray) -> UncertainAffineRows:
    r"""Rows ``keep`` of the running error as an affine function of the columns ``cols`` of ``design``, the
    others fixed at ``x_base``: exact coefficients from the running estimator's model (P2 eqs. (2)-(3), (6)-(8),
    :func:`eqrec.design.augmented.runtime.running_error_maps`).

    With ``x_f``: ``x_base`` with ``cols`` set to 0, the innovations ``z(i) = Z_i δ + z_i`` and the error
    ``ξ(t) = G^0_t δ + c^0_t`` are those of the gains of ``x_f``, and a column of ``M(s, i)[b, π]`` or
    ``ν_s[b]`` adds ``Φ(t, s+1)[:, b] (Z_i[π] δ + z_i[π])`` or ``Φ(t, s+1)[:, b]`` to ``ξ(t)``, ``t > s``
    (``Φ(t, s+1) = A_{t-1} ... A_{s+1}``).  Valid (checked, else :class:`~eqrec.errors.InputError`) when every column of
    ``cols`` is a gain column of a step ``s >= k_c``, ``k_c`` the last missing step whose runtime gain ``L_k``
    is nonzero: then ``u_e(s)`` enters ``e = ξ - s`` at no later step, so no ``z(i)`` depends on ``cols``.
    """
    n, p, T = system.n, system.p, design.T
    cols, keep = (np.asarray(a, dtype=np.int64) for a in (cols, keep))
    # each column's step s, source i (None for ν) and entry (b, π)
    info = {int(col): (s_, i_, k // p, k % p) for (s_, i_), mc in design.m_cols.items() for k, col in enumerate(mc)}
    info.update({int(col): (k // n, None, k % n, None) for k, col in enumerate(design.nu_cols)})
    if any(int(j) not in info for j in cols):
        raise InputError("the free columns must be gain columns (M, nu) of the design LP", field="cols")
    L = runtime_L(design.L, T, n, p, design.word, runtime)
    q = arrival_indicator(design.word)
    k_c = max((k for k in range(T) if q[k] == 0 and np.any(L[k])), default=0)  # the last coupled missing step
    early = sorted({info[int(j)][0] for j in cols if info[int(j)][0] < k_c})
    if early:
        raise InputError(f"the {runtime} running error is not affine in the free gains: gains of steps {early} "
                         f"are free and feed the auxiliary state's error at missing step {k_c}", field="cols")
    x_f = np.array(x_base, dtype=float)
    x_f[cols] = 0.0
    Gt, ct, Z, zc = running_error_maps(system, design.gains_from_x(x_f), runtime)
    D = Gt.shape[-1]
    dG = np.zeros((T + 1, n, D, cols.size))  # the coefficients of the free columns, by time
    dc = np.zeros((T + 1, n, cols.size))
    phi = design.st.transition
    for j, col in enumerate(cols):
        s_, i_, b, pi = info[int(col)]
        for t in range(s_ + 1, T + 1):
            P = phi[t][s_ + 1][:, b]
            dc[t, :, j] = P if i_ is None else P * zc[i_, pi]
            if i_ is not None:
                dG[t, :, :, j] = np.outer(P, Z[i_, pi])
    G0, c0 = Gt.reshape(-1, D)[keep], ct.reshape(-1)[keep]
    dG, dc = dG.reshape(-1, D, cols.size)[keep], dc.reshape(-1, cols.size)[keep]
    er, ed = np.nonzero((G0 != 0) | np.any(dG != 0, axis=-1))

    def on_x(m) -> sp.csr_matrix:  # column j of m is column cols[j] of x
        m = sp.coo_matrix(m)
        return sp.csr_matrix((m.data, (m.row, cols[m.col])), shape=(m.shape[0], x_base.size))

    return UncertainAffineRows(entry_row=er, entry_coord=ed, G0=G0[er, ed], Gx=on_x(dG[er, ed].reshape(er.size, -1)),
                               c0=c0, cx=on_x(dc))


def best_guarantee_among_optima(system: AffineSystem, word: "str | ArrivalPattern", mu1: float, L: np.ndarray, *,
                                s0: np.ndarray | None = None, design_mode: str = "masked_gain",
                                runtime: str = "theorem2", bound: str = "all", solver: str = "highs",
                                recover: bool = False, rel_tol: float = OPTIMUM_RTOL,
                                abs_tol: float = OPTIMUM_ATOL, options: dict | None = None) -> GuaranteeAmongOptima:
    r"""The best guarantee any optimum of a design reading gives as the estimator that runs.

    The design LP of ``design_mode`` (:class:`AugmentedLP`) at fixed ``L`` and ``s0``
    usually has many optimal gains ``(M, ν)``, and the worst case of the estimator that
    actually runs with them (``runtime``) differs between them, so certifying the optimum
    a solver returns gives a solver-dependent number.  This function bounds the
    solver-independent

    .. math:: \gamma^* = \min\Big\{\max_{t,\,|\delta| \le b} |\xi^{\rm run}_t(M, \nu, \delta)| :
              (M, \nu, \mu_2) \text{ feasible for the design LP},\
              \mu_2 \le \mu_2^*(1 + \epsilon_r) + \epsilon_a\Big\}

    (``t = 0..T``, or ``t = T`` only with ``bound="terminal"``).  The design LP is built
    and solved first (its optimum ``μ2*``).  Then an LP is built on the design LP's columns
    (:meth:`AugmentedLP.add_decision_variables`) with its robust rows (level ``μ2``, ``μ1``
    at the end, ``μ2`` bounded as above) and the running error's robust rows bounded by a
    new variable ``γ``, minimised; all rows go through :func:`eqrec.lp.robust.add_robust_rows`
    (``form="abs"``), so ``γ`` is the exact worst case that
    :func:`eqrec.bounds.certify.certify_schedule` computes from the converted gains.

    * ``runtime="theorem2"`` (``L`` zeroed at missing steps): the error of ``s`` does not
      depend on the gains, so the running error is affine in ``(M, ν)`` with the innovation
      maps of the ``"theorem2"`` reading (:meth:`AugmentedLP.robust_rows` of an
      :class:`AugmentedLP` in that mode, same columns).  One LP: ``lower = upper = γ*``.
    * ``runtime="hold"`` (the constant ``L`` kept at missing steps): ``s`` then receives
      ``-L C s`` at a missing step, the later innovations depend on earlier injections and the
      running error has products of gains (not an LP).  Two LPs bound ``γ*``: *lower*, the
      ``"theorem2"`` LP restricted to the times ``t <= runtimes_agree_until(word)``, where the
      two runtimes have the same error for every gain; *upper*, the gains of the injections
      before the last missing step fixed at that solution (then the running error is affine
      in the others, its coefficients from the running estimator's model) and ``γ`` minimised over
      all times.  When they meet (:attr:`GuaranteeAmongOptima.exact`) the value is known.

    Parameters
    ----------
    system : AffineSystem
        The system.
    word : str or ArrivalPattern
        The designed worst-case word (the running estimator ignores measurements the word lacks,
        so its error is the same on every word with at least the designed word's measurements).
    mu1 : float
        Recovery level ``μ1``.
    L : numpy.ndarray
        Observer gain, ``(n, p)`` or ``(T, n, p)``, as for :class:`AugmentedLP`.
    s0 : numpy.ndarray, optional
        Fixed ``s0``, shape ``(n,)`` (default 0).
    design_mode : str, optional
        The design reading whose optima are searched (default ``"masked_gain"``).
    runtime : {"theorem2", "hold"}, optional
        The running estimator (:data:`eqrec.design.augmented.model.RUNTIME_MODES`).
    bound : {"all", "terminal"}, optional
        ``"all"``: every time (the certified ``μ2``); ``"terminal"``: the end of the horizon only.
    solver : str, optional
        LP solver of the registry (every LP).
    recover : bool, optional
        Also require the running error to recover: its worst case at ``t = T`` at most ``μ1``
        (imposed where the running error is affine: the ``"theorem2"`` LP, the ``"hold"`` upper
        LP; the lower LP of ``"hold"`` stays a relaxation, and the upper LP can be infeasible for
        the injections it fixes even when a recovering optimum exists).
    rel_tol, abs_tol : float, optional
        Tolerance of "optimal for the design LP".
    options : dict, optional
        Options of the LP solver.

    Returns
    -------
    GuaranteeAmongOptima

    Raises
    ------
    InputError
        Unknown ``runtime`` or ``bound``.
    InfeasibleDesign, SolverFailure
        If an LP has no optimum.
    """
    check_mode(design_mode, DESIGN_MODES)
    check_mode(runtime, RUNTIME_MODES)
    if bound not in ("all", "terminal"):
        raise InputError(f"bound must be 'all' or 'terminal', got {bound!r}", field="bound")
    design = AugmentedLP(system, word, mu1, L, s0=s0, mode=design_mode)
    opt = float(design.solve(solver, options).require_optimal(f"{design_mode} design LP ({solver})").objective)
    level = opt * (1.0 + rel_tol) + abs_tol
    n, T = system.n, design.T
    terminal = np.arange(T * n, (T + 1) * n)
    rows_bound = np.arange((T + 1) * n) if bound == "all" else terminal
    agree = runtimes_agree_until(design.word)
    rows_d, _ = design.robust_rows(L)  # the design reading's rows, shared by every LP below

    def optima_lp(extra_rows, fixed: dict | None = None, recover_rows=None):
        # the design LP's columns and robust rows, mu2 at most `level`, plus rows bounded by gamma (minimised)
        b = LPBuilder()
        mu2 = design.add_decision_variables(b, cost=False)
        gamma = int(b.add_variables(1, lower=0.0, name="gamma")[0])
        b.set_cost(gamma, 1.0)
        b.add_rows(np.array([0]), np.array([mu2]), np.array([1.0]), lower=-np.inf, upper=level, count=1)
        if fixed:
            cols = np.fromiter(fixed, dtype=np.int64)
            vals = np.array([fixed[c] for c in cols])
            b.add_rows(np.arange(cols.size), cols, np.ones(cols.size), lower=vals, upper=vals, count=cols.size)
        add_robust_rows(b, rows_d, design.radius, level_const=design.level_const, level_col=mu2,
                        level_coef=design.level_coef, form="abs")
        if extra_rows.num_rows:
            add_robust_rows(b, extra_rows, design.radius, level_const=0.0, level_col=gamma, level_coef=1.0,
                            form="abs")
        if recover_rows is not None:
            add_robust_rows(b, recover_rows, design.radius, level_const=design.mu1, form="abs")
        what = f"best {bound} guarantee ({runtime} runtime) among the {design_mode} optima ({solver})"
        sol = solve_lp(b.build(), solver, options).require_optimal(what)
        return sol, float(sol.x[gamma]), float(sol.x[mu2])

    # the theorem2 running error: affine in (M, nu); for "hold" only its rows up to `agree` are the same
    run = AugmentedLP(system, design.word, mu1, L, s0=design.s0, mode="theorem2")
    if run.m_cols.keys() != design.m_cols.keys() or not np.array_equal(run.nu_cols, design.nu_cols):
        raise AssertionError("design and runtime LPs do not share their columns")  # pragma: no cover
    rows_t2, _ = run.robust_rows(L)
    keep = rows_bound if runtime == "theorem2" else rows_bound[rows_bound < (agree + 1) * n]
    rec_t2 = _select_rows(rows_t2, terminal) if (recover and runtime == "theorem2") else None
    sol, lower, mu2v = optima_lp(_select_rows(rows_t2, keep), recover_rows=rec_t2)
    x = sol.x[: design.num_columns]
    upper = lower
    if runtime == "hold":
        # gains of the injections ue(j), j < last missing step, fixed: the hold error is affine in the rest
        q = arrival_indicator(design.word)
        k_last = int(np.flatnonzero(q == 0).max()) if np.any(q == 0) else 0
        early = np.concatenate([mc for (s_, _), mc in design.m_cols.items() if s_ < k_last]
                               + [design.nu_cols[: k_last * n]])
        free = np.setdiff1d(np.arange(1, design.num_columns), early)
        rows_h = _running_rows(system, design, x.copy(), free, "hold", rows_bound)
        rec_h = _running_rows(system, design, x.copy(), free, "hold", terminal) if recover else None
        sol2, upper, mu2v = optima_lp(rows_h, fixed={int(c): float(x[c]) for c in early}, recover_rows=rec_h)
        x = sol2.x[: design.num_columns]
    return GuaranteeAmongOptima(lower=lower, upper=upper, bound=bound, runtime=runtime, design_mode=design_mode,
                                design_optimum=opt, optimum_bound=level, gains=design.gains_from_x(x),
                                design_mu2=mu2v, agree_until=agree, solver=solver)
