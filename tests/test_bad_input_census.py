"""Census of bad inputs (issue 24, sections 1 and 5): every bad input is an eqrec error naming the field.

Read as the list of bad inputs tried.  ``PYTHON`` holds calls of the public
API, each row ``(id, call, field, error)``: the call must raise ``error`` (a
subclass of :class:`eqrec.errors.EqrecError`, never a bare ``TypeError``,
``ValueError``, ``KeyError``, ``IndexError`` or ``AttributeError``) whose
``field`` is the one named, or whose message names it.  ``CLI`` holds
``eqrec design`` command lines, each row ``(id, system file, arguments, exit
code, text)``: the run must end with the documented exit code (1 malformed
input, 2 usage, 3 infeasible, 4 solver or certification failure), name the
file or field on stderr, print no traceback and leave no output file behind
(no row reaches exit 4: input alone does not make a solver fail).  The
objects the calls need are built in ``tests/census_context.py``.
"""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path
from typing import Any, Callable, NamedTuple

import numpy as np
import pytest

import eqrec
from census_context import AMBIGUOUS, DELAYS, INF, NAN, WORDS, Ctx
from eqrec.arrivals import draws as arrivals
from eqrec.arrivals.draws import ArrivalTrace
from eqrec.systems.noise import GaussianDesign
from eqrec.errors import EqrecError, InfeasibleDesign, InputError
from eqrec.estimators.kalman import TimestampedKalman
from eqrec.lmv.estimator import LMVEstimator


class Case(NamedTuple):
    id: str
    call: Callable[[Ctx], Any]
    field: str  # named by the error (its .field or its message)
    error: type = InputError


