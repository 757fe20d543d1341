r"""Estimator gains: recovery from the Q-parametrisation and gain schedules.

The output injection of eq. (7) of the prefix-based paper is

.. math:: u_e(t) = u_0(t, q_{0:t}) + \sum_{\tau \le t} F(t, \tau, q_{0:t})\, y_\xi(\tau),

with :math:`y_\xi(\tau) = y(\tau) - C\hat x(\tau)` when measured and 0 otherwise.
For one word, stacking the gains gives a block lower-triangular ``F`` and a
vector ``u0``; eqs. (1) and (2) map them to ``(Q, r)``:

.. math:: Q = F(I - \bar C S F)^{-1}, \qquad r = (I + Q\bar C S) u_0,

with inverses :math:`F = (I + Q\bar C S)^{-1} Q` and
:math:`u_0 = (I + Q\bar C S)^{-1} r` (the proof of Proposition 1).

A :class:`GainSchedule` holds one gain row per prefix-tree node (a
prefix-based estimator, keyed by arrival-pattern prefixes) or per time step
(a time-based estimator, which ignores the observed prefix).  With delayed
data the same convention holds: ``F(t, τ)`` multiplies ``y_ξ(τ)`` for every
``τ`` available at ``t`` (late measurements included, with ``y_ξ(τ)`` formed
with the estimate ``x̂(τ)`` of their own time).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from eqrec.errors import InputError
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_pattern


def _solve_unit_lower(Mtx: np.ndarray, rhs: np.ndarray) -> np.ndarray:
    # I + Q C̄ S is unit lower triangular (Q C̄ S is strictly block lower triangular).
    return sla.solve_triangular(Mtx, rhs, lower=True, unit_diagonal=True)


def q_to_f(Q: np.ndarray, r: np.ndarray, CS: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of eqs. (1)-(2) of the prefix-based paper: ``(Q, r) -> (F, u0)``.

    Parameters
    ----------
    Q : ndarray, shape (Tn, Tp)
        Block lower-triangular Q-parameter.
    r : ndarray, shape (Tn,)
        Feedforward parameter of eq. (2).
    CS : ndarray, shape (Tp, Tn)
        The product ``C̄ S`` (strictly block lower triangular).

    Returns
    -------
    F : ndarray, shape (Tn, Tp)
        Stacked output-injection gains, ``(I + Q C̄ S)^{-1} Q``.
    u0 : ndarray, shape (Tn,)
        Stacked feedforward terms, ``(I + Q C̄ S)^{-1} r``.
    """
    Mtx = np.eye(Q.shape[0]) + Q @ CS
    return _solve_unit_lower(Mtx, Q), _solve_unit_lower(Mtx, r)


