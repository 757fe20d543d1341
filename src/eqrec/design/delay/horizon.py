"""The longest horizon that solves: a bisection on ``T``, bounded in time, for a design that failed (issue 41 §2).

A design of an unstable plant over a long horizon fails: every error map grows like ``ρ^T`` (``ρ`` the spectral
radius of ``A``), and past about ``log(1e8) / log ρ`` steps its entries span more than a double-precision LP
resolves (:func:`eqrec.design.inputs.growth_hint`).  Which horizon still solves is found by trying: this module
starts at that horizon and halves the interval between one that solved and one that did not.  The search is
bounded: at most ``max_tries`` designs and ``budget`` seconds in all (:data:`HORIZON_SEARCH_SECONDS`), announced
first; each design is estimated first (:func:`eqrec.design.inputs.estimate_delay_design`) and skipped when its
estimate exceeds the time left, and runs in a child process that is stopped when the time left is up (a solver
that does not return counts as "no answer": the search goes on below it).  ``eqrec design --horizon`` runs it after
a failed design (:func:`eqrec.cli.main`); from Python, :func:`longest_horizon`.
"""

from __future__ import annotations

import math
import os
import sys
import time
from dataclasses import dataclass
from typing import Callable

import numpy as np

from eqrec.checks import integer, short_label
from eqrec.design.inputs import RESOLVED_GROWTH, check_system, estimate_delay_design, growth_hint
from eqrec.errors import CertificationFailure, InfeasibleDesign, InputError, SolverFailure
from eqrec.systems.affine import AffineSystem

#: Seconds the search for the longest horizon that solves may take in all (every design it tries included).
HORIZON_SEARCH_SECONDS = 120.0
#: Designs the search tries at most.
HORIZON_SEARCH_TRIES = 8


@dataclass(frozen=True)
class HorizonSearch:
    """The outcome of a search for the longest horizon that solves.

    Parameters
    ----------
    horizon : int
        The horizon searched below (the one that failed).
    longest : int or None
        The longest horizon that solved (``None``: none did).
    shortest_failing : int
        The shortest horizon that failed, was skipped or gave no answer in time (``horizon`` if none below).
    tries : tuple of tuple
        ``(T, outcome, seconds, message)`` of each design tried, in order; ``outcome`` is ``"solves"``,
        ``"fails"``, ``"no answer"`` (stopped when the time was up) or ``"skipped"`` (estimated past it).
    seconds : float
        Time the search took.
    budget : float
        Its time limit.
    reason : str
        Why a long horizon fails (:func:`eqrec.design.inputs.growth_hint`; empty for a plant that does not grow).
    """

    horizon: int
    longest: int | None
    shortest_failing: int
    tries: tuple
    seconds: float
    budget: float
    reason: str = ""

    @property
    def exact(self) -> bool:
        """``longest + 1 == shortest_failing``: the longest horizon that solves is known exactly."""
        return self.longest is not None and self.shortest_failing - self.longest == 1

    def summary(self, flag: str = "horizon ") -> str:
        """One line: the longest horizon that solves, or why none was found.

        Parameters
        ----------
        flag : str, optional
            How a horizon is named (``"--horizon "`` for the command line).

        Returns
        -------
        str
            E.g. ``"--horizon 37 solves and 38 does not"``.
        """
        n, spent = len(self.tries), self.seconds
        if self.longest is None:
            last = next((t for t in reversed(self.tries) if t[1] == "fails" and t[3]), None)
            why = f"; the last failure: {last[3]}" if last else ""
            out = [t for t in self.tries if t[1] in ("no answer", "skipped")]
            if out and not any(t[1] == "fails" for t in self.tries):
                why = f"; no answer within the search's {self.budget:.0f} s"
            return f"no horizon below {self.shortest_failing} solved either ({n} designs in {spent:.0f} s){why}"
        above = next((t for t in self.tries if t[0] == self.shortest_failing), None)
        if above is None or above[1] == "fails":
            not_above = f"{self.shortest_failing} does not"
        elif above[1] == "skipped":
            not_above = f"{self.shortest_failing} was estimated past the time left"
        else:
            not_above = f"{self.shortest_failing} gave no answer in the time left"
        if self.exact:
            return f"{flag}{self.longest} solves and {not_above}"
        return f"{flag}{self.longest} solves (the longest found in {n} designs and {spent:.0f} s; {not_above})"


