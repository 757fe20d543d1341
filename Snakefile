# Main workflow: recomputes every table and figure of the equalized-recovery
# papers and the LMV companion study, then compares them with the published
# values (results/claims.csv, results/REPRODUCTION.md).
#
#   snakemake --cores 2                          # everything, default config
#   snakemake --cores 2 p1                       # one paper (p1, p2, p3, p4)
#   snakemake --cores 2 compare                  # every estimator family on the same traces (results/compare/)
#   snakemake --cores 2 notebooks                # the executed notebooks (results/notebooks/)
#   snakemake --cores 2 p3_scale                 # the P3 scale table (slow, up to 16 GB; not in `all`)
#   snakemake --cores 2 --configfile my.yaml     # overrides (or --config p1='{mu1: 1.5}')
#   snakemake --report report.html               # browsable report with figure captions
import logging
import os

from snakemake.exceptions import WorkflowError
from snakemake.utils import min_version

# One set of BLAS kernels on every x86-64 machine (OpenBLAS picks them by CPU otherwise, and an AVX-512 Intel
# and an AMD machine then differ in the last bits, enough to change printed results): the jobs, started from
# here, inherit it. The tests set the same (tests/conftest.py).
# One BLAS thread per job too: the zonotope window's solves go through LAPACK, whose blocked factorizations may
# split sums by thread count (a machine with more cores would otherwise differ); the jobs already fill the cores.
os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from eqrec.studies.pipeline import configuration, resume

min_version("9.0")

# After a hard kill (kill -9, a lost session) the next run stops with Snakemake's LockException;
# eqrec.studies.pipeline.resume follows that error with whether a Snakemake process still runs here
# and, when none does, the one command that resumes (snakemake --unlock && <this command>). Only in the
# main process (not in a cluster job's own Snakemake).
if workflow.is_main_process:
    resume.explain_lock_errors(
        logging.getLogger("snakemake.logging"), os.getcwd(), resume.cli_arguments()
    )


report: "workflow/report/workflow.rst"


# Snakemake's scheduler (9.x) ends every scheduling pass by starting a timer for its job rate limiter
# (--max-jobs-per-timespan, default 100/1s) that wakes it for another pass a second later; each finished job
# starts one more such chain, so by the end of the main job dozens of passes run per second, each reading the
# size of every input of every waiting job (a rule's inputs include the package modules its step imports).
# On 2 cores that took tens of seconds of CPU from the jobs per forced run. Local jobs are not submitted to
# any queue the limit protects, so on the local executor the limiter is dropped (a pass then runs when a job
# ends); a cluster executor (the SLURM profile) keeps it.
onstart:
    if workflow.local_exec:
        workflow.scheduler.job_rate_limiter = None


configfile: "config/config.yaml"
configfile: "config/p2.yaml"
configfile: "config/p3.yaml"
configfile: "config/p4.yaml"
configfile: "config/compare.yaml"


# Validate the whole configuration once, after the --configfile/--config
# overrides, with the defaults of its schemas filled in (configuration.
# validate_config: snakemake.utils.validate(config, "config/schemas/
# config.schema.yaml", set_default=True), then the cross-field checks of the
# studies); a bad value, unknown key or unknown section stops the run here,
# naming file and field.
# nested --config values arrive as text: give them the types their schema asks for
configuration.type_cli_config(
    config, workflow.config_settings.config, root=workflow.basedir
)
try:
    configuration.validate_config(
        config,
        root=workflow.basedir,
        configfiles=workflow.config_settings.configfiles,
        overrides=workflow.config_settings.config,
    )
except configuration.ConfigError as exc:
    raise WorkflowError(f"invalid configuration: {exc}")


# The template of every rule that runs a step (`use rule step as p1_model with:`
# gives the files, log and params): the one script, which runs the step named by
# the params through eqrec.studies.pipeline.harness. Not a target of its own.
# The script by its full path (a relative one would be read from each rules file).
rule step:
    """Template of the step rules: runs the step its params name (not a target)."""
    log:
        "logs/step.log",
    script:
        f"{workflow.basedir}/workflow/scripts/run_step.py"


include: "workflow/rules/common.smk"
include: "workflow/rules/p1.smk"
include: "workflow/rules/p2.smk"
include: "workflow/rules/p3.smk"
include: "workflow/rules/p4.smk"
include: "workflow/rules/compare.smk"
include: "workflow/rules/notebooks.smk"
include: "workflow/rules/claims.smk"


rule all:
    default_target: True
    input:
        rules.claims.output,
        rules.p1.input,
        rules.p2.input,
        rules.p3.input,
        rules.p4.input,
        rules.compare.input,
        rules.notebooks.input,
