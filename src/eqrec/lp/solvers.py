"""The LP solver registry: one list of solver names, one entry point.

Every design solves a :class:`eqrec.lp.model.LinearProgram`; the solver is a
parameter.  :data:`SOLVERS` maps each name to a :class:`SolverInfo`;
:data:`SOLVER_NAMES` is the list the CLI and the configuration schemas offer
(a test checks they agree).

``"ipopt"`` is the interior-point NLP solver the augmented paper uses, run
through CasADi on the LP as a smooth problem with linear constraints; its
optimum is accurate to its tolerance only, so :attr:`SolverInfo.accuracy`
widens the certification tolerance for it.  The nonconvex augmented design
with ``L`` free is a design *method* (:mod:`eqrec.design.augmented.nlp`), not
an LP solver.
"""

from __future__ import annotations

import re
import time
from contextlib import contextmanager
from dataclasses import dataclass
from typing import Callable

import numpy as np
import scipy.sparse as sp

from eqrec.lp.model import INF, LinearProgram, LPSolution
from eqrec.errors import InputError


#: HiGHS model status (``highspy.HighsModelStatus`` number) -> our status, for both HiGHS drivers (highspy and
#: SciPy's ``linprog``).  The definitive outcomes in our words ("unbounded or infeasible", which HiGHS's presolve
#: reports for an infeasible design LP, reads as infeasible: the design LPs bound their objective below); every
#: other status in HiGHS's own words (``Highs.modelStatusToString``; stored sweep results hold "Unknown", "Not Set"
#: and "Solve error").
HIGHS_STATUS: dict[int, str] = {
    0: "Not Set", 1: "Load error", 2: "Model error", 3: "Presolve error", 4: "Solve error", 5: "Postsolve error",
    6: "Empty", 7: "optimal", 8: "infeasible", 9: "infeasible", 10: "unbounded", 11: "Bound on objective reached",
    12: "Target for objective reached", 13: "Time limit reached", 14: "Iteration limit reached", 15: "Unknown",
    16: "Solution limit reached", 17: "Interrupted by user", 18: "Memory limit reached", 19: "Interrupted by HiGHS",
}

#: SciPy ``linprog`` status -> HiGHS model status, when SciPy's message does not carry HiGHS's own (SciPy's checks
#: before calling HiGHS): 0 optimal, 2 infeasible, 3 unbounded; 1 (a limit) and 4 (numerical) name no outcome.
_SCIPY_TO_HIGHS = {0: 7, 2: 8, 3: 10}


def highs_status(code: int, fallback: str = "") -> tuple[str, float]:
    """Our status of a HiGHS model status and the objective value that goes with it (:data:`HIGHS_STATUS`).

    Parameters
    ----------
    code : int
        The ``highspy.HighsModelStatus`` number.
    fallback : str
        The status of a number outside the table (default ``"HiGHS model status <code>"``).

    Returns
    -------
    status : str
        ``"optimal"``, ``"infeasible"``, ``"unbounded"`` or HiGHS's words for any other status.
    objective : float
        ``+inf`` for an infeasible LP, ``-inf`` for an unbounded one, ``nan`` otherwise (the optimal value is the
        caller's).
    """
    status = HIGHS_STATUS.get(int(code), fallback or f"HiGHS model status {int(code)}")
    return status, {"infeasible": INF, "unbounded": -INF}.get(status, np.nan)


def _f64(a) -> np.ndarray:
    """``a`` as a contiguous float64 array (a buffer HiGHS reads as is)."""
    return np.ascontiguousarray(a, dtype=np.float64)


def _i32(a) -> np.ndarray:
    """``a`` as a contiguous int32 array (HighsInt: 32 bits)."""
    return np.ascontiguousarray(a, dtype=np.int32)


