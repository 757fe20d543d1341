"""The failed long design of an unstable plant and the search for the longest horizon that solves, on the real
cart-pole (figures, not tests; issue 41 §2).

    python benchmarks/bench_horizon_search.py                          # the issue's case: (1, 1000), Ts = 20 ms
    python benchmarks/bench_horizon_search.py --ts 0.1 --max-delay 0 --horizon 80 --budget 30   # quick (~30 s)

The plant is the gallery's cart-pole (``examples/gallery/plot_cart_pole.py``: cart 1 kg, pole 0.1 kg and 0.5 m,
sampled at ``--ts`` with a zero-order hold; one unstable mode, spectral radius 1.097 at 20 ms, 1.59 at 100 ms).
It is written to a system file and ``eqrec design FILE --method delay --max-delay D --horizon T --mu1 free`` runs
in a fresh process, as a user would: the design fails (HiGHS cannot resolve error maps that grow like ``ρ^T``), and
the command searches for the longest horizon that solves within ``--budget`` seconds
(:data:`eqrec.cli.HORIZON_SEARCH_SECONDS`, set in the child process only).  Printed: the command's exit code, its last lines (the reason and the answer),
every design the search tried with its outcome, and the wall times of the whole and of the search.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
from scipy.linalg import expm

ROOT = Path(__file__).resolve().parents[1]


def cart_pole_yaml(Ts: float) -> str:
    """The gallery cart-pole sampled at ``Ts`` as a system file."""
    M, m, length, g = 1.0, 0.1, 0.5, 9.81
    Ac = np.array([[0, 1, 0, 0], [0, 0, -m * g / M, 0], [0, 0, 0, 1], [0, 0, (M + m) * g / (M * length), 0]])
    Bc = np.array([[0], [1 / M], [0], [-1 / (M * length)]])
    big = expm(np.block([[Ac, Bc], [np.zeros((1, 5))]]) * Ts)
    E = np.diag([0, Ts, 0, Ts]) + np.diag([Ts ** 2 / 2, 0, Ts ** 2 / 2], 1)
    rows = {"A": big[:4, :4], "B": big[:4, 4:], "C": np.array([[1.0, 0, 0, 0], [0, 0, 1.0, 0]]), "E": E}
    return "".join(f"{k}: {v.tolist()}\n" for k, v in rows.items()) + "eta_w: 0.05\neta_v: 0.002\nname: cart-pole\n"


CHILD = """
import sys
from eqrec import cli
cli.HORIZON_SEARCH_SECONDS = float(sys.argv[1])
sys.exit(cli.main(sys.argv[2:]))
"""


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--ts", type=float, default=0.02, help="sampling period, s")
    ap.add_argument("--max-delay", type=int, default=1)
    ap.add_argument("--horizon", type=int, default=1000)
    ap.add_argument("--budget", type=float, default=120.0, help="seconds of the horizon search")
    ap.add_argument("--jobs", type=int, default=2)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "cart_pole.yaml"
        path.write_text(cart_pole_yaml(a.ts))
        A = np.array(eval(path.read_text().splitlines()[0][3:]))  # noqa: S307 (our own file)
        rho = max(abs(np.linalg.eigvals(A)))
        args = ["design", str(path), "--method", "delay", "--max-delay", str(a.max_delay), "--horizon",
                str(a.horizon), "--mu1", "free", "--jobs", str(a.jobs)]
        print(f"cart-pole at Ts = {a.ts:g} s: spectral radius {rho:.4f}, rho^T = {rho ** a.horizon:.3g}; "
              f"eqrec {' '.join(args[:1] + args[2:])}; search budget {a.budget:g} s; load average "
              f"{os.getloadavg()[0]:.2f}", flush=True)
        t0 = time.perf_counter()
        proc = subprocess.Popen([sys.executable, "-c", CHILD, str(a.budget), *args], stdout=subprocess.PIPE,
                                stderr=subprocess.PIPE, text=True)
        search_start = None
        lines = []
        for line in proc.stderr:
            lines.append(line.rstrip())
            if "searching for the longest horizon" in line:
                search_start = time.perf_counter()
            if line.startswith("eqrec:") and "terminal classes" not in line and " / " not in line[:60]:
                print(f"   [{time.perf_counter() - t0:7.1f} s] {line.rstrip()[:400]}", flush=True)
        rc = proc.wait()
        total = time.perf_counter() - t0
    search = total - (search_start - t0) if search_start else 0.0
    print(f"exit code {rc}; total {total:.1f} s, of which the search {search:.1f} s (budget {a.budget:g} s)")
    print(f"answer: {lines[-1] if lines else '(no output)'}")


if __name__ == "__main__":
    main()
