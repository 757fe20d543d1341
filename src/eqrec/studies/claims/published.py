"""The claims file ``config/claims.yaml``: read, checked, and the published values it holds.

Each entry holds what a paper says (``id``, ``quantity``, ``paper_value``,
``source``, ``compare``) and our wording, pointing (``value``) at our value
and its evidence in a ``values.json`` under ``results/``.  Every text is a
``str.format`` template with plain named fields and a format spec
(``{mu2:.6f}``, ``{{``/``}}`` for braces): a field that is anything else
(an expression, an index, a conversion, a nested spec) is refused here with
the claim id and the text named, and so is an unknown key (a ``when:``
condition of the former format).  Which texts a row shows is decided in
Python (:mod:`eqrec.studies.claims.table` and the studies' ``p*_claims`` modules).

This module imports none of them: :func:`published_value`, which the
Snakefile and P2's ``printed`` step use, depends on the file only.
"""

from __future__ import annotations

import copy
import functools
import re
import string
from pathlib import Path
from typing import Any, Mapping

import yaml

from eqrec.errors import InputError

KINDS = ("number", "interval", "array", "text", "none")
KEYS = ("id", "quantity", "paper_value", "source", "compare", "value", "shown_as", "note", "explanation")

_FIELD = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def check_template(template: Any, where: str) -> None:
    """Refuse a template that is not ``str.format`` with plain named fields and format specs.

    Parameters
    ----------
    template : Any
        The text of the claims file.
    where : str
        The claim id and key, for the message.
    """
    if not isinstance(template, str):
        raise InputError(f"{where}: a text must be a string, not {type(template).__name__}")
    try:
        parsed = list(string.Formatter().parse(template))
    except ValueError as exc:
        raise InputError(f"{where}: {exc} in {template!r}") from None
    for _, name, spec, conversion in parsed:  # name None: text after the last field
        if name is not None and (not _FIELD.fullmatch(name) or conversion or "{" in (spec or "")):
            field = name + (f"!{conversion}" if conversion else "") + (f":{spec}" if spec else "")
            raise InputError(f"{where}: field {{{field}}} is not a plain name with a format spec; "
                             "derive it in the claim's reason function (eqrec.studies.p*_claims)")


def named_texts(entry: dict, key: str, cid: str) -> dict[str, str]:
    """The named texts under ``key`` of a claim (a single ``note`` or ``shown_as`` is named after the key).

    Parameters
    ----------
    entry : dict
        One claim of the claims file.
    key : str
        ``note``, ``explanation`` or ``shown_as``.
    cid : str
        The claim id, for the message.

    Returns
    -------
    dict[str, str]
        Name -> template.
    """
    spec = entry.get(key)
    if spec is None:
        return {}
    if isinstance(spec, str) and key != "explanation":
        return {key: spec}
    if key == "shown_as" or not isinstance(spec, Mapping) or not spec:
        raise InputError(f"claim {cid}: '{key}' has the wrong form (note: a text or named texts; shown_as: a "
                         "text; explanation: named texts)", field=key)
    return {str(k): v for k, v in spec.items()}


def read_claims(path: str | Path) -> list[dict]:
    """Read and check the claims file.

    Parameters
    ----------
    path : str or Path
        ``config/claims.yaml``.

    Returns
    -------
    list of dict
        The entries, checked: keys, ids, comparison kinds, every text a plain template.
    """
    path = Path(path)
    data = yaml.safe_load(path.read_text())
    if not isinstance(data, list):
        raise InputError("must be a list of claim entries", str(path))
    for i, entry in enumerate(data):
        cid = entry.get("id", f"entry {i}")
        for key in ("id", "quantity", "paper_value", "source", "compare", "value"):
            if key not in entry:
                raise InputError(f"{cid} lacks '{key}'", str(path), key)
        if set(entry) - set(KEYS):
            raise InputError(f"claim {cid}: unknown keys {sorted(set(entry) - set(KEYS))} (the keys are {KEYS}; "
                             "conditions are the claim's reason function's)", str(path), "id")
        if entry["id"] in (earlier["id"] for earlier in data[:i]):
            raise InputError(f"duplicate claim id {entry['id']}", str(path), "id")
        kind = entry["compare"].get("kind")
        if kind not in KINDS:
            raise InputError(f"claim {cid}: unknown compare kind {kind!r}", str(path), "compare")
        for key in ("shown_as", "note", "explanation"):
            for name, text in named_texts(entry, key, cid).items():
                check_template(text, f"claim {cid}, {key}" + (f".{name}" if name != key else ""))
    return data


def published_value(claims_path: str | Path, claim_id: str) -> Any:
    """The paper's value of one claim of ``config/claims.yaml`` (the only place published numbers live).

    Parameters
    ----------
    claims_path : str or Path
        The claims file (read once per file version).
    claim_id : str
        The claim's id, e.g. ``"P2-F2:L"``.

    Returns
    -------
    Any
        A copy of its ``paper_value`` as written (a string keeps its printed trailing zeros).
    """
    path = Path(claims_path)
    for entry in _loaded_claims(path, path.stat().st_mtime_ns):
        if entry["id"] == claim_id:
            return copy.deepcopy(entry["paper_value"])
    raise InputError(f"{claims_path} has no claim {claim_id!r}", field="printed")


@functools.lru_cache(maxsize=4)
def _loaded_claims(path: Path, mtime_ns: int) -> list[dict]:
    return read_claims(path)
