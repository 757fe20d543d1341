r"""What the class gains ``K`` give: their exact worst case, and the node gains of the recursive estimator.

The class engine (:mod:`eqrec.design.classes.engine`) designs one gain ``K`` per
(time, available data) class ``(d, S)``; the class-form estimator's error
after a prefix of the class is exactly :math:`(E_d - K Z_S)\delta` for
:math:`\delta = (w, v, \xi_0)` in the box of radii
:math:`\beta = (\eta_w, \eta_v, \mu_1)`.  :func:`certify_classes` recomputes
each row's worst case :math:`\sum_c \beta_c |(E_d - K Z_S)[r, c]|` from the
``K``\ s alone (no LP, no solver); :func:`node_schedule` turns the ``K``\ s
into the node gains ``(F, u0)`` of the prefix-based paper's recursive
estimator (eqs. (1)-(2), (7) there).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.bounds.certify import class_bounds
from eqrec.bounds.data_classes import ClassGains, ClassSet
from eqrec.bounds.gains import GainSchedule, q_to_f, schedule_from_word_gains
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.errors import InputError


def box_radius(stacking: Stacking, mu1: float) -> np.ndarray:
    """Radii ``β = (η_w, η_v, μ1)`` of the uncertainty box of ``stacking``'s coordinates.

    Parameters
    ----------
    stacking : Stacking
        Stacked maps of the system over the horizon (its layout orders the coordinates ``(w, v, ξ0)``).
    mu1 : float
        Recovery level ``μ1``, the radius of the initial error ``ξ0``.

    Returns
    -------
    numpy.ndarray
        Radius of each coordinate of ``δ = (w, v, ξ0)``.
    """
    sys = stacking.system
    return stacking.layout.radius(sys.eta_w, sys.eta_v, mu1)


@dataclass
class ClassCertificate:
    """Worst case of every state row of every class, recomputed from the ``K``\\ s alone.

    ``bounds[i, r] = Σ_c β_c |(E_d - K Z_S)[r, c]|`` is the exact worst case of
    :math:`\\xi_r(d)` for the class-form estimator (and for the node gains
    derived from it) over the box at ``mu1``.

    Parameters
    ----------
    mu1 : float
        Recovery level ``μ1`` of the box.
    classes : ClassSet
        The classes certified.
    bounds : numpy.ndarray
        ``(len(classes), n)`` worst case of each state row of each class.
    """

    mu1: float
    classes: ClassSet
    bounds: np.ndarray  # (classes, n)

    @property
    def levels(self) -> np.ndarray:
        """Certified level of each class (largest row)."""
        return self.bounds.max(axis=1) if self.bounds.size else np.zeros(0)

    @property
    def terminal(self) -> float:
        """Largest certified level of a terminal class (at most ``μ1`` for a valid design)."""
        lv = [lv for lv, c in zip(self.levels, self.classes) if c.terminal]
        return float(max(lv, default=0.0))

    @property
    def mu2(self) -> float:
        """Largest certified level of an inner class, at least ``μ1``."""
        return float(max([self.mu1, *(lv for lv, c in zip(self.levels, self.classes) if c.inner)]))


def certify_classes(system: "AffineSystem | Stacking", gains: ClassGains, mu1: float,
                    stacking: Stacking | None = None) -> ClassCertificate:
    """Exact worst case of every class row from the gains ``K`` alone (no LP, no solver).

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the classes' horizon (read from there).
    gains : ClassGains
        One gain ``K`` per class of ``gains.classes``.
    mu1 : float
        Recovery level ``μ1`` (radius of ``ξ0``).
    stacking : Stacking, optional
        Stacked maps over the classes' horizon (as ``system`` may be); built when neither is one.

    Returns
    -------
    ClassCertificate
        ``bounds[i, r] = Σ_c β_c |(E_d - K Z_S)[r, c]|`` for every class ``i`` and row ``r``.
    """
    st = Stacking.of(stacking or system, gains.classes.horizon)
    # the one formula of the certificate (eqrec.bounds.certify.class_bounds), so that a recertification agrees
    return ClassCertificate(mu1=float(mu1), classes=gains.classes, bounds=class_bounds(st.system, gains, mu1, st))


def node_schedule(system: "AffineSystem | Stacking", gains: ClassGains, tree: PrefixTree | None = None,
                  time_based: bool = False) -> GainSchedule:
    r"""Node gains ``(F, u0 = 0)`` per prefix of ``tree`` that realise the class-form errors.

    Along a word, the gain row of time ``d-1`` in the Q-parametrisation is
    :math:`Q_{d-1} = -K_{(d,S)} + A(d-1) K_{(d-1,S')}` (``S' ⊆ S`` embedded;
    ``K = 0`` before any data), so that
    :math:`\sum_{s<d}\Phi(d, s{+}1) Q_s Z_{S_s} = -K_{(d,S)} Z_S`; then
    ``F`` by eq. (2) of the prefix-based paper.  Tested equal in effect (same
    estimates) to the class form.

    Parameters
    ----------
    system : AffineSystem or Stacking
        The system, or the design's stacked model over the tree's depth (its ``C̄ S`` blocks read from there).
    gains : ClassGains
        One gain ``K`` per class.
    tree : PrefixTree, optional
        Prefix tree of the language; defaults to ``gains.classes.tree`` (absent for a window-rule class set:
        :class:`~eqrec.errors.InputError`).
    time_based : bool, optional
        Whether the schedule picks gains by time only (:class:`~eqrec.bounds.gains.GainSchedule`).

    Returns
    -------
    GainSchedule
        The node gains ``(F, u0 = 0)``.
    """
    classes = gains.classes
    tree = tree or classes.tree
    if tree is None:
        raise InputError("node gains need the prefix tree of the language (a small language); this class set "
                         "was built from the window rule")
    st = Stacking.of(system, tree.depth)
    system = st.system
    n, p = system.n, system.p
    word_gains = {}
    for word in tree.patterns:
        Tw = word.T
        Q = np.zeros((Tw * n, Tw * p))
        prev = np.zeros((n, Tw * p))  # K of the parent class, embedded over all times
        for node in tree.path(word):
            t = node.depth - 1
            K = gains.K[classes.node_class[node.index]]
            cur = np.zeros((n, Tw * p))
            for j, tau in enumerate(node.available):
                cur[:, tau * p:(tau + 1) * p] = K[:, j * p:(j + 1) * p]
            Q[t * n:(t + 1) * n] = -cur + system.A_at(t) @ prev
            prev = cur
        word_gains[word] = q_to_f(Q, np.zeros(Tw * n), st.word_CS(word))
    return schedule_from_word_gains(tree, word_gains, n, p, time_based=time_based)
