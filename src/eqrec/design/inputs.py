"""What the design entries take: typed word lists, languages, the system, ``μ1`` and the solver, checked.

Every public design entry (:func:`eqrec.design_prefix`, :func:`eqrec.design_time_based`,
:func:`eqrec.design_delay`, :func:`eqrec.design_delay_global`, :func:`eqrec.design_augmented`,
:func:`eqrec.min_recovery_level`) reads its inputs through this module, so a bad input is an
:class:`~eqrec.errors.InputError` naming the parameter, never a raw numpy or Python error.

Words are read by the one rule of :mod:`eqrec.arrivals.words`: a 0/1 string is both a missing-data
word and a delay word, so :func:`missing_words` and :func:`delay_words` make the reading explicit
(typed patterns need no reading).
"""

from __future__ import annotations

import contextlib
import contextvars
import numbers
import os
from dataclasses import dataclass
from itertools import combinations
from typing import Any, Iterable

import numpy as np

from eqrec.checks import available_memory as _memory_available, integer
from eqrec.bounds.data_classes import ClassSet, classes_of_tree
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.lp.solvers import solver_info
from eqrec.systems.affine import AffineSystem
from eqrec.arrivals.words import as_language
from eqrec.errors import InputError

#: The value of ``mu1`` that asks for the smallest feasible recovery level (the μ1-free theorem).
FREE = "free"


def missing_words(words: Iterable["str | ArrivalPattern"], *, field_name: str = "words",
                  source: str | None = None) -> tuple[ArrivalPattern, ...]:
    """Missing-data words ``q(0) ... q(T-1)`` over ``{0, 1}`` as typed patterns (``1`` arrives, ``0`` is lost).

    The explicit reading of eq. (3) of the prefix-based paper, accepted by
    every design entry (a 0/1 string alone is also a delay word: see
    :mod:`eqrec.arrivals.words`).  Equal words are merged; lengths may differ
    (the design entries check them).

    Parameters
    ----------
    words : iterable of str or ArrivalPattern
        0/1 words (surrounding whitespace ignored) or patterns; a single word is a one-word language.
    field_name : str, optional
        Field named in error messages.
    source : str or None, optional
        File (or other origin) named in error messages.

    Returns
    -------
    tuple of ArrivalPattern
        One pattern per distinct word, in the order of first occurrence.

    Raises
    ------
    InputError
        A letter other than ``0`` and ``1``, an empty word or language.

    Examples
    --------
    >>> import eqrec
    >>> eqrec.missing_words(["0111", "1011"])
    (ArrivalPattern('0111', arrivals=(None, 1, 2, 3)), ArrivalPattern('1011', arrivals=(0, None, 2, 3)))
    """
    return as_language(words, kind="missing", fixed_length=False, field_name=field_name, source=source)


def missing_words_at_most(T: int, m: int) -> tuple[ArrivalPattern, ...]:
    r"""Every missing-data word of length ``T`` with at most ``m`` zeros: at most ``m`` measurements lost per block.

    The prefix design's language for the loss-aware rule of :func:`eqrec.delay_classes` without delays
    (``max_delay=0``: the same arrival patterns, so the same classes).  Ordered by the number of zeros,
    then by the positions of the zeros (``111..1``, then ``011..1``, ``101..1``, ...).

    Parameters
    ----------
    T : int
        Word length (the horizon), at least 1.
    m : int
        Largest number of zeros, ``0..T`` (``T``: all ``2^T`` words).

    Returns
    -------
    tuple of ArrivalPattern
        :math:`\sum_{j \le m} \binom{T}{j}` typed missing-data patterns (no reading needed).

    Raises
    ------
    InputError
        ``T`` not an integer >= 1 or ``m`` not one in ``0..T`` (the field is named), or more than
        :data:`eqrec.arrivals.words.MAX_LISTED_WORDS` words (field ``T``).

    Examples
    --------
    >>> import eqrec
    >>> [p.label for p in eqrec.missing_words_at_most(4, 1)]
    ['1111', '0111', '1011', '1101', '1110']
    """
    from math import comb

    from eqrec.arrivals.words import check_listed_words

    T = integer(T, "T", low=1)
    m = integer(m, "m", high=T)
    check_listed_words(sum(comb(T, j) for j in range(m + 1)), f"at most {m} of {T} lost", "T")
    words = []
    for j in range(m + 1):
        for zeros in combinations(range(T), j):
            word = ["1"] * T
            for i in zeros:
                word[i] = "0"
            words.append("".join(word))
    return missing_words(words)


