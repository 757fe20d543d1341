r"""The causal equalized-recovery estimator running on a measurement stream.

Eqs. (5)-(7) of the prefix-based paper:

.. math::
    \hat x(t+1) = A\hat x(t) + Bu(t) - u_e(t) + f, \qquad
    u_e(t) = u_0(t, q_{0:t}) + \sum_{\tau \le t} F(t, \tau, q_{0:t})\, y_\xi(\tau),

with :math:`y_\xi(\tau) = y(\tau) - C\hat x(\tau)` when the measurement of time
``τ`` arrived and 0 when it is missing.  The gains are looked up by the
observed prefix ``q(0..t)`` (prefix-based) or by ``t`` alone (time-based).

With ``periodic=True`` the estimator restarts its horizon every ``T`` steps
(Section V of the prefix-based paper, Section III-D of the augmented paper):
the error is back below ``M1`` at the end of each period, so the same gains
apply again.
"""

from __future__ import annotations

import numpy as np

from eqrec.errors import InputError
from eqrec.core.gains import GainSchedule
from eqrec.core.systems import AffineSystem


class RecoveryEstimator:
    """Causal estimator of eqs. (5)-(7).

    Parameters
    ----------
    system
        The model (``A, B, C, f``) used by the estimator.
    schedule
        Prefix-based or time-based gains.
    xhat0
        Initial estimate ``x̂(0)``.
    periodic
        Restart the horizon every ``T`` steps instead of stopping.
    """

    def __init__(self, system: AffineSystem, schedule: GainSchedule, xhat0: np.ndarray, periodic: bool = False):
        self.system = system
        self.schedule = schedule
        self.T = schedule.horizon
        self.periodic = periodic
        self.xhat = np.asarray(xhat0, float).reshape(system.n).copy()
        self._t = 0  # time since the start of the current period
        self._k = 0  # absolute time (for time-varying models)
        self._prefix = ""
        self._yxi: list[np.ndarray] = []

    @property
    def observed_prefix(self) -> str:
        return self._prefix

    def step(self, y: np.ndarray | None, u: np.ndarray | None = None) -> np.ndarray:
        """Process time ``t``: measurement ``y(t)`` (``None`` if missing) and input ``u(t)``.

        Returns the prediction ``x̂(t+1)``.
        """
        sys = self.system
        if self._t == self.T:
            if not self.periodic:
                raise InputError(f"the estimator's horizon T = {self.T} is over (use periodic=True to restart)")
            self._t, self._prefix, self._yxi = 0, "", []
        k = self._k
        C = sys.C_at(k)
        if y is None:
            self._prefix += "0"
            self._yxi.append(np.zeros(sys.p))
        else:
            y = np.asarray(y, float).reshape(-1)
            if y.shape != (sys.p,):
                raise InputError(f"measurement at time {k} has {y.size} entries, expected p = {sys.p}")
            self._prefix += "1"
            self._yxi.append(y - C @ self.xhat)
        gain = self.schedule.row(self._prefix)
        ue = gain.u0 + gain.F @ np.concatenate(self._yxi)
        u = np.zeros(sys.m) if u is None else np.asarray(u, float).reshape(-1)
        self.xhat = sys.A_at(k) @ self.xhat + sys.B_at(k) @ u - ue + sys.f
        self._t += 1
        self._k += 1
        return self.xhat.copy()
