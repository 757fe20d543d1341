# The comparison table: every published number next to ours, worded by the
# templates of config/claims.yaml from the evidence in the values.json files.


rule claims:
    """results/claims.csv and the readable results/REPRODUCTION.md."""
    input:
        claims="config/claims.yaml",
        values=VALUES_FILES,
        timings=TIMING_VALUES_FILES,
        code=code_inputs("eqrec.studies.claims.table:step_table"),
    output:
        csv=report(
            "results/claims.csv", caption="../report/claims.rst", category="Claims"
        ),
        md=report(
            "results/REPRODUCTION.md",
            caption="../report/reproduction.rst",
            category="Claims",
        ),
        timings="results/timings/claims.csv",
    log:
        "logs/claims.log",
    params:
        step="eqrec.studies.claims.table:step_table",
    script:
        RUN_STEP
