r"""Robust counterparts of affine constraints under box uncertainty.

Every design problem in the papers asks that some affine functions of the
uncertainty :math:`\delta = (w, v, \xi_0)` stay bounded for *all* :math:`\delta`
in a box :math:`|\delta_j| \le b_j`:

.. math::  |c_k(x) + g_k(x)^\top \delta| \le \ell_k(x) \quad \forall |\delta| \le b,

with :math:`c_k, g_k, \ell_k` affine in the decision variables :math:`x`.
Because the box is symmetric, the worst case is attained at a vertex and the
constraint is equivalent to

.. math::  |c_k(x)| + |g_k(x)|^\top b \le \ell_k(x),

which becomes linear with auxiliary variables, either
:math:`a \ge \pm g_k(x)` (``form="abs"``, two inequalities per entry) or a
split :math:`g_k(x) = p - m`, :math:`p, m \ge 0`, bounding
:math:`|g_k| \le p + m` (``form="split"``, one equality per entry; the
default, about twice as fast with HiGHS on the P1 designs).  Both are exact:
the bound is tight at :math:`p = g^+, m = g^-`.  The prefix-based paper writes
the same counterpart through LP duality with multipliers
:math:`\Pi \ge 0, \Pi\Omega = [I; -I] G` (eq. (16)); ``form="dual"`` builds
that form literally so the two can be compared.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from eqrec.lp.model import LPBuilder


@dataclass
class UncertainAffineRows:
    """Rows ``e_k(x, δ) = c0_k + cx_k·x + Σ_j G_kj(x) δ_j`` with ``G_kj(x) = G0_e + Gx_e·x``.

    ``G`` is stored by its structural entries ``e`` (pairs ``(row, coord)``),
    so rows that see only a few uncertain coordinates stay small.

    Parameters
    ----------
    entry_row, entry_coord : ndarray of int, shape (E,)
        Row and uncertain coordinate of each structural entry of ``G``.
    G0 : ndarray, shape (E,)
        Constant part of each entry.
    Gx : scipy.sparse.csr_matrix, shape (E, nx)
        Linear part of each entry in the decision variables.
    c0 : ndarray, shape (R,)
        Constant part of the certain term.
    cx : scipy.sparse.csr_matrix, shape (R, nx)
        Linear part of the certain term.
    """

    entry_row: np.ndarray
    entry_coord: np.ndarray
    G0: np.ndarray
    Gx: sp.csr_matrix
    c0: np.ndarray
    cx: sp.csr_matrix

    @property
    def num_rows(self) -> int:
        """Number ``R`` of rows."""
        return self.c0.shape[0]


@dataclass
class RobustRowsIndex:
    """Where :func:`add_robust_rows` put its rows, auxiliary columns and ``x``-dependent entries.

    Parameters
    ----------
    form : str
        The robust-counterpart form used (``"split"``, ``"abs"`` or ``"dual"``).
    level_rows : list of ndarray
        LP rows of the level constraints, one array per sign of the certain
        term (``+`` first); entry ``k`` is the row of robust row ``k``.
    aux_cols : ndarray of int
        The auxiliary columns (``a`` for ``"abs"``; ``p`` then ``m`` for
        ``"split"``; ``π`` blocks for ``"dual"``).
    gx_entries, gx_cols : ndarray of int
        For each ``x``-dependent coefficient ``Gx[e, j]`` placed in the LP:
        the structural entry ``e`` and the variable column ``j``.
    gx_handles : list of (int, float)
        ``(handle, sign)`` pairs: the LP coefficient at
        ``lp.positions(handle)[i]`` equals ``sign * Gx[gx_entries[i], gx_cols[i]]``.
        Rewriting these values updates the LP in place when only ``Gx`` changes.
    g0_rows : list of (ndarray, float)
        ``"abs"`` form with ``track_gx``: the rows ``a_e ∓ Gx_e x >= ±G0_e`` of the ``x``-dependent entries, with
        their sign (:meth:`update_g0`).
    """

    form: str
    level_rows: list[np.ndarray]
    aux_cols: np.ndarray
    gx_entries: np.ndarray
    gx_cols: np.ndarray
    gx_handles: list[tuple[int, float]]
    g0_rows: list[tuple[np.ndarray, float]] = field(default_factory=list)

    def update_gx(self, lp, values: np.ndarray) -> None:
        """Write new ``Gx`` values (ordered as ``gx_entries, gx_cols``) into a built LP.

        Parameters
        ----------
        lp : LinearProgram
            The LP built with ``track_gx=True``; its matrix is changed in place.
        values : ndarray, shape (len(gx_entries),)
            The new coefficients ``Gx[gx_entries[i], gx_cols[i]]``.
        """
        for handle, sign in self.gx_handles:
            lp.A.data[lp.positions(handle)] = sign * values

    def update_g0(self, lp, rows: UncertainAffineRows, radius: np.ndarray, level_const: np.ndarray | float) -> None:
        """Write the row bounds of new constant coefficients ``rows.G0`` (and certain terms ``rows.c0``) into a
        built LP, ``"abs"`` form with ``track_gx``: the bounds :func:`add_robust_rows` gives those rows, computed
        the same way (the same numbers as a rebuild).

        Parameters
        ----------
        lp : LinearProgram
            The LP built with ``track_gx=True``; its row bounds are changed in place.
        rows : UncertainAffineRows
            The rows with the new ``G0`` and ``c0`` (entries, coordinates and the pattern of ``Gx`` as built).
        radius : ndarray, shape (D,)
            Box radii, as built.
        level_const : ndarray, shape (R,), or float
            Constant part of the bounds, as built.
        """
        if self.form != "abs" or not self.g0_rows:
            raise ValueError("update_g0 needs the 'abs' form built with track_gx=True")
        if len(self.level_rows) == 1 and np.any(rows.c0):  # checked first: a refused update changes nothing
            raise ValueError("built with no certain term (one level row per row); rebuild for a nonzero c0")
        var_entries, const_part = _variable_entries(rows, rows.Gx.tocsr(), np.asarray(radius, float)[rows.entry_coord])
        for new_rows, sign in self.g0_rows:
            lp.row_lower[new_rows] = sign * rows.G0[var_entries]
        level_const = np.broadcast_to(np.asarray(level_const, float), (rows.num_rows,))
        for level_rows, sign in zip(self.level_rows, (+1.0, -1.0)):
            lp.row_upper[level_rows] = _level_upper(level_const, const_part, rows.c0, sign)


def add_robust_rows(builder: LPBuilder, rows: UncertainAffineRows, radius: np.ndarray,
                    level_const: np.ndarray | float, level_col: int | None = None,
                    level_coef: np.ndarray | float = 1.0, form: str = "split", *,
                    level_cols: np.ndarray | None = None, track_gx: bool = False) -> RobustRowsIndex:
    """Add ``|e_k(x, δ)| <= level_const_k + level_coef_k * x[col_k]`` for all ``|δ| <= radius``.

    Parameters
    ----------
    builder : LPBuilder
        LP under construction; auxiliary variables are added to it.
    rows : UncertainAffineRows
        The uncertain affine rows.
    radius : ndarray, shape (D,)
        Box radii ``b`` of the uncertain coordinates (indexed by ``entry_coord``).
    level_const : ndarray, shape (R,), or float
        Constant part of the bound ``ℓ_k``.
    level_col : int or None, optional
        One level variable for every row (e.g. the intermediate level ``M2``); ``None``: none.
    level_coef : ndarray, shape (R,), or float, optional
        Coefficient of the level variable in ``ℓ_k`` (default 1).
    form : {"split", "abs", "dual"}, optional
        ``"split"`` (default): ``G_e(x) = p_e - m_e``, ``p, m >= 0``;
        ``"abs"``: auxiliary ``a_e >= |G_e(x)|`` (one per variable entry);
        ``"dual"``: the Π multipliers of eq. (16) of the prefix-based paper.
    level_cols : ndarray of int, shape (R,), or None, optional
        A level variable per row (``-1``: none), e.g. a level ``μ2,k`` per
        prefix-tree node and a variable ``μ1`` on the terminal rows; overrides ``level_col``.
    track_gx : bool, optional
        Keep the positions of the ``x``-dependent coefficients in the built
        LP (:attr:`RobustRowsIndex.gx_handles`) so they can be rewritten in place.

    Returns
    -------
    RobustRowsIndex
        Where the rows, auxiliary columns and tracked coefficients are.
    """
    R = rows.num_rows
    level_const = np.broadcast_to(np.asarray(level_const, float), (R,))
    level_coef = np.broadcast_to(np.asarray(level_coef, float), (R,))
    if level_cols is None:
        level_cols = np.full(R, -1 if level_col is None else int(level_col), dtype=np.int64)
    else:
        level_cols = np.broadcast_to(np.asarray(level_cols, dtype=np.int64), (R,))
    b = np.asarray(radius, float)[rows.entry_coord]
    Gx = rows.Gx.tocsr()
    cx = rows.cx.tocoo()
    levels = (level_const, level_cols, level_coef)
    if form == "abs":
        return _add_abs_form(builder, rows, Gx, cx, b, levels, track_gx)
    if form == "split":
        return _add_split_form(builder, rows, Gx, cx, b, levels, track_gx)
    if form == "dual":
        return _add_dual_form(builder, rows, Gx, cx, b, levels, track_gx)
    raise ValueError(f"unknown robust-counterpart form {form!r} (use 'split', 'abs' or 'dual')")


def _variable_entries(rows: UncertainAffineRows, Gx: sp.csr_matrix, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Entries of ``G`` that depend on ``x``, and per row the worst case ``Σ |G0| b`` of the fixed ones."""
    has_var = np.diff(Gx.indptr) > 0
    const_part = np.bincount(rows.entry_row[~has_var], weights=np.abs(rows.G0[~has_var]) * b[~has_var],
                             minlength=rows.num_rows)
    return np.flatnonzero(has_var), const_part


