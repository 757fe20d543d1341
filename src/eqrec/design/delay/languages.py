"""The languages of the delayed-data design: delay words, their reduced event language, the full language's classes.

Re-exported by :mod:`eqrec.design.delay.design` (:func:`delay_language`, :func:`delay_classes`), which designs on them.
"""

from __future__ import annotations

from eqrec.checks import integer
from eqrec.bounds.data_classes import ClassSet, classes_of_full_language
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_language, full_delay_language
from eqrec.design.inputs import language_classes, language_tree
from eqrec.errors import InputError


def delay_language(words=None, *, max_delay: int | None = None, horizon: int | None = None,
                   source: str | None = None) -> tuple[ArrivalPattern, ...]:
    """The reduced event language ``L^{E'}`` of delay words, or of the full language ``{0..τ̄}^T``.

    Parameters
    ----------
    words : sequence of str or ArrivalPattern, optional
        Delay words (digit strings; a delay reaching past the horizon means missing) or patterns.
    max_delay, horizon : int or None, optional
        ``τ̄`` and ``T``: without ``words`` the full language (all ``(τ̄+1)^T`` words), else limits checked.
    source : str or None, optional

    Returns
    -------
    tuple of ArrivalPattern
        The distinct event sequences (equal ones merged, the first word kept as label).
    """
    if words is None:
        if max_delay is None or horizon is None:
            raise InputError("give delay words, or both the maximum delay and the horizon", source, "delays")
        words = full_delay_language(horizon, max_delay)
    return as_language(words, kind="delay", max_delay=max_delay, length=horizon, source=source)


def delay_classes(*, max_delay: int, horizon: int) -> ClassSet:
    """The classes of the full language ``{0..τ̄}^T`` from the window rule (no word enumerated).

    Parameters
    ----------
    max_delay, horizon : int
        The largest delay ``τ̄`` and the horizon ``T``.

    Returns
    -------
    ClassSet
        The (time, available data) classes, for :func:`design_delay` and :func:`design_delay_global`.

    Raises
    ------
    InputError
        ``horizon`` not an integer >= 1 or ``max_delay`` not one >= 0 (the field is named).

    Examples
    --------
    >>> import eqrec
    >>> classes = eqrec.delay_classes(max_delay=4, horizon=30)
    >>> len(classes), classes.words
    (446, 931322574615478515625)
    """
    return classes_of_full_language(integer(horizon, "horizon", low=1), integer(max_delay, "max_delay"))


def _tree(patterns, kind: str | None = None) -> PrefixTree:
    """The prefix tree of a fixed-length language of delay (or, with ``kind``, missing-data) words or patterns."""
    return language_tree(patterns, kind=kind, field_name="patterns")


def _classes(patterns, kind: str | None = None) -> ClassSet:
    """Classes of a fixed-length language given as words, patterns, a tree or already as classes."""
    return language_classes(patterns, kind=kind, field_name="patterns")


