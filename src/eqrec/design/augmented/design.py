r"""Design of the state-augmented estimator (Proposition 1 / Theorem 2 of the augmented paper).

* **L and s0 fixed** (Remark 1): the LP of :class:`eqrec.design.augmented.word_lp.AugmentedLP`.
* **L and s0 free**: IPOPT through CasADi (:func:`eqrec.design.augmented.nlp.solve_free_ipopt`),
  started from the LP solution at a pole-placement ``L``.

Every design is certified from its converted time-based gains with
:func:`eqrec.bounds.certify.certify_schedule`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from eqrec.bounds.certify import CERT_RTOL, certify_design, certify_schedule
from eqrec.checks import instance
from eqrec.lp.model import LPSolution
from eqrec.arrivals.words import as_language, worst_case_pattern
from eqrec.lp.solvers import solver_info
from eqrec.bounds.stacking import Stacking
from eqrec.systems.affine import AffineSystem
from eqrec.design.augmented.word_lp import AugmentedLP
from eqrec.design.inputs import check_flags, check_mu1, check_solver, check_system, real_array
from eqrec.design.augmented.model import (DESIGN_MODES, AugmentedGains, check_mode, default_runtime,
                                          missing_data_pattern)
from eqrec.design.augmented.runtime import schedule_from_augmented
from eqrec.design.augmented.nlp import solve_free_ipopt
from eqrec.design.observers import default_poles, observability_rank, place_observer
from eqrec.design.result import Design
from eqrec.errors import InfeasibleDesign, InputError, SolverFailure


def certify_augmented(system: AffineSystem, gains: AugmentedGains, words, mu1: float, runtime: str | None = None):
    """Certify the converted time-based schedule of ``gains`` (the estimator as it really runs).

    Parameters
    ----------
    system : AffineSystem
        The system.
    gains : AugmentedGains
        Augmented gains ``(M, ν, L, s0)`` along one word.
    words : sequence of str or ArrivalPattern
        Words on which the schedule is certified.
    mu1 : float
        Recovery level ``μ1``.
    runtime : {"theorem2", "hold"} or None, optional
        Reading of a missing step at run time (default: ``"theorem2"`` for a ``"theorem2"`` design, else
        ``"hold"``).

    Returns
    -------
    schedule : GainSchedule
        The converted time-based gains.
    certificate : Certificate
        Their certificate (:func:`eqrec.bounds.certify.certify_schedule`) on ``words``.
    """
    schedule = schedule_from_augmented(system, gains, runtime)
    return schedule, certify_schedule(system, schedule, list(words), mu1)


@dataclass
class AugmentedDetails:
    """What an augmented design adds to its :class:`~eqrec.design.result.Design` (its ``augmented`` field).

    Parameters
    ----------
    mode : str
        The runtime the LP designed for (:data:`~eqrec.design.augmented.model.DESIGN_MODES`).
    gains : AugmentedGains
        The augmented gains ``(L, s0, M, nu)`` (:mod:`eqrec.design.augmented.model`).
    L : list
        ``L`` as nested lists: one ``n x p`` matrix when constant over time, else ``T x n x p``.
    s0, M, nu : list
        ``s0``, ``M`` and ``nu`` as nested lists.
    eig_A_minus_LC : list of complex
        The eigenvalues of ``A - L(0) C``.
    poles : list of complex or None, optional
        The poles ``L`` was placed at (``L`` by pole placement or free); ``None``: ``L`` given.
    ipopt_status : str or None, optional
        ``L="free"``: IPOPT's status (``None`` otherwise, as the three below).
    ipopt_iterations : int or None, optional
        IPOPT's iterations.
    initial_mu2 : float or None, optional
        The LP's ``μ2`` IPOPT started from.
    initial_guess : str or None, optional
        That starting point in words.
    certified_runtime : str or None, optional
        A ``"leak"`` or ``"masked_gain"`` design: the runtime its certificate is of (``"hold"``); ``None`` for
        ``"theorem2"``, certified as designed.
    """

    mode: str
    gains: AugmentedGains
    L: list
    s0: list
    M: list
    nu: list
    eig_A_minus_LC: list
    poles: list | None = None
    ipopt_status: str | None = None
    ipopt_iterations: int | None = None
    initial_mu2: float | None = None
    initial_guess: str | None = None
    certified_runtime: str | None = None


def design_augmented(system: AffineSystem, words, mu1: float, *, L=None, poles=None, s0=None,
                     solver: str = "highs", mode: str = "theorem2", certify: bool = True,
                     ipopt_options: dict | None = None) -> Design:
    r"""Design the augmented estimator of the augmented paper for the worst-case word of ``words``.

    The state-augmented estimator of eqs. (2), (3) of the augmented paper
    (Hassaan, Shen, Yong, ACC 2019) carries the estimate ``x̂`` and an
    auxiliary state ``s``, a Luenberger-like estimate of the error, with
    gains ``L_k``, ``M(k, i)``, ``ν_k`` and initial ``s0``
    (:mod:`eqrec.design.augmented.model`).  For a language of 0/1 words
    it is designed on the worst-case word (bitwise AND, Section III-C) by
    Theorem 2 / eq. (12): minimise ``μ2`` subject to equalized recovery
    with zero gains on the missing measurements.  With ``L`` and ``s0``
    fixed the robust problem (Proposition 1 / eq. (11) with the constraints
    of Theorem 2) is a linear program (Remark 1); with ``L="free"`` it is
    bilinear and solved locally by IPOPT.  The design is certified from its
    converted time-based gains (:func:`eqrec.bounds.certify.certify_schedule`),
    i.e. the estimator as it really runs, on every word of the language and
    the worst case.

    Parameters
    ----------
    system : AffineSystem
        The system (``W_k`` of the paper is ``system.E``).
    words : sequence of str or ArrivalPattern
        The language: 0/1 words (or missing-data patterns) of one length.
    mu1 : float
        Recovery level ``μ1``, positive.
    L : None, array_like or "free", optional
        ``None``: pole placement at ``poles`` (default :func:`eqrec.design.observers.default_poles`), then the LP;
        an array of shape ``(n, p)`` or ``(T, n, p)``: the LP with this ``L``;
        ``"free"``: IPOPT on Proposition 1 with ``L`` and ``s0`` free, started from the
        LP at the pole-placement ``L``.
    poles : array_like or None, optional
        ``n`` eigenvalues of ``A - L C`` for the pole placement (``L`` not
        an array); default :func:`eqrec.design.observers.default_poles`
        (``{0, 0.5, -0.5}`` for ``n = 3``).
    s0 : array_like or None, optional
        Fixed ``s0``, shape ``(n,)`` (default 0; the initial guess when ``L="free"``).
    solver : str, optional
        LP solver of the registry :data:`eqrec.lp.solvers.SOLVER_NAMES` (with ``L="free"``:
        the solver of the LP that gives IPOPT its starting point).
    mode : {"theorem2", "leak", "masked_gain"}, optional
        ``"theorem2"`` (default: the text of Theorem 2, ``L_k = 0`` at a
        missing step) or another reading of the missing steps
        (:mod:`eqrec.design.augmented.model`); a ``"leak"`` or
        ``"masked_gain"`` design is certified as the actual (``"hold"``)
        estimator and its design ``μ2`` is not a guarantee.
    certify : bool, optional
        Certify the converted gains and attach the certificate (default).
    ipopt_options : dict or None, optional
        Options passed to IPOPT (``L="free"`` only).

    Returns
    -------
    Design
        ``method="augmented"``, ``schedule`` the converted time-based gains,
        ``certificate`` attached, ``language`` and ``worst_case_word``, ``augmented`` (an
        :class:`AugmentedDetails`: ``L, s0, M, nu`` and solver details).

    Raises
    ------
    InputError
        Malformed words, ``L``, ``s0`` or ``poles`` of the wrong shape, an
        unknown ``mode``, or a failed pole placement.
    InfeasibleDesign
        If ``(A, C)`` is not observable (no pole placement) or no estimator
        recovers to ``mu1``.
    SolverFailure
        If the LP solver or IPOPT stops without an optimum.
    CertificationFailure
        If (mode ``"theorem2"``) the converted gains do not achieve the
        optimised ``μ2`` or ``μ1`` to the solver's accuracy; within it the
        stored levels are raised to the certified worst cases
        (:func:`eqrec.bounds.certify.certify_design`, ``μ1`` possibly a few
        ulps above the request).

    Examples
    --------
    The language ``{101111, 110111}`` of Section IV-B of the augmented paper
    (worst case ``100111``), ``μ1 = 1``, ``L`` by pole placement:

    >>> import eqrec
    >>> design = eqrec.design_augmented(eqrec.acc_system(), ["101111", "110111"], mu1=1.0)
    >>> design.worst_case_word, round(design.mu2, 4)
    ('100111', 1.7371)
    """
    check_mode(mode, DESIGN_MODES)
    system = check_system(system)
    check_solver(solver)
    check_flags(certify=certify)
    instance(ipopt_options, (dict, type(None)), "ipopt_options", "a dict or None")
    patterns = as_language(words, kind="missing")
    mu1 = check_mu1(mu1)
    wc_pattern = missing_data_pattern(worst_case_pattern(patterns))
    language = tuple(p.label for p in patterns)
    wc = wc_pattern.label
    accuracy = solver_info(solver).accuracy
    T, n, p = len(wc), system.n, system.p
    ipopt: dict = {}  # L free: IPOPT's record (AugmentedDetails)
    placed = None
    free = isinstance(L, str)
    if free and L != "free":
        raise InputError(f"L must be None, an array or 'free', got {L!r}", field="L")
    if s0 is not None and real_array(s0, "s0").shape != (n,):
        raise InputError(f"s0 must be a vector of n = {n} entries (the state dimension), got shape "
                         f"{np.shape(s0)}", field="s0")
    if L is None or free:
        rank = observability_rank(system.A_at(0), system.C_at(0))
        if rank < n:
            raise InfeasibleDesign(f"(A, C) is not observable (rank {rank} of the observability matrix, n = {n}): "
                                   "no observer gain L places the eigenvalues of A - L C, so no augmented "
                                   "design with L by pole placement exists; give L explicitly (--L)")
        poles = default_poles(system.n) if poles is None else real_array(poles, "poles", complex_ok=True)
        if poles.shape != (n,):
            raise InputError(f"give n = {n} poles, got {poles.size}", field="poles")
        pp = place_observer(system.A_at(0), system.C_at(0), poles)
        if not pp.ok:
            raise InputError(f"pole placement at {poles} failed: {pp.message}", field="poles")
        L_fixed = pp.L
        placed = [complex(x) for x in poles]
    else:
        L_fixed = real_array(L, "L")
        if L_fixed.shape not in ((n, p), (T, n, p)):
            raise InputError(f"L must be an n x p = {n} x {p} matrix (or T x n x p), got shape {L_fixed.shape}",
                             field="L")
    s0v = np.zeros(n) if s0 is None else real_array(s0, "s0").reshape(n)
    st = Stacking(system, T)  # the design's one stacked model: the LP and its augmented maps read it
    model = AugmentedLP(st, wc, mu1, L_fixed, s0=s0v, mode=mode)
    sol = model.solve(solver).require_optimal(f"augmented design (M1 = {mu1:g})")
    gains = model.gains(sol)
    mu2 = float(sol.x[model.mu2_col])
    solution = sol
    if free:
        res = solve_free_ipopt(model, gains, mu2, free_L=True, free_s0=True, options=ipopt_options)
        if not res.success:
            raise SolverFailure(f"IPOPT stopped with status {res.status} after {res.iterations} iterations")
        gains, mu2 = res.gains, res.mu2
        solution = LPSolution("optimal", None, mu2, "ipopt", res.iterations, res.solve_time, {})
        ipopt = {"ipopt_status": res.status, "ipopt_iterations": res.iterations, "initial_mu2": res.initial_mu2,
                 "initial_guess": f"LP ({solver}) at the pole-placement L"}
        accuracy = max(accuracy, solver_info("ipopt").accuracy)
    details = AugmentedDetails(
        mode=mode, gains=gains, L=gains.L[0].tolist() if np.allclose(gains.L, gains.L[0]) else gains.L.tolist(),
        s0=gains.s0.tolist(), M=gains.M.tolist(), nu=gains.nu.tolist(),
        eig_A_minus_LC=[complex(x) for x in np.linalg.eigvals(system.A_at(0) - gains.L[0] @ system.C_at(0))],
        poles=placed, **ipopt)
    runtime = default_runtime(mode)
    schedule = schedule_from_augmented(system, gains, runtime)
    design = Design(method="augmented", system=system, patterns=(wc,), T=T, mu1=float(mu1), mu2=mu2,
                    schedule=schedule, solution=solution, build_time=model.build_time, language=language,
                    worst_case_word=wc, augmented=details)
    if certify:
        cert_words = sorted(set(language) | {wc})
        if mode == "theorem2":  # every stored level at least its certified worst case, exactly (M1 raised if need be)
            certify_design(design, words=cert_words, rtol=CERT_RTOL + accuracy)
        else:
            design.certificate = certify_schedule(system, schedule, cert_words, mu1)
            details.certified_runtime = runtime
    return design
