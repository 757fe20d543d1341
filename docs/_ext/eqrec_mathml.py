"""Sphinx: maths as MathML written when the site is built (no script, no network).

Every ``:math:`` role, ``.. math::`` directive and MyST ``$…$`` / ``$$…$$`` becomes a ``<math>`` element made by
:func:`eqrec.studies.notebooks.html.tex_to_mathml` (latex2mathml, the converter of the notebooks' offline HTML),
which browsers draw without MathJax or KaTeX.  A formula latex2mathml cannot read stops the build, naming it.
"""
from __future__ import annotations

from docutils import nodes
from sphinx.errors import ExtensionError
from sphinx.util.math import get_node_equation_number

from eqrec.studies.notebooks.html import tex_to_mathml


def _convert(tex: str, display: bool) -> str:
    try:
        return tex_to_mathml(tex, display=display)
    except Exception as exc:  # latex2mathml raises its own exceptions, of several kinds
        raise ExtensionError(f"MathML: cannot convert the formula {tex!r}: {exc}") from exc


def visit_math(self, node: nodes.Node) -> None:
    self.body.append(f'<span class="math notranslate">{_convert(node.astext(), False)}</span>')
    raise nodes.SkipNode


def visit_displaymath(self, node: nodes.Node) -> None:
    # a directive's equations are separated by blank lines; each is one display formula
    nowrap = node.get("no-wrap", node.get("nowrap", False))
    parts = [node.astext()] if nowrap else [p for p in node.astext().split("\n\n") if p.strip()]
    self.body.append(self.starttag(node, "div", CLASS="math notranslate"))
    if node.get("number"):
        self.body.append(f'<span class="eqno">({get_node_equation_number(self, node)})')
        self.add_permalink_ref(node, "Link to this equation")
        self.body.append("</span>")
    for part in parts:
        # several lines of one equation (``\\``): latex2mathml reads them inside an aligned environment
        tex = part if "\\\\" not in part or "\\begin" in part else r"\begin{aligned}" + part + r"\end{aligned}"
        self.body.append(_convert(tex, True))
    self.body.append("</div>\n")
    raise nodes.SkipNode


def setup(app):
    app.add_html_math_renderer("mathml", (visit_math, None), (visit_displaymath, None))
    return {"parallel_read_safe": True, "parallel_write_safe": True}
