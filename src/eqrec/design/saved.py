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
may change the last bit of a gain, so its estimates agree to rounding, not bit for bit.

A design file is input, and a file cannot lie: every design kind is certified again on loading, from the gains
and the file's system alone, as at design time (:func:`eqrec.bounds.certify.certify_design`): the class gains'
worst case of every class (:func:`eqrec.design.classes.gains.certify_classes`) and the node gains' worst case
along every designed word (:func:`eqrec.bounds.certify.certify_schedule`; a time-based or augmented design: every
word of its language).  Every stored value must equal what the gains earn, to the design-time accuracy of the
LP that wrote it (:data:`~eqrec.bounds.certify.CERT_RTOL` plus the solver's accuracy, relative to
``max(1, level, μ1)``): ``μ1`` (at least the terminal worst case), ``μ2`` (the largest inner worst case, at least
``μ1``), ``certified_mu2``, ``certified_terminal``, each class's ``certified`` and ``level`` and each prefix
node's ``level`` and ``certified``.  A value off by more is refused (:class:`~eqrec.errors.InputError` naming
the field: an edited file, or a file of another plant); one within it (round-off, a weighted design's gains
multiplied back) is raised to the exact worst case, so the loaded estimator's bound is never below its error,
exactly in floating point.  Numbers that are not finite are refused.
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
from eqrec.checks import short_label
from eqrec.errors import CertificationFailure, InputError
from eqrec.lp.model import LPSolution
from eqrec.systems.affine import AffineSystem

#: The methods whose JSON :func:`load_design` reads.
METHODS = ("prefix", "time", "delay", "augmented")
def _need(data: dict, key: str, source: str, where: str = "") -> Any:
    """``data[key]``, else an :class:`InputError` naming the field (``where.key`` inside a row)."""
    if key not in data:
        if where:
            raise InputError("missing (a design JSON of eqrec design --out has it)", source, f"{where}.{key}")
        raise InputError("missing field (a design JSON of eqrec design --out has it; files written before eqrec "
                         "stored the system lack 'system' and 'T': run the design again)", source, key)
    return data[key]


