"""The public face of :mod:`eqrec`: namespace and numpydoc docstrings.

In the spirit of python-control's ``control/tests/docstrings_test.py``: every
public function, class and method of the library (the packages of
``LIBRARY_PACKAGES`` and the modules of ``LIBRARY_MODULES``, so every name of
``eqrec._PUBLIC`` too) passes numpydoc's own validator
(:func:`numpydoc.validate.validate`) on the checks of ``CHECKS``: the
documented parameters match the signature, each with a type, a ``Returns``
(or ``Yields``) section when it returns something, the sections known and in
order.  The docstring examples of the public names run as doctests.
"""

from __future__ import annotations

import doctest
import inspect
import subprocess
import sys
import types
from typing import Protocol

import numpy as np
import pytest
from numpydoc.docscrape import get_doc_object
from numpydoc.validate import ERROR_MSGS, validate

import eqrec

# ---------------------------------------------------------------------------
# numpydoc's validator
# ---------------------------------------------------------------------------

#: The numpydoc checks every library docstring passes.
CHECKS = (
    "GL01", "GL02", "GL03", "GL05",  # layout: where the text starts and ends, blank lines, tabs
    "GL06", "GL07",  # no unknown section; sections in numpydoc's order
    "GL08", "GL09", "GL10",  # a docstring; deprecation first; reST directives with two colons
    "SS01", "SS02", "SS03", "SS04",  # a one-line summary, capitalised, with a period
    "PR01", "PR02", "PR03",  # the documented parameters are the signature's, in its order
    "PR04", "PR05", "PR06", "PR10",  # each with a type ("name : type"), spelt as numpydoc wants
    "PR08", "PR09",  # a parameter's description capitalised, with a period
    "RT01", "RT02", "RT04", "RT05",  # a Returns section when something is returned, one type a line
    "YD01",  # a Yields section for a generator
    "SA02", "SA03", "SA04",  # See Also entries described
)

#: Left out: too many docstrings fail them for no real fault (counts: the library with numpydoc 1.11.0).
LEFT_OUT = {
    "ES01": "no extended summary (253 objects): a one-line summary says enough for most helpers",
    "EX01": "no Examples section (358): examples are asked of the public names, run below as doctests",
    "SA01": "no See Also section (395)",
    "PR07": "a parameter without description (73, 71 in eqrec.design: system, solver, n_jobs, ...)",
    "RT03": "a return value without description (23)",
    "SS05": "a summary not in the infinitive (20, noun phrases such as 'Errors of ...' included)",
    "SS06": "a summary over two lines (11)",
}

#: Parameter checks a ``typing.Protocol`` skips: its constructor is typing's ``(*args, **kwargs)``, not ours (a
#: protocol documents the methods it asks for).
SIGNATURE_CHECKS = {"PR01", "PR02", "PR03"}


def numpydoc_problems(name: str, obj) -> list[str]:
    """numpydoc's errors of the checks of ``CHECKS`` for the object ``obj`` importable as ``name``."""
    result = validate(name)
    skip = SIGNATURE_CHECKS if inspect.isclass(obj) and getattr(obj, "_is_protocol", False) else set()
    return [f"{name}: {code} {message}" for code, message in result["errors"] if code in CHECKS and code not in skip]


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

def test_every_numpydoc_check_is_chosen_or_left_out():
    assert set(CHECKS) | set(LEFT_OUT) == set(ERROR_MSGS) and not set(CHECKS) & set(LEFT_OUT)


@pytest.mark.parametrize("name, obj", LIBRARY, ids=[n for n, _ in LIBRARY])
def test_numpydoc_docstring_of_the_library(name, obj):
    """Every public function, class and method of the library, not only those of the ``eqrec`` namespace."""
    problems = numpydoc_problems(name, obj)
    assert not problems, "\n".join(problems)


def _key(obj) -> tuple[str, str]:
    obj = getattr(obj, "__func__", obj)  # a classmethod read from its class
    return obj.__module__, obj.__qualname__


def test_the_library_is_covered():
    names = dict(LIBRARY)
    assert len(LIBRARY) > 250
    assert {"eqrec.lp.model.LPBuilder", "eqrec.design.classes.block_lp.build_class_lp", "eqrec.lmv.recursion.lmv_recursion",
            "eqrec.estimators.kalman.make_filter", "eqrec.systems.examples.batch_reactor"} <= names.keys()
    assert not any(n.startswith(("eqrec.studies", "eqrec.cli")) for n in names)
    # the public names and their methods are library objects, so they are validated above
    checked = {_key(obj) for _, obj in LIBRARY}
    assert not [name for name, obj in PUBLIC if _key(obj) not in checked]


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

    Returns
    -------
    float
        The sum.

    Parameters
    ----------
    a : float
        First number.
    b
        Second number (no type).
    d : float
        Not a parameter.

    Outputs
    -------
    Nothing.
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


def _no_docstring():
    pass


class _KeepsExceptionArgs(Exception):
    """An error that keeps Exception's ``(*args)``: nothing of ours to document."""


class _Stepping(Protocol):
    """What steps."""

    def step(self, y: float) -> float:
        """Step.

        Parameters
        ----------
        y : float
            A measurement.

        Returns
        -------
        float
            The estimate.
        """


def _problems(obj) -> list[str]:
    """:func:`numpydoc_problems` of an example of this module, without the module's name."""
    name = f"{__name__}.{obj.__qualname__}"
    return [p.removeprefix(f"{name}: ") for p in numpydoc_problems(name, obj)]


def test_the_validator_reports_what_is_wrong():
    with pytest.warns(UserWarning, match="Unknown section Outputs"):  # numpydoc's parser warns as well
        text = "\n".join(_problems(_undocumented))
    assert "PR01 Parameters {" in text and all(p in text for p in ("'c'", "'*args'", "'**kwargs'")), text
    assert 'PR04 Parameter "b" has no type' in text, text
    assert "PR02 Unknown parameters {'d'}" in text, text
    assert 'GL06 Found unknown section "Outputs"' in text, text
    assert "GL07 Sections are in the wrong order" in text, text
    assert _problems(_no_returns) == ["RT01 No Returns section found"]
    assert _problems(_no_docstring) == ["GL08 The object does not have a docstring"]
    assert _problems(_KeepsExceptionArgs) == []
    assert _problems(_Stepping) == []  # numpydoc alone: PR01 for typing's (*args, **kwargs)
    assert "PR01" in {code for code, _ in validate(get_doc_object(_Stepping))["errors"]}


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
