r"""The example plants of the papers, built from first principles: one home for them.

:func:`acc_system`
    The adaptive-cruise-control plant of Section VI of the prefix-based paper (P1), from its Table I constants.
:func:`batch_reactor`
    The batch reactor of the delayed/missing-data paper (P3).
:func:`two_mass`
    Two carts and a lightly damped spring, one position measured (a user's kind of plant, not from a paper).
:func:`tank_chain`
    A chain of ``n`` coupled tanks with ``p`` level sensors: plants of any size (the scale benchmarks and tests).

The batch reactor
-----------------
Rosenbrock's unstable batch reactor (the continuous model of Walsh, Ye,
Bushnell 2002, used by the paper's ref. [20]),

.. math:: \dot x = A_c x + B_c u, \qquad z = C x + V v,

is discretised with a zero-order hold and ``Ts = 0.05`` s (what MATLAB's
``c2d`` does; here :func:`zoh`, the arithmetic of :func:`scipy.signal.cont2discrete`).  Section IV-A of the
paper uses the output matrix ``C`` printed there (not the ``C`` of the
networked-control literature), no process noise (``W = ∅``: the system has
zero noise columns), ``V = I`` and ``ηv = 0.05`` (5 standard deviations of
``v ~ N(0, 0.01²)``).

The paper prints the discretised ``A``, ``B`` to four decimals; those
printed values live with the other published numbers (``config/claims.yaml``
and the tests), never here: :func:`discretisation_gaps` measures how far a
printed pair is from this discretisation.
"""

from __future__ import annotations

import numpy as np

from eqrec.checks import integer, positive
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

#: Continuous-time state matrix of the batch reactor.
BATCH_REACTOR_AC = np.array([[1.38, -0.2077, 6.715, -5.676],
                             [-0.5814, -4.29, 0.0, 0.675],
                             [1.067, 4.273, -6.654, 5.893],
                             [0.048, 4.273, 1.343, -2.104]])
#: Continuous-time input matrix of the batch reactor.
BATCH_REACTOR_BC = np.array([[0.0, 0.0],
                             [5.679, 0.0],
                             [1.136, -3.146],
                             [1.136, 0.0]])
#: Output matrix used in Section IV-A of the delayed-data paper.
BATCH_REACTOR_C = np.array([[1.0, 0.0, 1.0, -1.0],
                            [0.0, 1.0, 0.0, 0.0]])
#: Sampling time and measurement-noise bound of Section IV-A.
BATCH_REACTOR_TS = 0.05
BATCH_REACTOR_ETA_V = 0.05


def zoh(Ac: np.ndarray, Bc: np.ndarray, Ts: float) -> tuple[np.ndarray, np.ndarray]:
    """Zero-order-hold discretisation ``(A, B) = (e^{Ac Ts}, ∫_0^Ts e^{Ac s} ds Bc)`` (as MATLAB ``c2d``).

    Both blocks come from one matrix exponential, ``expm(Ts [[Ac, Bc], [0, 0]]) = [[A, B], [0, I]]``: the
    arithmetic of :func:`scipy.signal.cont2discrete` with ``method="zoh"`` (the same matrix, the same
    :func:`scipy.linalg.expm`, so the same bits), without importing :mod:`scipy.signal` (about a second of CPU,
    in every job that builds the batch reactor).

    Parameters
    ----------
    Ac : ndarray, shape (n, n)
        Continuous-time state matrix.
    Bc : ndarray, shape (n, m)
        Continuous-time input matrix.
    Ts : float
        Sampling time [s], positive.

    Returns
    -------
    A : ndarray, shape (n, n)
        Discrete state matrix.
    B : ndarray, shape (n, m)
        Discrete input matrix.
    """
    from scipy.linalg import expm

    Ac = np.asarray(Ac, float)
    Bc = np.asarray(Bc, float)
    if not (np.isfinite(Ts) and Ts > 0):
        raise InputError(f"the sampling time must be positive, got {Ts}", field="Ts")
    n, m = Ac.shape[0], Bc.shape[1]
    em = np.vstack((np.hstack((Ac, Bc)), np.hstack((np.zeros((m, n)), np.zeros((m, m))))))
    ms = expm(Ts * em)[:n, :]
    return ms[:, :n], ms[:, n:]