def _level_triplets(levels, R: int) -> tuple[list, list, list]:
    """Triplets ``-level_coef_k x[col_k]`` of the level rows (rows with a level variable only)."""
    _, cols, coef = levels
    has = cols >= 0
    k = np.flatnonzero(has)
    return [k], [cols[has]], [-coef[has]]


def _level_upper(level_const: np.ndarray, const_part: np.ndarray, c0: np.ndarray, sign: float) -> np.ndarray:
    """The upper bound ``level_const - const_part - sign c0`` of the level rows of one sign (built and updated)."""
    return level_const - const_part - sign * c0


def _add_level_rows(builder, rows, cx, bound_cols, bound_rows, bound_vals, const_part, levels) -> list[np.ndarray]:
    """``±(c0 + cx x) + Σ (bound of |G_e|) b_e + const_part <= level_const + level_coef x[level_col]``.

    One row suffices when the certain term is identically zero.
    """
    R = rows.num_rows
    level_const = levels[0]
    signs = (+1.0,) if (cx.nnz == 0 and not np.any(rows.c0)) else (+1.0, -1.0)
    out = []
    for sign in signs:
        lr, lc, lv = _level_triplets(levels, R)
        r = [cx.row, bound_rows] + lr
        c = [cx.col, bound_cols] + lc
        v = [sign * cx.data, bound_vals] + lv
        out.append(builder.add_rows(np.concatenate(r), np.concatenate(c), np.concatenate(v), lower=-np.inf,
                                    upper=_level_upper(level_const, const_part, rows.c0, sign), count=R))
    return out