def delay_words(words: Iterable["str | ArrivalPattern"], max_delay: int | None = None, *,
                field_name: str = "delays", source: str | None = None) -> tuple[ArrivalPattern, ...]:
    """Delay words ``τ(0) ... τ(T-1)`` of digits as typed patterns (eq. (1) of the delayed-data paper).

    The explicit reading of a delay word (:func:`eqrec.parse_delay_word`):
    ``0111`` is then "``y(0)`` on time, ``y(1)``, ``y(2)`` one step late,
    ``y(3)`` beyond the horizon", not a missing-data word.  Words with equal
    event sequences are merged (the reduced language ``L^{E'}``).

    Parameters
    ----------
    words : iterable of str or ArrivalPattern
        Digit words or patterns; a single word is a one-word language.
    max_delay : int or None, optional
        Largest allowed delay ``τ̄`` (``None``: no limit).
    field_name : str, optional
        Field named in error messages.
    source : str or None, optional
        File (or other origin) named in error messages.

    Returns
    -------
    tuple of ArrivalPattern
        One pattern per distinct event sequence, in the order of first occurrence.

    Raises
    ------
    InputError
        A letter that is not a digit, a delay above ``max_delay``, an empty word or language.

    Examples
    --------
    >>> import eqrec
    >>> eqrec.delay_words(["0111"])
    (ArrivalPattern('0111', arrivals=(0, 2, 3, None)),)
    """
    return as_language(words, kind="delay", max_delay=max_delay, fixed_length=False, field_name=field_name,
                       source=source)


def language_tree(words: Any, *, kind: str | None, fixed_length: bool = True,
                  field_name: str = "words") -> PrefixTree:
    """The prefix tree of a design entry's language: a tree, patterns, or strings read as ``kind``.

    Parameters
    ----------
    words : PrefixTree, ArrivalPattern, str or iterable of them
        The language.
    kind : {"missing", "delay"} or None
        Reading of the strings (:func:`eqrec.arrivals.words.as_language`; ``None``: refuse 0/1 strings).
    fixed_length : bool, optional
        Refuse words of different lengths, with the command line's message (default).
    field_name : str, optional
        Parameter named in error messages.

    Returns
    -------
    PrefixTree
        ``words`` itself if it is a tree, else the tree of its patterns.

    Raises
    ------
    InputError
        Malformed or ambiguous words, or mixed lengths with ``fixed_length``.
    """
    if isinstance(words, PrefixTree):
        if fixed_length:
            as_language(words.patterns, fixed_length=True, field_name=field_name)
        return words
    patterns = as_language(words, kind=kind, fixed_length=fixed_length, field_name=field_name)
    return PrefixTree(patterns)


def language_classes(language: Any, *, kind: str | None, fixed_length: bool = True,
                     field_name: str = "patterns") -> ClassSet:
    """The (time, available data) classes of a language given as classes, a prefix tree, patterns or words.

    Parameters
    ----------
    language : ClassSet, PrefixTree, ArrivalPattern, str or iterable of them
        The language (a :class:`~eqrec.bounds.data_classes.ClassSet` is returned as is).
    kind : {"missing", "delay"} or None
        Reading of string words (:func:`language_tree`).
    fixed_length : bool, optional
        Refuse words of different lengths (default).
    field_name : str, optional
        Parameter named in error messages.

    Returns
    -------
    ClassSet
        The classes (:func:`eqrec.bounds.data_classes.classes_of_tree` of the language's tree).
    """
    if isinstance(language, ClassSet):
        return language
    return classes_of_tree(language_tree(language, kind=kind, fixed_length=fixed_length, field_name=field_name))


def check_system(system: Any) -> AffineSystem:
    """``system`` if it is an :class:`~eqrec.systems.affine.AffineSystem`, else an :class:`InputError`.

    Parameters
    ----------
    system : AffineSystem
        The value given as the system.

    Returns
    -------
    AffineSystem
        ``system`` unchanged.
    """
    if not isinstance(system, AffineSystem):
        raise InputError(f"expected an AffineSystem (eqrec.AffineSystem(...) or eqrec.load_system(path)), got "
                         f"{type(system).__name__}", field="system")
    return system


def check_solver(solver: Any) -> str:
    """``solver`` if it names a solver of the registry, else an :class:`InputError` (field ``solver``).

    Parameters
    ----------
    solver : str
        A name of :data:`eqrec.lp.solvers.SOLVER_NAMES`.

    Returns
    -------
    str
        ``solver`` unchanged.
    """
    solver_info(solver)
    return solver


def check_flags(*, none_ok: tuple[str, ...] = ("node_gains",), **flags: Any) -> None:
    """Each flag ``True`` or ``False`` (or ``None``, the default, for those in ``none_ok``), else :class:`InputError`.

    A string such as ``"no"`` would otherwise be read as true.

    Parameters
    ----------
    none_ok : tuple of str, optional
        The flags that may also be ``None`` (default ``("node_gains",)``).
    **flags : bool
        The flags, by name (the name is the field of the error).
    """
    for name, value in flags.items():
        if not (isinstance(value, (bool, np.bool_)) or (value is None and name in none_ok)):
            raise InputError(f"must be True or False, got {value!r}", field=name)


