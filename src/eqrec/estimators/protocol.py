r"""The one estimator protocol: every estimator of the package runs as ``reset`` then ``step``.

Every estimator, guaranteed (bounded-error designs of the three equalized-recovery
papers) or stochastic (Kalman-type filters, the LMV filter and predictor of the
companion study), is driven the same way, in the convention of python-control's
discrete-time systems and of filterpy's filters:

* ``est.reset(xhat0, t0=0)`` starts a run from the initial estimate
  :math:`\hat x(t_0)` and returns the estimator;
* ``est.step(y, u)`` processes time ``t``: what arrived at ``t`` (``None`` when
  nothing arrived, ``y(t)`` as an array when it arrived on time, or time-stamped
  packets ``(τ, y(τ))``, :class:`~eqrec.estimators.causal.Packet`, for late ones) and
  the input ``u(t)``; it returns the pair ``(x̂(t+1), spread)``;
* ``spread`` is a guarantee ``b`` with :math:`\|x(t+1) - \hat x(t+1)\|_\infty \le b`
  for every noise in the box (``kind == "guaranteed"``, a float) or the error
  covariance the estimator believes in (``kind == "stochastic"``, an ``(n, n)``
  array);
* ``est.time`` is the absolute time of the current estimate and ``est.x`` a copy
  of it.

A call that raises leaves the estimator exactly as it was (every input is
checked before any state changes), and non-finite data is refused with
:class:`~eqrec.errors.InputError` naming the field.

One loop, :func:`eqrec.simulate.loop.closed_loop`, runs any estimator that
follows this protocol.

Sets: predicted and filtered
----------------------------
An estimator that carries a *set* of states (the set-membership estimators,
:class:`~eqrec.estimators.zonotope.ZonotopeEstimator` and
:class:`~eqrec.estimators.exact_set.ExactSetEstimator`, and
:class:`~eqrec.estimators.guaranteed.GuaranteedEstimator`, whose predicted set is that of
the estimate it reports) also gives, after a step at
time ``t`` (``est.time == t + 1``), two :class:`StateSet`:

* ``est.predicted``: the set of :math:`x(t+1)` given the data received up to
  ``t`` (the papers' convention, what ``step`` returns: its centre is
  ``x̂(t+1)`` and ``max`` of its radius the bound);
* ``est.filtered``: the set of :math:`x(t)` given the same data (the
  convention of set-based toolboxes and of a controller that wants
  :math:`x(t)`).

Each is a centre and per-state bounds ``lower <= x <= upper`` (rounded outward:
a guarantee in floating point), and a zonotope ``centre + generators ε``,
:math:`\|\varepsilon\|_\infty \le 1`, where the estimator has one (``generators``
is ``None`` otherwise, e.g. for the exact estimator, whose set is a constrained
zonotope).  Right after ``reset`` ``predicted`` is the initial set and
``filtered`` raises (no data yet).  ``step`` keeps returning the prediction.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np

from eqrec.arrivals.packets import as_packets
from eqrec.errors import InputError

#: What a step returns besides the estimate: a float bound (guaranteed) or a covariance (stochastic).
Spread = "float | np.ndarray"

EstimatorKind = Literal["guaranteed", "stochastic"]

#: Unit roundoff of float64.
_U = np.finfo(float).eps / 2


@dataclass(frozen=True)
class StateSet:
    r"""A set of states at one time, as a set-valued estimator reports it (module docstring).

    Parameters
    ----------
    time : int
        The absolute time ``s`` of the state :math:`x(s)` the set contains.
    centre : numpy.ndarray, shape (n,)
        The estimate, the centre of the set (of its zonotope, or of its interval hull).
    lower, upper : numpy.ndarray, shape (n,)
        Per-state bounds, :math:`\text{lower} \le x(s) \le \text{upper}` (rounded outward).
    generators : numpy.ndarray of shape (n, q), or None
        The zonotope :math:`\{\text{centre} + G\varepsilon : \|\varepsilon\|_\infty \le 1\}` containing
        :math:`x(s)` (its interval hull lies inside the bounds), ``None`` when the set is not a zonotope.
    """

    time: int
    centre: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    generators: "np.ndarray | None" = None

    @property
    def radius(self) -> np.ndarray:
        """Per state, ``max(upper - centre, centre - lower)`` rounded upward: ``|x_i(s) - centre_i| <= radius_i``.

        Returns
        -------
        numpy.ndarray, shape (n,)
            The radius.
        """
        return np.nextafter(np.maximum(self.upper - self.centre, self.centre - self.lower), np.inf)

    @classmethod
    def around(cls, time: int, centre: np.ndarray, radius: np.ndarray,
               generators: "np.ndarray | None" = None) -> "StateSet":
        """The set ``|x_i - centre_i| <= radius_i`` (bounds rounded outward), with its zonotope if any.

        Parameters
        ----------
        time : int
            The absolute time of the state.
        centre : numpy.ndarray, shape (n,)
            The centre.
        radius : numpy.ndarray, shape (n,)
            Per-state radius (a guarantee).
        generators : numpy.ndarray or None, optional
            The zonotope's generators.

        Returns
        -------
        StateSet
            Copies of the arrays.
        """
        c, r = np.array(centre, dtype=float), np.asarray(radius, dtype=float)
        slack = 2 * _U * (np.abs(c) + r)
        return cls(int(time), c, np.nextafter(c - r - slack, -np.inf), np.nextafter(c + r + slack, np.inf),
                   None if generators is None else np.array(generators, dtype=float))


@runtime_checkable
class Estimator(Protocol):
    """An estimator run step by step (module docstring).

    Attributes
    ----------
    kind : {"guaranteed", "stochastic"}
        What the second value of :meth:`step` is: a bound on the infinity
        norm of the error, or an error covariance.
    name : str
        The family in words, e.g. ``"Kalman, time-stamped"`` or
        ``"guaranteed, class engine"`` (a column of ``eqrec compare``).
    """

    kind: EstimatorKind
    name: str

    def reset(self, xhat0: Any, t0: int = 0) -> "Estimator":
        """Start a run from ``x̂(t0) = xhat0``.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            The initial estimate (finite).
        t0 : int, optional
            Absolute time of the first step.

        Returns
        -------
        Estimator
            ``self``, so that ``est.reset(x0).step(...)`` chains.
        """
        ...

    def step(self, y: Any = None, u: Any = None) -> tuple[np.ndarray, Any]:
        """Process time ``t``: what arrived and the input.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None
            ``y(t)`` on time, time-stamped packets ``(τ, y(τ))``, or ``None``.
        u : array_like or None
            The input ``u(t)`` (``None``: zero).

        Returns
        -------
        xhat : ndarray, shape (n,)
            The estimate the estimator reports for this step (``x̂(t+1)`` for the guaranteed estimators).
        spread : float or ndarray
            The bound (``kind == "guaranteed"``) or the error covariance (``"stochastic"``).
        """
        ...

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        ...

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate."""
        ...