def probe_in_child(run: Callable[[], None], seconds: float) -> tuple[str, str]:
    """Run ``run()`` in a forked child process, stopped after ``seconds``.

    Parameters
    ----------
    run : callable
        The design (its messages and progress lines go to ``/dev/null``).
    seconds : float
        Its time limit.

    Returns
    -------
    outcome : str
        ``"solves"``, ``"fails"`` (a design error: infeasible, solver, certification or input) or
        ``"no answer"`` (still running when the time was up: stopped).
    message : str
        The failure's message, shortened (empty otherwise).
    """
    import multiprocessing

    reader, writer = multiprocessing.get_context("fork").Pipe(duplex=False)

    def child() -> None:
        try:
            os.dup2(os.open(os.devnull, os.O_WRONLY), 2)
        except OSError:
            pass
        sys.stderr = open(os.devnull, "w")
        try:
            run()
        except (InfeasibleDesign, SolverFailure, CertificationFailure, InputError) as exc:
            writer.send(short_label(f"{type(exc).__name__}: {exc}".split("; the horizon ")[0], 300))
            os._exit(1)
        os._exit(0)

    proc = multiprocessing.get_context("fork").Process(target=child, daemon=True)
    proc.start()
    writer.close()
    proc.join(seconds)
    if proc.is_alive():
        proc.kill()
        proc.join()
        return "no answer", ""
    message = reader.recv() if proc.exitcode == 1 and reader.poll() else ""
    return ("solves", "") if proc.exitcode == 0 else ("fails", message)