def check_mu1(mu1: Any, *, allow_free: bool = False, field_name: str = "mu1") -> "float | str":
    """The recovery level ``μ1`` as a positive finite float (or ``"free"`` where allowed), else :class:`InputError`.

    Parameters
    ----------
    mu1 : float or str
        The value given.
    allow_free : bool, optional
        Accept the string ``"free"`` (the smallest feasible ``μ1``).
    field_name : str, optional
        Parameter named in error messages.

    Returns
    -------
    float or str
        ``float(mu1)``, or ``"free"``.
    """
    if isinstance(mu1, str) and mu1.strip().lower() == FREE:
        if allow_free:
            return FREE
        raise InputError("'free' is not accepted here; give a positive number", field=field_name)
    if isinstance(mu1, (bool, np.bool_)) or not isinstance(mu1, numbers.Real):
        what = "a positive number or 'free'" if allow_free else "a positive number"
        raise InputError(f"the recovery level must be {what}, got {mu1!r}", field=field_name)
    value = float(mu1)
    if not np.isfinite(value) or value <= 0:
        raise InputError(f"the recovery level mu1 must be positive, got {value}", field=field_name)
    return value


def real_array(value: Any, field_name: str, *, complex_ok: bool = False) -> np.ndarray:
    """``value`` as a finite float (or, with ``complex_ok``, complex) array, else :class:`InputError`.

    Strings, booleans, ``None`` entries and ragged nesting are refused, not
    converted (``"1"`` is not the number 1).

    Parameters
    ----------
    value : array_like
        The value given.
    field_name : str
        Parameter named in error messages.
    complex_ok : bool, optional
        Accept complex entries (poles).

    Returns
    -------
    numpy.ndarray
        A float (or complex) array of ``value``'s shape.
    """
    kinds = "iufc" if complex_ok else "iuf"
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):  # ragged nesting
        raw = None
    if raw is None or raw.dtype.kind not in kinds:
        what = "numbers" if complex_ok else "real numbers"
        raise InputError(f"must be an array of {what}, got {value!r}", field=field_name)
    arr = raw.astype(complex if raw.dtype.kind == "c" else float)
    if not np.all(np.isfinite(arr)):
        raise InputError("contains NaN or infinite entries", field=field_name)
    return arr


