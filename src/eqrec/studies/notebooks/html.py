"""The notebooks' HTML rendering, readable offline: maths rendered at build time, no script from the network.

nbconvert's HTML loads MathJax, require.js and mermaid from a CDN; offline the
maths of a notebook shows as raw ``$L_1 = \\{…\\}$``.  Here every ``$…$`` and
``$$…$$`` of the markdown (cells and ``text/markdown`` outputs) becomes
MathML when the HTML is built (:func:`tex_to_mathml`, with latex2mathml),
which browsers draw without any script, and the page's template
(:data:`OFFLINE_TEMPLATE`) drops the three script blocks.  The ``.ipynb``
keeps its TeX (GitHub and Jupyter render it); only the HTML copy changes.
"""

from __future__ import annotations

import copy
import re

#: nbconvert's ``lab`` page without the blocks that load require.js, MathJax and mermaid from the network; a PNG
#: output's ``alt`` metadata (the figure's caption, :func:`eqrec.studies.notebooks.execute.add_alt_text`) becomes
#: the ``alt`` of its image, and its ``width`` metadata (``Image(..., width=800)``) the image's width, as in
#: Jupyter (nbconvert's own template drops it: the figure would show at its pixel size).
OFFLINE_TEMPLATE = """{%- extends 'index.html.j2' -%}
{%- block html_head_js -%}{%- endblock html_head_js -%}
{%- block html_head_js_mathjax -%}{%- endblock html_head_js_mathjax -%}
{%- block html_head_js_mermaidjs -%}{%- endblock html_head_js_mermaidjs -%}
{% block data_png scoped %}
<div class="jp-RenderedImage jp-OutputArea-output {{ extra_class }}">
{%- set alttext = output | get_metadata('alt', 'image/png') %}
{%- set width = output | get_metadata('width', 'image/png') %}
<img src="data:image/png;base64,{{ output.data['image/png'] | escape_html }}"
{%- if width %} width="{{ width | escape_html }}" style="max-width: 100%; height: auto"{% endif %}
{%- if alttext %} alt="{{ alttext | escape_html }}"{% endif %}>
</div>
{%- endblock data_png %}
"""

# code spans (left alone), display maths, inline maths; a dollar escaped as \$ is text
_MATH = re.compile(r"(?P<code>`+[^`]*`+)|(?<!\\)\$\$(?P<display>.+?)(?<!\\)\$\$|(?<![\\$])\$(?P<inline>[^$\n]+?)(?<!\\)\$",
                   re.S)

# MathML Core draws only mathvariant="normal": script letters become their Unicode characters
_SCRIPT_EXCEPTIONS = {"B": "\u212c", "E": "\u2130", "F": "\u2131", "H": "\u210b", "I": "\u2110", "L": "\u2112",
                      "M": "\u2133", "R": "\u211b", "e": "\u212f", "g": "\u210a", "o": "\u2134"}
_SCRIPT_MI = re.compile(r'<mi mathvariant="script">([A-Za-z])</mi>')


def _script_letter(ch: str) -> str:
    if ch in _SCRIPT_EXCEPTIONS:
        return _SCRIPT_EXCEPTIONS[ch]
    return chr(0x1D49C + ord(ch) - ord("A") if ch.isupper() else 0x1D4B6 + ord(ch) - ord("a"))


def tex_to_mathml(tex: str, display: bool = False) -> str:
    """One TeX formula as a MathML element (no script needed to draw it).

    Parameters
    ----------
    tex : str
        The formula without its dollars.
    display : bool, optional
        A display (block) formula rather than an inline one.

    Returns
    -------
    str
        ``<math …>…</math>`` on one line, with the TeX source kept as its ``alttext``.
    """
    from html import escape

    from latex2mathml.converter import convert

    out = convert(tex.strip(), display="block" if display else "inline")
    out = _SCRIPT_MI.sub(lambda m: f"<mi>{_script_letter(m.group(1))}</mi>", out)
    # HTML needs no namespace on <math>; with one, nbconvert's heading anchors rewrite it as <ns0:math>
    out = out.replace(' xmlns="http://www.w3.org/1998/Math/MathML"', "")
    return out.replace("<math ", f'<math alttext="{escape(tex.strip())}" ', 1).replace("\n", "")


def markdown_maths(text: str) -> str:
    """Markdown with every ``$…$`` and ``$$…$$`` outside code spans replaced by MathML."""
    def repl(m: re.Match) -> str:  # one group of code, display, inline matched: m.lastgroup
        kind = m.lastgroup
        return m[kind] if kind == "code" else tex_to_mathml(m[kind], display=kind == "display")

    return _MATH.sub(repl, text)


def with_mathml(nb):
    """A copy of the notebook whose markdown (cells and ``text/markdown`` outputs) carries MathML, not TeX."""
    nb = copy.deepcopy(nb)
    for cell in nb.cells:
        if cell.cell_type == "markdown":
            cell.source = markdown_maths(cell.source)
        for out in cell.get("outputs", []):
            data = out.get("data", {})
            if "text/markdown" in data:
                data["text/markdown"] = markdown_maths(data["text/markdown"])
    return nb


def offline_html(nb, title: str) -> str:
    """The nbconvert HTML of an executed notebook, its maths as MathML and no script loaded from the network.

    Parameters
    ----------
    nb : nbformat.NotebookNode
        The executed notebook (not modified).
    title : str
        The page title.

    Returns
    -------
    str
        The page, ending with a newline.
    """
    from jinja2 import DictLoader
    from nbconvert import HTMLExporter

    exporter = HTMLExporter(extra_loaders=[DictLoader({"eqrec_offline.html.j2": OFFLINE_TEMPLATE})],
                            template_file="eqrec_offline.html.j2")
    body, _ = exporter.from_notebook_node(with_mathml(nb), resources={"metadata": {"name": title}})
    return body if body.endswith("\n") else body + "\n"
