"""The public face of :mod:`eqrec`: namespace and numpydoc docstrings.

In the spirit of python-control's ``control/tests/docstrings_test.py``: every
public function and class of ``eqrec._PUBLIC`` (and every public method of
the public classes) has a numpydoc docstring whose ``Parameters`` section
documents exactly the parameters of its signature, with a ``Returns`` (or
``Yields``) section when it returns something; the docstring examples run as
doctests.  ``numpydoc`` is not a dependency of the project, so the sections
are parsed here with a small parser of the numpydoc layout (a section title
underlined with dashes, entries ``name : type`` at the section's indentation,
descriptions indented below).
"""

from __future__ import annotations

import ast
import doctest
import inspect
import re
import subprocess
import sys
import textwrap
import types

import numpy as np
import pytest

import eqrec

# ---------------------------------------------------------------------------
# A small numpydoc section parser
# ---------------------------------------------------------------------------

SECTION_TITLES = ("Parameters", "Other Parameters", "Attributes", "Returns", "Yields", "Receives", "Raises",
                  "Warns", "Warnings", "See Also", "Notes", "References", "Examples", "Methods")


def docstring_sections(doc: str | None) -> dict[str, list[str]]:
    """Sections of a numpydoc docstring: title -> its lines (dedented), ``""`` -> the summary part."""
    lines = inspect.cleandoc(doc or "").splitlines()
    sections: dict[str, list[str]] = {"": []}
    current = ""
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        title = line.strip()
        if title in SECTION_TITLES and re.fullmatch(r"\s*-{3,}\s*", nxt) and len(nxt.strip()) >= len(title):
            current = title
            sections[current] = []
            i += 2
            continue
        sections[current].append(line)
        i += 1
    return {k: textwrap.dedent("\n".join(v)).splitlines() for k, v in sections.items()}


ENTRY = re.compile(r"^(?P<names>[*\w][\w*]*(?:\s*,\s*[*\w][\w*]*)*)\s*(?::\s*(?P<type>.*\S))?\s*$")


def documented_parameters(doc: str | None, section: str = "Parameters") -> dict[str, str | None]:
    """``name -> type`` (``None`` without a type) of the entries of a ``Parameters``-like section.

    An entry is a line at the section's own indentation; ``a, b : float``
    documents both names.  Leading ``*`` of ``*args``, ``**kwargs`` are kept.
    """
    out: dict[str, str | None] = {}
    for line in docstring_sections(doc).get(section, []):
        if not line.strip() or line[0].isspace():
            continue  # blank or a description line
        m = ENTRY.match(line)
        if m is None:
            out[line.strip()] = None  # malformed entry: reported as an unknown name
            continue
        for name in re.split(r"\s*,\s*", m["names"]):
            out[name] = m["type"]
    return out


def signature_parameters(obj) -> list[str] | None:
    """Parameter names of a callable as numpydoc spells them (``*args``, ``**kwargs``), without ``self``/``cls``.

    ``None`` when the signature is not introspectable (a builtin).
    """
    try:
        sig = inspect.signature(obj)
    except (TypeError, ValueError):
        return None
    names = []
    for i, (name, par) in enumerate(sig.parameters.items()):
        if i == 0 and name in ("self", "cls") and not isinstance(obj, type):
            continue
        prefix = {inspect.Parameter.VAR_POSITIONAL: "*", inspect.Parameter.VAR_KEYWORD: "**"}.get(par.kind, "")
        names.append(prefix + name)
    return names


def returns_value(func) -> bool:
    """Whether a function returns something other than ``None`` (annotation, else its ``return`` statements)."""
    ann = inspect.signature(func).return_annotation
    if ann in (None, "None"):
        return False
    if ann is not inspect.Signature.empty:
        return True
    try:
        tree = ast.parse(textwrap.dedent(inspect.getsource(func)))
    except (OSError, TypeError, SyntaxError):
        return False
    body = tree.body[0]

    def walk(node):  # the function's own statements, not those of nested functions
        for child in ast.iter_child_nodes(node):
            if isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef)):
                continue
            yield child
            yield from walk(child)

    for node in walk(body):
        if isinstance(node, (ast.Yield, ast.YieldFrom)):
            return True
        if isinstance(node, ast.Return) and node.value is not None and not (
                isinstance(node.value, ast.Constant) and node.value.value is None):
            return True
    return False


