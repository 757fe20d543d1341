"""The languages of the delayed-data design: delay words, their reduced event language, the full language's classes.

Re-exported by :mod:`eqrec.design.delay.design` (:func:`delay_language`, :func:`delay_classes`), which designs on them.
"""

from __future__ import annotations


from eqrec.checks import integer
from eqrec.bounds.data_classes import ClassSet, classes_of_full_language
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import MAX_DELAY, as_language, full_delay_language
from eqrec.bounds.data_classes import full_language_counts
from eqrec.design.inputs import SetEstimate, class_shape, language_classes, language_tree, report_size
from eqrec.errors import InputError


#: The time model of an enumerated language (:func:`delay_language`): seconds and bytes per word (measured
#: 2026-11-29: 85 to 120 µs a word for {0..2}^9, {0..1}^14, {0..3}^7; about 2 kB a pattern kept).
SECONDS_PER_WORD, BYTES_PER_WORD = 1.5e-4, 2000.0

#: The letter of a lost measurement in the words of a loss-aware language (:func:`delay_loss_words`).
LOST = "x"


def delay_loss_words(horizon: int, max_delay: int, max_lost: int) -> tuple[ArrivalPattern, ...]:
    r"""Every word of the loss-aware language: delays ``0..τ̄`` or lost (``x``), at most ``max_lost`` lost.

    The words (not reduced) in lexicographic order over ``0 < 1 < ... < τ̄ < x``, each as the pattern it
    gives, labelled by the word: a lost measurement never arrives; a delay reaching past the horizon is
    missing in the block without being a loss (:func:`eqrec.bounds.data_classes.classes_of_full_language`).
    There are :math:`\sum_{j \le m} \binom{T}{j}(\bar\tau+1)^{T-j}` of them: for small languages only
    (the class engine builds the classes without them, :func:`delay_classes`).

    Parameters
    ----------
    horizon : int
        ``T``, at least 1.
    max_delay : int
        ``τ̄``, ``0..9``.
    max_lost : int
        ``m``, ``0..T``.

    Returns
    -------
    tuple of ArrivalPattern
        One pattern per word.

    Raises
    ------
    InputError
        A value out of range (the field is named).

    Examples
    --------
    >>> from eqrec.design.delay.languages import delay_loss_words
    >>> [p.label for p in delay_loss_words(2, 1, 1)]
    ['00', '01', '0x', '10', '11', '1x', 'x0', 'x1']
    """
    T = integer(horizon, "horizon", low=1)
    D = integer(max_delay, "max_delay", high=MAX_DELAY)
    m = integer(max_lost, "max_lost", high=T)
    letters = [*range(D + 1), LOST]
    out = []

    def extend(word: list, lost: int) -> None:  # lexicographic, never past the loss budget (no 4^T scan)
        if len(word) == T:
            arrivals = tuple(None if c == LOST or i + c >= T else i + c for i, c in enumerate(word))
            out.append(ArrivalPattern(arrivals, "".join(map(str, word))))
            return
        for c in letters:
            if c != LOST or lost < m:
                word.append(c)
                extend(word, lost + (c == LOST))
                word.pop()

    extend([], 0)
    return tuple(out)


def delay_language(words=None, *, max_delay: int | None = None, horizon: int | None = None,
                   max_lost: int | None = None, source: str | None = None,
                   force: bool = False) -> tuple[ArrivalPattern, ...]:
    """The reduced event language ``L^{E'}`` of delay words, of the full language ``{0..τ̄}^T``, or of its
    loss-aware version (at most ``max_lost`` lost per block).

    Parameters
    ----------
    words : sequence of str or ArrivalPattern, optional
        Delay words (digit strings; a delay reaching past the horizon means missing) or patterns.
    max_delay, horizon : int or None, optional
        ``τ̄`` and ``T``: without ``words`` the full language (all ``(τ̄+1)^T`` words), else limits checked.
    max_lost : int or None, optional
        Without ``words``: at most this many measurements lost per block, ``0..T``
        (:func:`delay_loss_words`; ``None``: no loss).  Not with ``words``.
    source : str or None, optional
    force : bool, optional
        Enumerate a full language past the documented size anyway (:func:`eqrec.design.inputs.report_size`:
        its estimate is printed from :data:`~eqrec.design.inputs.ESTIMATE_PRINT_SECONDS` on, and it is refused
        past :data:`~eqrec.design.inputs.MAX_ESTIMATED_SECONDS` or the memory limit unless ``force``).

    Returns
    -------
    tuple of ArrivalPattern
        The distinct event sequences (equal ones merged, the first word kept as label; a lost measurement
        is the letter ``x`` of the label).

    Raises
    ------
    InputError
        Malformed words, missing limits, or ``max_lost`` with ``words`` or out of range, or a full language
        past the documented size without ``force`` (e.g. ``{0..2}^30`` with one lost: 4^30 words to enumerate;
        :func:`delay_classes` gives its classes without them) (the field is named).
    """
    if max_lost is not None:
        if words is not None:
            raise InputError("max_lost builds a language from max_delay and horizon; it does not apply to given "
                             "words (write a lost measurement as a delay past the horizon)", source, "max_lost")
        if max_delay is None or horizon is None:
            raise InputError("max_lost needs both the maximum delay and the horizon", source, "max_lost")
        _check_enumeration(horizon, max_delay, max_lost, force, source)
        return as_language(delay_loss_words(horizon, max_delay, max_lost), kind="delay", source=source)
    if words is None:
        if max_delay is None or horizon is None:
            raise InputError("give delay words, or both the maximum delay and the horizon", source, "delays")
        _check_enumeration(horizon, max_delay, None, force, source)
        words = full_delay_language(horizon, max_delay)
    return as_language(words, kind="delay", max_delay=max_delay, length=horizon, source=source)


