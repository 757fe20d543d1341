"""A hard kill and a resume leave results/ exactly as an uninterrupted run writes it (issue 44).

The workflow runs in a temporary copy of the repository (Snakefile, workflow/, config/, the default profile
and results/, committed in a git repository of its own) on the P4 sweeps: the targets ``p4_fig5 p4_fig6``,
five jobs (three temp() chunks and the two steps that merge them), about 30 s of work on 2 cores.
Snakemake runs in a process group of its own and the whole group is killed with SIGKILL:

* in a first run of the targets (their results removed), after the first job has ended (others running),
  while jobs compute, and right after a merging job has ended; after each kill the same command is
  refused by the lock, with the advice of eqrec.studies.pipeline.resume (the lock is stale; the one
  command that resumes), then ``snakemake --unlock`` and the same command go on;
* in the window where the orphaned chunk of the issue came from: a merging job has ended and Snakemake
  has not yet removed its temp() chunk.  A kill right after the "Finished" line of the merge hits it only
  sometimes (Snakemake removes the chunk a few milliseconds later), so this run keeps its chunks
  (``--notemp``), which makes the state of that kill certain: the chunk is left, outside results/.

After the resumes ``git status --porcelain --untracked-files=all -- results ':!results/timings'`` must be
empty: no orphaned chunk, no partial file, every result byte-identical to the committed one.  A write killed
half-way (the temporary file of eqrec.io.atomic_path, made by a real SIGKILL inside it) is left in results/
before a resume: the resumed job removes it (eqrec.io.remove_stale_temporaries, from workflow/scripts/run_step.py).
"""
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from eqrec.io import remove_stale_temporaries
from eqrec.studies.pipeline import resume

ROOT = Path(__file__).resolve().parents[1]
SNAKEMAKE = [sys.executable, "-m", "snakemake"]
TARGETS = ["p4_fig5", "p4_fig6"]
#: The targets' results (the chunks are temp() files, under intermediate/).
OUTPUTS = ["fig5_eta.pdf", "fig5_eta.png", "sweep_eta.npz", "fig6_q.pdf", "fig6_q.png", "sweep_q.npz",
           "regions.pdf", "regions.png"]
ETA_CHUNK = Path("intermediate/p4/sweep_eta/chunk_1-of-1.npz")
FINISHED = re.compile(r"^Finished jobid: \d+ \(Rule: (\w+)\)")
TIMEOUT = 600