def docstring_problems(obj, name: str) -> list[str]:
    """Everything wrong with the numpydoc docstring of the function, method or class ``obj`` called ``name``."""
    doc = inspect.getdoc(obj) if not isinstance(obj, type) else obj.__doc__
    if not doc or not doc.strip():
        return [f"{name}: no docstring"]
    problems = []
    summary = [line for line in docstring_sections(doc)[""] if line.strip()]
    if not summary:
        problems.append(f"{name}: no one-line summary")
    if isinstance(obj, type):
        # a class documents its constructor; an exception that keeps Exception's (*args) has nothing to document
        init = obj.__dict__.get("__init__") or next(
            (c.__dict__["__init__"] for c in obj.__mro__ if "__init__" in c.__dict__), None)
        if init is None or getattr(init, "__module__", "").split(".")[0] != "eqrec":
            return problems
        params = signature_parameters(obj)
    else:
        params = signature_parameters(obj)
    if params is None:
        return problems
    documented = documented_parameters(doc)
    if params and "Parameters" not in docstring_sections(doc):
        problems.append(f"{name}: no Parameters section (parameters {params})")
    for p in params:
        if p not in documented and p.lstrip("*") not in documented:
            problems.append(f"{name}: parameter {p!r} is not documented")
        elif documented.get(p, documented.get(p.lstrip("*"))) is None:
            problems.append(f"{name}: parameter {p!r} is documented without a type ('{p} : type')")
    bare = {p.lstrip("*") for p in params}
    for d in documented:
        if d.lstrip("*") not in bare:
            problems.append(f"{name}: documented parameter {d!r} is not in the signature {params}")
    order = [d for d in documented if d.lstrip("*") in bare]
    if order != [p for p in params if p in documented or p.lstrip("*") in documented]:
        problems.append(f"{name}: parameters documented in the order {order}, signature order {params}")
    if not isinstance(obj, type) and returns_value(obj):
        sections = docstring_sections(doc)
        if "Returns" not in sections and "Yields" not in sections:
            problems.append(f"{name}: returns a value but has no Returns section")
    return problems


# ---------------------------------------------------------------------------
# What is public
# ---------------------------------------------------------------------------

def public_objects() -> list[tuple[str, object]]:
    """``(qualified name, object)`` of the public functions, classes and the classes' public methods."""
    out = []
    for name in eqrec._PUBLIC:
        obj = getattr(eqrec, name)
        out.append((f"eqrec.{name}", obj))
        if isinstance(obj, type):
            out += [(f"eqrec.{name}.{m}", f) for m, f in public_methods(obj)]
    return out


def public_methods(cls: type) -> list[tuple[str, object]]:
    """Public methods (functions, static and class methods) defined by ``cls`` or its eqrec base classes."""
    seen: dict[str, object] = {}
    for klass in cls.__mro__:
        if klass.__module__.split(".")[0] != "eqrec":
            continue  # Exception's with_traceback, object's methods: not ours to document
        for mname, attr in vars(klass).items():
            if mname.startswith("_") or mname in seen:
                continue
            if isinstance(attr, (staticmethod, classmethod)):
                seen[mname] = getattr(cls, mname)
            elif isinstance(attr, types.FunctionType):
                seen[mname] = getattr(cls, mname)
    return sorted(seen.items())


def public_properties(cls: type) -> list[tuple[str, property]]:
    seen: dict[str, property] = {}
    for klass in cls.__mro__:
        if klass.__module__.split(".")[0] != "eqrec":
            continue
        for pname, attr in vars(klass).items():
            if not pname.startswith("_") and pname not in seen and isinstance(attr, property):
                seen[pname] = attr
    return sorted(seen.items())


PUBLIC = public_objects()
CLASSES = [(f"eqrec.{n}", getattr(eqrec, n)) for n in eqrec._PUBLIC if isinstance(getattr(eqrec, n), type)]


#: The library: every module of these packages (the studies are the pipeline's orchestration, the CLI a command).
LIBRARY_PACKAGES = ("eqrec.systems", "eqrec.arrivals", "eqrec.lp", "eqrec.bounds", "eqrec.estimators", "eqrec.simulate",
                    "eqrec.lmv", "eqrec.design", "eqrec.interop")
LIBRARY_MODULES = ("eqrec.checks", "eqrec.errors", "eqrec.io")


def library_objects() -> list[tuple[str, object]]:
    """``(qualified name, object)`` of every public function and class defined in a library module, and of the
    public methods each class defines (python-control's ``docstrings_test`` checks its whole package the same way)."""
    import importlib
    import pkgutil

    names = list(LIBRARY_MODULES)
    for pkg in LIBRARY_PACKAGES:
        names += [m.name for m in pkgutil.walk_packages(importlib.import_module(pkg).__path__, pkg + ".")
                  if not m.ispkg]
    out = []
    for modname in sorted(names):
        mod = importlib.import_module(modname)
        for name, obj in vars(mod).items():
            if name.startswith("_") or not (inspect.isfunction(obj) or inspect.isclass(obj)):
                continue
            if obj.__module__ != modname:
                continue  # imported here, checked where it is defined
            out.append((f"{modname}.{name}", obj))
            if inspect.isclass(obj):
                out += [(f"{modname}.{name}.{m}", f) for m, f in public_methods(obj)
                        if f.__qualname__.split(".")[0] == name]
    return out


LIBRARY = library_objects()


# ---------------------------------------------------------------------------
# Docstrings
# ---------------------------------------------------------------------------

@pytest.mark.parametrize("name, obj", PUBLIC, ids=[n for n, _ in PUBLIC])
def test_numpydoc_docstring(name, obj):
    problems = docstring_problems(obj, name)
    assert not problems, "\n".join(problems)


@pytest.mark.parametrize("name, obj", LIBRARY, ids=[n for n, _ in LIBRARY])
def test_numpydoc_docstring_of_the_library(name, obj):
    """Every public function, class and method of the library, not only those of the ``eqrec`` namespace."""
    problems = docstring_problems(obj, name)
    assert not problems, "\n".join(problems)