def highs_model(lp: LinearProgram, options: dict):
    """A ``highspy.Highs`` holding ``lp`` with ``options`` set (quiet), for callers that keep the model and change it
    between runs (warm starts).

    The arrays go to HiGHS through its array form of ``passModel`` (NumPy buffers, read at C speed): the same model,
    entry for entry, as one filled in a ``highspy.HighsLp``, whose vector fields pybind11 converts one Python
    element at a time (seconds for the dense class LPs of a long horizon).  What HiGHS says of the model is
    read from the run, as before.

    Parameters
    ----------
    lp : LinearProgram
        The LP, its matrix column-wise (CSC) as :class:`~eqrec.lp.model.LinearProgram` stores it.
    options : dict
        HiGHS options, set one by one (``output_flag`` is set ``False`` first).

    Returns
    -------
    highspy.Highs
        The solver holding the model, not yet run.
    """
    import highspy

    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    for key, val in options.items():
        h.setOptionValue(key, val)
    nr, nc = lp.A.shape
    h.passModel(nc, nr, int(lp.A.nnz), int(highspy.MatrixFormat.kColwise),
                 int(highspy.ObjSense.kMinimize), 0.0, _f64(lp.c), _f64(lp.col_lower), _f64(lp.col_upper),
                 _f64(lp.row_lower), _f64(lp.row_upper), _i32(lp.A.indptr), _i32(lp.A.indices), _f64(lp.A.data),
                 np.zeros(nc, np.int32))  # every column continuous
    return h


def _highs_run(h, lp: LinearProgram, cost: np.ndarray) -> LPSolution:
    """Run ``h`` (holding ``lp`` with objective ``cost``) and read its answer."""
    t0 = time.perf_counter()
    h.run()
    elapsed = time.perf_counter() - t0
    ms = h.getModelStatus()
    info = h.getInfo()
    iters = int(info.simplex_iteration_count) + int(max(info.ipm_iteration_count, 0))
    status, objective = highs_status(int(ms), h.modelStatusToString(ms))
    if status == "optimal":
        hs = h.getSolution()
        x = np.asarray(hs.col_value)
        return LPSolution("optimal", x, float(cost @ x), "highs", iters, elapsed, lp.blocks,
                          row_dual=np.asarray(hs.row_dual) if hs.dual_valid else None)
    return LPSolution(status, None, objective, "highs", iters, elapsed, lp.blocks)


def _solve_highs(lp: LinearProgram, options: dict) -> LPSolution:
    return _highs_run(highs_model(lp, options), lp, lp.c)


def _solve_clarabel(lp: LinearProgram, options: dict) -> LPSolution:
    import clarabel

    A = lp.A.tocsr()
    nc = A.shape[1]
    eye = sp.identity(nc, format="csr")
    eq = np.isfinite(lp.row_lower) & (lp.row_lower == lp.row_upper)
    up = np.isfinite(lp.row_upper) & ~eq
    lo = np.isfinite(lp.row_lower) & ~eq
    cup = np.isfinite(lp.col_upper)
    clo = np.isfinite(lp.col_lower)
    # Clarabel form: A_c x + s = b, s in cones; equalities first (zero cone).
    parts = [A[eq], A[up], -A[lo], eye[cup], -eye[clo]]
    rhs = [lp.row_upper[eq], lp.row_upper[up], -lp.row_lower[lo], lp.col_upper[cup], -lp.col_lower[clo]]
    Ac = sp.vstack(parts, format="csc")
    b = np.concatenate(rhs)
    n_eq = int(eq.sum())
    cones = []
    if n_eq:
        cones.append(clarabel.ZeroConeT(n_eq))
    if Ac.shape[0] - n_eq:
        cones.append(clarabel.NonnegativeConeT(Ac.shape[0] - n_eq))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    for key, val in options.items():
        setattr(settings, key, val)
    P = sp.csc_matrix((nc, nc))
    t0 = time.perf_counter()
    solver = clarabel.DefaultSolver(P, lp.c, Ac, b, cones, settings)
    sol = solver.solve()
    elapsed = time.perf_counter() - t0
    status = str(sol.status)
    if status in ("Solved", "AlmostSolved"):
        x = np.asarray(sol.x)
        # KKT of Clarabel: c + A_cᵀ z = 0, so y = -z on equality and upper rows, +z on (negated) lower rows
        z = np.asarray(sol.z)
        y = np.zeros(A.shape[0])
        k = 0
        for mask, sign in ((eq, -1.0), (up, -1.0), (lo, 1.0)):
            cnt = int(mask.sum())
            y[mask] += sign * z[k:k + cnt]
            k += cnt
        return LPSolution("optimal", x, float(lp.c @ x), "clarabel", int(sol.iterations), elapsed, lp.blocks,
                          row_dual=y)
    if "PrimalInfeasible" in status:
        return LPSolution("infeasible", None, INF, "clarabel", int(sol.iterations), elapsed, lp.blocks)
    if "DualInfeasible" in status:
        return LPSolution("unbounded", None, -INF, "clarabel", int(sol.iterations), elapsed, lp.blocks)
    return LPSolution(status, None, np.nan, "clarabel", int(sol.iterations), elapsed, lp.blocks)


