"""Missing-data languages: words, worst-case words and prefix trees.

A word is a string over ``{0, 1}``; character ``t`` (0-based) is ``q(t)``:
``1`` when the measurement at time ``t`` arrives, ``0`` when it is missing
(eq. (3) of the prefix-based paper).  A *language* is a finite set of words.

The prefix-based estimator (eq. (7) of the prefix-based paper) chooses its gain
at time ``t`` by the observed prefix ``q(0) ... q(t)``; the set of prefixes of
a language is naturally a tree, which the design uses to share variables.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Sequence

from eqrec.errors import InputError

ALPHABET = frozenset("01")


def validate_word(word: str, *, field_name: str = "word", source: str | None = None) -> str:
    """Return ``word`` if it is a non-empty string over {0, 1}, else raise :class:`InputError`."""
    if not isinstance(word, str):
        raise InputError(f"a word must be a string of 0 and 1, got {word!r}", source, field_name)
    word = word.strip()
    if not word:
        raise InputError("empty word", source, field_name)
    bad = set(word) - ALPHABET
    if bad:
        raise InputError(f"word {word!r} has letters {sorted(bad)} outside the alphabet {{0, 1}}",
                         source, field_name)
    return word


def validate_language(words: Iterable[str], *, fixed_length: bool = True, length: int | None = None,
                      field_name: str = "words", source: str | None = None) -> tuple[str, ...]:
    """Validate and de-duplicate a language, keeping the order of first appearance.

    Parameters
    ----------
    words
        The words.
    fixed_length
        Require all words to have the same length (the fixed-length languages
        ``L ⊆ B^T`` of Problem 1 of the prefix-based paper).
    length
        If given, the required length of every word.
    """
    out: list[str] = []
    for w in words:
        w = validate_word(w, field_name=field_name, source=source)
        if w not in out:
            out.append(w)
    if not out:
        raise InputError("the language is empty", source, field_name)
    lengths = sorted({len(w) for w in out})
    if fixed_length and len(lengths) > 1:
        raise InputError(f"words of mixed lengths {lengths} in a fixed-length language: {out}",
                         source, field_name)
    if length is not None:
        wrong = [w for w in out if len(w) != length]
        if wrong:
            raise InputError(f"words {wrong} do not have the required length {length}", source, field_name)
    return tuple(out)


def worst_case_word(words: Sequence[str]) -> str:
    """Bitwise AND of a fixed-length language (Section III of the prefix-based paper).

    A measurement is kept only if every word has it, so an estimator that
    works for the worst-case word works for every word of the language.
    """
    words = validate_language(words)
    return "".join("1" if all(w[t] == "1" for w in words) else "0" for t in range(len(words[0])))


def prefixes(word: str) -> list[str]:
    """All non-empty prefixes ``Pref(word)``, shortest first."""
    return [word[: i + 1] for i in range(len(word))]


def extend_word(word: str, length: int) -> str:
    """Pad a word with ``1`` (measurements available) up to ``length``.

    Used for the minimum recovery time of Section V of the prefix-based paper,
    which assumes no missing measurement in the extension.
    """
    if length < len(word):
        raise InputError(f"cannot shorten word {word!r} to length {length}")
    return word + "1" * (length - len(word))


@dataclass
class PrefixNode:
    """A node of the prefix tree: the prefix ``q(0..depth-1)``.

    The gain row of time ``depth - 1`` (``F(t, ., prefix)`` and ``u0(t, prefix)``
    of eq. (7)) belongs to this node.
    """

    index: int
    prefix: str
    parent: int | None
    children: list[int] = field(default_factory=list)
    terminal: bool = False  # a word of the language ends here

    @property
    def depth(self) -> int:
        return len(self.prefix)

    @property
    def last(self) -> int:
        """``q(depth - 1)``: whether the measurement of this node's time arrives."""
        return int(self.prefix[-1])


class PrefixTree:
    """The prefix tree of a (finite-length) language.

    Nodes are numbered in breadth-first order (by depth, then
    lexicographically), so a parent always precedes its children.

    Parameters
    ----------
    words
        The language. Words may have different lengths (finite-length
        languages, Section V of the prefix-based paper); a word that is a
        prefix of another is allowed and marks an inner node terminal.
    """

    def __init__(self, words: Iterable[str], *, source: str | None = None):
        self.words: tuple[str, ...] = validate_language(words, fixed_length=False, source=source)
        all_prefixes = sorted({p for w in self.words for p in prefixes(w)}, key=lambda s: (len(s), s))
        self.index_of: dict[str, int] = {}
        self.nodes: list[PrefixNode] = []
        for p in all_prefixes:
            parent = self.index_of[p[:-1]] if len(p) > 1 else None
            node = PrefixNode(index=len(self.nodes), prefix=p, parent=parent, terminal=p in self.words)
            self.index_of[p] = node.index
            self.nodes.append(node)
            if parent is not None:
                self.nodes[parent].children.append(node.index)

    def __len__(self) -> int:
        return len(self.nodes)

    def __iter__(self):
        return iter(self.nodes)

    @property
    def depth(self) -> int:
        """Length of the longest word."""
        return max(len(w) for w in self.words)

    def node(self, prefix: str) -> PrefixNode:
        try:
            return self.nodes[self.index_of[prefix]]
        except KeyError:
            raise InputError(f"prefix {prefix!r} is not a prefix of any word of the language "
                             f"{list(self.words)}") from None

    def path(self, prefix: str) -> list[PrefixNode]:
        """Nodes of ``prefix[:1], prefix[:2], ..., prefix``."""
        return [self.node(p) for p in prefixes(prefix)]

    def contains_prefix(self, prefix: str) -> bool:
        return prefix in self.index_of
