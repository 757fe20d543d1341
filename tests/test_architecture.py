"""The import graph of ``src/eqrec``: every module in a layer (core <- design <- studies; lmv on its own; the CLI
and the package namespace on top), imports only downwards, and no circle between modules."""
import ast
from pathlib import Path

import pytest

PKG = Path(__file__).resolve().parents[1] / "src" / "eqrec"

# subpackage -> subpackages (and top-level modules) it may import
ALLOWED = {
    "core": {"core", "errors"},
    "design": {"core", "design", "errors"},
    "lmv": {"lmv", "errors"},
    "filters": {"core", "filters", "lmv", "errors"},
    "studies": {"core", "design", "lmv", "filters", "studies", "errors", "models", "io"},
    "interop": {"core", "design", "interop", "errors"},
    # top-level modules
    "errors": {"errors"},
    "io": set(),
    "models": {"core", "errors"},
    "cli": {"core", "design", "errors", "io", "__init__"},
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
    """The ``eqrec`` modules a file imports (also inside functions: a lazy import is still a dependency)."""
    out = set()
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.split(".")[0] == "eqrec":
            out |= {f"{node.module}.{a.name}" for a in node.names if f"{node.module}.{a.name}" in MODULES}
            if node.module in MODULES:
                out.add(node.module)
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names if a.name in MODULES}
    return out - {_module_name(path)}


def _imports(path: Path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("eqrec."):
            yield node.module.split(".")[1]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("eqrec."):
                    yield alias.name.split(".")[1]


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
    assert len(graph) > 50 and "eqrec.cli" in graph and "eqrec.models" in graph
    assert not _circles(graph), f"import circles: {_circles(graph)}"
