"""eqrec.io.compiled_once: on a fresh Numba cache the first job runs alone and leaves a marker; later jobs run at
once (issue 40: a first ``snakemake`` compiles the kernels once, not once per job)."""

import fcntl

import numba
import pytest

from eqrec.io import compiled_once


@pytest.fixture
def cache(tmp_path, monkeypatch):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    return tmp_path


def _locked_elsewhere(lock_file) -> bool:
    """Whether another open file description holds the lock (as another job's process would see it)."""
    with open(lock_file, "a") as other:
        try:
            fcntl.flock(other, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            return True
        fcntl.flock(other, fcntl.LOCK_UN)
        return False


def test_the_first_run_holds_the_lock_then_leaves_the_marker(cache):
    with compiled_once():
        assert _locked_elsewhere(cache / "eqrec-compile.lock")
        assert not list(cache.glob("eqrec-compiled-*"))
    assert len(list(cache.glob("eqrec-compiled-*"))) == 1
    assert not _locked_elsewhere(cache / "eqrec-compile.lock")
    with compiled_once():  # warm: no lock taken
        assert not _locked_elsewhere(cache / "eqrec-compile.lock")


def test_a_failed_first_run_leaves_no_marker_and_no_lock(cache):
    with pytest.raises(RuntimeError):
        with compiled_once():
            raise RuntimeError("killed while compiling")
    assert not list(cache.glob("eqrec-compiled-*"))
    assert not _locked_elsewhere(cache / "eqrec-compile.lock")
    with compiled_once():  # the next job compiles, alone
        assert _locked_elsewhere(cache / "eqrec-compile.lock")


def test_without_file_locks_every_job_runs_as_before(cache, monkeypatch):
    def refuse(*_):
        raise OSError(37, "No locks available")
    monkeypatch.setattr(fcntl, "flock", refuse)
    ran = []
    with compiled_once():
        ran.append(1)
    assert ran == [1] and not list(cache.glob("eqrec-compiled-*"))
