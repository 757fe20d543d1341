"""The notebooks (``notebooks/*.py``, jupytext): executed into ``results/notebooks/``, with HTML whose maths
renders offline, and the report's captions, rendered from the results they describe.

:mod:`~eqrec.studies.notebooks.execute`
    The step that executes a notebook.
:mod:`~eqrec.studies.notebooks.html`
    The notebook HTML, maths as MathML at build time.
:mod:`~eqrec.studies.notebooks.captions`
    The facts of ``results/`` the captions quote, and a caption rendered as the report renders it.
:mod:`~eqrec.studies.notebooks.text`
    ASCII maths of the result files made maths, whole-cell tables, and the checks of rendered text.
"""