C = Case
PYTHON = [
    # ------------------------------------------------------------------ AffineSystem, load_system
    C("A-string", lambda c: c.sys(A="abc"), "A"),
    C("A-dict", lambda c: c.sys(A={"a": 1}), "A"),
    C("A-ragged", lambda c: c.sys(A=[[1.0, 0.1], [0.0]]), "A"),
    C("A-nan", lambda c: c.sys(A=[[NAN, 0.1], [0.0, 1.0]]), "A"),
    C("A-inf", lambda c: c.sys(A=[[INF, 0.1], [0.0, 1.0]]), "A"),
    C("A-not-square", lambda c: c.sys(A=[[1.0, 0.1, 0.0], [0.0, 1.0, 0.0]]), "A"),
    C("A-missing", lambda c: c.sys(A=None), "A"),
    C("C-wrong-columns", lambda c: c.sys(C=[[1.0, 0.0, 0.0]]), "C"),
    C("E-wrong-rows", lambda c: c.sys(E=np.eye(3)), "E"),
    C("V-wrong-rows", lambda c: c.sys(V=np.eye(2)), "V"),
    C("B-wrong-rows", lambda c: c.sys(B=[[1.0], [0.0], [0.0]]), "B"),
    C("f-wrong-length", lambda c: c.sys(f=[0.0, 0.0, 0.0]), "f"),
    C("eta_w-missing", lambda c: c.sys(eta_w=None), "eta_w"),
    C("eta_v-missing", lambda c: c.sys(eta_v=None), "eta_v"),
    C("eta_w-negative", lambda c: c.sys(eta_w=-0.1), "eta_w"),
    C("eta_w-nan", lambda c: c.sys(eta_w=NAN), "eta_w"),
    C("eta_v-inf", lambda c: c.sys(eta_v=INF), "eta_v"),
    C("eta_w-string", lambda c: c.sys(eta_w="0.1"), "eta_w"),
    C("eta_w-dict", lambda c: c.sys(eta_w={"w": 0.1}), "eta_w"),
    C("eta_w-per-channel-wrong-length", lambda c: c.sys(eta_w=[0.1, 0.2, 0.3]), "eta_w"),
    C("eta_w-per-channel-nan", lambda c: c.sys(eta_w=[0.1, NAN]), "eta_w"),
    C("eta_v-per-channel-negative", lambda c: c.sys(V=np.eye(1, 2), eta_v=[0.1, -0.2]), "eta_v"),
    C("dt-negative", lambda c: c.sys(dt=-0.1), "dt"),
    C("name-not-string", lambda c: c.sys(name=3), "name"),
    C("time-varying-lengths", lambda c: c.sys(A=np.stack([np.eye(2)] * 3), C=np.ones((4, 1, 2))), "C"),
    C("load-missing-file", lambda c: eqrec.load_system("/no/such/system.yaml"), "system.yaml"),
    C("load-not-a-path", lambda c: eqrec.load_system(42), "path"),
    C("load-binary-file", lambda c: eqrec.load_system(c.binary_file), "binary.yaml"),
    # ------------------------------------------------------------------ words and languages
    C("words-bad-letter", lambda c: eqrec.missing_words(["1021"]), "words"),
    C("words-empty", lambda c: eqrec.missing_words([]), "words"),
    C("words-empty-word", lambda c: eqrec.missing_words([""]), "words"),
    C("words-mixed-lengths", lambda c: eqrec.as_language(["1111", "101"], kind="missing"), "words"),
    C("words-none", lambda c: eqrec.missing_words(None), "words"),
    C("words-integers", lambda c: eqrec.missing_words([1011, 1101]), "words"),
    C("words-a-dict", lambda c: eqrec.missing_words({"1111": 1}), "words"),
    C("delays-bad-letter", lambda c: eqrec.delay_words(["12a0"]), "delays"),
    C("delays-over-max", lambda c: eqrec.delay_words(["2100"], max_delay=1), "delays"),
    C("delays-max-negative", lambda c: eqrec.delay_words(["0000"], max_delay=-1), "max_delay"),
    C("delays-max-string", lambda c: eqrec.delay_words(["0000"], max_delay="2"), "max_delay"),
    C("language-ambiguous", lambda c: eqrec.as_language(AMBIGUOUS), "kind"),
    C("language-unknown-kind", lambda c: eqrec.as_language(AMBIGUOUS, kind="lossy"), "kind"),
    C("language-ragged", lambda c: eqrec.as_language(["000", "0000"], kind="delay"), "words"),
    C("delay-word-empty", lambda c: eqrec.parse_delay_word(""), "delays"),
    C("delay-word-none", lambda c: eqrec.parse_delay_word(None), "delays"),
    C("full-language-T-zero", lambda c: eqrec.full_delay_language(0, 1), "T"),
    C("full-language-D-ten", lambda c: eqrec.full_delay_language(3, 10), "max_delay"),
    C("full-language-T-string", lambda c: eqrec.full_delay_language("3", 1), "T"),
    C("delay-classes-D-negative", lambda c: eqrec.delay_classes(max_delay=-1, horizon=3), "max_delay"),
    C("delay-classes-T-float", lambda c: eqrec.delay_classes(max_delay=1, horizon=2.5), "horizon"),
    # ------------------------------------------------------------------ designs
    C("design-system-string", lambda c: eqrec.design_prefix("plant.yaml", WORDS, 1.0), "system"),
    C("design-mu1-nan", lambda c: c.prefix(mu1=NAN), "mu1"),
    C("design-mu1-inf", lambda c: c.prefix(mu1=INF), "mu1"),
    C("design-mu1-negative", lambda c: c.prefix(mu1=-1.0), "mu1"),
    C("design-mu1-zero", lambda c: c.prefix(mu1=0), "mu1"),
    C("design-mu1-string", lambda c: c.prefix(mu1="one"), "mu1"),
    C("design-mu1-none", lambda c: c.prefix(mu1=None), "mu1"),
    C("design-solver-gurobi", lambda c: c.prefix(solver="gurobi"), "solver"),
    C("design-engine-unknown", lambda c: c.prefix(engine="magic"), "engine"),
    C("design-levels-unknown", lambda c: c.prefix(levels="all"), "levels"),
    C("design-form-unknown", lambda c: c.prefix(form="dense"), "form"),
    C("design-T-short", lambda c: c.prefix(T=2), "T"),
    C("design-T-string", lambda c: c.prefix(T="4"), "T"),
    C("design-words-bad-letter", lambda c: c.prefix(words=["1121"]), "words"),
    C("design-words-mixed", lambda c: c.prefix(words=["1111", "011"]), "words"),
    C("design-words-empty", lambda c: c.prefix(words=[]), "words"),
    C("design-weights-negative", lambda c: c.prefix(state_weights=[1, -1]), "state_weights"),
    C("design-weights-short", lambda c: c.prefix(state_weights=[1.0]), "state_weights"),
    C("design-weights-nan", lambda c: c.prefix(state_weights=[1, NAN]), "state_weights"),
    C("design-infeasible-mu1", lambda c: c.prefix(mu1=0.01), "mu1", InfeasibleDesign),
    C("design-certify-string", lambda c: c.prefix(certify="no"), "certify"),
    C("design-node-gains-string", lambda c: c.prefix(node_gains="no"), "node_gains"),
    C("design-fixed-length-string", lambda c: c.prefix(fixed_length="no"), "fixed_length"),
    C("time-engine-unknown", lambda c: eqrec.design_time_based(c.plant, WORDS, 1.0, engine="x"), "engine"),
    C("time-words-none", lambda c: eqrec.design_time_based(c.plant, None, 1.0), "words"),
    C("time-free-weights-3", lambda c: eqrec.design_time_based(c.plant, WORDS, "free", state_weights=[1, 1, 1]),
      "state_weights"),
    C("delay-ambiguous-words", lambda c: eqrec.design_delay(c.plant, AMBIGUOUS, 1.0), "kind"),
    C("delay-cost-unknown", lambda c: c.delay(cost="median"), "cost"),
    C("delay-bad-letter", lambda c: eqrec.design_delay(c.plant, ["0x00"], 1.0, kind="delay"), "patterns"),
    C("delay-solver-gurobi", lambda c: c.delay(solver="gurobi"), "solver"),
    C("delay-kind-unknown", lambda c: eqrec.design_delay(c.plant, DELAYS, 1.0, kind="late"), "kind"),
    C("delay-solver-options-string", lambda c: c.delay(solver_options="presolve=off"), "solver_options"),
    C("global-ambiguous-words", lambda c: eqrec.design_delay_global(c.plant, AMBIGUOUS), "kind"),
    C("global-rtol-negative", lambda c: eqrec.design_delay_global(c.plant, DELAYS, kind="delay", rtol=-1), "rtol"),
    C("global-engine-unknown", lambda c: eqrec.design_delay_global(c.plant, DELAYS, kind="delay", engine="x"),
      "engine"),
    C("global-node-gains-string", lambda c: eqrec.design_delay_global(c.plant, DELAYS, kind="delay", node_gains="x"),
      "node_gains"),
    C("augmented-L-shape", lambda c: c.aug(L=[[1, 2, 3]]), "L"),
    C("augmented-L-word", lambda c: c.aug(L="fixed"), "L"),
    C("augmented-poles-count", lambda c: c.aug(poles=[0.1]), "poles"),
    C("augmented-s0-nan", lambda c: c.aug(s0=[NAN, 0.0]), "s0"),
    C("augmented-mode-unknown", lambda c: c.aug(mode="x"), "mode"),
    C("augmented-mu1-free", lambda c: eqrec.design_augmented(c.plant, WORDS, "free"), "mu1"),
    C("augmented-ipopt-options-string", lambda c: c.aug(ipopt_options="tol=1e-9"), "ipopt_options"),
    C("min-level-ambiguous", lambda c: eqrec.min_recovery_level(c.plant, AMBIGUOUS), "kind"),
    C("min-level-solver", lambda c: eqrec.min_recovery_level(c.plant, WORDS, kind="missing", solver="x"), "solver"),
    C("min-level-language-int", lambda c: eqrec.min_recovery_level(c.plant, 42, kind="missing"), "words"),
    C("certify-mu1-nan", lambda c: eqrec.certify_schedule(c.plant, c.design.schedule, WORDS, NAN), "mu1"),
    C("certify-schedule-string", lambda c: eqrec.certify_schedule(c.plant, "gains", WORDS, 1.0), "schedule"),
    C("certify-word-not-designed", lambda c: eqrec.certify_schedule(c.plant, c.design.schedule, ["0000"], 1.0),
      "words"),
    # ------------------------------------------------------------------ the runtime estimator
    C("estimator-strict-string", lambda c: c.design.estimator(strict="yes"), "strict"),
    C("estimator-periodic-none", lambda c: c.design.estimator(periodic=None), "periodic"),
    C("reset-xhat0-nan", lambda c: c.design.estimator().reset([NAN, 0.0]), "xhat0"),
    C("reset-xhat0-length", lambda c: c.design.estimator().reset([0.0, 0.0, 0.0]), "xhat0"),
    C("reset-xhat0-string", lambda c: c.design.estimator().reset("00"), "xhat0"),
    C("reset-xhat0-none", lambda c: c.design.estimator().reset(None), "xhat0"),
    C("reset-t0-float", lambda c: c.design.estimator().reset([0.0, 0.0], t0=1.5), "t0"),
    C("step-before-reset", lambda c: c.design.estimator().step([0.0]), "reset"),
    C("step-y-nan", lambda c: c.est.step([NAN]), "y"),
    C("step-y-inf", lambda c: c.est.step(np.array([INF])), "y"),
    C("step-y-shape", lambda c: c.est.step([1.0, 2.0]), "y"),
    C("step-y-string", lambda c: c.est.step("1.0"), "y"),
    C("step-y-dict", lambda c: c.est.step({"y": 1.0}), "y"),
    C("step-u-inf", lambda c: c.est.step([0.0], u=[INF]), "u"),
    C("step-u-length", lambda c: c.est.step([0.0], u=[1.0, 2.0]), "u"),
    C("step-u-string", lambda c: c.est.step([0.0], u="1"), "u"),
    C("step-packet-future", lambda c: c.est.step(eqrec.Packet(5, [0.0])), "y"),
    C("step-stamp-float", lambda c: c.est.step([(0.5, [0.0])]), "y"),
    C("step-stamp-twice", lambda c: c.est.step([(0, [0.0]), (0, [1.0])]), "y"),
    C("step-outside-language", lambda c: [c.est.step(None) for _ in range(2)], "y"),
    C("step-outside-language-node-gains", lambda c: [c.tree_est.step(None) for _ in range(2)], "y"),
    C("estimator-gains-string", lambda c: eqrec.GuaranteedEstimator(c.plant, "K", float, 1.0).reset([0, 0]), "gains"),
    C("update-y-nan", lambda c: c.est.update([NAN]), "y"),
    # ------------------------------------------------------------------ simulation
    C("run-word-bad-letter", lambda c: c.run(word="1121"), "word"),
    C("run-delta-length", lambda c: c.run(delta=c.delta[:3]), "delta"),
    C("run-delta-nan", lambda c: c.run(delta=c.delta + NAN), "delta"),
    C("run-x0-inf", lambda c: c.run(x0=[INF, 0]), "x0"),
    C("run-x0-length", lambda c: c.run(x0=[0]), "x0"),
    C("run-inputs-shape", lambda c: c.run(inputs=np.zeros((2, 1))), "inputs"),
    C("run-schedule-none", lambda c: c.run(schedule=None), "schedule"),
    C("run-system-string", lambda c: eqrec.simulate_run("plant", c.design.schedule, "1111", c.delta, [0, 0]),
      "system"),
    C("run-periodic-string", lambda c: c.run(periodic="yes"), "periodic"),
    C("mc-kind-unknown", lambda c: c.mc(kind="gauss"), "kind"),
    C("mc-runs-negative", lambda c: c.mc(runs=-1), "runs"),
    C("mc-runs-string", lambda c: c.mc(runs="5"), "runs"),
    C("mc-mu1-nan", lambda c: c.mc(mu1=NAN), "mu1"),
    C("mc-seed-string", lambda c: c.mc(seed="seed"), "seed"),
    C("mc-words-empty", lambda c: c.mc(words=[]), "words"),
    C("mc-words-mixed", lambda c: c.mc(words=["1111", "111"]), "words"),
    C("mc-words-none", lambda c: c.mc(words=None), "words"),
    C("mc-x0-nan", lambda c: c.mc(x0=[NAN, 0]), "x0"),
    C("mc-system-string", lambda c: eqrec.monte_carlo("plant", c.design.schedule, WORDS, 1.0, 2, 0), "system"),
    C("loop-w-nan", lambda c: c.loop(w=np.full((3, 2), NAN)), "w"),
    C("loop-w-string", lambda c: c.loop(w="noise"), "w"),
    C("loop-v-shape", lambda c: c.loop(v=np.zeros((3, 2))), "v"),
    C("loop-x0-nan", lambda c: c.loop(x0=[NAN, 0.0]), "x0"),
    C("loop-x0-string", lambda c: c.loop(x0="zero"), "x0"),
    C("loop-arrive-future", lambda c: c.loop(arrive=[[1], [0], [2]]), "arrive"),
    C("loop-arrive-string", lambda c: c.loop(arrive="111"), "arrive"),
    C("loop-t0-float", lambda c: c.loop(t0=0.5), "t0"),
    # ------------------------------------------------------------------ python-control
    C("loop-est-string", lambda c: c.loop(est="kalman"), "est"),
    C("loop-system-none", lambda c: c.loop(system=None), "system"),
    C("ss-not-statespace", lambda c: c.from_ss("ss"), "ss"),
    C("ss-eta_w-nan", lambda c: c.from_ss(c.ss, eta_w=NAN), "eta_w"),
    C("ss-eta_v-negative", lambda c: c.from_ss(c.ss, eta_v=-1.0), "eta_v"),
    C("ss-E-shape", lambda c: c.from_ss(c.ss, E=[[1.0, 2.0, 3.0]]), "E"),
    C("ss-f-string", lambda c: c.from_ss(c.ss, f="zero"), "f"),
    C("iosys-design-string", lambda c: c.iosys("design"), "design"),
    C("iosys-strict-string", lambda c: c.iosys(c.design, strict="no"), "strict"),
    C("iosys-dt-negative", lambda c: c.iosys(c.design, dt=-1.0), "dt"),
    # ------------------------------------------------------------------ Kalman filters, LMV
    C("iosys-name-number", lambda c: c.iosys(c.design, name=3), "name"),
    C("gauss-mu1-nan", lambda c: GaussianDesign.from_box(c.plant, NAN), "mu1"),
    C("gauss-mu1-negative", lambda c: GaussianDesign.from_box(c.plant, -1.0), "mu1"),
    C("gauss-sigmas-zero", lambda c: GaussianDesign.from_box(c.plant, 1.0, sigmas=0), "sigmas"),
    C("kalman-design-string", lambda c: TimestampedKalman(c.plant, "design"), "design"),
    C("kalman-system-none", lambda c: TimestampedKalman(None, c.gauss), "system"),
    C("kalman-xhat0-nan", lambda c: c.kalman.reset([NAN, 0.0]), "xhat0"),
    C("kalman-y-nan", lambda c: c.kalman.step([NAN]), "y"),
    C("kalman-u-string", lambda c: c.kalman.step([0.0], u=["a"]), "u"),
    C("kalman-packet-future", lambda c: c.kalman.step(eqrec.Packet(9, [0.0])), "y"),
    C("kalman-inputs-nan", lambda c: TimestampedKalman(c.plant, c.gauss, np.full((3, 1), NAN)), "inputs"),
    C("kalman-inputs-width", lambda c: TimestampedKalman(c.plant, c.gauss, np.zeros((3, 2))), "inputs"),
    C("lmv-system-affine", lambda c: LMVEstimator(c.plant), "sys"),
    C("lmv-compensation-unknown", lambda c: c.lmv(compensation="mean"), "compensation"),
    C("lmv-result-string", lambda c: c.lmv(result="gains"), "result"),
    C("lmv-xhat0-nan", lambda c: c.lmv().reset([NAN, 0.0]), "xhat0"),
    C("lmv-y-nan", lambda c: c.lmv().reset().step([NAN]), "y"),
    C("lmv-u-string", lambda c: c.lmv().reset().step([0.0], u="x"), "u"),
    # ------------------------------------------------------------------ arrival samplers
    C("bernoulli-loss-over-1", lambda c: arrivals.bernoulli_trace(c.rng, 10, 1.5), "loss"),
    C("bernoulli-loss-negative", lambda c: arrivals.bernoulli_trace(c.rng, 10, -0.1), "loss"),
    C("bernoulli-loss-nan", lambda c: arrivals.bernoulli_trace(c.rng, 10, NAN), "loss"),
    C("bernoulli-steps-negative", lambda c: arrivals.bernoulli_trace(c.rng, -3, 0.1), "steps"),
    C("bernoulli-steps-float", lambda c: arrivals.bernoulli_trace(c.rng, 2.5, 0.1), "steps"),
    C("bernoulli-rng-string", lambda c: arrivals.bernoulli_trace("rng", 10, 0.1), "rng"),
    C("arrivals-p-over-1", lambda c: arrivals.bernoulli_arrivals(c.rng, 5, 2.0), "arrival"),
    C("arrivals-shape-negative", lambda c: arrivals.bernoulli_arrivals(c.rng, -2, 0.5), "shape"),
    C("delay-trace-sum-over-1", lambda c: arrivals.delay_trace(c.rng, 10, [0.5, 0.7]), "probabilities"),
    C("delay-trace-negative", lambda c: arrivals.delay_trace(c.rng, 10, [-0.1, 0.5]), "probabilities"),
    C("delay-trace-strings", lambda c: arrivals.delay_trace(c.rng, 10, ["a", "b"]), "probabilities"),
    C("draw-delays-D-zero", lambda c: arrivals.draw_delays(c.rng, 10, 0, 0.5), "max_delay"),
    C("draw-delays-p-over-1", lambda c: arrivals.draw_delays(c.rng, 10, 2, 1.2), "p_on_time"),
    C("gilbert-p-over-1", lambda c: arrivals.gilbert_elliott_trace(c.rng, 10, 1.5, 0.5), "p_good_to_bad"),
    C("gilbert-start-unknown", lambda c: arrivals.gilbert_elliott_trace(c.rng, 10, 0.1, 0.5, start="x"), "start"),
    C("uniform-empty-language", lambda c: arrivals.uniform_words(c.rng, []), "words"),
    C("uniform-language-none", lambda c: arrivals.uniform_words(c.rng, None), "words"),
    C("trace-fractional-delay", lambda c: ArrivalTrace(np.array([0.5, 1.0])), "delays"),
    C("trace-arrived-2d", lambda c: ArrivalTrace.from_arrived([[1, 0], [0, 1]]), "arrived"),
    C("trace-arrived-half", lambda c: ArrivalTrace.from_arrived([1, 0.5, 0]), "arrived"),
]