def check_fraction(value: Any, field_name: str) -> float:
    """``value`` as a float strictly between 0 and 1 (a relative tolerance), else :class:`InputError`.

    Parameters
    ----------
    value : float
        The value given.
    field_name : str
        Parameter named in error messages.

    Returns
    -------
    float
        ``float(value)``.
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real) or not 0 < float(value) < 1:
        raise InputError(f"must be a number strictly between 0 and 1, got {value!r}", field=field_name)
    return float(value)


# ---------------------------------------------------------------------------
# The size of a --max-delay design, before solving (issue 33 §2)
# ---------------------------------------------------------------------------

#: Estimated seconds above which ``eqrec design`` refuses a ``--max-delay`` design unless ``--force`` (10 min).
MAX_ESTIMATED_SECONDS = 600.0
#: Fraction of the machine's available memory above which it refuses (unless ``--force``).
MAX_MEMORY_FRACTION = 0.8
#: The time model of :func:`estimate_delay_design`: a class's level LPs at both μ1 of a μ1-free design take about
#: ``SECONDS_PER_RUN`` per LP plus ``SECONDS_PER_WORK * n * work**WORK_EXPONENT`` (``work`` = rows x columns,
#: :func:`eqrec.design.classes.blocks.class_work`; the exponent from one class's LPs alone, 0.014 s at time 100,
#: 0.047 s at 200, 0.14 s at 400), the factor fit on the whole two-mass (1, T) designs of
#: ``benchmarks/bench_horizon.py`` on this project's 2-core machine (HiGHS 1.15; maps, models and certificates
#: included), between a quiet machine (2.0 s at T = 100, 6.3 s at 200, 26 s at 400, 94 s at 600) and one shared
#: with other jobs (2.9 s, 16 s, 67 s): the estimate is meant to within a factor 2.
SECONDS_PER_RUN, SECONDS_PER_WORK, WORK_EXPONENT = 1.1e-3, 9e-7, 0.85
#: Work (``eqrec.design.classes.blocks.class_work``) above which a class's level LPs run HiGHS's primal simplex
#: without presolve (``LARGE_CLASS_OPTIONS`` of the class engine) instead of the caller's settings: on the dense
#: LPs of a deep class (hundreds of measurements) the warm-started dual simplex takes 2-3 times the iterations
#: (the two-mass plant's class at time 400: 0.63 s against 0.14 s for its 8 LPs); with HiGHS and a largest delay
#: of 1 these classes follow one chain instead (:mod:`eqrec.design.classes.chains`).  Above every class of the
#: papers' studies and of every example plant up to T = 100 (at most 6.1e4: the reactor's and the ACC's (τ̄, 100)),
#: whose bytes therefore do not change.
LARGE_CLASS_WORK = 100_000
#: The time model of a chained class (``max_delay = 1``, work above :data:`LARGE_CLASS_WORK`): its warm-started
#: level LPs, at both μ1, and its certificate take about this many seconds per state row and per step of its time
#: ``d`` (the chain's LP grows by one step per class, and a warm start needs a few dozen simplex iterations): the
#: two-mass (1, 1000) design's chained classes, 62 core-seconds for 3.9e6 row-steps.
SECONDS_PER_CHAIN_STEP = 1.6e-5


@dataclass(frozen=True)
class WorkEstimate:
    """The estimated size of a class-engine design, from the class sizes alone (nothing solved).

    Parameters
    ----------
    classes : int
        (time, available data) classes.
    lp_rows : int
        Rows of all the class LPs (``n`` LPs of ``|S| p`` rows per class).
    nonzeros : int
        Upper bound of their nonzeros (dense ``Z_S``).
    seconds : float
        Expected wall-clock seconds on ``workers`` processes of this machine.
    memory : float
        Expected peak memory in bytes (the stacked maps of every worker and the largest class).
    workers : int
        Worker processes assumed.
    more : bool, optional
        The class count stopped at :data:`MAX_COUNTED_CLASSES`: there are more (the figures are lower bounds).
    """

    classes: int
    lp_rows: int
    nonzeros: int
    seconds: float
    memory: float
    workers: int
    more: bool = False

    def summary(self) -> str:
        """One line: classes, LP rows, time and memory.

        Returns
        -------
        str
        """
        count = f"{self.classes}" if self.classes < 10 ** 12 else f"{self.classes:.3g}"
        return (f"{'more than ' if self.more else ''}{count} classes, {self.lp_rows:.3g} LP rows "
                f"({self.nonzeros:.3g} nonzeros); about {_duration(self.seconds)} and {self.memory / 2**30:.2g} GiB "
                f"on {self.workers} core{'s' * (self.workers > 1)}")

    def too_large(self, available_memory: float | None = None) -> str | None:
        """Why this design is past the documented size (:data:`MAX_ESTIMATED_SECONDS`, :data:`MAX_MEMORY_FRACTION`).

        Parameters
        ----------
        available_memory : float or None, optional
            Bytes available (default: read from the system; ``None`` there: the memory is not checked).

        Returns
        -------
        str or None
            The reason, or ``None`` when it is within the limits.
        """
        return _too_large(self.seconds, self.memory, available_memory)


def _class_sizes(max_delay: int, horizon: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(depth, |S|, terminal)`` of every class of ``{0..D}^T``, without building them past a short horizon.

    Past the first ``2D + 4`` times the window rule repeats: every depth ``d < T`` has the classes of depth
    ``T0 - 1`` of the horizon ``T0``, with the same numbers of measurements missing, and the terminal
    classes (``d = T``) those of ``T0``; the classes of depth ``< T0 - 1`` are built.
    """
    from eqrec.bounds.data_classes import classes_of_full_language

    T0 = min(horizon, 2 * max_delay + 4)
    built = classes_of_full_language(T0, max_delay).classes
    depth = np.array([c.depth for c in built], np.int64)
    size = np.array([len(c.available) for c in built], np.int64)
    if horizon == T0:
        return depth, size, depth == T0
    inner = depth < T0 - 1
    gap_mid = depth[depth == T0 - 1] - size[depth == T0 - 1]  # measurements missing at an inner depth
    gap_end = depth[depth == T0] - size[depth == T0]
    mid = np.arange(T0 - 1, horizon)
    d = np.concatenate([depth[inner], np.repeat(mid, gap_mid.size), np.full(gap_end.size, horizon)])
    s = np.concatenate([size[inner], (mid[:, None] - gap_mid[None, :]).ravel(), horizon - gap_end])
    return d, s, d == horizon


#: Estimated seconds from which a size estimate is printed (the CLI and the Python entries alike).
ESTIMATE_PRINT_SECONDS = 10.0
#: The time model of a loss-aware class set's construction (:func:`eqrec.delay_classes` with ``max_lost >= 1``,
#: whose classes hold their data as tuples): seconds per class and per entry of its data (measured 2026-11-29:
#: (1, 8000), 16,000 classes and 1.3e8 entries, in 3.3 to 7 s on the shared 2-core machine) and bytes per class
#: and per entry (585 MB at (1, 8000), its weights' big integers included).
SECONDS_PER_CLASS, SECONDS_PER_ENTRY, BYTES_PER_CLASS, BYTES_PER_ENTRY = 2e-5, 5e-8, 400.0, 9.0
#: The same without losses, linear in the classes (:class:`eqrec.bounds.data_classes.WindowData`: a class holds
#: ``O(τ̄)`` whatever ``T``, its weight expanded only when read): seconds and bytes per class (measured
#: 2026-11-29 on the shared 2-core machine at a load of 6: 16 µs and 630 bytes a class at (2, 100000),
#: 400,000 classes in 6.3 s; 15 µs at (4, 100000); ``benchmarks/bench_classes.py --only e``).
SECONDS_PER_WINDOW_CLASS, BYTES_PER_WINDOW_CLASS = 2e-5, 700.0
#: Depths :func:`class_shape` reads one by one; a longer horizon is sampled (an estimate within a few per cent).
SHAPE_DEPTHS = 20_000
#: Classes past which the closed-form count stops (the estimate then says "more than"; refused whatever the plant).
MAX_COUNTED_CLASSES = 1e15


