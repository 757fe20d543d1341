"""The package as a library: a wheel and an sdist, installed beside other packages.

* ``python -m build`` makes a wheel and an sdist of the checkout; the wheel carries the package, its ``py.typed``
  and the ``eqrec`` command, its metadata the compatible ranges of ``pyproject.toml`` (no exact pin).
* The wheel installs in a fresh virtual environment next to the **latest** ``control`` and ``cvxpy`` the package
  index offers (no constraints file: pip resolves the ranges), and the getting-started page's Python code runs
  there as written, outside the checkout; so does ``eqrec design`` on the page's system file.
* ``pyproject.toml``'s ranges admit the lock's versions, every direct requirement is in the lock, and each range's
  lower bound is the locked version (so the lower bounds are exactly what ``.ci/run`` installs and tests).

The fresh environment takes a few minutes to install on 2 cores (numpy, scipy, numba, casadi, ...), once per
session.  ``EQREC_SKIP_WHEEL_TEST=1`` skips it (for a machine without a package index).
"""
from __future__ import annotations

import json
import os
import re
import subprocess
import sys
import tomllib
import venv
import zipfile
from pathlib import Path

import pytest
from packaging.requirements import Requirement

ROOT = Path(__file__).resolve().parents[1]


def _project() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]


def _lock() -> dict[str, str]:
    pins = {}
    for line in (ROOT / "requirements" / "pipeline.lock").read_text(encoding="utf-8").splitlines():
        if line.strip() and not line.startswith("#"):
            name, _, version = line.partition("==")
            pins[re.sub(r"[-_.]+", "-", name).lower()] = version.strip()
    return pins


def _requirements() -> list[Requirement]:
    project = _project()
    texts = list(project["dependencies"])
    for extra in project["optional-dependencies"].values():
        texts += extra
    return [Requirement(t) for t in texts if not t.startswith("eqrec[")]


def test_the_ranges_admit_the_lock_and_pin_nothing():
    lock = _lock()
    assert len(lock) > 50
    for req in _requirements():
        key = re.sub(r"[-_.]+", "-", req.name).lower()
        assert key in lock, f"{req.name} is not in requirements/pipeline.lock"
        assert req.specifier.contains(lock[key], prereleases=True), f"{req} does not admit the locked {lock[key]}"
        assert not any(spec.operator == "==" for spec in req.specifier), f"{req}: a library declares ranges"
        # each lower bound is the locked version: the lower bounds are what .ci/run installs and tests
        lower = [spec.version for spec in req.specifier if spec.operator == ">="]
        assert lower == [lock[key]], f"{req}: lower bound {lower} is not the locked {lock[key]}"


def _getting_started_code() -> str:
    text = (ROOT / "docs" / "getting-started.md").read_text(encoding="utf-8")
    blocks = re.findall(r"```python\n(.*?)```", text, flags=re.S)
    assert len(blocks) >= 2
    return "\n".join(blocks)


def _system_file() -> str:
    text = (ROOT / "docs" / "getting-started.md").read_text(encoding="utf-8")
    return re.search(r"```yaml\n(.*?)```", text, flags=re.S).group(1)


@pytest.fixture(scope="module")
def dist(tmp_path_factory):
    out = tmp_path_factory.mktemp("dist")
    run = subprocess.run([sys.executable, "-m", "build", "--sdist", "--wheel", "--outdir", str(out), str(ROOT)],
                         capture_output=True, text=True, timeout=900)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    wheels, sdists = sorted(out.glob("eqrec-*.whl")), sorted(out.glob("eqrec-*.tar.gz"))
    assert len(wheels) == 1 and len(sdists) == 1, list(out.iterdir())
    return {"wheel": wheels[0], "sdist": sdists[0], "dir": out}