def _add_abs_form(builder, rows, Gx, cx, b, levels, track_gx) -> RobustRowsIndex:
    var_entries, const_part = _variable_entries(rows, Gx, b)
    k = var_entries.size
    aux = builder.add_variables(k, lower=0.0)
    # a_e - Gx_e x >= G0_e  and  a_e + Gx_e x >= -G0_e
    sub = Gx[var_entries].tocoo()
    handles, g0_rows = [], []
    for sign in (+1.0, -1.0):
        new_rows = builder.add_rows(np.arange(k), aux, np.ones(k), lower=sign * rows.G0[var_entries], upper=np.inf,
                                    count=k)
        h = builder.add_entries(new_rows[sub.row], sub.col, -sign * sub.data, track=track_gx)
        if track_gx:
            handles.append((h, -sign))
            g0_rows.append((new_rows, sign))
    level_rows = _add_level_rows(builder, rows, cx, aux, rows.entry_row[var_entries], b[var_entries], const_part,
                                 levels)
    return RobustRowsIndex("abs", level_rows, aux, var_entries[sub.row], sub.col, handles, g0_rows)


def _add_split_form(builder, rows, Gx, cx, b, levels, track_gx) -> RobustRowsIndex:
    # G_e(x) = p_e - m_e with p, m >= 0; |G_e| <= p_e + m_e (tight at an optimum of the bound).
    var_entries, const_part = _variable_entries(rows, Gx, b)
    k = var_entries.size
    pos = builder.add_variables(k, lower=0.0)
    neg = builder.add_variables(k, lower=0.0)
    sub = Gx[var_entries].tocoo()
    r = np.concatenate([np.arange(k), np.arange(k)])
    c = np.concatenate([pos, neg])
    v = np.concatenate([np.ones(k), -np.ones(k)])
    new_rows = builder.add_rows(r, c, v, lower=rows.G0[var_entries], upper=rows.G0[var_entries], count=k)
    h = builder.add_entries(new_rows[sub.row], sub.col, -sub.data, track=track_gx)
    er, bv = rows.entry_row[var_entries], b[var_entries]
    level_rows = _add_level_rows(builder, rows, cx, np.concatenate([pos, neg]), np.concatenate([er, er]),
                                 np.concatenate([bv, bv]), const_part, levels)
    return RobustRowsIndex("split", level_rows, np.concatenate([pos, neg]), var_entries[sub.row], sub.col,
                           [(h, -1.0)] if track_gx else [])


