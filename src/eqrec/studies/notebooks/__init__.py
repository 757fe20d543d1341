"""The notebooks (``notebooks/*.py``, jupytext): executed into ``results/notebooks/``, with HTML whose maths
renders offline.

:mod:`~eqrec.studies.notebooks.execute`
    The step that executes a notebook.
:mod:`~eqrec.studies.notebooks.html`
    The notebook HTML, maths as MathML at build time.
"""
