"""Mutation probe of the code of issue 41: plant one bug at a time, run the targeted tests, restore the file.

Each mutation replaces one exact piece of text (found exactly once) in one file of ``src/eqrec``, runs the tests
that should catch it (``pytest -x -q``, stopped at the first failure), and restores the file byte for byte,
whatever happens (``finally``, and a SIGINT/SIGTERM handler; the originals are also kept in memory and checked
against ``git diff`` at the end).  The table says, per mutation, caught (by which test) or survived.

Run::

    python benchmarks/mutation_probe.py          # all 15
    python benchmarks/mutation_probe.py -k cache  # the mutations whose id contains "cache"
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "eqrec"


#: Address space of a mutant's test run (bytes): a planted bug that drops a size refusal makes its tests start the
#: huge job; they then fail with a MemoryError instead of taking the shared machine's memory (one took 17 GB).
MEMORY_LIMIT = 6 * 2**30


def _limit_memory() -> None:
    import resource

    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_LIMIT, MEMORY_LIMIT))


@dataclass(frozen=True)
class Mutation:
    id: str
    file: str  # under src/eqrec
    old: str
    new: str
    tests: tuple[str, ...]  # pytest arguments (files or node ids)
    what: str  # the bug, in words


DESIGN_FILES = ("tests/test_design_files.py", "tests/test_silent_inputs.py")
MUTATIONS = [
    Mutation("tree-mu2-not-recertified", "design/saved.py",
             "    if check.off(mu2, earned_mu2):\n",
             "    if False and check.off(mu2, earned_mu2):\n",
             DESIGN_FILES, "a node-gain design's stored mu2 is not compared with what its gains earn"),
    Mutation("class-K-nan-accepted", "design/saved.py",
             'gain = _finite_array(row["K"], (system.n, len(available) * system.p), source, f"{where}.K")',
             'gain = np.asarray(row["K"], dtype=float).reshape(system.n, len(available) * system.p)',
             DESIGN_FILES, "a class gain is read without its finiteness and shape check"),
    Mutation("class-certified-not-compared", "design/saved.py",
             "            if check.off(certified[i], float(cc.levels[i])):\n",
             "            if False:\n",
             DESIGN_FILES, "a class's stored certified level is not compared with its recomputed worst case"),
    Mutation("class-k-unbounded", "design/saved.py",
             'k = _integer(row["k"], source, f"{where}.k", 1, T)',
             'k = _integer(row["k"], source, f"{where}.k", 1, 10**9)',
             DESIGN_FILES, "a class depth past T is accepted (k = 99: a raw IndexError before issue 41)"),
    Mutation("file-V-ignored", "design/saved.py",
             '("A", "C", "E", "eta_w", "eta_v", "B", "f", "V")},',
             '("A", "C", "E", "eta_w", "eta_v", "B", "f")},',
             DESIGN_FILES, "load_design ignores the plant's V (the issue's planted bug)"),
    Mutation("class-set-not-checked", "design/saved.py",
             '    words = data.get("words")\n    if "max_delay" in data and "horizon" in data:',
             '    return\n    words = data.get("words")\n    if "max_delay" in data and "horizon" in data:',
             DESIGN_FILES, "a class row dropped from a file is accepted (the census's finding)"),
    Mutation("J-not-checked", "design/saved.py",
             "    _check_cost(design, check)\n",
             "    pass\n",
             DESIGN_FILES, "a delay design's stored J is not compared with the cost of its levels"),
    # the tests of a refusal run the huge job when the refusal is gone: a few of them, under the memory limit
    Mutation("size-refusal-dropped", "design/inputs.py",
             "    if reason is not None and not force:\n",
             "    if reason is not None and force == 'never':\n",
             ("tests/test_design_size.py", "-k", "huge_class_sets or min_recovery_level_is_estimated"),
             "the size model prints its estimate but never refuses"),
    Mutation("force-string-read-as-true", "design/inputs.py",
             "    check_flags(force=force)  # a string such as \"no\" would read as true, and run past the limits\n",
             "    pass\n",
             ("tests/test_design_size.py",), "force='yes' is accepted by the size model (read as true)"),
    Mutation("trace-delay-overflow", "arrivals/traces.py",
             "        if raw.size and np.any(raw > MAX_TRACE_DELAY):",
             "        if False:",
             ("tests/test_information_limit.py", "tests/test_slipped_through.py", "tests/test_arrivals.py"),
             "ArrivalTrace accepts a delay of 2**63 - 1 (its arrival time overflows to -2**63)"),
    Mutation("information-cache-key-coarse", "bounds/information.py",
             "key = (ctx, t, np.packbits(delivered_at[: t + 1] <= t).tobytes())",
             "key = (ctx, t, int(np.count_nonzero(delivered_at[: t + 1] <= t)))",
             ("tests/test_information_limit.py",),
             "the information limit's cache is keyed by the number of delivered measurements, not the sets"),
    Mutation("zonotope-reset-t0-wraps", "estimators/zonotope.py",
             "if lim is not None and not 0 <= self._model_time(int(t0)) < lim:",
             "if lim is not None and not self._model_time(int(t0)) < lim:",
             ("tests/test_slipped_through.py", "tests/test_zonotope.py"),
             "ZonotopeEstimator.reset(t0=-3) on a time-varying plant reads A[-3] by wrap-around"),
    Mutation("zonotope-reset-overflow-unchecked", "estimators/zonotope.py",
             "        if not np.all(reach <= MAX_SET_REACH):\n",
             "        if False:\n",
             ("tests/test_slipped_through.py", "tests/test_zonotope.py", "tests/test_atomic_steps.py"),
             "a zonotope set whose first prediction overflows is accepted (reset x0_radius=1e308)"),
    Mutation("data-overflow-unchecked", "arrivals/packets.py",
             "    if value.size and float(np.max(np.abs(value))) > MAX_DATA_MAGNITUDE:\n",
             "    if False:\n",
             ("tests/test_atomic_steps.py",),
             "measurements, inputs and initial estimates of 1e308 reach the estimators (inf / NaN estimates)"),
    Mutation("state-bounds-strict-mu1", "estimators/guaranteed.py",
             "            return np.full(self.system.n, self.bound)\n",
             "            return np.full(self.system.n, self.mu1)\n",
             ("tests/test_out_of_language.py", "tests/test_silent_inputs.py", "tests/test_exact_bound_total.py"),
             "state_bounds under strict=True gives mu1, not the designed level of the current estimate"),
]


_ORIGINALS: dict[Path, bytes] = {}


def _restore_all() -> None:
    for path, text in _ORIGINALS.items():
        if path.read_bytes() != text:
            path.write_bytes(text)


def _on_signal(signum, frame):  # noqa: ARG001 - restore, then stop
    _restore_all()
    sys.exit(128 + signum)


def probe(m: Mutation, timeout: float) -> dict:
    path = SRC / m.file
    original = path.read_bytes()
    _ORIGINALS.setdefault(path, original)
    text = original.decode("utf-8")
    count = text.count(m.old)
    if count != 1:
        return {"id": m.id, "status": "error", "by": f"the text is found {count} times", "seconds": 0.0}
    start = time.perf_counter()
    try:
        path.write_text(text.replace(m.old, m.new), encoding="utf-8")
        env = {**os.environ, "PYTHONPATH": str(ROOT / "src"), "PYTHONDONTWRITEBYTECODE": "1"}
        try:
            run = subprocess.run([sys.executable, "-m", "pytest", "-x", "-q", "-p", "no:cacheprovider",
                                  "-p", "no:randomly", *m.tests], cwd=ROOT, env=env, capture_output=True, text=True,
                                 timeout=timeout, preexec_fn=_limit_memory)
        except subprocess.TimeoutExpired:
            return {"id": m.id, "status": "timeout", "by": f"no verdict in {timeout:.0f} s",
                    "seconds": time.perf_counter() - start}
    finally:
        path.write_bytes(original)
    failed = [line for line in run.stdout.splitlines() if line.startswith(("FAILED", "ERROR"))]
    status = "caught" if run.returncode != 0 else "survived"
    by = failed[0].split(" - ")[0].replace("FAILED ", "").replace("ERROR ", "") if failed else ""
    if status == "caught" and not by and "MemoryError" in run.stdout:
        by = (f"{' '.join(m.tests)}: a test started the job and ran out of the probe's {MEMORY_LIMIT / 2**30:.0f} GiB "
              "(MemoryError)")
    elif status == "caught" and not by:
        by = f"exit {run.returncode}: " + (run.stdout.strip().splitlines() or [""])[-1][:120]
    return {"id": m.id, "status": status, "by": by, "seconds": time.perf_counter() - start}


def main(argv: "list[str] | None" = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-k", default="", help="only the mutations whose id contains this")
    parser.add_argument("--timeout", type=float, default=600.0, help="seconds per mutation's tests")
    args = parser.parse_args(argv)
    signal.signal(signal.SIGINT, _on_signal)
    signal.signal(signal.SIGTERM, _on_signal)
    rows = []
    try:
        for m in MUTATIONS:
            if args.k not in m.id:
                continue
            row = probe(m, args.timeout)
            rows.append(row)
            print(f"{row['status']:8s} {m.id:36s} {row['seconds']:6.0f} s  {row['by']}", flush=True)
    finally:
        _restore_all()
    dirty = subprocess.run(["git", "diff", "--stat", "--", "src"], cwd=ROOT, capture_output=True, text=True).stdout
    caught = sum(r["status"] == "caught" for r in rows)
    print(f"caught {caught} of {len(rows)}; src restored{' (git diff --stat src: ' + dirty.strip() + ')' if dirty else ''}")
    return 0 if caught == len(rows) else 1


if __name__ == "__main__":
    sys.exit(main())