def _number(value: Any, source: str, field: str, *, positive: bool = False) -> float:
    """A finite number (``positive``: above 0) of the file, else an :class:`InputError` naming ``field``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise InputError(f"must be a number, got {short_label(repr(value))}", source, field)
    value = float(value)
    if not np.isfinite(value) or (positive and not value > 0):
        raise InputError(f"must be a finite{' positive' if positive else ''} number, got {value!r}", source, field)
    return value


def _integer(value: Any, source: str, field: str, low: int, high: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
        raise InputError(f"must be an integer {low}..{high}" + (" (the horizon T)" if high > low else "")
                         + f", got {short_label(repr(value))}", source, field)
    return value


def _finite_array(value: Any, shape: tuple, source: str, field: str) -> np.ndarray:
    """An array of finite numbers of ``shape`` (its entries in any nesting), else an :class:`InputError`."""
    try:
        arr = np.array(value, dtype=float)
    except (TypeError, ValueError) as exc:
        raise InputError(f"must be an array of numbers ({type(exc).__name__}: {exc})", source, field) from None
    if arr.size != int(np.prod(shape)):
        raise InputError(f"must have {int(np.prod(shape))} entries (shape {shape}), got {arr.size}", source, field)
    if not np.all(np.isfinite(arr)):
        raise InputError("holds a number that is not finite (nan or inf)", source, field)
    return arr.reshape(shape)


def _pattern(label: Any, kind: str, source: str, T: int, field: str = "gains") -> ArrivalPattern:
    if not isinstance(label, str):
        raise InputError(f"a word is a string, got {short_label(repr(label))}", source, field)
    if kind == "delay" and "x" in label:  # a loss-aware word (--max-lost): x is a measurement lost
        digits = as_pattern(label.replace("x", "0"), kind=kind, field_name=field, source=source)  # checks the rest
        arrivals = tuple(None if c == "x" else a for c, a in zip(label, digits.arrivals))
        pattern = ArrivalPattern(arrivals, label)
    else:
        pattern = as_pattern(label, kind=kind, field_name=field, source=source)
    if pattern.T != T:
        raise InputError(f"the word {short_label(label)!r} has length {pattern.T}, not the file's horizon T = {T}",
                         source, "T")
    return pattern


def _weights(value: Any, n: int, source: str) -> np.ndarray | None:
    if value is None:
        return None
    if not isinstance(value, list):
        raise InputError(f"must be a list of {n} positive numbers, got {short_label(repr(value))}", source,
                         "state_weights")
    weights = _finite_array(value, (n,), source, "state_weights")
    if not np.all(weights > 0):
        raise InputError(f"must be {n} positive numbers, got {weights.tolist()}", source, "state_weights")
    return weights


def _class_gains(rows: Any, system: AffineSystem, T: int, weights: np.ndarray | None, data: dict,
                 source: str) -> tuple[ClassGains, np.ndarray, np.ndarray]:
    """The class gains, and the file's certified level and level of each class."""
    if not isinstance(rows, list):
        raise InputError("must be a list of class rows", source, "classes")
    classes, K, certified, levels = [], [], [], []
    for i, row in enumerate(rows):
        where = f"classes[{i}]"
        if not isinstance(row, dict):
            raise InputError("a class row is a mapping (k, data, terminal, K, certified, level, ...)", source, where)
        for key in ("k", "data", "terminal", "K", "certified"):
            _need(row, key, source, where)
        k = _integer(row["k"], source, f"{where}.k", 1, T)  # a class of depth past T: T edited?
        if not isinstance(row["data"], list) or not all(
                isinstance(d, int) and not isinstance(d, bool) for d in row["data"]):
            raise InputError("must be a list of measurement times", source, f"{where}.data")
        available = tuple(row["data"])
        if list(available) != sorted(set(available)) or any(not 0 <= d < k for d in available):
            raise InputError(f"must be increasing times 0..{k - 1} (the data available at time k - 1), got "
                             f"{short_label(str(list(available)))}", source, f"{where}.data")
        flags = [row["terminal"], row.get("inner", not row["terminal"])]
        if not all(isinstance(f, bool) for f in flags):
            raise InputError("terminal and inner must be true or false", source, f"{where}.terminal")
        counts = [row.get("sequences", 0), row.get("nodes", 0)]
        if not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in counts):
            raise InputError("sequences and nodes must be non-negative integers", source, f"{where}.sequences")
        classes.append(DataClass(k, available, flags[0], flags[1], counts[0], counts[1]))
        gain = _finite_array(row["K"], (system.n, len(available) * system.p), source, f"{where}.K")
        K.append(gain if weights is None else gain * weights[:, None])
        certified.append(_number(row["certified"], source, f"{where}.certified"))
        levels.append(_number(row.get("level", row["certified"]), source, f"{where}.level"))
    keys = [c.key for c in classes]
    if len(set(keys)) != len(keys):
        raise InputError("a (time, available data) class is given twice", source, "classes")
    words = data.get("words")
    n_words = words if isinstance(words, int) and not isinstance(words, bool) else len(
        words if isinstance(words, list) else ())
    extra_counts = [data.get("sequences") or 0, data.get("nodes") or 0]
    if not all(isinstance(c, int) and not isinstance(c, bool) and c >= 0 for c in extra_counts):
        raise InputError("must be a non-negative integer", source, "sequences")
    class_set = ClassSet(classes=tuple(classes), horizon=T, words=int(n_words), sequences=extra_counts[0],
                         nodes=extra_counts[1], source="window" if isinstance(words, int) else "tree")
    return ClassGains(class_set, K, system.n, system.p), np.array(certified), np.array(levels)


def _schedule(gains: Any, labels: Any, kind: str, system: AffineSystem, T: int, time_based: bool,
              weights: np.ndarray | None, source: str) -> GainSchedule:
    """The node gains: the rows of each designed word's stacked ``(F, u0)`` (eq. (9) of the prefix-based paper)."""
    n, p = system.n, system.p
    if not isinstance(gains, dict):
        raise InputError("must map each designed word to its gains F and u0", source, "gains")
    if not isinstance(labels, list) or not labels:
        raise InputError("must be a non-empty list of the designed words", source, "designed_words")
    rows: dict[ArrivalPattern, GainRow] = {}
    designed = []
    for label in labels:
        if not isinstance(label, str) or label not in gains:
            raise InputError(f"no gains for the designed word {short_label(repr(label))}", source, "gains")
        pattern = _pattern(label, kind, source, T)
        designed.append(pattern)
        entry = gains[label]
        where = f"gains[{short_label(label)!r}]"
        if not isinstance(entry, dict):
            raise InputError("must be a mapping with F and u0", source, where)
        F = _finite_array(_need(entry, "F", source, where), (T * n, T * p), source, f"{where}.F")
        u0 = _finite_array(_need(entry, "u0", source, where), (T * n,), source, f"{where}.u0")
        if weights is not None:  # back to z = W x (eqrec.design.report.original_coordinates divided them)
            row_w = np.tile(weights, pattern.T)
            F, u0 = F * row_w[:, None], u0 * row_w
        for t, prefix in enumerate(pattern.prefixes()):
            rows.setdefault(prefix, GainRow(F[t * n:(t + 1) * n, :(t + 1) * p].copy(), u0[t * n:(t + 1) * n].copy()))
    return GainSchedule(rows=rows, n=n, p=p, time_based=time_based, designed=tuple(designed))


