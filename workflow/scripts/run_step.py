# The one script every rule runs: the rule's params name the step (study, step)
# and carry its configuration section (cfg); eqrec.studies.pipeline.harness does the rest.
# First, the temporary files a killed earlier run of this job left beside its outputs are removed
# (this job holds the lock of its outputs: no other run is writing them).
from eqrec.studies.pipeline.harness import run_from_snakemake
from eqrec.studies.pipeline.resume import remove_stale_temporaries

remove_stale_temporaries(snakemake.output)  # noqa: F821 (injected by Snakemake's script directive)
run_from_snakemake(snakemake)  # noqa: F821
