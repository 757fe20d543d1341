"""The result of every design method: gains, levels, solver record and certificate."""

from __future__ import annotations

from dataclasses import dataclass, field

from eqrec.core.gains import GainSchedule
from eqrec.core.lp import LPSolution
from eqrec.core.systems import AffineSystem


@dataclass
class Design:
    """A solved and certified equalized-recovery design."""

    method: str
    system: AffineSystem
    words: tuple[str, ...]
    T: int
    M1: float
    mu2: float
    schedule: GainSchedule
    solution: LPSolution
    build_time: float
    certificate: "object | None" = None
    extra: dict = field(default_factory=dict)

    @property
    def solve_time(self) -> float:
        return self.solution.solve_time
