r"""python-control interop: a ``control.StateSpace`` in, the designed estimator out as an I/O system.

Requires the optional extra ``pip install -e ".[control]"`` (python-control).

* :func:`system_from_statespace` turns a discrete-time ``control.StateSpace``
  ``x(t+1) = A x + B u``, ``y = C x`` with the noise gains and bounds of the
  papers' model (``+ E w``, ``+ V v``, ``|w|∞ <= η_w``, ``|v|∞ <= η_v``) into an
  :class:`eqrec.systems.affine.AffineSystem`.
* :func:`estimator_iosys` turns a class-engine design into a discrete-time
  ``control.NonlinearIOSystem`` usable with ``control.input_output_response``:
  inputs ``u`` (m), ``y`` (p) and ``arrived`` (1: the measurement of this
  time arrived, 0: lost), outputs the estimate ``xhat`` (n) and its guarantee
  ``bound`` (1).  Its state is everything the class-form estimator
  :math:`\hat x(d) = \bar x(d) + K_{(d,S)}(y_S - \bar y_S)` keeps within a
  period: the noise-free prediction :math:`\bar x` (n), the innovations
  :math:`y(\tau) - C\bar x(\tau)` of the period (T·p), which measurements
  arrived (T) and the time in the period (1); every ``T`` steps it restarts
  from its estimate (periodic reuse).  A signal carries one ``y`` per time,
  so this form covers missing-data languages (on time or lost); late
  packets need :meth:`eqrec.design.result.Design.estimator`.  A weighted
  design (``state_weights``) runs in ``z = W x`` inside and takes and gives
  the original state ``x``, as :class:`eqrec.design.weighted.WeightedEstimator`.

**One step apart.**  Column ``k`` of the response's ``xhat`` output is
``x̂(k)``, computed from the data of times ``0..k-1`` (an output of the state
at ``k``); :meth:`GuaranteedEstimator.step <eqrec.estimators.guaranteed.GuaranteedEstimator.step>`
called with the data of time ``k`` returns ``x̂(k+1)``.  So the ``k``-th
value returned by ``step`` (counting from 0) equals column ``k + 1`` of the
response, and column 0 is ``x̂(0)`` itself.
"""

from __future__ import annotations

import numpy as np

from eqrec.checks import instance, positive
from eqrec.arrivals.packets import check_estimate
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


def _control():
    try:
        import control
    except ImportError as exc:  # pragma: no cover - exercised only without the extra
        raise InputError('python-control is not installed: pip install -e ".[control]"') from exc
    return control


def system_from_statespace(ss, *, eta_w: float, eta_v: float, E=None, V=None, f=None,
                           name: str | None = None) -> AffineSystem:
    """An :class:`AffineSystem` from a discrete-time ``control.StateSpace`` and the noise bounds.

    Parameters
    ----------
    ss : control.StateSpace
        Discrete time (``ss.dt`` true or positive), ``D = 0`` (the papers'
        output ``y = C x + V v`` has no feedthrough of ``u``).
    eta_w, eta_v : float
        Bounds of the process and measurement noise (infinity norm).
    E, V : array_like, optional
        Noise gains (default: ``E = I_n``, ``V = I_p``).
    f : array_like, optional
        Constant affine term of the state equation.
    name : str or None, optional
        Name of the system (default ``"python-control system"``).

    Returns
    -------
    AffineSystem
        The model of eq. (3) of the prefix-based paper with these matrices.

    Raises
    ------
    InputError
        A continuous-time system (discretise it first, e.g. ``control.c2d``),
        a nonzero ``D``, or bad noise bounds or gains (as :class:`AffineSystem`).
    """
    control = _control()
    if not isinstance(ss, control.StateSpace):
        raise InputError(f"expected a control.StateSpace, got {type(ss).__name__}", field="ss")
    if ss.dt is None or ss.dt is False or (not isinstance(ss.dt, bool) and ss.dt == 0):
        raise InputError("the StateSpace is continuous-time (dt = 0 or None): discretise it first, "
                         "e.g. control.c2d(sys, Ts)", field="dt")
    A, B, C, D = (np.asarray(m, float) for m in (ss.A, ss.B, ss.C, ss.D))
    if np.any(D != 0):
        raise InputError("D must be zero: the model y = C x + V v has no feedthrough of u", field="D")
    # E, V, f and the bounds are checked by AffineSystem (the field is named; V and f default to I and 0)
    return AffineSystem(A=A, B=B, C=C, E=np.eye(A.shape[0]) if E is None else E, eta_w=eta_w, eta_v=eta_v, V=V,
                        f=f, name=name or "python-control system", dt=None if ss.dt is True else float(ss.dt))


