"""A design JSON written by ``eqrec design --out`` read back into a :class:`~eqrec.design.result.Design`.

The JSON (:func:`eqrec.design.report.to_json` for ``--method delay``, the command line's own record for
``prefix``, ``time`` and ``augmented``) holds everything the estimator runs on: the system as the file gave
it (``system``), the horizon ``T``, ``μ1``, ``μ2``, and the gains: one ``K`` per (time, available data) class
(``classes``, the class engine) and/or the node gains ``(F, u0)`` per designed word (``gains``), with the
certified level of each class or prefix node.  :func:`load_design` rebuilds the gains and levels exactly (JSON
numbers are written with Python's shortest round-trip ``repr``), so the loaded design's
:meth:`~eqrec.design.result.Design.estimator` gives the same estimates and bounds, bit for bit, as the design
that wrote the file.

A weighted design's JSON (``--state-weights``) holds its gains in the system file's state ``x``
(:func:`eqrec.design.report.original_coordinates`: divided by the weights); they are multiplied back here, which
may change the last bit of a gain, so its estimates agree to rounding, not bit for bit.  Class gains are
certified again from the gains alone on loading (:func:`eqrec.design.classes.gains.certify_classes`); the bound
of a class is the larger of that and the file's certified level.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_pattern
from eqrec.bounds.data_classes import ClassGains, ClassSet, DataClass
from eqrec.bounds.gains import GainRow, GainSchedule
from eqrec.design.result import Design
from eqrec.errors import InputError
from eqrec.lp.model import LPSolution
from eqrec.systems.affine import AffineSystem

#: The methods whose JSON :func:`load_design` reads.
METHODS = ("prefix", "time", "delay", "augmented")


def _need(data: dict, key: str, source: str, what: str = "") -> Any:
    if key not in data:
        raise InputError(f"missing {what or 'field'} (a design JSON of eqrec design --out has it; files written "
                         "before eqrec stored the system lack 'system' and 'T': run the design again)", source, key)
    return data[key]


def _pattern(label: str, kind: str, source: str) -> ArrivalPattern:
    return as_pattern(label, kind=kind, field_name="gains", source=source)


def _class_gains(rows: list, system: AffineSystem, T: int, weights: np.ndarray | None, data: dict,
                 source: str) -> tuple[ClassGains, np.ndarray]:
    """The class gains and the file's certified level of each class."""
    classes, K, certified = [], [], []
    try:
        for row in rows:
            available = tuple(int(i) for i in row["data"])
            classes.append(DataClass(int(row["k"]), available, bool(row["terminal"]),
                                     bool(row.get("inner", not row["terminal"])), int(row["sequences"]),
                                     int(row["nodes"])))
            gain = np.array(row["K"], dtype=float).reshape(system.n, len(available) * system.p)
            K.append(gain if weights is None else gain * weights[:, None])
            certified.append(float(row["certified"]))
    except (KeyError, TypeError, ValueError) as exc:
        raise InputError(f"a class row is malformed ({type(exc).__name__}: {exc})", source, "classes") from None
    words = data.get("words")
    n_words = words if isinstance(words, int) else len(words or ())
    class_set = ClassSet(classes=tuple(classes), horizon=T, words=int(n_words),
                         sequences=int(data.get("sequences") or 0), nodes=int(data.get("nodes") or 0),
                         source="window" if isinstance(words, int) else "tree")
    return ClassGains(class_set, K, system.n, system.p), np.array(certified)


def _schedule(gains: dict, labels: list, kind: str, system: AffineSystem, time_based: bool,
              weights: np.ndarray | None, source: str) -> GainSchedule:
    """The node gains: the rows of each designed word's stacked ``(F, u0)`` (eq. (9) of the prefix-based paper)."""
    n, p = system.n, system.p
    rows: dict[ArrivalPattern, GainRow] = {}
    designed = []
    for label in labels:
        if label not in gains:
            raise InputError(f"no gains for the designed word {label!r}", source, "gains")
        pattern = _pattern(label, kind, source)
        designed.append(pattern)
        try:
            F = np.array(gains[label]["F"], dtype=float).reshape(pattern.T * n, pattern.T * p)
            u0 = np.array(gains[label]["u0"], dtype=float).reshape(pattern.T * n)
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"the gains of {label!r} are malformed ({type(exc).__name__}: {exc})", source,
                             "gains") from None
        if weights is not None:  # back to z = W x (eqrec.design.report.original_coordinates divided them)
            row_w = np.tile(weights, pattern.T)
            F, u0 = F * row_w[:, None], u0 * row_w
        for t, prefix in enumerate(pattern.prefixes()):
            rows.setdefault(prefix, GainRow(F[t * n:(t + 1) * n, :(t + 1) * p].copy(), u0[t * n:(t + 1) * n].copy()))
    return GainSchedule(rows=rows, n=n, p=p, time_based=time_based, designed=tuple(designed))


