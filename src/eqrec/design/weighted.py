r"""A design with per-state weights: the guarantee on ``max_i w_i |x_i − x̂_i|``, the estimate in the original state.

With ``state_weights = (w_1, ..., w_n)`` a design entry designs on the system in the weighted state
``z = W x``, ``W = diag(w)`` (:meth:`eqrec.systems.affine.AffineSystem.scaled`): every level and
certificate is then a bound on

.. math:: \|W (x - \hat x)\|_\infty = \max_i w_i |x_i - \hat x_i|,

so a state vector of mixed units (rad, rad/s, A) gets a meaningful norm (``w_i = 1 / (\text{unit scale
of } x_i)``).  The outputs ``y = C x = (C W^{-1}) z`` and the inputs are those of the original system, so the
estimator of ``z`` runs on the same data; :class:`WeightedEstimator` hands back ``x̂ = W^{-1} ẑ``.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from eqrec.systems.affine import AffineSystem


def weigh(system: AffineSystem, state_weights: Any) -> tuple[AffineSystem, np.ndarray | None]:
    """The system a design entry designs on, and the weights it records (``None``: no weights).

    Parameters
    ----------
    system : AffineSystem
        The system as given.
    state_weights : array_like or None
        ``n`` positive weights, or ``None``.

    Returns
    -------
    system : AffineSystem
        ``system.scaled(state_weights)``, or ``system`` itself without weights.
    weights : numpy.ndarray or None
        The weights as floats.

    Raises
    ------
    InputError
        Weights that are not ``n`` positive finite numbers (field ``state_weights``).
    """
    if state_weights is None:
        return system, None
    scaled = system.scaled(state_weights)
    return scaled, np.asarray(state_weights, float).reshape(-1)


class WeightedEstimator:
    r"""The estimator of a weighted design, in the original coordinates (module docstring).

    Wraps the designed estimator of ``z = W x`` (:class:`eqrec.estimators.guaranteed.GuaranteedEstimator`, made by
    :meth:`eqrec.design.result.Design.estimator`) and keeps its protocol: :meth:`reset` from ``x̂(t0)``,
    :meth:`step` ``(y, u) -> (x̂(t+1), bound)``, :attr:`time`, :attr:`x`, :attr:`bound`.  The estimate is
    ``x̂ = W^{-1} ẑ``; the **bound is on the weighted norm**,

    .. math:: \max_i w_i |x_i(t+1) - \hat x_i(t+1)| \le \text{bound},

    so each state has ``|x_i − x̂_i| <= bound / w_i`` (:attr:`state_bounds`).  The guarantee assumes
    ``max_i w_i |x_i(t0) − x̂_i(t0)| <= μ1``.  Any other attribute is the wrapped estimator's.

    Parameters
    ----------
    estimator : GuaranteedEstimator
        The estimator of the weighted system.
    weights : numpy.ndarray
        The ``n`` positive state weights ``w``.

    Attributes
    ----------
    weights : numpy.ndarray
        The state weights.
    estimator : GuaranteedEstimator
        The wrapped estimator (of ``z = W x``).

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111"], mu1=1.0,
    ...                              state_weights=[1.0, 2.0, 0.5])
    >>> est = design.estimator().reset(np.zeros(3))
    >>> xhat, bound = est.step([1.0, 2.0])
    >>> bool(np.allclose(est.state_bounds, bound / np.array([1.0, 2.0, 0.5])))
    True
    """

    def __init__(self, estimator: Any, weights: np.ndarray):
        self.estimator = estimator
        self.weights = np.asarray(weights, float)

    def __getattr__(self, name: str) -> Any:
        if name in ("estimator", "weights"):  # not set yet (copying, unpickling): no recursion
            raise AttributeError(name)
        return getattr(self.estimator, name)

    def reset(self, xhat0: Any, t0: int = 0) -> "WeightedEstimator":
        """Start from ``x̂(t0) = xhat0`` (original coordinates); the guarantee assumes ``max_i w_i |x_i − x̂_i| <= μ1``.

        Parameters
        ----------
        xhat0 : array_like, shape (n,)
            Initial estimate of the original state.
        t0 : int, optional
            Absolute time of the first step (default 0).

        Returns
        -------
        WeightedEstimator
            ``self``.

        Raises
        ------
        InputError
            If ``xhat0`` is not ``n`` numbers, and the errors of the wrapped estimator's ``reset``.
        """
        from eqrec.arrivals.packets import check_estimate

        x0 = check_estimate(xhat0, self.weights.size)
        self.estimator.reset(self.weights * x0, t0)
        return self

    def step(self, y: Any = None, u: Any = None) -> tuple[np.ndarray, float]:
        """Process time ``t`` as the wrapped estimator does; returns ``(x̂(t+1), bound)`` in the original state.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            What arrived at time ``t`` (:meth:`eqrec.estimators.guaranteed.GuaranteedEstimator.step`).
        u : array_like or None, optional
            The input ``u(t)`` (``None``: zero).

        Returns
        -------
        xhat : numpy.ndarray, shape (n,)
            The estimate ``x̂(t+1) = W^{-1} ẑ(t+1)``.
        bound : float
            ``max_i w_i |x_i(t+1) − x̂_i(t+1)| <= bound``.
        """
        z, bound = self.estimator.step(y, u)
        return z / self.weights, bound

    def update(self, y: Any = None, u: Any = None) -> np.ndarray:
        """The filterpy spelling of :meth:`step` without the bound; returns ``x̂(t+1)``.

        Parameters
        ----------
        y : array_like, Packet, sequence of packets, or None, optional
            What arrived at the current time.
        u : array_like or None, optional
            The input (``None``: zero).

        Returns
        -------
        numpy.ndarray, shape (n,)
            The estimate in the original state.
        """
        return self.step(y, u)[0]

    @property
    def time(self) -> int:
        """Absolute time of the current estimate."""
        return self.estimator.time

    @property
    def x(self) -> np.ndarray:
        """A copy of the current estimate ``x̂`` (original coordinates)."""
        return self.estimator.x / self.weights

    @property
    def bound(self) -> float:
        """The guarantee on ``max_i w_i |x_i − x̂_i|`` of the current estimate."""
        return self.estimator.bound

    @property
    def state_bounds(self) -> np.ndarray:
        """Per state, ``|x_i − x̂_i| <= state_bounds[i]``: the exact per-state bounds of ``z = W x`` divided by ``w_i``
        with ``strict=False``, else ``bound / w_i``."""
        if self.estimator.strict:
            return self.estimator.bound / self.weights
        return self.estimator.state_bounds / self.weights

    @property
    def error_box(self) -> np.ndarray:
        """The same as :attr:`state_bounds` (``strict=False``; the name of earlier versions)."""
        return self.estimator.error_box / self.weights
