"""The loggers of the study steps and the progress lines of long sweeps.

A step logs through ``get_logger(study)``; the harness
(:mod:`eqrec.studies.pipeline.harness`) prints the records as ``[study] message`` in
the rule's log file.
"""

from __future__ import annotations

import logging
import time


def get_logger(study: str) -> logging.Logger:
    """The logger of a study's steps; the harness prints its records as ``[study] message``."""
    return logging.getLogger(f"eqrec.studies.{study}")


class Progress:
    """Progress lines for a long sweep: ``[p2] heat map theorem2 chunk 0: 31/124 points (2.1 s)``.

    Logs at every tenth of the work (and at the end).
    """

    def __init__(self, log: logging.Logger, total: int, what: str, unit: str = "points"):
        self.log, self.total, self.what, self.unit = log, max(int(total), 0), what, unit
        self.done, self.t0 = 0, time.perf_counter()
        self._next = 1 if self.total else 0
        self._stride = max(1, self.total // 10)

    def advance(self, n: int = 1) -> None:
        """Count ``n`` more units of work; log a line at every tenth."""
        self.done += n
        if self.done >= self._next or self.done >= self.total:
            self._next = self.done + self._stride
            self.log.info("%s: %d/%d %s (%.1f s)", self.what, self.done, self.total, self.unit,
                          time.perf_counter() - self.t0)