def _node_levels(data: dict, T: int, source: str) -> tuple[dict[str, float], dict[str, float]]:
    """The file's level and certified worst case of every inner prefix node (``levels``, ``0 < k < T``)."""
    rows = data.get("levels") or []
    if not isinstance(rows, list):
        raise InputError("must be a list of rows (prefix, k, level, certified)", source, "levels")
    levels, certified = {}, {}
    for i, row in enumerate(rows):
        where = f"levels[{i}]"
        if not isinstance(row, dict):
            raise InputError("a level row is a mapping (prefix, k, level, certified)", source, where)
        k = _integer(_need(row, "k", source, where), source, f"{where}.k", 0, T)
        prefix = _need(row, "prefix", source, where)
        if not isinstance(prefix, str):
            raise InputError(f"must be a string, got {short_label(repr(prefix))}", source, f"{where}.prefix")
        level = _number(_need(row, "level", source, where), source, f"{where}.level")
        if 0 < k < T:
            levels[prefix] = level
            if "certified" in row:
                certified[prefix] = _number(row["certified"], source, f"{where}.certified")
    return levels, certified


def _accuracy(data: dict) -> float:
    """How far a stored value may differ from what the gains earn: the design-time ``rtol`` of its solver."""
    from eqrec.bounds.certify import CERT_RTOL
    from eqrec.lp.solvers import SOLVER_NAMES, solver_info

    name = data.get("solver")
    known = [solver_info(s).accuracy for s in SOLVER_NAMES]
    return CERT_RTOL + (solver_info(name).accuracy if name in SOLVER_NAMES else max(known, default=0.0))


class _Recertification:
    """The checks of a loaded design against what its gains earn (module docstring), each naming its field."""

    def __init__(self, source: str, rtol: float, mu1: float) -> None:
        self.source, self.rtol, self.mu1 = source, rtol, mu1

    def off(self, stored: float, earned: float) -> bool:
        """Whether ``stored`` differs from ``earned`` by more than the design-time accuracy."""
        return abs(stored - earned) > self.rtol * max(1.0, abs(stored), abs(earned), self.mu1)

    def below(self, stored: float, earned: float) -> bool:
        """Whether ``stored`` is below ``earned`` by more than the design-time accuracy (a level that lies)."""
        return earned - stored > self.rtol * max(1.0, abs(stored), abs(earned), self.mu1)

    def refuse(self, field: str, what: str, stored: float, earned: float) -> None:
        raise InputError(f"{what}: the file says {float(stored)!r} but its gains earn {float(earned)!r} on the "
                         "file's system (an edited file, or a file of another plant?)", self.source, field)


