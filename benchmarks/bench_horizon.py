"""Time of a ``--max-delay D --horizon T`` design as ``T`` grows, with the fitted growth exponent (figures, not
tests).

    python benchmarks/bench_horizon.py [--system examples/two_mass.yaml] [--max-delay 1]
                                       [--horizons 100,200,400,1000] [--jobs 2] [--mu1 free]

Each row runs ``eqrec design SYSTEM --method delay --max-delay D --horizon T --mu1 free`` in a fresh process (as a
user would; the pool start and the imports included), and prints the wall time, the peak memory of the process
tree when ``/usr/bin/time`` is there, the estimate of :func:`eqrec.design.inputs.estimate_delay_design`, and the
local growth exponent ``log(t_i / t_{i-1}) / log(T_i / T_{i-1})`` against the row before.  Then the exponent ``b``
of ``time ≈ a T^b`` fitted by least squares on the logs of the last three horizons, and what that fit predicts at
``T = 1000`` (issue 33 §2 asks for (1, 1000) within 60 s).

The time is mostly HiGHS's simplex on the class LPs.  Solved per class (a class of time ``d`` has about ``d p``
rows and ``d (nw + nv)`` columns, dense in ``w``, cold-started) the local exponent of the two-cart plant on two
cores rose from about 1.7 (T = 100 to 200) to about 2.7 (T = 400 to 1000): 288 s at T = 1000.  With maximum delay
1 the classes above :data:`eqrec.design.classes.blocks.LARGE_CLASS_WORK` (here from time 182) are solved in
state-space form along their chain, warm-started (:mod:`eqrec.design.classes.chains`): 9.5 s at T = 400, 46 s at
T = 1000, local exponent about 1.7.
"""

from __future__ import annotations

import argparse
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from eqrec.design.inputs import estimate_delay_design
from eqrec.systems.files import load_system

ROOT = Path(__file__).resolve().parents[1]


def _run(system: str, D: int, T: int, jobs: int, mu1: str) -> tuple[float, float | None, str]:
    """Wall seconds, peak memory (MiB, or None) and the last stderr line of one design."""
    with tempfile.TemporaryDirectory() as tmp:
        cmd = [sys.executable, "-m", "eqrec.cli", "design", system, "--method", "delay", "--max-delay", str(D),
               "--horizon", str(T), "--mu1", mu1, "--jobs", str(jobs), "--force", "--out", os.path.join(tmp, "d.json")]
        timer = ["/usr/bin/time", "-f", "peak %M KB"] if os.path.exists("/usr/bin/time") else []
        t0 = time.perf_counter()
        res = subprocess.run(timer + cmd, capture_output=True, text=True, cwd=ROOT)
        wall = time.perf_counter() - t0
    peak = re.search(r"peak (\d+) KB", res.stderr)
    lines = [line for line in res.stderr.splitlines() if line and not line.startswith("peak ")]
    status = "ok" if res.returncode == 0 else f"exit {res.returncode}: {lines[-1][:80] if lines else ''}"
    return wall, (int(peak.group(1)) / 1024 if peak else None), status


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--system", default=str(ROOT / "examples" / "two_mass.yaml"))
    ap.add_argument("--max-delay", type=int, default=1)
    ap.add_argument("--horizons", default="100,200,400,1000")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--mu1", default="free")
    args = ap.parse_args(argv)
    horizons = [int(t) for t in args.horizons.split(",")]
    system, _ = load_system(args.system)
    print(f"{Path(args.system).name}, D = {args.max_delay}, mu1 {args.mu1}, {args.jobs} jobs, "
          f"{os.cpu_count()} cores")
    print(f"{'T':>6} {'classes':>8} {'LP rows':>9} {'time s':>8} {'est. s':>8} {'peak MiB':>9} {'b local':>8}  status")
    times: list[float] = []
    for T in horizons:
        est = estimate_delay_design(system, args.max_delay, T, mu1_free=args.mu1 == "free", workers=args.jobs)
        wall, peak, status = _run(args.system, args.max_delay, T, args.jobs, args.mu1)
        local = np.log(wall / times[-1]) / np.log(T / horizons[len(times) - 1]) if times else None
        times.append(wall)
        print(f"{T:>6} {est.classes:>8} {est.lp_rows:>9.3g} {wall:>8.2f} {est.seconds:>8.1f} "
              f"{'-' if peak is None else f'{peak:.0f}':>9} {'-' if local is None else f'{local:.2f}':>8}  {status}",
              flush=True)
    if len(horizons) >= 2:
        k = min(3, len(horizons))
        b, loga = np.polyfit(np.log(horizons[-k:]), np.log(times[-k:]), 1)
        print(f"growth exponent b = {b:.2f} (time ~ T^b over T = {horizons[-k]}..{horizons[-1]}); "
              f"the fit predicts {np.exp(loga) * 1000 ** b:.0f} s at T = 1000")


if __name__ == "__main__":
    main()
