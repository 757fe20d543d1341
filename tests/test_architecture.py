"""Import directions between the subpackages: core <- design <- studies; lmv on its own; no cycles."""
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
    "studies": {"core", "design", "lmv", "filters", "studies", "errors", "models"},
    "interop": {"core", "design", "interop", "errors"},
}


def _imports(path: Path):
    tree = ast.parse(path.read_text())
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("eqrec."):
            yield node.module.split(".")[1]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("eqrec."):
                    yield alias.name.split(".")[1]


@pytest.mark.parametrize("sub", sorted(ALLOWED))
def test_import_directions(sub):
    folder = PKG / sub
    if not folder.is_dir():
        pytest.skip(f"no subpackage {sub}")
    bad = {(f.name, target) for f in folder.rglob("*.py") for target in _imports(f) if target not in ALLOWED[sub]}
    assert not bad, f"eqrec.{sub} imports outside its layer: {sorted(bad)}"
