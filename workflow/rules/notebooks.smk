# The notebooks (notebooks/<name>.py, jupytext) executed against results/:
# results/notebooks/<name>.ipynb with outputs and figures embedded (readable on
# GitHub without running anything) and its HTML rendering (in the report).
# Each runs after the result files it reads (eqrec.studies.notebooks.execute.READS;
# rule_inputs gives the notebook's source and those files); the step
# eqrec.studies.notebooks.execute.execute writes byte-identical files for unchanged
# inputs.
from eqrec.studies.notebooks import execute as notebook_execute

NOTEBOOKS = sorted(notebook_execute.READS)


use rule step as notebooks_execute with:
    """One notebook executed: .ipynb with its outputs, and its HTML rendering."""
    input:
        unpack(notebook_execute.rule_inputs),
        code=code_inputs("eqrec.studies.notebooks.execute:step_execute"),
    output:
        ipynb="results/notebooks/{name}.ipynb",
        html=in_report("results/notebooks/{name}.html", "notebooks", "Notebooks"),
    log:
        "logs/notebooks/{name}.log",
    wildcard_constraints:
        name="|".join(NOTEBOOKS),
    params:
        step="eqrec.studies.notebooks.execute:step_execute",


rule notebooks:
    """All executed notebooks."""
    input:
        expand(rules.notebooks_execute.output, name=NOTEBOOKS),
