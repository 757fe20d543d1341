"""Checks of inputs shared by the core modules: integers, positive numbers, float arrays, random generators.

Each returns the checked value or raises :class:`~eqrec.errors.InputError`
naming the field, so an entry point refuses a bad scalar before it changes
anything (never a raw ``TypeError`` from a comparison or ``ValueError``
from numpy).
"""

from __future__ import annotations

import numbers
from typing import Any

import numpy as np

from eqrec.errors import InputError


#: Longest label (a class ``d:0110...``, a word, a data list) quoted whole in a message; a longer one is shortened
#: to its first and last characters and its length (:func:`short_label`).
LABEL_CHARS = 40


def short_label(label: Any, limit: int = LABEL_CHARS) -> str:
    """A label for a message: whole up to ``limit`` characters, else its first and last characters and its length.

    Parameters
    ----------
    label : object
        A class label (``d:0110...``), a word, a list of times (its ``str``).
    limit : int, optional
        The longest label quoted whole.

    Returns
    -------
    str
        ``label``, or e.g. ``'1000:11111111111111111111…00000000000000000101 (1005 characters)'``.

    Examples
    --------
    >>> from eqrec.checks import short_label
    >>> short_label("3:101"), short_label("1" * 100, limit=10)
    ('3:101', '1111…1111 (100 characters)')
    """
    label = str(label)
    if len(label) <= limit:
        return label
    half = max(1, (limit - 1) // 2)
    return f"{label[:half]}…{label[-half:]} ({len(label)} characters)"


def integer(value: Any, field: str, *, low: int = 0, high: int | None = None, source: str | None = None) -> int:
    """``value`` as an ``int`` in ``low..high``, else an :class:`InputError` naming ``field``.

    Parameters
    ----------
    value : int
        The value given (a Python or numpy integer; booleans and floats are refused).
    field : str
        The field named in the error.
    low : int, optional
        Smallest allowed value (default 0).
    high : int or None, optional
        Largest allowed value (``None``: no limit).
    source : str or None, optional
        File (or other origin) named in the error.

    Returns
    -------
    int
        ``int(value)``.

    Examples
    --------
    >>> from eqrec.checks import integer
    >>> integer(3, "runs", low=1)
    3
    """
    ok = isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))
    if not ok or value < low or (high is not None and value > high):
        span = f"{low}..{high}" if high is not None else f">= {low}"
        raise InputError(f"must be an integer {span}, got {value!r}", source, field)
    return int(value)


def positive(value: Any, field: str, *, zero_ok: bool = False, source: str | None = None) -> float:
    """``value`` as a positive (or non-negative) finite ``float``, else an :class:`InputError` naming ``field``.

    Parameters
    ----------
    value : float
        The value given (a real number; strings and booleans are refused).
    field : str
        The field named in the error.
    zero_ok : bool, optional
        Accept 0 as well (default ``False``).
    source : str or None, optional
        File (or other origin) named in the error.

    Returns
    -------
    float
        ``float(value)``.

    Examples
    --------
    >>> from eqrec.checks import positive
    >>> positive(0.5, "mu1")
    0.5
    """
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, numbers.Real) or not np.isfinite(value) \
            or value < 0 or (value == 0 and not zero_ok):
        raise InputError(f"must be a {'non-negative' if zero_ok else 'positive'} finite number, got {value!r}",
                         source, field)
    return float(value)


def generator(rng: Any, field: str = "rng") -> np.random.Generator:
    """``rng`` if it is a :class:`numpy.random.Generator`, else an :class:`InputError` naming ``field``.

    Parameters
    ----------
    rng : numpy.random.Generator
        The value given.
    field : str, optional
        The field named in the error (default ``"rng"``).

    Returns
    -------
    numpy.random.Generator
        ``rng`` unchanged.

    Examples
    --------
    >>> import numpy as np
    >>> from eqrec.checks import generator
    >>> isinstance(generator(np.random.default_rng(0)), np.random.Generator)
    True
    """
    if not isinstance(rng, np.random.Generator):
        raise InputError(f"expected a numpy.random.Generator (numpy.random.default_rng(seed)), got "
                         f"{type(rng).__name__}", field=field)
    return rng


def floats(value: Any, field: str) -> np.ndarray:
    """``value`` as a float array, else an :class:`InputError` naming ``field`` (shape and finiteness unchecked).

    Parameters
    ----------
    value : array_like
        The numbers given.
    field : str
        The field named in the error.

    Returns
    -------
    numpy.ndarray
        ``numpy.asarray(value, float)``.

    Examples
    --------
    >>> from eqrec.checks import floats
    >>> floats([1, 2], "x0")
    array([1., 2.])
    """
    try:
        return np.asarray(value, float)
    except (TypeError, ValueError):  # strings, ragged or non-numeric data
        raise InputError(f"must be numbers, got {value!r:.60}", field=field) from None


