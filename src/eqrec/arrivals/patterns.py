r"""Arrival patterns: which measurements are available at each time, and their prefix trees.

An *arrival pattern* over a horizon ``T`` gives, for every measurement time
``τ = 0..T-1``, the time ``a(τ) ∈ {τ, ..., T-1}`` at which the measurement
``y(τ)`` reaches the estimator, or *never* (within the horizon).  At time
``t`` the available set is

.. math:: \mathcal A(t) = \{\tau \le t : a(\tau) \le t\},

which is nested (``A(t) ⊆ A(t+1)``): once arrived, a measurement stays
available.  Two kinds of words map to patterns:

* a **missing-data word** ``q(0) ... q(T-1)`` over ``{0, 1}`` (eq. (3) of the
  prefix-based paper): ``a(τ) = τ`` if ``q(τ) = 1``, never otherwise;
* a **delay word** ``τ(0) ... τ(T-1)`` over ``{0, ..., τ̄}`` (eq. (1) of the
  delayed-data paper): ``a(i) = i + τ(i)`` if ``i + τ(i) < T`` and never
  (missing within the horizon) otherwise.

The *event* at time ``t`` (Definition 2 of the delayed-data paper) is the
availability mask ``d_0 ... d_t`` with ``d_l = 1`` iff ``l ∈ A(t)``; its index
``j_t`` is eq. (2).  A pattern *is* its event sequence: two delay words with
the same event sequence (e.g. ``01`` and ``02`` for ``T = 2``) give equal
patterns, so a set of patterns is the reduced event-based language
``L^{E'}``.  The estimator at time ``t`` can only know the events ``0..t``,
i.e. the pattern truncated to horizon ``t + 1`` (its *prefix*); a
:class:`~eqrec.arrivals.prefix_tree.PrefixTree` has one node per distinct prefix.

Words are read into patterns by :mod:`eqrec.arrivals.words`; prefix trees are
built in :mod:`eqrec.arrivals.prefix_tree`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Sequence

import numpy as np

from eqrec.errors import InputError
from eqrec.checks import short_label


@dataclass(frozen=True)
class ArrivalPattern:
    """Arrival times of the measurements of times ``0..T-1`` within the horizon ``T``.

    Equality and hashing use ``arrivals`` only: equal event sequences are
    equal patterns.

    Parameters
    ----------
    arrivals : tuple of (int or None)
        ``arrivals[τ]`` is the arrival time ``a(τ)`` (``τ <= a(τ) < T``) or
        ``None`` when the measurement does not arrive within the horizon.
    given_label : str, optional
        The word the pattern was made from (not part of equality); :attr:`label`
        falls back to :attr:`canonical_label`.
    """

    arrivals: tuple[int | None, ...]
    given_label: str = field(default="", compare=False, repr=False)

    def __post_init__(self) -> None:
        T = len(self.arrivals)
        for tau, a in enumerate(self.arrivals):
            if a is not None and not (tau <= a < T):
                raise InputError(f"arrival time {a} of the measurement of time {tau} is outside [{tau}, {T - 1}]")

    @cached_property
    def label(self) -> str:
        """The word the pattern was made from, else :attr:`canonical_label`."""
        return self.given_label or self.canonical_label

    def __repr__(self) -> str:
        return f"ArrivalPattern({self.label!r}, arrivals={self.arrivals})"

    # -- construction ---------------------------------------------------------
    @classmethod
    def from_missing_word(cls, word: str) -> "ArrivalPattern":
        """Pattern of a missing-data word (``1`` arrives on time, ``0`` never).

        Parameters
        ----------
        word : str
            Word ``q(0) ... q(T-1)`` over ``{0, 1}`` (eq. (3) of the prefix-based paper); kept as the label.

        Returns
        -------
        ArrivalPattern
            Pattern of horizon ``len(word)``.
        """
        return cls(tuple(t if c == "1" else None for t, c in enumerate(word)), word)

    @classmethod
    def from_delays(cls, delays: Sequence[int], label: str | None = None) -> "ArrivalPattern":
        """Pattern of a delay word: ``a(i) = i + τ(i)``, missing when ``i + τ(i) >= T``.

        Parameters
        ----------
        delays : sequence of int
            Delays ``τ(0) ... τ(T-1)`` (eq. (1) of the delayed-data paper).
        label : str, optional
            Label of the pattern (default: the delays' digits joined).

        Returns
        -------
        ArrivalPattern
            Pattern of horizon ``len(delays)``.
        """
        T = len(delays)
        arr = tuple(i + d if i + d < T else None for i, d in enumerate(delays))
        return cls(arr, label if label is not None else "".join(str(d) for d in delays))

    # -- basic properties ------------------------------------------------------
    @property
    def T(self) -> int:
        """Horizon (number of measurement times)."""
        return len(self.arrivals)

    def __len__(self) -> int:
        return len(self.arrivals)

    def __str__(self) -> str:
        return self.label

    @property
    def is_missing_data(self) -> bool:
        """Every measurement arrives on time or never (a word over ``{0, 1}``)."""
        return all(a is None or a == t for t, a in enumerate(self.arrivals))

    @property
    def canonical_label(self) -> str:
        """``0/1`` word for a missing-data pattern, else the event sequence ``e_0.e_1...``."""
        if self.is_missing_data:
            return "".join("0" if a is None else "1" for a in self.arrivals)
        return ".".join(self.event(t) for t in range(self.T))

    def arrives(self, tau: int) -> bool:
        """Whether ``y(τ)`` arrives within the horizon (``q(τ)`` of the stacked ``C̄``, ``N``).

        Parameters
        ----------
        tau : int
            Measurement time, ``0 <= tau < T``.

        Returns
        -------
        bool
            ``a(tau)`` is not never.
        """
        return self.arrivals[tau] is not None

    def available(self, t: int) -> tuple[int, ...]:
        """``A(t)``: measurement times ``τ <= t`` that have arrived by time ``t``, increasing.

        Parameters
        ----------
        t : int
            Time.

        Returns
        -------
        tuple of int
            The available set ``A(t)``.
        """
        return tuple(tau for tau in range(min(t + 1, self.T)) if (a := self.arrivals[tau]) is not None and a <= t)

    def arriving_at(self, t: int) -> tuple[int, ...]:
        """Measurement times whose packets arrive exactly at time ``t``.

        Parameters
        ----------
        t : int
            Time.

        Returns
        -------
        tuple of int
            ``{τ : a(τ) = t}``, increasing.
        """
        return tuple(tau for tau, a in enumerate(self.arrivals) if a == t)

    @cached_property
    def mask(self) -> np.ndarray:
        """Availability ``mask[t, τ] = τ ∈ A(t)`` (shape ``(T, T)``, lower triangular)."""
        m = np.zeros((self.T, self.T), bool)
        for tau, a in enumerate(self.arrivals):
            if a is not None:
                m[a:, tau] = True
        return m

    # -- events (Definitions 2-4, eq. (2) of the delayed-data paper) -------------
    def event(self, t: int) -> str:
        """Event ``e_{t, j_t}`` as the digits ``d_0 ... d_t``.

        Parameters
        ----------
        t : int
            Time.

        Returns
        -------
        str
            ``t + 1`` digits, ``d_l = 1`` iff ``l ∈ A(t)`` (Definition 2 of the delayed-data paper).
        """
        avail = set(self.available(t))
        return "".join("1" if l in avail else "0" for l in range(t + 1))

    def event_index(self, t: int) -> int:
        """``j_t = Σ_l 2^l 1[τ(t-l) <= l]`` (eq. (2)): the event read as a binary number.

        Parameters
        ----------
        t : int
            Time.

        Returns
        -------
        int
            The index ``j_t`` of the event at ``t``.
        """
        return int(self.event(t), 2)

    def events(self) -> tuple[str, ...]:
        """The event sequence ``E = e_{0,j_0} ... e_{T-1,j_{T-1}}`` (Definition 4).

        Returns
        -------
        tuple of str
            :meth:`event` of each time ``0..T-1``.
        """
        return tuple(self.event(t) for t in range(self.T))

    # -- prefixes ----------------------------------------------------------------
    def prefix(self, length: int) -> "ArrivalPattern":
        """The events ``0..length-1`` as a pattern of horizon ``length`` (Definition 6).

        Measurements arriving at or after ``length`` are not yet available.

        Parameters
        ----------
        length : int
            Prefix length, ``1 <= length <= T``.

        Returns
        -------
        ArrivalPattern
            The prefix (unlabelled: its label is canonical).
        """
        if not 0 < length <= self.T:
            raise InputError(f"prefix length {length} outside 1..{self.T}")
        return self._prefixes[length - 1]

    @cached_property
    def _prefixes(self) -> tuple["ArrivalPattern", ...]:
        out = []
        for length in range(1, self.T):
            out.append(ArrivalPattern(tuple(a if a is not None and a < length else None
                                            for a in self.arrivals[:length])))
        return tuple(out) + (self if not self.given_label else ArrivalPattern(self.arrivals),)

    def prefixes(self) -> list["ArrivalPattern"]:
        """All non-empty prefixes, shortest first.

        Returns
        -------
        list of ArrivalPattern
            ``prefix(1), ..., prefix(T)``.
        """
        return list(self._prefixes)

    def extend(self, length: int) -> "ArrivalPattern":
        """Append on-time measurements up to ``length`` (the minimum-recovery-time search, Sec. V of P1).

        Parameters
        ----------
        length : int
            New horizon, ``>= T``.

        Returns
        -------
        ArrivalPattern
            The pattern followed by ``length - T`` on-time measurements.
        """
        if length < self.T:
            raise InputError(f"cannot shorten pattern {short_label(self.label)!r} to length {length}")
        arr = self.arrivals + tuple(range(self.T, length))
        label = self.label + "1" * (length - self.T) if self.is_missing_data else ""
        return ArrivalPattern(arr, label)


# ---------------------------------------------------------------------------
# Event matrices and the zero patterns (7) of the delayed-data paper
# ---------------------------------------------------------------------------

def event_indices(pattern: ArrivalPattern) -> tuple[int, ...]:
    """``(j_0, ..., j_{T-1})`` of eq. (2): the event sequence ``e_{0,j_0} ... e_{T-1,j_{T-1}}`` of Definition 4.

    Parameters
    ----------
    pattern : ArrivalPattern
        Arrival pattern of horizon ``T``.

    Returns
    -------
    tuple of int
        The event indices ``j_t``.
    """
    return tuple(pattern.event_index(t) for t in range(pattern.T))


def event_sequence_label(pattern: ArrivalPattern, upto: int | None = None) -> str:
    """``e_{0,j_0}e_{1,j_1}...`` as printed in Examples 3-5 (the first ``upto`` events: a prefix, Definition 6).

    Parameters
    ----------
    pattern : ArrivalPattern
        Arrival pattern.
    upto : int, optional
        Number of events (default all ``T``).

    Returns
    -------
    str
        The label, e.g. ``e_{0,1}e_{1,3}``.
    """
    idx = event_indices(pattern)[: pattern.T if upto is None else upto]
    return "".join(f"e_{{{t},{j}}}" for t, j in enumerate(idx))


def event_matrix(pattern: ArrivalPattern) -> np.ndarray:
    """The event matrix ``E_α`` of Section III-B: row ``i`` holds the digits ``d_0 ... d_i`` of the event at time ``i``.

    ``E_α[i, l] = 1`` iff the measurement of time ``l`` is available at time
    ``i`` (lower triangular, shape ``(T, T)``, integers).

    Parameters
    ----------
    pattern : ArrivalPattern
        Arrival pattern of horizon ``T``.

    Returns
    -------
    ndarray of int, shape (T, T)
        ``E_α``.
    """
    return pattern.mask.astype(int)


def gain_zero_pattern(pattern: ArrivalPattern, gain: str = "M") -> list[list[str]]:
    """Block structure that constraint (7) imposes on ``M^α`` or ``L^α`` (``"*"`` free block, ``"0"`` zero block).

    ``M^α`` (eq. (5)) is block lower triangular; its block ``(k, i)`` is zero
    where ``E_α[k, i] = 0`` (``y(i)`` not yet available at time ``k``).
    ``L^α`` is block diagonal (Appendix); its diagonal block ``L_k`` is zero
    where ``E_α[k, k] = 0`` (``y(k)`` not on time), as Example 5 states.

    Parameters
    ----------
    pattern : ArrivalPattern
        Arrival pattern ``α`` of horizon ``T``.
    gain : str, optional
        ``"M"`` or ``"L"``.

    Returns
    -------
    list of list of str
        ``T x T`` blocks, ``"*"`` (free) or ``"0"`` (zero).
    """
    if gain not in ("M", "L"):
        raise InputError(f"gain must be 'M' or 'L', got {gain!r}", field="gain")
    E = event_matrix(pattern)
    T = pattern.T
    return [["*" if E[k, i] and (gain == "M" or i == k) else "0" for i in range(T)] for k in range(T)]


def pattern_text(rows: Sequence[Sequence[str]]) -> str:
    """A zero pattern (:func:`gain_zero_pattern`) on one line, rows separated by ``;``.

    Parameters
    ----------
    rows : sequence of sequence of str
        Blocks row by row, ``"*"`` (free) or ``"0"`` (zero).

    Returns
    -------
    str
        ``"[a, b; c, d]"``.
    """
    return "[" + "; ".join(", ".join(r) for r in rows) + "]"
