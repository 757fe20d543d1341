"""The step registry: every pipeline step, as the study modules hand them over.

Each module that defines steps lists them in a ``STEPS`` table (step name ->
``step(cfg, inputs, outputs, wildcards)``; ``p1`` its computations,
``p1_figures`` its figures, ...); :func:`steps_of` imports the modules of a
study by explicit import statements, so the import graph shows which modules
the workflow runs (no module loaded by name), while a job imports only its
own study.  A study module does not import its figures module to list its
steps: a figure's rule lists as code inputs what drawing imports, not the
LPs.  The harness
(:mod:`eqrec.studies.pipeline.harness`) looks a step up here.  The Snakefile does not
import this module (a study module imports the solvers); it reads the same
statements and tables with :mod:`ast` to list each rule's code inputs
(:func:`eqrec.studies.pipeline.imports.step_module`).
"""

from __future__ import annotations

from typing import Any, Callable

from eqrec.errors import StepError

Step = Callable[..., Any]

#: The studies with pipeline steps (``compare`` runs every estimator family on the same traces, ``claims`` builds
#: the comparison table, ``notebooks`` executes the notebooks).
STUDIES = ("p1", "p2", "p3", "p4", "compare", "claims", "notebooks")


def steps_of(study: str) -> dict[str, Step]:
    """The steps of one study (step name -> function): the ``STEPS`` tables of the modules that define them,
    importing that study's modules only."""
    if study == "p1":
        from eqrec.studies.p1 import steps as p1, figures as p1_figures

        tables = p1.STEPS, p1_figures.STEPS
    elif study == "p2":
        from eqrec.studies.p2 import steps as p2, figures as p2_figures, sweeps as p2_sweeps, values as p2_values

        tables = p2.STEPS, p2_sweeps.STEPS, p2_values.STEPS, p2_figures.STEPS
    elif study == "p3":
        from eqrec.studies.p3 import steps as p3, figures as p3_figures, scale_table as p3_scale, free_table as p3_scale_free, strategy as p3_strategy, values as p3_values

        tables = (p3.STEPS, p3_figures.STEPS, p3_values.STEPS, p3_strategy.STEPS, p3_scale.STEPS,
                  p3_scale_free.STEPS)
    elif study == "p4":
        from eqrec.studies.p4 import steps as p4, figures as p4_figures, values as p4_values

        tables = p4.STEPS, p4_figures.STEPS, p4_values.STEPS
    elif study == "compare":
        from eqrec.studies.compare import steps as compare

        tables = (compare.STEPS,)
    elif study == "claims":
        from eqrec.studies.claims import table as claims

        tables = (claims.STEPS,)
    elif study == "notebooks":
        from eqrec.studies.notebooks import execute as notebooks

        tables = (notebooks.STEPS,)
    else:
        raise StepError(f"unknown study {study!r}; choose from {list(STUDIES)}")
    steps: dict[str, Step] = {}
    for table in tables:
        twice = steps.keys() & table.keys()
        if twice:
            raise StepError(f"study {study!r}: steps {sorted(twice)} are listed twice")
        steps.update(table)
    return steps


def registry() -> dict[tuple[str, str], Step]:
    """``(study, step) -> function`` for every step of every study."""
    return {(study, name): fn for study in STUDIES for name, fn in steps_of(study).items()}


def get_step(study: str, step: str) -> Step:
    """The function of one step; :class:`~eqrec.errors.StepError` naming the choices otherwise."""
    table = steps_of(study)
    if step not in table:
        raise StepError(f"study {study!r} has no step {step!r}; steps: {sorted(table)}")
    return table[step]