def _solve_scipy(lp: LinearProgram, options: dict) -> LPSolution:
    from scipy.optimize import linprog

    A = lp.A.tocsr()
    eq = lp.row_lower == lp.row_upper
    up = np.isfinite(lp.row_upper) & ~eq
    lo = np.isfinite(lp.row_lower) & ~eq
    A_ub = sp.vstack([A[up], -A[lo]], format="csr")
    b_ub = np.concatenate([lp.row_upper[up], -lp.row_lower[lo]])
    bounds = np.column_stack([np.where(np.isfinite(lp.col_lower), lp.col_lower, None),
                              np.where(np.isfinite(lp.col_upper), lp.col_upper, None)])
    t0 = time.perf_counter()
    res = linprog(lp.c, A_ub=A_ub, b_ub=b_ub, A_eq=A[eq] if eq.any() else None,
                  b_eq=lp.row_upper[eq] if eq.any() else None, bounds=bounds, method="highs", options=options)
    elapsed = time.perf_counter() - t0
    code = re.search(r"HiGHS Status (\d+)", str(res.message))  # SciPy's message names HiGHS's model status
    status, obj = highs_status(int(code.group(1)) if code else _SCIPY_TO_HIGHS.get(res.status, -1), str(res.message))
    x = res.x if status == "optimal" else None
    y = None
    if status == "optimal":  # marginals are d(objective)/d(rhs): y on equality and upper rows, minus on lower rows
        y = np.zeros(A.shape[0])
        if eq.any():
            y[eq] = res.eqlin.marginals
        m_ub = np.asarray(res.ineqlin.marginals) if A_ub.shape[0] else np.zeros(0)
        y[up] += m_ub[: int(up.sum())]
        y[lo] -= m_ub[int(up.sum()):]
        obj = float(res.fun)
    return LPSolution(status, x, obj, "scipy", int(getattr(res, "nit", 0) or 0), elapsed, lp.blocks, row_dual=y)


#: The IPOPT settings of every nonlinear solve (CasADi ``nlpsol`` options): quiet, tolerance 1e-9, at most 3000
#: iterations.  :func:`ipopt_options` adds the caller's settings.
IPOPT_OPTIONS: dict = {"ipopt.print_level": 0, "ipopt.sb": "yes", "print_time": False, "ipopt.tol": 1e-9,
                       "ipopt.max_iter": 3000}


def ipopt_options(options: dict | None = None, *, prefix: bool = True, **defaults) -> dict:
    """CasADi ``nlpsol`` options for IPOPT: :data:`IPOPT_OPTIONS`, then ``defaults``, then ``options``.

    Parameters
    ----------
    options : dict or None, optional
        The caller's settings; with ``prefix``, a name without a dot is an IPOPT option (``tol`` ->
        ``ipopt.tol``).
    prefix : bool, optional
        Whether to add ``ipopt.`` to the names of ``options`` without a dot.
    **defaults : object
        Settings of one use (e.g. ``{"ipopt.acceptable_tol": 1e-7}``), overridden by ``options``.

    Returns
    -------
    dict
        The options to pass to ``casadi.nlpsol(..., "ipopt", ...)``.
    """
    out = {**IPOPT_OPTIONS, **defaults}
    for key, val in (options or {}).items():
        out[key if not prefix or "." in key else f"ipopt.{key}"] = val
    return out


def _solve_ipopt(lp: LinearProgram, options: dict) -> LPSolution:
    import casadi as ca

    A = lp.A.tocsc()
    A.sort_indices()
    nr, nc = A.shape
    x = ca.MX.sym("x", nc)
    Acas = ca.DM(ca.Sparsity(nr, nc, A.indptr.tolist(), A.indices.tolist()), A.data)
    nlp = {"x": x, "f": ca.dot(ca.DM(lp.c), x), "g": ca.mtimes(Acas, x)}
    x0 = np.asarray(options.pop("x0", np.zeros(nc)), float)
    solver = ca.nlpsol("lp", "ipopt", nlp, ipopt_options(options))
    t0 = time.perf_counter()
    sol = solver(x0=x0, lbx=lp.col_lower, ubx=lp.col_upper, lbg=lp.row_lower, ubg=lp.row_upper)
    elapsed = time.perf_counter() - t0
    stats = solver.stats()
    status = str(stats.get("return_status"))
    iters = int(stats.get("iter_count", 0))
    if status in ("Solve_Succeeded", "Solved_To_Acceptable_Level"):
        xv = np.asarray(sol["x"]).reshape(-1)
        # stationarity of c x + lam_gᵀ (A x) + lam_xᵀ x: y = -lam_g
        return LPSolution("optimal", xv, float(lp.c @ xv), "ipopt", iters, elapsed, lp.blocks,
                          row_dual=-np.asarray(sol["lam_g"]).reshape(-1))
    if status == "Infeasible_Problem_Detected":
        return LPSolution("infeasible", None, INF, "ipopt", iters, elapsed, lp.blocks)
    if status == "Diverging_Iterates":
        return LPSolution("unbounded", None, -INF, "ipopt", iters, elapsed, lp.blocks)
    return LPSolution(status, None, np.nan, "ipopt", iters, elapsed, lp.blocks)


