"""The pipeline under the studies: what every Snakemake job shares.

:mod:`~eqrec.studies.pipeline.harness`
    Runs one step for a rule (its configuration keys, inputs, outputs, log) and writes its outputs atomically.
:mod:`~eqrec.studies.pipeline.configuration`, :mod:`~eqrec.studies.pipeline.checks`
    The workflow configuration: schema validation and the cross-field checks.
:mod:`~eqrec.studies.pipeline.outputs`, :mod:`~eqrec.studies.pipeline.chunks`, :mod:`~eqrec.studies.pipeline.logs`
    Result files (JSON, CSV, timings beside), sweep chunks, job logs.
:mod:`~eqrec.studies.pipeline.code`
    A rule's code inputs: the modules its step imports, from grimp's import graph of the package.
:mod:`~eqrec.studies.pipeline.resume`
    Resuming after a hard kill: the leftovers of killed writes, and whether a lock is stale.
"""
