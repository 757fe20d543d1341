"""The package's imports, read with :mod:`ast` (nothing imported): the code inputs of every rule.

A rule lists as ``code`` inputs the source files of the module defining its
step's function and of every ``eqrec`` module that imports, transitively, plus
the harness that runs it (:func:`code_inputs`), so editing code a step does
not import (a figure's rule does not import the LP modules) does not re-run
its job.  The step's module is read from the step registry (:func:`step_module`:
the ``STEPS`` tables each study's branch of :func:`eqrec.studies.pipeline.steps.steps_of`
imports; a table lists functions defined in its own module, by name) without
importing them: the Snakefile asks at planning time, and importing the study
modules there would cost seconds.

:func:`eqrec_imports` is the package's one import walker (also used by the
layer and circle checks of ``tests/test_architecture.py``).
"""

from __future__ import annotations

import ast
import functools
from pathlib import Path

from eqrec.errors import StepError


def _package_root() -> Path:
    local = Path("src") / "eqrec"
    return local if local.is_dir() else Path(__file__).resolve().parents[2]


#: Imports the code-input walk does not follow: the configuration checks run when the workflow is planned, never
#: inside a step through the harness (a changed check re-validates the configuration at the next start; a step
#: that imports them itself lists them); the step registry imports the modules of every study, and a step's code
#: is its own module and what that imports.
NOT_FOLLOWED = frozenset({("eqrec.studies.pipeline.configuration", "eqrec.studies.pipeline.checks"),
                          ("eqrec.studies.pipeline.harness", "eqrec.studies.pipeline.steps")})

#: The step registry: its ``steps_of`` imports the ``STEPS`` tables of each study.
REGISTRY = "eqrec.studies.pipeline.steps"


def module_path(name: str, pkg: Path | None = None) -> Path | None:
    """The source file of the ``eqrec`` module ``name`` (``None`` if there is none, e.g. a function's name)."""
    return _module_path(name, pkg or _package_root())


@functools.lru_cache(maxsize=None)
def _module_path(name: str, pkg: Path) -> Path | None:
    parts = name.split(".")
    if parts[0] != "eqrec":
        return None
    base = pkg.joinpath(*parts[1:])
    for cand in (base.with_suffix(".py"), base / "__init__.py"):
        if cand.is_file():
            return cand
    return None


def _tree(path: Path) -> ast.Module:
    """A source file's syntax tree (not kept: the caches hold what is read from it, freeing a tree costs time)."""
    return ast.parse(path.read_text())


def eqrec_imports(path: str | Path) -> list[str]:
    """The ``eqrec`` names one source file imports, read with :mod:`ast` (nothing imported).

    ``from eqrec.a import b`` gives ``eqrec.a`` and ``eqrec.a.b`` (``b`` may be
    a module or a name); ``import eqrec.a`` gives ``eqrec.a``.  Imports inside
    functions count: a lazy import is still a dependency.  The one import
    walker of the package (code inputs here, the layer and circle checks of
    ``tests/test_architecture.py``).
    """
    path = Path(path)
    return list(_imports_of(path, path.stat().st_mtime_ns))


@functools.lru_cache(maxsize=None)
def _imports_of(path: Path, mtime_ns: int) -> tuple[str, ...]:
    """:func:`eqrec_imports`, walked once per file version."""
    out: list[str] = []
    for node in ast.walk(_tree(path)):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "eqrec":
            out.append(node.module)
            out += [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Import):
            out += [a.name for a in node.names if a.name.split(".")[0] == "eqrec"]
    return tuple(out)


def module_closure(*roots: str) -> list[str]:
    """Source files of the ``eqrec`` modules ``roots`` and of every module they import, transitively
    (a package's modules import the package's ``__init__`` first), except the edges in :data:`NOT_FOLLOWED`."""
    pkg = _package_root()
    seen: dict[Path, str] = {}
    todo = [(None, r) for r in roots]
    while todo:
        importer, name = todo.pop()
        if (importer, name) in NOT_FOLLOWED:
            continue
        path = module_path(name, pkg)
        if path is None or path in seen:
            continue
        seen[path] = name
        parent = name.rpartition(".")[0]
        if parent:
            todo.append((name, parent))
        todo += [(name, imported) for imported in eqrec_imports(path)]
    return sorted(str(p) for p in seen)


