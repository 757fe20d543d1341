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
:class:`PrefixTree` has one node per distinct prefix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from typing import Iterable, Sequence

import numpy as np

from eqrec.errors import InputError

MISSING_ALPHABET = frozenset("01")
KINDS = ("missing", "delay")


@dataclass(frozen=True)
class ArrivalPattern:
    """Arrival times of the measurements of times ``0..T-1`` within the horizon ``T``.

    Parameters
    ----------
    arrivals
        ``arrivals[τ]`` is the arrival time ``a(τ)`` (``τ <= a(τ) < T``) or
        ``None`` when the measurement does not arrive within the horizon.
    given_label
        The word the pattern was made from (not part of equality); :attr:`label`
        falls back to :attr:`canonical_label`.

    Equality and hashing use ``arrivals`` only: equal event sequences are
    equal patterns.
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
        """Pattern of a missing-data word (``1`` arrives on time, ``0`` never)."""
        return cls(tuple(t if c == "1" else None for t, c in enumerate(word)), word)

    @classmethod
    def from_delays(cls, delays: Sequence[int], label: str | None = None) -> "ArrivalPattern":
        """Pattern of a delay word: ``a(i) = i + τ(i)``, missing when ``i + τ(i) >= T``."""
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
        """Whether ``y(τ)`` arrives within the horizon (``q(τ)`` of the stacked ``C̄``, ``N``)."""
        return self.arrivals[tau] is not None

    def available(self, t: int) -> tuple[int, ...]:
        """``A(t)``: measurement times ``τ <= t`` that have arrived by time ``t``, increasing."""
        return tuple(tau for tau in range(min(t + 1, self.T)) if (a := self.arrivals[tau]) is not None and a <= t)

    def arriving_at(self, t: int) -> tuple[int, ...]:
        """Measurement times whose packets arrive exactly at time ``t``."""
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
        """Event ``e_{t, j_t}`` as the digits ``d_0 ... d_t``."""
        avail = set(self.available(t))
        return "".join("1" if l in avail else "0" for l in range(t + 1))

    def event_index(self, t: int) -> int:
        """``j_t = Σ_l 2^l 1[τ(t-l) <= l]`` (eq. (2)): the event read as a binary number."""
        return int(self.event(t), 2)

    def events(self) -> tuple[str, ...]:
        """The event sequence ``E = e_{0,j_0} ... e_{T-1,j_{T-1}}`` (Definition 4)."""
        return tuple(self.event(t) for t in range(self.T))

    # -- prefixes ----------------------------------------------------------------
    def prefix(self, length: int) -> "ArrivalPattern":
        """The events ``0..length-1`` as a pattern of horizon ``length`` (Definition 6).

        Measurements arriving at or after ``length`` are not yet available.
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
        """All non-empty prefixes, shortest first."""
        return list(self._prefixes)

    def extend(self, length: int) -> "ArrivalPattern":
        """Append on-time measurements up to ``length`` (the minimum-recovery-time search, Sec. V of P1)."""
        if length < self.T:
            raise InputError(f"cannot shorten pattern {self.label!r} to length {length}")
        arr = self.arrivals + tuple(range(self.T, length))
        label = self.label + "1" * (length - self.T) if self.is_missing_data else ""
        return ArrivalPattern(arr, label)


Patternish = "ArrivalPattern | str"


# ---------------------------------------------------------------------------
# Parsing and validation
# ---------------------------------------------------------------------------

def validate_word(word: str, *, field_name: str = "word", source: str | None = None) -> str:
    """Return ``word`` if it is a non-empty string over {0, 1}, else raise :class:`InputError`."""
    if not isinstance(word, str):
        raise InputError(f"a word must be a string of 0 and 1, got {word!r}", source, field_name)
    word = word.strip()
    if not word:
        raise InputError("empty word", source, field_name)
    bad = set(word) - MISSING_ALPHABET
    if bad:
        raise InputError(f"word {word!r} has letters {sorted(bad)} outside the alphabet {{0, 1}}",
                         source, field_name)
    return word


