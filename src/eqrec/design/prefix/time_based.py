"""Time-based equalized-recovery design (the authors' earlier work, ref. [10] of the prefix-based paper).

The time-based estimator (eq. (6) of the prefix-based paper) chooses its
gains by time only and is designed for the worst-case pattern of the language
(each measurement at its latest arrival; for missing data the bitwise AND),
with zero gain on the measurements the worst case lacks; an estimator for the
worst case then works for every pattern of the language.  It is the
single-pattern special case of :func:`eqrec.design.prefix.design.design_prefix`.
"""

from __future__ import annotations

from eqrec.bounds.certify import certify_design
from eqrec.arrivals.words import as_language, worst_case_pattern
from eqrec.systems.affine import AffineSystem
from eqrec.design.prefix.design import design_prefix
from eqrec.design.inputs import check_flags, check_system
from eqrec.design.result import Design
from eqrec.design.weighted import weigh


def design_time_based(system: AffineSystem, words, mu1: float, *, solver: str = "highs",
                      certify: bool = True, form: str = "split", engine: str = "classes",
                      state_weights=None) -> Design:
    """Minimise ``M2`` of a time-based estimator for the worst-case pattern of ``words``.

    The time-based estimator (eqs. (5), (6) of the prefix-based paper, the
    authors' earlier work, ref. [10] there) has gains ``F(t, τ)``, ``u0(t)``
    that depend on time only.  It is designed for the worst-case pattern of
    the language (each measurement at its latest arrival; for missing-data
    words the bitwise AND, Section III of the prefix-based paper), with zero
    gain on the measurements the worst case lacks, so it works for every
    word of the language.  The design is the single-word prefix design
    (:func:`design_prefix`, Remark 2 / Theorem 3 of the prefix-based paper)
    on the worst-case pattern (one word: its classes are its nodes, so the
    class engine applies; ``engine="tree"`` uses the tree LP).  The
    certificate covers every pattern of the language and the worst case.

    Parameters
    ----------
    system : AffineSystem
        The system.
    words : sequence of str or ArrivalPattern
        The language: arrival patterns or 0/1 words of one length.
    mu1 : float or "free"
        Recovery level ``μ1`` (the prefix-based paper's ``M1``), positive, or
        ``"free"``: the smallest feasible one (as for :func:`design_prefix`).
    solver : str, optional
        LP solver (default ``"highs"``), as for :func:`design_prefix`.
    certify : bool, optional
        Certify the gains independently (:func:`eqrec.bounds.certify.certify_design`)
        on every word of the language and the worst case (default).
    form : str, optional
        Robust counterpart of the tree LP (``"split"``, ``"abs"`` or the
        paper's Π-dual ``"dual"``); ``engine="tree"`` only.
    engine : {"classes", "tree"}, optional
        The class engine (default) or the tree LP of :mod:`eqrec.design.prefix.design`.
    state_weights : array_like or None, optional
        ``n`` positive per-state weights ``w``: every level and certificate
        then bounds ``max_i w_i |x_i − x̂_i|`` (the design is made on
        ``z = W x``, :meth:`AffineSystem.scaled`; :meth:`Design.estimator`
        runs in the original state).  ``None`` (default): ``‖x − x̂‖∞``.

    Returns
    -------
    Design
        ``method="time"``, one pattern (the worst case), ``mu2`` the
        optimal ``M2``; ``language`` and ``worst_case_word``.

    Raises
    ------
    InputError
        Malformed words, words of mixed lengths, a non-positive ``mu1`` or an
        unknown engine.
    InfeasibleDesign
        If no time-based estimator recovers to ``mu1``.
    SolverFailure
        If the solver stops without an optimum.
    CertificationFailure
        If the recovered gains do not achieve the optimum on some word.

    Examples
    --------
    The language ``L1`` of Section VI of the prefix-based paper: the design is
    the prefix design on its worst-case word alone (claim P1-M2:time-L1 compares
    the level with the paper's):

    >>> import eqrec
    >>> words = ["101111", "110111", "111011", "111101"]
    >>> design = eqrec.design_time_based(eqrec.acc_system(), words, mu1=1.0)
    >>> worst = design.worst_case_word
    >>> bool(design.mu2 == eqrec.design_prefix(eqrec.acc_system(), [worst], mu1=1.0).mu2)
    True
    """
    system, weights = weigh(check_system(system), state_weights)
    check_flags(certify=certify)
    language = as_language(words, kind="missing")
    wc = worst_case_pattern(language)
    design = design_prefix(system, [wc], mu1, solver=solver, form=form, certify=False, method="time",
                           engine=engine)
    design.state_weights = weights
    design.language = tuple(p.label for p in language)
    design.worst_case_word = wc.label
    if certify:
        certify_design(design, words=sorted(set(language) | {wc}, key=lambda p: p.label))
    return design