def test_the_library_is_covered():
    names = dict(LIBRARY)
    assert len(LIBRARY) > 250
    assert {"eqrec.lp.model.LPBuilder", "eqrec.design.classes.block_lp.build_class_lp", "eqrec.lmv.recursion.lmv_recursion",
            "eqrec.estimators.kalman.make_filter", "eqrec.systems.examples.batch_reactor"} <= names.keys()
    assert not any(n.startswith(("eqrec.studies", "eqrec.cli")) for n in names)


@pytest.mark.parametrize("name, cls", CLASSES, ids=[n for n, _ in CLASSES])
def test_public_properties_have_docstrings(name, cls):
    missing = [f"{name}.{p}" for p, prop in public_properties(cls) if not (prop.__doc__ or "").strip()]
    assert not missing, f"properties without a docstring: {missing}"


def test_public_functions_and_classes_are_covered():
    kinds = {n: type(getattr(eqrec, n)).__name__ for n in eqrec._PUBLIC}
    assert all(callable(getattr(eqrec, n)) for n in eqrec._PUBLIC), kinds
    assert "eqrec.Design.estimator" in dict(PUBLIC)
    assert {"reset", "step", "update"} <= {m for m, _ in public_methods(eqrec.GuaranteedEstimator)}


def _undocumented(a, b, *args, c: int = 1, **kwargs) -> float:
    """Add numbers.

    Parameters
    ----------
    a : float
        First number.
    b
        Second number (no type).
    d : float
        Not a parameter.
    """
    return a + b + c


def _no_returns(x: int) -> int:
    """Square.

    Parameters
    ----------
    x : int
        The number.
    """
    return x * x


def test_checker_reports_what_is_wrong():
    problems = docstring_problems(_undocumented, "_undocumented")
    text = "\n".join(problems)
    assert "_undocumented: parameter 'c' is not documented" in text
    assert "_undocumented: parameter '*args' is not documented" in text
    assert "_undocumented: parameter '**kwargs' is not documented" in text
    assert "_undocumented: parameter 'b' is documented without a type" in text
    assert "_undocumented: documented parameter 'd' is not in the signature" in text
    assert "_undocumented: returns a value but has no Returns section" in text
    assert docstring_problems(_no_returns, "_no_returns") == ["_no_returns: returns a value but has no Returns section"]
    assert docstring_problems(lambda: None, "anonymous") == ["anonymous: no docstring"]


def test_parser():
    doc = """Summary.

    Parameters
    ----------
    x, y : float
        Coordinates.

        More text : not an entry.
    *args
    **kwargs : dict
        Options.

    Returns
    -------
    float
    """
    assert documented_parameters(doc) == {"x": "float", "y": "float", "*args": None, "**kwargs": "dict"}
    assert set(docstring_sections(doc)) == {"", "Parameters", "Returns"}
    assert signature_parameters(_undocumented) == ["a", "b", "*args", "c", "**kwargs"]
    assert returns_value(_undocumented) and not returns_value(test_parser)


# ---------------------------------------------------------------------------
# Doctests of the public names
# ---------------------------------------------------------------------------

def _doctests():
    finder = doctest.DocTestFinder(recurse=False)
    out = []
    for name, obj in PUBLIC:
        module = inspect.getmodule(obj)
        globs = {"eqrec": eqrec, "np": np}
        for test in finder.find(obj, name, module=module, globs=globs):
            if test.examples:
                out.append(test)
    return out


DOCTESTS = _doctests()


def test_public_names_have_examples():
    assert len(DOCTESTS) >= 5, [t.name for t in DOCTESTS]


@pytest.mark.parametrize("test", DOCTESTS, ids=[t.name for t in DOCTESTS])
def test_doctest(test):
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    out: list[str] = []
    result = runner.run(test, out=out.append)
    assert result.failed == 0, f"doctest of {test.name} failed:\n" + "".join(out)


# ---------------------------------------------------------------------------
# The namespace
# ---------------------------------------------------------------------------

def test_all_names_resolve():
    for name in eqrec.__all__:
        assert getattr(eqrec, name) is not None, name
    assert set(eqrec._PUBLIC) <= set(eqrec.__all__)


def test_dir_lists_public_names():
    listed = dir(eqrec)
    missing = [n for n in eqrec.__all__ if n not in listed]
    assert not missing, missing


def test_public_names_come_from_their_module():
    import importlib

    for name, module in eqrec._PUBLIC.items():
        assert getattr(eqrec, name) is getattr(importlib.import_module(module), name), name


def test_unknown_attribute_raises():
    with pytest.raises(AttributeError, match="no_such_name"):
        eqrec.no_such_name  # noqa: B018
    assert not hasattr(eqrec, "design_nothing")


def test_import_loads_no_solver():
    code = "import sys, eqrec; print('highspy' in sys.modules, 'scipy' in sys.modules)"
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    highspy, scipy = res.stdout.split()
    assert highspy == "False", res.stdout
    assert scipy == "False", res.stdout
