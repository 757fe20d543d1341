"""The prefix tree of a language of arrival patterns (one node per distinct prefix).

The node of a prefix of length ``t + 1`` owns the gain row of time ``t``
(eq. (7) of the prefix-based paper; constraint (6) of the delayed-data
paper): patterns sharing a prefix share these gains.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable

import numpy as np

from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_language, as_pattern
from eqrec.checks import short_label
from eqrec.errors import InputError


@dataclass
class PrefixNode:
    """A node of the prefix tree: the pattern prefix of length ``depth`` (events ``0..depth-1``).

    The gain row of time ``depth - 1`` (``F(t, ., prefix)`` and ``u0(t, prefix)``
    of eq. (7) of the prefix-based paper) belongs to this node; it multiplies
    the measurements ``available`` at that time.

    Parameters
    ----------
    index : int
        Position of the node in the tree's node list (the root is 0).
    prefix : ArrivalPattern
        The prefix (events ``0..depth-1``) this node stands for.
    parent : int or None
        Index of the parent node (``None`` for the root).
    children : list of int
        Indices of the child nodes.
    terminal : bool
        Whether a pattern of the language ends here.
    """

    index: int
    prefix: ArrivalPattern
    parent: int | None
    children: list[int] = field(default_factory=list)
    terminal: bool = False  # a pattern of the language ends here

    @property
    def depth(self) -> int:
        """Length of the prefix."""
        return self.prefix.T

    @property
    def label(self) -> str:
        """Label of the prefix (its word)."""
        return self.prefix.label

    @property
    def time(self) -> int:
        """The time ``t = depth - 1`` whose gain row this node owns."""
        return self.prefix.T - 1

    @property
    def available(self) -> tuple[int, ...]:
        """``A(t)`` of this node: the measurement times its gain row multiplies."""
        return self.prefix.available(self.prefix.T - 1)


def _shorter(q: ArrivalPattern) -> ArrivalPattern:
    """``q.prefix(q.T - 1)`` without caching every prefix of ``q``."""
    n = q.T - 1
    return ArrivalPattern(tuple(a if a is not None and a < n else None for a in q.arrivals[:n]))


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
            # the parent is q's prefix one shorter, made directly (O(T)): q.prefix() would build and cache every
            # prefix of every node (O(T^2) each, O(T^3) for one word of length T: 62 s at T = 1000)
            parent = self.index_of[_shorter(q)] if q.T > 1 else None
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
        return as_pattern(prefix)

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
            raise InputError(f"prefix {short_label(key.label)!r} is not a prefix of any word of the language "
                             f"{short_label(list(self.words))}") from None

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

