"""What reaches an estimator at one step, in the forms of the estimator protocol (:mod:`eqrec.core.protocol`).

At time ``t`` an estimator is given ``None`` (nothing arrived), ``y(t)``
itself (its packet arrived on time and alone), or time-stamped packets
``(τ, y(τ))`` (:class:`~eqrec.core.estimator.Packet`, late ones among them).
:func:`eqrec.core.simulate.what_arrived` builds that form from an arrival
trace for the simulation loop; :func:`as_packets` reads any of the forms back
into checked packets for an estimator, before the estimator changes any
state.  The module needs no estimator (a packet is anything with a ``time``
and a ``y``), so the LMV layer reads packets without the bounded-error ones.
"""

from __future__ import annotations

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


def _is_packet(item: Any) -> bool:
    return hasattr(item, "time") and hasattr(item, "y") and not isinstance(item, np.ndarray)


def _is_pair(item: Any) -> bool:
    return (isinstance(item, (tuple, list)) and len(item) == 2 and isinstance(item[0], (int, np.integer))
            and not isinstance(item[0], (bool, np.bool_)) and not np.isscalar(item[1]))


def as_packets(y: Any, now: int, shape: tuple[int, ...], field: str = "y") -> list[Stamped]:
    """Read what arrived at time ``now`` in any of the protocol's forms, checked before anything is used.

    Forms: ``None`` or an empty list (nothing); ``y(now)`` itself (an array,
    or a list of numbers); a :class:`~eqrec.core.estimator.Packet` or a pair
    ``(τ, y(τ))``; a list of packets and pairs.

    Parameters
    ----------
    y : object
        What arrived.
    now : int
        Absolute time of the step.
    shape : tuple of int
        Shape every measurement must have (``(p,)``, or ``(p, K)`` for affine runs).
    field : str, optional
        Field named in the errors (default ``"y"``).

    Returns
    -------
    list of Stamped
        The packets, in the given order, each ``y`` a float array of ``shape``.

    Raises
    ------
    InputError
        A measurement of another shape or with NaN/inf entries, a stamp that is
        not an integer, from the future (``> now``) or given twice, naming ``field``.
    """
    if y is None or (isinstance(y, (list, tuple)) and len(y) == 0):
        return []
    if _is_packet(y) or _is_pair(y):
        items = [y]
    elif isinstance(y, np.ndarray) or np.isscalar(y) or (isinstance(y, (list, tuple)) and all(np.isscalar(e) for e in y)):
        items = [Stamped(int(now), y)]
    elif isinstance(y, (list, tuple)):
        items = list(y)
    else:
        raise InputError(f"expected a measurement, packets or None, got {type(y).__name__}", field=field)
    out: list[Stamped] = []
    for item in items:
        if _is_packet(item):
            tau, val = item.time, item.y
        elif _is_pair(item):
            tau, val = item
        else:
            raise InputError(f"a packet is (time stamp, y), got {item!r}", field=field)
        if isinstance(tau, (bool, np.bool_)) or not isinstance(tau, (int, np.integer)):
            raise InputError(f"a time stamp is an integer, got {tau!r}", field=field)
        if tau > now:
            raise InputError(f"packet stamped {tau} received at time {now}: a packet cannot come from the future",
                             field=field)
        if any(pk.time == tau for pk in out):
            raise InputError(f"two packets stamped {tau} received at time {now}", field=field)
        try:
            arr = np.asarray(val, dtype=float)
        except (TypeError, ValueError):
            raise InputError(f"the measurement of time {tau} is not numeric: {val!r}", field=field) from None
        if arr.shape != tuple(shape):
            if arr.size == int(np.prod(shape)) and len(shape) == 1:
                arr = arr.reshape(shape)
            else:
                raise InputError(f"the measurement of time {tau} has shape {arr.shape}, expected {tuple(shape)}",
                                 field=field)
        if not np.all(np.isfinite(arr)):
            raise InputError(f"the measurement of time {tau} contains NaN or infinite entries", field=field)
        out.append(Stamped(int(tau), arr))
    return out
