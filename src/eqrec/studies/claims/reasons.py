"""What a claim's reason function returns, the registry by claim id, and the list formats of the wording.

A row of ``config/claims.yaml`` holds the paper's value and our wording as
``str.format`` templates with plain named fields (``{mu2:.6f}``).  When the
wording depends on the evidence (which alternative text, whether an
explanation still holds, a joined list, a count), a function of the study's
``claims`` module (:mod:`eqrec.studies.p1.claims` ... :mod:`eqrec.studies.p4.claims`)
decides, registered under the claim's id in the one registry :data:`REASONS`::

    from eqrec.studies.claims.reasons import reason

    @reason("P1-M2:prefix-L1")
    def prefix_l1(ev, texts):
        ...
        return Reason(fields={...}, note=["optimum", "proven"], explanation={"misprint": holds})

``ev`` is the claim's evidence (the ``evidence`` of its ``values.json`` entry)
plus ``value`` (ours), ``paper`` (the published value, a number where it reads
as one), ``tol`` (the tolerance of ``number`` and ``interval`` claims) and
``published`` (every claim's published value by id, for a reason that cites
another claim's); ``texts`` maps the names of the claim's ``note`` texts to
their templates (for wording repeated per item of a list).  The chosen texts
are filled from ``ev`` and the returned fields.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Callable, Mapping, Sequence


@dataclass(frozen=True)
class Reason:
    """The wording a reason function chooses for one claim row.

    Parameters
    ----------
    fields : Mapping[str, Any]
        Named fields the templates use beyond the evidence (joined lists, counts, derived numbers).
    note : Sequence[str] or None
        The names of the claim's ``note`` texts to show, in order (``None``: the claim's single ``note``).
    explanation : Mapping[str, bool]
        For each named ``explanation`` text of the claim, whether its evidence holds; one that does not
        is withdrawn, and the table says so.
    """

    fields: Mapping[str, Any] = field(default_factory=dict)
    note: Sequence[str] | None = None
    explanation: Mapping[str, bool] = field(default_factory=dict)


ReasonFunction = Callable[[Mapping[str, Any], Mapping[str, str]], Reason]


def registry() -> tuple[dict[str, ReasonFunction], Callable[..., Callable[[ReasonFunction], ReasonFunction]]]:
    """A study's table of reason functions by claim id, and the decorator that fills it.

    Returns
    -------
    table : dict[str, callable]
        Claim id -> reason function ``f(ev, texts) -> Reason``.
    reason : callable
        ``@reason("P1-M2:time-L1", ...)`` registers the decorated function under those ids.
    """
    table: dict[str, ReasonFunction] = {}

    def reason(*ids: str) -> Callable[[ReasonFunction], ReasonFunction]:
        def register(fn: ReasonFunction) -> ReasonFunction:
            for cid in ids:
                if cid in table:
                    raise ValueError(f"claim {cid} has two reason functions")
                table[cid] = fn
            return fn
        return register

    return table, reason


#: Every study's reason functions by claim id, filled by the ``@reason`` decorators of the studies' ``claims``
#: modules when they are imported (the claims table imports them by name: it reads the studies through this table).
REASONS, reason = registry()


def fmtlist(xs: Any, spec: str = ".4g") -> str:
    """``[a, b, c]`` with every number formatted by ``spec`` (nested lists too).

    Parameters
    ----------
    xs : Any
        A number, a string or a (nested) list of them.
    spec : str
        Python format spec of the numbers.

    Returns
    -------
    str
    """
    if isinstance(xs, (list, tuple)):
        return "[" + ", ".join(fmtlist(x, spec) for x in xs) + "]"
    if isinstance(xs, (int, float)) and not isinstance(xs, bool):
        return format(xs, spec)
    return str(xs)


def fmtlists(ev: Mapping[str, Any], *keys: str) -> dict[str, str]:
    """Fields ``<key>_list``: the lists ``ev[key]`` formatted by :func:`fmtlist` (``.4g``).

    Parameters
    ----------
    ev : Mapping[str, Any]
        Evidence (or one item of it).
    *keys : str
        The keys of the lists.

    Returns
    -------
    dict[str, str]
    """
    return {f"{k}_list": fmtlist(ev[k]) for k in keys}


def fmtcomplex(pairs: Sequence[Sequence[float]], spec: str = ".3f") -> str:
    """``{a+bj, c}`` from ``[[re, im], ...]`` (the imaginary part shown only when nonzero).

    Parameters
    ----------
    pairs : sequence of (float, float)
        Real and imaginary parts.
    spec : str
        Python format spec of each part.

    Returns
    -------
    str
    """
    return "{" + ", ".join(format(a, spec) + (format(b, "+" + spec) + "j" if abs(b) > 1e-9 else "")
                           for a, b in pairs) + "}"


def join(x: Mapping[str, Any] | Sequence[Any], sep: str = ", ") -> str:
    """A mapping as ``k: v, k: v``; a list as ``a, b``.

    Parameters
    ----------
    x : Mapping or Sequence
        The items.
    sep : str
        Separator.

    Returns
    -------
    str
    """
    if isinstance(x, Mapping):
        return sep.join(f"{k}: {v}" for k, v in x.items())
    return sep.join(str(v) for v in x)


def all_are(x: Mapping[str, Any] | Sequence[Any], value: Any) -> bool:
    """Whether every entry (of a list, or value of a mapping) equals ``value``; false if there is none.

    Parameters
    ----------
    x : Mapping or Sequence
        The entries.
    value : Any
        The value each must equal.

    Returns
    -------
    bool
    """
    items = list(x.values()) if isinstance(x, Mapping) else list(x)
    return bool(items) and all(i == value for i in items)


def each(x: Mapping[str, Any] | Sequence[Any], template: str, sep: str = "; ") -> str:
    """``template`` filled once per item, joined by ``sep``.

    Parameters
    ----------
    x : Mapping or Sequence
        The items; a template sees ``key`` (the mapping key, or the list index), ``item`` (the
        value) and, when the value is a mapping, its keys.
    template : str
        A plain ``str.format`` template of the claims file.
    sep : str
        Separator.

    Returns
    -------
    str
    """
    pairs = x.items() if isinstance(x, Mapping) else enumerate(x)
    return sep.join(template.format_map({**(v if isinstance(v, Mapping) else {}), "key": k, "item": v})
                    for k, v in pairs)
