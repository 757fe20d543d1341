"""Exceptions with enough context to name the offending file and field."""

from __future__ import annotations


class EqrecError(Exception):
    """Base class of all errors raised on purpose by :mod:`eqrec`."""


class InputError(EqrecError, ValueError):
    """Malformed user input (matrix shapes, words, config fields).

    Parameters
    ----------
    message
        What is wrong.
    source
        File (or other origin) the value came from, if known.
    field
        Name of the offending field, if known.
    """

    def __init__(self, message: str, source: str | None = None, field: str | None = None):
        self.source = source
        self.field = field
        where = ""
        if source and field:
            where = f"{source}: field '{field}': "
        elif source:
            where = f"{source}: "
        elif field:
            where = f"field '{field}': "
        super().__init__(where + message)


class InfeasibleDesign(EqrecError):
    """The design problem has no solution (e.g. the recovery level is too small)."""


class SolverFailure(EqrecError):
    """The solver stopped without a usable optimum (numerical trouble, limits)."""


class CertificationFailure(EqrecError):
    """Recovered gains do not achieve what the optimiser reported."""


class NotMeanSquareStable(EqrecError):
    """A stochastic system whose second moments diverge."""
