"""Reading a design: levels per event prefix and time, certificates per word, class tables, the CLI's JSON.

Nothing here designs or solves: every function reads a
:class:`~eqrec.design.result.Design` (and its certificates) as the design
functions returned it.  The levels are the guaranteed ``μ2,k^α`` of the
delayed-data paper's cost (Theorem 1 / Proposition 1, :mod:`eqrec.design.cost`)
or the prefix-based paper's common ``M2``.
"""

from __future__ import annotations

import numpy as np

from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import parse_delay_word
from eqrec.checks import short_label
from eqrec.design.cost import node_bounds
from eqrec.errors import InputError

# ``Design`` in the annotations is eqrec.design.result.Design, not imported: that module imports this one
# (Design.save writes design_json), and the annotations are never evaluated (postponed)

#: Largest reduced language (sequences) whose node gains ``to_json`` writes unless asked.
JSON_NODE_GAINS_LIMIT = 200


def level_table(design: Design) -> list[dict]:
    """Per event prefix and time: designed level, certified worst case, number of sequences through it.

    Rows for ``k = 0`` (level ``μ1``), every non-terminal node (``k = 1..T-1``)
    and every sequence's end (``k = T``, level ``μ1``).

    Parameters
    ----------
    design : Design
        A certified delay design (node gains and ``certificate`` present).

    Returns
    -------
    list of dict
        One row per node: ``prefix``, ``k``, ``level``, ``certified``, ``sequences``.
    """
    tree = PrefixTree(design.patterns, kind="delay")
    w = tree.sequences_through()
    bound = node_bounds(design.certificate)
    rows = [{"prefix": "", "k": 0, "level": design.mu1, "certified": design.mu1, "sequences": len(tree.patterns)}]
    for node in tree:
        lvl = design.mu1 if node.terminal else node_level(design, node.prefix)
        rows.append({"prefix": node.label, "k": node.depth, "level": float(lvl), "certified": bound[node.label],
                     "sequences": w[node.index]})
    return rows


def path_levels(design: Design, pattern) -> np.ndarray:
    """The guaranteed levels ``μ2,k^α``, ``k = 0..T``, along one pattern (``μ1`` at ``k = 0`` and ``k = T``).

    With per-node levels (cost ``"sum"``) each time's level is that of the
    prefix node; with one common level (``"max"``) it is ``mu2``.

    Parameters
    ----------
    design : Design
        The design whose levels are read.
    pattern : str or ArrivalPattern
        A delay word or pattern of horizon ``T``.

    Returns
    -------
    numpy.ndarray
        Shape ``(T+1,)``: the level at each time ``k = 0..T``.
    """
    pat = parse_delay_word(pattern) if isinstance(pattern, str) else pattern
    T = pat.T
    out = np.full(T + 1, design.mu1)
    for k in range(1, T):
        out[k] = node_level(design, pat.prefix(k))
    return out


def word_certificate(design: Design, word):
    """The certificate of the designed sequence equal to ``word`` (a delay word or pattern; any word of its class).

    Parameters
    ----------
    design : Design
        A certified design.
    word : str or ArrivalPattern
        The delay word or pattern to look up.

    Returns
    -------
    WordCertificate
        The word's entry of ``design.certificate.words`` (its worst-case bounds per time).

    Raises
    ------
    InputError
        If ``word`` is not an event sequence of the designed language.
    """
    pat = parse_delay_word(word) if isinstance(word, str) else word
    for p in design.patterns:
        if p == pat:
            return design.certificate.words[p.label]
    raise InputError(f"{short_label(pat.label)!r} is not an event sequence of the designed language", field="pattern")


def class_table(design: Design) -> list[dict]:
    """Per (time, available data) class: its level, certified worst case, sum-cost weight and gain ``K``.

    Parameters
    ----------
    design : Design
        A class-engine design (``class_gains`` and ``class_certificate`` present).

    Returns
    -------
    list of dict
        One row per class: ``class``, ``k``, ``data``, ``terminal``, ``inner``, ``sequences``,
        ``nodes``, ``level``, ``certified``, ``K``.
    """
    cc = design.class_certificate
    gains = design.class_gains
    levels = design.class_levels
    rows = []
    for i, cls in enumerate(gains.classes.classes):
        rows.append({"class": cls.label, "k": cls.depth, "data": list(cls.available), "terminal": cls.terminal,
                     "inner": cls.inner, "sequences": int(cls.weight), "nodes": int(cls.nodes),
                     "level": float(max(design.mu1, levels[i])) if cls.inner else float(levels[i]),
                     "certified": float(cc.levels[i]), "K": gains.K[i].tolist()})
    return rows


