# Shared by the rules files. Every rule is thin: it runs the one generic
# script, workflow/scripts/run_step.py, which calls
# eqrec.studies.harness.run_from_snakemake; the rule's params name the step
# (study, step) and carry cfg, the study's configuration section as Snakemake
# resolved it (config files, --configfile, --config; validated by the
# Snakefile). A changed value therefore re-plans that study's jobs (params
# rerun trigger) and reaches them. No mathematics here.
#
# Each study's rules list as `code` inputs the package modules that study
# imports, transitively (harness.code_inputs walks the imports with ast), so
# editing code a study does not import (e.g. eqrec/lmv for P1) does not re-run
# its jobs. configuration.section_params sorts the section's keys, so only a changed
# value re-plans.
from eqrec.studies.configuration import section_params
from eqrec.studies.harness import code_inputs

# The paper's value of one claim (config/claims.yaml, the only place published
# numbers live), for rules that evaluate the paper's own design or draw a published
# value for comparison (P2: the printed gain L, the Fig. 3b interval). As a param,
# the rule reruns when that value changes, not on other edits of claims.yaml.
from eqrec.studies.claims import published_value

CLAIMS_FILE = "config/claims.yaml"

# The timings file (under results/timings/) a step writes beside each results file.
from eqrec.studies.outputs import timings_of

# Relative to the rules files.
RUN_STEP = "../scripts/run_step.py"
