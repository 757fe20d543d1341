# The documentation site (docs/, Sphinx): `snakemake --cores 2 docs`, not part of the
# default run. One command, the one the README names: sphinx-build with every warning
# and broken cross-reference an error (-W --keep-going -n); it runs the gallery's
# examples (examples/gallery/) and reads the stored results (results/REPRODUCTION.md,
# results/notebooks/*.html) as they are committed: they are not inputs of this rule, so
# building the site never plans a study's job (the build fails, naming the file, if
# one is missing).
import glob
import sys
from pathlib import Path

DOCS_BUILT = {
    "_build",
    "generated",
    "auto_examples",
}  # written by the build, not its sources

DOCS_SOURCES = sorted(
    f
    for pattern in (
        "docs/**/*.md",
        "docs/**/*.rst",
        "docs/**/*.py",
        "examples/gallery/*",
    )
    for f in glob.glob(pattern, recursive=True)
    if not DOCS_BUILT & set(Path(f).parts)
)


rule docs:
    """The documentation site, docs/_build/html (sphinx-build -W --keep-going -n)."""
    input:
        sources=DOCS_SOURCES,
        code=sorted(glob.glob("src/eqrec/**/*.py", recursive=True)),
    output:
        index="docs/_build/html/index.html",
    log:
        "logs/docs.log",
    params:
        python=sys.executable,
        builder="html",
    shell:
        "{params.python} -m sphinx -W --keep-going -n -b {params.builder} docs docs/_build/html > {log} 2>&1"