def git(repo, *args):
    out = subprocess.run(["git", "-c", "user.name=test", "-c", "user.email=test@example.org", *args], cwd=repo,
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    return out.stdout


def results_status(repo):
    """What git sees changed or new under results/ outside results/timings/ (empty: as committed)."""
    return git(repo, "status", "--porcelain", "--untracked-files=all", "--", "results", ":!results/timings")


def snakemake(repo, args, kill=None):
    """Run Snakemake in ``repo`` in a process group of its own.

    ``kill(line, finished)`` (an output line, the rules finished so far) returns True to SIGKILL the whole
    group there, or a number of seconds to do it that much later.  Returns (exit code, output, rules
    finished, killed)."""
    proc = subprocess.Popen(SNAKEMAKE + args, cwd=repo, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                            text=True, start_new_session=True)
    fired = threading.Event()

    def fire():
        if proc.poll() is None:
            fired.set()
            os.killpg(proc.pid, signal.SIGKILL)

    lines, finished, timers, start = [], [], [], time.monotonic()
    watchdog = threading.Timer(TIMEOUT, lambda: proc.poll() is None and os.killpg(proc.pid, signal.SIGKILL))
    watchdog.start()
    try:
        for line in proc.stdout:
            lines.append(line)
            if match := FINISHED.match(line):
                finished.append(match[1])
            when = kill(line, finished) if kill is not None and not fired.is_set() and not timers else False
            if when is True:
                fire()
                break
            if when:
                timers.append(threading.Timer(when, fire))
                timers[-1].start()
    finally:
        for timer in (watchdog, *timers):
            timer.cancel()
        proc.stdout.close()
        proc.wait(timeout=60)
    assert time.monotonic() - start < TIMEOUT, "".join(lines)[-3000:]
    print(f"snakemake {' '.join(args)}: exit {proc.returncode}, {time.monotonic() - start:.1f} s, "
          f"finished {finished}" + (", killed" if fired.is_set() else ""))
    return proc.returncode, "".join(lines), finished, fired.is_set()


def after_rule(rule):
    """Kill right after ``rule``'s job is reported finished."""
    return lambda line, finished: bool(FINISHED.match(line)) and finished[-1] == rule


def after_first_job(line, finished):
    """Kill right after the first job is reported finished (the others still run)."""
    return bool(FINISHED.match(line))


def while_running(line, finished):
    """Kill 2 s after the first jobs start (they compute then: each takes several seconds)."""
    return 2.0 if line.startswith("Execute") else False


def killed_write(path):
    """What a SIGKILL inside eqrec.io.atomic_path leaves: the temporary file beside ``path`` (made by a child
    process killed half-way through its write)."""
    code = ("import os, signal, sys\nfrom eqrec.io import atomic_path\n"
            "with atomic_path(sys.argv[1]) as tmp:\n"
            "    tmp.write_bytes(b'half a file')\n"
            "    os.kill(os.getpid(), signal.SIGKILL)\n")
    out = subprocess.run([sys.executable, "-c", code, str(path)], capture_output=True, timeout=120)
    assert out.returncode == -signal.SIGKILL
    left = [p for p in path.parent.iterdir() if p.name.startswith(f".{path.name}.") and p.name.endswith(".tmp")]
    assert len(left) == 1, left
    return left[0]


def refused_then_unlocked(repo, args):
    """The same command after a kill: refused by the lock, with the advice naming the command that resumes;
    then ``snakemake --unlock``.  False when the kill came after the last job (nothing left to do: Snakemake
    takes no lock then, and the stale one stays until the unlock)."""
    code, text, _, _ = snakemake(repo, args)
    refused = "Nothing to be done" not in text
    if refused:
        assert code != 0 and "LockException" in text, text[-3000:]
        assert "The lock is stale" in text, text[-3000:]
        assert f"snakemake --unlock && snakemake {' '.join(args)}" in text, text[-3000:]
    code, text, _, _ = snakemake(repo, ["--unlock"])
    assert code == 0 and "Unlocked" in text, text[-3000:]
    return refused


@pytest.fixture
def repo(tmp_path):
    """A git repository holding the workflow and the committed results (the working tree's), nothing else."""
    for item in ("Snakefile", "workflow", "config", "results", "profiles"):  # profiles/default: rerun-incomplete
        src = ROOT / item
        if src.is_symlink():
            (tmp_path / item).symlink_to(os.readlink(src))
        else:
            (shutil.copytree if src.is_dir() else shutil.copy)(src, tmp_path / item)
    (tmp_path / ".gitignore").write_text(".snakemake/\nlogs/\nintermediate/\n")
    git(tmp_path, "init", "-q")
    git(tmp_path, "add", "-A")
    git(tmp_path, "commit", "-q", "-m", "results as committed")
    return tmp_path


@pytest.mark.slow
def test_kills_and_resumes_leave_results_as_an_uninterrupted_run(repo):
    # a first run of the targets, their results removed so that every job runs, killed at three points
    for name in OUTPUTS:
        (repo / "results" / "p4" / name).unlink()
    args = ["--cores", "2", *TARGETS]
    finished, kills, refusals = [], [], []
    for kill in (after_first_job, while_running, after_rule("p4_fig5")):
        code, text, done, killed = snakemake(repo, args, kill)
        finished += done
        if not killed:  # the run ended before this kill point
            assert code == 0, text[-3000:]
            break
        kills.append(done)
        if len(kills) == 1:  # a write killed half-way in results/, beside an output of a job yet to run
            assert "p4_fig6" not in finished
            leftover = killed_write(repo / "results" / "p4" / "fig6_q.pdf")
        refusals.append(refused_then_unlocked(repo, args))
    else:
        code, text, done, _ = snakemake(repo, args)
        assert code == 0, text[-3000:]
        finished += done
    assert "Using workflow specific profile profiles/default" in text  # the README's default profile
    assert len(kills) >= 2 and refusals[:2] == [True, True], (kills, refusals)  # two kills with jobs left
    assert sorted(set(finished)) == ["p4_fig5", "p4_fig6", "p4_sweep_eta_chunk", "p4_sweep_q_chunk"], finished
    assert not leftover.exists()
    assert results_status(repo) == ""

    # the orphan's window, made certain: the merge has ended, its chunk is still there; killed
    notemp = ["--cores", "2", "--notemp", "--forcerun", "p4_fig5", "--", "p4_fig5"]
    code, text, done, killed = snakemake(repo, notemp, after_rule("p4_fig5"))
    assert killed and done[-1:] == ["p4_fig5"], text[-3000:]  # (its chunk re-made first if it was gone)
    assert (repo / ETA_CHUNK).is_file()  # what the kill left: outside results/
    refused_then_unlocked(repo, notemp)
    code, text, done, _ = snakemake(repo, args)  # the resume of the first command: nothing left to do
    assert code == 0 and done == [], text[-3000:]
    assert results_status(repo) == ""
    code, text, _, _ = snakemake(repo, ["--delete-temp-output", *TARGETS])  # what removes such a leftover
    assert code == 0 and not (repo / ETA_CHUNK).exists(), text[-3000:]
    assert results_status(repo) == ""


def test_stale_temporaries_of_the_outputs_only_are_removed(tmp_path):
    out = tmp_path / "fig.pdf"
    out.write_bytes(b"old")
    left = killed_write(out)
    other = killed_write(tmp_path / "fig.pdf.png")  # another output's leftover: not this job's to remove
    keep = [tmp_path / ".fig.pdf.tmp", tmp_path / ".fig.pdf.abc.tmp", tmp_path / "x.fig.pdf.abcdefgh.tmp"]
    for path in keep:
        path.write_text("not a leftover of atomic_path for fig.pdf")
    assert remove_stale_temporaries([out, tmp_path / "missing" / "a.json"]) == [left]
    assert not left.exists() and other.exists() and out.read_bytes() == b"old"
    assert all(path.exists() for path in keep)


def test_lock_advice_tells_a_stale_lock_from_a_running_snakemake(tmp_path):
    assert resume.lock_advice(tmp_path, ["--cores", "2"]) is None  # no lock
    locks = tmp_path / ".snakemake" / "locks"
    locks.mkdir(parents=True)
    (locks / "0.output.lock").write_text("results/p1/model.json\n")
    sub = tmp_path / "results"
    sub.mkdir()
    if resume.snakemake_processes(tmp_path) is None:
        pytest.skip("no /proc here: the advice cannot tell a stale lock")
    # a process whose command line says snakemake, working in a folder of the directory: the lock is held
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(120)", "snakemake"], cwd=sub)
    try:
        deadline = time.monotonic() + 30
        while sleeper.pid not in resume.snakemake_processes(tmp_path) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert sleeper.pid in resume.snakemake_processes(tmp_path)
        advice = resume.lock_advice(tmp_path, ["--cores", "2"])
        assert "still runs" in advice and str(sleeper.pid) in advice and "--unlock &&" not in advice
    finally:
        sleeper.kill()
        sleeper.wait()
    assert sleeper.pid not in resume.snakemake_processes(tmp_path)
    advice = resume.lock_advice(tmp_path, ["--cores", "2", "p1"])
    assert "The lock is stale" in advice and "snakemake --unlock && snakemake --cores 2 p1" in advice


def test_resume_command_keeps_the_location_options():
    assert resume.resume_command(["--cores", "2"]) == "snakemake --unlock && snakemake --cores 2"
    assert resume.resume_command(["--directory=/data/run", "--configfile", "my.yaml"]) == (
        "snakemake --directory=/data/run --unlock && snakemake --directory=/data/run --configfile my.yaml")
    assert resume.resume_command(["-s", "Snakefile", "-d", "a b"]) == (
        "snakemake -s Snakefile -d 'a b' --unlock && snakemake -s Snakefile -d 'a b'")
    assert resume.resume_command(None).startswith("snakemake --unlock && ")