def batch_reactor_matrices(Ts: float = BATCH_REACTOR_TS) -> tuple[np.ndarray, np.ndarray]:
    """Discrete ``(A, B)`` of the batch reactor (ZOH, sampling time ``Ts``).

    Parameters
    ----------
    Ts : float, optional
        Sampling time [s] (default :data:`BATCH_REACTOR_TS`, that of Section IV-A).

    Returns
    -------
    A : ndarray, shape (4, 4)
        Discrete state matrix.
    B : ndarray, shape (4, 2)
        Discrete input matrix.
    """
    return zoh(BATCH_REACTOR_AC, BATCH_REACTOR_BC, Ts)


def batch_reactor(Ts: float = BATCH_REACTOR_TS, eta_v: float = BATCH_REACTOR_ETA_V) -> AffineSystem:
    r"""The batch reactor of Section IV-A: ZOH at ``Ts``, printed ``C``, ``W = ∅``, ``V = I``, bound ``eta_v``.

    Rosenbrock's unstable batch reactor :math:`\dot x = A_c x + B_c u`
    (:data:`BATCH_REACTOR_AC`, :data:`BATCH_REACTOR_BC`) discretised with a
    zero-order hold, :math:`A = e^{A_c T_s}`,
    :math:`B = \int_0^{T_s} e^{A_c s}\,ds\,B_c` (as MATLAB's ``c2d``), with
    the output matrix :data:`BATCH_REACTOR_C` printed in Section IV-A of the
    delayed-data paper (Hassaan, Shen, Yong), no process noise and
    measurement noise :math:`V = I`, :math:`\|v\|_\infty \le \eta_v`.

    Parameters
    ----------
    Ts : float, optional
        Sampling time [s] (Section IV-A: 0.05).
    eta_v : float, optional
        Measurement-noise bound (Section IV-A: 0.05, five standard
        deviations of ``v ~ N(0, 0.01²)``).

    Returns
    -------
    AffineSystem
        ``n = 4``, ``p = 2``, ``m = 2`` and no process-noise columns
        (``E`` of shape ``(4, 0)``, ``eta_w = 0``).

    Raises
    ------
    InputError
        If ``Ts`` is not a positive number.

    Examples
    --------
    >>> import eqrec
    >>> reactor = eqrec.batch_reactor()
    >>> reactor.n, reactor.p, reactor.m, reactor.E.shape, reactor.eta_w
    (4, 2, 2, (4, 0), 0.0)
    >>> import numpy as np, scipy.linalg as sla  # A = exp(Ac Ts), the zero-order hold
    >>> bool(np.allclose(reactor.A, sla.expm(eqrec.systems.examples.BATCH_REACTOR_AC * 0.05)))
    True
    """
    A, B = batch_reactor_matrices(Ts)
    return AffineSystem(A=A, B=B, C=BATCH_REACTOR_C.copy(), E=np.zeros((4, 0)), eta_w=0.0, eta_v=eta_v,
                        V=np.eye(2), name="batch reactor")


