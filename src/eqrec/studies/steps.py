"""The step registry: every pipeline step, as the study modules hand them over.

Each study module lists its steps in a ``STEPS`` table (step name ->
``step(cfg, inputs, outputs, wildcards)``); this module imports every study
module and maps ``(study, step)`` to the function, so the import graph shows
which modules the workflow runs (no module loaded by name).  The harness
(:mod:`eqrec.studies.harness`) looks a step up here; the Snakefile never
imports this module (it would import every study), it reads the same tables
with :mod:`ast` to list each rule's code inputs
(:func:`eqrec.studies.harness.step_module`).
"""

from __future__ import annotations

from typing import Any, Callable

from eqrec.errors import StepError
from eqrec.studies import claims, notebooks, p1, p2, p3, p4

Step = Callable[..., Any]

#: study -> its ``STEPS`` table (``claims`` builds the comparison table, ``notebooks`` executes the notebooks).
STUDIES: dict[str, dict[str, Step]] = {
    "p1": p1.STEPS,
    "p2": p2.STEPS,
    "p3": p3.STEPS,
    "p4": p4.STEPS,
    "claims": claims.STEPS,
    "notebooks": notebooks.STEPS,
}


def registry() -> dict[tuple[str, str], Step]:
    """``(study, step) -> function`` for every step of every study."""
    return {(study, name): fn for study, table in STUDIES.items() for name, fn in table.items()}


def get_step(study: str, step: str) -> Step:
    """The function of one step; :class:`~eqrec.errors.StepError` naming the choices otherwise."""
    if study not in STUDIES:
        raise StepError(f"unknown study {study!r}; choose from {list(STUDIES)}")
    table = STUDIES[study]
    if step not in table:
        raise StepError(f"study {study!r} has no step {step!r}; steps: {sorted(table)}")
    return table[step]