def parse_delay_word(word: str, max_delay: int | None = None, *, field_name: str = "delays",
                     source: str | None = None) -> ArrivalPattern:
    """Parse a delay word of digits ``τ(0) ... τ(T-1)`` (eq. (1) of the delayed-data paper).

    The measurement of time ``i`` arrives at ``a(i) = i + τ(i)`` if
    ``i + τ(i) < T`` and never (missing within the horizon) otherwise, so
    a missing-data word is the special case where every delay is ``0`` or
    at least ``T``.  The word's event sequence (Definitions 2-4, eq. (2) of
    the delayed-data paper) is :meth:`ArrivalPattern.events`.

    Parameters
    ----------
    word : str
        Digits ``0-9``, one delay per measurement time (surrounding
        whitespace is ignored).
    max_delay : int or None, optional
        The largest allowed delay ``τ̄``; ``None``: no limit.
    field_name : str, optional
        Field named in the error message.
    source : str or None, optional
        File (or other origin) named in the error message.

    Returns
    -------
    ArrivalPattern
        The word's arrival pattern, labelled with ``word``.

    Raises
    ------
    InputError
        For a non-string or empty word, a non-digit letter, or a delay above
        ``max_delay``.

    Examples
    --------
    >>> import eqrec
    >>> pattern = eqrec.parse_delay_word("0120")
    >>> pattern
    ArrivalPattern('0120', arrivals=(0, 2, None, 3))
    >>> pattern.events()
    ('1', '10', '110', '1101')
    """
    if not isinstance(word, str):
        raise InputError(f"a delay word must be a string of digits, got {word!r}", source, field_name)
    word = word.strip()
    if not word:
        raise InputError("empty delay word", source, field_name)
    bad = sorted({c for c in word if not c.isdigit() or not c.isascii()})
    if bad:
        raise InputError(f"delay word {word!r} has letters {bad} that are not digits 0-9", source, field_name)
    delays = [int(c) for c in word]
    if max_delay is not None:
        over = [d for d in delays if d > max_delay]
        if over:
            raise InputError(f"delay word {word!r} has delays {sorted(set(over))} above the maximum delay "
                             f"{max_delay}", source, field_name)
    return ArrivalPattern.from_delays(delays, word)


def as_pattern(word: "ArrivalPattern | str", *, kind: str = "missing", max_delay: int | None = None,
               field_name: str = "word", source: str | None = None) -> ArrivalPattern:
    """A pattern from a pattern or a word of the given ``kind`` (``"missing"`` or ``"delay"``)."""
    if isinstance(word, ArrivalPattern):
        return word
    if kind == "missing":
        return ArrivalPattern.from_missing_word(validate_word(word, field_name=field_name, source=source))
    if kind == "delay":
        return parse_delay_word(word, max_delay, field_name=field_name, source=source)
    raise InputError(f"unknown word kind {kind!r}; choose one of {list(KINDS)}", source, "kind")


