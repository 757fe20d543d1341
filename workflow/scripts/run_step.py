# The one script every rule runs: the rule's params name the step (study, step)
# and carry its configuration section (cfg); eqrec.studies.pipeline.harness does the rest.
# First, the temporary files that killed writes of this job's outputs left (an earlier, hard-killed run)
# are removed: this job holds the lock of its outputs, no other run is writing them.
from eqrec.io import remove_stale_temporaries
from eqrec.studies.pipeline.harness import run_from_snakemake

remove_stale_temporaries(snakemake.output)  # noqa: F821 (injected by Snakemake's script directive)
run_from_snakemake(snakemake)  # noqa: F821
