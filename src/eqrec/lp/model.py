"""Sparse linear programs: building, solving and reading are separate steps.

The design problems of the papers are robust LPs whose finite counterparts
(eq. (16) of the prefix-based paper) have a few thousand sparse rows.  A
modelling layer such as cvxpy spends longer canonicalising them than HiGHS
spends solving them, so we assemble the sparse matrix ourselves:

1. :class:`LPBuilder` collects variable blocks and constraint rows as
   coordinate triplets;
2. :meth:`LPBuilder.build` freezes them into a :class:`LinearProgram`
   (CSC matrix + row and column bounds), independent of any solver;
3. :func:`eqrec.lp.solvers.solve_lp` passes it to a solver of the
   registry (HiGHS, Clarabel, SciPy, IPOPT) and returns an :class:`LPSolution`;
4. the caller reads variable blocks with :meth:`LPSolution.block`.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from eqrec.errors import InfeasibleDesign, SolverFailure

INF = np.inf


@dataclass
class LinearProgram:
    """``min c^T x`` subject to ``row_lower <= A x <= row_upper`` and ``col_lower <= x <= col_upper``.

    Parameters
    ----------
    c : ndarray, shape (N,)
        Objective coefficients.
    A : scipy.sparse.csc_matrix, shape (M, N)
        Constraint matrix.
    row_lower, row_upper : ndarray, shape (M,)
        Row bounds (``-inf``/``inf`` for a one-sided row).
    col_lower, col_upper : ndarray, shape (N,)
        Variable bounds.
    blocks : dict of str to ndarray
        Column indices of the named variable blocks.
    tracked : dict of int to ndarray
        Positions in ``A.data`` of tracked entries, by handle (see :meth:`positions`).
    """

    c: np.ndarray
    A: sp.csc_matrix
    row_lower: np.ndarray
    row_upper: np.ndarray
    col_lower: np.ndarray
    col_upper: np.ndarray
    blocks: dict[str, np.ndarray] = field(default_factory=dict)
    tracked: dict[int, np.ndarray] = field(default_factory=dict)

    def positions(self, handle: int) -> np.ndarray:
        """Positions in ``A.data`` of the entries added with :meth:`LPBuilder.add_entries` (``track=True``).

        Writing ``A.data[positions]`` changes those coefficients in place
        (the sparsity pattern is fixed), e.g. to update an ``L``-dependent LP.

        Parameters
        ----------
        handle : int
            Handle returned by :meth:`LPBuilder.add_entries`.

        Returns
        -------
        ndarray of int
            Positions in ``A.data``, in the order the entries were added.
        """
        return self.tracked[handle]

    @property
    def shape(self) -> tuple[int, int]:
        """``(rows, variables)`` of ``A``."""
        return self.A.shape

    def residual(self, x: np.ndarray) -> float:
        """Largest violation of any row or column bound by ``x``.

        Parameters
        ----------
        x : ndarray, shape (N,)
            A point (e.g. a solver's solution).

        Returns
        -------
        float
            ``max`` of the row and column bound violations, 0 when ``x`` is feasible.
        """
        ax = self.A @ x
        viol = [np.max(self.row_lower - ax, initial=0.0), np.max(ax - self.row_upper, initial=0.0),
                np.max(self.col_lower - x, initial=0.0), np.max(x - self.col_upper, initial=0.0)]
        return float(max(viol))


def _filled(value: float | np.ndarray, count: int) -> np.ndarray:
    """``value`` (a number, or an array broadcast to ``count``) as a new float array of ``count`` entries (a number
    through :func:`numpy.full`, the same floats without the broadcasting machinery: the trace LPs of the compare
    study add about 20,000 blocks of bounds a job)."""
    if isinstance(value, (int, float)):  # numbers (NumPy floats among them)
        return np.full(count, float(value))
    return np.broadcast_to(np.asarray(value, float), (count,)).copy()


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
        self._tracked: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    @property
    def num_variables(self) -> int:
        """Number of variables added so far."""
        return self._ncols

    @property
    def num_rows(self) -> int:
        """Number of rows added so far."""
        return self._nrows

    def add_variables(self, count: int, lower: float | np.ndarray = -INF, upper: float | np.ndarray = INF,
                      name: str | None = None) -> np.ndarray:
        """Add ``count`` variables and return their column indices.

        Parameters
        ----------
        count : int
            Number of variables.
        lower, upper : float or ndarray, optional
            Bounds (broadcast to ``count``; default free).
        name : str, optional
            Name of the block, readable with :meth:`LPSolution.block`.

        Returns
        -------
        ndarray of int, shape (count,)
            Global column indices of the new variables.
        """
        idx = np.arange(self._ncols, self._ncols + count)
        self._ncols += count
        self._col_lower.append(_filled(lower, count))
        self._col_upper.append(_filled(upper, count))
        if name is not None:
            self.blocks[name] = idx
        return idx

    def set_cost(self, columns: np.ndarray | int, coefficients: np.ndarray | float) -> None:
        """Add ``coefficients`` to the objective coefficients of ``columns``.

        Parameters
        ----------
        columns : int or ndarray of int
            Global column indices.
        coefficients : float or ndarray
            Added to their cost (broadcast to ``columns``).
        """
        for j, c in zip(np.atleast_1d(columns), np.broadcast_to(coefficients, np.shape(np.atleast_1d(columns)))):
            self._cost[int(j)] = self._cost.get(int(j), 0.0) + float(c)

    def add_rows(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray,
                 lower: np.ndarray | float, upper: np.ndarray | float, count: int | None = None) -> np.ndarray:
        """Add a block of rows given as local coordinate triplets.

        Parameters
        ----------
        rows, cols, vals : ndarray
            Triplets; ``rows`` are local (0 .. count-1), ``cols`` global.
        lower, upper : float or ndarray
            Row bounds (broadcast to ``count``).
        count : int, optional
            Number of rows (default ``max(rows) + 1``).

        Returns
        -------
        ndarray of int, shape (count,)
            Global indices of the new rows.
        """
        rows = np.asarray(rows, dtype=np.int64).ravel()
        if count is None:
            count = int(rows.max()) + 1 if rows.size else 0
        self._rows.append(rows + self._nrows)
        self._cols.append(np.asarray(cols, dtype=np.int64).ravel())
        self._vals.append(np.asarray(vals, dtype=float).ravel())
        self._row_lower.append(_filled(lower, count))
        self._row_upper.append(_filled(upper, count))
        out = np.arange(self._nrows, self._nrows + count)
        self._nrows += count
        return out

    def add_entries(self, rows: np.ndarray, cols: np.ndarray, vals: np.ndarray, track: bool = False) -> int | None:
        """Add coefficients to rows that already exist (global row indices).

        With ``track=True`` the entries are kept even when zero, must not
        coincide with other entries, and the returned handle gives their
        positions in the built matrix (:meth:`LinearProgram.positions`).

        Parameters
        ----------
        rows, cols : ndarray of int
            Global row and column indices.
        vals : ndarray
            Coefficients.
        track : bool, optional
            Keep the entries and return a handle to their positions.

        Returns
        -------
        int or None
            The handle with ``track=True``, else ``None``.
        """
        rows = np.asarray(rows, dtype=np.int64).ravel()
        cols = np.asarray(cols, dtype=np.int64).ravel()
        if rows.size and (rows.max() >= self._nrows or rows.min() < 0):
            raise ValueError("add_entries: a row index does not exist yet")
        self._rows.append(rows)
        self._cols.append(cols)
        self._vals.append(np.asarray(vals, dtype=float).ravel())
        if not track:
            return None
        handle = len(self._tracked)
        self._tracked[handle] = (rows, cols)
        return handle

    def build(self) -> LinearProgram:
        """Freeze into a solver-independent :class:`LinearProgram`.

        Returns
        -------
        LinearProgram
            CSC matrix (duplicates summed, zeros dropped unless tracked) and bounds.
        """
        c = np.zeros(self._ncols)
        for j, v in self._cost.items():
            c[j] = v
        rows = np.concatenate(self._rows) if self._rows else np.zeros(0, np.int64)
        cols = np.concatenate(self._cols) if self._cols else np.zeros(0, np.int64)
        vals = np.concatenate(self._vals) if self._vals else np.zeros(0)
        keep = vals != 0.0
        tracked_positions: dict[int, np.ndarray] = {}
        if self._tracked:
            # tracked entries stay in the pattern even when their current value is zero
            nr = self._nrows
            tkeys = {h: c_ * nr + r_ for h, (r_, c_) in self._tracked.items()}
            all_t = np.concatenate(list(tkeys.values()))
            keep |= np.isin(cols * nr + rows, all_t)
        A = sp.csc_matrix((vals[keep], (rows[keep], cols[keep])), shape=(self._nrows, self._ncols))
        A.sum_duplicates()
        A.sort_indices()
        if self._tracked:
            colidx = np.repeat(np.arange(A.shape[1], dtype=np.int64), np.diff(A.indptr))
            keyA = colidx * self._nrows + A.indices
            for h, k in tkeys.items():
                pos = np.searchsorted(keyA, k)
                if k.size and (pos.max() >= keyA.size or not np.array_equal(keyA[pos], k)):
                    raise AssertionError("a tracked LP entry is missing from the built matrix")
                tracked_positions[h] = pos
        cat = lambda parts: np.concatenate(parts) if parts else np.zeros(0)  # noqa: E731
        return LinearProgram(c=c, A=A, row_lower=cat(self._row_lower), row_upper=cat(self._row_upper),
                             col_lower=cat(self._col_lower), col_upper=cat(self._col_upper),
                             blocks=dict(self.blocks), tracked=tracked_positions)


@dataclass
class LPSolution:
    """What a solver returned, in solver-independent form.

    ``row_dual`` (optimal solutions of the registry's solvers): multipliers
    ``y`` of the rows in one convention for every solver, ``c - Aᵀy`` = the
    reduced costs (nonnegative at a column's lower bound, nonpositive at its
    upper bound), as HiGHS reports them.

    Parameters
    ----------
    status : str
        ``"optimal"``, ``"infeasible"``, ``"unbounded"``, or a solver message.
    x : ndarray or None
        The solution, shape (N,); ``None`` when the solver returned none.
    objective : float
        ``c^T x``.
    solver : str
        Name of the solver in the registry.
    iterations : int
        Iterations reported by the solver.
    solve_time : float
        Seconds spent inside the solver call.
    blocks : dict of str to ndarray
        Column indices of the named blocks (from :attr:`LinearProgram.blocks`).
    row_dual : ndarray or None
        Row multipliers ``y``, shape (M,), in the convention above.
    attempts : tuple of str, optional
        The solves tried before this answer that ended without a usable status, each ``"what: status"``
        (:func:`eqrec.lp.solvers.solve_lp`'s retries; empty when the first solve answered).
    solved_by : str, optional
        The solve that gave this answer, e.g. ``"highs"`` or ``"highs, primal simplex"`` (empty: ``solver``).
    """

    status: str  # "optimal", "infeasible", "unbounded", or a solver message
    x: np.ndarray | None
    objective: float
    solver: str
    iterations: int
    solve_time: float  # seconds spent inside the solver call
    blocks: dict[str, np.ndarray] = field(default_factory=dict)
    row_dual: np.ndarray | None = None
    attempts: tuple[str, ...] = ()
    solved_by: str = ""

    @property
    def optimal(self) -> bool:
        """Whether ``status`` is ``"optimal"``."""
        return self.status == "optimal"

    def block(self, name: str) -> np.ndarray:
        """Values of a named variable block.

        Parameters
        ----------
        name : str
            Block name given to :meth:`LPBuilder.add_variables`.

        Returns
        -------
        ndarray
            ``x`` at the block's columns.
        """
        if self.x is None:
            raise SolverFailure(f"no solution to read (status {self.status})")
        return self.x[self.blocks[name]]

    def require_optimal(self, what: str = "design") -> "LPSolution":
        """Raise :class:`InfeasibleDesign` or :class:`SolverFailure` unless optimal.

        Parameters
        ----------
        what : str, optional
            What was solved, for the error message.

        Returns
        -------
        LPSolution
            ``self``, when optimal.
        """
        if self.status == "infeasible":
            raise InfeasibleDesign(f"{what} is infeasible ({self.solver})")
        if self.status == "unbounded":
            raise InfeasibleDesign(f"{what} is unbounded ({self.solver})")
        if not self.optimal:
            tried = f" (tried: {'; '.join(self.attempts)})" if self.attempts else ""
            raise SolverFailure(f"{what}: solver {self.solver} stopped with status '{self.status}'{tried}")
        return self