def radii(value: Any, n: int, field: str = "x0_radius") -> np.ndarray:
    """``value`` as ``n`` finite non-negative radii (one number is used for every state).

    Parameters
    ----------
    value : float or array_like
        One radius, or one per state.
    n : int
        State dimension.
    field : str, optional
        The field named in the error (default ``x0_radius``).

    Returns
    -------
    numpy.ndarray, shape (n,)
        The radii as floats (a new array).

    Raises
    ------
    InputError
        A bool or a string, non-numeric data, a wrong number of entries, NaN, inf or a negative radius.

    Examples
    --------
    >>> from eqrec.checks import radii
    >>> radii(0.5, 3)
    array([0.5, 0.5, 0.5])
    """
    if isinstance(value, (bool, np.bool_, str)):
        raise InputError(f"must be a number or one number per state, got {value!r}", field=field)
    r = floats(value, field)
    if r.ndim == 0:
        r = np.full(n, float(r))
    if r.shape != (n,):
        raise InputError(f"one radius per state (n = {n}) or one number, got shape {r.shape}", field=field)
    if not np.all(np.isfinite(r)) or np.any(r < 0):
        raise InputError(f"radii must be finite and >= 0, got {r.tolist()}", field=field)
    return np.array(r)


def seeded(seed: Any, field: str = "seed") -> np.random.Generator:
    """``numpy.random.default_rng(seed)``, else an :class:`InputError` naming ``field``.

    Parameters
    ----------
    seed : int or None
        A seed :func:`numpy.random.default_rng` takes (a non-negative integer, ``None``, ...).
    field : str, optional
        The field named in the error (default ``"seed"``).

    Returns
    -------
    numpy.random.Generator
        The generator.

    Examples
    --------
    >>> from eqrec.checks import seeded
    >>> float(seeded(0).uniform()) == float(__import__("numpy").random.default_rng(0).uniform())
    True
    """
    try:
        return np.random.default_rng(seed)
    except (TypeError, ValueError):
        raise InputError(f"a seed is an integer >= 0 (or None), got {seed!r}", field=field) from None


def instance(value: Any, kind: "type | tuple[type, ...]", field: str, what: str | None = None) -> Any:
    """``value`` if it is an instance of ``kind``, else an :class:`InputError` naming ``field``.

    Parameters
    ----------
    value : object
        The value given.
    kind : type or tuple of type
        The type(s) accepted.
    field : str
        The field named in the error.
    what : str or None, optional
        What is expected, in words (default: the name of ``kind``).

    Returns
    -------
    object
        ``value`` unchanged.

    Examples
    --------
    >>> from eqrec.checks import instance
    >>> instance(True, bool, "strict")
    True
    """
    if not isinstance(value, kind):
        names = what or " or ".join(k.__name__ for k in (kind if isinstance(kind, tuple) else (kind,)))
        raise InputError(f"expected {names}, got {type(value).__name__}", field=field)
    return value


#: The fraction of the available memory above which an allocation is refused (the size model's limit,
#: :data:`eqrec.design.inputs.MAX_MEMORY_FRACTION`).
MEMORY_FRACTION = 0.8


def available_memory() -> "float | None":
    """The memory available (Linux ``/proc/meminfo``).

    Returns
    -------
    float or None
        Bytes available, or ``None`` where it cannot be read.
    """
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    return None


def peak_memory_mb() -> float:
    """Peak resident memory of this process in MB: ``VmHWM`` of ``/proc/self/status`` on Linux, else ``ru_maxrss``.

    ``ru_maxrss`` survives ``exec``: a worker started by a parent that forks (``subprocess`` with a memory limit
    set before ``exec``) reports at least the parent's size at the fork (a long test session's 700 MB, say).
    ``VmHWM`` is the high-water mark of the worker's own address space.

    Returns
    -------
    float
        Megabytes.
    """
    try:
        with open("/proc/self/status", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("VmHWM:"):
                    return int(line.split()[1]) / 1024.0  # kB
    except OSError:
        pass
    import resource  # not on every platform: only where /proc is not

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def check_allocation(nbytes: float, field: str, what: str) -> None:
    """Refuse, before it starts, an allocation past :data:`MEMORY_FRACTION` of the available memory.

    Parameters
    ----------
    nbytes : float
        The bytes the call would allocate.
    field : str
        The input that sets the size (named by the refusal).
    what : str
        What would be allocated, in words.

    Raises
    ------
    InputError
        Past the limit (field ``field``); nothing allocated.
    """
    avail = available_memory()
    limit = MEMORY_FRACTION * avail if avail is not None else 2.0**40
    if nbytes > limit:
        raise InputError(f"refused: {what} would take {nbytes / 2**30:.3g} GiB of memory, more than "
                         f"{MEMORY_FRACTION:.0%} of the {limit / MEMORY_FRACTION / 2**30:.3g} GiB available", field=field)
