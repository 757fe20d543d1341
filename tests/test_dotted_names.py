"""Every dotted ``eqrec.`` name a reader meets in the texts resolves to a module or an object (issue 25).

The texts: the claims file, the READMEs, the documentation's pages, the notebook sources, the report captions,
and the text files under
``results/`` (tables, reports, JSON, executed notebooks; not the timings).
"""
import pkgutil
import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOTTED = re.compile(r"\beqrec(?:\.[A-Za-z_][A-Za-z0-9_]*)+")
TEXT_SUFFIXES = {".md", ".csv", ".json", ".ipynb", ".txt", ".yaml", ".rst"}


def _texts() -> list[Path]:
    files = [ROOT / "config" / "claims.yaml", ROOT / "README.md", ROOT / "config" / "README.md"]
    files += [p for p in sorted((ROOT / "docs").rglob("*.md")) + sorted((ROOT / "docs").glob("*.rst"))
              if not {"_build", "auto_examples", "generated"} & set(p.relative_to(ROOT / "docs").parts)]
    files += sorted((ROOT / "notebooks").glob("*.py")) + sorted((ROOT / "workflow" / "report").glob("*.rst"))
    files += [p for p in sorted((ROOT / "results").rglob("*"))
              if p.suffix in TEXT_SUFFIXES and "timings" not in p.relative_to(ROOT).parts]
    return [f for f in files if f.is_file()]


def _unresolved(text: str) -> set[str]:
    bad = set()
    for match in DOTTED.finditer(text):
        name = match.group(0)
        try:
            pkgutil.resolve_name(name)
        except (ImportError, AttributeError, ValueError):
            bad.add(name)
    return bad


def test_the_finder_finds_a_stale_name():
    assert _unresolved("see eqrec.augmented and eqrec.systems.affine.AffineSystem") == {"eqrec.augmented"}


@pytest.mark.parametrize("path", _texts(), ids=lambda p: str(p.relative_to(ROOT)))
def test_every_dotted_name_resolves(path):
    bad = _unresolved(path.read_text(encoding="utf-8", errors="replace"))
    assert not bad, f"{path.relative_to(ROOT)} names {sorted(bad)}, which do not exist"
