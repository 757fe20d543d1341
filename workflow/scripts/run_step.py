# The one script every rule runs: the rule's params name the step (study, step)
# and carry its configuration section (cfg); eqrec.studies.pipeline.harness does the rest.
from eqrec.studies.pipeline.harness import run_from_snakemake

run_from_snakemake(snakemake)  # noqa: F821 (injected by Snakemake's script directive)
