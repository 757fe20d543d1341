"""System files: an :class:`~eqrec.systems.affine.AffineSystem` from a mapping or a YAML file.

The keys are the parameters of :class:`~eqrec.systems.affine.AffineSystem`
(plus ``name``) and an optional horizon ``T``; every entry is checked to be
a finite number of a size the double-precision design LPs solve reliably.
"""

from __future__ import annotations

import difflib
import os
from pathlib import Path
from typing import Any

import numpy as np

from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError

SYSTEM_KEYS = {"A", "C", "E", "eta_w", "eta_v", "T", "B", "f", "V", "name", "gaussian"}

#: Largest magnitude of a matrix entry or noise bound read from a file, and the smallest
#: nonzero noise bound. The design LPs are solved in double precision with absolute
#: tolerances near 1e-9 (and HiGHS treats coefficients above 1e15 as errors), and the
#: stacked matrices multiply entries over T steps; data outside this range should be
#: rescaled (change the units of the states and outputs).
MAX_DATA_MAGNITUDE = 1e6
MIN_NOISE_BOUND = 1e-6


def system_from_mapping(data: Any, source: str = "<mapping>") -> tuple[AffineSystem, int | None]:
    """Build a system from a mapping (e.g. parsed YAML).

    Parameters
    ----------
    data : dict
        The fields ``A, C, E, eta_w, eta_v`` (required) and the optional ones
        of ``SYSTEM_KEYS``; every leaf a finite number.
    source : str, optional
        Where the mapping came from (a file name), for error messages.

    Returns
    -------
    system : AffineSystem
    T : int or None
        The optional horizon ``T`` of the file.
    """
    if not isinstance(data, dict):
        raise InputError("top level must be a mapping with keys A, C, E, eta_w, eta_v", source)
    unknown = sorted(set(data) - SYSTEM_KEYS, key=str)
    for key in ("A", "C", "E", "eta_w", "eta_v"):
        if key not in data:
            # a misspelt key (eta_W, Eta_w) is the usual cause: name it with the missing one
            near = [k for k in unknown if str(k).lower() == key.lower()] or \
                difflib.get_close_matches(key, [str(k) for k in unknown], n=1)
            also = f"; unknown field(s) {unknown}" if unknown else ""
            hint = f" (keys are case-sensitive: write {key!r}, not {near[0]!r})" if near else ""
            raise InputError(f"missing required field{also}{hint}", source, key)
    if unknown:
        raise InputError(f"unknown field(s) {unknown}; allowed: {sorted(SYSTEM_KEYS)}", source)

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
    for key in ("eta_w", "eta_v"):  # a number, or a flat list of numbers: one bound per noise channel
        check_numbers(data[key], key)
        bounds = data[key] if isinstance(data[key], list) else [data[key]]
        if any(isinstance(b, list) for b in bounds):
            raise InputError("must be a number or a flat list of numbers (one bound per noise channel)", source, key)
        for bound in bounds:
            if 0 < bound < MIN_NOISE_BOUND:
                raise InputError(f"noise bound {bound:g} is below {MIN_NOISE_BOUND:g} (use 0 for no noise), "
                                 "beyond what the double-precision design LPs solve reliably; rescale the units "
                                 "of the states and outputs", source, key)
    T = data.get("T")
    if T is not None:
        if isinstance(T, bool) or not isinstance(T, int) or T < 1:
            raise InputError(f"must be a positive integer, got {T!r}", source, "T")
    sys = AffineSystem(A=data["A"], C=data["C"], E=data["E"], eta_w=data["eta_w"], eta_v=data["eta_v"],
                       B=data.get("B"), f=data.get("f"), V=data.get("V"),
                       name=_name(data.get("name", Path(source).stem), source), source=source)
    return sys, T


def load_system(path: str | Path) -> tuple[AffineSystem, int | None]:
    """Read a system YAML file (keys ``A, C, E, eta_w, eta_v`` and optional ``T, B, f, V``).

    The keys are the parameters of :class:`AffineSystem` (plus ``name``,
    default the file's stem) and an optional horizon ``T``; ``eta_w`` and
    ``eta_v`` are numbers or lists of one bound per noise channel
    (``eta_w: [1, 0.5, 2]`` means ``|w_i| <= eta_w[i]``).  Unquoted
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
        A path that is not a path, a missing, unreadable or binary file, a
        directory, invalid YAML, a missing, unknown or malformed field (the
        message names the file and the field).
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

    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"a system file is a path (str or pathlib.Path), got {type(path).__name__}", field="path")
    path = Path(path)
    if path.is_dir():
        raise InputError("is a directory, not a system file", str(path))
    if not path.is_file():
        raise InputError("file not found", str(path))
    try:
        data = yaml.load(path.read_text(), Loader=_Loader)  # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        raise InputError(f"not valid YAML ({exc})", str(path)) from None
    except (OSError, UnicodeDecodeError) as exc:  # unreadable, or not a text file
        raise InputError(f"cannot read the file ({exc})", str(path)) from None
    return system_from_mapping(data, str(path))


def _name(value: object, source: str) -> str:
    """The system's ``name``: a string (a list or a number is a malformed file, not a name)."""
    if not isinstance(value, str):
        raise InputError(f"must be a string, got {type(value).__name__} {value!r:.60}", source, "name")
    return value
