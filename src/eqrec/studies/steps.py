"""The step registry: every pipeline step, as the study modules hand them over.

Each study module lists its steps in a ``STEPS`` table (step name ->
``step(cfg, inputs, outputs, wildcards)``); :func:`steps_of` imports the
module of a study by an explicit import statement, one per study, so the
import graph shows which modules the workflow runs (no module loaded by
name), while a job imports only its own study.  The harness
(:mod:`eqrec.studies.harness`) looks a step up here.  The Snakefile does not
import this module (a study module imports the solvers); it reads the same
statements and tables with :mod:`ast` to list each rule's code inputs
(:func:`eqrec.studies.imports.step_module`).
"""

from __future__ import annotations

from typing import Any, Callable

from eqrec.errors import StepError

Step = Callable[..., Any]

#: The studies with pipeline steps (``claims`` builds the comparison table, ``notebooks`` executes the notebooks).
STUDIES = ("p1", "p2", "p3", "p4", "claims", "notebooks")


def steps_of(study: str) -> dict[str, Step]:
    """The ``STEPS`` table of one study (step name -> function), importing that study's modules only."""
    if study == "p1":
        from eqrec.studies.p1 import STEPS
    elif study == "p2":
        from eqrec.studies.p2 import STEPS
    elif study == "p3":
        from eqrec.studies.p3 import STEPS
    elif study == "p4":
        from eqrec.studies.p4 import STEPS
    elif study == "claims":
        from eqrec.studies.claims import STEPS
    elif study == "notebooks":
        from eqrec.studies.notebooks import STEPS
    else:
        raise StepError(f"unknown study {study!r}; choose from {list(STUDIES)}")
    return STEPS


def registry() -> dict[tuple[str, str], Step]:
    """``(study, step) -> function`` for every step of every study."""
    return {(study, name): fn for study in STUDIES for name, fn in steps_of(study).items()}


def get_step(study: str, step: str) -> Step:
    """The function of one step; :class:`~eqrec.errors.StepError` naming the choices otherwise."""
    table = steps_of(study)
    if step not in table:
        raise StepError(f"study {study!r} has no step {step!r}; steps: {sorted(table)}")
    return table[step]