def as_language(words: Iterable["ArrivalPattern | str"], *, kind: str = "missing", max_delay: int | None = None,
                fixed_length: bool = True, length: int | None = None, field_name: str = "words",
                source: str | None = None) -> tuple[ArrivalPattern, ...]:
    """Patterns of a language, reduced to distinct event sequences (``L^{E'}``), first label kept.

    Words whose event sequences agree (e.g. the delay words ``0120`` and
    ``0130``: both lose ``y(2)`` within the horizon) are one pattern: the
    reduced event-based language ``L^{E'}`` of Section III-A of the
    delayed-data paper.  Order is kept (first occurrence).

    Parameters
    ----------
    words : iterable of str or ArrivalPattern
        The language: patterns, or words of ``kind``; a single word or
        pattern is a one-word language.
    kind : {"missing", "delay"}, optional
        How to read string words: 0/1 missing-data words (eq. (3) of the
        prefix-based paper) or delay words (:func:`parse_delay_word`).
    max_delay : int or None, optional
        Largest allowed delay of a delay word (``None``: no limit).
    fixed_length : bool, optional
        Require all words to have the same length (default).
    length : int or None, optional
        Required length of every word (``None``: any).
    field_name : str, optional
        Field named in error messages.
    source : str or None, optional
        File (or other origin) named in error messages.

    Returns
    -------
    tuple of ArrivalPattern
        The distinct patterns, in the order of their first occurrence.

    Raises
    ------
    InputError
        For bad letters, an empty language, mixed lengths when
        ``fixed_length``, a length other than ``length``, or an unknown
        ``kind``.

    Examples
    --------
    >>> import eqrec
    >>> eqrec.as_language(["0120", "0130", "0000"], kind="delay")
    (ArrivalPattern('0120', arrivals=(0, 2, None, 3)), ArrivalPattern('0000', arrivals=(0, 1, 2, 3)))
    """
    if isinstance(words, (str, ArrivalPattern)):
        words = [words]
    out: dict[ArrivalPattern, ArrivalPattern] = {}
    for w in words:
        pat = as_pattern(w, kind=kind, max_delay=max_delay, field_name=field_name, source=source)
        out.setdefault(pat, pat)
    if not out:
        raise InputError("the language is empty", source, field_name)
    pats = tuple(out.values())
    lengths = sorted({p.T for p in pats})
    if fixed_length and len(lengths) > 1:
        raise InputError(f"words of mixed lengths {lengths} in a fixed-length language: "
                         f"{[p.label for p in pats]}", source, field_name)
    if length is not None:
        wrong = [p.label for p in pats if p.T != length]
        if wrong:
            raise InputError(f"words {wrong} do not have the required length {length}", source, field_name)
    return pats


def validate_language(words: Iterable[str], *, fixed_length: bool = True, length: int | None = None,
                      field_name: str = "words", source: str | None = None) -> tuple[str, ...]:
    """Validate and de-duplicate a missing-data language given as 0/1 words (order kept).

    The string form of :func:`as_language` for missing-data words
    ``q(0) ... q(T-1)`` (eq. (3) of the prefix-based paper: ``1`` the
    measurement is available, ``0`` missing).

    Parameters
    ----------
    words : iterable of str
        Words over ``{0, 1}`` (surrounding whitespace is ignored); a single
        string is a one-word language.
    fixed_length : bool, optional
        Require all words to have the same length (default).
    length : int or None, optional
        Required length of every word (``None``: any).
    field_name : str, optional
        Field named in error messages.
    source : str or None, optional
        File (or other origin) named in error messages.

    Returns
    -------
    tuple of str
        The distinct words, in the order of their first occurrence.

    Raises
    ------
    InputError
        For letters other than ``0`` and ``1``, an empty language, mixed
        lengths when ``fixed_length``, or a length other than ``length``.

    Examples
    --------
    >>> import eqrec
    >>> eqrec.validate_language(["101111", "110111", "101111"])
    ('101111', '110111')
    """
    return tuple(p.label for p in as_language(words, fixed_length=fixed_length, length=length,
                                              field_name=field_name, source=source))


def full_delay_language(T: int, max_delay: int) -> tuple[str, ...]:
    """All ``(τ̄+1)^T`` delay words of length ``T`` with delays ``0..τ̄``, in lexicographic order.

    The full delayed-data language ``{0, ..., τ̄}^T`` of the delayed-data
    paper (Example 1: ``T = 2``, ``τ̄ = 2``, nine words; Section IV-A:
    ``T = 5``, ``τ̄ = 2``, 243 words).  The words are not reduced to
    distinct event sequences (:func:`as_language` does that: six for
    Example 1, as in Example 3; 162 for Section IV-A).

    Parameters
    ----------
    T : int
        Word length (horizon), at least 1.
    max_delay : int
        Largest delay ``τ̄``, ``0..9`` (one digit per delay).

    Returns
    -------
    tuple of str
        The ``(max_delay + 1) ** T`` words.

    Raises
    ------
    InputError
        If ``T < 1`` or ``max_delay`` is outside ``0..9``.

    Examples
    --------
    >>> import eqrec
    >>> eqrec.full_delay_language(2, 2)
    ('00', '01', '02', '10', '11', '12', '20', '21', '22')
    >>> len(eqrec.as_language(eqrec.full_delay_language(2, 2), kind="delay"))
    6
    """
    if T < 1 or max_delay < 0 or max_delay > 9:
        raise InputError(f"need T >= 1 and 0 <= max delay <= 9, got T = {T}, max delay = {max_delay}")
    digits = np.indices((max_delay + 1,) * T).reshape(T, -1).T
    return tuple("".join(map(str, row)) for row in digits)


