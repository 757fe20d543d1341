# Shared by the rules files. Every rule is thin: it runs the one generic
# script, workflow/scripts/run_step.py, which calls
# eqrec.studies.harness.run_from_snakemake; the rule's params name the step
# (study, step) and carry cfg, the study's configuration section as Snakemake
# resolved it (config files, --configfile, --config; validated by the
# Snakefile). A changed value therefore re-plans that study's jobs (params
# rerun trigger) and reaches them. No mathematics here.
from eqrec.studies.harness import code_inputs, section_params

# Relative to the rules files.
RUN_STEP = "../scripts/run_step.py"


def study_code(study):
    """The package modules a study's steps import (transitively), as rule inputs.

    Editing code a study does not import (e.g. eqrec/lmv for P1) does not
    re-run its jobs.
    """
    return code_inputs(study)


def study_cfg(section):
    """A configuration section as a rule param (keys sorted: only a changed value re-plans)."""
    return section_params(config, section)