@dataclass(frozen=True)
class SolverInfo:
    """A registered LP solver.

    Parameters
    ----------
    name : str
        Registry key (what users type).
    description : str
        One line for ``--help`` and the README.
    solve : callable
        ``solve(lp, options) -> LPSolution``.
    accuracy : float, optional
        Absolute accuracy of its optimum beyond the feasibility tolerance
        (added to the certification tolerance).
    """

    name: str
    description: str
    solve: Callable[[LinearProgram, dict], LPSolution]
    accuracy: float = 0.0


SOLVERS: dict[str, SolverInfo] = {
    "highs": SolverInfo("highs", "HiGHS dual simplex (highspy); exact vertex optimum", _solve_highs),
    "clarabel": SolverInfo("clarabel", "Clarabel interior point", _solve_clarabel),
    "scipy": SolverInfo("scipy", "scipy.optimize.linprog (HiGHS inside SciPy)", _solve_scipy),
    "ipopt": SolverInfo("ipopt", "IPOPT interior point through CasADi (the augmented paper's solver)",
                        _solve_ipopt, accuracy=1e-6),
}

#: The solver names offered by the CLI and the configuration schemas.
SOLVER_NAMES: tuple[str, ...] = tuple(SOLVERS)


def solver_info(name: str) -> SolverInfo:
    """The registry entry of ``name``; an :class:`~eqrec.errors.InputError` (field ``solver``) naming the choices otherwise.

    Parameters
    ----------
    name : str
        A name of :data:`SOLVER_NAMES`.

    Returns
    -------
    SolverInfo
        The entry of :data:`SOLVERS`.

    Raises
    ------
    InputError
        For any other value (also a :class:`ValueError`).
    """
    if not isinstance(name, str) or name not in SOLVERS:
        raise InputError(f"unknown solver {name!r}; choose one of {list(SOLVER_NAMES)}", field="solver")
    return SOLVERS[name]


#: Statuses that end the search for an answer: a definitive outcome, or a limit or stop (HiGHS sets no time or
#: iteration limit of its own: a limit is the caller's) (:func:`solve_lp` retries every other status).
FINAL_STATUSES = frozenset({"optimal", "infeasible", "unbounded", "Time limit reached", "Iteration limit reached",
                            "Interrupted by user", "Memory limit reached"})

#: The retries of :func:`solve_lp` after a solve ends without a usable status, in order: ``(solver, what,
#: options)``.  The HiGHS settings start from HiGHS's defaults (the caller's options may be what failed);
#: ``"scaled"`` is HiGHS on the model equilibrated by :func:`scaled_lp`; the last resort is another solver.
#: A retry with the caller's own solver and options is skipped (it would repeat the same run).  Measured on the
#: two-mass plant's (4, 100) design: a warm-started dual simplex that stalls on "basis change is taboo"
#: (status 'Unknown') and a dual phase 1 that meets a spurious unbounded ray on an ill-scaled Charnes-Cooper
#: LP (matrix entries over 3.5e7, status 'Not Set') both answer at the first retry.
RETRIES: tuple[tuple[str, str, dict | str], ...] = (
    ("highs", "defaults, cold start", {}),
    ("highs", "presolve off", {"presolve": "off"}),
    ("highs", "primal simplex", {"simplex_strategy": 4}),
    ("highs", "interior point", {"solver": "ipm"}),
    ("highs", "scaled model", "scaled"),
    ("clarabel", "", {}),
)


