"""The result of every design method: gains, levels, solver record and certificate."""

from __future__ import annotations

from dataclasses import dataclass, field


from eqrec.core.gains import GainSchedule
from eqrec.core.lp import LPSolution
from eqrec.core.patterns import ArrivalPattern, as_pattern
from eqrec.core.systems import AffineSystem


@dataclass
class Design:
    """A solved (and, once :func:`eqrec.core.certify.certify_design` ran, certified) design.

    Attributes
    ----------
    method
        ``"prefix"``, ``"time"``, ``"augmented"``, ...
    patterns
        The designed arrival patterns (0/1 words are converted).
    T
        Horizon.
    M1
        Recovery level ``μ1``.
    mu2
        Largest intermediate level (the LP optimum).
    schedule
        The gains ``(F, u0)`` per pattern prefix.
    solution
        The solver's record.
    levels
        Optional per-node levels ``μ2`` keyed by the node's prefix label.
    certificate
        The independent worst-case certificate (:class:`eqrec.core.certify.Certificate`).
    class_gains
        Class engine: one gain ``K`` per (time, available data) class
        (:class:`eqrec.core.classes.ClassGains`), the estimator in class form.
        ``schedule`` (node gains) is then derived from them, or ``None`` for a
        language too large to enumerate.
    class_certificate
        Class engine: the worst case of every class recomputed from the gains ``K``
        (:class:`eqrec.design.classes.ClassCertificate`).
    """

    method: str
    system: AffineSystem
    patterns: tuple[ArrivalPattern, ...]
    T: int
    M1: float
    mu2: float
    schedule: GainSchedule | None
    solution: LPSolution
    build_time: float
    certificate: "object | None" = None
    extra: dict = field(default_factory=dict)
    levels: dict[str, float] = field(default_factory=dict)
    class_gains: "object | None" = None
    class_certificate: "object | None" = None

    def __post_init__(self) -> None:
        self.patterns = tuple(as_pattern(p) for p in self.patterns)
        self.mu2 = float(self.mu2)

    @property
    def words(self) -> tuple[str, ...]:
        """Labels of the designed patterns (the 0/1 or delay words)."""
        return tuple(p.label for p in self.patterns)

    @property
    def solve_time(self) -> float:
        return self.solution.solve_time