def to_json(design: Design, free=None, node_gains: bool | None = None) -> dict:
    """What ``eqrec design --method delay`` writes.

    Always: ``μ1``, ``μ2``, ``J`` and the certified values; for the class
    engine the classes (level, certified worst case, ``K``).  Node gains,
    levels per event prefix and the event sequences: with ``node_gains``
    (default: when the reduced language has at most
    :data:`JSON_NODE_GAINS_LIMIT` sequences and node gains exist).  ``free``
    (a :class:`eqrec.design.delay.design.FreeMu1Result`) adds, for ``μ1`` free, the
    route, the lower bound of ``J`` that certifies it (global route) and the
    certified smallest ``μ1``.

    Parameters
    ----------
    design : Design
        The delay design to write.
    free : FreeMu1Result or None, optional
        The ``μ1``-free result the design came from, or ``None``.
    node_gains : bool or None, optional
        Write node gains, levels and event sequences; ``None`` decides by size.

    Returns
    -------
    dict
        The JSON-serialisable record.

    Raises
    ------
    InputError
        If node gains are asked for but the design has none.
    """
    cert = design.certificate
    ccert = design.class_certificate
    if node_gains is None:
        node_gains = design.schedule is not None and len(design.patterns) <= JSON_NODE_GAINS_LIMIT
    if node_gains and design.schedule is None:
        raise InputError("node gains were asked for but the design has none (a language too large for its prefix "
                         "tree: use the class gains K)", field="node-gains")
    certified = cert if cert is not None else ccert
    out = {"method": "delay", "engine": design.engine, "cost": design.cost,
           "T": design.T, "mu1": design.mu1, "mu2": design.mu2, "J": design.J,
           "J_certified": design.J_certified,
           "certified_mu2": None if certified is None else certified.mu2,
           "certified_terminal": None if certified is None else certified.terminal,
           "sequences": design.sequences, "nodes": design.nodes}
    if design.mu1_requested is not None:  # mu1 raised to what the gains certify (eqrec.bounds.certify)
        out["mu1_requested"] = design.mu1_requested
    if design.class_gains is not None:
        out["classes"] = class_table(design)
    if node_gains:
        out["levels"] = level_table(design) if cert is not None else []
        out["event_sequences"] = {p.label: list(p.events()) for p in design.patterns}
        out["gains"] = design.schedule.to_json()
    if free is not None:
        out["mu1_free"] = {"route": free.route, "J": free.J, "lower_bound": free.lower_bound, "gap": free.gap,
                           "lps": free.lps, "time": free.time}
        if free.mu1_min is not None:
            out["mu1_free"]["mu1_min"] = {"upper": free.mu1_min.upper, "lower": free.mu1_min.lower,
                                          "binding": free.mu1_min.binding}
    elif design.mu1_free is not None:  # a design (not the free result) at hand: what it keeps of the route
        mf = design.mu1_free
        out["mu1_free"] = {"route": mf.route, "lower_bound": mf.lower_bound}
        if mf.mu1_min is not None:
            out["mu1_free"]["mu1_min"] = {"upper": mf.mu1_min, "lower": mf.mu1_min_lower, "binding": mf.binding}
    return out


def word_design_json(design: Design, words=None, head: dict | None = None) -> dict:
    """What ``eqrec design --method prefix | time | augmented`` writes (without ``state_weights`` and ``system``).

    Parameters
    ----------
    design : Design
        A certified design of a missing-data language.
    words : list of str, optional
        The language as given (default: the design's language, else its patterns).
    head : dict, optional
        Entries written after the words (the augmented design's ``L``, ``s0``, ``M``, ``nu``; default: read
        from ``design.augmented``).

    Returns
    -------
    dict
        The JSON-serialisable record.
    """
    cert = design.certificate if design.certificate is not None else design.class_certificate
    if words is None:
        words = list(design.language) if design.language is not None else list(design.words)
    if head is None:
        aug = design.augmented
        head = {} if aug is None else {k: np.asarray(getattr(aug, k)).tolist() for k in ("L", "s0", "M", "nu")}
    out = {"method": design.method, "T": design.T, "mu1": design.mu1, "mu2": design.mu2,
           "certified_mu2": cert.mu2, "certified_terminal": cert.terminal, "solver": design.solution.solver,
           "status": design.solution.status, "words": [str(w) for w in words], **head}
    if design.mu1_requested is not None:  # mu1 raised to the fixed point the gains certify (eqrec.bounds.certify)
        out["mu1_requested"] = design.mu1_requested
    if design.schedule is not None:  # none for a class-engine language too large for node gains
        out.update(designed_words=list(design.schedule.designed_words), gains=design.schedule.to_json())
    if design.method == "time":
        out["worst_case_word"] = design.worst_case_word
    if design.method in ("prefix", "time"):  # the class engine's entries
        free = design.mu1_free
        if free is not None:
            out["mu1_free"] = {"route": free.route, "mu1_min": {
                "upper": free.mu1_min, "lower": free.mu1_min_lower, "binding": free.binding}}
        out["engine"] = design.engine
        if design.class_gains is not None:
            out["classes"] = class_table(design)
    return out


