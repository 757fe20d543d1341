"""The issue-41 census of bad inputs (``benchmarks/census.py``), a fast subset: every size case (each must be
estimated and refused within 5 s), every step case of one estimator per kind of refusal, and every fourth of the
others.  Each must be *clear*: a documented error naming the field, or the CLI's documented exit code and a message
naming it; never raw, silent or a hang (the whole census: ``python benchmarks/census.py``)."""
from __future__ import annotations

import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "benchmarks"))

import census  # noqa: E402


def _subset():
    cases = census.all_cases()
    keep = [c for i, c in enumerate(cases) if "size" in c.id or "4-800" in c.id or "1e" in c.id or i % 4 == 0]
    return keep


def test_the_census_is_large_enough_and_its_ids_unique():
    cases = census.all_cases()
    ids = [c.id for c in cases]
    assert len(ids) == len(set(ids))
    python = [c for c in cases if isinstance(c, census.Py)]
    cli = [c for c in cases if isinstance(c, census.Cli)]
    assert len(python) >= 180 and len(cli) >= 70 and len(cases) >= 250


@pytest.fixture(scope="module")
def rows(tmp_path_factory):
    return census.run(_subset(), tmp=tmp_path_factory.mktemp("census"), verbose=False)


def test_a_subset_of_the_census_is_all_clear(rows):
    bad = [f"{r['status']} {r['id']}: {r['note']}" for r in rows if r["status"] != "clear"]
    assert len(rows) >= 80
    assert not bad, "\n".join(bad)
