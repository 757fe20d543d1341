"""Words next to the results: ASCII maths made maths, tables shown whole, and the checks the text tests apply.

The result files keep plain text (``e_{0,1}e_{1,3}``, ``L^E'``, ``mu1``): it is
what a CSV or a terminal shows.  A reader of a notebook or the report gets
maths: :func:`ascii_to_tex` wraps each such token in ``$…$`` (a notebook's
markdown, drawn as MathML in its HTML by :mod:`eqrec.studies.notebooks.html`),
and :func:`markdown_table` shows a table with every cell in full (no cell is
cut at a width; a long cell wraps in the page).  :data:`ASCII_MATHS` and
:data:`RAW_TEX` are what ``tests/test_prose.py`` looks for in rendered text.
"""

from __future__ import annotations

import re
from typing import Iterable

#: ASCII maths a reader should not see in prose or alt text: ``x_{k}``, ``E_alpha``, ``10^4``, ``mu1``,
#: ``||x||``, ``+-``, ``>=``, Greek letters spelled out.
ASCII_MATHS = re.compile(
    r"\b[A-Za-z]+_\{|\b[A-Za-z]_[A-Za-z0-9]+\b|[A-Za-z0-9)]\^[-+{0-9A-Za-z]|\bmu_?\d|\bmu\b|"
    r"\b(?:theta|lambda|alpha|sigma|eta|xi|pi|Phi|tau|delta)\b|\|\||\+-|>=|<=|\bx_hat\b|\bx_bar\b")
#: TeX left for a script to draw: a control word or a dollar-delimited formula.
RAW_TEX = re.compile(r"\\[A-Za-z]+|(?<!\\)\$[^$\s][^$]*\$")

# an ASCII token and its TeX: event sequences e_{0,1}e_{1,3}, the reduced language L^E', E_alpha, j_k,
# d_0..d_k, mu1 / mu2, Greek letters spelled out
_TOKENS = [
    (re.compile(r"\|\|([^|\s]*)\|\|_inf"), lambda m: rf"\|{m[1]}\|_\infty"),
    (re.compile(r"\bx\(t\|I_t(-1)?\)"), lambda m: r"x(t \mid I_{t-1})" if m[1] else r"x(t \mid I_t)"),
    (re.compile(r"\bmu2_k\^alpha\b"), lambda m: r"\mu_{2,k}^\alpha"),
    (re.compile(r"\bmu_?2_k\b"), lambda m: r"\mu_{2,k}"),
    (re.compile(r"\bsum_(k|alpha)\b"), lambda m: r"\sum_" + ("k" if m[1] == "k" else r"\alpha")),
    (re.compile(r"\bPhi\b"), lambda m: r"\Phi"),
    (re.compile(r"\be\^\(\+-j theta\)"), lambda m: r"e^{\pm j\theta}"),
    (re.compile(r"\b10\^(\d+)\b"), lambda m: f"10^{{{m[1]}}}"),
    (re.compile(r"\{[\d,]+\}\^\d+"), lambda m: m[0].replace("{", r"\{").replace("}", r"\}")),
    (re.compile(r"\b([A-Z]\d?)\^T\b"), lambda m: f"{m[1]}^T"),
    (re.compile(r"(?:e_\{[^{}]*\})+"), lambda m: m[0]),
    (re.compile(r"L\^E'?"), lambda m: r"\mathcal{L}^{" + m[0][2:] + "}"),
    (re.compile(r"\b([A-Za-z]+)\^([0-9])\b"), lambda m: f"{m[1]}^{m[2]}"),
    (re.compile(r"\b([A-Za-z])_(max|min|bar|hold|zero|crit)\b"), lambda m: rf"{m[1]}_{{\mathrm{{{m[2]}}}}}"),
    (re.compile(r"\beta_bar\b"), lambda m: r"\bar\eta"),
    (re.compile(r"\b([A-Q])_(xi|lambda)\b"), lambda m: rf"{m[1]}_\{m[2]}"),
    (re.compile(r"\bE_alpha\b"), lambda m: r"E_\alpha"),
    (re.compile(r"\bd_0\.\.d_k\b"), lambda m: r"d_0, \ldots, d_k"),
    (re.compile(r"\b([A-Za-z])_([a-z0-9])\b"), lambda m: f"{m[1]}_{m[2]}"),
    (re.compile(r"\bmu_?([12])\b"), lambda m: rf"\mu_{m[1]}"),
    (re.compile(r"\bs0\b"), lambda m: "s_0"),
    (re.compile(r"(?<=\s)(<=|>=)(?=\s)"), lambda m: r"\le" if m[0] == "<=" else r"\ge"),
    (re.compile(r"\b(alpha|theta|lambda|tau|sigma|eta|xi|pi)\b"), lambda m: rf"\{m[1]}"),
]
_CODE_OR_MATHS = re.compile(r"`[^`]*`|(?<!\\)\$[^$]*\$")