def _recertify(design: Design, data: dict, words: list, file_classes: tuple | None,
               node_levels: tuple[dict, dict], source: str) -> None:
    """Certify a loaded design again from its gains and system alone; refuse a stored value they do not earn.

    Changes ``design`` in place (levels raised to the exact worst case where round-off left them a few ulps
    below, as :func:`eqrec.bounds.certify.certify_design` does at design time).
    """
    from eqrec.bounds.certify import certify_design, certify_schedule
    from eqrec.design.classes.gains import certify_classes

    mu1, mu2 = design.mu1, design.mu2
    check = _Recertification(source, _accuracy(data), mu1)
    system = design.system
    earned_mu2, earned_terminal = mu1, -np.inf
    try:
        cert = None if design.schedule is None else certify_schedule(system, design.schedule, words, mu1)
        cc = None if design.class_gains is None else certify_classes(system, design.class_gains, mu1)
    except InputError as exc:  # e.g. a time-varying system shorter than T
        raise InputError(str(exc).split(": ", 1)[-1] if exc.source else str(exc), source, exc.field or "T") from None
    if cc is not None:
        earned_mu2 = max(earned_mu2, cc.mu2)
        earned_terminal = max(earned_terminal, cc.terminal)
    if cert is not None:
        earned_mu2 = max(earned_mu2, cert.mu2)
        earned_terminal = max(earned_terminal, cert.terminal)
    if cc is not None:
        certified, levels = file_classes
        for i, cls in enumerate(design.class_gains.classes.classes):
            what = f"class {short_label(cls.label)}"
            if check.off(certified[i], float(cc.levels[i])):
                check.refuse(f"classes[{i}].certified", f"{what}: certified worst case", certified[i],
                             float(cc.levels[i]))
            if check.below(levels[i], float(cc.levels[i])):
                check.refuse(f"classes[{i}].level", f"{what}: level", levels[i], float(cc.levels[i]))
        # the bound of a class: the file's certified level (the design's, bit for bit), never below what the
        # gains give
        bounds = cc.bounds
        rows = np.arange(len(certified))
        top_row = bounds.argmax(axis=1) if bounds.size else np.zeros(0, int)
        bounds[rows, top_row] = np.maximum(bounds[rows, top_row], certified)
        design.class_certificate = cc
        design.class_levels = np.asarray(levels, float)
    if cert is not None:
        stored, stored_certified = node_levels
        node_bound: dict[str, float] = {}
        for wc in cert.words.values():
            for t in range(1, wc.pattern.T):
                lab = wc.pattern.prefix(t).label
                node_bound[lab] = max(node_bound.get(lab, -np.inf), float(wc.bounds[t].max()))
        for lab, level in stored.items():
            if lab not in node_bound:
                raise InputError(f"the prefix {short_label(lab)!r} is no inner node of the designed words", source,
                                 "levels")
            earned = node_bound[lab]
            what = f"prefix {short_label(lab)!r}"
            if check.below(level, earned):
                check.refuse("levels", f"{what}: level", level, earned)
            if check.off(level, max(mu1, earned)) and check.off(level, mu2):
                check.refuse("levels", f"{what}: level (max(mu1, its worst case) or the common mu2)", level,
                             max(mu1, earned))
            if lab in stored_certified and check.off(stored_certified[lab], earned):
                check.refuse("levels", f"{what}: certified worst case", stored_certified[lab], earned)
    if check.below(mu1, earned_terminal):
        check.refuse("mu1", "mu1 (at least the terminal worst case)", mu1, earned_terminal)
    if check.off(mu2, earned_mu2):
        check.refuse("mu2", "mu2 (the largest worst case before the horizon's end, at least mu1)", mu2, earned_mu2)
    for key, earned in (("certified_mu2", cert.mu2 if cert is not None else cc.mu2),
                        ("certified_terminal", cert.terminal if cert is not None else cc.terminal)):
        if data.get(key) is not None:
            stored_value = _number(data[key], source, key)
            if check.off(stored_value, earned):
                check.refuse(key, key, stored_value, earned)
    if cc is not None:  # a class level above the design's mu2 (inner) or mu1 (terminal)
        for i, cls in enumerate(design.class_gains.classes.classes):
            top = mu2 if cls.inner else mu1
            if check.below(top, file_classes[1][i]):
                raise InputError(f"class {short_label(cls.label)}: level {float(file_classes[1][i])!r} above the "
                                 f"design's {'mu2' if cls.inner else 'mu1'} = {top!r} (an edited file?)", source,
                                 f"classes[{i}].level")
    try:  # raise a value a few ulps below its worst case to it, exactly (design-time rule); checks exactness
        certify_design(design, words, rtol=check.rtol)
    except CertificationFailure as exc:
        raise InputError(f"the gains do not certify the file's levels ({exc})", source, "mu2") from None
    _check_cost(design, check)


def _check_cost(design: Design, check: "_Recertification") -> None:
    """A delay design's stored cost ``J`` (and ``J_certified``) must be the cost of its levels (and certificate)."""
    from eqrec.arrivals.prefix_tree import PrefixTree
    from eqrec.design.cost import certified_cost, class_cost, paper_cost

    if design.J is None and design.J_certified is None:
        return
    cost = design.cost or "sum"
    if design.class_gains is not None:
        classes = design.class_gains.classes
        earned = class_cost(classes, design.mu1, design.class_levels, cost)
        earned_certified = class_cost(classes, design.mu1, design.class_certificate.levels, cost)
    elif design.schedule is not None and design.patterns:
        tree = PrefixTree(design.patterns)
        earned = paper_cost(tree, design.mu1, design.levels if cost == "sum" else {"*": design.mu2}, cost)
        earned_certified = certified_cost(design, tree, cost, design.certificate)
    else:
        return
    for key, stored, value in (("J", design.J, earned), ("J_certified", design.J_certified, earned_certified)):
        if stored is not None and check.off(float(stored), float(value)):
            check.refuse(key, f"{key} (the cost of the {'certified ' if key != 'J' else ''}levels)", float(stored),
                         float(value))