def _check_enumeration(horizon, max_delay, max_lost, force: bool, source: str | None) -> None:
    """The size check of a full language's enumeration (:func:`delay_language`): its words, time and memory."""
    from decimal import Decimal

    T = integer(horizon, "horizon", low=1)
    D = integer(max_delay, "max_delay", high=MAX_DELAY)
    m = None if max_lost is None else integer(max_lost, "max_lost", high=T)
    words = full_language_counts(T, D, m)["words"]
    what = (f"{{0..{D}}}^{T}" + (f" with at most {m} lost" if m is not None else "")
            + f": {Decimal(words):.3g} words to enumerate")
    estimate = SetEstimate(what, float(words) * SECONDS_PER_WORD, 2e8 + float(words) * BYTES_PER_WORD)
    report_size(estimate, force=force, field="horizon", source=source,
                advice="delay_classes(max_delay=..., horizon=...) gives its classes without enumerating a word")


def delay_classes(*, max_delay: int, horizon: int, max_lost: int | None = None, force: bool = False) -> ClassSet:
    """The classes of the full language ``{0..τ̄}^T`` from the window rule (no word enumerated).

    With ``max_lost = m``: the loss-aware language, delays ``0..τ̄`` and at most ``m`` measurements lost
    per block (a lost measurement never arrives; a delay past the block's end is, as without losses, only
    "not available in this block" and not a loss), from the window rule with losses and its counting rule
    (:func:`eqrec.bounds.data_classes.classes_of_full_language`, where both are proved).  ``m = 0`` is the
    language without losses, ``m = T`` every arrival pattern.

    Parameters
    ----------
    max_delay, horizon : int
        The largest delay ``τ̄`` (``0..9``, :data:`eqrec.arrivals.words.MAX_DELAY`: one digit per delay, the
        limit of delay words and of ``eqrec design --max-delay``) and the horizon ``T``.
    max_lost : int or None, optional
        At most this many measurements lost per block, ``0..T`` (``None``, default: no loss, the full
        delay language as before).
    force : bool, optional
        Build a class set past the documented size anyway.  Its size is estimated first, in closed form
        (:func:`eqrec.design.inputs.class_shape`: ``T 2^τ̄`` classes without losses, built in time and memory
        linear in ``T``; with ``m >= 1`` lost about ``T^(m+1)`` classes holding ``Σ |S|`` data entries): printed from
        :data:`~eqrec.design.inputs.ESTIMATE_PRINT_SECONDS` on and refused past
        :data:`~eqrec.design.inputs.MAX_ESTIMATED_SECONDS` or the memory limit unless ``force``
        (:func:`eqrec.design.inputs.report_size`).

    Returns
    -------
    ClassSet
        The (time, available data) classes, for :func:`design_delay` and :func:`design_delay_global`.

    Raises
    ------
    InputError
        ``horizon`` not an integer >= 1, ``max_delay`` not one in ``0..9`` or ``max_lost`` not one in
        ``0..T``, or a class set past the documented size without ``force`` (the field is named).

    Examples
    --------
    >>> import eqrec
    >>> classes = eqrec.delay_classes(max_delay=4, horizon=30)
    >>> len(classes), classes.words
    (446, 931322574615478515625)
    >>> lossy = eqrec.delay_classes(max_delay=4, horizon=100, max_lost=1)
    >>> len(lossy)
    76062
    """
    T = integer(horizon, "horizon", low=1)
    D = integer(max_delay, "max_delay", high=MAX_DELAY)
    m = None if max_lost is None else integer(max_lost, "max_lost", high=T)
    shape = class_shape(D, T, m)
    seconds, memory = shape.build_cost(T, D)
    what = (f"the classes of {{0..{D}}}^{T}" + (f" with at most {m} lost" if m is not None else "")
            + f": {'more than ' if shape.truncated else ''}{shape.classes:.4g} classes"
            + ("" if shape.windows else f" holding {shape.entries:.3g} data entries"))
    report_size(SetEstimate(what, seconds, memory), force=force, field="horizon",
                advice="shorten the horizon or lower max_lost")
    return classes_of_full_language(T, D) if m is None else classes_of_full_language(T, D, m)


def patterns_tree(patterns, kind: str | None = None) -> PrefixTree:
    """The prefix tree of a fixed-length language of delay (or, with ``kind``, missing-data) words or patterns.

    Parameters
    ----------
    patterns : sequence of str or ArrivalPattern, or PrefixTree
        The language, as the delayed-data designs take it (argument ``patterns``).
    kind : str or None, optional
        How words are read (``"delay"`` or ``"missing"``; ``None``: as :func:`eqrec.design.inputs.language_tree`).

    Returns
    -------
    PrefixTree
        Its prefix tree; bad input raises :class:`~eqrec.errors.InputError` naming ``patterns``.
    """
    return language_tree(patterns, kind=kind, field_name="patterns")


def patterns_classes(patterns, kind: str | None = None) -> ClassSet:
    """The (time, available data) classes of a fixed-length language given as words, patterns, a tree or classes.

    Parameters
    ----------
    patterns : sequence of str or ArrivalPattern, PrefixTree or ClassSet
        The language, as the delayed-data designs take it (argument ``patterns``).
    kind : str or None, optional
        How words are read (``"delay"`` or ``"missing"``; ``None``: as
        :func:`eqrec.design.inputs.language_classes`).

    Returns
    -------
    ClassSet
        Its classes; bad input raises :class:`~eqrec.errors.InputError` naming ``patterns``.
    """
    return language_classes(patterns, kind=kind, field_name="patterns")