# ---------------------------------------------------------------------------
# Worst case and helpers on words
# ---------------------------------------------------------------------------

def worst_case_pattern(patterns: Iterable["ArrivalPattern | str"]) -> ArrivalPattern:
    """Latest arrival of every measurement over a fixed-length language.

    For missing-data words this is the bitwise AND of Section III of the
    prefix-based paper: a measurement is kept only if every word has it, so
    an estimator that works for the worst case works for every word.
    """
    pats = as_language(patterns)
    arr = []
    for tau in range(pats[0].T):
        a = [p.arrivals[tau] for p in pats]
        arr.append(None if any(x is None for x in a) else max(a))
    return ArrivalPattern(tuple(arr))


def worst_case_word(words: Sequence[str]) -> str:
    """Bitwise AND of a fixed-length missing-data language (Section III of the prefix-based paper)."""
    return worst_case_pattern(validate_language(words)).label


def prefixes(word: str) -> list[str]:
    """All non-empty prefixes ``Pref(word)`` of a string, shortest first."""
    return [word[: i + 1] for i in range(len(word))]


def extend_word(word: str, length: int) -> str:
    """Pad a 0/1 word with ``1`` (measurements available) up to ``length`` (Section V of P1)."""
    if length < len(word):
        raise InputError(f"cannot shorten word {word!r} to length {length}")
    return word + "1" * (length - len(word))


# ---------------------------------------------------------------------------
# Prefix tree
# ---------------------------------------------------------------------------

@dataclass
class PrefixNode:
    """A node of the prefix tree: the pattern prefix of length ``depth`` (events ``0..depth-1``).

    The gain row of time ``depth - 1`` (``F(t, ., prefix)`` and ``u0(t, prefix)``
    of eq. (7) of the prefix-based paper) belongs to this node; it multiplies
    the measurements ``available`` at that time.
    """

    index: int
    prefix: ArrivalPattern
    parent: int | None
    children: list[int] = field(default_factory=list)
    terminal: bool = False  # a pattern of the language ends here

    @property
    def depth(self) -> int:
        return self.prefix.T

    @property
    def label(self) -> str:
        return self.prefix.label

    @property
    def time(self) -> int:
        """The time ``t = depth - 1`` whose gain row this node owns."""
        return self.prefix.T - 1

    @property
    def available(self) -> tuple[int, ...]:
        """``A(t)`` of this node: the measurement times its gain row multiplies."""
        return self.prefix.available(self.prefix.T - 1)


