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

import numbers
from typing import Any, Iterable

import numpy as np

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
