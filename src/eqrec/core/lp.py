"""Sparse linear programs: building, solving and reading are separate steps.

The design problems of the papers are robust LPs whose finite counterparts
(eq. (16) of the prefix-based paper) have a few thousand sparse rows.  A
modelling layer such as cvxpy spends longer canonicalising them than HiGHS
spends solving them, so we assemble the sparse matrix ourselves:

1. :class:`LPBuilder` collects variable blocks and constraint rows as
   coordinate triplets;
2. :meth:`LPBuilder.build` freezes them into a :class:`LinearProgram`
   (CSC matrix + row and column bounds), independent of any solver;
3. :func:`solve_lp` passes it to a named solver (``"highs"`` through
   highspy, ``"clarabel"`` through its Python API, ``"scipy"`` through
   :func:`scipy.optimize.linprog`) and returns an :class:`LPSolution`;
4. the caller reads variable blocks with :meth:`LPSolution.block`.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from eqrec.errors import InfeasibleDesign, SolverFailure

INF = np.inf
SOLVERS = ("highs", "clarabel", "scipy")


@dataclass
class LinearProgram:
    """``min c^T x`` subject to ``row_lower <= A x <= row_upper`` and ``col_lower <= x <= col_upper``."""

    c: np.ndarray
    A: sp.csc_matrix
    row_lower: np.ndarray
    row_upper: np.ndarray
    col_lower: np.ndarray
    col_upper: np.ndarray
    blocks: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def shape(self) -> tuple[int, int]:
        return self.A.shape

    def residual(self, x: np.ndarray) -> float:
        """Largest violation of any row or column bound by ``x``."""
        ax = self.A @ x
        viol = [np.max(self.row_lower - ax, initial=0.0), np.max(ax - self.row_upper, initial=0.0),
                np.max(self.col_lower - x, initial=0.0), np.max(x - self.col_upper, initial=0.0)]
        return float(max(viol))


class LPBuilder:
    """Accumulates variables and sparse rows of a linear program."""

    def __init__(self) -> None:
        self._ncols = 0
        self._col_lower: list[np.ndarray] = []
        self._col_upper: list[np.ndarray] = []
        self._cost: dict[int, float] = {}
        self._rows: list[np.ndarray] = []
        self._cols: list[np.ndarray] = []
        self._vals: list[np.ndarray] = []
        self._row_lower: list[np.ndarray] = []
        self._row_upper: list[np.ndarray] = []
        self._nrows = 0
        self.blocks: dict[str, np.ndarray] = {}

    @property
    def num_variables(self) -> int:
        return self._ncols

    @property
    def num_rows(self) -> int:
        return self._nrows

    def add_variables(self, count: int, lower: float | np.ndarray = -INF, upper: float | np.ndarray = INF,
                      name: str | None = None) -> np.ndarray:
        """Add ``count`` variables and return their column indices."""
        idx = np.arange(self._ncols, self._ncols + count)
        self._ncols += count
        self._col_lower.append(np.broadcast_to(np.asarray(lower, float), (count,)).copy())
        self._col_upper.append(np.broadcast_to(np.asarray(upper, float), (count,)).copy())
        if name is not None:
            self.blocks[name] = idx
        return idx

    def set_cost(self, columns: np.ndarray | int, coefficients: np.ndarray | float) -> None:
        """Add ``coefficients`` to the objective coefficients of ``columns``."""
        for j, c in zip(np.atleast_1d(columns), np.broadcast_to(coefficients, np.shape(np.atleast_1d(columns)))):
            self._cost[int(j)] = self._cost.get(int(j), 0.0) + float(c)

    def add_rows(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray,
                 lower: np.ndarray | float, upper: np.ndarray | float, count: int | None = None) -> np.ndarray:
        """Add a block of rows given as local coordinate triplets.

        Parameters
        ----------
        rows, cols, vals
            Triplets; ``rows`` are local (0 .. count-1), ``cols`` global.
        lower, upper
            Row bounds (broadcast to ``count``).
        count
            Number of rows (default ``max(rows) + 1``).
        """
        rows = np.asarray(rows, dtype=np.int64).ravel()
        if count is None:
            count = int(rows.max()) + 1 if rows.size else 0
        self._rows.append(rows + self._nrows)
        self._cols.append(np.asarray(cols, dtype=np.int64).ravel())
        self._vals.append(np.asarray(vals, dtype=float).ravel())
        self._row_lower.append(np.broadcast_to(np.asarray(lower, float), (count,)).copy())
        self._row_upper.append(np.broadcast_to(np.asarray(upper, float), (count,)).copy())
        out = np.arange(self._nrows, self._nrows + count)
        self._nrows += count
        return out

    def build(self) -> LinearProgram:
        """Freeze into a solver-independent :class:`LinearProgram`."""
        c = np.zeros(self._ncols)
        for j, v in self._cost.items():
            c[j] = v
        rows = np.concatenate(self._rows) if self._rows else np.zeros(0, np.int64)
        cols = np.concatenate(self._cols) if self._cols else np.zeros(0, np.int64)
        vals = np.concatenate(self._vals) if self._vals else np.zeros(0)
        keep = vals != 0.0
        A = sp.csc_matrix((vals[keep], (rows[keep], cols[keep])), shape=(self._nrows, self._ncols))
        A.sum_duplicates()
        cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)  # noqa: E731
        return LinearProgram(c=c, A=A, row_lower=cat(self._row_lower), row_upper=cat(self._row_upper),
                             col_lower=cat(self._col_lower), col_upper=cat(self._col_upper),
                             blocks=dict(self.blocks))


@dataclass
class LPSolution:
    """What a solver returned, in solver-independent form."""

    status: str  # "optimal", "infeasible", "unbounded", or a solver message
    x: np.ndarray | None
    objective: float
    solver: str
    iterations: int
    solve_time: float  # seconds spent inside the solver call
    blocks: dict[str, np.ndarray] = field(default_factory=dict)

    @property
    def optimal(self) -> bool:
        return self.status == "optimal"

    def block(self, name: str) -> np.ndarray:
        """Values of a named variable block."""
        if self.x is None:
            raise SolverFailure(f"no solution to read (status {self.status})")
        return self.x[self.blocks[name]]

    def require_optimal(self, what: str = "design") -> "LPSolution":
        """Raise :class:`InfeasibleDesign` or :class:`SolverFailure` unless optimal."""
        if self.status == "infeasible":
            raise InfeasibleDesign(f"{what} is infeasible ({self.solver})")
        if self.status == "unbounded":
            raise InfeasibleDesign(f"{what} is unbounded ({self.solver})")
        if not self.optimal:
            raise SolverFailure(f"{what}: solver {self.solver} stopped with status '{self.status}'")
        return self


def _solve_highs(lp: LinearProgram, options: dict) -> LPSolution:
    import highspy

    h = highspy.Highs()
    h.setOptionValue("output_flag", False)
    for key, val in options.items():
        h.setOptionValue(key, val)
    model = highspy.HighsLp()
    nr, nc = lp.A.shape
    model.num_col_ = nc
    model.num_row_ = nr
    model.col_cost_ = lp.c
    model.col_lower_ = lp.col_lower
    model.col_upper_ = lp.col_upper
    model.row_lower_ = lp.row_lower
    model.row_upper_ = lp.row_upper
    model.a_matrix_.format_ = highspy.MatrixFormat.kColwise
    model.a_matrix_.start_ = lp.A.indptr
    model.a_matrix_.index_ = lp.A.indices
    model.a_matrix_.value_ = lp.A.data
    model.a_matrix_.num_col_ = nc
    model.a_matrix_.num_row_ = nr
    h.passModel(model)
    t0 = time.perf_counter()
    h.run()
    elapsed = time.perf_counter() - t0
    ms = h.getModelStatus()
    info = h.getInfo()
    iters = int(info.simplex_iteration_count) + int(max(info.ipm_iteration_count, 0))
    if ms == highspy.HighsModelStatus.kOptimal:
        x = np.asarray(h.getSolution().col_value)
        return LPSolution("optimal", x, float(lp.c @ x), "highs", iters, elapsed, lp.blocks)
    if ms == highspy.HighsModelStatus.kInfeasible:
        return LPSolution("infeasible", None, INF, "highs", iters, elapsed, lp.blocks)
    if ms in (highspy.HighsModelStatus.kUnbounded, highspy.HighsModelStatus.kUnboundedOrInfeasible):
        status = "unbounded" if ms == highspy.HighsModelStatus.kUnbounded else "infeasible"
        return LPSolution(status, None, -INF, "highs", iters, elapsed, lp.blocks)
    return LPSolution(h.modelStatusToString(ms), None, np.nan, "highs", iters, elapsed, lp.blocks)


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
        return LPSolution("optimal", x, float(lp.c @ x), "clarabel", int(sol.iterations), elapsed, lp.blocks)
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
    status = {0: "optimal", 2: "infeasible", 3: "unbounded"}.get(res.status, res.message)
    x = res.x if res.status == 0 else None
    obj = float(res.fun) if res.status == 0 else np.nan
    return LPSolution(status, x, obj, "scipy", int(getattr(res, "nit", 0) or 0), elapsed, lp.blocks)


def solve_lp(lp: LinearProgram, solver: str = "highs", options: dict | None = None) -> LPSolution:
    """Solve a :class:`LinearProgram` with the named solver.

    Parameters
    ----------
    lp
        The problem.
    solver
        ``"highs"`` (dual simplex through highspy), ``"clarabel"`` (interior
        point) or ``"scipy"`` (``scipy.optimize.linprog``).
    options
        Passed to the solver (HiGHS option names / Clarabel settings).

    Returns
    -------
    LPSolution
        Never raises for infeasibility; call :meth:`LPSolution.require_optimal`.
    """
    options = dict(options or {})
    if solver == "highs":
        return _solve_highs(lp, options)
    if solver == "clarabel":
        return _solve_clarabel(lp, options)
    if solver == "scipy":
        return _solve_scipy(lp, options)
    raise ValueError(f"unknown solver {solver!r}; choose one of {SOLVERS}")
