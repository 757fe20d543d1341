# The comparison table: every published number next to ours, worded by the
# templates of config/claims.yaml from the evidence in the values.json files
# of the studies (included before this file) and the values of P1's timings.


use rule step as claims with:
    """results/claims.csv and the readable results/REPRODUCTION.md."""
    input:
        claims="config/claims.yaml",
        values=[
            rules.p1_values.output.json,
            rules.p2_values.output.json,
            rules.p3_values.output.json,
            rules.p3_strategy.output.values,
            rules.p4_values.output.values,
        ],
        timings=[rules.p1_values.output.timings],
        code=code_inputs("eqrec.studies.claims.table:step_table"),
    output:
        csv=in_report("results/claims.csv", "claims", "Claims"),
        md=in_report("results/REPRODUCTION.md", "reproduction", "Claims"),
        timings="results/timings/claims.csv",
    log:
        "logs/claims.log",
    params:
        step="eqrec.studies.claims.table:step_table",