def design_json(design: Design, **entries) -> dict:
    """The whole design file of ``eqrec design --out`` (what :func:`eqrec.load_design` reads), for every method.

    The method's record (:func:`to_json` for ``delay``, :func:`word_design_json` otherwise), a weighted design's
    gains in the system file's coordinates with its ``state_weights`` (:func:`original_coordinates`), and the
    system as the file gave it (``system``: for a weighted design the design's system in ``z = W x`` scaled back,
    to rounding).

    Parameters
    ----------
    design : Design
        A certified design (every method).
    **entries
        Passed to the method's record (``words``, ``head``; for ``delay``: ``free``, ``node_gains``); ``original``:
        the system as the file gave it (the command line's; default: ``design.system``, scaled back).

    Returns
    -------
    dict
        The JSON-serialisable record, ``system`` last.
    """
    if design.method == "delay":
        out = to_json(design, entries.get("free"), node_gains=entries.get("node_gains"))
        out.update(solver=design.solution.solver, status=design.solution.status)
        out["words"] = ([str(w) for w in entries["words"]] if entries.get("words") is not None
                        else list(design.words) if design.patterns or design.class_gains is None
                        else int(design.class_gains.classes.words))
        if design.schedule is not None and "gains" in out:
            out["designed_words"] = [p.label for p in design.schedule.designed]
    else:
        out = word_design_json(design, entries.get("words"), entries.get("head"))
    system = design.system
    if design.state_weights is not None:
        weights = np.asarray(design.state_weights, float)
        original_coordinates(out, weights)
        original = entries.get("original")
        system = original if original is not None else system.scaled(1.0 / weights)
    out["system"] = system.to_dict()  # as the file gave it: eqrec.load_design reads the design back
    return out


def original_coordinates(out: dict, weights: np.ndarray) -> dict:
    """The gains of a weighted design's JSON (``eqrec design --state-weights``) in the system file's state ``x``.

    A weighted design is made on ``z = W x`` (:mod:`eqrec.design.weighted`); its injection
    ``ue`` and class gains ``K`` act on ``z``.  In ``x`` they are ``W^{-1}`` times them: each row of
    ``F`` and ``u0`` (state ``i`` of its time block) and of ``K`` is divided by ``w_i``, so the JSON's
    conventions (``x̂(t+1) = A x̂ + B u − ue + f``, ``x̂(d) = x̄(d) + K (y_S − ȳ_S)``) hold with the file's
    matrices.  Levels and certificates stay bounds on ``max_i w_i |x_i − x̂_i|``.

    Parameters
    ----------
    out : dict
        The JSON record, with ``gains`` (per word ``F``, ``u0``) and/or ``classes`` (per class ``K``).
    weights : numpy.ndarray
        The ``n`` state weights.

    Returns
    -------
    dict
        ``out``, changed in place, with ``state_weights`` added.
    """
    w = np.asarray(weights, float)
    for gains in (out.get("gains") or {}).values():
        F, u0 = np.asarray(gains["F"], float), np.asarray(gains["u0"], float)
        row_w = np.tile(w, F.shape[0] // w.size)
        gains["F"], gains["u0"] = (F / row_w[:, None]).tolist(), (u0 / row_w).tolist()
    for row in out.get("classes") or []:
        row["K"] = (np.asarray(row["K"], float) / w[:, None]).tolist()
    out["state_weights"] = w.tolist()
    return out


def node_level(design: Design, prefix) -> float:
    """The guaranteed level ``μ2,k^α`` on ``ξ(k)`` after the event prefix of length ``k`` (``0 < k < T``).

    With per-node levels (the delayed-data paper's sum cost, Theorem 1 /
    Proposition 1, :mod:`eqrec.design.cost`) that of the prefix's node; with
    one common level (the prefix-based paper's ``M2``) ``mu2``.

    Parameters
    ----------
    design : Design
        The design whose levels are read.
    prefix : ArrivalPattern
        The event prefix (length ``k``) ending at the node.

    Returns
    -------
    float
        The node's level, else the design's common level ``mu2``.
    """
    return float(design.levels.get(prefix.label, design.mu2)) if design.levels else float(design.mu2)
