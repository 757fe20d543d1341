"""Sphinx: the executed notebooks' offline HTML (``results/notebooks/*.html``) copied into the site's ``notebooks/``.

The replication page links them; they carry their maths as MathML and their figures inline (no network).  A
missing notebook stops the build (the link would be broken).
"""
from __future__ import annotations

import shutil
from pathlib import Path

from sphinx.errors import ExtensionError

NOTEBOOKS = ("p1_prefix_based", "p2_augmented", "p3_delayed", "p4_lmv", "compare")


def copy_notebooks(app, exception):
    if exception is not None or app.builder.format != "html":
        return
    source = Path(app.srcdir).parent / "results" / "notebooks"
    target = Path(app.outdir) / "notebooks"
    target.mkdir(parents=True, exist_ok=True)
    for name in NOTEBOOKS:
        page = source / f"{name}.html"
        if not page.is_file():
            raise ExtensionError(f"{page} is missing: run `snakemake --cores 2 notebooks` first")
        shutil.copyfile(page, target / page.name)


def setup(app):
    app.connect("build-finished", copy_notebooks)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