# ---------------------------------------------------------------------------------------------- the command line
ROOT = Path(__file__).resolve().parents[1]
#: A valid system file (2 states, no T: the word length is the horizon), changed key by key in the rows below.
BASE = {"A": "[[1.0, 0.1], [0.0, 1.0]]", "C": "[[1.0, 0.0]]", "E": "[[0.1, 0.0], [0.0, 0.1]]", "eta_w": "0.1",
        "eta_v": "0.05"}


def yaml_of(**change: "str | None") -> str:
    """The text of :data:`BASE` with ``change`` applied (``None`` removes a key)."""
    return "".join(f"{key}: {value}\n" for key, value in {**BASE, **change}.items() if value is not None)


class K(NamedTuple):
    id: str
    system: "str | bytes | None"  # the file's text (bytes: binary), None: no file
    args: str  # after "eqrec design system.yaml" ("{tmp}" is the test's folder); "--out" added if not given
    code: int  # the exit status
    text: str  # in stderr


GOOD = yaml_of()
W = "--words 1111,1011,1101"
F = "system.yaml: field"
CLI = [
    # ------------------------------------------------------------------ system files (exit 1, file and field named)
    K("sys-missing-A", yaml_of(A=None), W, 1, f"{F} 'A'"),
    K("sys-missing-eta_v", yaml_of(eta_v=None), W, 1, f"{F} 'eta_v'"),
    K("sys-A-non-numeric", yaml_of(A="[[a, 0.1], [0.0, 1.0]]"), W, 1, f"{F} 'A'"),
    K("sys-A-nan", yaml_of(A="[[.nan, 0.1], [0.0, 1.0]]"), W, 1, f"{F} 'A'"),
    K("sys-eta_w-inf", yaml_of(eta_w=".inf"), W, 1, f"{F} 'eta_w'"),
    K("sys-eta_w-negative", yaml_of(eta_w="-0.1"), W, 1, f"{F} 'eta_w'"),
    K("sys-eta_v-quoted", yaml_of(eta_v='"0.05"'), W, 1, f"{F} 'eta_v'"),
    K("sys-eta_w-per-channel-length", yaml_of(eta_w="[1, 0.5, 2]"), W, 1, f"{F} 'eta_w'"),
    K("sys-eta_v-per-channel-nested", yaml_of(eta_v="[[0.05]]"), W, 1, f"{F} 'eta_v'"),
    K("sys-eta_w-per-channel-nan", yaml_of(eta_w="[0.1, .nan]"), W, 1, f"{F} 'eta_w'"),
    K("sys-C-wrong-shape", yaml_of(C="[[1.0, 0.0, 0.0]]"), W, 1, f"{F} 'C'"),
    K("sys-E-wrong-rows", yaml_of(E="[[0.1], [0.0], [0.0]]"), W, 1, f"{F} 'E'"),
    K("sys-A-ragged", yaml_of(A="[[1.0, 0.1], [0.0]]"), W, 1, f"{F} 'A'"),
    K("sys-f-length", yaml_of(f="[0, 0, 0]"), W, 1, f"{F} 'f'"),
    K("sys-B-string", yaml_of(B="two"), W, 1, f"{F} 'B'"),
    K("sys-T-zero", yaml_of(T="0"), W, 1, f"{F} 'T'"),
    K("sys-T-not-word-length", yaml_of(T="5"), W, 1, f"{F} 'T'"),
    K("sys-unknown-key", yaml_of(Q="1"), W, 1, "system.yaml: unknown field(s) ['Q']"),
    K("sys-not-a-mapping", "- 1\n- 2\n", W, 1, "system.yaml: top level must be a mapping"),
    K("sys-empty-file", "", W, 1, "system.yaml: top level must be a mapping"),
    K("sys-invalid-yaml", "A: [[1, 0]\n", W, 1, "system.yaml: not valid YAML"),
    K("sys-binary-file", bytes(range(256)), W, 1, "system.yaml"),
    K("sys-missing-file", None, W, 1, "system.yaml: file not found"),
    # ------------------------------------------------------------------ words, delays, methods (exit 1)
    K("words-bad-letter", GOOD, "--words 1021", 1, "field '--words'"),
    K("words-mixed-lengths", GOOD, "--words 1111,101", 1, "field '--words'"),
    K("words-none-given", GOOD, "--words ,,", 1, "field '--words'"),
    K("words-missing", GOOD, "--method time", 1, "field '--words'"),
    K("words-for-delay-method", GOOD, "--method delay --words 1111", 1, "field '--words'"),
    K("delays-bad-letter", GOOD, "--method delay --delays 2x10", 1, "field '--delays'"),
    K("delays-mixed-lengths", GOOD, "--method delay --delays 0000,000", 1, "field '--delays'"),
    K("delays-for-prefix-method", GOOD, f"{W} --delays 0000", 1, "field '--delays'"),
    K("max-delay-ten", GOOD, "--method delay --max-delay 10 --horizon 3", 1, "field '--max-delay'"),
    K("horizon-zero", GOOD, "--method delay --max-delay 1 --horizon 0", 1, "field '--horizon'"),
    K("horizon-alone", GOOD, "--method delay --horizon 3", 1, "field '--max-delay'"),
    K("mu1-nan", GOOD, f"{W} --mu1 nan", 1, "field '--mu1'"),
    K("mu1-negative", GOOD, f"{W} --mu1 -1", 1, "field '--mu1'"),
    K("mu1-text", GOOD, f"{W} --mu1 one", 1, "field '--mu1'"),
    K("mu1-free-augmented", GOOD, f"{W} --method augmented --mu1 free", 1, "field '--mu1'"),
    K("weights-length", GOOD, f"{W} --state-weights 1,2,3", 1, "field '--state-weights'"),
    K("weights-negative", GOOD, f"{W} --state-weights 1,-1", 1, "field '--state-weights'"),
    K("weights-nan", GOOD, f"{W} --state-weights 1,nan", 1, "field '--state-weights'"),
    K("weights-text", GOOD, f"{W} --state-weights a,b", 1, "field '--state-weights'"),
    K("weights-augmented", GOOD, f"{W} --method augmented --state-weights 1,1", 1, "field '--state-weights'"),
    K("L-not-json", GOOD, f"{W} --method augmented --L [[1,", 1, "field '--L'"),
    K("L-wrong-shape", GOOD, f"{W} --method augmented --L [[1,2,3]]", 1, "L must be an n x p"),
    K("poles-text", GOOD, f"{W} --method augmented --poles a,b", 1, "field '--poles'"),
    K("s0-nan", GOOD, f"{W} --method augmented --s0 [NaN,0]", 1, "field 's0'"),
    K("engine-for-time", GOOD, f"{W} --method time --engine tree", 1, "field '--engine'"),
    K("cost-for-prefix", GOOD, f"{W} --cost max", 1, "field '--cost'"),
    K("out-missing-folder", GOOD, f"{W} --out {{tmp}}/missing/d.json", 1, "field '--out'"),
    K("out-is-a-folder", GOOD, f"{W} --out {{tmp}}/out", 1, "field '--out'"),
    # ------------------------------------------------------------------ usage errors (exit 2, argparse)
    K("solver-gurobi", GOOD, f"{W} --solver gurobi", 2, "--solver"),
    K("method-unknown", GOOD, f"{W} --method kalman", 2, "--method"),
    K("engine-unknown", GOOD, f"{W} --engine magic", 2, "--engine"),
    K("horizon-text", GOOD, "--method delay --max-delay 1 --horizon three", 2, "--horizon"),
    K("option-unknown", GOOD, f"{W} --loss 0.1", 2, "--loss"),
    # ------------------------------------------------------------------ infeasible designs (exit 3, nothing written)
    K("infeasible-prefix", GOOD, f"{W} --mu1 0.01", 3, "mu1"),
    K("infeasible-time", GOOD, f"{W} --method time --mu1 0.01", 3, "mu1"),
    K("infeasible-delay", GOOD, "--method delay --delays 0000,1000,0100 --mu1 0.01", 3, "mu1"),
    K("infeasible-any-mu1", "A: [[2.0]]\nC: [[1.0]]\nE: [[0.0]]\neta_w: 0.0\neta_v: 0.1\n",
      "--method delay --delays 333 --mu1 free", 3, "terminal class"),
]
ENV = {**os.environ, "PYTHONPATH": str(ROOT / "src")}  # this tree's eqrec, whatever is installed


