"""The objects the calls of the bad-input census need (tests/test_bad_input_census.py): a small plant, its designs,
estimators and filters, built once per module."""
from __future__ import annotations

from functools import cached_property
from pathlib import Path
from typing import Any

import numpy as np
import pytest

import eqrec
from eqrec.systems.noise import GaussianDesign, GaussianNoise, NoisySystem
from eqrec.simulate.loop import closed_loop
from eqrec.estimators.kalman import TimestampedKalman
from eqrec.interop.python_control import estimator_iosys, system_from_statespace
from eqrec.lmv.estimator import LMVEstimator
from eqrec.lmv.model import system_of
from eqrec.lmv.plant import Plant

NAN, INF = float("nan"), float("inf")
WORDS = ["1111", "1011", "1101"]  # a missing-data language the 2-state plant recovers from at mu1 = 1
DELAYS = ["0000", "1000", "0100"]  # delay words (a packet one step late)
AMBIGUOUS = ["0111", "1011"]  # 0/1 words: missing-data or delay words, a reading must be named


class Ctx:
    """The objects the calls need, built once (a small plant, its designs, estimators and filters)."""

    plant = eqrec.AffineSystem(A=[[1.0, 0.1], [0.0, 1.0]], B=[[0.005], [0.1]], C=[[1.0, 0.0]], E=0.1 * np.eye(2),
                               eta_w=0.1, eta_v=0.05)
    rng = np.random.default_rng(0)

    @staticmethod
    def sys(**change: Any) -> eqrec.AffineSystem:
        fields = dict(A=[[1.0, 0.1], [0.0, 1.0]], C=[[1.0, 0.0]], E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)
        return eqrec.AffineSystem(**{**fields, **change})

    @cached_property
    def design(self):
        return eqrec.design_prefix(self.plant, WORDS, 1.0)

    @cached_property
    def binary_file(self) -> Path:
        (self.tmp / "binary.yaml").write_bytes(bytes(range(256)))
        return self.tmp / "binary.yaml"

    est = property(lambda self: self.design.estimator().reset([0.0, 0.0]))
    tree_est = property(lambda self: self.prefix(engine="tree").estimator().reset([0.0, 0.0]))
    delta = property(lambda self: np.zeros(4 * (self.plant.nw + self.plant.nv) + self.plant.n))
    gauss = cached_property(lambda self: GaussianDesign.from_box(self.plant, 1.0))
    kalman = property(lambda self: TimestampedKalman(self.plant, self.gauss).reset([0.0, 0.0]))

    def prefix(self, words=WORDS, mu1: Any = 1.0, **kw: Any):
        return eqrec.design_prefix(self.plant, words, mu1, **kw)

    def delay(self, patterns=DELAYS, mu1: Any = 1.0, **kw: Any):
        return eqrec.design_delay(self.plant, patterns, mu1, **{"kind": "delay", **kw})

    def aug(self, **kw: Any):
        return eqrec.design_augmented(self.plant, WORDS, 2.0, **kw)

    def run(self, word="1111", delta=None, x0: Any = (0.0, 0.0), schedule: Any = "design", **kw: Any):
        schedule = self.design.schedule if schedule == "design" else schedule
        return eqrec.simulate_run(self.plant, schedule, word, self.delta if delta is None else delta, x0, **kw)

    def mc(self, words: Any = WORDS, mu1: Any = 1.0, runs: Any = 2, seed: Any = 0, **kw: Any):
        return eqrec.monte_carlo(self.plant, self.design.schedule, words, mu1, runs, seed, **kw)

    def loop(self, **change: Any):
        """``closed_loop`` on 3 steps, everything arriving on time, with ``change`` applied."""
        args = dict(arrive=[[0], [1], [2]], x0=np.zeros(2), xi0=np.zeros(2), w=np.zeros((3, 2)), v=np.zeros((3, 1)))
        args = {"system": self.plant, "est": self.design.estimator(), **args, **change}
        return closed_loop(args.pop("system"), args.pop("est"), **args)

    def lmv(self, **kw: Any) -> LMVEstimator:
        stable = eqrec.AffineSystem(A=[[0.9, 0.2], [0.0, 0.7]], C=[[1.0, 0.5]], E=[[0.0], [1.0]], eta_w=0.5, eta_v=0.2)
        plant = Plant.from_description(NoisySystem(stable, GaussianNoise.from_box(stable, mu1=1.0)))
        return LMVEstimator(system_of(plant, "zero-input", 0.8), **kw)

    @cached_property
    def ss(self):
        return pytest.importorskip("control").ss([[1.0, 0.1], [0.0, 1.0]], [[0.0], [0.1]], [[1.0, 0.0]], [[0.0]], 0.1)

    def iosys(self, design: Any, **kw: Any):
        pytest.importorskip("control")
        return estimator_iosys(design, **kw)

    def from_ss(self, ss: Any, **kw: Any):
        pytest.importorskip("control")
        return system_from_statespace(ss, **{"eta_w": 0.1, "eta_v": 0.1, **kw})
