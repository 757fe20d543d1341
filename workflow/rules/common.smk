# Shared helpers of the rules files. Rules stay thin: each runs one step of
# a package module (python -m eqrec.<module> <step> ...); no mathematics here.
import sys

# The interpreter running Snakemake has the package installed.
PY = sys.executable
CONFIG_FILE = "config/config.yaml"