def scaled_lp(lp: LinearProgram, passes: int = 8) -> tuple[LinearProgram, np.ndarray, np.ndarray]:
    """``lp`` with its rows and columns scaled by powers of 2 (geometric equilibration of ``A``).

    With ``A' = R A S`` (``R``, ``S`` diagonal, powers of two so that the scaling itself is exact), the LP in
    ``x' = S^{-1} x`` has cost ``S c``, column bounds ``S^{-1}`` times ``lp``'s and row bounds ``R`` times; an
    optimum ``x'``, ``y'`` of it gives ``x = S x'`` and ``y = R y'`` for ``lp`` (same objective).

    Parameters
    ----------
    lp : LinearProgram
        The model.
    passes : int, optional
        Alternating row and column passes.

    Returns
    -------
    tuple
        The scaled :class:`LinearProgram`, the row factors ``R`` ``(M,)`` and the column factors ``S`` ``(N,)``.
    """
    A = sp.csc_matrix(lp.A, copy=True)
    A.data = np.abs(A.data)
    A.eliminate_zeros()
    nr, nc = A.shape
    R, S = np.ones(nr), np.ones(nc)
    logA = A.copy()
    logA.data = np.log2(logA.data)
    for _ in range(passes):
        # each row (column): bring the geometric mean of its largest and smallest entry to 1
        M = logA.tocsr()
        B = M.copy()
        B.data = B.data + np.log2(R)[np.repeat(np.arange(nr), np.diff(M.indptr))] + \
            np.log2(S)[M.indices]
        R *= _mid_scale(B.data, B.indptr)
        Bc = logA.copy()
        Bc.data = Bc.data + np.log2(R)[Bc.indices] + np.log2(S)[np.repeat(np.arange(nc), np.diff(Bc.indptr))]
        S *= _mid_scale(Bc.data, Bc.indptr)
    As = sp.diags(R) @ lp.A @ sp.diags(S)
    out = LinearProgram(c=lp.c * S, A=sp.csc_matrix(As), row_lower=lp.row_lower * R, row_upper=lp.row_upper * R,
                        col_lower=lp.col_lower / S, col_upper=lp.col_upper / S, blocks=lp.blocks)
    return out, R, S


def _mid_scale(logs: np.ndarray, indptr: np.ndarray) -> np.ndarray:
    """Per segment of ``logs`` (log2 of the entries of a row or column): ``2^-round((max + min) / 2)``; 1 if empty."""
    has = np.diff(indptr) > 0
    out = np.ones(indptr.size - 1)
    if has.any():
        starts = indptr[:-1][has]  # the nonempty segments, delimited by each other's starts
        mid = (np.maximum.reduceat(logs, starts) + np.minimum.reduceat(logs, starts)) / 2
        out[has] = np.exp2(-np.round(mid))
    return out


def _solve_scaled(name: str, lp: LinearProgram, options: dict) -> LPSolution:
    """Solve :func:`scaled_lp` of ``lp`` with solver ``name`` and map its answer back to ``lp``."""
    model, R, S = scaled_lp(lp)
    sol = SOLVERS[name].solve(model, options)
    if sol.x is None:
        return sol
    x = sol.x * S
    return LPSolution(sol.status, x, float(lp.c @ x), sol.solver, sol.iterations, sol.solve_time, lp.blocks,
                      row_dual=None if sol.row_dual is None else sol.row_dual * R)


#: The active retry logs of :func:`retry_log`, innermost last.
_LOGS: list[list[str]] = []


@contextmanager
def retry_log():
    """Collect, while active, the LP solves of this process that needed a retry of :func:`solve_lp`.

    Each entry is the :attr:`LPSolution.solved_by` of a retried solve (``"failed"`` when every attempt failed),
    recorded in the innermost active log only; :func:`record_retries` adds the entries of solves made elsewhere
    (worker processes).

    Yields
    ------
    list of str
        The entries, in the order of the solves.
    """
    entries: list[str] = []
    _LOGS.append(entries)
    try:
        yield entries
    finally:
        del _LOGS[next(i for i, log in enumerate(_LOGS) if log is entries)]  # by identity: logs compare equal


def record_retries(entries) -> None:
    """Add ``entries`` (from another process's :func:`retry_log`) to the innermost active log, if any.

    Parameters
    ----------
    entries : iterable of str
    """
    if _LOGS:
        _LOGS[-1].extend(entries)


def _attempt_name(solver: str, what: str) -> str:
    return f"{solver}, {what}" if what else solver


