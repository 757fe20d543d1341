# Main workflow: recomputes every table and figure of the equalized-recovery
# papers and the LMV companion study, then compares them with the published
# values (results/claims.csv, results/REPRODUCTION.md).
#
#   snakemake --cores 2              # everything, default config
#   snakemake --cores 2 p1           # one paper (p1, p2, p4)
#   snakemake --report report.html   # browsable report with figure captions
from snakemake.exceptions import WorkflowError
from snakemake.utils import min_version, validate

min_version("9.0")


configfile: "config/config.yaml"
configfile: "config/p2.yaml"
configfile: "config/p4.yaml"


def validate_section(section, schema, source):
    """Validate config[section] (after --configfile/--config overrides) and name the section on failure."""
    try:
        validate(config[section] if section else config, schema)
    except Exception as exc:
        raise WorkflowError(f"invalid configuration: section '{section or 'p1'}' (from {source} and any "
                            f"--configfile/--config override) does not satisfy {schema}:\n{exc}")


validate_section(None, "config/schemas/config.schema.yaml", "config/config.yaml")
validate_section("p2", "config/schemas/p2.schema.yaml", "config/p2.yaml")
validate_section("p4", "config/schemas/p4.schema.yaml", "config/p4.yaml")

# Each rules file appends the values.json its analysis writes; the claims
# table (claims.smk, included last) needs all of them.
VALUES_FILES = []


include: "workflow/rules/common.smk"
include: "workflow/rules/p1.smk"
include: "workflow/rules/p2.smk"
include: "workflow/rules/p4.smk"
include: "workflow/rules/claims.smk"


rule all:
    default_target: True
    input:
        rules.claims.output,
        rules.p1.input,
        rules.p2.input,
        rules.p4.input,
