"""Write requirements/pipeline.lock: the exact versions of this environment that eqrec and its extras need.

The lock is a pip constraints file (``pip install -c requirements/pipeline.lock -e ".[pipeline]"``): every
distribution that eqrec's dependencies and extras (``pipeline``, ``docs``, ``test``, ``dask``, ``control``,
``slurm``) pull in, transitively, at the version installed here, sorted by name.  These are the versions under
which ``results/`` is reproduced byte for byte and the test suite passes; ``pyproject.toml`` declares the
compatible ranges.  To move the lock: install the new versions, run the tests and ``snakemake --cores 2
--forceall`` (``results/`` outside ``results/timings/`` must not change, or be regenerated in a commit of its
own), then ``python requirements/lock.py`` and commit the lock.
"""
from __future__ import annotations

import importlib.metadata as md
import re
import sys
import tomllib
from pathlib import Path

from packaging.markers import default_environment
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]
EXTRAS = ("pipeline", "docs", "test", "dask", "control", "slurm")


def _key(name: str) -> str:
    return re.sub(r"[-_.]+", "-", name).lower()


def _project_requirements(extras: tuple[str, ...]) -> list[str]:
    """eqrec's own requirements with ``extras``, read from pyproject.toml (not from an installed copy)."""
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    out, todo, done = list(project["dependencies"]), list(extras), set()
    while todo:
        extra = todo.pop()
        if extra in done:
            continue
        done.add(extra)
        for text in project["optional-dependencies"][extra]:
            req = Requirement(text)
            if _key(req.name) == "eqrec":
                todo.extend(req.extras)
            else:
                out.append(text)
    return out


def closure(extras: tuple[str, ...] = EXTRAS) -> dict[str, str]:
    """Every installed distribution ``eqrec[extras]`` needs, transitively: normalised name -> version."""
    seen: dict[str, str] = {}
    todo: list[tuple[str, frozenset[str]]] = [("eqrec", frozenset(extras))]
    done: set[tuple[str, frozenset[str]]] = set()
    while todo:
        name, wanted = todo.pop()
        if (name, wanted) in done:
            continue
        done.add((name, wanted))
        if name == "eqrec":
            requires = _project_requirements(tuple(wanted))
        else:
            dist = md.distribution(name)
            seen[_key(dist.metadata["Name"])] = dist.version
            requires = dist.requires or []
        for text in requires:
            req = Requirement(text)
            env = default_environment()
            active = req.marker is None or any(req.marker.evaluate({**env, "extra": e}) for e in (wanted or {""}))
            if not active:
                continue
            try:
                md.distribution(req.name)
            except md.PackageNotFoundError:
                raise SystemExit(f"{req.name} (needed by {name}) is not installed: install eqrec[{','.join(EXTRAS)}]")
            todo.append((req.name, frozenset(req.extras)))
    return seen


def main() -> int:
    pins = closure()
    lines = [
        "# The exact versions under which results/ is reproduced byte for byte and the test suite passes",
        "# (pip constraints; written by `python requirements/lock.py`, which says how to move it).",
        '# pip install -c requirements/pipeline.lock -e ".[pipeline]"   (or ".[test]", ".[docs]", ".[slurm]")',
        f"# Python {sys.version_info.major}.{sys.version_info.minor} on Linux x86_64.",
        *[f"{name}=={version}" for name, version in sorted(pins.items())],
    ]
    (ROOT / "requirements" / "pipeline.lock").write_text("\n".join(lines) + "\n", encoding="utf-8")
    print(f"requirements/pipeline.lock: {len(pins)} distributions")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
