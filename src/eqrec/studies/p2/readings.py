"""P2 readings: the ways of reading the augmented paper's text that the P2 study compares.

* ``theorem2`` — the text of Theorem 2 (word positions are 0-based times);
* ``one_based`` — the word's missing positions taken as 1-based time indices
  (the Fig. 2 caption says missing ``k = 2, 3`` for ``100111``);
* ``leak`` — constant ``L`` kept at the missing steps with the missing
  measurement inside ``s`` (a design-only reading);
* ``masked_gain`` — the Appendix's matrices with ``Φ = A − LC`` at every
  step and the measurement gain zeroed at missing steps (design-only).
"""

from __future__ import annotations

import numpy as np

from eqrec.bounds.gains import GainSchedule, schedule_from_word_gains
from eqrec.arrivals.prefix_tree import PrefixTree
from eqrec.arrivals.words import as_pattern
from eqrec.errors import InputError

#: Heat-map / projection variants: name -> (mode of the augmented model, word reading)
VARIANTS = {"theorem2": ("theorem2", "zero_based"), "one_based": ("theorem2", "one_based"),
            "leak": ("leak", "zero_based"), "masked_gain": ("masked_gain", "zero_based")}


def one_based_word(word: str) -> str:
    """The word's missing positions taken as 1-based time indices.

    ``100111`` misses ``k = 1, 2`` (0-based); the Fig. 2 caption says
    ``k = 2 and 3``. Read 1-based, the missing steps become ``k = 2, 3``:
    ``110011``. A missing position shifted past the horizon is dropped.
    The 0/1 word is shifted one step later, its first step measured.
    """
    return ("1" + word)[:len(word)]


def variant_word(word: str, variant: str) -> tuple[str, str]:
    """``(mode, word)`` used by a heat-map variant."""
    if variant not in VARIANTS:
        raise InputError(f"unknown variant {variant!r}; choose from {list(VARIANTS)}", field="variants")
    mode, reading = VARIANTS[variant]
    return mode, (one_based_word(word) if reading == "one_based" else word)


def heatmap_poles(r: float, theta: float) -> np.ndarray:
    """Fig. 3a: one eigenvalue at 0 and a pair at ``r e^{±jθ}``."""
    lam = r * np.exp(1j * theta)
    if abs(lam.imag) <= 1e-12 * max(r, 1.0):  # θ = 0 or π: a real double eigenvalue, not a rounding-error pair
        lam = complex(lam.real, 0.0)
    return np.array([0.0, lam, np.conj(lam)])


def retarget(schedule: GainSchedule, designed: str, actual: str) -> GainSchedule:
    """Run a time-based schedule designed for word ``designed`` on data following ``actual``.

    The gains on measurements that ``actual`` lacks multiply ``ỹ = 0``: zero
    those columns (what the running estimator really does).
    """
    F, u0 = schedule.word_matrices(designed)
    lacks = np.repeat(~as_pattern(actual).mask.diagonal(), schedule.p)  # the measurements ``actual`` lacks
    return schedule_from_word_gains(PrefixTree([actual]), {actual: (np.where(lacks, 0.0, F), u0)}, schedule.n,
                                    schedule.p, time_based=True)