def load_design(path: "str | os.PathLike") -> Design:
    """Read a design JSON written by ``eqrec design ... --out design.json`` back into a :class:`Design`.

    Its :meth:`~eqrec.design.result.Design.estimator` runs the same gains with the same levels as the design that
    wrote the file (module docstring): the same estimates and bounds, bit for bit (a weighted design: to
    rounding).  Methods ``prefix``, ``time``, ``delay`` and ``augmented``.  What is not needed to run the
    estimator is not rebuilt: ``solution`` holds the solver's name and status only, ``certificate`` (node
    gains' certificate) is ``None``, and the file's certified values are in ``extra``.

    Parameters
    ----------
    path : str or os.PathLike
        The JSON file.

    Returns
    -------
    Design
        With ``system`` (for a weighted design: the system in ``z = W x``, as the design entries return it),
        ``T``, ``mu1``, ``mu2``, ``patterns``, the gains (``class_gains`` and ``class_certificate``, and/or
        ``schedule``), ``levels`` and ``state_weights``.

    Raises
    ------
    InputError
        A missing or unreadable file, invalid JSON, another method, or a missing or malformed field (named;
        a file without class or node gains: a delay design too large for node gains written with
        ``--engine tree``, field ``gains``).

    Examples
    --------
    >>> import eqrec
    >>> design = eqrec.load_design("design.json")  # doctest: +SKIP
    >>> estimator = design.estimator().reset([0.0, 0.0])  # doctest: +SKIP
    """
    if not isinstance(path, (str, os.PathLike)):
        raise InputError(f"a design file is a path (str or pathlib.Path), got {type(path).__name__}", field="path")
    source = str(path)
    file = Path(path)
    if not file.is_file():
        raise InputError("file not found" + (" (a directory)" if file.is_dir() else ""), source)
    try:
        data = json.loads(file.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise InputError(f"not a readable JSON file ({exc})", source) from None
    if not isinstance(data, dict):
        raise InputError("top level must be a JSON object (eqrec design --out writes one)", source)
    method = _need(data, "method", source)
    if method not in METHODS:
        raise InputError(f"unknown method {method!r}; a design JSON has one of {list(METHODS)}", source, "method")
    spec = _need(data, "system", source)
    if not isinstance(spec, dict):
        raise InputError("must be a mapping of the system's matrices", source, "system")
    try:
        original = AffineSystem(**{k: spec.get(k) for k in ("A", "C", "E", "eta_w", "eta_v", "B", "f", "V")},
                                name=str(spec.get("name", "system")), source=source)
    except InputError as exc:
        raise InputError(f"{exc}", source, "system") from None
    weights = data.get("state_weights")
    weights = None if weights is None else np.asarray(weights, dtype=float)
    system = original if weights is None else original.scaled(weights)
    T = _need(data, "T", source)
    if isinstance(T, bool) or not isinstance(T, int) or T < 1:
        raise InputError(f"must be a positive integer, got {T!r}", source, "T")
    try:
        mu1, mu2 = float(_need(data, "mu1", source)), float(_need(data, "mu2", source))
    except (TypeError, ValueError):
        raise InputError("mu1 and mu2 must be numbers", source, "mu1") from None
    kind = "delay" if method == "delay" else "missing"
    class_gains = class_certificate = None
    if data.get("classes"):
        from eqrec.design.classes.gains import certify_classes

        class_gains, certified = _class_gains(data["classes"], system, T, weights, data, source)
        class_certificate = certify_classes(system, class_gains, mu1)
        recomputed = class_certificate.levels
        if np.any(recomputed > certified * (1 + 1e-6) + 1e-12):
            i = int(np.argmax(recomputed - certified))
            raise InputError(f"the gain of class {class_gains.classes.classes[i].label} gives worst case "
                             f"{recomputed[i]:.9g} > the file's certified level {certified[i]:.9g} (an edited file?)",
                             source, "classes")
        # the bound of a class: the file's certified level, never below what the gains give
        bounds = class_certificate.bounds
        rows = np.arange(len(certified))
        top = bounds.argmax(axis=1) if bounds.size else np.zeros(0, int)
        bounds[rows, top] = np.maximum(bounds[rows, top], certified)
    schedule = None
    gains = data.get("gains")
    if gains:
        labels = data.get("designed_words") or list(gains)
        schedule = _schedule(gains, labels, kind, system, method in ("time", "augmented"), weights, source)
    if class_gains is None and schedule is None:
        raise InputError("the file holds neither class gains ('classes') nor node gains ('gains'): write the "
                         "design with the class engine or with --node-gains", source, "gains")
    levels = {}
    for row in data.get("levels") or []:  # delay node gains: the level of every inner prefix node
        if 0 < int(row["k"]) < T:
            levels[str(row["prefix"])] = float(row["level"])
    if schedule is not None:
        patterns = schedule.designed if method != "delay" else tuple(
            _pattern(w, kind, source) for w in data.get("event_sequences") or data.get("designed_words") or ())
    else:
        words = data.get("words")
        patterns = tuple(_pattern(w, kind, source) for w in words) if isinstance(words, list) else ()
    solution = LPSolution(status=str(data.get("status", "optimal")), x=None, objective=mu2,
                          solver=str(data.get("solver", "")), iterations=0, solve_time=0.0)
    # the file's records that have a field of the design, and (extra) those that have none, as written
    fields = {k: data[k] for k in ("engine", "cost", "J", "J_certified", "worst_case_word") if k in data}
    extra = {k: data[k] for k in ("certified_mu2", "certified_terminal", "mu1_free", "L", "s0", "M", "nu")
             if k in data}
    return Design(method=method, system=system, patterns=patterns, T=T, mu1=mu1, mu2=mu2, schedule=schedule,
                  solution=solution, build_time=0.0, extra=extra, levels=levels, class_gains=class_gains,
                  class_certificate=class_certificate, state_weights=weights, loaded_from=source, **fields)
