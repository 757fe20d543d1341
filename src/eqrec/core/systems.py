"""Affine discrete-time systems with bounded noise.

The model of eq. (3) of the prefix-based paper, with the noise gains of its
Remark 1 and of eq. (1) of the augmented paper::

    x(t+1) = A(t) x(t) + B(t) u(t) + f + E(t) w(t),   ||w(t)||_inf <= eta_w
    y(t)   = C(t) x(t) + V(t) v(t)   if q(t) = 1,     ||v(t)||_inf <= eta_v
    y(t)   = (missing)               if q(t) = 0.

Time-varying matrices are given as arrays with a leading time axis.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
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


@dataclass(frozen=True)
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
    eta_w, eta_v : float
        Infinity-norm bounds of ``w`` and ``v`` (finite, non-negative).
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

    Attributes
    ----------
    n, p, m, nw, nv : int
        State, output, input, process-noise and measurement-noise dimensions.
    horizon_limit : int or None
        Length of the time-varying data, ``None`` if time-invariant.

    Raises
    ------
    InputError
        Non-numeric, non-finite or wrongly shaped matrices, negative noise
        bounds, or time-varying matrices of different lengths.

    Examples
    --------
    >>> import eqrec
    >>> plant = eqrec.AffineSystem(A=[[1.0, 0.5], [0.0, 1.0]], C=[[1.0, 0.0]], E=[[0.0], [1.0]],
    ...                            eta_w=0.1, eta_v=0.05)
    >>> plant.n, plant.p, plant.nw, plant.nv, plant.m
    (2, 1, 1, 1, 0)
    >>> plant.V
    array([[1.]])
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

    def __post_init__(self) -> None:
        src = self.source
        A = _as_matrix(self.A, "A", src)
        C = _as_matrix(self.C, "C", src)
        E = _as_matrix(self.E, "E", src)
        n = A.shape[-1]
        if A.shape[-2] != n:
            raise InputError(f"A must be square, got shape {A.shape}", src, "A")
        if C.shape[-1] != n:
            raise InputError(f"C must have {n} columns (n = {n}), got shape {C.shape}", src, "C")
        if E.shape[-2] != n:
            raise InputError(f"E must have {n} rows (n = {n}), got shape {E.shape}", src, "E")
        p = C.shape[-2]
        V = np.eye(p) if self.V is None else _as_matrix(self.V, "V", src)
        if V.shape[-2] != p:
            raise InputError(f"V must have {p} rows (p = {p}), got shape {V.shape}", src, "V")
        B = None if self.B is None else _as_matrix(self.B, "B", src)
        if B is not None and B.shape[-2] != n:
            raise InputError(f"B must have {n} rows, got shape {B.shape}", src, "B")
        f = np.zeros(n) if self.f is None else np.asarray(self.f, dtype=float).reshape(-1)
        if f.shape != (n,):
            raise InputError(f"f must have {n} entries, got {f.size}", src, "f")
        for name in ("eta_w", "eta_v"):
            val = getattr(self, name)
            try:
                val = float(val)
            except (TypeError, ValueError):
                raise InputError("must be a number", src, name) from None
            if not np.isfinite(val) or val < 0:
                raise InputError(f"must be a finite non-negative number, got {val}", src, name)
            object.__setattr__(self, name, val)
        lengths = {arr.shape[0] for arr in (A, C, E, V) if arr.ndim == 3}
        if len(lengths) > 1:
            raise InputError(f"time-varying matrices have different horizons {sorted(lengths)}", src)
        for key, val in dict(A=A, C=C, E=E, V=V, B=B, f=f).items():
            object.__setattr__(self, key, val)

    # -- dimensions -------------------------------------------------------
    @property
    def n(self) -> int:
        """State dimension."""
        return self.A.shape[-1]

    @property
    def p(self) -> int:
        """Output dimension."""
        return self.C.shape[-2]

    @property
    def nw(self) -> int:
        """Process-noise dimension."""
        return self.E.shape[-1]

    @property
    def nv(self) -> int:
        """Measurement-noise dimension."""
        return self.V.shape[-1]

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

    def A_at(self, t: int) -> np.ndarray:
        """State matrix ``A(t)`` at time ``t``.

        Parameters
        ----------
        t : int
            Time index (ignored by a time-invariant matrix).

        Returns
        -------
        ndarray, shape (n, n)
            ``A[t]`` if ``A`` is time-varying, else ``A`` itself (not a copy).
        """
        return self._at(self.A, t)

    def C_at(self, t: int) -> np.ndarray:
        """Output matrix ``C(t)`` at time ``t``.

        Parameters
        ----------
        t : int
            Time index (ignored by a time-invariant matrix).

        Returns
        -------
        ndarray, shape (p, n)
            ``C[t]`` if ``C`` is time-varying, else ``C`` itself (not a copy).
        """
        return self._at(self.C, t)

    def E_at(self, t: int) -> np.ndarray:
        """Process-noise gain ``E(t)`` at time ``t``.

        Parameters
        ----------
        t : int
            Time index (ignored by a time-invariant matrix).

        Returns
        -------
        ndarray, shape (n, nw)
            ``E[t]`` if ``E`` is time-varying, else ``E`` itself (not a copy).
        """
        return self._at(self.E, t)

    def V_at(self, t: int) -> np.ndarray:
        """Measurement-noise gain ``V(t)`` at time ``t``.

        Parameters
        ----------
        t : int
            Time index (ignored by a time-invariant matrix).

        Returns
        -------
        ndarray, shape (p, nv)
            ``V[t]`` if ``V`` is time-varying, else ``V`` itself (not a copy).
        """
        return self._at(self.V, t)

    def B_at(self, t: int) -> np.ndarray:
        """Input matrix ``B(t)`` at time ``t``.

        Parameters
        ----------
        t : int
            Time index (ignored by a time-invariant matrix).

        Returns
        -------
        ndarray, shape (n, m)
            ``B[t]`` if ``B`` is time-varying, else ``B``; an ``(n, 0)``
            array of zeros for a system without input.
        """
        if self.B is None:
            return np.zeros((self.n, 0))
        return self._at(self.B, t)

    def check_horizon(self, T: int) -> None:
        """Raise if a time-varying system is shorter than the horizon ``T``.

        Parameters
        ----------
        T : int
            Horizon (number of steps) a design or simulation needs.

        Raises
        ------
        InputError
            If the time-varying data covers fewer than ``T`` steps.
        """
        lim = self.horizon_limit
        if lim is not None and lim < T:
            raise InputError(f"time-varying data covers {lim} steps, horizon needs {T}", self.source)

    def to_dict(self) -> dict:
        """JSON-serialisable description (matrices as nested lists).

        Returns
        -------
        dict
            Keys ``name, A, C, E, V, f, eta_w, eta_v`` and ``B`` when the
            system has an input; the keys of a system file
            (:func:`load_system`), without ``source``.
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


