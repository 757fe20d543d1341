"""What reaches an estimator at one step, in the forms of the estimator protocol (:mod:`eqrec.estimators.protocol`).

At time ``t`` an estimator is given ``None`` (nothing arrived), ``y(t)``
itself (its packet arrived on time and alone), or time-stamped packets
``(τ, y(τ))`` (:class:`~eqrec.estimators.causal.Packet`, late ones among them).
:func:`eqrec.simulate.loop.what_arrived` builds that form from an arrival
trace for the simulation loop; :func:`as_packets` reads any of the forms back
into checked packets for an estimator, before the estimator changes any
state.  The module needs no estimator (a packet is anything with a ``time``
and a ``y``), so the LMV layer reads packets without the bounded-error ones.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np

from eqrec.errors import InputError


class Stamped(NamedTuple):
    """A checked measurement with its time stamp (what :func:`as_packets` returns).

    Parameters
    ----------
    time : int
        Absolute time ``τ`` of the measurement.
    y : numpy.ndarray
        The measurement ``y(τ)``, a finite float array.
    """

    time: int
    y: np.ndarray


class _Checked(list):
    """Packets already checked by :func:`as_packets` for the time ``now`` and the shape ``shape`` (not checked
    again when an estimator passes them on)."""

    now: int
    shape: tuple[int, ...]


def _is_packet(item: Any) -> bool:
    return hasattr(item, "time") and hasattr(item, "y") and not isinstance(item, np.ndarray)


def is_stamp(value: Any) -> bool:
    """Whether ``value`` is a time stamp: an integer (Python or NumPy), not a bool.

    Parameters
    ----------
    value : object
        The value to test.

    Returns
    -------
    bool
        ``True`` for ``3`` or ``np.int64(3)``, ``False`` for ``True``, ``3.0`` or ``"3"``.
    """
    return isinstance(value, (int, np.integer)) and not isinstance(value, (bool, np.bool_))


def _is_pair(item: Any) -> bool:
    return isinstance(item, (tuple, list)) and len(item) == 2 and is_stamp(item[0]) and not np.isscalar(item[1])


def _is_number(value: Any) -> bool:
    return np.isscalar(value) and not isinstance(value, (str, bytes))


def finite_array(value: Any, shape: tuple[int, ...], field: str, what: str, symbol: str = "") -> np.ndarray:
    """``value`` as a new finite float array of ``shape`` (a vector may come nested), or an :class:`InputError`.

    Parameters
    ----------
    value : array_like
        The numbers (strings, booleans and objects are refused, not converted).
    shape : tuple of int
        The shape required; a vector of ``shape = (k,)`` may be given with any nesting of ``k`` entries.
    field : str
        The field named in the error.
    what : str
        What the value is, in words (the start of the message).
    symbol : str, optional
        The name of the length in the message (``"p"`` gives ``expected p = 2``).

    Returns
    -------
    numpy.ndarray
        A new float array of ``shape``.

    Raises
    ------
    InputError
        A string, non-numeric entries, another shape, or NaN/inf entries.
    """
    if isinstance(value, (str, bytes)):
        raise InputError(f"{what} must be numbers, got a string", field=field)
    try:
        raw = np.asarray(value)
    except (TypeError, ValueError):  # ragged nesting
        raise InputError(f"{what} must be numbers, got {value!r:.60}", field=field) from None
    if raw.dtype.kind not in "iuf":
        raise InputError(f"{what} must be numbers, got {value!r:.60}", field=field)
    shape = tuple(shape)
    arr = np.array(raw, dtype=float)
    if len(shape) == 1 and arr.size == shape[0]:
        arr = arr.reshape(shape)
    if arr.shape != shape:
        expected = f"{symbol} = {shape[0]}" if symbol and len(shape) == 1 else str(shape)
        raise InputError(f"{what} has {arr.size} entries (shape {raw.shape}), expected {expected}", field=field)
    if not np.isfinite(arr).all():
        raise InputError(f"{what} contains NaN or infinite entries: {arr.tolist()}", field=field)
    return arr


def checked_columns(packets: "list[tuple[int, np.ndarray]]", now: int, shape: tuple[int, ...]) -> list[Stamped]:
    """Stamped measurements that their caller has checked already, marked so: :func:`as_packets` returns them as
    they are (the arrays themselves, not copies) for the time ``now`` and the shape ``shape``.

    For a caller that makes the measurements it passes on (``eqrec.exact_bound``'s affine columns): their stamps
    read by :func:`as_packets` (integers, distinct, none after ``now``) and every value a float array of ``shape``
    with finite entries of magnitude at most :data:`MAX_DATA_MAGNITUDE` (what the reader would check).

    Parameters
    ----------
    packets : list of (int, numpy.ndarray)
        ``(τ, y(τ))``, checked as above.
    now : int
        Absolute time of the step.
    shape : tuple of int
        Their shape.

    Returns
    -------
    list of Stamped
        The packets, marked as checked for ``now`` and ``shape``.
    """
    out = _Checked(Stamped(int(tau), y) for tau, y in packets)
    out.now, out.shape = now, tuple(shape)
    return out


def in_scale_array(value: np.ndarray) -> bool:
    """Whether every entry of a float array is finite and at most :data:`MAX_DATA_MAGNITUDE` in magnitude (a NaN
    fails the comparison, an infinity exceeds the limit).

    Parameters
    ----------
    value : numpy.ndarray
        A float array.

    Returns
    -------
    bool
        What :func:`as_packets` would accept of its values.
    """
    return value.dtype == np.float64 and bool(np.abs(value).max(initial=0.0) <= MAX_DATA_MAGNITUDE)


def as_packets(y: Any, now: int, shape: "tuple[int, ...] | int", field: str = "y") -> list[Stamped]:
    """Read what arrived at time ``now`` in any of the protocol's forms, checked before anything is used.

    Forms: ``None`` or an empty list (nothing); ``y(now)`` itself (an array,
    a list of numbers or, for ``p = 1``, a number); a
    :class:`~eqrec.estimators.causal.Packet` or a pair ``(τ, y(τ))`` with an
    integer stamp; a list of packets and pairs.  The one reader of packets of
    every estimator.

    Parameters
    ----------
    y : object
        What arrived.
    now : int
        Absolute time of the step.
    shape : tuple of int or int
        Shape every measurement must have (``(p,)`` or ``p``, or ``(p, K)`` for affine runs).
    field : str, optional
        Field named in the errors (default ``"y"``).

    Returns
    -------
    list of Stamped
        The packets, in the given order, each ``y`` a new float array of ``shape``.

    Raises
    ------
    InputError
        A string, a malformed packet, a measurement of another shape or with
        NaN/inf entries, a stamp that is not an integer, from the future
        (``> now``) or given twice, naming ``field``.
    """
    shape = (int(shape),) if isinstance(shape, (int, np.integer)) else tuple(shape)
    if y is None or (isinstance(y, (list, tuple)) and len(y) == 0):
        return []
    if isinstance(y, _Checked) and y.now == now and y.shape == shape:
        return y
    if type(y) is np.ndarray:  # the common form, y(now) on time: checked without the general reader's steps
        fast = _plain_measurement(y, shape)
        if fast is not None:
            out = _Checked([Stamped(int(now), fast)])
            out.now, out.shape = now, shape
            return out
    if isinstance(y, (str, bytes)):
        raise InputError("a measurement must be numbers, got a string", field=field)
    if type(y) is list and all(type(item) is Packet for item in y):  # late packets as the simulation gives them
        items = y
    elif _is_packet(y) or _is_pair(y):
        items = [y]
    elif isinstance(y, np.ndarray) or _is_number(y) or (isinstance(y, (list, tuple)) and all(_is_number(e) for e in y)):
        items = [Stamped(int(now), y)]
    elif isinstance(y, (list, tuple)):
        items = list(y)
    else:
        raise InputError(f"expected a measurement, packets or None, got {type(y).__name__}", field=field)
    out = _Checked()
    out.now, out.shape = now, shape
    seen: set[int] = set()
    for item in items:
        if type(item) is Packet or _is_packet(item):
            tau, val = item.time, item.y
        elif isinstance(item, (tuple, list)) and len(item) == 2 and not np.isscalar(item[1]):
            tau, val = item
        else:
            raise InputError(f"a packet is (time stamp, y), got {item!r:.80}", field=field)
        if not is_stamp(tau):
            raise InputError(f"a time stamp is an integer, got {tau!r}", field=field)
        if tau > now:
            raise InputError(f"packet stamped {tau} received at time {now}: a packet cannot come from the future",
                             field=field)
        if int(tau) in seen:
            raise InputError(f"a second packet stamped {tau} received at time {now}", field=field)
        seen.add(int(tau))
        y_tau = _plain_measurement(val, shape) if type(val) is np.ndarray else None
        if y_tau is None:  # any other form, or a value the general checks refuse (they name it)
            y_tau = finite_array(val, shape, field, f"the measurement of time {tau}", "p")
            y_tau = in_scale(y_tau, field, f"the measurement of time {tau}")
        out.append(Stamped(int(tau), y_tau))
    return out


def _plain_measurement(value: np.ndarray, shape: tuple[int, ...]) -> "np.ndarray | None":
    """A float array of exactly ``shape`` with finite entries of magnitude at most :data:`MAX_DATA_MAGNITUDE`, as a
    new array (what :func:`finite_array` and :func:`in_scale` return for it); ``None`` for anything else, which the
    general checks then read (and refuse with their message, or accept in another form).

    A NaN fails ``<=`` and an infinity exceeds the limit, so both are left to the general checks."""
    if value.dtype != np.float64 or value.shape != shape or value.size > 64:
        return None
    arr = np.array(value, dtype=float)  # the general reader's copy (its memory order too)
    limit = MAX_DATA_MAGNITUDE
    for entry in arr.ravel().tolist():
        if not -limit <= entry <= limit:
            return None
    return arr


def plain_vector(value: Any, shape: tuple[int, ...]) -> "np.ndarray | None":
    """``value`` as a new float array when it is a NumPy float array of exactly ``shape`` with finite entries in
    scale (at most 64 of them), the form that needs no general reading; ``None`` for anything else (read it with
    the general checks, which accept it in another form or refuse it with their message).

    Parameters
    ----------
    value : object
        A measurement or input as given.
    shape : tuple of int
        The shape it must have.

    Returns
    -------
    numpy.ndarray or None
        A copy of ``value``, or ``None``.
    """
    return _plain_measurement(value, shape) if type(value) is np.ndarray else None


#: The largest magnitude of a measurement, input or initial estimate an estimator takes.  Every estimate is a
#: sum of products of such data with the plant's matrices and gains: past this, a propagation overflows in
#: floating point to an infinite or NaN estimate and bound (``1e308`` did), so the data are refused at once
#: (nothing changes) and the message says why.
MAX_DATA_MAGNITUDE = 1e150


def in_scale(value: np.ndarray, field: str, what: str) -> np.ndarray:
    """``value`` if its entries are at most :data:`MAX_DATA_MAGNITUDE` in magnitude, else an :class:`InputError`.

    Parameters
    ----------
    value : numpy.ndarray
        Finite numbers.
    field : str
        The field named in the error.
    what : str
        What the value is, in words.

    Returns
    -------
    numpy.ndarray
        ``value`` itself.

    Raises
    ------
    InputError
        An entry above :data:`MAX_DATA_MAGNITUDE` in magnitude: its propagation would overflow.
    """
    if value.size and float(np.max(np.abs(value))) > MAX_DATA_MAGNITUDE:
        raise InputError(f"{what} has an entry of magnitude {float(np.max(np.abs(value))):.3g}, above "
                         f"{MAX_DATA_MAGNITUDE:g}: its propagation through the plant would overflow in floating "
                         "point (an infinite estimate and bound); scale the data (nothing changed)", field=field)
    return value


@dataclass(frozen=True)
class Packet:
    """A measurement ``y`` of time ``time`` (its time stamp).

    Parameters
    ----------
    time : int
        Absolute time ``τ`` of the measurement (not the time it arrives).
    y : ndarray, shape (p,)
        The measurement ``y(τ)``.

    Examples
    --------
    A packet of time 3 arriving late, at time 5, among what arrives then:

    >>> import numpy as np
    >>> import eqrec
    >>> late = eqrec.Packet(3, np.array([1.0, 2.0]))
    >>> late.time
    3
    """

    time: int
    y: np.ndarray


def check_input(u, m: int) -> np.ndarray:
    """The input ``u(t)`` as a finite vector of ``m`` entries (``None``: zero).

    Parameters
    ----------
    u : array_like or None
        The input.
    m : int
        Number of inputs.

    Returns
    -------
    ndarray, shape (m,)
        A new array.

    Raises
    ------
    InputError
        (field ``u``) a string, the wrong number of entries, a nested array (a column ``(m, 1)`` or
        ``(1, 1)``: give a flat vector), NaN/inf, or an entry above :data:`MAX_DATA_MAGNITUDE`.
    """
    if u is None:
        return np.zeros(m)
    if type(u) is np.ndarray:  # the common form: a flat float vector, checked without the general steps
        fast = _plain_measurement(u, (m,))
        if fast is not None:
            return fast
    return in_scale(_flat(u, finite_array(u, (m,), "u", "the input u", "m"), "u", "the input u"), "u",
                    "the input u")


def _flat(value, checked: np.ndarray, field: str, what: str) -> np.ndarray:
    """``checked`` if ``value`` was a flat vector (or a number, for one entry), else an :class:`InputError`.

    A column ``(k, 1)`` or a ``(1, 1)`` array has the right number of entries but is not the vector the
    estimator's protocol takes (and a matrix input usually means a mistake upstream), so it is refused.
    """
    shape = np.shape(value)
    if len(shape) > 1 or (len(shape) == 0 and checked.size != 1):
        raise InputError(f"{what} must be a flat vector of {checked.size} entries (shape ({checked.size},)), got "
                         f"shape {shape}", field=field)
    return checked


def check_estimate(xhat0, n: int, field: str = "xhat0") -> np.ndarray:
    """An initial estimate as a finite vector of ``n`` entries (a copy).

    Parameters
    ----------
    xhat0 : array_like
        The estimate.
    n : int
        Number of states.
    field : str, optional
        Name used in the error.

    Returns
    -------
    ndarray, shape (n,)
        A new array.

    Raises
    ------
    InputError
        A string, the wrong number of entries, a nested array (a column ``(n, 1)``: give a flat
        vector), NaN/inf, or an entry above :data:`MAX_DATA_MAGNITUDE`.
    """
    checked = _flat(xhat0, finite_array(xhat0, (n,), field, "the initial estimate", "n"), field,
                    "the initial estimate")
    return in_scale(checked, field, "the initial estimate")
