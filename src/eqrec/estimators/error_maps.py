r"""The error boxes of an estimator running outside its designed language (``strict=False``).

:class:`ClassBoxes` computes, for a class-engine design, the exact per-state
worst case of every class map for any initial error box (the maps are linear
in the initial error), and the box of a step on the model alone; its
:meth:`ClassBoxes.advance` is the one transition of the boxes, used by
:class:`eqrec.estimators.guaranteed.GuaranteedEstimator` and by
:func:`eqrec.interop.python_control.estimator_iosys`.  The mathematics, and
when the designed guarantee returns, are in the docstring of
:mod:`eqrec.estimators.guaranteed`.
"""

from __future__ import annotations

from typing import Callable, NamedTuple

import numpy as np

from eqrec.bounds.data_classes import ClassGains, class_error_map
from eqrec.estimators.causal import _has_class
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem

#: ``bound_of(prefix)``: the guarantee on ``ξ(t+1)`` after the observed arrival prefix of length ``t + 1``.
BoundRule = Callable[[ArrivalPattern], float]


class BoxState(NamedTuple):
    """The error boxes of an estimator running with ``strict=False`` (module docstring).

    Parameters
    ----------
    beta0 : ndarray, shape (n,)
        Bounds on the initial error of the current period.
    beta : ndarray, shape (n,)
        Bounds on the error of the current estimate.
    coasting : bool
        The data have left the language in this period.
    in_design : bool
        The designed guarantee applies to the current estimate.
    """

    beta0: np.ndarray
    beta: np.ndarray
    coasting: bool
    in_design: bool


class ClassBoxes:
    """Exact per-state worst cases of the class maps for any initial error box, and the coasting box.

    For the class ``(d, S)`` the error is ``G δ`` with ``G = E_d − K Z_S``
    (:func:`eqrec.bounds.data_classes.class_maps`); its worst case over
    ``|w| <= η_w, |v| <= η_v, |ξ0| <= β0`` is ``|G_wv| r + |G_ξ0| β0``.  The two
    parts are computed on first use of a class and kept.  :meth:`advance` is the
    one transition of the boxes, used by :class:`GuaranteedEstimator` and by
    :func:`eqrec.interop.python_control.estimator_iosys`.

    Parameters
    ----------
    system : AffineSystem
        The model (its noise bounds give the radii).
    gains : ClassGains
        The design's class gains.
    mu1 : float
        The recovery level.
    """

    def __init__(self, system: AffineSystem, gains: ClassGains, mu1: float):
        self.system, self.gains, self.mu1 = system, gains, float(mu1)
        self.stacking = Stacking(system, gains.horizon)
        lay = self.stacking.layout
        self.radius = lay.radius(system.eta_w, system.eta_v, mu1)[: lay.xi0.start]
        self._parts: dict[int, tuple[np.ndarray, np.ndarray]] = {}

    def start(self) -> BoxState:
        """The boxes after ``reset``: ``|ξ(0)| <= μ1``, in the design.

        Returns
        -------
        BoxState
            ``β0 = β = μ1``.
        """
        mu1 = np.full(self.system.n, self.mu1)
        return BoxState(mu1, mu1, False, True)

    def box(self, depth: int, available: tuple[int, ...], beta0: np.ndarray) -> np.ndarray:
        """The exact per-state worst case of the class ``(depth, available)`` from the initial box ``beta0``.

        Parameters
        ----------
        depth : int
            Period time of the estimate.
        available : tuple of int
            Period times of the measurements received.
        beta0 : ndarray, shape (n,)
            Bounds on the period's initial error.

        Returns
        -------
        ndarray, shape (n,)
            ``|G_wv| r + |G_ξ0| β0``.
        """
        i = self.gains.classes.index(depth, available)
        if i not in self._parts:
            G = np.abs(class_error_map(self.stacking, self.gains, i))
            cut = self.stacking.layout.xi0.start
            self._parts[i] = (G[:, :cut] @ self.radius, G[:, cut:])
        noise, initial = self._parts[i]
        return noise + initial @ beta0

    def coast(self, t: int, beta: np.ndarray) -> np.ndarray:
        """The box after a step on the model alone: ``|A(t)| β + |E(t)| r_w``.

        Parameters
        ----------
        t : int
            Period time of the step.
        beta : ndarray, shape (n,)
            Bounds on the current error.

        Returns
        -------
        ndarray, shape (n,)
            Bounds on the next error.
        """
        sys = self.system
        r_w = self.radius[: sys.nw]  # w(t) has the same radii at every t
        return np.abs(sys.A_at(t)) @ beta + np.abs(sys.E_at(t)) @ r_w

    def advance(self, state: BoxState, t: int, available: tuple[int, ...]) -> tuple[BoxState, bool]:
        """The boxes after the step at period time ``t`` with the measurements ``available`` received.

        The step coasts when the period has already left the language or when
        the class ``(t+1, available)`` is not in the design.  At the period's
        end the next period starts from the box reached (``μ1`` if the period
        stayed in the design: the certified recovery level), in the design iff
        that box is within ``μ1``.

        Parameters
        ----------
        state : BoxState
            The boxes before the step.
        t : int
            Period time of the step (``0..T-1``).
        available : tuple of int
            Period times of the measurements received by the end of the step.

        Returns
        -------
        state : BoxState
            The boxes after the step.
        coasting : bool
            Whether the step runs on the model alone.
        """
        coasting = state.coasting or not _has_class(self.gains, t + 1, available)
        if coasting:
            beta, in_design = self.coast(t, state.beta), False
        else:
            beta, in_design = self.box(t + 1, available, state.beta0), state.in_design
        if t + 1 == self.gains.horizon:  # the period's end: the next one starts from this box
            if in_design:
                beta = np.full(self.system.n, self.mu1)
            return BoxState(beta, beta, False, bool(np.all(beta <= self.mu1))), coasting
        return BoxState(state.beta0, beta, coasting, in_design), coasting

    def bound(self, state: BoxState, t: int, available: tuple[int, ...], bound_of: BoundRule,
              prefix: ArrivalPattern) -> float:
        """The guarantee after the step at period time ``t``: the designed level in the design, else ``max β``.

        Parameters
        ----------
        state : BoxState
            The boxes after the step (:meth:`advance`).
        t : int
            Period time of the step.
        available : tuple of int
            Period times of the measurements received.
        bound_of : callable
            The design's level of an observed prefix.
        prefix : ArrivalPattern
            The observed prefix (used in the design only).

        Returns
        -------
        float
            The bound on ``‖ξ(t+1)‖∞``.
        """
        if not state.in_design:
            return float(state.beta.max())
        return self.mu1 if t + 1 == self.gains.horizon else float(bound_of(prefix))
