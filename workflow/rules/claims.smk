# The comparison table: every published number next to ours.


rule claims:
    """results/claims.csv and the readable results/REPRODUCTION.md."""
    input:
        claims="config/claims.yaml",
        values=VALUES_FILES,
    output:
        csv="results/claims.csv",
        md=report("results/REPRODUCTION.md", caption="../report/claims.rst", category="Claims"),
    log:
        "logs/claims.log",
    shell:
        "{PY} -m eqrec.claims --claims {input.claims} --results results"
        " --csv {output.csv} --md {output.md} > {log} 2>&1"
