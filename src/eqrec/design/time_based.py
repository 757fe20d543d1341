"""Time-based equalized-recovery design (the authors' earlier work, ref. [10] of the prefix-based paper).

The time-based estimator (eq. (6) of the prefix-based paper) chooses its
gains by time only and is designed for the worst-case pattern of the language
(each measurement at its latest arrival; for missing data the bitwise AND),
with zero gain on the measurements the worst case lacks; an estimator for the
worst case then works for every pattern of the language.  It is the
single-pattern special case of :func:`eqrec.design.prefix.design_prefix`.
"""

from __future__ import annotations

from eqrec.core.certify import certify_design
from eqrec.core.patterns import as_language, worst_case_pattern
from eqrec.core.systems import AffineSystem
from eqrec.design.prefix import design_prefix
from eqrec.design.result import Design


def design_time_based(system: AffineSystem, words, M1: float, *, solver: str = "highs",
                      certify: bool = True, form: str = "split", engine: str = "classes") -> Design:
    """Minimise ``M2`` of a time-based estimator for the worst-case pattern of ``words``.

    ``words`` are arrival patterns or 0/1 words.  The design is the
    single-word prefix design on the worst-case pattern (one word: its
    classes are its nodes, so the class engine applies; ``engine="tree"``
    uses the tree LP).  The certificate covers every pattern of the
    language and the worst case.
    """
    language = as_language(words)
    wc = worst_case_pattern(language)
    design = design_prefix(system, [wc], M1, solver=solver, form=form, certify=False, method="time",
                           engine=engine)
    design.extra["language"] = tuple(p.label for p in language)
    design.extra["worst_case_word"] = wc.label
    if certify:
        certify_design(design, words=sorted(set(language) | {wc}, key=lambda p: p.label))
    return design