def check_estimator(est: Any, field: str = "est") -> Any:
    """``est`` if it can be run by the protocol (callable ``reset`` and ``step``), else an :class:`InputError`.

    Checked before a run starts (:func:`eqrec.simulate.loop.closed_loop`); it
    says nothing about the estimator's kind, only that it can be reset and stepped.

    Parameters
    ----------
    est : object
        The estimator.
    field : str, optional
        The field named in the error.

    Returns
    -------
    object
        ``est`` unchanged.

    Raises
    ------
    InputError
        An object without a callable ``reset`` or ``step``.
    """
    missing = [m for m in ("reset", "step") if not callable(getattr(est, m, None))]
    if missing:
        raise InputError(f"expected an estimator of the protocol (reset, step), got {type(est).__name__} without "
                         f"{' and '.join(missing)}", field=field)
    return est


class OnTimeOnly:
    """A protocol estimator fed only the packet of the current time: a late packet counts as lost.

    An adapter for the estimators whose model has losses but no delays (the
    prefix-based paper's, the LMV filters) on traces with late packets
    (:mod:`eqrec.compare`).

    Parameters
    ----------
    estimator : object
        An estimator of the protocol (:mod:`eqrec.estimators.protocol`).
    p : int
        Number of outputs.
    """

    def __init__(self, estimator: Any, p: int):
        self.estimator, self.p = estimator, p
        self.kind, self.name = estimator.kind, estimator.name

    def reset(self, xhat0: Any, t0: int = 0) -> "OnTimeOnly":
        """Start the wrapped estimator (:meth:`eqrec.estimators.protocol.Estimator.reset`).

        Parameters
        ----------
        xhat0 : array_like
            Initial estimate.
        t0 : int, optional
            Absolute time of the first step.

        Returns
        -------
        OnTimeOnly
            ``self``.
        """
        self.estimator.reset(xhat0, t0)
        return self

    def step(self, y: Any = None, u: Any = None) -> tuple[np.ndarray, Any]:
        """Pass ``y(t)`` on if its packet is among those arriving at ``t``, else ``None``.

        Parameters
        ----------
        y : object
            What arrived (any protocol form).
        u : array_like or None, optional
            The input.

        Returns
        -------
        tuple
            What the wrapped estimator returns.
        """
        now = self.estimator.time
        on_time = [pk.y for pk in as_packets(y, now, self.p) if pk.time == now]
        return self.estimator.step(on_time[0] if on_time else None, u)

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        return self.estimator.time

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate."""
        return self.estimator.x

    def __getattr__(self, name: str) -> Any:
        return getattr(self.__dict__["estimator"], name)