@dataclass(frozen=True)
class ClassShape:
    """The classes of a full (loss-aware) delay language, grouped by (depth, size): ``count`` classes of depth
    ``depth`` with ``size`` measurements available, from the window rule's closed form (nothing built).

    Parameters
    ----------
    depth, size : numpy.ndarray
        Depth ``d`` and ``|S|`` of each group.
    terminal : numpy.ndarray
        Whether the group's classes are terminal (``d = T``).
    count : numpy.ndarray
        Classes in the group (float: the count of a large loss-aware language exceeds 64-bit integers).
    truncated : bool
        The count stopped at :data:`MAX_COUNTED_CLASSES` (more classes exist).
    windows : bool
        The classes are built as window classes (no loss: their data are views,
        :class:`eqrec.bounds.data_classes.WindowData`, and their weights expanded when read), in time and
        memory linear in the classes; else each holds its data and weight (the loss-aware language).
    """

    depth: np.ndarray
    size: np.ndarray
    terminal: np.ndarray
    count: np.ndarray
    truncated: bool = False
    windows: bool = False

    @property
    def classes(self) -> float:
        """The number of classes (a float; at least it when ``truncated``)."""
        return float(self.count.sum())

    @property
    def entries(self) -> float:
        """The data entries of every class together, ``Σ |S|`` (the class set's size in memory)."""
        return float((self.count * self.size).sum())

    def build_cost(self, horizon: int, max_delay: int) -> tuple[float, float]:
        """Seconds and bytes to build the class set: :data:`SECONDS_PER_WINDOW_CLASS` and
        :data:`BYTES_PER_WINDOW_CLASS` a class without losses (linear in ``T``), else :data:`SECONDS_PER_CLASS`
        and the others (per class and per entry of its data).

        Parameters
        ----------
        horizon : int
            ``T`` (the weights' big integers add about ``T log2(τ̄+2) / 8`` bytes a class).
        max_delay : int
            ``τ̄``.

        Returns
        -------
        seconds : float
            Expected seconds.
        memory : float
            Expected peak bytes.
        """
        if self.windows:
            return self.classes * SECONDS_PER_WINDOW_CLASS, 2e8 + self.classes * BYTES_PER_WINDOW_CLASS
        weight_bytes = horizon * np.log2(max_delay + 2) / 8
        return (self.classes * SECONDS_PER_CLASS + self.entries * SECONDS_PER_ENTRY,
                2e8 + self.classes * (BYTES_PER_CLASS + weight_bytes) + self.entries * BYTES_PER_ENTRY)


