# The comparison table: every published number next to ours.
CLAIMS_SRC = module_sources("studies.claims")


rule claims:
    """results/claims.csv and the readable results/REPRODUCTION.md."""
    input:
        claims="config/claims.yaml",
        values=VALUES_FILES,
        code=CLAIMS_SRC,
    output:
        csv="results/claims.csv",
        md=report("results/REPRODUCTION.md", caption="../report/claims.rst", category="Claims"),
    params:
        cmd=f"{PY} -m eqrec.studies.claims",
    log:
        "logs/claims.log",
    shell:
        "{params.cmd} --claims {input.claims} --results results"
        " --csv {output.csv} --md {output.md} > {log} 2>&1"
