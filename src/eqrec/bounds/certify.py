r"""Independent certification of a designed estimator from its gains alone.

Given the gain schedule (``F``, ``u0`` per prefix), the error of the causal
estimator (5), (7) along a word is affine in the uncertainty
:math:`\delta = (w, v, \xi_0)`:

.. math:: \xi(t+1) = A\xi(t) + E w(t) + u_0(t) + \sum_{\tau \le t} F(t,\tau)\,q(\tau)\,(C\xi(\tau) + V v(\tau)).

Propagating the affine maps :math:`\xi(t) = G_t\delta + c_t` forward in time
(no Q-parametrisation, no LP) gives the exact worst case over the noise box
of every component at every time, :math:`|c_t| + |G_t| b`, attained at a box
vertex.  A design is accepted only if every one of these bounds is at most
its stored level, exactly in floating point (no tolerance on the guarantee
side): at most ``M2`` everywhere, at most a node's level after its prefix and
at most ``M1`` at each pattern's end.

Exact levels
------------
An LP optimum meets its constraints only to the solver's tolerance, so the
gains may give a worst case a little above the level the LP reports.
:func:`certify_design` then **raises the stored level to the certified
value**: ``mu2``, the node and class levels to their worst cases, and the
recovery level ``μ1`` to a fixed point of its terminal worst case.  Raising
``μ1`` widens the initial-error box, so every bound moves with it; each
terminal row's worst case is affine in ``μ1``, :math:`a_r\mu_1 + b_r` with
:math:`a_r < 1` for gains that contract, and
:math:`\mu_1' = \max_r b_r / (1 - a_r)` (then a few ulps up until the
recomputed certificate is at most ``μ1'`` in floating point) is the
smallest level these gains recover to (:func:`recovery_fixed_point`).  The
returned design's ``mu1`` may therefore exceed the requested one by the
LP's round-off (``design.mu1_requested`` keeps the request); its
estimator reports the raised levels, which its error never exceeds.

``rtol`` is not a tolerance on the guarantee: it bounds how far above the
optimiser's levels the gains may sit before the design is refused as wrong
(:class:`~eqrec.errors.CertificationFailure`), relative to the scale of the
LP's coefficients (``max(1, level, μ1)``: with ``μ1 = 1e9`` an absolute
round-off of ``1e-5`` on a level of ``0.6`` is the LP's normal accuracy).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Callable

import numpy as np

from eqrec.errors import CertificationFailure, InputError
from eqrec.checks import positive
from eqrec.bounds.gains import GainSchedule
from eqrec.arrivals.patterns import ArrivalPattern
from eqrec.bounds.data_classes import ClassGains, class_error_map
from eqrec.arrivals.words import as_language, as_pattern
from eqrec.lp.robust import worst_case_abs, worst_case_vertex
from eqrec.bounds.stacking import Stacking, UncertaintyLayout
from eqrec.systems.affine import AffineSystem

#: How far (relative to ``max(1, level, μ1)``) the gains may give more than the optimiser's level before the design
#: is refused as wrong; below it the stored level is raised to the certified value (module docstring).  Never a
#: tolerance on the guarantee side.
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


def class_bounds(system: AffineSystem, gains: ClassGains, mu1: float, stacking: Stacking | None = None,
                 only=None) -> np.ndarray:
    r"""Exact worst case :math:`\sum_c \beta_c |(E_d - K Z_S)[r, c]|` of every class row, from the gains ``K`` alone.

    The class engine's certificate (:func:`eqrec.design.classes.gains.certify_classes` returns it as a
    ``ClassCertificate``): the worst case of the class-form estimator's error over the box of radii
    :math:`\beta = (\eta_w, \eta_v, \mu_1)`.

    Parameters
    ----------
    system : AffineSystem
        The system.
    gains : ClassGains
        One gain ``K`` per class of ``gains.classes``.
    mu1 : float
        Recovery level ``μ1`` (radius of ``ξ0``).
    stacking : Stacking, optional
        Stacked maps over the classes' horizon; built when omitted.
    only : sequence of int, optional
        Compute these classes only (the other rows stay 0).

    Returns
    -------
    numpy.ndarray
        Shape ``(len(gains.classes), n)``.
    """
    st = stacking or Stacking(system, gains.classes.horizon)
    beta = st.layout.radius(system.eta_w, system.eta_v, mu1)
    bounds = np.zeros((len(gains.classes), system.n))
    for i in range(len(gains.classes)) if only is None else only:
        bounds[i] = np.abs(class_error_map(st, gains, i)) @ beta
    return bounds


def _affine_rows(G: np.ndarray, c: np.ndarray, radius: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """Per row of ``ξ = G δ + c``: the worst case ``a μ1 + b`` split into ``a`` (``ξ0``, the last ``n`` coordinates)
    and ``b`` (noise and offset)."""
    R = np.abs(G)
    return R[:, -n:].sum(axis=1), np.abs(c) + R[:, :-n] @ radius[:-n]


def recovery_fixed_point(terminal_at: Callable[[float], float],
                         rows: Callable[[], tuple[np.ndarray, np.ndarray]], mu1: float) -> float:
    r"""The smallest ``μ ≥ mu1`` (to a few ulps) whose terminal worst case ``terminal_at(μ)`` is at most ``μ``, exactly.

    Each terminal row's worst case is :math:`a_r\mu + b_r` (``slopes``, ``intercepts``), so with every
    :math:`a_r < 1` the fixed point is :math:`\max_r b_r/(1 - a_r)`; from there ``μ`` moves up by
    ``(terminal_at(μ) − μ) / (1 − max a)`` (at least one ulp) until the certificate recomputed in floating point
    is at most ``μ`` (module docstring).

    Parameters
    ----------
    terminal_at : callable
        ``μ -> `` the largest terminal worst case at recovery level ``μ`` (the certificate itself).
    rows : callable
        ``() -> (a, b)``: the slopes ``a_r`` and intercepts ``b_r`` of every terminal row (called only if
        ``mu1`` itself is not certified).
    mu1 : float
        The level to start from.

    Returns
    -------
    float
        ``mu1`` itself if its certificate holds, else the raised level.

    Raises
    ------
    CertificationFailure
        If the gains do not contract the initial error (some ``a_r >= 1``), or no level is found.
    """
    term = terminal_at(mu1)
    if term <= mu1:
        return mu1
    slopes, intercepts = rows()
    amax = float(np.max(slopes, initial=0.0))
    if not amax < 1.0:
        raise CertificationFailure(f"the gains do not contract the initial error (a terminal row's worst case grows "
                                   f"by {amax:.9g} per unit of mu1): no recovery level is certified; terminal "
                                   f"worst case {term:.9g} > mu1 = {mu1:.9g}")
    mu = max(mu1, float(np.max(intercepts / (1.0 - slopes))))
    for _ in range(200):
        term = terminal_at(mu)
        if term <= mu:
            return mu
        mu = max(float(np.nextafter(mu, np.inf)), mu + (term - mu) / (1.0 - amax))
    raise CertificationFailure(f"no recovery level certified near mu1 = {mu1:.9g} (terminal worst case {term:.9g})")


def certify_design(design, words=None, rtol: float = CERT_RTOL, *, nodes: bool = True,
                   stacking: Stacking | None = None) -> "Certificate | None":
    """Certify a :class:`eqrec.design.result.Design` from its gains alone; make its stored levels exact.

    Recomputes every worst case from the gains (the node gains along each word,
    :func:`certify_schedule`, and for a class-engine design every class row,
    :func:`class_bounds`), then raises each stored level that a worst case
    exceeds to that worst case: ``mu1`` to the fixed point of its terminal
    worst case (:func:`recovery_fixed_point`; the request is kept in
    ``design.mu1_requested``), then ``mu2``, the node levels, the class
    levels (``design.class_levels``) and the class certificate at the final
    ``mu1`` (module docstring).  On return every certified worst case is at most
    its stored level, exactly in floating point.

    Parameters
    ----------
    design : Design
        A design result (its system, gains, ``mu1``, ``mu2`` and levels); changed in place.
    words : iterable of str or ArrivalPattern, optional
        Patterns to certify (default the design's patterns).
    rtol : float, optional
        How far above an optimised level (relative to ``max(1, level, μ1)``) a worst case may be before the
        gains are refused as not the optimiser's; below it the level is raised.  Never a tolerance on the guarantee.
    nodes : bool, optional
        Certify the node gains (``design.schedule``; default).  ``False``: the class certificate only.
    stacking : Stacking, optional
        The design's stacked model over its classes' horizon, which the class bounds read (default: built
        from ``design.system``).  The node gains are certified by their own forward recursion
        (:func:`certify_schedule`), without it.

    Returns
    -------
    Certificate or None
        The node-gain certificate at the final ``mu1``, also stored as ``design.certificate``
        (``None`` without node gains).

    Raises
    ------
    CertificationFailure
        If a worst case exceeds ``M2``, a node's level or ``M1`` by more than ``rtol`` (scaled as above), or the
        gains do not contract the initial error.
    InputError
        A ``stacking`` of another system than ``design.system`` (nothing changed).
    """
    words = list(design.patterns if words is None else words)
    nodes = nodes and design.schedule is not None
    system, mu1, n = design.system, float(design.mu1), design.system.n
    if stacking is not None and stacking.system is not system:
        raise InputError("the stacking is of another system than the design's", field="stacking")
    cg = design.class_gains if isinstance(design.class_gains, ClassGains) else None
    stacked: list = []  # the class maps' stacking: the design's, or built on first use (a recertification at the
    # certified μ1 reads the stored class certificate and needs none)

    def st() -> Stacking:
        if not stacked:
            stacked.append(Stacking.of(stacking or system, cg.classes.horizon))
        return stacked[0]
    term_cls = [i for i, c in enumerate(cg.classes.classes) if c.terminal] if cg is not None else []
    cc = design.class_certificate if cg is not None else None
    cache: dict = {}

    def certs(mu: float):  # the node certificate and the class bounds (terminal classes at least) at μ
        if mu not in cache:
            cache.clear()
            cb = None
            if cg is not None:
                cb = cc.bounds if cc is not None and cc.mu1 == mu else class_bounds(system, cg, mu, st(), term_cls)
            cache[mu] = (certify_schedule(system, design.schedule, words, mu) if nodes else None, cb)
        return cache[mu]

    def terminal_at(mu: float) -> float:
        cert, cb = certs(mu)
        return max(cert.terminal if cert is not None else -np.inf,
                   float(cb[term_cls].max()) if term_cls else -np.inf)

    cert, _ = certs(mu1)
    if cert is not None:  # the gains are the optimiser's, up to its accuracy (else refused: a wrong design)
        def too_far(bound: float, level: float) -> bool:
            return bound - level > rtol * max(1.0, abs(level), mu1)

        if too_far(cert.mu2, design.mu2):
            raise CertificationFailure(f"{design.method} design: gains give worst-case error {cert.mu2:.9g} "
                                       f"> optimised mu2 = {design.mu2:.9g}")
        if too_far(cert.terminal, mu1):
            raise CertificationFailure(f"{design.method} design: terminal worst-case error {cert.terminal:.9g} "
                                       f"> mu1 = {mu1:.9g}")
        for wc in cert.words.values():
            for t in range(1, wc.pattern.T):
                level = design.levels.get(wc.pattern.prefix(t).label)
                if level is not None and too_far(wc.bounds[t].max(), level):
                    raise CertificationFailure(f"{design.method} design: worst-case error {wc.bounds[t].max():.9g} "
                                               f"after prefix {wc.pattern.prefix(t).label!r} > its level {level:.9g}")

    def rows() -> tuple[np.ndarray, np.ndarray]:  # every terminal row's worst case as a μ1 + b
        out = [(np.zeros(0), np.zeros(0))]
        if cert is not None:
            out += [_affine_rows(wc.G[-1], wc.c[-1], wc.radius, n) for wc in cert.words.values()]
        if term_cls:
            beta = st().layout.radius(system.eta_w, system.eta_v, mu1)
            out += [_affine_rows(class_error_map(st(), cg, i), np.zeros(n), beta, n) for i in term_cls]
        return np.concatenate([a for a, _ in out]), np.concatenate([b for _, b in out])

    # the recovery level: the fixed point of the terminal worst case (affine in μ1 row by row)
    mu = recovery_fixed_point(terminal_at, rows, mu1) if (cert is not None or term_cls) else mu1
    cert, _ = certs(mu)
    old = {"mu1": mu1, "mu2": float(design.mu2)}
    if mu != mu1:
        if design.mu1_requested is None:  # the first request, through repeated certifications
            design.mu1_requested = mu1
        design.mu1 = mu
    # every stored level at least the worst case the gains give at the final μ1
    mu2 = max(float(design.mu2), mu)
    if cert is not None:
        mu2 = max(mu2, cert.mu2)
        for wc in cert.words.values():
            for t in range(1, wc.pattern.T):
                lab = wc.pattern.prefix(t).label
                if lab in design.levels:
                    design.levels[lab] = max(design.levels[lab], float(wc.bounds[t].max()))
    if cg is not None:
        cb = cc.bounds if cc is not None and cc.mu1 == mu else class_bounds(system, cg, mu, st())
        if cc is not None and cc.mu1 != mu:  # the class certificate (the class-form estimator's bounds) at μ
            design.class_certificate = cc = replace(cc, mu1=mu, bounds=cb)
        cls_levels = cb.max(axis=1) if cb.size else np.zeros(0)
        inner = np.array([c.inner for c in cg.classes.classes], bool)
        mu2 = max(mu2, float(cls_levels[inner].max(initial=mu)))
        if design.class_levels is not None:
            design.class_levels = np.maximum(np.asarray(design.class_levels, float), cls_levels)
        tree = cg.classes.tree
        if design.levels and tree is not None:
            for node in tree:
                if not node.terminal and node.label in design.levels:
                    design.levels[node.label] = max(design.levels[node.label],
                                                    float(cls_levels[cg.classes.node_class[node.index]]))
    if mu != mu1 and design.levels:  # the convention μ2 >= μ1 of the node levels, kept at the raised μ1
        design.levels = {k: (max(v, mu) if v >= mu1 else v) for k, v in design.levels.items()}
    design.mu2 = mu2
    design.level_raise = max((design.mu1 - old["mu1"]) / old["mu1"],
                             (design.mu2 - old["mu2"]) / max(old["mu2"], np.finfo(float).tiny))
    _check_exact(design, cert)
    if cert is not None:
        design.certificate = cert
    return cert


def _check_exact(design, cert: "Certificate | None") -> None:
    """:class:`CertificationFailure` unless every certified worst case is at most its stored level (no tolerance)."""
    bad = []
    if cert is not None:
        if not cert.mu2 <= design.mu2:
            bad.append(f"mu2: {cert.mu2!r} > {design.mu2!r}")
        if not cert.terminal <= design.mu1:
            bad.append(f"terminal: {cert.terminal!r} > mu1 = {design.mu1!r}")
        for wc in cert.words.values():
            for t in range(1, wc.pattern.T):
                level = design.levels.get(wc.pattern.prefix(t).label)
                if level is not None and not wc.bounds[t].max() <= level:
                    bad.append(f"prefix {wc.pattern.prefix(t).label!r}: {wc.bounds[t].max()!r} > {level!r}")
    cc = design.class_certificate
    if cc is not None and design.class_gains is not None:
        if not cc.mu1 == design.mu1:
            bad.append(f"class certificate at mu1 = {cc.mu1!r}, design at {design.mu1!r}")
        if not cc.terminal <= design.mu1:
            bad.append(f"terminal class: {cc.terminal!r} > mu1 = {design.mu1!r}")
        if not cc.mu2 <= design.mu2:
            bad.append(f"inner class: {cc.mu2!r} > mu2 = {design.mu2!r}")
    if bad:
        raise CertificationFailure(f"{design.method} design: a certified worst case exceeds its stored level: "
                                   + "; ".join(bad[:3]))


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
