# Main workflow: recomputes every table and figure of the equalized-recovery
# papers and the LMV companion study, then compares them with the published
# values (results/claims.csv, results/REPRODUCTION.md).
#
#   snakemake --cores 2            # everything on the default config
#   snakemake --cores 2 p1         # one paper
#   snakemake --report report.html # browsable report with figure captions
from pathlib import Path

from snakemake.utils import min_version, validate

min_version("9.0")


configfile: "config/config.yaml"


validate(config, "config/schemas/config.schema.yaml")

# Each rules file appends the values.json files its analysis writes; the
# claims table needs all of them.
VALUES_FILES = []


include: "workflow/rules/common.smk"
include: "workflow/rules/p1.smk"


if Path("workflow/rules/p2.smk").exists():

    include: "workflow/rules/p2.smk"


if Path("workflow/rules/p4.smk").exists():

    include: "workflow/rules/p4.smk"


rule all:
    default_target: True
    input:
        rules.claims.output,