def solve_lp(lp: LinearProgram, solver: str = "highs", options: dict | None = None, *,
             retry: bool = True, tried: tuple[str, ...] = ()) -> LPSolution:
    """Solve a :class:`LinearProgram` with a registered solver, retrying other settings when it gives no answer.

    When the solve ends without a usable status (any status outside :data:`FINAL_STATUSES`, e.g. HiGHS's
    'Not Set' or 'Unknown' after a numerical breakdown), the solves of :data:`RETRIES` are tried in order
    until one answers; :attr:`LPSolution.attempts` lists the ones that did not and
    :attr:`LPSolution.solved_by` the one that did.  The model is never changed.

    Parameters
    ----------
    lp : LinearProgram
        The problem.
    solver : str, optional
        A name of :data:`SOLVER_NAMES` (default ``"highs"``).
    options : dict or None, optional
        Passed to the solver (HiGHS option names, Clarabel settings, IPOPT
        options; ``x0`` is IPOPT's starting point); not to the retries.
    retry : bool, optional
        Whether to retry (default); ``False``: the one solve's answer, whatever its status.
    tried : tuple of str, optional
        Attempts already made by the caller (e.g. a warm-started HiGHS run), each ``"what: status"``; they are
        listed first in :attr:`LPSolution.attempts`.

    Returns
    -------
    LPSolution
        Never raises for infeasibility; call :meth:`LPSolution.require_optimal`.  When every attempt fails:
        the first one's answer, with every attempt in ``attempts`` (the message of
        :meth:`~LPSolution.require_optimal` names them).
    """
    options = dict(options or {})
    first = solver_info(solver).solve(lp, dict(options))
    if not retry or first.status in FINAL_STATUSES:
        if tried:
            first.attempts, first.solved_by = tuple(tried), _attempt_name(solver, "cold start")
            record_retries([first.solved_by])
        return first
    mine = ", ".join(f"{k}={v}" for k, v in options.items() if k != "x0")
    attempts = list(tried) + [f"{_attempt_name(solver, mine)}: {first.status}"]
    for name, what, opts in RETRIES:
        if name == solver and opts == options:
            continue  # the same solve again
        if opts == "scaled":
            sol = _solve_scaled(name, lp, {})
        else:
            sol = SOLVERS[name].solve(lp, dict(opts))
        if sol.status in FINAL_STATUSES:
            sol.attempts, sol.solved_by = tuple(attempts), _attempt_name(name, what)
            record_retries([sol.solved_by])
            return sol
        attempts.append(f"{_attempt_name(name, what)}: {sol.status}")
    first.attempts = tuple(attempts)
    record_retries(["failed"])
    return first


def solve_lp_warm(lp: LinearProgram, basis=None, options: dict | None = None):
    """Solve ``lp`` with HiGHS from ``basis``, the optimal basis of an LP of the same shape (e.g. the previous
    point of a sweep whose coefficients move a little): the answer and its own optimal basis, for the next.

    The basis is only a starting point: the optimum is the LP's own, but where it is not unique (a vertex, or
    its last bits) a warm start may end at another optimal vertex than a cold one, so a sweep's answers then
    depend on the order of its points (kept fixed by the caller).  Without ``basis`` (or with one of another
    shape) this is the cold HiGHS solve of :func:`solve_lp`, the same numbers.  A run that ends without a usable
    status is solved again from scratch with the retries of :func:`solve_lp`.

    Parameters
    ----------
    lp : LinearProgram
        The problem.
    basis : highspy.HighsBasis or None, optional
        Where to start (``None``: from scratch).
    options : dict or None, optional
        HiGHS options, as :func:`solve_lp`.

    Returns
    -------
    solution : LPSolution
        The answer (never raises for infeasibility).
    basis : highspy.HighsBasis or None
        Its optimal basis (``None`` when it is not optimal or came from a retry).
    """
    nr, nc = lp.A.shape
    h = highs_model(lp, dict(options or {}))
    warm = basis is not None and len(basis.col_status) == nc and len(basis.row_status) == nr
    if warm:
        h.setBasis(basis)
    sol = _highs_run(h, lp, lp.c)
    if sol.status not in FINAL_STATUSES:  # from scratch, with the retries (a cold run: exactly solve_lp's answer)
        return solve_lp(lp, "highs", options, tried=(f"highs, warm start: {sol.status}",) if warm else ()), None
    return sol, (h.getBasis() if sol.status == "optimal" else None)