def _add_dual_form(builder, rows, Gx, cx, b, levels, track_gx) -> RobustRowsIndex:
    # For each row k and sign s: π_s ∈ R^{2E_k} ≥ 0, π_s Ω = s g_k, π_s·[b; b] <= ℓ_k - s c_k,
    # i.e. per entry e: π_{s,e}^+ - π_{s,e}^- = s G_e(x).
    R = rows.num_rows
    E = rows.entry_row.size
    Gc = Gx.tocoo()
    level_const = levels[0]
    aux, level_rows, handles = [], [], []
    for sign in (+1.0, -1.0):
        pi_plus = builder.add_variables(E, lower=0.0)
        pi_minus = builder.add_variables(E, lower=0.0)
        aux += [pi_plus, pi_minus]
        # π+ - π- - s Gx x = s G0
        new_rows = builder.add_rows(np.concatenate([np.arange(E), np.arange(E)]), np.concatenate([pi_plus, pi_minus]),
                                    np.concatenate([np.ones(E), -np.ones(E)]), lower=sign * rows.G0,
                                    upper=sign * rows.G0, count=E)
        h = builder.add_entries(new_rows[Gc.row], Gc.col, -sign * Gc.data, track=track_gx)
        if track_gx:
            handles.append((h, -sign))
        # Σ_e b_e (π+ + π-) + s (c0 + cx x) - level_coef x[level] <= level_const
        lr, lc, lv = _level_triplets(levels, R)
        r = [rows.entry_row, rows.entry_row, cx.row] + lr
        c = [pi_plus, pi_minus, cx.col] + lc
        v = [b, b, sign * cx.data] + lv
        level_rows.append(builder.add_rows(np.concatenate(r), np.concatenate(c), np.concatenate(v), lower=-np.inf,
                                           upper=level_const - sign * rows.c0, count=R))
    return RobustRowsIndex("dual", level_rows, np.concatenate(aux), Gc.row, Gc.col, handles)


def worst_case_abs(G: np.ndarray, c: np.ndarray, radius: np.ndarray) -> np.ndarray:
    """Exact ``max_{|δ| <= b} |c + G δ|`` per row: ``|c| + |G| b``.

    Parameters
    ----------
    G : ndarray, shape (R, D)
        Uncertainty coefficients of the rows.
    c : ndarray, shape (R,)
        Certain terms.
    radius : ndarray, shape (D,)
        Box radii ``b``.

    Returns
    -------
    ndarray, shape (R,)
        The worst-case absolute value of each row.
    """
    return np.abs(c) + np.abs(G) @ np.asarray(radius, float)


def worst_case_vertex(G_row: np.ndarray, c: float, radius: np.ndarray) -> np.ndarray:
    """A vertex ``δ*`` of the box with ``|c + G_row δ*| = |c| + |G_row| b``.

    Parameters
    ----------
    G_row : ndarray, shape (D,)
        Uncertainty coefficients of one row.
    c : float
        Its certain term.
    radius : ndarray, shape (D,)
        Box radii ``b``.

    Returns
    -------
    ndarray, shape (D,)
        The maximising vertex ``δ*``.
    """
    s = 1.0 if c >= 0 else -1.0
    sgn = np.sign(G_row)
    sgn[sgn == 0] = 1.0
    return s * sgn * np.asarray(radius, float)