# ---------------------------------------------------------------------------
# The adaptive cruise control example
# ---------------------------------------------------------------------------

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


# ---------------------------------------------------------------------------
# Loading user systems
# ---------------------------------------------------------------------------

SYSTEM_KEYS = {"A", "C", "E", "eta_w", "eta_v", "T", "B", "f", "V", "name"}

#: Largest magnitude of a matrix entry or noise bound read from a file, and the smallest
#: nonzero noise bound. The design LPs are solved in double precision with absolute
#: tolerances near 1e-9 (and HiGHS treats coefficients above 1e15 as errors), and the
#: stacked matrices multiply entries over T steps; data outside this range should be
#: rescaled (change the units of the states and outputs).
MAX_DATA_MAGNITUDE = 1e6
MIN_NOISE_BOUND = 1e-6


def system_from_mapping(data: Any, source: str = "<mapping>") -> tuple[AffineSystem, int | None]:
    """Build a system from a mapping (e.g. parsed YAML).

    Returns
    -------
    system : AffineSystem
    T : int or None
        The optional horizon ``T`` of the file.
    """
    if not isinstance(data, dict):
        raise InputError("top level must be a mapping with keys A, C, E, eta_w, eta_v", source)
    for key in ("A", "C", "E", "eta_w", "eta_v"):
        if key not in data:
            raise InputError("missing required field", source, key)
    unknown = set(data) - SYSTEM_KEYS
    if unknown:
        raise InputError(f"unknown field(s) {sorted(unknown)}; allowed: {sorted(SYSTEM_KEYS)}", source)

    def check_numbers(value: Any, key: str, where: str = "") -> None:
        # every leaf a finite YAML number (no quoted numbers, booleans or nulls) of usable size
        if isinstance(value, np.ndarray):
            value = value.tolist()
        if isinstance(value, (list, tuple)):
            for i, item in enumerate(value):
                check_numbers(item, key, f"{where}[{i}]")
            return
        what = f"entry {where}" if where else "value"
        if isinstance(value, (bool, np.bool_)) or not isinstance(value, (int, float, np.integer, np.floating)):
            hint = ""
            if isinstance(value, str):
                try:
                    float(value)
                    hint = " (a quoted number is a string: remove the quotes)"
                except ValueError:
                    pass
            raise InputError(f"{what} must be a number, got {value!r}{hint}", source, key)
        if not np.isfinite(value):
            raise InputError(f"{what} must be finite, got {value!r}", source, key)
        if abs(value) > MAX_DATA_MAGNITUDE:
            raise InputError(f"{what} {value:g} exceeds {MAX_DATA_MAGNITUDE:g} in "
                             "magnitude, beyond what the double-precision design LPs solve reliably; "
                             "rescale the units of the states and outputs", source, key)

    for key in ("A", "C", "E", "B", "f", "V"):
        if data.get(key) is not None:
            check_numbers(data[key], key)
    for key in ("eta_w", "eta_v"):
        check_numbers(data[key], key)
        if 0 < data[key] < MIN_NOISE_BOUND:
            raise InputError(f"noise bound {data[key]:g} is below {MIN_NOISE_BOUND:g} (use 0 for no noise), "
                             "beyond what the double-precision design LPs solve reliably; rescale the units "
                             "of the states and outputs", source, key)
    T = data.get("T")
    if T is not None:
        if isinstance(T, bool) or not isinstance(T, int) or T < 1:
            raise InputError(f"must be a positive integer, got {T!r}", source, "T")
    sys = AffineSystem(A=data["A"], C=data["C"], E=data["E"], eta_w=data["eta_w"], eta_v=data["eta_v"],
                       B=data.get("B"), f=data.get("f"), V=data.get("V"),
                       name=str(data.get("name", Path(source).stem)), source=source)
    return sys, T


