"""The adaptive-cruise-control plant of Section VI of the prefix-based paper, from its Table I constants."""

from __future__ import annotations

import numpy as np

from eqrec.core.systems import AffineSystem

#: Table I of the prefix-based paper (SI units).
ACC_CONSTANTS = {"m": 1370.0, "k0": 7.58, "k1": 9.9407, "Ts": 0.5, "eta_w": 0.1, "eta_v": 0.05}


def acc_system(m: float = ACC_CONSTANTS["m"], k0: float = ACC_CONSTANTS["k0"],
               k1: float = ACC_CONSTANTS["k1"], Ts: float = ACC_CONSTANTS["Ts"],
               eta_w: float = ACC_CONSTANTS["eta_w"], eta_v: float = ACC_CONSTANTS["eta_v"]) -> AffineSystem:
    r"""Discrete adaptive-cruise-control model of Section VI of the prefix-based paper.

    Exact zero-order-hold discretisation of ``m dv_e/dt = u - k0 - k1 v_e``,
    ``dh/dt = v_L - v_e``, ``dv_L/dt = w`` (lead acceleration), with state
    ``x = [v_e, h, v_L]`` (ego speed, headway, lead speed) and outputs
    ``[v_e, h]``; built from the Table I constants, not from rounded
    matrices.  With :math:`\kappa = k_1/m` and :math:`a = e^{-\kappa T_s}`,

    .. math::
        A = \begin{bmatrix} a & 0 & 0 \\ (a-1)/\kappa & 1 & T_s \\ 0 & 0 & 1 \end{bmatrix},
        \quad
        B = \frac{1}{k_1^2}\begin{bmatrix} (1-a)\,k_1 \\ m(1-a) - k_1 T_s \\ 0 \end{bmatrix},
        \quad
        f = -k_0 B,
        \quad
        E = \begin{bmatrix} 0 \\ T_s^2/2 \\ T_s \end{bmatrix}.

    Parameters
    ----------
    m : float
        Vehicle mass [kg] (Table I: 1370).
    k0 : float
        Friction coefficient ``k̄0`` [N] (Table I: 7.58).
    k1 : float
        Drag coefficient ``k̄1`` [N s/m] (Table I: 9.9407).
    Ts : float
        Sampling time [s] (Table I: 0.5).
    eta_w : float
        Bound on the lead vehicle's acceleration ``|w|`` (Table I: 0.1).
    eta_v : float
        Bound on the measurement noise ``‖v‖∞`` (Table I: 0.05).

    Returns
    -------
    AffineSystem
        Named ``"ACC"``, with ``n = 3``, ``p = 2``, ``m = 1``,
        ``E = [0, Ts^2/2, Ts]^T`` and ``V = I``.

    Examples
    --------
    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> acc.A.shape, acc.C.shape, acc.E.shape
    ((3, 3), (2, 3), (3, 1))
    >>> acc.eta_w, acc.eta_v
    (0.1, 0.05)
    """
    kappa = k1 / m
    a = np.exp(-kappa * Ts)
    A = np.array([[a, 0.0, 0.0],
                  [(a - 1.0) / kappa, 1.0, Ts],
                  [0.0, 0.0, 1.0]])
    B = (1.0 / k1**2) * np.array([[(1.0 - a) * k1], [m * (1.0 - a) - k1 * Ts], [0.0]])
    f = np.array([-(k0 / k1) * (1.0 - a), -(k0 / k1**2) * (m * (1.0 - a) - k1 * Ts), 0.0])
    C = np.array([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]])
    E = np.array([[0.0], [Ts**2 / 2.0], [Ts]])
    return AffineSystem(A=A, B=B, f=f, C=C, E=E, eta_w=eta_w, eta_v=eta_v, name="ACC")