def solve_lp_grid(lp: LinearProgram, costs, bounds=None, solver: str = "highs",
                  options: dict | None = None) -> list[list[LPSolution]]:
    """Solve ``lp`` for every column-bound pair of ``bounds`` and, under each, every objective of ``costs``.

    The rows and the matrix stay.  With HiGHS the model is loaded once and each solve starts from the previous
    optimal basis (after an objective change it is still primal feasible, after a bound change still dual
    feasible), in the fixed order bounds then objectives, so the answers depend only on the arguments; the other
    solvers solve each variant from scratch.

    Parameters
    ----------
    lp : LinearProgram
        The problem (its own ``c`` is ignored; its column bounds are used when ``bounds`` is ``None``).
    costs : sequence of numpy.ndarray
        The objectives, each of length ``lp.shape[1]``.
    bounds : sequence of tuple of numpy.ndarray, optional
        ``(col_lower, col_upper)`` pairs (default: ``lp``'s own, once).
    solver : str, optional
        A name of :data:`SOLVER_NAMES` (default ``"highs"``).
    options : dict or None, optional
        Passed to the solver, as :func:`solve_lp`.

    Returns
    -------
    list of list of LPSolution
        ``out[j][i]``: bounds ``j``, objective ``i`` (never raises for infeasibility).
    """
    solver_info(solver)
    bounds = [(lp.col_lower, lp.col_upper)] if bounds is None else list(bounds)
    variant = lambda c, lo, hi: LinearProgram(c=np.asarray(c, float), A=lp.A, row_lower=lp.row_lower,  # noqa: E731
                                              row_upper=lp.row_upper, col_lower=lo, col_upper=hi, blocks=lp.blocks)
    if solver != "highs":
        return [[solve_lp(variant(c, lo, hi), solver, options) for c in costs] for lo, hi in bounds]
    out: list[list[LPSolution]] = []
    h = None
    cols = np.arange(lp.A.shape[1], dtype=np.int32)
    for lo, hi in bounds:
        if h is not None:
            h.changeColsBounds(cols.size, cols, np.asarray(lo, float), np.asarray(hi, float))
        row = []
        for c in costs:
            c = np.asarray(c, float)
            if h is None:
                h = highs_model(variant(c, lo, hi), dict(options or {}))
            else:
                h.changeColsCost(c.size, cols, c)
            sol = _highs_run(h, lp, c)
            if sol.status not in FINAL_STATUSES:
                # a warm start that broke down (e.g. 'Unknown' after "basis change is taboo"): this variant from
                # scratch with the retries of solve_lp, and the next one from scratch too
                h.clearSolver()
                sol = solve_lp(variant(c, lo, hi), solver, options, tried=(f"highs, warm start: {sol.status}",))
            row.append(sol)
        out.append(row)
    return out



def leading_lp(lp: LinearProgram, rows: int, cols: int, cost: np.ndarray, bounds=None) -> LinearProgram:
    """The LP on the first ``rows`` rows and ``cols`` columns of ``lp``, with objective ``cost``.

    Parameters
    ----------
    lp : LinearProgram
    rows, cols : int
        Size of the leading block (its rows must not touch a later column).
    cost : numpy.ndarray
        Objective, length ``cols``.
    bounds : tuple of numpy.ndarray, optional
        ``(col_lower, col_upper)`` of every column of ``lp`` (default ``lp``'s own).

    Returns
    -------
    LinearProgram
    """
    lo, hi = (lp.col_lower, lp.col_upper) if bounds is None else bounds
    return LinearProgram(c=np.asarray(cost, float), A=sp.csc_matrix(lp.A[:rows, :cols]),
                         row_lower=lp.row_lower[:rows], row_upper=lp.row_upper[:rows],
                         col_lower=np.asarray(lo, float)[:cols], col_upper=np.asarray(hi, float)[:cols],
                         blocks=lp.blocks)


