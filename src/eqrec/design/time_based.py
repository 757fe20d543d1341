"""Time-based equalized-recovery design (the authors' earlier work, ref. [10] of the prefix-based paper).

The time-based estimator (eq. (6)) chooses its gains by time only and is
designed for the worst-case word of the language (bitwise AND), with zero
gain on the measurements the worst-case word lacks; an estimator for the
worst-case word then works for every word of the language.  It is the
single-word special case of :func:`eqrec.design_prefix.design_prefix`.
"""

from __future__ import annotations

from eqrec.core.certify import certify_design
from eqrec.design.prefix import design_prefix
from eqrec.design.result import Design
from eqrec.core.patterns import validate_language, worst_case_word
from eqrec.core.systems import AffineSystem


def design_time_based(system: AffineSystem, words, M1: float, *, solver: str = "highs",
                      certify: bool = True, form: str = "split") -> Design:
    """Minimise ``M2`` of a time-based estimator for the worst-case word of ``words``.

    The certificate covers every word of the language and the worst-case word.
    """
    language = validate_language(words)
    wc = worst_case_word(language)
    design = design_prefix(system, [wc], M1, solver=solver, form=form, certify=False, method="time")
    design.extra["language"] = language
    design.extra["worst_case_word"] = wc
    if certify:
        certify_design(design, words=sorted(set(language) | {wc}))
    return design