class PrefixTree:
    """The prefix tree of a (finite-length) language of arrival patterns.

    One node per distinct non-empty prefix ``Pref(λ)`` of the language's
    patterns (for delay words: per prefix of the event sequence,
    Definition 6 of the delayed-data paper).  The node of a prefix of length
    ``t + 1`` owns the gain row of time ``t``, ``F(t, ·, q_{0:t})`` and
    ``u0(t, q_{0:t})`` of eq. (7) of the prefix-based paper: the words
    sharing a prefix share these gains, which is the set ``Q(L)`` of
    Theorem 1 / eq. (11) there (constraint (6) of the delayed-data paper).
    For ``{1011, 1101}`` the nodes are ``1, 10, 11, 101, 110, 1011, 1101``
    (Section III of the prefix-based paper).

    Nodes are numbered breadth first (by depth, then by label), so a parent
    always precedes its children.

    Parameters
    ----------
    words : iterable of str or ArrivalPattern
        Patterns, or words of ``kind`` (reduced to distinct event
        sequences).  Patterns may differ in length (finite-length languages,
        Section V of the prefix-based paper); a pattern that is a prefix of
        another marks an inner node terminal.
    kind : {"missing", "delay"}, optional
        How to read string words (:func:`as_pattern`): 0/1 missing-data
        words (default) or delay words.
    max_delay : int or None, optional
        Largest allowed delay of a delay word (``None``: no limit).
    source : str or None, optional
        File (or other origin) named in error messages.

    Attributes
    ----------
    patterns : tuple of ArrivalPattern
        The language's distinct patterns (:func:`as_language`).
    nodes : list of PrefixNode
        The nodes, breadth first.
    index_of : dict
        Node index of each prefix (an :class:`ArrivalPattern`).

    Raises
    ------
    InputError
        For bad words or an empty language.

    Examples
    --------
    >>> import eqrec
    >>> tree = eqrec.PrefixTree(["1011", "1101"])
    >>> len(tree), tree.depth, tree.nodes_per_depth()
    (7, 4, [1, 2, 2, 2])
    >>> [node.label for node in tree]
    ['1', '10', '11', '101', '110', '1011', '1101']
    """

    def __init__(self, words: Iterable["ArrivalPattern | str"], *, kind: str = "missing",
                 max_delay: int | None = None, source: str | None = None):
        self.patterns: tuple[ArrivalPattern, ...] = as_language(words, kind=kind, max_delay=max_delay,
                                                                fixed_length=False, source=source)
        terminal = set(self.patterns)
        all_prefixes = {q for p in self.patterns for q in p.prefixes()}
        ordered = sorted(all_prefixes, key=lambda q: (q.T, q.label))
        self.index_of: dict[ArrivalPattern, int] = {}
        self.nodes: list[PrefixNode] = []
        for q in ordered:
            parent = self.index_of[q.prefix(q.T - 1)] if q.T > 1 else None
            node = PrefixNode(index=len(self.nodes), prefix=q, parent=parent, terminal=q in terminal)
            self.index_of[q] = node.index
            self.nodes.append(node)
            if parent is not None:
                self.nodes[parent].children.append(node.index)

    def __len__(self) -> int:
        return len(self.nodes)

    def __iter__(self):
        return iter(self.nodes)

    @property
    def words(self) -> tuple[str, ...]:
        """Labels of the language's patterns (the words as given)."""
        return tuple(p.label for p in self.patterns)

    @property
    def depth(self) -> int:
        """Length of the longest pattern."""
        return max(p.T for p in self.patterns)

    def nodes_per_depth(self) -> list[int]:
        """Number of nodes at depths ``1..depth``.

        Returns
        -------
        list of int
            Entry ``k`` counts the prefixes of length ``k + 1``.
        """
        return np.bincount([n.depth for n in self.nodes], minlength=self.depth + 1)[1:].tolist()

    def _key(self, prefix: "ArrivalPattern | str") -> ArrivalPattern:
        return prefix if isinstance(prefix, ArrivalPattern) else as_pattern(prefix)

    def node(self, prefix: "ArrivalPattern | str") -> PrefixNode:
        """The node of a prefix.

        Parameters
        ----------
        prefix : ArrivalPattern or str
            A prefix of one of the language's patterns (a 0/1 word is read as
            a missing-data pattern).

        Returns
        -------
        PrefixNode
            Its node (index, parent, children, terminal flag).

        Raises
        ------
        InputError
            If ``prefix`` is not a prefix of any pattern of the language.

        Examples
        --------
        >>> import eqrec
        >>> tree = eqrec.PrefixTree(["1011", "1101"])
        >>> node = tree.node("10")
        >>> node.index, node.parent, node.children, node.terminal
        (1, 0, [3], False)
        """
        key = self._key(prefix)
        try:
            return self.nodes[self.index_of[key]]
        except KeyError:
            raise InputError(f"prefix {key.label!r} is not a prefix of any word of the language "
                             f"{list(self.words)}") from None

    def path(self, pattern: "ArrivalPattern | str") -> list[PrefixNode]:
        """Nodes of the prefixes of length ``1, 2, ..., len(pattern)``.

        Parameters
        ----------
        pattern : ArrivalPattern or str
            A pattern (or 0/1 word) all of whose prefixes are in the tree,
            e.g. one of the language's patterns or a prefix of one.

        Returns
        -------
        list of PrefixNode
            Root first; the node of length ``t + 1`` owns the gain row of
            time ``t`` along ``pattern``.

        Raises
        ------
        InputError
            If a prefix of ``pattern`` is not in the tree.
        """
        return [self.node(q) for q in self._key(pattern).prefixes()]

    def contains_prefix(self, prefix: "ArrivalPattern | str") -> bool:
        """Whether ``prefix`` is a prefix of a pattern of the language (a node of the tree).

        Parameters
        ----------
        prefix : ArrivalPattern or str
            The prefix (a 0/1 word is read as a missing-data pattern).

        Returns
        -------
        bool
        """
        return self._key(prefix) in self.index_of

    def sequences_through(self) -> dict[int, int]:
        """Number of the language's patterns through each node: the weight of a node's level in the sum cost.

        In the delayed-data paper's cost
        ``J = μ1 + Σ_k Σ_α μ2,k^α`` (Section IV-A, with the problem of
        Proposition 1 / eq. (10)), the level of a node is paid once by every
        event sequence through it.

        Returns
        -------
        dict of int to int
            Node index -> number of patterns having that node's prefix.
        """
        through = {node.index: 0 for node in self.nodes}
        for pat in self.patterns:
            for anc in self.path(pat):
                through[anc.index] += 1
        return through