def _table(module: str, name: str) -> ast.Dict:
    for node in _tree(module_path(module)).body:
        targets = node.targets if isinstance(node, ast.Assign) else [node.target] if isinstance(node, ast.AnnAssign) else []
        if any(isinstance(t, ast.Name) and t.id == name for t in targets) and isinstance(node.value, ast.Dict):
            return node.value
    raise StepError(f"{module} has no table {name} = {{...}}")


def _step_names(module: str, table: str) -> tuple[str, ...]:
    """The step names of one ``STEPS`` table; each lists a function defined in that module by its name."""
    path = module_path(module)
    return _step_names_of(module, table, path.stat().st_mtime_ns if path else 0)


@functools.lru_cache(maxsize=None)
def _step_names_of(module: str, table: str, mtime_ns: int) -> tuple[str, ...]:
    defined = {node.name for node in _tree(module_path(module)).body if isinstance(node, ast.FunctionDef)}
    node = _table(module, table)
    for key, value in zip(node.keys, node.values):
        if not (isinstance(key, ast.Constant) and isinstance(key.value, str)):
            raise StepError(f"{module}.{table}: keys are step names")
        if not (isinstance(value, ast.Name) and value.id in defined):
            raise StepError(f"{module}.{table}[{key.value!r}]: a step table lists functions defined in its own "
                            f"module, by name (got {ast.unparse(value)!r})")
    return tuple(k.value for k in node.keys)


def _study_tables() -> dict[str, list[tuple[str, str]]]:
    """``study -> [(module, "STEPS"), ...]`` from the registry's ``steps_of``: each ``if study == "p1":`` branch
    imports the study's modules (``from eqrec.studies import p1, p1_figures``) and lists their tables
    (``tables = p1.STEPS, p1_figures.STEPS``)."""
    path = module_path(REGISTRY)
    return _study_tables_of(path, path.stat().st_mtime_ns)


@functools.lru_cache(maxsize=None)
def _study_tables_of(path: Path, mtime_ns: int) -> dict[str, list[tuple[str, str]]]:
    out: dict[str, list[tuple[str, str]]] = {}
    for node in ast.walk(_tree(path)):
        if not (isinstance(node, ast.If) and isinstance(node.test, ast.Compare)
                and isinstance(node.test.comparators[0], ast.Constant)):
            continue
        local = {a.asname or a.name: f"{stmt.module}.{a.name}" for stmt in node.body
                 if isinstance(stmt, ast.ImportFrom) for a in stmt.names}
        tables = [v for stmt in node.body if isinstance(stmt, ast.Assign)
                  for v in (stmt.value.elts if isinstance(stmt.value, ast.Tuple) else [stmt.value])]
        out[node.test.comparators[0].value] = [(local[t.value.id], t.attr) for t in tables
                                               if isinstance(t, ast.Attribute) and isinstance(t.value, ast.Name)]
    return out


def step_module(study: str, step: str) -> str:
    """The module defining the function of step ``(study, step)``, read with :mod:`ast` from the step registry
    (:func:`eqrec.studies.pipeline.steps.steps_of`) and the study's ``STEPS`` table; nothing is imported, so the
    Snakefile can ask."""
    studies = _study_tables()
    if study not in studies:
        raise StepError(f"unknown study {study!r}; choose from {list(studies)}")
    steps = {name: module for module, table in studies[study] for name in _step_names(module, table)}
    if step not in steps:
        raise StepError(f"study {study!r} has no step {step!r}; steps: {sorted(steps)}")
    return steps[step]


def code_inputs(study: str, step: str) -> list[str]:
    """Source files a rule lists as code inputs: the module defining its step's function and every ``eqrec``
    module that imports, transitively, plus the harness that runs it.

    Editing code the step does not import (a figure's rule does not import
    the LP modules) does not re-run its job.
    """
    return module_closure(step_module(study, step), "eqrec.studies.pipeline.harness")
