"""Exceptions with enough context to name the offending file and field."""

from __future__ import annotations


class EqrecError(Exception):
    """Base class of all errors raised on purpose by :mod:`eqrec`.

    Catch it to handle every deliberate failure of a design (bad input,
    infeasible problem, solver or certification failure) in one place.

    Examples
    --------
    >>> import eqrec
    >>> issubclass(eqrec.InfeasibleDesign, eqrec.EqrecError)
    True
    """


class InputError(EqrecError, ValueError):
    """Malformed user input (matrix shapes, words, config fields).

    Also a :class:`ValueError`.  The message is prefixed with the source and
    the field when known (``"<source>: field '<field>': <message>"``); the
    command line reports it with exit status 1.

    Parameters
    ----------
    message : str
        What is wrong.
    source : str or None, optional
        File (or other origin) the value came from, if known.
    field : str or None, optional
        Name of the offending field, if known.

    Attributes
    ----------
    source : str or None
        As given.
    field : str or None
        As given.

    Examples
    --------
    >>> import eqrec
    >>> try:
    ...     eqrec.validate_language(["1012"], source="language.yaml")
    ... except eqrec.InputError as exc:
    ...     print(exc.field, "|", exc)
    words | language.yaml: field 'words': word '1012' has letters ['2'] outside the alphabet {0, 1}
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
    """The design problem has no solution (e.g. the recovery level is too small).

    Raised when the design LP is infeasible: no estimator of the chosen
    structure achieves equalized recovery at the requested level ``μ1``
    (exit status 3 on the command line).  The message names the terminal
    class that cannot reach ``μ1`` where the class engine knows it, and the
    smallest feasible ``μ1`` where it is known (then also :attr:`mu1_min`).

    Parameters
    ----------
    message : str
        What is infeasible, and what to do.
    mu1_min : float or None, optional
        The smallest feasible recovery level, as printed in the message
        (rounded up, so a retry at it succeeds), or ``None`` if unknown.

    Attributes
    ----------
    mu1_min : float or None
        As given.
    """

    def __init__(self, message: str = "", mu1_min: float | None = None):
        self.mu1_min = None if mu1_min is None else float(mu1_min)
        super().__init__(message)

    def __reduce__(self):  # keep mu1_min across processes (an error raised in a worker)
        return type(self), (str(self), self.mu1_min)


class SolverFailure(EqrecError):
    """The solver stopped without a usable optimum (numerical trouble, limits).

    Exit status 4 on the command line.
    """


class CertificationFailure(EqrecError):
    """Recovered gains do not achieve what the optimiser reported.

    Raised by the independent certification
    (:func:`eqrec.bounds.certify.certify_design`) when the exact worst case of
    the recovered gains exceeds the optimised ``μ2`` (or ``μ1`` at a
    pattern's end) by more than the tolerance; exit status 4 on the command
    line.
    """


class NotMeanSquareStable(EqrecError):
    """A stochastic system whose second moments diverge."""


class StepError(EqrecError):
    """A pipeline step that did not do what its rule declares.

    An output not written, a timing without a timings output.
    """