def search_horizon(probe: Callable[[int, float], tuple[str, str]], horizon: int, rho: float, *,
                   estimate: Callable[[int], float] | None = None, budget: float = HORIZON_SEARCH_SECONDS,
                   max_tries: int = HORIZON_SEARCH_TRIES, flag: str = "horizon ", reason: str = "") -> HorizonSearch:
    """The bisection of :func:`longest_horizon` on any design: ``probe(T, seconds)`` tries the horizon ``T``.

    Parameters
    ----------
    probe : callable
        ``probe(T, seconds) -> (outcome, message)`` (:func:`probe_in_child`), stopped after ``seconds``.
    horizon : int
        The horizon that failed.
    rho : float
        The spectral radius of ``A``: the first guess is where ``ρ^T`` reaches
        :data:`~eqrec.design.inputs.RESOLVED_GROWTH` (half the horizon when ``ρ <= 1``).
    estimate : callable or None, optional
        ``estimate(T) -> seconds`` of a design (a design estimated past the time left is skipped).
    budget : float, optional
        Seconds for the whole search.
    max_tries : int, optional
        Designs tried at most.
    flag : str, optional
        How a horizon is named in the progress lines (``"--horizon "`` for the command line).
    reason : str, optional
        Why a long horizon fails, kept in the result.

    Returns
    -------
    HorizonSearch
        The longest horizon that solved (if any) and every design tried; each printed to stderr as it ends.
    """
    print(f"eqrec: searching for the longest horizon that solves: at most {max_tries} designs and {budget:.0f} s",
          file=sys.stderr)
    start = time.perf_counter()
    tries = []
    lo, hi = 0, int(horizon)  # lo: solves (0: none found yet), hi: fails
    if rho > 1:
        guess = min(hi - 1, max(1, int(np.log(RESOLVED_GROWTH) / np.log(rho))))
    else:
        guess = max(1, hi // 2)
    while hi - lo > 1 and len(tries) < max_tries and time.perf_counter() - start < budget:
        T = guess if not tries else (lo + hi) // 2
        left = budget - (time.perf_counter() - start)
        t0 = time.perf_counter()
        expected = estimate(T) if estimate is not None else 0.0
        if expected > left:
            outcome, message = "skipped", ""
            print(f"eqrec: trying {flag}{T}: skipped (estimated {expected:.0f} s, {left:.0f} s left)",
                  file=sys.stderr)
        else:
            outcome, message = probe(T, max(1.0, left))
            print(f"eqrec: trying {flag}{T}: {outcome}" + (f" within {left:.0f} s" if outcome == "no answer" else "")
                  + f" ({time.perf_counter() - t0:.1f} s)", file=sys.stderr)
        tries.append((T, outcome, time.perf_counter() - t0, message))
        if outcome == "solves":
            lo = T
        else:
            hi = T
    return HorizonSearch(horizon=int(horizon), longest=lo or None, shortest_failing=hi, tries=tuple(tries),
                         seconds=time.perf_counter() - start, budget=float(budget), reason=reason)


def spectral_radius(system: AffineSystem) -> float:
    """The spectral radius of ``A`` (time-varying: of its first matrix); ``nan`` if it cannot be computed.

    Parameters
    ----------
    system : AffineSystem
        The plant.

    Returns
    -------
    float
        ``max |λ(A)|``.
    """
    try:
        return float(np.max(np.abs(np.linalg.eigvals(np.asarray(system.A_at(0), float)))))
    except (np.linalg.LinAlgError, ValueError):
        return math.nan


def longest_horizon(system: AffineSystem, max_delay: int, horizon: int, *, max_lost: int | None = None,
                    mu1="free", cost: str = "sum", budget: float | None = None,
                    max_tries: int = HORIZON_SEARCH_TRIES) -> HorizonSearch:
    """The longest horizon below ``horizon`` whose design of ``{0..τ̄}^T`` solves, by a bisection bounded in time.

    For a design that failed (typically an unstable plant over a long horizon: the error maps grow like ``ρ^T``,
    :func:`eqrec.design.inputs.growth_hint`); the Python side of what ``eqrec design --horizon`` does after a
    failure.  At most ``max_tries`` designs and ``budget`` seconds (default :data:`HORIZON_SEARCH_SECONDS`),
    announced first; each design is estimated first and skipped past the time left, and runs in a child process
    stopped when the time left is up; each is printed (stderr) as it ends.

    Parameters
    ----------
    system : AffineSystem
        The plant.
    max_delay : int
        ``τ̄`` (``0..9``).
    horizon : int
        The horizon that failed (the search looks below it), ``>= 2``.
    max_lost : int or None, optional
        At most this many measurements lost per block (:func:`eqrec.delay_classes`).
    mu1 : float or "free", optional
        ``"free"`` (default): :func:`eqrec.design_delay_global`; a number: :func:`eqrec.design_delay` at it.
    cost : str, optional
        ``"sum"`` or ``"max"``.
    budget : float or None, optional
        Seconds for the whole search (``None``: :data:`HORIZON_SEARCH_SECONDS`).
    max_tries : int, optional
        Designs tried at most.

    Returns
    -------
    HorizonSearch
        ``longest`` (``None`` if no horizon tried solved), ``shortest_failing``, every design tried with its
        outcome, time and failure message, and ``summary()``: the answer in one line.

    Raises
    ------
    InputError
        A bad plant, delay, horizon, loss budget, ``mu1`` or budget (the field is named).

    Examples
    --------
    >>> import eqrec
    >>> found = eqrec.longest_horizon(eqrec.acc_system(), 1, 6, mu1=1.0, budget=60)  # doctest: +SKIP
    >>> found.summary()  # doctest: +SKIP
    'horizon 5 solves and 6 does not'
    """
    from eqrec.design.delay.design import design_delay, design_delay_global
    from eqrec.design.delay.languages import delay_classes
    from eqrec.design.inputs import check_mu1

    system = check_system(system)
    D = integer(max_delay, "max_delay", high=9)
    T = integer(horizon, "horizon", low=2)
    m = None if max_lost is None else integer(max_lost, "max_lost", high=T)
    free = isinstance(mu1, str) and mu1.strip().lower() == "free"
    level = None if free else check_mu1(mu1)
    budget = HORIZON_SEARCH_SECONDS if budget is None else float(budget)
    if not (budget > 0 and math.isfinite(budget)):
        raise InputError(f"must be a positive number of seconds, got {budget!r}", field="budget")
    integer(max_tries, "max_tries", low=1)

    def probe(t: int, seconds: float) -> tuple[str, str]:
        def run() -> None:
            classes = delay_classes(max_delay=D, horizon=t, max_lost=m)
            if free:
                design_delay_global(system, classes, cost=cost, n_jobs=1)
            else:
                design_delay(system, classes, level, cost=cost, n_jobs=1)
        return probe_in_child(run, seconds)

    def estimate(t: int) -> float:
        return estimate_delay_design(system, D, t, max_lost=m, mu1_free=free).seconds

    return search_horizon(probe, T, spectral_radius(system), estimate=estimate, budget=budget, max_tries=max_tries,
                          reason=growth_hint(system, T))