def load_system(path: str | Path) -> tuple[AffineSystem, int | None]:
    """Read a system YAML file (keys ``A, C, E, eta_w, eta_v`` and optional ``T, B, f, V``).

    The keys are the parameters of :class:`AffineSystem` (plus ``name``,
    default the file's stem) and an optional horizon ``T``.  Unquoted
    numbers in exponent notation without a dot (``1e-3``, ``5E2``) are read
    as numbers, as YAML 1.2 does (PyYAML's YAML 1.1 rules would make them
    strings); quoted numbers stay strings and are rejected naming the field.
    Entries larger than :data:`MAX_DATA_MAGNITUDE` in magnitude and nonzero
    noise bounds below :data:`MIN_NOISE_BOUND` are rejected (rescale the
    units instead).

    Parameters
    ----------
    path : str or pathlib.Path
        The YAML file.

    Returns
    -------
    system : AffineSystem
        The system, with ``source`` the file's path.
    T : int or None
        The file's horizon ``T``, ``None`` if it has none.

    Raises
    ------
    InputError
        A missing file or directory, invalid YAML, a missing, unknown or
        malformed field (the message names the file and the field).
    """
    import re

    import yaml

    class _Loader(yaml.SafeLoader):
        pass

    _Loader.yaml_implicit_resolvers = {k: list(v) for k, v in yaml.SafeLoader.yaml_implicit_resolvers.items()}
    _Loader.add_implicit_resolver(
        "tag:yaml.org,2002:float",
        re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$"),
        list("-+0123456789."))

    path = Path(path)
    if path.is_dir():
        raise InputError("is a directory, not a system file", str(path))
    if not path.is_file():
        raise InputError("file not found", str(path))
    try:
        data = yaml.load(path.read_text(), Loader=_Loader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise InputError(f"not valid YAML ({exc})", str(path)) from None
    return system_from_mapping(data, str(path))
