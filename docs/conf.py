"""Sphinx configuration of the eqrec documentation: ``sphinx-build -W --keep-going -n docs docs/_build/html``
(from the repository root, after ``pip install -c requirements/pipeline.lock -e ".[docs]"``).

Built offline: the PyData theme ships its fonts and scripts, the maths is MathML written at build time
(``_ext/eqrec_mathml.py``), the examples gallery runs every example (sphinx-gallery), the API reference is
``eqrec.__all__`` (``_ext/eqrec_api.py``) and the CLI reference is the commands' ``--help`` (``_ext/eqrec_cli.py``).
"""
from __future__ import annotations

import os
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
ROOT = DOCS.parent
sys.path.insert(0, str(DOCS / "_ext"))
sys.path.insert(0, str(ROOT / "src"))  # the checkout's package, also when it is not installed
os.environ.setdefault("OPENBLAS_CORETYPE", "Haswell")
os.environ.setdefault("MPLBACKEND", "Agg")

import eqrec  # noqa: E402

project = "eqrec"
author = "the eqrec developers"
copyright = "2026, the eqrec developers"
version = release = eqrec.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "numpydoc",
    "myst_parser",
    "sphinx_gallery.gen_gallery",
    "eqrec_mathml",
    "eqrec_api",
    "eqrec_cli",
    "eqrec_results",
]

source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
exclude_patterns = ["_build", "screenshots", "**.ipynb_checkpoints", "auto_examples/*.ipynb",
                    "auto_examples/*.py", "auto_examples/*.zip", "auto_examples/*.codeobj.json",
                    "auto_examples/*.md5", "sg_execution_times.rst", "auto_examples/sg_execution_times.rst"]
templates_path = ["_templates"]
nitpicky = True
html_math_renderer = "mathml"

# MyST: $…$ and $$…$$ maths, ::: fences, heading anchors for [text](page.md#anchor)
myst_enable_extensions = ["dollarmath", "colon_fence", "deflist"]
myst_heading_anchors = 3

# API reference: one page per public name (autosummary), numpydoc sections; signatures without type hints
# (the numpydoc "Parameters" give each type in words, with the paper's equation)
autosummary_generate = True
autosummary_imported_members = True
autodoc_typehints = "none"
autodoc_member_order = "bysource"
numpydoc_show_class_members = False
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

sphinx_gallery_conf = {
    "examples_dirs": str(ROOT / "examples" / "gallery"),
    "gallery_dirs": "auto_examples",
    "filename_pattern": r"/plot_",  # every example runs
    "download_all_examples": False,
    "remove_config_comments": True,
    "abort_on_example_error": True,
    "only_warn_on_example_error": False,
    "image_scrapers": ("matplotlib",),
    "matplotlib_animations": False,
    "within_subsection_order": "FileNameSortKey",
    "show_memory": False,
    "write_computation_times": False,  # its page loads DataTables from a CDN
}

html_theme = "pydata_sphinx_theme"
html_title = f"eqrec {version}"
html_theme_options = {
    "navbar_end": ["theme-switcher", "navbar-icon-links"],
    "icon_links": [],
    "show_toc_level": 2,
    "navigation_with_keys": False,
    "secondary_sidebar_items": ["page-toc"],
    "footer_start": ["copyright"],
    "footer_end": [],
}
html_sidebars = {"**": ["sidebar-nav-bs"]}
html_show_sourcelink = False
html_copy_source = False
html_static_path = []