def estimator_iosys(design, *, name: str = "eqrec_estimator", dt: "float | bool | None" = None,
                    strict: bool = True):
    """The class-form estimator of a class-engine design as a discrete-time ``control.NonlinearIOSystem``.

    Parameters
    ----------
    design : eqrec.design.result.Design
        A design of the class engine (``design.class_gains`` set), weighted
        (``state_weights``) or not: ``x̂`` is always in the original state, the
        bound on ``max_i w_i |x_i − x̂_i|`` for a weighted one.
    name : str, optional
        Name of the returned I/O system.
    dt : float, True or None, optional
        Sampling time of the I/O system (``None``: the plant's ``dt`` when the
        system came from :func:`system_from_statespace`, else ``True``).
    strict : bool, optional
        ``True`` (the default and the only value): arrivals outside the language raise.  Outside the
        language ``design.estimator(strict=False)`` carries the exact error set, a zonotope whose number
        of generators varies, and a set-membership fallback: no fixed-size I/O state holds them, so
        ``False`` is refused (run ``design.estimator(strict=False)``).

    Returns
    -------
    control.NonlinearIOSystem
        Inputs ``u[i]``, ``y[j]``, ``arrived``; outputs ``xhat[k]``, ``bound``.
        Output column ``k`` is ``x̂(k)`` and its bound, from the inputs of
        times ``0..k-1``: one step behind ``design.estimator().step``, whose
        call with the data of time ``k`` returns ``x̂(k+1)`` (module docstring).
        The initial state for an initial estimate ``x̂(0)`` is
        ``sys.initial_state(xhat0)`` (an attribute set on the returned system).
        ``arrived`` must be 0 or 1 exactly; ``y`` is not read when it is 0;
        ``u`` and an arrived ``y`` must be finite.  Give a lost packet a
        finite ``y`` (e.g. 0), not NaN: ``control.input_output_response``
        interpolates the input array, and ``0 · NaN`` would reach the
        neighbouring samples (refused there with :class:`InputError`).

    Raises
    ------
    InputError
        A design without class gains, a ``dt`` that is not ``True`` or a positive number, a ``name`` that is not
        a string; during a simulation, ``arrived`` other
        than 0 or 1, NaN/inf in ``u`` or in an arrived ``y``, or arrivals
        outside the design's language.
    """
    control = _control()
    gains = getattr(design, "class_gains", None)
    if dt is not None and dt is not True:
        positive(dt, "dt")
    instance(name, str, "name")
    if gains is None:
        raise InputError("estimator_iosys needs a class-engine design (design_prefix or design_delay); "
                         "for other designs use design.estimator()", field="design")
    weights = getattr(design, "state_weights", None)  # the state inside is z = W x; x̂ = ẑ / w outside
    if strict is not True:
        raise InputError(f"estimator_iosys runs inside the language only (strict=True), got strict={strict!r}: "
                         "outside it, run design.estimator(strict=False), which carries the exact error set",
                         field="strict")
    system, cert = design.system, design.class_certificate
    classes = gains.classes
    n, p, m, T = system.n, system.p, system.m, classes.horizon
    ix_bar, ix_inn = slice(0, n), slice(n, n + T * p)
    ix_arr, ix_t = slice(n + T * p, n + T * p + T), n + T * p + T

    def unpack(x):
        t = int(round(x[ix_t]))
        return x[ix_bar], x[ix_inn].reshape(T, p), x[ix_arr] > 0.5, t

    def level(t, S):
        return design.mu1 if t == 0 else float(cert.levels[classes.index(t, S)])

    def estimate(xbar, innov, arrived, t):
        """x̂(t) and its bound from the state at the start of step t."""
        if t == 0:
            return xbar.copy(), design.mu1
        S = tuple(int(i) for i in np.flatnonzero(arrived[:t]))
        try:
            xhat = gains.estimate(t, S, xbar, innov[list(S)])
        except InputError:
            raise InputError(f"the measurements {list(S)} of the first {t} steps of a period are not an arrival "
                             "pattern of the design's language (design.estimator(strict=False) keeps an exact "
                             "bound outside it)", field="arrived") from None
        return xhat, level(t, S)

    def checked(t, u):
        uu, y, got = u[:m], u[m:m + p], u[m + p]
        if got not in (0.0, 1.0):
            raise InputError(f"arrived must be 0 or 1, got {got!r} at period step {t}", field="arrived")
        if not np.all(np.isfinite(uu)):
            raise InputError(f"the input u contains NaN or infinite entries at period step {t}: {uu.tolist()}",
                             field="u")
        if got and not np.all(np.isfinite(y)):
            raise InputError(f"an arrived measurement y contains NaN or infinite entries at period step {t}: "
                             f"{y.tolist()} (control.input_output_response interpolates its input array, so a NaN "
                             "in a lost packet's y reaches the neighbouring samples: give lost packets a finite y, "
                             "e.g. 0)", field="y")
        return uu, y, bool(got)

    def update(_t, x, u, _params):
        x = np.asarray(x, float)
        xbar, innov, arrived, t = unpack(x)
        innov, arrived = innov.copy(), arrived.copy()
        uu, y, got = checked(t, np.asarray(u, float))
        if got:
            innov[t] = y - system.C_at(t) @ xbar
            arrived[t] = True
        nxt = system.A_at(t) @ xbar + system.B_at(t) @ uu + system.f
        if t + 1 == T:  # period end: restart from the estimate of time T
            xhat_T, _ = estimate(nxt, innov, arrived, T)
            return start(xhat_T)
        return np.concatenate([nxt, innov.reshape(-1), arrived.astype(float), [t + 1]])

    def output(_t, x, _u, _params):
        x = np.asarray(x, float)
        xhat, bound = estimate(*unpack(x))
        return np.concatenate([xhat if weights is None else xhat / weights, [bound]])

    def start(zhat):  # the state at a period's start, from the estimate inside (ẑ = W x̂ for a weighted design)
        return np.concatenate([zhat, np.zeros(T * p + T), [0.0]])

    def initial_state(xhat0):
        xhat0 = check_estimate(xhat0, n)
        return start(xhat0 if weights is None else weights * xhat0)

    if dt is None:
        dt = system.dt or True
    outputs = [f"xhat[{k}]" for k in range(n)] + ["bound"]
    sys_io = control.nlsys(update, output, dt=dt, name=name,
                           inputs=[f"u[{i}]" for i in range(m)] + [f"y[{j}]" for j in range(p)] + ["arrived"],
                           outputs=outputs, states=n + T * p + T + 1)
    sys_io.initial_state = initial_state
    return sys_io