def discretisation_gaps(printed_A, printed_B, Ts: float = BATCH_REACTOR_TS) -> dict[str, float]:
    """Largest entrywise gaps between printed ``A``, ``B`` and the ZOH discretisation at ``Ts``.

    Parameters
    ----------
    printed_A : array_like, shape (4, 4)
        State matrix as printed (four decimals).
    printed_B : array_like, shape (4, 2)
        Input matrix as printed.
    Ts : float, optional
        Sampling time [s] of the discretisation (default :data:`BATCH_REACTOR_TS`).

    Returns
    -------
    dict of str to float
        ``{"A": max |A_zoh - A_printed|, "B": max |B_zoh - B_printed|,
        "A_rel_digit": ..., "B_rel_digit": ...}``; the ``*_rel_digit`` values
        are the gaps in units of the printed rounding step ``5e-5`` (four
        decimals): a value ``<= 1`` means the printed matrix is the
        discretisation rounded.
    """
    A, B = batch_reactor_matrices(Ts)
    pa, pb = np.asarray(printed_A, float), np.asarray(printed_B, float)
    if pa.shape != A.shape or pb.shape != B.shape:
        raise InputError(f"printed matrices must have shapes {A.shape} and {B.shape}, got {pa.shape}, {pb.shape}")
    gA, gB = float(np.abs(A - pa).max()), float(np.abs(B - pb).max())
    return {"A": gA, "B": gB, "A_rel_digit": gA / 5e-5, "B_rel_digit": gB / 5e-5}

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

    Raises
    ------
    InputError
        ``m``, ``k1`` or ``Ts`` not a positive number, ``k0`` not one ``>= 0``, or malformed noise bounds
        (the field is named).

    Examples
    --------
    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> acc.A.shape, acc.C.shape, acc.E.shape
    ((3, 3), (2, 3), (3, 1))
    >>> acc.eta_w, acc.eta_v
    (0.1, 0.05)
    """
    m, k1, Ts = positive(m, "m"), positive(k1, "k1"), positive(Ts, "Ts")
    k0 = positive(k0, "k0", zero_ok=True)
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


#: The two-cart plant of :func:`two_mass` (SI units; ``eta_w`` per velocity channel).
TWO_MASS_CONSTANTS = {"m1": 1.0, "m2": 1.0, "k": 1.0, "c": 0.02, "Ts": 0.1, "eta_w": (0.01, 0.02), "eta_v": 0.05}


def two_mass(m1: float = 1.0, m2: float = 1.0, k: float = 1.0, c: float = 0.02, Ts: float = 0.1,
             eta_w=(0.01, 0.02), eta_v: float = 0.05) -> AffineSystem:
    r"""Two carts coupled by a lightly damped spring, only the first position measured (a user's kind of plant).

    States :math:`x = (x_1, v_1, x_2, v_2)` (positions and velocities), a force ``u`` on cart 1,

    .. math::
        m_1 \dot v_1 = -k(x_1 - x_2) - c(v_1 - v_2) + u, \qquad
        m_2 \dot v_2 = k(x_1 - x_2) + c(v_1 - v_2),

    discretised with a zero-order hold at ``Ts`` (:func:`zoh`); process noise added to both velocities after
    the step, :math:`E = [e_2, e_4]` with one bound per channel (``|w_1| <= eta_w[0]``, ``|w_2| <= eta_w[1]``,
    folded into ``E`` by :class:`AffineSystem`), ``y = x_1 + v``, ``|v| <= eta_v``.  ``A`` has a double
    eigenvalue 1 (the free rigid-body motion), a lightly damped complex pair near the unit circle and negative
    entries: the hard case for set-membership estimation (``examples/two_mass.yaml`` is the same plant).

    Parameters
    ----------
    m1 : float, optional
        Mass of cart 1 [kg].
    m2 : float, optional
        Mass of cart 2 [kg].
    k : float, optional
        Spring constant [N/m].
    c : float, optional
        Damping of the spring [N s/m].
    Ts : float, optional
        Sampling time [s].
    eta_w : float or sequence of two floats, optional
        Bounds of the velocity noise (one per cart, or one for both).
    eta_v : float, optional
        Bound of the position measurement noise.

    Returns
    -------
    AffineSystem
        Named ``"two carts"``, ``n = 4``, ``p = 1``, ``m = 1``, ``nw = 2``, ``dt = Ts``.

    Raises
    ------
    InputError
        If ``Ts``, ``m1`` or ``m2`` is not a positive number, ``k`` or ``c`` not one ``>= 0``, or the noise
        bounds are malformed.

    Examples
    --------
    >>> import numpy as np
    >>> import eqrec
    >>> carts = eqrec.two_mass()
    >>> carts.n, carts.p, carts.m, carts.nw, float(carts.E[1, 0]), float(carts.E[3, 1])
    (4, 1, 1, 2, 0.01, 0.02)
    >>> bool(np.abs(np.linalg.eigvals(carts.A)).max() <= 1.0 + 1e-6)  # a double eigenvalue 1 (rounding splits it)
    True
    """
    m1, m2 = positive(m1, "m1"), positive(m2, "m2")
    k, c = positive(k, "k", zero_ok=True), positive(c, "c", zero_ok=True)
    Ac = np.array([[0.0, 1.0, 0.0, 0.0],
                   [-k / m1, -c / m1, k / m1, c / m1],
                   [0.0, 0.0, 0.0, 1.0],
                   [k / m2, c / m2, -k / m2, -c / m2]])
    Bc = np.array([[0.0], [1.0 / m1], [0.0], [0.0]])
    A, B = zoh(Ac, Bc, Ts)
    E = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 0.0], [0.0, 1.0]])
    return AffineSystem(A=A, B=B, C=[[1.0, 0.0, 0.0, 0.0]], E=E, eta_w=list(np.broadcast_to(eta_w, (2,))),
                        eta_v=eta_v, name="two carts", dt=Ts)


def tank_chain(n: int, p: int, a: float = 0.2, leak: float = 0.05, eta_w: float = 0.01,
               eta_v: float = 0.02) -> AffineSystem:
    r"""A chain of ``n`` coupled tanks: level ``i`` exchanges ``a`` times the difference with its neighbours, the
    last tank leaks ``leak`` of its level, the input flows into tank 1.

    .. math::
        x_i(k+1) = x_i(k) + a\,(x_{i-1}(k) - x_i(k)) + a\,(x_{i+1}(k) - x_i(k)) + w_i(k)
        \ (\text{minus } \mathrm{leak}\cdot x_n(k) \text{ for } i = n), \qquad y = C x + v,

    with process noise on every level (``E = I``, ``|w| <= eta_w``) and ``p`` level sensors: the last tank when
    ``p = 1`` (the furthest from the inflow), else spread evenly along the chain with the first and the last
    among them (``|v| <= eta_v``).  Slow modes and few sensors at any size: the plant of the scale benchmarks
    (``benchmarks/bench_zonotope.py``) and of the tests at larger ``n``.

    Parameters
    ----------
    n : int
        Number of tanks, ``>= 1``.
    p : int
        Number of level sensors, ``1..n``.
    a : float, optional
        Exchange rate between neighbours per step.
    leak : float, optional
        Leak rate of the last tank per step.
    eta_w, eta_v : float, optional
        Bounds of the process and measurement noise.

    Returns
    -------
    AffineSystem
        Named ``"tanks{n}"``, ``m = 1``, ``nw = n``.

    Raises
    ------
    InputError
        If ``n`` or ``p`` is out of range, or a rate or bound is not a number ``>= 0``.

    Examples
    --------
    >>> from eqrec.systems.examples import tank_chain
    >>> plant = tank_chain(6, 2)
    >>> plant.n, plant.p, plant.m, [int(i) for i in plant.C.argmax(axis=1)]
    (6, 2, 1, [0, 5])
    """
    n = integer(n, "n", low=1)
    p = integer(p, "p", low=1, high=n)
    a, leak = positive(a, "a", zero_ok=True), positive(leak, "leak", zero_ok=True)
    A = np.eye(n)
    for i in range(n - 1):
        A[i, i] -= a
        A[i + 1, i + 1] -= a
        A[i, i + 1] += a
        A[i + 1, i] += a
    A[-1, -1] -= leak
    sensors = np.unique(np.round(np.linspace(0, n - 1, p)).astype(int)) if p > 1 else np.array([n - 1])
    B = np.zeros((n, 1))
    B[0, 0] = 1.0
    return AffineSystem(A=A, C=np.eye(n)[sensors], E=np.eye(n), eta_w=eta_w, eta_v=eta_v, B=B, name=f"tanks{n}")