# ---------------------------------------------------------------------------
# Event matrices and the zero patterns (7) of the delayed-data paper
# ---------------------------------------------------------------------------

def event_indices(pattern: ArrivalPattern) -> tuple[int, ...]:
    """``(j_0, ..., j_{T-1})`` of eq. (2): the event sequence ``e_{0,j_0} ... e_{T-1,j_{T-1}}`` of Definition 4."""
    return tuple(pattern.event_index(t) for t in range(pattern.T))


def event_sequence_label(pattern: ArrivalPattern, upto: int | None = None) -> str:
    """``e_{0,j_0}e_{1,j_1}...`` as printed in Examples 3-5 (the first ``upto`` events: a prefix, Definition 6)."""
    idx = event_indices(pattern)[: pattern.T if upto is None else upto]
    return "".join(f"e_{{{t},{j}}}" for t, j in enumerate(idx))


def event_matrix(pattern: ArrivalPattern) -> np.ndarray:
    """The event matrix ``E_α`` of Section III-B: row ``i`` holds the digits ``d_0 ... d_i`` of the event at time ``i``.

    ``E_α[i, l] = 1`` iff the measurement of time ``l`` is available at time
    ``i`` (lower triangular, shape ``(T, T)``, integers).
    """
    return pattern.mask.astype(int)


def gain_zero_pattern(pattern: ArrivalPattern, gain: str = "M") -> list[list[str]]:
    """Block structure that constraint (7) imposes on ``M^α`` or ``L^α`` (``"*"`` free block, ``"0"`` zero block).

    ``M^α`` (eq. (5)) is block lower triangular; its block ``(k, i)`` is zero
    where ``E_α[k, i] = 0`` (``y(i)`` not yet available at time ``k``).
    ``L^α`` is block diagonal (Appendix); its diagonal block ``L_k`` is zero
    where ``E_α[k, k] = 0`` (``y(k)`` not on time), as Example 5 states.
    """
    if gain not in ("M", "L"):
        raise InputError(f"gain must be 'M' or 'L', got {gain!r}", field="gain")
    E = event_matrix(pattern)
    T = pattern.T
    return [["*" if E[k, i] and (gain == "M" or i == k) else "0" for i in range(T)] for k in range(T)]
