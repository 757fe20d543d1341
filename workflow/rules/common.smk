# Shared helpers of the rules files. Rules stay thin: each runs one step of
# a package module (python -m eqrec.<module> <step> ...); no mathematics here.
import os
import sys
from pathlib import Path

# The interpreter running Snakemake has the package installed. It reaches the
# shell commands through the environment, so no absolute path of this machine
# ends up in params (and in the report).
os.environ["EQREC_PYTHON"] = sys.executable
PY = "$EQREC_PYTHON"
# Every step reads the configuration Snakemake resolved (config files, then
# --configfile and --config overrides), written by rule resolved_config; its
# params carry the section, so a changed value re-runs that study's jobs.
CONFIG_FILE = "resolved/p1.yaml"


def resolved(section):
    """Path of the resolved configuration of one study section."""
    return f"resolved/{section}.yaml"

# Results depend on the package code: a change to any module re-runs the
# rules that use it (Snakemake does not track the code behind a shell command).
PKG_SRC = sorted(str(p) for p in Path("src/eqrec").rglob("*.py"))


def module_sources(module):
    """Source files of eqrec.<module> and of every eqrec module it imports, transitively.

    A rule lists these as inputs, so editing code a study does not import
    (e.g. the LMV code for P1) does not re-run its jobs.
    """
    import ast

    def path_of(name):
        base = Path("src") / Path(*name.split("."))
        for cand in (base.with_suffix(".py"), base / "__init__.py"):
            if cand.is_file():
                return cand
        return None

    seen, todo = set(), [f"eqrec.{module}"]
    while todo:
        path = path_of(todo.pop())
        if path is None or path in seen:
            continue
        seen.add(path)
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom) and node.module and node.module.startswith("eqrec"):
                todo.append(node.module)
                todo += [f"{node.module}.{a.name}" for a in node.names]
            elif isinstance(node, ast.Import):
                todo += [a.name for a in node.names if a.name.startswith("eqrec")]
    return sorted(str(p) for p in seen)


def study_cmd(module, step):
    """Command line of one pipeline step: `python -m eqrec.<module> <step>`."""
    return f"{PY} -m eqrec.{module} {step}"


rule resolved_config:
    """The resolved configuration section the steps of one study read (no computation)."""
    output:
        "resolved/{section}.yaml",
    params:
        cfg=lambda wildcards: config[wildcards.section],
    wildcard_constraints:
        section="p1|p2|p4",
    log:
        "logs/resolved_{section}.log",
    run:
        import yaml

        Path(output[0]).parent.mkdir(parents=True, exist_ok=True)
        Path(output[0]).write_text(yaml.safe_dump({wildcards.section: params.cfg}, sort_keys=False))