def ascii_to_tex(text: str) -> str:
    """``text`` with each ASCII-maths token (outside code spans and ``$…$``) as inline TeX ``$…$``.

    Parameters
    ----------
    text : str
        Markdown, e.g. a table of ``results/p3/examples.md`` or a cell of ``results/claims.csv``.

    Returns
    -------
    str
        The same markdown, the tokens in dollars (``e_{0,1}e_{1,3}`` becomes ``$e_{0,1}e_{1,3}$``).
    """
    out, last = [], 0
    for m in _CODE_OR_MATHS.finditer(text):
        out += [_tex_tokens(text[last:m.start()]), m[0]]
        last = m.end()
    return "".join(out + [_tex_tokens(text[last:])])


def _tex_tokens(text: str) -> str:
    text = re.sub(r"\+-\s?(?=[\d.])|(?<=\s)\+-(?=\s)", "± ", text)  # plus-minus: a character, not maths
    pattern = re.compile("|".join(f"(?P<t{i}>{p.pattern})" for i, (p, _) in enumerate(_TOKENS)))

    def repl(m: re.Match) -> str:
        i = int(next(k for k, v in m.groupdict().items() if v is not None and k.startswith("t"))[1:])
        return f"${_TOKENS[i][1](_TOKENS[i][0].match(m.string, m.start()))}$"

    return pattern.sub(repl, text)


def markdown_table(rows: Iterable[dict], columns: list[str], code: tuple[str, ...] = ("id",)) -> str:
    """A Markdown table of ``rows`` with every cell in full, its ASCII maths as TeX and ``|`` escaped.

    Parameters
    ----------
    rows : iterable of dict
        One mapping per row (``DataFrame.to_dict("records")``); a missing or NaN value is an empty cell.
    columns : list of str
        The columns shown, in order.
    code : tuple of str, optional
        Columns shown as code, as they are (identifiers such as the claims' ids).

    Returns
    -------
    str
        The table (header, rule, one line per row).
    """
    def cell(v) -> str:
        if v is None or (isinstance(v, float) and v != v):
            return ""
        return ascii_to_tex(" ".join(str(v).split())).replace("|", r"\|")

    lines = ["| " + " | ".join(columns) + " |", "|" + "---|" * len(columns)]
    lines += ["| " + " | ".join(f"`{r.get(c)}`" if c in code else cell(r.get(c)) for c in columns) + " |"
              for r in rows]
    return "\n".join(lines)


def claims_markdown(claims, prefix: str, columns: tuple[str, ...] = ("id", "quantity", "paper_value", "our_value",
                                                                   "status", "reason")) -> str:
    """The rows of the claims table whose id starts with ``prefix``, as a whole-cell Markdown table.

    Parameters
    ----------
    claims : pandas.DataFrame
        ``results/claims.csv`` as read by pandas (``id`` a column, not the index).
    prefix : str
        ``"P1"``, ``"P3-F1:"``, …
    columns : tuple of str, optional
        The columns shown.

    Returns
    -------
    str
        :func:`markdown_table` of those rows.
    """
    rows = claims[claims["id"].str.startswith(prefix)]
    return markdown_table(rows.to_dict("records"), list(columns))
