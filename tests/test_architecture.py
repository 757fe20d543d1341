"""The import graph of ``src/eqrec``: every module in a layer (core <- design <- studies; lmv on its own; the CLI
and the package namespace on top), imports only downwards, and no circle between modules."""
from pathlib import Path

import pytest

from eqrec.studies.pipeline.imports import eqrec_imports

PKG = Path(__file__).resolve().parents[1] / "src" / "eqrec"

# subpackage -> subpackages (and top-level modules) it may import
ALLOWED = {
    "core": {"core", "errors"},
    "design": {"core", "design", "errors"},
    "lmv": {"lmv", "core", "errors"},
    "filters": {"core", "filters", "lmv", "errors"},
    "studies": {"core", "design", "lmv", "filters", "studies", "errors", "models", "io", "compare"},
    "interop": {"core", "design", "interop", "errors"},
    # top-level modules
    "errors": {"errors"},
    "io": set(),
    "models": {"core", "errors"},
    "cli": {"core", "design", "errors", "io", "cli_help", "compare", "__init__"},
    "cli_help": set(),
    "compare": {"core", "design", "filters", "lmv", "errors", "io", "compare"},
    "__main__": {"cli"},
    "__init__": {"core", "design", "filters", "lmv", "interop", "errors", "models"},
}


def _module_name(path: Path) -> str:
    parts = path.relative_to(PKG.parent).with_suffix("").parts
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def _layer(path: Path) -> str:
    rel = path.relative_to(PKG)
    return rel.parts[0] if len(rel.parts) > 1 else rel.stem


MODULES = {_module_name(f): f for f in sorted(PKG.rglob("*.py"))}


def _module_imports(path: Path) -> set[str]:
    """The ``eqrec`` modules a file imports (also inside functions: a lazy import is still a dependency), read by
    the package's one import walker."""
    return {name for name in eqrec_imports(path) if name in MODULES} - {_module_name(path)}


def _imports(path: Path):
    """The subpackages (or top-level modules) of ``eqrec`` a file imports from (``__init__`` for a name of the
    package itself, such as ``from eqrec import __version__``)."""
    for name in eqrec_imports(path):
        parts = name.split(".")
        if len(parts) > 1:
            yield parts[1] if f"eqrec.{parts[1]}" in MODULES else "__init__"


@pytest.mark.parametrize("sub", sorted(k for k in ALLOWED if (PKG / k).is_dir()))
def test_import_directions(sub):
    folder = PKG / sub
    if not folder.is_dir():
        pytest.skip(f"no subpackage {sub}")
    bad = {(f.name, target) for f in folder.rglob("*.py") for target in _imports(f) if target not in ALLOWED[sub]}
    assert not bad, f"eqrec.{sub} imports outside its layer: {sorted(bad)}"


def test_every_module_is_in_a_layer():
    """No module escapes the direction check (the CLI, the models, the namespace included)."""
    assert {_layer(f) for f in MODULES.values()} <= set(ALLOWED), sorted({_layer(f) for f in MODULES.values()})
    for name, f in MODULES.items():
        if len(f.relative_to(PKG).parts) == 1:  # a top-level module
            bad = {t for t in _imports(f) if t not in ALLOWED[_layer(f)]}
            assert not bad, f"{name} imports {sorted(bad)}"


def _circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    circles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on_stack.add(v)
        for w in sorted(graph.get(v, ())):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                circles.append(sorted(comp))

    for v in sorted(graph):
        if v not in index:
            visit(v)
    return circles


def test_circle_finder_finds_circles():
    assert _circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert _circles({"a": {"b"}, "b": set()}) == []


def test_no_import_circle_between_modules():
    graph = {name: _module_imports(f) for name, f in MODULES.items()}
    assert len(graph) > 50 and "eqrec.cli" in graph and "eqrec.systems.examples" in graph
    assert not _circles(graph), f"import circles: {_circles(graph)}"


def test_the_step_registry_imports_every_table_of_steps_and_nothing_loads_a_module_by_name():
    """The steps the workflow runs are edges of the graph: the registry imports each module with a STEPS table,
    and no study module imports another one only to list its steps (a figures module is not an edge of the
    study module, so a figure's rule does not list the LP code as its code)."""
    with_steps = {name for name, f in MODULES.items() if name.startswith("eqrec.studies.")
                  and any(line.startswith("STEPS = ") for line in f.read_text().splitlines())}
    registry = _module_imports(MODULES["eqrec.studies.pipeline.steps"])
    studies = {"eqrec.studies." + s for s in ("p1", "p2", "p3", "p4", "compare", "claims", "notebooks")}
    assert studies <= with_steps and with_steps <= registry
    for name in ("p1_figures", "p3_figures", "p3_strategy"):
        assert "eqrec.studies." + name in with_steps
    for study in ("p1", "p3"):
        assert not any(m.startswith(f"eqrec.studies.{study}_") for m in _module_imports(MODULES["eqrec.studies." + study]))
    for name, f in MODULES.items():
        if name.startswith("eqrec.studies"):
            assert "importlib" not in f.read_text() and "__import__" not in f.read_text(), name