def test_build_makes_a_wheel_and_an_sdist_with_ranges(dist):
    with zipfile.ZipFile(dist["wheel"]) as whl:
        names = whl.namelist()
        metadata = whl.read(next(n for n in names if n.endswith(".dist-info/METADATA"))).decode()
        entry = whl.read(next(n for n in names if n.endswith(".dist-info/entry_points.txt"))).decode()
    assert "eqrec/__init__.py" in names and "eqrec/py.typed" in names
    assert "eqrec/estimators/zonotope.py" in names
    assert "eqrec = eqrec.cli:main" in entry
    requires = [line for line in metadata.splitlines() if line.startswith("Requires-Dist:")]
    assert any(line.startswith("Requires-Dist: numpy<3,>=") or line.startswith("Requires-Dist: numpy>=")
               for line in requires), requires
    pinned = [line for line in requires
              if any(spec.operator in ("==", "===") for spec in Requirement(line.split(":", 1)[1]).specifier)]
    assert not pinned, pinned
    assert (dist["sdist"].stat().st_size > 100_000)


@pytest.mark.skipif(os.environ.get("EQREC_SKIP_WHEEL_TEST") == "1", reason="EQREC_SKIP_WHEEL_TEST=1")
def test_the_wheel_installs_beside_the_latest_control_and_cvxpy_and_the_getting_started_page_runs(dist, tmp_path):
    env_dir = tmp_path / "venv"
    venv.EnvBuilder(with_pip=True, clear=True).create(env_dir)
    python = env_dir / "bin" / "python"
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONPATH", "VIRTUAL_ENV", "PIP_CONSTRAINT")}
    env["OPENBLAS_CORETYPE"] = os.environ.get("OPENBLAS_CORETYPE", "Haswell")
    install = subprocess.run([str(python), "-m", "pip", "install", "--quiet", str(dist["wheel"]), "control", "cvxpy"],
                             capture_output=True, text=True, env=env, timeout=1800)
    assert install.returncode == 0, install.stdout[-3000:] + install.stderr[-3000:]
    check = subprocess.run([str(python), "-m", "pip", "check"], capture_output=True, text=True, env=env, timeout=300)
    assert check.returncode == 0, check.stdout + check.stderr
    versions = subprocess.run([str(python), "-c", "import importlib.metadata as m; print(m.version('control'), "
                               "m.version('cvxpy'), m.version('numpy'), m.version('scipy'))"],
                              capture_output=True, text=True, env=env, timeout=120)
    print(f"beside control, cvxpy, numpy, scipy = {versions.stdout.strip()}")
    work = tmp_path / "user"  # outside the checkout: the installed wheel, not the source tree, is imported
    work.mkdir()
    (work / "getting_started.py").write_text(
        "import eqrec, pathlib\nassert 'site-packages' in pathlib.Path(eqrec.__file__).as_posix()\n"
        + _getting_started_code(), encoding="utf-8")
    run = subprocess.run([str(python), "getting_started.py"], cwd=work, capture_output=True, text=True, env=env,
                         timeout=900)
    assert run.returncode == 0, run.stdout[-3000:] + run.stderr[-3000:]
    assert "mu1 = 1.1300, levels inside a block <= 1.2530" in run.stdout, run.stdout
    errors = re.findall(r"error ([0-9.]+) <= bound ([0-9.]+)", run.stdout)
    assert len(errors) == 9 and all(float(e) <= float(b) for e, b in errors), run.stdout
    (work / "my_plant.yaml").write_text(_system_file(), encoding="utf-8")
    cli = subprocess.run([str(env_dir / "bin" / "eqrec"), "design", "my_plant.yaml", "--method", "delay", "--delays",
                          "000,300,030,003", "--mu1", "free", "--out", "design.json"],
                         cwd=work, capture_output=True, text=True, env=env, timeout=600)
    assert cli.returncode == 0, cli.stdout + cli.stderr
    assert "mu1 = 1.13, mu2 = 1.253" in cli.stderr and (work / "design.json").is_file(), cli.stderr
    # without --out the design is JSON on stdout, and nothing else (no solver banner)
    piped = subprocess.run([str(env_dir / "bin" / "eqrec"), "design", "my_plant.yaml", "--method", "delay", "--delays",
                            "000,300,030,003", "--mu1", "free"], cwd=work, capture_output=True, text=True, env=env,
                           timeout=600)
    assert piped.returncode == 0, piped.stderr
    assert json.loads(piped.stdout)["mu2"] == pytest.approx(1.253), piped.stdout[:500]