def class_shape(max_delay: int, horizon: int, max_lost: int | None = None) -> ClassShape:
    r"""The classes of ``{0..τ̄}^T`` (with ``max_lost``: the loss-aware language) by depth and size, in closed form.

    At depth ``d`` the window holds :math:`w = \min(ar	au, d)` times and the old times are the other
    :math:`o = d - w`; a class is a subset of the window (``r`` of them available) and, with losses, ``j <= m``
    old times lost (:func:`eqrec.bounds.data_classes.classes_of_full_language`): :math:`inom{w}{r}inom{o}{j}`
    classes with :math:`|S| = o - j + r`.  Linear in ``T`` (times ``m``, stopping at
    :data:`MAX_COUNTED_CLASSES`), nothing enumerated; past :data:`SHAPE_DEPTHS` depths every
    ``ceil(T / SHAPE_DEPTHS)``-th depth stands for its neighbours (an estimate, exact up to there).

    Parameters
    ----------
    max_delay, horizon : int
        ``τ̄`` and ``T``.
    max_lost : int or None, optional
        ``m`` (``None``: no loss).

    Returns
    -------
    ClassShape
    """
    from math import comb

    D, T = int(max_delay), int(horizon)
    # every depth up to SHAPE_DEPTHS of them; past that a sample, each sampled depth standing for `stride` depths
    # (the sizes change by one per depth: an estimate, as the time model is), the last depth T exactly
    stride = max(1, -(-(T - 1) // SHAPE_DEPTHS))
    d = np.append(np.arange(1, T, stride, dtype=np.int64), T)
    per = np.append(np.full(d.size - 1, float(stride)), 1.0)
    if stride > 1:  # the last block of sampled depths stands for the depths left before T
        per[-2] = float(T - 1 - stride * (d.size - 2))
    w = np.minimum(D, d)
    o = d - w
    window_ways = np.array([[float(comb(x, r)) for x in range(D + 1)] for r in range(D + 1)])
    depth, size, count = [], [], []
    for r in range(D + 1):  # window subsets of r times
        ok = r <= w
        depth.append(d[ok]), size.append(o[ok] + r), count.append(window_ways[r][w[ok]] * per[ok])
    truncated = False
    if max_lost:  # j >= 1 old times lost: C(o, j) more of each window subset, each with j fewer data
        log_choose = _log_comb
        total = float(sum(c.sum() for c in count))
        for j in range(1, int(max_lost) + 1):
            ok = o >= j
            if not ok.any():
                break
            old_ways = np.exp(log_choose(o[ok], j)) * per[ok]
            for r in range(D + 1):
                sel = r <= w[ok]
                ways = window_ways[r][w[ok][sel]] * old_ways[sel]
                depth.append(d[ok][sel]), size.append(o[ok][sel] - j + r), count.append(ways)
                total += float(ways.sum())
            if total > MAX_COUNTED_CLASSES:
                truncated = j < int(max_lost) and bool((o > j).any())
                break
    depth_a, size_a, count_a = np.concatenate(depth), np.concatenate(size), np.concatenate(count)
    return ClassShape(depth_a, size_a, depth_a == T, count_a, truncated, windows=not max_lost)


def _log_comb(n: np.ndarray, j: int) -> np.ndarray:
    """``log C(n, j)`` for an array ``n >= j`` (floats: the counts of large loss-aware languages)."""
    from scipy.special import gammaln

    n = np.asarray(n, float)
    return gammaln(n + 1) - gammaln(j + 1) - gammaln(n - j + 1)


#: The longest horizon whose classes :func:`estimate_delay_design` lists one by one (:func:`_class_sizes`: an array
#: entry per class, about ``T`` times the classes of one depth); past it the closed form of :func:`class_shape`
#: (counted up to :data:`MAX_COUNTED_CLASSES`), which answers at once (at ``T = 10^9`` the list took minutes and
#: gigabytes before any estimate).
MAX_LISTED_HORIZON = 100_000


def estimate_delay_design(system: AffineSystem, max_delay: int, horizon: int, *, max_lost: int | None = None,
                          mu1_free: bool = False, workers: int = 1) -> WorkEstimate:
    """Estimate the size, time and memory of the class-engine design of ``{0..max_delay}^horizon``.

    From the class sizes alone (:func:`class_shape`: the window rule's closed form, also with ``max_lost``),
    in the time model of :data:`SECONDS_PER_RUN`, :data:`SECONDS_PER_WORK` and :data:`WORK_EXPONENT` (with a
    largest delay of 1, :data:`SECONDS_PER_CHAIN_STEP` for the classes above :data:`LARGE_CLASS_WORK`, which
    follow one chain) plus the construction of the classes (:meth:`ClassShape.build_cost`); the memory is the
    stacked maps of the horizon (``(T+1) n`` state and ``T p`` output rows over ``T (nw + nv) + n`` uncertain
    coordinates) held by every worker, plus the largest class and the class set.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    max_delay : int
        Largest delay ``D``.
    horizon : int
        Horizon ``T``.
    max_lost : int or None, optional
        At most this many measurements lost per block (``None``: none).
    mu1_free : bool, optional
        A μ1-free design (level LPs at two μ1 and the Charnes–Cooper LPs of the terminal classes).
    workers : int, optional
        Worker processes.

    Returns
    -------
    WorkEstimate
        The estimate.
    """
    if max_lost is None and int(horizon) <= MAX_LISTED_HORIZON:
        depth, size, terminal = _class_sizes(int(max_delay), int(horizon))
        shape = ClassShape(depth, size, terminal, np.ones(depth.size))
    else:
        shape = class_shape(max_delay, horizon, max_lost)
    return estimate_class_work(system, shape, int(horizon), int(max_delay), mu1_free=mu1_free, workers=workers)


def estimate_classes(system: AffineSystem, classes: ClassSet, *, mu1_free: bool = False,
                     workers: int = 1) -> WorkEstimate:
    """:func:`estimate_delay_design` for a class set at hand (the Python entries' size check): the same model.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    classes : ClassSet
        The classes to design for.
    mu1_free : bool, optional
        A μ1-free design.
    workers : int, optional
        Worker processes.

    Returns
    -------
    WorkEstimate
        The estimate (the class set already built: no construction time).
    """
    depth = np.array([c.depth for c in classes.classes], np.int64)
    size = np.array([len(c.available) for c in classes.classes], np.int64)
    shape = ClassShape(depth, size, np.array([c.terminal for c in classes.classes], bool), np.ones(depth.size))
    # the largest delay the model needs is whether it is 1 (the large classes then follow one chain): the widest
    # gap between a class's time and a measurement it misses, over the deepest classes
    gap = max((c.depth - min(set(range(c.depth)).difference(c.available), default=c.depth)
               for c in classes.classes[-64:]), default=0)
    return estimate_class_work(system, shape, int(classes.horizon), 1 if gap == 1 else 2, mu1_free=mu1_free,
                               workers=workers, built=True)


def estimate_class_work(system: AffineSystem, shape: ClassShape, horizon: int, max_delay: int, *,
                        mu1_free: bool = False, workers: int = 1, built: bool = False) -> WorkEstimate:
    """The one time and memory model of a class-engine design (:func:`estimate_delay_design`), from its classes'
    depths and sizes.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    shape : ClassShape
        The classes by depth and size.
    horizon, max_delay : int
        ``T`` and ``τ̄`` (with ``τ̄ = 1`` the large classes follow one chain).
    mu1_free : bool, optional
        A μ1-free design.
    workers : int, optional
        Worker processes.
    built : bool, optional
        The class set exists already (no construction time or memory added).

    Returns
    -------
    WorkEstimate
    """
    n, p, nw, nv = system.n, system.p, system.nw, system.nv
    depth, size, terminal, count = shape.depth, shape.size, shape.terminal, shape.count
    m = size.astype(float) * p
    cols = depth * nw + size * nv + n
    work = np.maximum(1.0, m * cols)
    runs = 2 if mu1_free else 1
    per_class = n * (runs * SECONDS_PER_RUN + runs / 2 * SECONDS_PER_WORK * work ** WORK_EXPONENT)
    if int(max_delay) == 1:  # the large classes follow one chain (HiGHS, the default solver)
        chained = work > LARGE_CLASS_WORK
        per_class = np.where(chained, n * SECONDS_PER_CHAIN_STEP * depth, per_class)
    if mu1_free:  # the Charnes-Cooper LPs of the terminal classes, about one level LP each
        per_class = per_class + terminal * n * (SECONDS_PER_RUN + SECONDS_PER_WORK / 2 * work ** WORK_EXPONENT)
    cores = max(1, min(int(workers), os.cpu_count() or 1))
    build_seconds, build_bytes = (0.0, 0.0) if built else shape.build_cost(horizon, max_delay)
    seconds = 1.0 + float((per_class * count).sum()) / cores + build_seconds
    coords = horizon * (nw + nv) + n
    stacked = 8.0 * coords * ((horizon + 1) * n + horizon * p)
    largest = 8.0 * 3 * float(m.max(initial=0)) * coords
    memory = 2e8 + (cores + 1) * (stacked + largest) + build_bytes  # every worker and this process; the classes
    return WorkEstimate(classes=_count(shape.classes), lp_rows=_count(n * (m * count).sum()),
                        nonzeros=_count(n * (m * cols * count).sum()), seconds=seconds, memory=memory,
                        workers=cores, more=shape.truncated)


def _count(value: float) -> int:
    """A count of the estimate as an int (a float past 64 bits stays exact enough: an estimate)."""
    return int(value) if np.isfinite(value) else 2 ** 1023


_SIZE_CHECKED: "contextvars.ContextVar[bool]" = contextvars.ContextVar("eqrec_size_checked", default=False)


@contextlib.contextmanager
def size_check_done():
    """Within it, the Python entries skip their size check: the caller (``eqrec design``) made it already.

    Yields
    ------
    None
    """
    token = _SIZE_CHECKED.set(True)
    try:
        yield
    finally:
        _SIZE_CHECKED.reset(token)


def size_checked() -> bool:
    """Whether the size check was made already (inside :func:`size_check_done`).

    Returns
    -------
    bool
    """
    return _SIZE_CHECKED.get()


def report_size(estimate: "WorkEstimate | SetEstimate", *, force: bool, field: str, source: str | None = None,
                advice: str = "") -> None:
    """Print a long job's estimate (to stderr); refuse one past the documented size unless ``force``.

    The one answer of the CLI and the Python entries: the estimate is printed when it is
    :data:`ESTIMATE_PRINT_SECONDS` or more, or past the limits (:data:`MAX_ESTIMATED_SECONDS`,
    :data:`MAX_MEMORY_FRACTION` of the available memory); past them an :class:`InputError` naming ``field``
    unless ``force``.

    Parameters
    ----------
    estimate : WorkEstimate or SetEstimate
        The estimate (``summary()``, ``too_large()``, ``seconds``).
    force : bool
        Run past the limits anyway (the estimate is still printed).
    field : str
        The input to name in the refusal (e.g. ``"horizon"``, ``"--horizon"``).
    source : str or None, optional
        ``"command line"`` or ``None``.
    advice : str, optional
        What to do instead (appended to the refusal).

    Raises
    ------
    InputError
        Past the limits without ``force`` (nothing started).
    """
    import sys

    check_flags(force=force)  # a string such as "no" would read as true, and run past the limits
    if size_checked():
        return
    reason = estimate.too_large()
    if estimate.seconds >= ESTIMATE_PRINT_SECONDS or reason is not None:
        print(f"eqrec: estimate: {estimate.summary()}", file=sys.stderr)
    if reason is not None and not force:
        how = "--force" if source == "command line" else "force=True"
        raise InputError(f"refused: {reason} ({estimate.summary()}); {advice + ', or ' if advice else ''}pass {how} "
                         "to run it anyway", source, field)


@dataclass(frozen=True)
class SetEstimate:
    """The estimated time and memory of a job that is not a design (a class set, a language, a comparison run).

    Parameters
    ----------
    what : str
        What it is (one line).
    seconds : float
        Expected wall-clock seconds.
    memory : float
        Expected peak memory in bytes.
    """

    what: str
    seconds: float
    memory: float

    def summary(self) -> str:
        """One line: what, time and memory.

        Returns
        -------
        str
        """
        return f"{self.what}; about {_duration(self.seconds)} and {self.memory / 2**30:.2g} GiB"

    def too_large(self, available_memory: float | None = None) -> str | None:
        """Why this job is past the documented size (as :meth:`WorkEstimate.too_large`).

        Parameters
        ----------
        available_memory : float or None, optional
            Bytes available (default: read from the system).

        Returns
        -------
        str or None
        """
        return _too_large(self.seconds, self.memory, available_memory)


def _duration(t: float) -> str:
    if not np.isfinite(t):
        return "forever"
    return f"{t:.0f} s" if t < 120 else f"{t / 60:.0f} min" if t < 7200 else f"{t / 3600:.3g} h" if t < 3.6e7 \
        else f"{t / 3.156e7:.3g} years"


def _too_large(seconds: float, memory: float, available_memory: float | None) -> str | None:
    mem = _memory_available() if available_memory is None else available_memory
    if mem is not None and memory > MAX_MEMORY_FRACTION * mem:
        return f"it needs about {memory / 2**30:.3g} GiB, more than {MAX_MEMORY_FRACTION:.0%} of the " \
               f"{mem / 2**30:.3g} GiB available"
    if seconds > MAX_ESTIMATED_SECONDS:
        return f"it would take about {_duration(seconds)}, more than {MAX_ESTIMATED_SECONDS / 60:.0f} min"
    return None


#: Growth ``ρ^T`` of the error maps over the horizon (``ρ`` the spectral radius of ``A``) from which a failed
#: design is blamed on the horizon (a marginally stable plant, ``ρ = 1`` up to rounding, is not blamed).
UNSTABLE_GROWTH = 1e3
#: The spread of entries a double-precision LP resolves: horizons up to ``log(RESOLVED_GROWTH) / log ρ``.
RESOLVED_GROWTH = 1e8


def growth_hint(system: AffineSystem, horizon: int, *, suspect: bool = False) -> str:
    """Why a design of an unstable plant over a long horizon fails, and the horizon that usually solves.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    horizon : int
        The horizon ``T`` that failed.
    suspect : bool, optional
        For a design found infeasible: only past :data:`RESOLVED_GROWTH`, where the verdict may be the
        solver's (a longer horizon never makes a design harder for the plant: more data), and said so.

    Returns
    -------
    str
        Empty when ``ρ^T`` is below :data:`UNSTABLE_GROWTH` (``suspect``: :data:`RESOLVED_GROWTH`; ``ρ`` the
        spectral radius of ``A``, time-varying: of its first matrix); else the reason and
        ``log(RESOLVED_GROWTH) / log ρ``.
    """
    try:
        rho = float(np.max(np.abs(np.linalg.eigvals(np.asarray(system.A_at(0), float)))))
    except (np.linalg.LinAlgError, ValueError):
        return ""
    with np.errstate(over="ignore"):
        growth = rho ** int(horizon)
    if not growth > (RESOLVED_GROWTH if suspect else UNSTABLE_GROWTH):
        return ""
    usual = max(1, int(np.log(RESOLVED_GROWTH) / np.log(rho)))
    verdict = "this verdict may be the solver's, not the plant's: " if suspect else ""
    return (f"{verdict}the horizon {horizon} is too long for so unstable a plant: A has spectral radius {rho:.4g}, "
            "so the "
            f"error maps grow like {rho:.4g}^T = {growth:.3g}, past what a double-precision LP resolves; horizons up "
            f"to about {usual} usually solve (eqrec design --horizon searches for the longest; from Python "
            f"eqrec.longest_horizon(system, max_delay, {horizon}))")
