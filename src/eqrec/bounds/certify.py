r"""Independent certification of a designed estimator from its gains alone.

Given the gain schedule (``F``, ``u0`` per prefix), the error of the causal
estimator (5), (7) along a word is affine in the uncertainty
:math:`\delta = (w, v, \xi_0)`:

.. math:: \xi(t+1) = A\xi(t) + E w(t) + u_0(t) + \sum_{\tau \le t} F(t,\tau)\,q(\tau)\,(C\xi(\tau) + V v(\tau)).

Propagating the affine maps :math:`\xi(t) = G_t\delta + c_t` forward in time
(no Q-parametrisation, no LP) gives the exact worst case over the noise box
of every component at every time, :math:`|c_t| + |G_t| b`, attained at a box
vertex.  A design is accepted only if these bounds confirm the optimiser's
levels: at most ``M2`` everywhere and at most ``M1`` at each pattern's end.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from eqrec.errors import CertificationFailure, InputError
from eqrec.checks import positive
from eqrec.bounds.gains import GainSchedule
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.arrivals.words import as_language, as_pattern
from eqrec.lp.robust import worst_case_abs, worst_case_vertex
from eqrec.bounds.stacking import Stacking, UncertaintyLayout
from eqrec.systems.affine import AffineSystem

#: Relative tolerance for accepting an LP optimum (solver feasibility tolerances are ~1e-7..1e-9).
CERT_RTOL = 1e-6


@dataclass
class WordCertificate:
    """Closed-loop error maps and worst-case bounds along one word.

    Parameters
    ----------
    word : str
        Label of the pattern.
    G : ndarray, shape (T+1, n, D)
        Linear part of ``ξ(t) = G[t] δ + c[t]`` (``δ`` laid out by ``UncertaintyLayout``).
    c : ndarray, shape (T+1, n)
        Affine part (from ``u0``).
    bounds : ndarray, shape (T+1, n)
        ``max`` over the box of ``|ξ_i(t)|``.
    radius : ndarray, shape (D,)
        Radii ``b`` of the uncertainty box (``η_w``, ``η_v``, ``μ1`` entries).
    pattern : ArrivalPattern, optional
        The pattern itself.
    """

    word: str
    G: np.ndarray  # (T+1, n, D): ξ(t) = G[t] δ + c[t]
    c: np.ndarray  # (T+1, n)
    bounds: np.ndarray  # (T+1, n): max over the box of |ξ_i(t)|
    radius: np.ndarray
    pattern: ArrivalPattern | None = None

    def worst_vertex(self, t: int, i: int) -> np.ndarray:
        """A box vertex ``δ*`` at which ``|ξ_i(t)|`` equals its bound.

        Parameters
        ----------
        t : int
            Time, ``0..T``.
        i : int
            State component.

        Returns
        -------
        ndarray, shape (D,)
            The worst-case uncertainty ``δ*``.
        """
        return worst_case_vertex(self.G[t, i], self.c[t, i], self.radius)

    def errors(self, deltas: np.ndarray) -> np.ndarray:
        """Errors ``ξ(t) = G_t δ + c_t`` for samples ``deltas``.

        Parameters
        ----------
        deltas : ndarray, shape (N, D) or (D,)
            Uncertainty samples.

        Returns
        -------
        ndarray, shape (N, T+1, n)
            The error trajectories.
        """
        return np.einsum("tnd,kd->ktn", self.G, np.atleast_2d(deltas)) + self.c[None]


@dataclass
class Certificate:
    """Worst-case bounds of a design over a set of words.

    Parameters
    ----------
    mu1 : float
        Recovery level ``μ1`` (radius of the initial-error box).
    words : dict of str to WordCertificate, optional
        Per-pattern certificates, keyed by label.
    """

    mu1: float
    words: dict[str, WordCertificate] = field(default_factory=dict)

    @property
    def mu2(self) -> float:
        """Certified intermediate level: max over words, times and components."""
        return float(max(wc.bounds.max() for wc in self.words.values()))

    @property
    def terminal(self) -> float:
        """Certified level at the end of each word (must be <= M1)."""
        return float(max(wc.bounds[-1].max() for wc in self.words.values()))

    def per_time(self) -> np.ndarray:
        """Max over words and components of the bound at each time (words of equal length).

        Returns
        -------
        ndarray, shape (T+1,)
            Certified level at each time ``0..T``.
        """
        return np.max(np.stack([wc.bounds.max(axis=1) for wc in self.words.values()]), axis=0)

    def to_json(self) -> dict:
        """JSON form: certified ``mu2`` and terminal level, ``M1`` and the per-word bounds.

        Returns
        -------
        dict
            Keys ``certified_mu2``, ``certified_terminal``, ``M1``, ``bounds`` (label -> nested lists).
        """
        return {"certified_mu2": self.mu2, "certified_terminal": self.terminal, "M1": self.mu1,
                "bounds": {w: wc.bounds.tolist() for w, wc in self.words.items()}}


def closed_loop_maps(system: AffineSystem, schedule: GainSchedule,
                     pattern: "ArrivalPattern | str") -> tuple[np.ndarray, np.ndarray, UncertaintyLayout]:
    """Affine maps ``ξ(t) = G[t] δ + c[t]``, ``t = 0..T``, of the causal estimator along ``pattern``.

    At time ``t`` the estimator injects ``u_e(t) = u0 + Σ_{τ ∈ A(t)} F(t, τ) y_ξ(τ)``
    with ``y_ξ(τ) = C ξ(τ) + V v(τ)`` formed with the error of time ``τ``
    (for a late measurement, the estimate ``x̂(τ)`` the runtime estimator kept).

    Parameters
    ----------
    system : AffineSystem
        The system (its matrices, possibly time-varying).
    schedule : GainSchedule
        Gains ``(F, u0)`` per prefix.
    pattern : ArrivalPattern or str
        Pattern (or 0/1 word) of horizon ``T``.

    Returns
    -------
    G : ndarray, shape (T+1, n, D)
        Linear maps from ``δ = (w, v, ξ0)``.
    c : ndarray, shape (T+1, n)
        Affine terms.
    layout : UncertaintyLayout
        Positions of ``w(t)``, ``v(t)`` and ``ξ0`` in ``δ`` (``D = layout.size``).
    """
    pattern = as_pattern(pattern)
    T, n, p = pattern.T, system.n, system.p
    lay = UncertaintyLayout(T, system.nw, system.nv, n)
    G = np.zeros((T + 1, n, lay.size))
    c = np.zeros((T + 1, n))
    G[0][:, lay.xi0] = np.eye(n)
    Yg = np.zeros((T, p, lay.size))  # y_ξ(τ) = Yg[τ] δ + yc[τ] once y(τ) has arrived
    yc = np.zeros((T, p))
    avail = np.zeros((T, p))  # 1 on the rows of the measurements available at the current time
    for t, pre in enumerate(pattern.prefixes()):
        C = system.C_at(t)
        Yg[t] = C @ G[t]
        Yg[t][:, lay.v(t)] += system.V_at(t)
        yc[t] = C @ c[t]
        for tau in pattern.arriving_at(t):
            avail[tau] = 1.0
        g = schedule.row(pre)
        Fr = g.F * avail[: t + 1].reshape(1, -1)  # n x (t+1)p, zero on measurements not yet arrived
        A = system.A_at(t)
        G[t + 1] = A @ G[t] + Fr @ Yg[: t + 1].reshape(-1, lay.size)
        G[t + 1][:, lay.w(t)] += system.E_at(t)
        c[t + 1] = A @ c[t] + g.u0 + Fr @ yc[: t + 1].reshape(-1)
    return G, c, lay


def certify_schedule(system: AffineSystem, schedule: GainSchedule, words, mu1: float) -> Certificate:
    r"""Exact worst-case error bounds of ``schedule`` for each pattern (or 0/1 word) in ``words``.

    From the gains alone (no Q-parametrisation, no LP): along each pattern
    the error of the causal estimator (5), (7) of the prefix-based paper is
    affine in the uncertainty :math:`\delta = (w, v, \xi_0)`,
    :math:`\xi(t) = G_t\delta + c_t` (:func:`closed_loop_maps`), so its exact
    worst case over the box :math:`|w| \le \eta_w`, :math:`|v| \le \eta_v`,
    :math:`|\xi_0| \le \mu_1` (radii ``b``) is, componentwise,

    .. math:: \max_\delta |\xi_i(t)| = |c_{t,i}| + |G_{t,i}|\, b,

    attained at a box vertex.  The certificate confirms equalized recovery
    when ``Certificate.mu2`` is at most the designed ``M2`` and
    ``Certificate.terminal`` at most ``M1``
    (:func:`certify_design` checks this for a design).

    Parameters
    ----------
    system : AffineSystem
        The system (its matrices and noise bounds).
    schedule : GainSchedule
        Node gains ``(F, u0)`` per prefix (e.g. ``design.schedule``); a
        time-based schedule applies to every pattern of its horizon.
    words : iterable of str or ArrivalPattern
        Patterns (or 0/1 words) to certify; each needs its prefixes in
        ``schedule``.
    mu1 : float
        Recovery level ``μ1``: the radius of the initial-error box.

    Returns
    -------
    Certificate
        Keyed by the patterns' labels: per word the maps ``G, c`` and the
        bounds (shape ``(T+1, n)``); ``mu2`` (largest bound) and
        ``terminal`` (largest bound at a word's end).

    Raises
    ------
    InputError
        Malformed words, or a pattern with a prefix the schedule has no gains for (field ``words``), a
        ``mu1`` that is not a positive finite number, a ``system`` or ``schedule`` of another type.

    Examples
    --------
    >>> import eqrec
    >>> acc = eqrec.acc_system()
    >>> design = eqrec.design_prefix(acc, ["101111", "110111", "111011", "111101"], mu1=1.0)
    >>> cert = eqrec.certify_schedule(acc, design.schedule, ["101111", "110111"], mu1=1.0)
    >>> sorted(cert.words), cert.mu2 <= design.mu2 * (1 + 1e-9), cert.terminal <= 1.0 + 1e-6
    (['101111', '110111'], True, True)
    """
    if not isinstance(system, AffineSystem):
        raise InputError(f"expected an AffineSystem, got {type(system).__name__}", field="system")
    if not isinstance(schedule, GainSchedule):
        raise InputError(f"expected node gains (GainSchedule, design.schedule), got {type(schedule).__name__}",
                         field="schedule")
    cert = Certificate(mu1=positive(mu1, "mu1"))
    if not isinstance(words, (list, tuple)):  # one word, or an iterable: read (and refused) as a language
        words = as_language(words, kind="missing", fixed_length=False)
    for w in words:
        w = as_pattern(w, field_name="words")
        try:
            G, c, lay = closed_loop_maps(system, schedule, w)
        except InputError as exc:  # a prefix the gains do not cover: the word is at fault
            if exc.field is not None:
                raise
            raise InputError(f"word {w.label!r}: {exc}", field="words") from None
        radius = lay.radius(system.eta_w, system.eta_v, mu1)
        bounds = np.stack([worst_case_abs(G[t], c[t], radius) for t in range(w.T + 1)])
        cert.words[w.label] = WordCertificate(word=w.label, G=G, c=c, bounds=bounds, radius=radius, pattern=w)
    return cert


def certify_design(design, words=None, rtol: float = CERT_RTOL) -> Certificate:
    """Certify a :class:`eqrec.design.result.Design` from its gains alone and attach the certificate.

    Parameters
    ----------
    design : Design
        A design result (its system, schedule, ``mu1``, ``mu2`` and levels).
    words : iterable of str or ArrivalPattern, optional
        Patterns to certify (default the design's patterns).
    rtol : float, optional
        Relative tolerance on the optimised levels.

    Returns
    -------
    Certificate
        The certificate, also stored as ``design.certificate``.

    Raises
    ------
    CertificationFailure
        If a bound exceeds the designed ``M2`` (or ``M1`` at a word's end) by
        more than ``rtol`` relative, or exceeds a node's level after a prefix.
    """
    words = list(design.patterns if words is None else words)
    cert = certify_schedule(design.system, design.schedule, words, design.mu1)
    tol_2 = rtol * max(1.0, design.mu2)
    tol_1 = rtol * max(1.0, design.mu1)
    if cert.mu2 > design.mu2 + tol_2:
        raise CertificationFailure(f"{design.method} design: gains give worst-case error {cert.mu2:.9g} "
                                   f"> optimised mu2 = {design.mu2:.9g}")
    if cert.terminal > design.mu1 + tol_1:
        raise CertificationFailure(f"{design.method} design: terminal worst-case error {cert.terminal:.9g} "
                                   f"> mu1 = {design.mu1:.9g}")
    for wc in cert.words.values():  # per-node levels: the bound after each prefix stays below that node's level
        pattern = wc.pattern
        for t in range(1, pattern.T):
            level = design.levels.get(pattern.prefix(t).label)
            if level is not None and wc.bounds[t].max() > level + rtol * max(1.0, level):
                raise CertificationFailure(f"{design.method} design: worst-case error {wc.bounds[t].max():.9g} after "
                                           f"prefix {pattern.prefix(t).label!r} > its level {level:.9g}")
    design.certificate = cert
    return cert


def no_data_growth(system: AffineSystem, steps: int) -> float:
    r"""The factor :math:`\|A^k\|_\infty` by which an initial error box grows over ``k`` steps with no data.

    Along a pattern whose first ``k`` measurements are all late or missing, no
    estimator has data before time ``k`` and (without process noise)
    :math:`\xi(k) = A^k \xi(0)`, so every level of that prefix is at least
    :math:`\|A^k\|_\infty \mu_1` (the lower bound used to explain the batch
    reactor's max μ2 in the delayed-data paper, Sec. IV-A).

    For a time-varying system the power is the transition
    :math:`A_{k-1} \cdots A_0` from time 0.

    Parameters
    ----------
    system : AffineSystem
        The system.
    steps : int
        Number ``k`` of steps without data.

    Returns
    -------
    float
        The row-sum norm ``||A^k||_∞``.

    Raises
    ------
    InputError
        A time-varying system shorter than ``steps``.
    """
    steps = int(steps)
    if system.is_time_varying:  # the transition of the stacked maps (checks the horizon)
        P = Stacking(system, steps).transition[steps][0]
    else:
        P = np.linalg.matrix_power(np.asarray(system.A, float), steps)
    return float(np.abs(P).sum(axis=1).max())
