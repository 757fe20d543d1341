r"""The delayed-data paper's cost ``J`` (Theorem 1 / Proposition 1), counted from levels or a certificate.

What exactly is counted
-----------------------
``cost="sum"`` is the paper's ``J = μ1 + Σ_{k=0}^{T} Σ_{α=1}^{|L^{E'}|} μ2,k^α``:

* the sum over ``α`` runs over the **reduced** language ``L^{E'}`` (distinct
  event sequences; the batch reactor's 243 words give 162), as printed;
* ``μ2,k^α`` bounds ``ξ(k)`` along ``α``; ``ξ(k)`` depends on the events
  ``0..k-1`` only, so its best level is that of the prefix node of depth
  ``k`` and every sequence through the node pays it: the node's weight is
  the number of sequences through it;
* ``k = 0``: ``‖ξ(0)‖ <= μ1`` and ``μ2,0 >= μ1``, so ``μ2,0^α = μ1`` at any
  optimum; ``k = T``: ``‖ξ(T)‖ <= μ1`` is imposed and ``μ2,T^α >= μ1``, so
  ``μ2,T^α = μ1``.  Each contributes ``|L^{E'}| μ1``:

  .. math:: J = (1 + 2|L^{E'}|)\,\mu_1 + \sum_{k=1}^{T-1}\sum_{\text{nodes } \nu,\ |\nu| = k} w_\nu\,\mu_{2,\nu}.

  :func:`cost_weights` returns this coefficient of ``μ1`` and the node
  weights; :func:`paper_cost` evaluates ``J`` from node levels (a test checks
  it against the literal double sum), and
  :func:`class_cost` from class levels (nodes of one class share their level,
  :mod:`eqrec.design.classes.engine`).

``cost="max"``: the largest level ``max_{k,α} μ2,k^α`` (one common level, the
prefix-based paper's ``M2``), and ``J = μ1 + max μ2`` when ``μ1`` is free.
"""

from __future__ import annotations

import numpy as np

from eqrec.bounds.data_classes import ClassSet
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.errors import InputError

COSTS = ("sum", "max")


def check_cost(cost: str) -> str:
    """``cost`` if it is one of :data:`COSTS`, else :class:`~eqrec.errors.InputError`.

    Parameters
    ----------
    cost : str
        ``"sum"`` (the paper's ``J``) or ``"max"`` (one common level).

    Returns
    -------
    str
        ``cost`` unchanged.
    """
    if cost not in COSTS:
        raise InputError(f"unknown cost {cost!r}; choose one of {list(COSTS)}", field="cost")
    return cost


def cost_weights(tree: PrefixTree, cost: str = "sum") -> tuple[float, dict[int, float]]:
    """Coefficient of ``μ1`` in ``J`` and weight of each non-terminal node's level.

    ``"sum"``: ``(1 + 2|L^{E'}|, {node: sequences through it})`` (module
    docstring: ``k = 0`` and ``k = T`` contribute ``|L^{E'}| μ1`` each);
    ``"max"``: ``(1, {})`` (``J = μ1 + max level``).

    Parameters
    ----------
    tree : PrefixTree
        Prefix tree of the reduced language ``L^{E'}``.
    cost : str, optional
        ``"sum"`` (default) or ``"max"``.

    Returns
    -------
    coefficient : float
        Coefficient of ``μ1`` in ``J``.
    weights : dict of int to float
        Node index -> weight of its level (non-terminal nodes; empty for ``"max"``).
    """
    check_cost(cost)
    if cost == "max":
        return 1.0, {}
    w = tree.sequences_through()
    return 1.0 + 2.0 * len(tree.patterns), {i: float(c) for i, c in w.items() if not tree.nodes[i].terminal}


def paper_cost(tree: PrefixTree, mu1: float, levels: dict[str, float], cost: str = "sum") -> float:
    """``J`` from node levels (keyed by node label; missing nodes count as ``μ1``).

    Parameters
    ----------
    tree : PrefixTree
        Prefix tree of the reduced language ``L^{E'}``.
    mu1 : float
        Recovery level ``μ1``.
    levels : dict of str to float
        Node label -> level ``μ2`` of the node (levels below ``μ1`` count as ``μ1``).
    cost : str, optional
        ``"sum"`` (default, the delayed paper's ``J`` of Theorem 1) or ``"max"``.

    Returns
    -------
    float
        The cost ``J``.
    """
    a, w = cost_weights(tree, cost)
    if cost == "max":
        return mu1 + max([mu1, *levels.values()])
    return a * mu1 + sum(wi * max(mu1, levels.get(tree.nodes[i].label, mu1)) for i, wi in w.items())


def class_cost(classes: ClassSet, mu1: float, levels: np.ndarray, cost: str = "sum") -> float:
    r"""``J`` from class levels: :math:`(1 + 2|\mathcal L^{E'}|)\mu_1 + \sum_{\text{inner}} w \max(\mu_1, \ell)`
    (``"sum"``, weights the sequences through the class) or :math:`\mu_1 + \max(\mu_1, \max_{\text{inner}}\ell)`
    (``"max"``).

    Parameters
    ----------
    classes : ClassSet
        The (time, available data) classes; their weights count the sequences through them.
    mu1 : float
        Recovery level ``μ1``.
    levels : numpy.ndarray
        ``(len(classes),)`` level of each class (terminal classes are ignored).
    cost : str, optional
        ``"sum"`` (default) or ``"max"``.

    Returns
    -------
    float
        The cost ``J``.
    """
    check_cost(cost)
    inner = [(c.weight, float(lv)) for c, lv in zip(classes.classes, levels) if c.inner]
    if cost == "max":
        return mu1 + max([mu1, *(lv for _, lv in inner)])
    return (1.0 + 2.0 * classes.sequences) * mu1 + sum(float(w) * max(mu1, lv) for w, lv in inner)


def node_bounds(certificate) -> dict[str, float]:
    """Certified worst case of ``ξ(k)`` after each event prefix (node label), ``k = 1..T``, over the words through it.

    Parameters
    ----------
    certificate : Certificate
        Per-word certificate of a design (``certificate.words[w].bounds`` of shape ``(T+1, n)``).

    Returns
    -------
    dict of str to float
        Node label -> largest certified ``|ξ_r(k)|`` over the rows and the words through the node.
    """
    bound: dict[str, float] = {}
    for wc in certificate.words.values():
        for t in range(1, wc.pattern.T + 1):
            lab = wc.pattern.prefix(t).label
            bound[lab] = max(bound.get(lab, 0.0), float(wc.bounds[t].max()))
    return bound


def certified_cost(design, tree: PrefixTree, cost: str, certificate=None) -> float:
    """``J`` recomputed from the certificate: each node's level replaced by its worst case (at least ``μ1``).

    Parameters
    ----------
    design : Design
        The design (its ``mu1`` and, by default, its ``certificate``).
    tree : PrefixTree
        Prefix tree of the reduced language ``L^{E'}``.
    cost : str
        ``"sum"`` or ``"max"``.
    certificate : Certificate, optional
        Certificate to use instead of ``design.certificate``.

    Returns
    -------
    float
        The certified cost ``J``.
    """
    cert = certificate or design.certificate
    if cost == "max":
        return design.mu1 + max(design.mu1, cert.mu2)
    return paper_cost(tree, design.mu1, node_bounds(cert), "sum")
