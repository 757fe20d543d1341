"""Affine discrete-time systems with bounded noise.

The model of eq. (3) of the prefix-based paper, with the noise gains of its
Remark 1 and of eq. (1) of the augmented paper::

    x(t+1) = A(t) x(t) + B(t) u(t) + f + E(t) w(t),   ||w(t)||_inf <= eta_w
    y(t)   = C(t) x(t) + V(t) v(t)   if q(t) = 1,     ||v(t)||_inf <= eta_v
    y(t)   = (missing)               if q(t) = 0.

Time-varying matrices are given as arrays with a leading time axis.  The
adaptive-cruise-control plant of the prefix-based paper is built in
:mod:`eqrec.systems.examples`; system files are read by :mod:`eqrec.systems.files`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from eqrec.errors import InputError


def _as_matrix(value: Any, name: str, source: str | None, ndim_ok=(2, 3)) -> np.ndarray:
    try:
        kind = np.asarray(value).dtype.kind
    except (TypeError, ValueError):  # ragged nesting: reported by the conversion below
        kind = "O"
    if kind in "USb":  # quoted numbers or booleans are not silently converted
        raise InputError("entries must be numbers, not strings or booleans", source, name)
    if kind == "c":
        raise InputError("entries must be real numbers, not complex", source, name)
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"not a numeric matrix ({exc})", source, name) from None
    if arr.ndim == 1 and 2 in ndim_ok:
        arr = arr.reshape(-1, 1) if name in ("E", "B") else arr.reshape(1, -1)
    if arr.ndim not in ndim_ok:
        raise InputError(f"expected a matrix, got an array with {arr.ndim} dimensions", source, name)
    if not np.all(np.isfinite(arr)):
        raise InputError("contains NaN or infinite entries", source, name)
    return arr


def _as_vector(value: Any, name: str, source: str | None) -> np.ndarray:
    """A finite float vector (any nesting flattened), else :class:`InputError` naming ``name``."""
    arr = _as_matrix(value, name, source, ndim_ok=(0, 1, 2))
    return arr.reshape(-1)


def _read_only(arr: np.ndarray) -> np.ndarray:
    """A read-only copy of ``arr`` (a frozen system's arrays do not change)."""
    out = np.array(arr, dtype=float)
    out.flags.writeable = False
    return out


def _noise_bound(value: Any, key: str, channels: int, what: str,
                 source: str | None) -> tuple[float, np.ndarray | None]:
    """A noise bound: a number, or one bound per channel as the scale of the channels and the bound 1.

    Returns ``(bound, None)`` for a number (or a vector whose entries are all
    equal: the same box), else ``(1.0, scale)``: the gain's columns are
    multiplied by ``scale`` so that ``|w_i| <= scale[i]`` becomes ``|w'|∞ <= 1``.
    """
    if isinstance(value, (bool, np.bool_, str)):
        raise InputError(f"must be a number or a list of numbers, got {value!r}", source, key)
    if np.ndim(value) == 0:
        try:
            bound = float(value)
        except (TypeError, ValueError):
            raise InputError(f"must be a number or a list of numbers, got {value!r}", source, key) from None
        if not np.isfinite(bound) or bound < 0:
            raise InputError(f"must be a finite non-negative number, got {bound}", source, key)
        return bound, None
    vec = _as_matrix(value, key, source, ndim_ok=(1,))
    if vec.shape != (channels,):
        raise InputError(f"one bound per noise channel: {channels} entries (the {what}), got {vec.size}",
                         source, key)
    if np.any(vec < 0):
        raise InputError(f"bounds must be non-negative, got {vec.tolist()}", source, key)
    if channels and np.all(vec == vec[0]):
        return float(vec[0]), None
    return 1.0, vec


def _time_indexed(name: str, what: str, shape: str, absent: str = ""):
    """The method ``<name>_at(t)`` of :class:`AffineSystem`: matrix ``name`` at time ``t`` (A, B, C, E, V alike)."""

    def at(self, t: int) -> np.ndarray:
        arr = getattr(self, name)
        if arr is None:  # only B may be absent
            return np.zeros((self.n, 0))
        return self._at(arr, t)

    at.__name__ = f"{name}_at"
    at.__qualname__ = f"AffineSystem.{name}_at"
    at.__doc__ = f"""{what} ``{name}(t)`` at time ``t``.

        Parameters
        ----------
        t : int
            Time index (ignored by a time-invariant matrix).

        Returns
        -------
        ndarray, shape {shape}
            ``{name}[t]`` if ``{name}`` is time-varying, else ``{name}`` itself (not a copy){absent}.
        """
    return at


@dataclass(frozen=True, init=False)
class AffineSystem:
    r"""Affine (possibly time-varying) discrete-time system with box-bounded noise.

    The plant of eq. (3) of the prefix-based paper (Rutledge, Yong, Ozay,
    ACC 2019) with the noise gains of its Remark 1 and of eq. (1) of the
    augmented paper (Hassaan, Shen, Yong, ACC 2019):

    .. math::
        x(t+1) &= A(t)\,x(t) + B(t)\,u(t) + f + E(t)\,w(t),
        \qquad \|w(t)\|_\infty \le \eta_w, \\
        y(t) &= C(t)\,x(t) + V(t)\,v(t) \ \text{if } y(t) \text{ arrives},
        \qquad \|v(t)\|_\infty \le \eta_v.

    Time-varying matrices are given as arrays with a leading time axis;
    matrices are converted to float arrays and validated on construction
    (a 1-D ``B`` or ``E`` is read as a column, any other 1-D matrix as a
    row).  Instances are frozen; matrices are read at a time ``t`` with
    :meth:`A_at`, :meth:`C_at`, ... .

    Parameters
    ----------
    A : array_like, shape (n, n) or (T, n, n)
        State matrix (a leading axis makes it time-varying).
    C : array_like, shape (p, n) or (T, p, n)
        Output matrix.
    E : array_like, shape (n, nw) or (T, n, nw)
        Process-noise gain (``W_k`` in the augmented paper); ``nw = 0``
        columns for a system without process noise.
    eta_w, eta_v : float or array_like
        Infinity-norm bounds of ``w`` and ``v`` (finite, non-negative), or
        one bound per noise channel (``|w_i| <= eta_w[i]``, one entry per
        column of ``E``; likewise ``eta_v`` and ``V``).  Per-channel bounds
        are stored as the equivalent scalar description: ``E`` becomes
        ``E diag(eta_w)`` and ``eta_w`` becomes 1 (the same noise set, so
        every design, certificate and simulation uses it unchanged); equal
        entries are the scalar bound.  The bounds as given stay readable in
        :attr:`eta_w_channels` and :attr:`eta_v_channels`.
    B : array_like, shape (n, m) or (T, n, m), optional
        Input matrix (does not enter the error dynamics); ``None``: no input.
    f : array_like, shape (n,), optional
        Affine term (does not enter the error dynamics); zero by default.
    V : array_like, shape (p, nv) or (T, p, nv), optional
        Measurement-noise gain, identity by default.
    name : str, optional
        Label used in reports (default ``"system"``).
    source : str or None, optional
        File (or other origin) of the data, named in the errors; not part of
        equality.
    dt : float or None, optional
        Sampling time in seconds, if known (kept for python-control's
        systems; not part of equality or of any design).

    Attributes
    ----------
    n, p, m, nw, nv : int
        State, output, input, process-noise and measurement-noise dimensions.
    horizon_limit : int or None
        Length of the time-varying data, ``None`` if time-invariant.
    eta_w_channels, eta_v_channels : numpy.ndarray or None
        The per-channel bounds as given (read-only, one per column of ``E``
        or ``V``), ``None`` when one bound was given.  Informative only:
        ``E`` and ``V`` already carry them (``E = E_given diag(eta_w)``,
        ``eta_w = 1``), which every computation uses; not part of equality
        nor of :meth:`to_dict` (a copy made with ``dataclasses.replace`` is
        built from the folded form and has ``None``).

    Raises
    ------
    InputError
        A missing required field (``A``, ``C``, ``E``, ``eta_w``, ``eta_v``),
        non-numeric, non-finite or wrongly shaped matrices or ``f``, negative
        or non-finite noise bounds, or time-varying matrices of different
        lengths (the field is named).

    Examples
    --------
    >>> import eqrec
    >>> plant = eqrec.AffineSystem(A=[[1.0, 0.5], [0.0, 1.0]], C=[[1.0, 0.0]], E=[[0.0], [1.0]],
    ...                            eta_w=0.1, eta_v=0.05)
    >>> plant.n, plant.p, plant.nw, plant.nv, plant.m
    (2, 1, 1, 1, 0)
    >>> plant.V
    array([[1.]])

    One bound per process-noise channel (``|w_1| <= 0.1``, ``|w_2| <= 0.5``):

    >>> plant = eqrec.AffineSystem(A=[[1.0, 0.5], [0.0, 1.0]], C=[[1.0, 0.0]], E=[[1.0, 0.0], [0.0, 1.0]],
    ...                            eta_w=[0.1, 0.5], eta_v=0.05)
    >>> plant.E, plant.eta_w
    (array([[0.1, 0. ],
           [0. , 0.5]]), 1.0)
    >>> plant.eta_w_channels, plant.eta_v_channels
    (array([0.1, 0.5]), None)
    """

    A: np.ndarray
    C: np.ndarray
    E: np.ndarray
    eta_w: float
    eta_v: float
    B: np.ndarray | None = None
    f: np.ndarray | None = None
    V: np.ndarray | None = None
    name: str = "system"
    source: str | None = field(default=None, compare=False)
    dt: float | None = field(default=None, compare=False)
    eta_w_channels: np.ndarray | None = field(default=None, init=False, compare=False, repr=False)
    eta_v_channels: np.ndarray | None = field(default=None, init=False, compare=False, repr=False)

    def __init__(self, A: Any = None, C: Any = None, E: Any = None, eta_w: Any = None, eta_v: Any = None,
                 B: Any = None, f: Any = None, V: Any = None, name: str = "system", source: str | None = None,
                 dt: Any = None):
        src = source
        if dt is not None and (isinstance(dt, bool) or not isinstance(dt, (int, float, np.floating, np.integer))
                               or not np.isfinite(dt) or dt <= 0):
            raise InputError(f"the sampling time must be a positive number of seconds, got {dt!r}", src, "dt")
        for key, value in (("A", A), ("C", C), ("E", E), ("eta_w", eta_w), ("eta_v", eta_v)):
            if value is None:
                raise InputError("missing required field (the system needs A, C, E, eta_w and eta_v)", src, key)
        A = _as_matrix(A, "A", src)
        C = _as_matrix(C, "C", src)
        E = _as_matrix(E, "E", src)
        n = A.shape[-1]
        if A.shape[-2] != n:
            raise InputError(f"A must be square, got shape {A.shape}", src, "A")
        if C.shape[-1] != n:
            raise InputError(f"C must have {n} columns (n = {n}), got shape {C.shape}", src, "C")
        if E.shape[-2] != n:
            raise InputError(f"E must have {n} rows (n = {n}), got shape {E.shape}", src, "E")
        p = C.shape[-2]
        V = np.eye(p) if V is None else _as_matrix(V, "V", src)
        if V.shape[-2] != p:
            raise InputError(f"V must have {p} rows (p = {p}), got shape {V.shape}", src, "V")
        B = None if B is None else _as_matrix(B, "B", src)
        if B is not None and B.shape[-2] != n:
            raise InputError(f"B must have {n} rows, got shape {B.shape}", src, "B")
        f = np.zeros(n) if f is None else _as_vector(f, "f", src)
        if f.shape != (n,):
            raise InputError(f"f must have {n} entries, got {f.size}", src, "f")
        eta_w, w_scale = _noise_bound(eta_w, "eta_w", E.shape[-1], "columns of E", src)
        eta_v, v_scale = _noise_bound(eta_v, "eta_v", V.shape[-1], "columns of V", src)
        if w_scale is not None:  # |w_i| <= eta_w[i]: E diag(eta_w) with |w'|_inf <= 1 is the same noise set
            E = E * w_scale
        if v_scale is not None:
            V = V * v_scale
        bounds = {"eta_w": eta_w, "eta_v": eta_v}
        lengths = {key: arr.shape[0] for key, arr in zip("ACEV", (A, C, E, V)) if arr.ndim == 3}
        if len(set(lengths.values())) > 1:  # name the first matrix whose horizon differs from the first one's
            odd = next(k for k, h in lengths.items() if h != next(iter(lengths.values())))
            raise InputError(f"time-varying matrices have different horizons {lengths}", src, odd)
        if not isinstance(name, str):
            raise InputError(f"must be a string, got {name!r}", src, "name")
        dt = None if dt is None else float(dt)
        given = {f"{key}_channels": None if scale is None else _read_only(scale)
                 for key, scale in (("eta_w", w_scale), ("eta_v", v_scale))}
        for key, val in dict(A=A, C=C, E=E, V=V, B=B, f=f, name=name, source=source, dt=dt, **bounds,
                             **given).items():
            object.__setattr__(self, key, val)

    def __eq__(self, other: object) -> bool:
        """Equal matrices (``numpy.array_equal``), bounds and name; ``source`` is not compared."""
        if not isinstance(other, AffineSystem):
            return NotImplemented
        same = (np.array_equal(getattr(self, k), getattr(other, k)) if getattr(self, k) is not None
                else getattr(other, k) is None for k in ("A", "C", "E", "B", "f", "V"))
        return all(same) and (self.eta_w, self.eta_v, self.name) == (other.eta_w, other.eta_v, other.name)

    __hash__ = None  # type: ignore[assignment]  # mutable numpy fields: not hashable (as before)

    # -- dimensions (read from the matrices) -------------------------------
    n = property(lambda self: self.A.shape[-1], doc="State dimension (int).")
    p = property(lambda self: self.C.shape[-2], doc="Output dimension (int).")
    nw = property(lambda self: self.E.shape[-1], doc="Process-noise dimension (int).")
    nv = property(lambda self: self.V.shape[-1], doc="Measurement-noise dimension (int).")

    @property
    def m(self) -> int:
        """Input dimension (0 without B)."""
        return 0 if self.B is None else self.B.shape[-1]

    @property
    def horizon_limit(self) -> int | None:
        """Length of the time-varying data, ``None`` if time-invariant."""
        for arr in (self.A, self.C, self.E, self.V):
            if arr.ndim == 3:
                return arr.shape[0]
        return None

    @property
    def is_time_varying(self) -> bool:
        """Whether any of ``A, C, E, V`` has a leading time axis."""
        return self.horizon_limit is not None

    # -- time-indexed access ---------------------------------------------
    @staticmethod
    def _at(arr: np.ndarray, t: int) -> np.ndarray:
        return arr[t] if arr.ndim == 3 else arr

    A_at = _time_indexed("A", "State matrix", "(n, n)")
    C_at = _time_indexed("C", "Output matrix", "(p, n)")
    E_at = _time_indexed("E", "Process-noise gain", "(n, nw)")
    V_at = _time_indexed("V", "Measurement-noise gain", "(p, nv)")
    B_at = _time_indexed("B", "Input matrix", "(n, m)", "; an ``(n, 0)`` array of zeros for a system without input")

    def check_horizon(self, T: int) -> None:
        """Raise if a time-varying system is shorter than the horizon ``T``.

        Parameters
        ----------
        T : int
            Horizon (number of steps) a design or simulation needs.

        Raises
        ------
        InputError
            If the time-varying data covers fewer than ``T`` steps (the field is the first time-varying matrix).
        """
        lim = self.horizon_limit
        if lim is not None and lim < T:
            name = next(k for k in "ACEV" if getattr(self, k).ndim == 3)  # the time-varying matrices share a length
            raise InputError(f"time-varying data covers {lim} steps, horizon needs {T}", self.source, name)

    def scaled(self, weights: Any) -> "AffineSystem":
        r"""The system in the weighted state ``z = W x``, ``W = diag(weights)``.

        A bound on ``‖z‖∞`` is one on ``max_i w_i |x_i|``.  The similarity transform :math:`A' = W A W^{-1}`, :math:`B' = W B`,
        :math:`C' = C W^{-1}`, :math:`E' = W E`, :math:`f' = W f` (``V`` and
        the noise bounds unchanged): the outputs are the same and the state
        error of an estimator of ``z`` is ``W`` times that of ``x``.  A state
        vector of mixed units (rad, rad/s, A) gets a meaningful infinity norm.

        Parameters
        ----------
        weights : array_like, shape (n,)
            Positive finite weight ``w_i`` of each state.

        Returns
        -------
        AffineSystem
            The transformed system (same name and source).

        Raises
        ------
        InputError
            Weights that are not ``n`` positive finite numbers (field ``state_weights``).

        Examples
        --------
        >>> import eqrec
        >>> plant = eqrec.AffineSystem(A=[[1.0, 0.5], [0.0, 1.0]], C=[[1.0, 0.0]], E=[[0.0], [1.0]],
        ...                            eta_w=0.1, eta_v=0.05)
        >>> plant.scaled([1.0, 10.0]).A
        array([[1.  , 0.05],
               [0.  , 1.  ]])
        """
        w = _as_matrix(weights, "state_weights", self.source, ndim_ok=(1,))
        if w.shape != (self.n,) or np.any(w <= 0):
            raise InputError(f"need n = {self.n} positive weights, one per state, got {w.tolist()}", self.source,
                             "state_weights")
        col = w[:, None]
        out = AffineSystem(A=self.A * col / w, C=self.C / w, E=self.E * col, eta_w=self.eta_w, eta_v=self.eta_v,
                           B=None if self.B is None else self.B * col, f=self.f * w, V=self.V, name=self.name,
                           source=self.source, dt=self.dt)
        for key in ("eta_w_channels", "eta_v_channels"):  # the noise is the same: its bounds as given too
            object.__setattr__(out, key, getattr(self, key))
        return out

    def to_dict(self) -> dict:
        """JSON-serialisable description (matrices as nested lists).

        Returns
        -------
        dict
            Keys ``name, A, C, E, V, f, eta_w, eta_v`` and ``B`` when the
            system has an input; the keys of a system file
            (:func:`eqrec.systems.files.load_system`), without ``source``.
        """
        out = {
            "name": self.name,
            "A": self.A.tolist(),
            "C": self.C.tolist(),
            "E": self.E.tolist(),
            "V": self.V.tolist(),
            "f": self.f.tolist(),
            "eta_w": self.eta_w,
            "eta_v": self.eta_v,
        }
        if self.B is not None:
            out["B"] = self.B.tolist()
        return out