@pytest.fixture(scope="module")
def ctx(tmp_path_factory) -> Ctx:
    c = Ctx()
    c.tmp = tmp_path_factory.mktemp("census")
    return c


def test_the_census_is_large_and_its_ids_unique():
    assert len(PYTHON) >= 60 and len(CLI) >= 30
    for table in (PYTHON, CLI):
        ids = [row.id for row in table]
        assert len(set(ids)) == len(ids)


@pytest.mark.parametrize("case", PYTHON, ids=[case.id for case in PYTHON])
def test_python_bad_input_is_an_eqrec_error_naming_the_field(ctx, case):
    try:
        case.call(ctx)
    except Exception as exc:  # noqa: BLE001 - the census looks at whatever is raised
        assert isinstance(exc, EqrecError), f"raw {type(exc).__name__}: {exc}"
        assert isinstance(exc, case.error), f"{type(exc).__name__}: {exc}"
        assert getattr(exc, "field", None) == case.field or case.field in str(exc), str(exc)
    else:
        pytest.fail(f"{case.id}: accepted")


@pytest.mark.parametrize("case", CLI, ids=[case.id for case in CLI])
def test_cli_bad_input_exit_code_message_no_traceback_no_file(tmp_path, case):
    system = tmp_path / "system.yaml"
    if isinstance(case.system, bytes):
        system.write_bytes(case.system)
    elif case.system is not None:
        system.write_text(case.system)
    out_dir = tmp_path / "out"
    out_dir.mkdir()
    args = case.args.replace("{tmp}", str(tmp_path)).split()
    if "--out" not in args:
        args += ["--out", str(out_dir / "design.json")]
    run = subprocess.run([sys.executable, "-m", "eqrec", "design", str(system), *args], capture_output=True,
                         text=True, env=ENV, timeout=300)
    assert "Traceback" not in run.stderr, run.stderr
    assert run.returncode == case.code, run.stderr
    assert case.text in run.stderr, run.stderr
    assert not list(out_dir.iterdir()) and not (tmp_path / "missing").exists()  # no output, no partial file