def _check_class_set(class_set: ClassSet, data: dict, kind: str, T: int, source: str) -> None:
    """The file's classes must be those of its language (its words, or its ``max_delay``, ``horizon`` and
    ``max_lost``): a class dropped, added or edited is refused (a language the gains do not cover)."""
    from eqrec.design.inputs import language_classes
    from eqrec.design.delay.languages import delay_classes

    words = data.get("words")
    if "max_delay" in data and "horizon" in data:  # a --max-delay language (its listed words write a loss as x)
        try:
            expected = delay_classes(max_delay=data["max_delay"], horizon=data["horizon"],
                                     max_lost=data.get("max_lost"), force=True)
        except InputError as exc:
            raise InputError(str(exc).split(": ", 1)[-1], source, exc.field) from None
    elif isinstance(words, list) and words:
        expected = language_classes([_pattern(w, kind, source, T, "words") for w in words], kind=kind,
                                    field_name="words")
    else:  # a class set of Python (Design.save of delay_classes): its language is not named in the file
        return
    have = {c.key: c for c in class_set.classes}
    want = {c.key: c for c in expected.classes}
    missing = [c for key, c in want.items() if key not in have]
    extra = [c for key, c in have.items() if key not in want]
    if missing or extra:
        what = (f"the class {short_label(missing[0].label)} of the language is missing" if missing
                else f"the class {short_label(extra[0].label)} is no class of the language")
        raise InputError(f"{what} ({len(missing)} missing, {len(extra)} extra): the classes do not cover the "
                         "file's words (an edited file?)", source, "classes")


