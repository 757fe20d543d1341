r"""Words to arrival patterns: the one parser of missing-data and delay words, languages, worst cases.

A **missing-data word** ``q(0) ... q(T-1)`` over ``{0, 1}`` (eq. (3) of the
prefix-based paper) and a **delay word** ``τ(0) ... τ(T-1)`` of digits
(eq. (1) of the delayed-data paper) both become an
:class:`~eqrec.arrivals.patterns.ArrivalPattern`.  Every reader of a word in
the package goes through :func:`validate_word` (0/1 words) or
:func:`parse_delays` / :func:`parse_delay_word` (delay words).  A
language is reduced to its distinct event sequences (``L^{E'}``,
:func:`as_language`); :func:`worst_case_pattern` is the bitwise AND of
Section III of the prefix-based paper.

The reading of a word (one rule, the same in Python and on the command line): a string over
``{0, 1}`` is a valid missing-data word *and* a valid delay word (every packet on time or one
step late), so it is read as ``kind`` says.  Patterns (:class:`ArrivalPattern`, e.g. from
:func:`eqrec.missing_words` or :func:`eqrec.delay_words`) need no reading.  An entry that takes
both readings (:func:`as_language`, :func:`eqrec.design_delay`, :func:`eqrec.design_delay_global`)
has no default: a list of 0/1 strings without ``kind`` is refused naming the two readings, and a
word with a digit ``2-9`` makes the list a delay language.  Entries that only take missing-data
words (:func:`validate_language`, :func:`eqrec.design_prefix`, :func:`eqrec.design_time_based`,
:func:`eqrec.design_augmented`, ``eqrec design --words``) read 0/1 strings as missing data;
``eqrec design --delays`` reads delay words.
"""

from __future__ import annotations

import itertools
from typing import Iterable, Sequence

from eqrec.checks import integer, short_label
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.errors import InputError

MISSING_ALPHABET = frozenset("01")
KINDS = ("missing", "delay")
#: Largest delay ``τ̄`` of a delay language: one digit per delay in a word.  The one limit of every entry that
#: takes a maximum delay (:func:`full_delay_language`, :func:`eqrec.delay_classes`, ``eqrec design --max-delay``).
MAX_DELAY = 9


def validate_word(word: str, *, field_name: str = "word", source: str | None = None) -> str:
    """Return ``word`` if it is a non-empty string over {0, 1}, else raise :class:`InputError`.

    Parameters
    ----------
    word : str
        A missing-data word ``q(0) ... q(T-1)`` (eq. (3) of the prefix-based
        paper; ``1`` available, ``0`` missing).
    field_name : str, optional
        Field named in the error message.
    source : str or None, optional
        File (or other origin) named in the error message.

    Returns
    -------
    str
        The word, surrounding whitespace stripped.
    """
    if not isinstance(word, str):
        raise InputError(f"a word must be a string of 0 and 1, got {short_label(repr(word))}", source, field_name)
    word = word.strip()
    if not word:
        raise InputError("empty word", source, field_name)
    bad = set(word) - MISSING_ALPHABET
    if bad:
        raise InputError(f"word {short_label(repr(word))} has letters {sorted(bad)} outside the alphabet {{0, 1}}",
                         source, field_name)
    return word


