r"""Data classes of a prefix tree: the nodes that see the same data at the same time.

A node of depth ``d`` of the prefix tree of a language (missing-data words,
delay words) owns the error :math:`\xi(d)` and the gain row of time ``d-1``,
which multiplies the measurements available at ``d-1``: the set
:math:`S = \mathcal A(d-1)` of times ``i`` with ``i + τ(i) <= d-1``.  The pair
``(d, S)`` is the node's **class**.  :mod:`eqrec.design.classes.engine` proves that
every design on the tree separates into one small LP per (class, state row)
and that nodes of one class have the same optimal level; this module finds
the classes, without solving anything.

Two ways to get them
--------------------
* :func:`classes_of_tree`: from any prefix tree (missing-data or delay
  words, words of different lengths), with each class's nodes, whether a
  word ends in it (its level is then bounded by ``μ1``) and the weight of
  the sum cost (sequences of the reduced language through its inner nodes).
* :func:`classes_of_full_language`: for the full language
  :math:`\{0..\bar\tau\}^T` of the delayed-data paper, directly from the
  **window rule**, never enumerating a word: at time ``k = d-1`` every
  measurement ``i <= k - τ̄`` has arrived, and each ``i`` in the window
  ``(k - τ̄, k]`` has arrived or not, independently.  So depth ``d`` has
  :math:`2^{\min(\bar\tau, d)}` classes and the whole language
  :math:`\sum_{d=1}^{T} 2^{\min(\bar\tau, d)}` (18 for the batch reactor's
  ``(5, 2)``, 446 for ``(30, 4)``, where there are :math:`5^{30} \approx
  9.3\cdot 10^{20}` words).  The counts the sum cost needs follow in closed
  form because the arrival times of different measurements are independent
  (:func:`full_language_counts`).
* the same with ``max_lost=m``: the **loss-aware** language of delays
  ``0..τ̄`` and at most ``m`` measurements *lost* per block (a lost
  measurement never arrives), still from a window rule, with a counting
  rule for the weights (:func:`classes_of_full_language`).

The error maps of a class, :math:`E_d` (open loop) and :math:`Z_S` (the
stacked output maps of the measurements in ``S``), come from
:class:`eqrec.bounds.stacking.Stacking` (:func:`class_maps`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from itertools import chain, combinations
from math import comb, factorial, prod

import numpy as np

from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.bounds.stacking import Stacking
from eqrec.checks import integer, short_label
from eqrec.errors import InputError


@dataclass(frozen=True, eq=False, slots=True)
class DataClass:
    """The nodes of depth ``depth`` whose available data at time ``depth - 1`` is ``available``.

    Parameters
    ----------
    depth : int
        ``d``: the class bounds the error :math:`\\xi(d)` (``1 <= d <= T``).
    available : tuple of int or WindowData
        ``S``: the measurement times available at ``d - 1``, increasing (the classes of
        :func:`classes_of_full_language` hold a :class:`WindowData`, which reads as that tuple).
    terminal : bool
        A word of the language ends at a node of this class (its level must
        be at most ``μ1``: the terminal constraint).
    inner : bool
        A node of this class is not a word's end (its level counts in ``μ2``).
    weight : int
        Sequences of the reduced language through the class's inner nodes:
        the class's weight in the delayed-data paper's sum cost.
    nodes : int
        Prefix-tree nodes in the class.
    """

    depth: int
    available: tuple[int, ...]
    terminal: bool
    inner: bool
    weight: int
    nodes: int

    @property
    def key(self) -> tuple[int, tuple[int, ...]]:
        """``(d, S)``."""
        return self.depth, self.available

    def _fields(self) -> tuple:
        return self.depth, self.available, self.terminal, self.inner, self.weight, self.nodes

    def __eq__(self, other) -> bool:
        """Equal fields (whatever the representation of the data: a tuple or a :class:`WindowData`)."""
        if not isinstance(other, DataClass):
            return NotImplemented
        return self._fields() == other._fields()

    def __hash__(self) -> int:
        return hash(self._fields())

    def __repr__(self) -> str:
        """The fields, with a long label and a huge weight shortened (Python refuses to print an ``int`` of more
        than 4,300 digits, and the weights of long horizons have more)."""
        return (f"DataClass({self.depth}, {short_label(self.label)}, terminal={self.terminal}, inner={self.inner}, "
                f"weight={_count(self.weight)}, nodes={_count(self.nodes)})")

    @property
    def label(self) -> str:
        """``d:S`` with ``S`` as a 0/1 string over the times ``0..d-1`` (``1``: available)."""
        s = set(self.available)
        return f"{self.depth}:" + "".join("1" if i in s else "0" for i in range(self.depth))


class WindowData(Sequence):
    """The data ``S`` of a class of the full language, ``(0, 1, ..., old - 1) + chosen``, without its tuple.

    The old times of a class of depth ``d`` (every time ``<= d - 1 - τ̄``) have all arrived, so ``S`` is them
    and a subset ``chosen`` of the window (at most ``τ̄`` times): held as ``old`` and ``chosen`` it costs
    ``O(τ̄)`` whatever ``d``, and the ``T 2^τ̄`` classes of ``{0..τ̄}^T`` are built in time and memory linear in
    ``T`` (as tuples they hold ``Σ|S| ≈ 2^τ̄ T² / 2`` entries).  It reads as the tuple it stands for: length,
    indexing, iteration, ``in`` (``O(1)``), equality and hash (a dict key interchangeable with the tuple).

    Parameters
    ----------
    old : int
        The times ``0..old-1``, all available.
    chosen : tuple of int
        The available window times, increasing, all ``>= old``.
    """

    __slots__ = ("old", "chosen", "_hash")

    def __init__(self, old: int, chosen: tuple[int, ...]) -> None:
        self.old, self.chosen, self._hash = old, chosen, None

    def __len__(self) -> int:
        return self.old + len(self.chosen)

    def __iter__(self):
        return chain(range(self.old), self.chosen)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return tuple(self)[i]
        n = len(self)
        i = i + n if i < 0 else i
        if not 0 <= i < n:
            raise IndexError("index out of range")
        return i if i < self.old else self.chosen[i - self.old]

    def __contains__(self, x) -> bool:
        return (isinstance(x, int) and 0 <= x < self.old) or x in self.chosen

    def as_tuple(self) -> tuple[int, ...]:
        """The tuple it stands for.

        Returns
        -------
        tuple of int
            ``(0, ..., old - 1) + chosen`` (``O(|S|)`` work).
        """
        return tuple(self)

    def __eq__(self, other) -> bool:
        if isinstance(other, WindowData):
            return self.old == other.old and self.chosen == other.chosen
        if isinstance(other, tuple):
            return len(other) == len(self) and other == tuple(self)
        return NotImplemented

    def __hash__(self) -> int:
        if self._hash is None:
            self._hash = hash(tuple(self))
        return self._hash

    def __lt__(self, other) -> bool:
        return tuple(self) < tuple(other)

    def __repr__(self) -> str:
        return repr(tuple(self))

    def __reduce__(self):
        return WindowData, (self.old, self.chosen)


class _WindowClass(DataClass):
    """A class of :func:`classes_of_full_language`: its data a :class:`WindowData` made when read, its weight and
    node count ``(τ̄+1)^exp * small`` expanded when read (the exponents grow with ``T``, the factors do not), so
    that a class holds neither an ``O(T)``-bit integer nor an ``O(T)`` tuple (two objects: itself and its
    window's tuple)."""

    __slots__ = ("_old", "_chosen", "_base", "_weight_power", "_node_power")

    def __init__(self, depth: int, old: int, chosen: tuple[int, ...], inner: bool, base: int,
                 weight_power: tuple[int, int], node_power: tuple[int, int]) -> None:
        set_ = object.__setattr__  # frozen: set once, here
        set_(self, "depth", depth)
        set_(self, "terminal", not inner)
        set_(self, "inner", inner)
        set_(self, "_old", old)
        set_(self, "_chosen", chosen)
        set_(self, "_base", base)
        set_(self, "_weight_power", weight_power)
        set_(self, "_node_power", node_power)

    @property
    def available(self) -> WindowData:  # type: ignore[override]
        return WindowData(self._old, self._chosen)

    @property
    def weight(self) -> int:  # type: ignore[override]
        exp, small = self._weight_power
        return self._base ** exp * small if small else 0

    @property
    def nodes(self) -> int:  # type: ignore[override]
        exp, small = self._node_power
        return self._base ** exp * small

    def __reduce__(self):
        return _WindowClass, (self.depth, self._old, self._chosen, self.inner, self._base, self._weight_power,
                              self._node_power)


def _count(value: int) -> str:
    """An integer as text; past 30 digits its order of magnitude (``~1e3010``), from its bit length."""
    if abs(value) < 10 ** 30:
        return str(value)
    return f"~1e{int(value.bit_length() * 0.30102999566398120)}"


@dataclass(repr=False)
class ClassSet:
    """The classes of a language, ordered by depth then by data set.

    Parameters
    ----------
    classes : tuple of DataClass
        The classes, ordered by depth, then size and content of ``S``.
    horizon : int
        ``T``: the longest word (the stacking horizon).
    words, sequences, nodes : int
        Words of the language, sequences of its reduced language
        (distinct event sequences) and prefix-tree nodes.
    source : str
        ``"tree"`` (:func:`classes_of_tree`) or ``"window"``
        (:func:`classes_of_full_language`).
    node_class : dict
        Tree only: node index -> position of its class in ``classes``.
    tree : PrefixTree or None
        Tree only: the prefix tree the classes come from.
    """

    classes: tuple[DataClass, ...]
    horizon: int
    words: int
    sequences: int
    nodes: int
    source: str
    node_class: dict[int, int] = field(default_factory=dict)
    tree: PrefixTree | None = None

    def __len__(self) -> int:
        return len(self.classes)

    def __iter__(self):
        return iter(self.classes)

    def __repr__(self) -> str:
        """A summary (the classes themselves can number millions, their counts thousands of digits)."""
        return (f"ClassSet({len(self.classes)} classes, horizon={self.horizon}, words={_count(self.words)}, "
                f"sequences={_count(self.sequences)}, nodes={_count(self.nodes)}, source={self.source!r})")

    def index(self, depth: int, available) -> int:
        """Position of the class ``(depth, available)``; :class:`InputError` if the language has none.

        Parameters
        ----------
        depth : int
            ``d``, ``1 <= d <= T``.
        available : iterable of int
            ``S``: measurement times available at ``d - 1`` (any order).

        Returns
        -------
        int
            Index into ``classes``.
        """
        try:
            return self._index[(int(depth), tuple(sorted(int(i) for i in available)))]
        except KeyError:
            raise InputError(f"no class of depth {depth} with data {short_label(sorted(available))} in this "
                             "language") from None

    @property
    def _index(self) -> dict:
        idx = self.__dict__.get("_idx")
        if idx is None:
            idx = self.__dict__["_idx"] = {c.key: i for i, c in enumerate(self.classes)}
        return idx

    def per_depth(self) -> list[int]:
        """Number of classes at depths ``1..T``.

        Returns
        -------
        list of int
            Length ``T``; entry ``d - 1`` counts the classes of depth ``d``.
        """
        return np.bincount([c.depth for c in self.classes], minlength=self.horizon + 1)[1:].tolist()


def _ordered(found: dict) -> tuple[DataClass, ...]:
    return tuple(sorted(found.values(), key=lambda c: (c.depth, len(c.available), c.available)))


def classes_of_tree(tree: PrefixTree) -> ClassSet:
    """The classes ``(d, S)`` of the nodes of ``tree`` (any language, words of any lengths).

    The weight of a class is the number of the tree's patterns (sequences of
    the reduced language) through its inner nodes.

    Parameters
    ----------
    tree : PrefixTree
        Prefix tree of the language.

    Returns
    -------
    ClassSet
        The classes, with ``node_class`` and ``tree`` set (``source="tree"``).
    """
    through = tree.sequences_through()
    acc: dict[tuple, dict] = {}
    of_node: dict[int, tuple] = {}
    for node in tree:
        key = (node.depth, tuple(node.available))
        a = acc.setdefault(key, {"terminal": False, "inner": False, "weight": 0, "nodes": 0})
        a["nodes"] += 1
        if node.terminal:
            a["terminal"] = True
        if not node.terminal:  # a word's end (even with children) is bounded by μ1 only
            a["inner"] = True
            a["weight"] += through[node.index]
        of_node[node.index] = key
    found = {k: DataClass(k[0], k[1], v["terminal"], v["inner"], v["weight"], v["nodes"]) for k, v in acc.items()}
    classes = _ordered(found)
    pos = {c.key: i for i, c in enumerate(classes)}
    return ClassSet(classes=classes, horizon=tree.depth, words=len(tree.patterns), sequences=len(tree.patterns),
                    nodes=len(tree), source="tree", node_class={i: pos[k] for i, k in of_node.items()}, tree=tree)


def _arrival_values(i: int, T: int, max_delay: int) -> int:
    """Distinct arrival outcomes of measurement ``i`` in ``{0..τ̄}^T``: times ``i..min(i+τ̄, T-1)``, and 'never'
    when ``i + τ̄ >= T`` (a delay past the horizon means missing)."""
    return min(max_delay, T - 1 - i) + 1 + (1 if i + max_delay >= T else 0)


def _arrived_by(i: int, k: int, max_delay: int) -> int:
    """Outcomes of measurement ``i`` that arrive by time ``k`` (``i <= k``): times ``i..min(i+τ̄, k)``."""
    return min(max_delay, k - i) + 1


def full_language_counts(T: int, max_delay: int, max_lost: int | None = None) -> dict[str, int]:
    r"""Words, sequences (distinct event sequences) and prefix-tree nodes of ``{0..τ̄}^T``, in closed form.

    The arrival outcome of each measurement (a time, or never) is independent
    of the others', so the reduced language is the product of the outcome
    sets; a node of depth ``d`` is a choice, per ``i < d``, of an arrival
    time ``<= d-1`` or 'not yet' (possible when ``i + τ̄ > d-1``).

    With ``max_lost = m`` (the loss-aware language, :func:`classes_of_full_language`)
    a word is a delay ``0..τ̄`` or 'lost' per measurement with at most ``m``
    lost: :math:`\sum_{j \le m} \binom{T}{j} (\bar\tau+1)^{T-j}` words.  The
    sequences and nodes are counted with one polynomial per measurement, in a
    variable ``z`` marking a loss (:func:`_lossy`), truncated at degree ``m``.

    Parameters
    ----------
    T : int
        Horizon (word length).
    max_delay : int
        Largest delay ``τ̄``.
    max_lost : int or None, optional
        At most this many measurements lost per block (``None``: none lost, the full delay language).

    Returns
    -------
    dict of str to int
        ``{"words": ..., "sequences": ..., "nodes": ...}`` (``(τ̄+1)^T`` words without losses).
    """
    if max_lost is not None:
        return _loss_counts(int(T), int(max_delay), int(max_lost))
    T, D = int(T), int(max_delay)
    sequences = _tail(0, T, D)
    # the nodes of depth d: (D + 1)^|old| (each old time arrived at one of D + 1 times) times, per window time
    # i = d-1-j (j < w = min(D, d)), its j + 1 arrival times by d-1 or 'not yet': (w + 1)! in all.  From d = D on
    # the window is full, a geometric series: closed form, no O(T)-bit integer per depth
    nodes = sum(factorial(d + 1) for d in range(1, min(T, D - 1) + 1))
    if T >= max(D, 1):
        first = max(D, 1)  # D = 0: every depth has one node
        terms = T - first + 1
        nodes += factorial(D + 1) * (D + 1) ** (first - D) * (terms if D == 0 else ((D + 1) ** terms - 1) // D)
    return {"words": (D + 1) ** T, "sequences": sequences, "nodes": nodes}


def _tail(d: int, T: int, D: int) -> int:
    """The outcomes of the times ``d..T-1`` together, ``∏ _arrival_values(i)``: ``D + 1`` for each time
    ``i < T - D`` (every delay lands in the block), ``T - i + 1`` for the later ones."""
    return (D + 1) ** max(0, T - D - d) * _tail_small(d, T, D)


def _tail_small(d: int, T: int, D: int) -> int:
    """The factor of :func:`_tail` of the times ``max(d, T-D)..T-1`` (at most ``D`` of them)."""
    return prod(T - i + 1 for i in range(max(d, T - D), T))


def classes_of_full_language(T: int, max_delay: int, max_lost: int | None = None) -> ClassSet:
    r"""The classes of ``{0..τ̄}^T`` from the window rule (module docstring), never enumerating words.

    The weight of the inner class ``(d, S)`` (``d < T``) is the number of
    sequences whose data at ``d-1`` is ``S``: per ``i < d``, the outcomes
    arriving by ``d-1`` if ``i ∈ S`` and the others if not, times all the
    outcomes of ``i >= d``.

    **Loss-aware language** (``max_lost = m``).  A word gives each
    measurement ``i`` of the block a delay ``τ(i) ∈ {0..τ̄}`` or *lost*, with at
    most ``m`` lost.  A lost measurement never arrives; a delay with
    ``i + τ(i) >= T`` is, as without losses, "not available in this block"
    and is *not* a loss.  So the outcome "never" of ``i`` costs one loss
    exactly when ``i + τ̄ < T`` (every delay would land in the block), and is
    free otherwise; ``m = T`` allows every arrival pattern.

    *Window rule with losses.*  At ``k = d-1`` split the times ``i <= k``
    into the old ones ``O = {i <= k - τ̄}`` and the window
    ``W = (k - τ̄, k]``.  The classes of depth ``d`` are exactly the
    :math:`S \subseteq \{0..k\}` with :math:`|O \setminus S| \le m`, so
    :math:`2^{|W|} \sum_{j \le m} \binom{|O|}{j}` of them
    (:func:`full_language_class_count`).
    Proof sketch: an old ``i`` missing at ``k`` was not delivered although
    ``i + τ̄ <= k < T``, so it is lost (one loss each): no word of the
    language gives more than ``m`` old times missing.  Conversely, for such
    an ``S``, the word with the old missing times lost, the other old times
    and the window times of ``S`` on time, the window times outside ``S``
    delayed by ``τ̄`` (they arrive after ``k``, or never: no loss), and the
    times after ``k`` on time, has ``|O \ S| <= m`` losses and data ``S`` at
    ``k``.  The prefix-tree nodes of the class are the choices of an arrival
    time ``<= k`` for each ``i ∈ S`` (the 'not yet' of ``i ∉ S`` is one
    node), all of them reachable by the same construction, so their number
    is the formula without losses.

    *Counting rule for the weights.*  Outcomes of different measurements are
    chosen independently except for the loss budget, so the number of
    sequences with data ``S`` at ``k`` is the sum of the coefficients of
    ``z^0..z^m`` of the product, over all ``i``, of one polynomial per
    measurement whose coefficient of ``z^ℓ`` counts its outcomes with ``ℓ``
    losses: ``i ∈ S``: the arrival times ``<= k`` (no ``z``); ``i <= k``,
    ``i ∉ S``: the arrival times after ``k`` plus the free 'never', and
    ``z`` for the lost 'never' (:func:`_lossy`); ``i > k``: all its
    outcomes, ``z`` for the lost one.  An old missing time contributes just
    ``z``, an old time of ``S`` the constant ``τ̄ + 1``, so the product is
    :math:`(\bar\tau+1)^{|O \cap S|} z^{|O \setminus S|}` times one
    polynomial per (depth, window subset), computed once.  With ``m = 0`` the
    rule and the counts are those of the full language ``{0..τ̄}^T``.

    Parameters
    ----------
    T : int
        Horizon, ``>= 1``.
    max_delay : int
        Largest delay ``τ̄``, ``>= 0``.
    max_lost : int or None, optional
        At most this many measurements lost per block, ``0..T`` (``None``, default, or ``0``: the language
        without losses).

    Returns
    -------
    ClassSet
        The classes (``source="window"``, no tree) and the counts of :func:`full_language_counts`.  Without
        losses built in time and memory linear in ``T`` (``O(τ̄)`` per class): each class's data is a
        :class:`WindowData` (the old times as a count, the window's as a tuple) and its weight and node count
        are expanded from ``(τ̄+1)^e`` times a small factor only when read (as tuples and integers the
        ``T 2^τ̄`` classes hold ``Σ|S| ≈ 2^τ̄ T²/2`` entries and ``O(T)``-bit weights each).  With losses each
        class holds its data tuple and weight.

    Raises
    ------
    InputError
        ``T < 1``, ``max_delay < 0``, or ``max_lost`` outside ``0..T`` (the field is named).
    """
    T, D = int(T), int(max_delay)
    if T < 1 or D < 0:
        raise InputError(f"the full language needs horizon >= 1 and max delay >= 0, got ({T}, {D})",
                         field="max_delay")
    if max_lost is not None and _check_lost(max_lost, T):  # m = 0: the language without losses, its classes
        return _classes_with_losses(T, D, _check_lost(max_lost, T))
    counts = full_language_counts(T, D, max_lost)
    # per class O(D) work and memory whatever T: its data a WindowData (the old times 0..n_old-1 and the chosen
    # window times), its weight and node count (D+1)^exp times a small factor, expanded only when read; the
    # weight is tail(d) (the outcomes of the times d..T-1) times (D+1)^n_old times the window's factor
    classes = []
    base = D + 1
    for d in range(1, T + 1):
        k = d - 1
        n_old = max(0, d - D)  # the old times 0..k-D: every one arrived by k, D + 1 ways
        window = tuple(range(n_old, d))
        inner = d < T
        by_k = {i: _arrived_by(i, k, D) for i in window}
        not_yet = {i: _arrival_values(i, T, D) - by_k[i] for i in window}
        weight_exp, tail_small = max(0, T - D - d) + n_old, _tail_small(d, T, D)
        for r in range(len(window) + 1):
            for chosen in combinations(window, r):
                s = set(chosen)
                # nodes: per i < d, an arrival time <= k if i ∈ S, else 'not yet' (the window makes it possible)
                node_power = (n_old, prod(by_k[i] for i in chosen))
                weight_power = (weight_exp, tail_small * prod(by_k[i] if i in s else not_yet[i] for i in window)
                                if inner else 0)
                classes.append(_WindowClass(d, n_old, chosen, inner, base, weight_power, node_power))
    # made in the order of _ordered (depth, then |S|, then S: combinations are lexicographic), each key once
    return ClassSet(classes=tuple(classes), horizon=T, source="window", **counts)


# ---------------------------------------------------------------------------------------------- with losses

def _check_lost(max_lost, T: int) -> int:
    """``max_lost`` as an int in ``0..T``, else an :class:`InputError` naming ``max_lost``."""
    return integer(max_lost, "max_lost", high=T)


def _lossy(i: int, T: int, max_delay: int) -> int:
    """1 if the outcome 'never' of measurement ``i`` is a loss (``i + τ̄ < T``: every delay lands in the block)."""
    return 1 if i + max_delay < T else 0


def _times(a: list[int], b: list[int], m: int) -> list[int]:
    """The product of two integer polynomials (coefficient ``ℓ`` of ``z^ℓ``), truncated at degree ``m``."""
    out = [0] * min(len(a) + len(b) - 1, m + 1)
    for i, x in enumerate(a[:m + 1]):
        if x:
            for j, y in enumerate(b[:m + 1 - i]):
                out[i + j] += x * y
    return out


def _outcomes(i: int, T: int, max_delay: int) -> list[int]:
    """All outcomes of measurement ``i``: ``[free, lost]`` (arrival times and the free 'never'; the lost 'never')."""
    return [_arrival_values(i, T, max_delay), _lossy(i, T, max_delay)]


def _loss_counts(T: int, D: int, m: int) -> dict[str, int]:
    """:func:`full_language_counts` of the loss-aware language (polynomials in the loss marker ``z``)."""
    m = _check_lost(m, T)
    words = sum(comb(T, j) * (D + 1) ** (T - j) for j in range(m + 1))
    seq = [1]
    for i in range(T):
        seq = _times(seq, _outcomes(i, T, D), m)
    nodes = 0
    for d in range(1, T + 1):
        k, poly = d - 1, [1]
        for i in range(d):  # an arrival time <= k, or 'not yet': free in the window, a loss for an old time
            window = i + D > k
            poly = _times(poly, [_arrived_by(i, k, D) + window, 0 if window else 1], m)
        nodes += sum(poly)
    return {"words": words, "sequences": sum(seq), "nodes": nodes}


def full_language_class_count(T: int, max_delay: int, max_lost: int | None = None) -> int:
    r"""Number of classes of :func:`classes_of_full_language`, without building them.

    :math:`\sum_{d=1}^{T} 2^{|W_d|} \sum_{j \le m} \binom{|O_d|}{j}` with
    ``|W_d| = min(τ̄, d)`` window times and ``|O_d| = d - |W_d|`` old ones
    (``m = ∞`` without losses: :math:`\sum_d 2^{\min(\bar\tau, d)}`).

    Parameters
    ----------
    T : int
        Horizon, ``>= 1``.
    max_delay : int
        Largest delay ``τ̄``, ``>= 0``.
    max_lost : int or None, optional
        At most this many lost per block (``None``: no loss).

    Returns
    -------
    int
        The number of classes ``(d, S)``.

    Examples
    --------
    >>> from eqrec.bounds.data_classes import full_language_class_count
    >>> full_language_class_count(30, 4), full_language_class_count(100, 4, 1)
    (446, 76062)
    """
    T, D = int(T), int(max_delay)
    m = 0 if max_lost is None else _check_lost(max_lost, T)
    total = 0
    for d in range(1, T + 1):
        w = min(D, d)
        total += 2 ** w * sum(comb(d - w, j) for j in range(min(m, d - w) + 1))
    return total


def _classes_with_losses(T: int, D: int, m: int) -> ClassSet:
    """The classes of the loss-aware language: the window rule with losses (:func:`classes_of_full_language`)."""
    counts = _loss_counts(T, D, m)
    # suffix[d]: the polynomial of the outcomes of the times d..T-1 (the tail of every class of depth d)
    suffix = [[1] for _ in range(T + 1)]
    for i in range(T - 1, -1, -1):
        suffix[i] = _times(suffix[i + 1], _outcomes(i, T, D), m)
    classes = []
    for d in range(1, T + 1):
        k = d - 1
        old = tuple(range(0, k - D + 1))
        window = tuple(range(max(0, k - D + 1), k + 1))
        inner = d < T
        for r in range(len(window) + 1):
            for chosen in combinations(window, r):
                s = set(chosen)
                # the window times: in S an arrival time <= k; else a later arrival or the free 'never', or lost
                poly = suffix[d]
                for i in window:
                    here = [_arrived_by(i, k, D)] if i in s else [_arrival_values(i, T, D) - _arrived_by(i, k, D),
                                                                     _lossy(i, T, D)]
                    poly = _times(poly, here, m)
                window_nodes = prod(_arrived_by(i, k, D) for i in chosen)
                for j in range(min(m, len(old)) + 1):  # j old times missing: each one lost
                    scale = (D + 1) ** (len(old) - j)
                    weight = scale * sum(poly[:m - j + 1]) if inner else 0
                    for lost in combinations(old, j):
                        S = tuple(sorted(set(old).difference(lost))) + chosen
                        classes.append(DataClass(d, S, terminal=not inner, inner=inner, weight=weight,
                                                 nodes=scale * window_nodes))
    return ClassSet(classes=_ordered({c.key: c for c in classes}), horizon=T, source="window", **counts)


def class_maps(stacking: Stacking, cls: DataClass) -> tuple[np.ndarray, np.ndarray]:
    r"""``(E_d, Z_S)``: the open-loop error map of time ``d`` and the stacked output maps of ``S``.

    With :math:`\delta = (w, v, \xi_0)`, :math:`x(d) - \bar x(d) = E_d\delta`
    and :math:`y_S - \bar y_S = Z_S\delta` for the noise-free prediction
    :math:`\bar x, \bar y` from :math:`\hat x(0)`.  Shapes ``(n, D)`` and
    ``(|S| p, D)``.

    Parameters
    ----------
    stacking : Stacking
        Stacked maps of the system over the horizon.
    cls : DataClass
        The class ``(d, S)``.

    Returns
    -------
    E : ndarray, shape (n, D)
        Open-loop error map of time ``d``.
    Z : ndarray, shape (|S| p, D)
        Output maps of the measurements in ``S``, by time then output.
    """
    E = stacking.open_loop[cls.depth]
    S = list(cls.available)
    Z = stacking.output_maps[S].reshape(len(S) * stacking.system.p, -1) if S else np.zeros((0, E.shape[1]))
    return E, Z


def class_error_map(stacking: Stacking, gains: "ClassGains", i: int) -> np.ndarray:
    r"""``G = E_d − K Z_S``: the error map of class ``i`` under its gain, :math:`\xi(d) = G\delta`.

    The one formula of a class's closed-loop error (certificate, long runs, error boxes).

    Parameters
    ----------
    stacking : Stacking
        Stacked maps of the system over the horizon.
    gains : ClassGains
        The class gains.
    i : int
        Index of the class in ``gains.classes``.

    Returns
    -------
    ndarray, shape (n, D)
        The map from ``δ = (w, v, ξ0)`` to the error at the class's time.
    """
    E, Z = class_maps(stacking, gains.classes.classes[i])
    return E - gains.K[i] @ Z


@dataclass
class ClassGains:
    r"""One gain per class: the estimator in class form.

    .. math:: \hat x(d) = \bar x(d) + K_{(d,S)}\,(y_S - \bar y_S),

    with :math:`\bar x, \bar y` the noise-free prediction from
    :math:`\hat x(0)` (inputs and ``f`` included) and ``S`` the data received
    by time ``d-1`` (:class:`eqrec.estimators.causal.ClassEstimator` runs it).

    Parameters
    ----------
    classes : ClassSet
        The classes of the language.
    K : list of ndarray
        ``K[i]`` of shape ``(n, |S_i| p)``, columns ordered by measurement time
        then output.
    n, p : int
        State and output dimensions.
    """

    classes: ClassSet
    K: list[np.ndarray]
    n: int
    p: int

    @property
    def horizon(self) -> int:
        """``T`` of the class set."""
        return self.classes.horizon

    def gain(self, depth: int, available) -> np.ndarray:
        """``K`` of the class ``(depth, available)``.

        Parameters
        ----------
        depth : int
            ``d``.
        available : iterable of int
            ``S``: measurement times available at ``d - 1``.

        Returns
        -------
        ndarray, shape (n, |S| p)
            The class gain.
        """
        return self.K[self.classes.index(depth, available)]

    def estimate(self, depth: int, available, xbar: np.ndarray, residuals) -> np.ndarray:
        r"""The class form :math:`\hat x(d) = \bar x(d) + K_{(d,S)}(y_S - \bar y_S)`.

        :class:`InputError` if the language has no class ``(depth, available)``.

        Parameters
        ----------
        depth : int
            ``d``.
        available : sequence of int
            ``S``, increasing.
        xbar : ndarray, shape (n,)
            Noise-free prediction :math:`\bar x(d)`.
        residuals : sequence of ndarray
            The :math:`y(\tau) - C(\tau)\bar x(\tau)` of the times in ``available``, each of length ``p``.

        Returns
        -------
        ndarray, shape (n,)
            The estimate :math:`\hat x(d)`.
        """
        S = tuple(available)
        K = self.gain(depth, S)
        return xbar + K @ np.concatenate([np.asarray(r, float) for r in residuals]) if S else np.array(xbar, float)

    def to_json(self) -> dict:
        """``{"d:S": K}`` (``S`` as a 0/1 string over times ``0..d-1``).

        Returns
        -------
        dict of str to list
            Class label -> ``K`` as nested lists.
        """
        return {c.label: k.tolist() for c, k in zip(self.classes, self.K)}