def f_to_q(F: np.ndarray, u0: np.ndarray, CS: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eqs. (1)-(2) of the prefix-based paper: ``Q = F (I - C̄ S F)^{-1}``, ``r = (I + Q C̄ S) u0``.

    Parameters
    ----------
    F : ndarray, shape (Tn, Tp)
        Stacked block lower-triangular gains of one word (eq. (9)).
    u0 : ndarray, shape (Tn,)
        Stacked feedforward terms.
    CS : ndarray, shape (Tp, Tn)
        The product ``C̄ S`` (strictly block lower triangular).

    Returns
    -------
    Q : ndarray, shape (Tn, Tp)
        Q-parameter of eq. (1).
    r : ndarray, shape (Tn,)
        Feedforward parameter of eq. (2).
    """
    Q = np.linalg.solve((np.eye(CS.shape[0]) - CS @ F).T, F.T).T
    r = (np.eye(Q.shape[0]) + Q @ CS) @ u0
    return Q, r


@dataclass
class GainRow:
    """Gains used at time ``t``: ``F(t, 0..t)`` as one ``n x (t+1)p`` block row and ``u0(t)``.

    Columns of measurements not available at ``t`` are zero (they multiply
    ``y_ξ(τ) = 0``).

    Parameters
    ----------
    F : ndarray, shape (n, (t+1)p)
        ``[F(t, 0), ..., F(t, t)]`` of eq. (7) of the prefix-based paper.
    u0 : ndarray, shape (n,)
        Feedforward term ``u0(t)``.
    """

    F: np.ndarray
    u0: np.ndarray


@dataclass
class GainSchedule:
    """Gains of a prefix-based (eq. (7)) or time-based (eq. (6)) estimator.

    Parameters
    ----------
    rows : dict of ArrivalPattern to GainRow
        ``rows[prefix]`` is the gain row used at time ``len(prefix) - 1``
        after observing the pattern prefix ``prefix`` (0/1 words are converted).
    n, p : int
        State and output dimensions.
    time_based : bool, optional
        If true the schedule has a single designed pattern and the gains are
        chosen by time only; the observed prefix is ignored (so measurements
        that the designed pattern does not have get zero gain).
    designed : tuple of ArrivalPattern, optional
        The patterns the schedule was designed for.
    """

    rows: dict[ArrivalPattern, GainRow]
    n: int
    p: int
    time_based: bool = False
    designed: tuple[ArrivalPattern, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        self.rows = {as_pattern(k): v for k, v in self.rows.items()}
        self.designed = tuple(as_pattern(w) for w in self.designed)

    @property
    def designed_words(self) -> tuple[str, ...]:
        """Labels of the designed patterns."""
        return tuple(p.label for p in self.designed)

    @property
    def horizon(self) -> int:
        """Length ``T`` of the longest prefix in ``rows``."""
        return max(k.T for k in self.rows)

    def row(self, observed_prefix: "ArrivalPattern | str", field: str | None = None) -> GainRow:
        """Gain row after observing ``observed_prefix`` (a pattern prefix of length ``t + 1``).

        Parameters
        ----------
        observed_prefix : ArrivalPattern or str
            Arrival-pattern prefix observed up to time ``t`` (or a 0/1 word).
        field : str or None, optional
            Field named in the error when the prefix has no gains (an estimator names its data ``y``).

        Returns
        -------
        GainRow
            Gains used at time ``t`` (by time alone when ``time_based``).
        """
        observed = as_pattern(observed_prefix)
        if self.time_based:
            if observed.T > self.designed[0].T:
                raise InputError(f"time {observed.T - 1} is beyond the horizon {self.horizon}", field=field)
            return self.rows[self.designed[0].prefix(observed.T)]
        try:
            return self.rows[observed]
        except KeyError:
            raise InputError(f"observed arrival prefix {observed.label!r} is not a prefix of any pattern "
                             f"of the design language {list(self.designed_words)}", field=field) from None

    def word_matrices(self, pattern: "ArrivalPattern | str") -> tuple[np.ndarray, np.ndarray]:
        """Stacked ``F (Tn x Tp)`` and ``u0 (Tn)`` used along ``pattern`` (eq. (9) of the prefix-based paper).

        Parameters
        ----------
        pattern : ArrivalPattern or str
            Arrival pattern (or 0/1 word) of length ``T``.

        Returns
        -------
        F : ndarray, shape (Tn, Tp)
            Block lower-triangular gains of the rows along ``pattern``.
        u0 : ndarray, shape (Tn,)
            Stacked feedforward terms.
        """
        pattern = as_pattern(pattern)
        T, n, p = pattern.T, self.n, self.p
        F = np.zeros((T * n, T * p))
        u0 = np.zeros(T * n)
        for t, pre in enumerate(pattern.prefixes()):
            g = self.row(pre)
            F[t * n:(t + 1) * n, : (t + 1) * p] = g.F
            u0[t * n:(t + 1) * n] = g.u0
        return F, u0

    def to_json(self) -> dict:
        """Per designed pattern ``{"F": ..., "u0": ...}`` in the CLI output convention, keyed by label.

        Returns
        -------
        dict of str to dict
            ``{label: {"F": nested lists, "u0": list}}`` from :meth:`word_matrices`.
        """
        return {w.label: dict(zip(("F", "u0"), (m.tolist() for m in self.word_matrices(w)))) for w in self.designed}


def schedule_from_word_gains(tree: PrefixTree, word_gains: dict, n: int, p: int,
                             time_based: bool = False, consistency_tol: float = 1e-7) -> GainSchedule:
    """Assemble a schedule from per-pattern stacked gains, checking prefix consistency.

    ``word_gains`` maps patterns (or 0/1 words) to ``(F, u0)``.  Patterns
    sharing a prefix must have the same gain rows on it (Proposition 1 of the
    prefix-based paper); a violation beyond ``consistency_tol`` (relative)
    raises :class:`AssertionError`.

    Parameters
    ----------
    tree : PrefixTree
        Prefix tree of the design language; its patterns become ``designed``.
    word_gains : dict
        Pattern (or 0/1 word) -> ``(F, u0)``, shapes ``(Tn, Tp)`` and ``(Tn,)``.
    n, p : int
        State and output dimensions.
    time_based : bool, optional
        Build a time-based schedule (eq. (6)) instead of a prefix-based one.
    consistency_tol : float, optional
        Relative tolerance of the prefix-consistency check.

    Returns
    -------
    GainSchedule
        One gain row per prefix of the patterns.
    """
    rows: dict[ArrivalPattern, GainRow] = {}
    for word, (F, u0) in word_gains.items():
        for t, pre in enumerate(as_pattern(word).prefixes()):
            row = GainRow(F[t * n:(t + 1) * n, : (t + 1) * p].copy(), u0[t * n:(t + 1) * n].copy())
            if pre in rows:
                old = rows[pre]
                scale = 1.0 + max(np.abs(old.F).max(initial=0), np.abs(old.u0).max(initial=0))
                diff = max(np.abs(old.F - row.F).max(initial=0), np.abs(old.u0 - row.u0).max(initial=0))
                if diff > consistency_tol * scale:
                    raise AssertionError(f"gains of prefix {pre.label!r} differ between patterns by {diff:.3g}")
            else:
                rows[pre] = row
    return GainSchedule(rows=rows, n=n, p=p, time_based=time_based, designed=tree.patterns)
