"""Sphinx: the API reference is exactly ``eqrec.__all__``, and references to a name's home module resolve.

* :func:`check_api_lists_all` stops the build when ``api.rst``'s ``autosummary`` lists differ from
  ``eqrec.__all__`` (a name exported but not documented, or documented but not exported).
* :func:`resolve_public_names`: the docstrings refer to a public name by the module that defines it
  (``:class:`~eqrec.systems.affine.AffineSystem```); the reference documents it as ``eqrec.AffineSystem``, so
  such a reference (and one to its methods and attributes) is resolved to the public page.
* The docstrings also name the package's inner modules, classes and helpers (``:mod:`eqrec.bounds.zonotope```),
  which the site does not document one by one (the reference is ``eqrec.__all__``; :doc:`guide/architecture`
  describes the rooms).  Such a reference is shown as code, without a link, **only if it names an object that
  exists** (:func:`existing_object`: imported, relative to the docstring's class and module as Python would
  read it); a reference to nothing (a typo, a renamed function) still fails the ``-n`` build.
"""
from __future__ import annotations

import importlib
import inspect
import re
from pathlib import Path

from sphinx.errors import ExtensionError

import eqrec

_ENTRY = re.compile(r"^\s{3,}(~?eqrec\.)?(?P<name>[A-Za-z_][A-Za-z0-9_]*)\s*$")


def listed_names(api_page: Path) -> list[str]:
    """The names under the ``autosummary`` directives of the API page, in order."""
    names, inside = [], False
    for line in api_page.read_text(encoding="utf-8").splitlines():
        if line.startswith(".. autosummary::"):
            inside = True
            continue
        if inside:
            if line.strip() == "" or line.lstrip().startswith(":"):
                continue
            m = _ENTRY.match(line)
            if m is None:
                inside = False
                continue
            names.append(m["name"])
    return names


def check_api_lists_all(app, config):
    names = listed_names(Path(app.srcdir) / "api.rst")
    public = [n for n in eqrec.__all__ if n != "__version__"]
    missing = sorted(set(public) - set(names))
    extra = sorted(set(names) - set(public))
    twice = sorted({n for n in names if names.count(n) > 1})
    if missing or extra or twice:
        raise ExtensionError(f"api.rst must list eqrec.__all__ once each: not listed {missing}, "
                             f"not exported {extra}, listed twice {twice}")


def resolve_public_names(app, env, node, contnode):
    if node.get("refdomain") != "py":
        return None
    target = node["reftarget"]
    for name, module in eqrec._PUBLIC.items():
        home = f"{module}.{name}"
        if target == home or target.startswith(home + "."):
            public = "eqrec." + name + target[len(home):]
            domain = env.get_domain("py")
            return domain.resolve_xref(env, node["refdoc"], app.builder, node["reftype"], public, node, contnode)
    return None


def _lookup(path: str):
    """The object ``path`` names (a module, or attributes of a module), or raise LookupError."""
    parts = path.split(".")
    for cut in range(len(parts), 0, -1):
        try:
            obj = importlib.import_module(".".join(parts[:cut]))
        except ImportError:
            continue
        for attr in parts[cut:]:
            if not hasattr(obj, attr):
                raise LookupError(path)
            obj = getattr(obj, attr)
        return obj
    raise LookupError(path)


def _instance_attribute(path: str) -> bool:
    """``Class.name`` where ``name`` is a dataclass field or set as ``self.name = …`` in the class's source."""
    owner_path, _, name = path.rpartition(".")
    try:
        owner = _lookup(owner_path)
    except LookupError:
        return False
    if not inspect.isclass(owner):
        return False
    if name in getattr(owner, "__dataclass_fields__", {}):
        return True
    for klass in owner.__mro__:
        try:
            source = inspect.getsource(klass)
        except (OSError, TypeError):
            continue
        if re.search(rf"\bself\.{re.escape(name)}\s*(:[^=]*)?=", source):
            return True
    return False


def existing_object(target: str, module: str | None, cls: str | None, page: str | None = None) -> bool:
    """Whether ``target``, read from a docstring of ``module.cls`` (either may be None), names a real object.

    Tried as Python's docstring readers would: absolute; in the class (and its home module, for a public name
    documented as ``eqrec.Name``); in the module.  ``page``, the API page (``generated/eqrec.Name…``) the
    reference is on, gives the home module of a public function.
    """
    target = target.lstrip("~.")
    scopes = [""]
    if page and page.startswith("generated/eqrec."):
        public = page.removeprefix("generated/eqrec.").split(".")[0]
        if public in eqrec._PUBLIC:
            scopes[:0] = [f"{eqrec._PUBLIC[public]}.{public}.", f"{eqrec._PUBLIC[public]}."]
    if module and cls:
        scopes.insert(0, f"{module}.{cls}.")
        try:
            owner = _lookup(f"{module}.{cls.split('.')[0]}")
            home = inspect.getmodule(owner)
            if home is not None:
                scopes.insert(1, f"{home.__name__}.{cls}.")
                scopes.insert(2, f"{home.__name__}.")
        except LookupError:
            pass
    if module:
        scopes.insert(len(scopes) - 1, f"{module}.")
    for scope in scopes:
        try:
            _lookup(scope + target)
            return True
        except LookupError:
            if scope.endswith(".") and _instance_attribute(scope + target):
                return True
    return False


def code_for_existing_objects(app, env, node, contnode):
    """Inner objects the site does not document: code without a link, if (and only if) they exist."""
    if node.get("refdomain") != "py" or node.get("reftype") not in ("mod", "func", "class", "meth", "attr",
                                                                      "data", "obj", "exc", "const"):
        return None
    if existing_object(node["reftarget"], node.get("py:module"), node.get("py:class"), node.get("refdoc")):
        return contnode
    return None


def _balanced_summary(original):
    """autosummary's one-sentence summary, extended to the next sentence end while it cuts a ````literal````.

    (autosummary splits the first paragraph at ``". "``; a literal such as ````e.g. x```` or ````x. y```` is then
    cut in two, which docutils reports as an inline literal without end.)
    """
    from sphinx.ext.autosummary import periods_re

    def extract_summary(doc, settings):
        summary = original(doc, settings)
        if summary.count("``") % 2 == 0:
            return summary
        stanza = []
        for line in doc:
            if not line.strip():
                if stanza:
                    break
                continue
            stanza.append(line.strip())
        sentences = periods_re.split(" ".join(stanza))
        for i in range(1, len(sentences) + 1):
            candidate = ". ".join(sentences[:i]).rstrip(".") + "."
            if candidate.count("``") % 2 == 0:
                return candidate
        return " ".join(stanza)

    return extract_summary


def setup(app):
    import sphinx.ext.autosummary as autosummary

    if not getattr(autosummary.extract_summary, "eqrec_balanced", False):
        autosummary.extract_summary = _balanced_summary(autosummary.extract_summary)
        autosummary.extract_summary.eqrec_balanced = True
    app.connect("config-inited", check_api_lists_all)
    app.connect("missing-reference", resolve_public_names, priority=400)
    app.connect("missing-reference", code_for_existing_objects, priority=900)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