def load_design(path: "str | os.PathLike") -> Design:
    """Read a design JSON written by ``eqrec design ... --out design.json`` back into a :class:`Design`, certified.

    Its :meth:`~eqrec.design.result.Design.estimator` runs the same gains with the same levels as the design that
    wrote the file (module docstring): the same estimates and bounds, bit for bit (a weighted design: to
    rounding).  Methods ``prefix``, ``time``, ``delay`` and ``augmented``; files of
    :meth:`~eqrec.design.result.Design.save` and of the command line alike.  Every design kind is certified
    again from its gains and the file's system alone, and every stored level, ``μ1`` and ``μ2`` must equal what
    the gains earn (module docstring).  What is not needed to run the estimator is not rebuilt: ``solution``
    holds the solver's name and status only, and the file's other certified values are in ``extra``.

    Parameters
    ----------
    path : str or os.PathLike
        The JSON file.

    Returns
    -------
    Design
        With ``system`` (for a weighted design: the system in ``z = W x``, as the design entries return it),
        ``T``, ``mu1``, ``mu2``, ``patterns``, the gains (``class_gains`` and ``class_certificate``, and/or
        ``schedule`` and its ``certificate``), ``levels`` and ``state_weights``.

    Raises
    ------
    InputError
        A missing or unreadable file, invalid JSON, another method, a missing or malformed field, a number that
        is not finite, or a stored level, ``μ1`` or ``μ2`` that the gains do not earn on the file's system (the
        field named; a file without class or node gains: a delay design too large for node gains written with
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
    except (OSError, UnicodeDecodeError, json.JSONDecodeError, RecursionError) as exc:
        raise InputError(f"not a readable JSON file ({type(exc).__name__}: {exc})", source) from None
    if not isinstance(data, dict):
        raise InputError("top level must be a JSON object (eqrec design --out writes one)", source)
    method = _need(data, "method", source)
    if method not in METHODS:
        raise InputError(f"unknown method {short_label(repr(method))}; a design JSON has one of {list(METHODS)}",
                         source, "method")
    spec = _need(data, "system", source)
    if not isinstance(spec, dict):
        raise InputError("must be a mapping of the system's matrices", source, "system")
    try:
        original = AffineSystem(**{k: spec.get(k) for k in ("A", "C", "E", "eta_w", "eta_v", "B", "f", "V")},
                                name=str(spec.get("name", "system")), source=source)
    except InputError as exc:
        raise InputError(f"{exc}", source, "system") from None
    weights = _weights(data.get("state_weights"), original.n, source)
    system = original if weights is None else original.scaled(weights)
    T = _need(data, "T", source)
    if isinstance(T, bool) or not isinstance(T, int) or T < 1:
        raise InputError(f"must be a positive integer, got {short_label(repr(T))}", source, "T")
    if system.horizon_limit is not None and T > system.horizon_limit:
        raise InputError(f"T = {T} but the system's time-varying matrices cover {system.horizon_limit} steps",
                         source, "T")
    mu1 = _number(_need(data, "mu1", source), source, "mu1", positive=True)
    mu2 = _number(_need(data, "mu2", source), source, "mu2", positive=True)
    kind = "delay" if method == "delay" else "missing"
    class_gains = file_classes = None
    if data.get("classes"):
        class_gains, certified, class_levels = _class_gains(data["classes"], system, T, weights, data, source)
        file_classes = (certified, class_levels)
        if method in ("prefix", "delay"):  # a time-based design's classes are those of its worst-case word
            _check_class_set(class_gains.classes, data, kind, T, source)
    schedule = None
    gains = data.get("gains")
    if gains:
        labels = data.get("designed_words") or (list(gains) if isinstance(gains, dict) else None)
        schedule = _schedule(gains, labels, kind, system, T, method in ("time", "augmented"), weights, source)
    if class_gains is None and schedule is None:
        raise InputError("the file holds neither class gains ('classes') nor node gains ('gains'): write the "
                         "design with the class engine or with --node-gains", source, "gains")
    levels, certified_levels = _node_levels(data, T, source)
    words = data.get("words")
    if words is not None and not (isinstance(words, list) or (isinstance(words, int) and not isinstance(words, bool)
                                                              and words >= 0)):
        raise InputError("must be the list of the language's words (or their number)", source, "words")
    if schedule is not None:
        if method == "delay":
            sequences = data.get("event_sequences") or data.get("designed_words") or ()
            if not isinstance(sequences, (list, dict)):
                raise InputError("must be the designed event sequences", source, "event_sequences")
            patterns = tuple(_pattern(w, kind, source, T, "event_sequences") for w in sequences)
        else:
            patterns = schedule.designed
            if isinstance(words, list):
                listed = {_pattern(w, kind, source, T, "words").label for w in words}
                if method == "prefix" and listed != {pat.label for pat in patterns}:
                    raise InputError("must be the words the gains are designed for (the keys of 'gains'), got "
                                     f"{short_label(str(sorted(listed)))}", source, "words")
    elif isinstance(words, list) and "max_delay" not in data:
        patterns = tuple(_pattern(w, kind, source, T, "words") for w in words)
    else:  # no words, or a --max-delay language's (a loss written x): its classes are checked against it
        patterns = ()
    # what the gains are certified on: the designed words, and a time-based or augmented design's language
    certified_words = list(patterns)
    if schedule is not None and method in ("time", "augmented") and isinstance(words, list):
        certified_words = sorted(set(patterns) | {_pattern(w, kind, source, T, "words") for w in words},
                                 key=lambda pat: pat.label)
    solution = LPSolution(status=str(data.get("status", "optimal")), x=None, objective=mu2,
                          solver=str(data.get("solver", "")), iterations=0, solve_time=0.0)
    fields = _record_fields(data, source)
    extra = {k: data[k] for k in ("certified_mu2", "certified_terminal", "mu1_free", "L", "s0", "M", "nu")
             if k in data}
    design = Design(method=method, system=system, patterns=patterns, T=T, mu1=mu1, mu2=mu2, schedule=schedule,
                    solution=solution, build_time=0.0, extra=extra, levels=levels, class_gains=class_gains,
                    state_weights=weights, loaded_from=source, **fields)
    _recertify(design, data, certified_words, file_classes, (levels, certified_levels), source)
    return design


def _record_fields(data: dict, source: str) -> dict:
    """The file's records that have a field of the design (``engine``, ``cost``, ``J``, ...), checked."""
    fields = {k: data[k] for k in ("engine", "cost", "J", "J_certified", "worst_case_word") if k in data}
    for key, allowed in (("engine", ("tree", "classes")), ("cost", (None, "sum", "max"))):
        if key in fields and fields[key] not in allowed:
            raise InputError(f"must be one of {list(allowed)}, got {short_label(repr(fields[key]))}", source, key)
    for key in ("J", "J_certified"):
        if fields.get(key) is not None:
            fields[key] = _number(fields[key], source, key)
    if fields.get("worst_case_word") is not None and not isinstance(fields["worst_case_word"], str):
        raise InputError("must be a word (a string)", source, "worst_case_word")
    return fields