def parse_delays(word: str, max_delay: int | None = None, *, field_name: str = "delays",
                 source: str | None = None) -> tuple[int, ...]:
    """The delays ``τ(0), ..., τ(T-1)`` of a delay word (eq. (1) of the delayed-data paper): the one digit reader.

    :func:`parse_delay_word` makes the word's arrival pattern from them; the
    long runs of :mod:`eqrec.simulate.long_runs` deliver packets by these raw
    delays (a delay past the period's end reaches the next period).

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
    tuple of int
        One delay per letter.

    Raises
    ------
    InputError
        For a non-string or empty word, a non-digit letter, a delay above
        ``max_delay``, or a ``max_delay`` that is not an integer >= 0 (field ``max_delay``).
    """
    if not isinstance(word, str):
        raise InputError(f"a delay word must be a string of digits, got {short_label(repr(word))}", source, field_name)
    word = word.strip()
    if not word:
        raise InputError("empty delay word", source, field_name)
    bad = sorted({c for c in word if not c.isdigit() or not c.isascii()})
    if bad:
        raise InputError(f"delay word {short_label(repr(word))} has letters {bad} that are not digits 0-9", source, field_name)
    delays = tuple(int(c) for c in word)
    if max_delay is not None:
        integer(max_delay, "max_delay", source=source)
        over = [d for d in delays if d > max_delay]
        if over:
            raise InputError(f"delay word {short_label(repr(word))} has delays {sorted(set(over))} above the maximum delay "
                             f"{max_delay}", source, field_name)
    return delays


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
        Digits ``0-9``, one delay per measurement time, read by :func:`parse_delays`.
    max_delay, field_name, source : int or None, str, str or None
        The largest allowed delay ``τ̄`` (``None``: no limit), and the field
        and file named in an error (as :func:`parse_delays`).

    Returns
    -------
    ArrivalPattern
        The word's arrival pattern, labelled with ``word`` (stripped).

    Raises
    ------
    InputError
        The errors of :func:`parse_delays`.

    Examples
    --------
    >>> import eqrec
    >>> pattern = eqrec.parse_delay_word("0120")
    >>> pattern
    ArrivalPattern('0120', arrivals=(0, 2, None, 3))
    >>> pattern.events()
    ('1', '10', '110', '1101')
    """
    return ArrivalPattern.from_delays(parse_delays(word, max_delay, field_name=field_name, source=source))


def as_pattern(word: "ArrivalPattern | str", *, kind: str = "missing", max_delay: int | None = None,
               field_name: str = "word", source: str | None = None) -> ArrivalPattern:
    """A pattern from a pattern or a word of the given ``kind`` (``"missing"`` or ``"delay"``).

    Parameters
    ----------
    word : ArrivalPattern or str
        A pattern (returned as is) or a word of ``kind``.
    kind : {"missing", "delay"}, optional
        A 0/1 missing-data word (:func:`validate_word`) or a delay word
        (:func:`parse_delay_word`).
    max_delay : int or None, optional
        Largest allowed delay of a delay word (``None``: no limit).
    field_name : str, optional
        Field named in error messages.
    source : str or None, optional
        File (or other origin) named in error messages.

    Returns
    -------
    ArrivalPattern
        The word's arrival pattern.
    """
    if isinstance(word, ArrivalPattern):
        return word
    if kind == "missing":
        return ArrivalPattern.from_missing_word(validate_word(word, field_name=field_name, source=source))
    if kind == "delay":
        return parse_delay_word(word, max_delay, field_name=field_name, source=source)
    raise InputError(f"unknown word kind {kind!r}; choose one of {list(KINDS)}", source, "kind")


def _reading(words: list, kind: str | None, field_name: str, source: str | None) -> str:
    """``kind``, or for ``None`` the one reading the strings of ``words`` allow (the module's rule)."""
    if kind is not None:
        if kind not in KINDS:
            raise InputError(f"unknown word kind {kind!r}; choose one of {list(KINDS)}", source, "kind")
        return kind
    strings = [w.strip() for w in words if isinstance(w, str)]
    if not strings or any(set(w) - MISSING_ALPHABET for w in strings):
        return "delay"  # patterns only (nothing to read), or a letter beyond 0/1: not a missing-data word
    shown = [short_label(w) for w in strings[:4]] + ([] if len(strings) <= 4 else ["..."])
    raise InputError(f"the words {shown} are made of 0 and 1 only, so they read two ways: as missing-data words "
                     "(1 = the measurement arrives, 0 = it is lost) or as delay words (each measurement on time "
                     "or one step late); say which with kind='missing' or kind='delay' (or give "
                     "eqrec.missing_words([...]) or eqrec.delay_words([...]))", source, field_name)


def as_language(words: Iterable["ArrivalPattern | str"], *, kind: str | None = None, max_delay: int | None = None,
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
    kind : {"missing", "delay"} or None, optional
        How to read string words: 0/1 missing-data words (eq. (3) of the
        prefix-based paper) or delay words (:func:`parse_delay_word`).
        ``None`` (default): delay words if a word has a digit ``2-9``, and
        an :class:`InputError` naming both readings if every word is made of
        ``0`` and ``1`` (module docstring).
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
        ``fixed_length``, a length other than ``length``, an unknown
        ``kind``, or 0/1 words without ``kind``.

    Examples
    --------
    >>> import eqrec
    >>> eqrec.as_language(["0120", "0130", "0000"], kind="delay")
    (ArrivalPattern('0120', arrivals=(0, 2, None, 3)), ArrivalPattern('0000', arrivals=(0, 1, 2, 3)))
    >>> eqrec.as_language(["0120", "0130", "0000"])  # a digit 2-9: delay words
    (ArrivalPattern('0120', arrivals=(0, 2, None, 3)), ArrivalPattern('0000', arrivals=(0, 1, 2, 3)))
    >>> eqrec.as_language(["0111", "1011"], kind="missing")
    (ArrivalPattern('0111', arrivals=(None, 1, 2, 3)), ArrivalPattern('1011', arrivals=(0, None, 2, 3)))
    """
    if isinstance(words, (str, ArrivalPattern)):
        words = [words]
    if isinstance(words, dict):  # its keys would be read silently
        raise InputError("a language is a list of words or patterns, got a dict", source, field_name)
    try:
        words = list(words)
    except TypeError:
        raise InputError(f"a language is a list of words or patterns, got {type(words).__name__}",
                         source, field_name) from None
    kind = _reading(words, kind, field_name, source)
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
                         f"{short_label([p.label for p in pats])}", source, field_name)
    if length is not None:
        wrong = [p.label for p in pats if p.T != length]
        if wrong:
            raise InputError(f"words {short_label(wrong)} do not have the required length {length}", source, field_name)
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
    fixed_length, length, field_name, source : bool, int or None, str, str or None
        As in :func:`as_language` (equal lengths required by default; the
        field and file are named in error messages).

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
    return tuple(p.label for p in as_language(words, kind="missing", fixed_length=fixed_length, length=length,
                                              field_name=field_name, source=source))


#: The most words a language is listed with (:func:`full_delay_language`, :func:`eqrec.missing_words_at_most`):
#: about a minute and a gigabyte of strings; larger languages are designed from their classes
#: (:func:`eqrec.delay_classes`), never listed.
MAX_LISTED_WORDS = 10**6


def check_listed_words(words: int, what: str, field: str) -> None:
    """Refuse to list a language of more than :data:`MAX_LISTED_WORDS` words, at once (nothing built).

    Parameters
    ----------
    words : int
        The number of words the call would list.
    what : str
        The language, in words (for the message).
    field : str
        The input named by the refusal.

    Raises
    ------
    InputError
        ``words`` above :data:`MAX_LISTED_WORDS` (field ``field``).
    """
    if words > MAX_LISTED_WORDS:
        raise InputError(f"refused: {what} has {float(words):.3g} words, more than the {MAX_LISTED_WORDS:.0e} "
                         "that are listed; eqrec.delay_classes(max_delay=..., horizon=..., max_lost=...) gives the "
                         "classes of such a language without listing a word", field=field)


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
        Largest delay ``τ̄``, ``0..9`` (:data:`MAX_DELAY`: one digit per delay).

    Returns
    -------
    tuple of str
        The ``(max_delay + 1) ** T`` words.

    Raises
    ------
    InputError
        If ``T`` is not an integer >= 1 or ``max_delay`` not one in ``0..9`` (the field is named), or the
        language has more than :data:`MAX_LISTED_WORDS` words (field ``T``).

    Examples
    --------
    >>> import eqrec
    >>> eqrec.full_delay_language(2, 2)
    ('00', '01', '02', '10', '11', '12', '20', '21', '22')
    >>> len(eqrec.as_language(eqrec.full_delay_language(2, 2), kind="delay"))
    6
    """
    T, max_delay = integer(T, "T", low=1), integer(max_delay, "max_delay", high=MAX_DELAY)
    check_listed_words((max_delay + 1) ** T, f"{{0..{max_delay}}}^{T}", "T")
    # lexicographic (the first delay varies slowest); itertools, not numpy.indices: numpy arrays have at most 64
    # dimensions, and {0}^80 (one word) raised a raw ValueError
    return tuple(map("".join, itertools.product("0123456789"[:max_delay + 1], repeat=T)))


# ---------------------------------------------------------------------------
# Worst case and helpers on words
# ---------------------------------------------------------------------------

def worst_case_pattern(patterns: Iterable["ArrivalPattern | str"]) -> ArrivalPattern:
    """Latest arrival of every measurement over a fixed-length language.

    For missing-data words this is the bitwise AND of Section III of the
    prefix-based paper: a measurement is kept only if every word has it, so
    an estimator that works for the worst case works for every word.

    Parameters
    ----------
    patterns : iterable of ArrivalPattern or str
        A fixed-length language (0/1 words or patterns).

    Returns
    -------
    ArrivalPattern
        The worst-case pattern (a measurement missing in some word is missing).
    """
    pats = as_language(patterns, kind="missing")
    arr = []
    for tau in range(pats[0].T):
        a = [p.arrivals[tau] for p in pats]
        arr.append(None if any(x is None for x in a) else max(a))
    return ArrivalPattern(tuple(arr))


def worst_case_word(words: Sequence[str]) -> str:
    """Bitwise AND of a fixed-length missing-data language (Section III of the prefix-based paper).

    Parameters
    ----------
    words : sequence of str
        0/1 words of one length.

    Returns
    -------
    str
        The worst-case word ``λ*``.
    """
    return worst_case_pattern(words).label


def prefixes(word: str) -> list[str]:
    """All non-empty prefixes ``Pref(word)`` of a string, shortest first.

    Parameters
    ----------
    word : str
        Any word.

    Returns
    -------
    list of str
        ``word[:1], word[:2], ..., word``.
    """
    return [word[: i + 1] for i in range(len(word))]


def extend_word(word: str, length: int) -> str:
    """Pad a 0/1 word with ``1`` (measurements available) up to ``length`` (Section V of P1).

    Parameters
    ----------
    word : str
        A 0/1 word.
    length : int
        Target length, at least ``len(word)``.

    Returns
    -------
    str
        The padded word.
    """
    if length < len(word):
        raise InputError(f"cannot shorten word {word!r} to length {length}")
    return word + "1" * (length - len(word))