def solve_lp_chain(lp: LinearProgram, prefixes, costs, bounds=None, solver: str = "highs",
                   options: dict | None = None) -> list[list[LPSolution]]:
    """Solve the growing leading blocks of ``lp`` in order, under each column-bound pair, each run warm-started.

    Block ``k`` is the LP on the first ``prefixes[k] = (rows, cols)`` rows and columns of ``lp`` (sizes
    nondecreasing; a block's rows touch none of the later columns) with objective ``costs[k]``, solved under
    every ``(col_lower, col_upper)`` of ``bounds``.  With HiGHS one model grows: the new columns are appended
    (nonbasic at a bound), then the new rows (their slacks basic), and each run starts from the basis of the
    run before, the bounds taken in the order ``0, 1, ...`` for even ``k`` and in reverse for odd ``k``, so that a
    block starts under the bounds the one before ended with (only the objective and the new rows change) and a
    change of bounds keeps the basis dual feasible.  The order is fixed, so the answers depend only on the
    arguments.  A run that ends without a usable status is solved again from scratch with the retries of
    :func:`solve_lp`, and the chain goes on from scratch.  The other solvers solve every variant from scratch.

    Parameters
    ----------
    lp : LinearProgram
        The largest block (its own ``c`` is ignored; its column bounds are used when ``bounds`` is ``None``).
    prefixes : sequence of tuple of int
        ``(rows, cols)`` of each block.
    costs : sequence of numpy.ndarray
        The objective of each block, of length its ``cols``.
    bounds : sequence of tuple of numpy.ndarray, optional
        ``(col_lower, col_upper)`` pairs over every column of ``lp`` (default: ``lp``'s own, once).
    solver : str, optional
        A name of :data:`SOLVER_NAMES` (default ``"highs"``).
    options : dict or None, optional
        Passed to the solver, as :func:`solve_lp`.

    Returns
    -------
    list of list of LPSolution
        ``out[k][j]``: block ``k`` under bounds ``j`` (``x`` of its columns, ``row_dual`` of its rows; never raises
        for infeasibility).
    """
    solver_info(solver)
    bounds = [(lp.col_lower, lp.col_upper)] if bounds is None else [tuple(np.asarray(b, float) for b in pair)
                                                                    for pair in bounds]
    if solver != "highs":
        return [[solve_lp(leading_lp(lp, r, c, cost, b), solver, options) for b in bounds]
                for (r, c), cost in zip(prefixes, costs)]
    A_cols, A_rows = sp.csc_matrix(lp.A), sp.csr_matrix(lp.A)
    lo0, hi0 = bounds[0]
    vary = np.flatnonzero(np.any([(lo != lo0) | (hi != hi0) for lo, hi in bounds], axis=0)).astype(np.int32)
    out: list[list[LPSolution]] = []
    h, r0, c0, prev, cur = None, 0, 0, np.zeros(0), 0  # cur: the bounds the model holds
    for k, ((r1, c1), cost) in enumerate(zip(prefixes, costs)):
        cost = np.asarray(cost, float)
        order = list(range(len(bounds))) if k % 2 == 0 else list(range(len(bounds)))[::-1]
        row: list = [None] * len(bounds)
        for j in order:
            lo, hi = bounds[j]
            if h is None:  # the first block, or after a breakdown
                h = highs_model(leading_lp(lp, r1, c1, cost, bounds[j]), dict(options or {}))
            else:
                if j != cur:  # switch the bounds that differ between the variants
                    sw = vary[vary < c0]
                    h.changeColsBounds(sw.size, sw, _f64(lo[sw]), _f64(hi[sw]))
                if c1 > c0:  # new columns, with their entries in the rows already there (cost set below)
                    new = A_cols[:r0, c0:c1].tocsc()
                    h.addCols(c1 - c0, np.zeros(c1 - c0), _f64(lo[c0:c1]), _f64(hi[c0:c1]), int(new.nnz),
                              _i32(new.indptr[:-1]), _i32(new.indices), _f64(new.data))
                if r1 > r0:  # new rows over every column so far
                    new = A_rows[r0:r1, :c1].tocsr()
                    h.addRows(r1 - r0, _f64(lp.row_lower[r0:r1]), _f64(lp.row_upper[r0:r1]), int(new.nnz),
                              _i32(new.indptr[:-1]), _i32(new.indices), _f64(new.data))
                changed = np.flatnonzero(np.concatenate([prev, np.zeros(c1 - prev.size)]) != cost).astype(np.int32)
                if changed.size:
                    h.changeColsCost(changed.size, changed, _f64(cost[changed]))
            r0, c0, prev, cur = r1, c1, cost, j
            sol = _highs_run(h, lp, cost)
            if sol.status not in FINAL_STATUSES:
                h = None  # the next run from scratch too
                sol = solve_lp(leading_lp(lp, r1, c1, cost, bounds[j]), solver, options,
                               tried=(f"highs, warm start: {sol.status}",))
            row[j] = sol
        out.append(row)
    return out
