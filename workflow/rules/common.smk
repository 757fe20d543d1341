# Shared by the rules files. Every rule is thin: it runs the one generic
# script, workflow/scripts/run_step.py, which calls
# eqrec.studies.pipeline.harness.run_from_snakemake; the rule's params name the
# step by the path of its function (step="eqrec.studies.p1.steps:step_model",
# resolved with pkgutil.resolve_name) and carry cfg, the configuration keys that
# step reads (no more; none when absent), as Snakemake resolved them (config
# files, --configfile, --config; validated by the Snakefile), nested as in the
# study's section. A changed value therefore re-plans the jobs whose step reads
# it (params rerun trigger), and only those: a figure's parameter re-plans that
# figure. A step reading a key its rule does not give fails naming the key
# (harness.StepConfig).
#
# Each rule lists as `code` inputs the package modules its step imports,
# transitively (the module of the step function and what it imports, from the
# import graph grimp builds of the package: eqrec.studies.pipeline.code), so
# editing code a step does not import (the LP modules for a figure, eqrec/lmv
# for P1) does not re-run its job. No mathematics here.
from functools import partial

from eqrec.studies.pipeline.configuration import step_params
from eqrec.studies.pipeline.code import code_inputs

# A rule's cfg param: step_config("p3", "strategy.figure", ...), the keys its
# step reads of config["p3"] ("mu1", "heatmap.solver", or a whole subtree).
step_config = partial(step_params, config)

# The paper's value of one claim (config/claims.yaml, the only place published
# numbers live), for rules that evaluate the paper's own design or draw a published
# value for comparison (P2: the printed gain L, the Fig. 3b interval). As a param,
# the rule reruns when that value changes, not on other edits of claims.yaml.
from eqrec.studies.claims.published import published_value

CLAIMS_FILE = "config/claims.yaml"

# The timings file (under results/timings/) a step writes beside each results file.
from eqrec.studies.pipeline.outputs import timings_of

# Relative to the rules files.
RUN_STEP = "../scripts/run_step.py"
