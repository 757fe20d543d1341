# Shared helpers of the rules files. Rules stay thin: each runs one step of
# a package module (python -m eqrec.<module> <step> ...); no mathematics here.
import sys
from pathlib import Path

# The interpreter running Snakemake has the package installed.
PY = sys.executable
CONFIG_FILE = "config/config.yaml"

# Results depend on the package code: a change to any module re-runs the
# rules that use it (Snakemake does not track the code behind a shell command).
PKG_SRC = sorted(str(p) for p in Path("src/eqrec").rglob("*.py"))


def study_cmd(module, step):
    """Command line of one pipeline step: `python -m eqrec.<module> <step>`."""
    return f"{PY} -m eqrec.{module} {step}"
