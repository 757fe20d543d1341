"""The code inputs of a rule: the source files of the modules its step imports, from the package's import graph.

A rule lists as ``code`` inputs the source file of the module defining its
step (``"eqrec.studies.p1.steps:step_designs"``), of every ``eqrec`` module
that module imports, transitively, and of the harness that runs it
(:func:`code_inputs`), so editing code a step does not import (a figure's
step imports no LP module) does not re-run its job.  The imports are those
:mod:`grimp` finds in the source (lazy imports inside functions included),
plus the parent packages a module's import runs first; the graph is built
once per planning (a few hundredths of a second: no cache).  Nothing of the
studies is imported here: the Snakefile asks at planning time.
"""

from __future__ import annotations

import functools
from pathlib import Path

import eqrec
from eqrec.errors import StepError
from eqrec.studies.pipeline.configuration import CLAIMS_MODULE, SECTIONS

#: Imports the walk does not follow: the configuration's cross-field checks run when the workflow is planned,
#: never inside a step through the harness (a changed check re-validates the configuration at the next start;
#: a step that imports the checks itself lists them).
NOT_FOLLOWED = {("eqrec.studies.pipeline.configuration", "eqrec.studies.pipeline.checks")}

HARNESS = "eqrec.studies.pipeline.harness"

#: The claims table imports each study's :data:`~eqrec.studies.pipeline.configuration.CLAIMS_MODULE` by name
#: (:func:`eqrec.studies.claims.table.load_reasons`); the walk follows these imports as if they were written.
CLAIMS_TABLE = "eqrec.studies.claims.table"


@functools.cache
def _graph():
    import grimp

    graph = grimp.build_graph("eqrec", cache_dir=None)
    for module in graph.modules - {"eqrec"}:  # importing a.b.c runs a/__init__ and a/b/__init__ first
        graph.add_import(importer=module, imported=module.rpartition(".")[0])
    for importer, imported in NOT_FOLLOWED:  # (no error if the import is not there)
        graph.remove_import(importer=importer, imported=imported)
    for name in {CLAIMS_MODULE.format(study) for study in SECTIONS} & graph.modules:  # the table's imports by name
        graph.add_import(importer=CLAIMS_TABLE, imported=name)
    return graph


def _path(module: str) -> str:
    """The source file of an ``eqrec`` module: under ``src/eqrec`` when planning from the repository (paths
    relative to the workflow), else where the package is installed."""
    local = Path("src") / "eqrec"
    base = (local if local.is_dir() else Path(eqrec.__file__).parent).joinpath(*module.split(".")[1:])
    return str(base / "__init__.py" if base.is_dir() else base.with_suffix(".py"))


def code_inputs(step: str) -> list[str]:
    """Source files a rule lists as code inputs: the module of ``step`` (``"module:function"``), every ``eqrec``
    module it imports, transitively (except the edges of :data:`NOT_FOLLOWED`), and the harness with its own."""
    graph, module = _graph(), step.partition(":")[0]
    if module not in graph.modules:
        raise StepError(f"step {step!r}: no module {module!r} in the package (a step is 'eqrec.module:function')")
    roots = {module, HARNESS}
    modules = roots | {m for root in roots for m in graph.find_upstream_modules(root)}
    return sorted(_path(m) for m in modules)
