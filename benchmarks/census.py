"""Census of bad inputs over the public API (issue 41, "Done when"): Python (``eqrec.__all__``) and the CLI.

Every case is a bad input, run in a process of its own (forked from one that built the shared objects: a small
plant, its designs and estimators, genuine design files) with a wall-clock limit of 5 s.  Its outcome is one of

* **clear**   - a documented error (:class:`eqrec.errors.EqrecError` and its subclasses) whose ``field`` is the one
  named, or whose message names it; from the CLI: the documented exit code (1 malformed input, 2 usage, 3
  infeasible) and the field in stderr, no traceback, no output file;
* **raw**     - any other exception, or a traceback, or an eqrec error that does not name the field, or another exit
  code;
* **silent**  - accepted: the call returned (a result of a bad input: NaN/inf, a wrong result, a file that lies),
  or a refused ``step`` left the estimator different from a twin that never saw the call;
* **hang**    - no answer within 5 s (a huge size must be estimated and refused within that time).

A few cases are *accept* cases: a call that must succeed with a checked answer (the information limit's cache
against a fresh computation, ``state_bounds`` under ``strict=True``, a stale packet dropped and counted); they
are clear when the answer is right, silent otherwise.

Run::

    python benchmarks/census.py            # every case, the table per category, Python and CLI
    python benchmarks/census.py --subprocess-cli   # the CLI cases as real `python -m eqrec` processes, under
                                                   # `timeout` (5 s plus the measured start-up of the interpreter)
    python benchmarks/census.py -k zono    # the cases whose id contains "zono"

The CLI cases run ``eqrec.cli.main(argv)`` in the forked process by default (what ``python -m eqrec`` runs, without
the 2-3 s start-up of a fresh interpreter on this machine), with stdout and stderr captured.
``tests/test_census.py`` runs a fast subset under pytest.
"""
from __future__ import annotations

import argparse
import contextlib
import copy
import io
import json
import math
import os
import pickle
import signal
import subprocess
import sys
import time
import traceback
from dataclasses import dataclass, field as dc_field
from pathlib import Path
from typing import Any, Callable

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))  # census_context: the shared plant and designs of the issue-24 census

import eqrec  # noqa: E402
from eqrec.errors import EqrecError  # noqa: E402

LIMIT = 5.0  # seconds per case
NAN, INF = float("nan"), float("inf")
ACC = ROOT / "examples" / "acc_system.yaml"
REACTOR = ROOT / "examples" / "batch_reactor.yaml"
L1 = "101111,110111,111011,111101"


# ============================================================================================ the cases
@dataclass
class Py:
    """A Python case: ``call(ctx)`` must raise an eqrec error naming ``field`` (or, with ``accept``, return a
    result that ``accept(ctx, result)`` finds right: it returns None, or what is wrong)."""
    id: str
    call: Callable[["Ctx"], Any]
    field: str
    accept: "Callable[[Any, Any], str | None] | None" = None
    group: str = "python"


@dataclass
class Cli:
    """A CLI case: ``eqrec <args>`` (``{sys}`` the system file written from ``system``, ``{tmp}`` the case's folder)
    must exit with ``code`` and name ``text`` on stderr, with no traceback and no output file."""
    id: str
    args: str
    code: int
    text: str
    system: "str | None" = None  # the system file's text (None: a 2-state plant without T, _yaml())
    group: str = "cli"


class Ctx:
    """The shared objects (built once in the parent, before the cases fork)."""

    def __init__(self, tmp: Path):
        from census_context import Ctx as Base
        self.tmp = tmp
        self.base = Base()
        self.base.tmp = tmp
        self.plant = self.base.plant
        self.design = self.base.design
        self.tree_design = self.base.prefix(engine="tree")
        self.acc = eqrec.acc_system()
        self.reactor = eqrec.load_system(REACTOR)[0]
        self.delay_design = eqrec.design_delay(self.reactor, eqrec.delay_classes(max_delay=1, horizon=4), 2.0)
        self.gauss = self.base.gauss
        self.binary_file = self.base.binary_file
        self.files = {}
        from eqrec.cli import main
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            for name, args in (("tree", f"{ACC} --words {L1} --engine tree"), ("classes", f"{ACC} --words {L1}"),
                               ("delay", f"{REACTOR} --method delay --max-delay 1 --horizon 4 --mu1 2 --engine tree"),
                               ("time", f"{ACC} --words {L1} --method time")):
                path = tmp / f"{name}.json"
                assert main(["design", *args.split(), "--out", str(path)]) == 0, name
                self.files[name] = json.loads(path.read_text())
        self.tv = eqrec.AffineSystem(A=[np.array([[0.9, 0.1], [0.0, 0.8]]) * (1.0 + 0.01 * t) for t in range(6)], C=[[[1.0, 0.0]]] * 6,
                                     E=[0.1 * np.eye(2)] * 6, eta_w=0.1, eta_v=0.05, name="tv")
        from eqrec.arrivals.draws import ArrivalTrace
        self.trace = ArrivalTrace([0, 1, -1, 0, 2, 0, 0, -1, 1, 0])
        self.data = np.random.default_rng(0).normal(size=(10, self.acc.p)) * 0.01
        self.tv_design = eqrec.design_prefix(self.tv, ["111111", "101111", "110111"], 2.0)
        with contextlib.redirect_stderr(io.StringIO()):
            for kind in ("guaranteed", "tree", "loose", "zonotope", "exactset", "classest", "kalman"):
                self.est(kind)  # compiled and cached once here, not in every forked case
            eqrec.ZonotopeEstimator(self.acc, x0_radius=0.5, max_delay=1).reset(np.zeros(3)).step([0.0, 0.0])
            eqrec.ZonotopeEstimator(self.tv, x0_radius=0.5).reset(np.zeros(2)).step([0.0])
            eqrec.information_limit(self.acc, self.trace, 0.5)

    # ---------------------------------------------------------------------------- builders
    def est(self, kind: str):
        """A fresh estimator of ``kind``, reset, after two valid steps."""
        p = self.plant
        if kind == "guaranteed":
            e = self.design.estimator().reset([0.0, 0.0])
        elif kind == "tree":
            e = self.tree_design.estimator().reset([0.0, 0.0])
        elif kind == "loose":
            e = self.design.estimator(strict=False).reset([0.0, 0.0])
        elif kind == "zonotope":
            e = eqrec.ZonotopeEstimator(p, x0_radius=0.5, max_delay=2).reset([0.0, 0.0])
        elif kind == "exactset":
            e = eqrec.ExactSetEstimator(p, x0_radius=0.5, max_delay=1).reset([0.0, 0.0])
        elif kind == "classest":
            e = eqrec.ClassEstimator(p, self.design.class_gains, periodic=True).reset([0.0, 0.0])
        elif kind == "kalman":
            from eqrec.estimators.kalman import TimestampedKalman
            e = eqrec.exact_bound(TimestampedKalman(p, self.gauss), p, 0.5, steps=20).reset([0.0, 0.0])
        else:
            raise KeyError(kind)
        e.step([0.01])
        e.step([(1, [0.02])])
        return e

    def save(self, name: str, edit: Callable[[dict], Any]) -> Path:
        data = copy.deepcopy(self.files[name])
        edit(data)
        path = self.tmp / "edited.json"
        path.write_text(json.dumps(data))
        return path

    def edited(self, name: str, edit: Callable[[dict], Any]):
        return eqrec.load_design(self.save(name, edit))


def _set(*path, value):
    def edit(d):
        *keys, last = path
        for k in keys:
            d = d[k]
        if value is _DEL:
            del d[last]
        else:
            d[last] = value
    return edit


_DEL = object()


def _gains(d, f):
    for g in d["gains"].values():
        g["F"] = f(np.asarray(g["F"])).tolist()


def _first_gain(d):
    return next(iter(d["gains"].values()))


def _step_cases() -> list[Py]:
    """Refused ``step`` calls on every estimator kind: each must raise, and leave the estimator bit-identical to a
    twin that never saw the call (both then run the same valid steps; estimates and bounds compared exactly)."""
    bad = {
        "y-nan": lambda: ([NAN], None, "y"),
        "y-inf": lambda: ([INF], None, "y"),
        "y-overflow": lambda: ([1e308], None, "y"),
        "y-shape": lambda: ([1.0, 2.0], None, "y"),
        "y-string": lambda: ("1.0", None, "y"),
        "u-nan": lambda: ([0.0], [NAN], "u"),
        "u-shape": lambda: ([0.0], [1.0, 2.0], "u"),
        "packet-future": lambda: (eqrec.Packet(50, [0.0]), None, "y"),
        "stamp-twice": lambda: ([(2, [0.0]), (2, [1.0])], None, "y"),
        "stamp-float": lambda: ([(2.5, [0.0])], None, "y"),
        "packet-y-nan": lambda: ([(2, [NAN]), (1, [0.0])], None, "y"),
    }
    kinds = ["guaranteed", "tree", "loose", "zonotope", "exactset", "classest", "kalman"]
    skip = {("kalman", "u-nan"), ("kalman", "u-shape"), ("classest", "u-nan")}  # the plant has an input: kept
    skip = set()
    cases = []
    for kind in kinds:
        for name, make in bad.items():
            if (kind, name) in skip:
                continue

            def call(c, kind=kind, make=make):
                y, u, _ = make()
                est, twin = c.est(kind), c.est(kind)
                try:
                    est.step(y, u=u) if u is not None else est.step(y)
                except EqrecError as exc:
                    for k in range(3):
                        a, b = est.step([0.01 * k]), twin.step([0.01 * k])
                        if not (np.array_equal(a[0], b[0]) and np.array_equal(a[1], b[1])):
                            raise AtomicityBroken(f"after the refusal, step {k}: {a} != twin {b}") from exc
                    raise
                return "accepted"
            cases.append(Py(f"step-{kind}-{name}", call, make()[2], group="python-step"))
    return cases


class AtomicityBroken(Exception):
    """A refused step changed the estimator (silent)."""


def _accept_finite(c, result) -> "str | None":
    return None


def _cache_check(c, result):
    fresh, cached = result
    # the same LPs solved warm or cold: equal to rounding (the wrong trace's rows differ by ~50 %)
    same = np.allclose(fresh, cached, rtol=1e-9, atol=1e-12)
    return None if same else f"cached rows differ: {cached[-1]} vs fresh {fresh[-1]}"


def _info_cache(c):
    from eqrec.arrivals.draws import ArrivalTrace
    a = ArrivalTrace([0, 0, 0, 0, 0, 0])
    b = ArrivalTrace([0, 2**62, 2**62, 2**62, 0, 0])  # three packets arrive past the run's end
    eqrec.information_limit(c.acc, a, 0.5)
    cached = eqrec.information_limit(c.acc, b, 0.5)
    fresh = eqrec.information_limit(c.acc, b, 0.5, cache=False)
    return fresh, cached


def _tv_period_time(c):
    """A design on a time-varying plant reads its matrices at the period's time: a negative t0 is no wrap-around
    (the same run as from t0 = 0)."""
    a = c.tv_design.estimator().reset([1.0, 1.0], t0=-3)
    b = c.tv_design.estimator().reset([1.0, 1.0], t0=0)
    return [a.step([(k - 3, [0.1 * k])]) for k in range(6)], [b.step([(k, [0.1 * k])]) for k in range(6)]


def _same_runs(c, result):
    a, b = result
    same = all(np.array_equal(x[0], y[0]) and x[1] == y[1] for x, y in zip(a, b))
    return None if same else "t0 = -3 and t0 = 0 differ"


def _state_bounds(c):
    est = c.design.estimator(strict=True).reset([0.0, 0.0])
    est.step([0.0])
    return est, est.state_bounds


def _state_bounds_check(c, result):
    est, sb = result
    sb = np.asarray(sb() if callable(sb) else sb, dtype=float)
    if sb.shape != (2,) or not np.all(np.isfinite(sb)):
        return f"state_bounds {sb}"
    return None


def _stale_packet(c):
    est = eqrec.ZonotopeEstimator(c.plant, x0_radius=0.5, max_delay=2).reset([0.0, 0.0])
    twin = eqrec.ZonotopeEstimator(c.plant, x0_radius=0.5, max_delay=2).reset([0.0, 0.0])
    a = est.step([(-1, [50.0])])
    b = twin.step(None)
    return est, a, b


def _stale_check(c, result):
    est, a, b = result
    if est.dropped_packets != 1 or not np.array_equal(a[0], b[0]) or a[1] != b[1]:
        return f"stale packet used: dropped={est.dropped_packets}"
    return None


def _reset_overflow(kind):
    def call(c):
        e = c.est(kind).reset(np.full(2, 1e308))
        return e.step([0.0])
    return call


def _python_cases() -> list[Py]:
    from eqrec.arrivals.draws import ArrivalTrace
    P = Py
    ac = eqrec.acc_system
    cases = [
        # ------------------------------------------------------------------ design files (tree: node gains)
        P("file-tree-A-edited", lambda c: c.edited("tree", lambda d: d["system"]["A"][0].__setitem__(0, 1.2)), "mu2"),
        P("file-tree-F-x1.3", lambda c: c.edited("tree", lambda d: _gains(d, lambda F: 1.3 * F)), "mu2"),
        P("file-tree-F-x0", lambda c: c.edited("tree", lambda d: _gains(d, lambda F: 0 * F)), ("mu1", "mu2")),
        P("file-tree-mu2-0.6", lambda c: c.edited("tree", _set("mu2", value=0.6)), "mu2"),
        P("file-tree-mu2-nan", lambda c: c.edited("tree", _set("mu2", value=NAN)), "mu2"),
        P("file-tree-mu2-string", lambda c: c.edited("tree", _set("mu2", value="0.6")), "mu2"),
        P("file-tree-mu2-missing", lambda c: c.edited("tree", _set("mu2", value=_DEL)), "mu2"),
        P("file-tree-mu1-nan", lambda c: c.edited("tree", _set("mu1", value=NAN)), "mu1"),
        P("file-tree-mu1-0.1", lambda c: c.edited("tree", _set("mu1", value=0.1)), "mu1"),
        P("file-tree-mu1-negative", lambda c: c.edited("tree", _set("mu1", value=-1.0)), "mu1"),
        P("file-tree-certified-nan", lambda c: c.edited("tree", _set("certified_mu2", value=NAN)), "certified_mu2"),
        P("file-tree-gain-nan", lambda c: c.edited("tree", lambda d: _first_gain(d)["F"][0].__setitem__(0, NAN)),
          "gains"),
        P("file-tree-gain-shape", lambda c: c.edited("tree", lambda d: _first_gain(d).__setitem__("F", [[1.0]])),
          "gains"),
        P("file-tree-u0-missing", lambda c: c.edited("tree", lambda d: _first_gain(d).pop("u0")), "u0"),
        P("file-tree-u0-edited", lambda c: c.edited("tree", lambda d: _first_gain(d).__setitem__(
            "u0", (np.asarray(_first_gain(d)["u0"]) + 1.0).tolist())), ("u0", "mu1", "mu2")),
        P("file-tree-gains-missing", lambda c: c.edited("tree", _set("gains", value=_DEL)), "gains"),
        P("file-tree-gains-list", lambda c: c.edited("tree", _set("gains", value=[1, 2])), "gains"),
        P("file-tree-V-half", lambda c: c.edited("tree", lambda d: d["system"].__setitem__(
            "V", (0.5 * np.eye(2)).tolist())), "mu2"),
        P("file-tree-V-triple", lambda c: c.edited("tree", lambda d: d["system"].__setitem__(
            "V", (3 * np.eye(2)).tolist())), "mu2"),
        P("file-tree-eta_w-doubled", lambda c: c.edited("tree", lambda d: d["system"].__setitem__("eta_w", 0.2)),
          "mu2"),
        P("file-tree-eta_v-nan", lambda c: c.edited("tree", lambda d: d["system"].__setitem__("eta_v", NAN)),
          "eta_v"),
        P("file-tree-E-x2", lambda c: c.edited("tree", lambda d: d["system"].__setitem__(
            "E", (2 * np.asarray(d["system"]["E"])).tolist())), "mu2"),
        P("file-tree-C-shape", lambda c: c.edited("tree", lambda d: d["system"].__setitem__("C", [[1.0]])), "C"),
        P("file-tree-system-missing", lambda c: c.edited("tree", _set("system", value=_DEL)), "system"),
        P("file-tree-method-unknown", lambda c: c.edited("tree", _set("method", value="magic")), "method"),
        P("file-tree-method-missing", lambda c: c.edited("tree", _set("method", value=_DEL)), "method"),
        P("file-tree-words-bad", lambda c: c.edited("tree", _set("words", value=["1x1111"])), "words"),
        P("file-tree-word-dropped", lambda c: c.edited("tree", lambda d: d["words"].pop()), "words"),
        P("file-tree-T-7", lambda c: c.edited("tree", _set("T", value=7)), "T"),
        P("file-tree-T-string", lambda c: c.edited("tree", _set("T", value="6")), "T"),
        P("file-time-F-x1.3", lambda c: c.edited("time", lambda d: _gains(d, lambda F: 1.3 * F)), ("mu1", "mu2")),
        P("file-time-mu2-0.1", lambda c: c.edited("time", _set("mu2", value=0.1)), "mu2"),
        # ------------------------------------------------------------------ design files (class designs)
        P("file-classes-K-nan", lambda c: c.edited("classes", lambda d: d["classes"][1]["K"][0].__setitem__(0, NAN)),
          "classes[1].K"),
        P("file-classes-K-x2", lambda c: c.edited("classes", lambda d: d["classes"][3].__setitem__(
            "K", (2 * np.asarray(d["classes"][3]["K"])).tolist())), "classes[3]"),
        P("file-classes-K-shape", lambda c: c.edited("classes", lambda d: d["classes"][3].__setitem__("K", [[1.0]])),
          "classes[3].K"),
        P("file-classes-certified-nan", lambda c: c.edited("classes", lambda d: d["classes"][1].__setitem__(
            "certified", NAN)), "classes[1].certified"),
        P("file-classes-level-0.5", lambda c: c.edited("classes", lambda d: d["classes"][1].__setitem__(
            "level", 0.5)), "classes[1].level"),
        P("file-classes-level-string", lambda c: c.edited("classes", lambda d: d["classes"][1].__setitem__(
            "level", "x")), "classes[1].level"),
        P("file-classes-mu2-0.6", lambda c: c.edited("classes", _set("mu2", value=0.6)), "mu2"),
        P("file-classes-mu2-9", lambda c: c.edited("classes", _set("mu2", value=9.0)), "mu2"),
        P("file-classes-mu1-2", lambda c: c.edited("classes", _set("mu1", value=2.0)), "classes"),
        P("file-classes-mu1-inf", lambda c: c.edited("classes", _set("mu1", value=INF)), "mu1"),
        P("file-classes-k-99", lambda c: c.edited("classes", lambda d: d["classes"][0].__setitem__("k", 99)),
          "classes[0].k"),
        P("file-classes-k-negative", lambda c: c.edited("classes", lambda d: d["classes"][2].__setitem__("k", -1)),
          "classes[2].k"),
        P("file-classes-k-string", lambda c: c.edited("classes", lambda d: d["classes"][2].__setitem__("k", "1")),
          "classes[2].k"),
        P("file-classes-k-missing", lambda c: c.edited("classes", lambda d: d["classes"][0].pop("k")),
          "classes[0].k"),
        P("file-classes-data-past-k", lambda c: c.edited("classes", lambda d: d["classes"][0].__setitem__(
            "data", [5])), "classes[0].data"),
        P("file-classes-data-string", lambda c: c.edited("classes", lambda d: d["classes"][2].__setitem__(
            "data", "abc")), "classes[2].data"),
        P("file-classes-data-dup", lambda c: c.edited("classes", lambda d: d["classes"][4].__setitem__(
            "data", [0, 0])), "classes[4]"),
        P("file-classes-terminal-string", lambda c: c.edited("classes", lambda d: d["classes"][0].__setitem__(
            "terminal", "yes")), "classes[0].terminal"),
        P("file-classes-T-5", lambda c: c.edited("classes", _set("T", value=5)), "classes"),
        P("file-classes-T-0", lambda c: c.edited("classes", _set("T", value=0)), "T"),
        P("file-classes-V-3", lambda c: c.edited("classes", lambda d: d["system"].__setitem__(
            "V", (3 * np.eye(2)).tolist())), "classes"),
        P("file-classes-weights-abc", lambda c: c.edited("classes", _set("state_weights", value="abc")),
          "state_weights"),
        P("file-classes-weights-zero", lambda c: c.edited("classes", _set("state_weights", value=[1, 0, 1])),
          "state_weights"),
        P("file-classes-weights-short", lambda c: c.edited("classes", _set("state_weights", value=[1, 2])),
          "state_weights"),
        P("file-classes-classes-dict", lambda c: c.edited("classes", _set("classes", value={"a": 1})), "classes"),
        P("file-classes-row-list", lambda c: c.edited("classes", lambda d: d["classes"].__setitem__(0, [1])),
          "classes[0]"),
        P("file-classes-row-dropped", lambda c: c.edited("classes", lambda d: d["classes"].pop(3)), "classes"),
        P("file-classes-J-string", lambda c: c.edited("classes", _set("J", value="abc")), "J"),
        # ------------------------------------------------------------------ design files (delay, node gains)
        P("file-delay-levels-k-missing", lambda c: c.edited("delay", lambda d: d["levels"][1].pop("k")),
          "levels[1].k"),
        P("file-delay-level-halved", lambda c: c.edited("delay", lambda d: d["levels"][2].__setitem__(
            "level", 1.0)), "levels"),
        P("file-delay-certified-edited", lambda c: c.edited("delay", lambda d: d["levels"][2].__setitem__(
            "certified", 1.0)), "levels"),
        P("file-delay-T-3", lambda c: c.edited("delay", _set("T", value=3)), "T"),
        P("file-delay-J-edited", lambda c: c.edited("delay", _set("J", value=0.1)), "J"),
        P("file-delay-F-x1.3", lambda c: c.edited("delay", lambda d: _gains(d, lambda F: 1.3 * F)), ("levels", "mu2")),
        P("file-delay-mu1-0.5", lambda c: c.edited("delay", _set("mu1", value=0.5)), ("mu1", "levels")),
        P("file-delay-levels-string", lambda c: c.edited("delay", _set("levels", value="abc")), "levels"),
        # ------------------------------------------------------------------ the file itself
        P("file-not-json", lambda c: (c.tmp / "x.json").write_text("{not json") and eqrec.load_design(
            c.tmp / "x.json"), "x.json"),
        P("file-empty", lambda c: (c.tmp / "e.json").write_text("") or eqrec.load_design(c.tmp / "e.json"),
          "e.json"),
        P("file-top-list", lambda c: (c.tmp / "l.json").write_text("[1, 2]") and eqrec.load_design(
            c.tmp / "l.json"), "l.json"),
        P("file-binary", lambda c: eqrec.load_design(c.binary_file), "binary.yaml"),
        P("file-missing", lambda c: eqrec.load_design(c.tmp / "none.json"), "none.json"),
        P("file-a-folder", lambda c: eqrec.load_design(c.tmp / "case0"), "case0"),
        P("file-path-int", lambda c: eqrec.load_design(3), "path"),
        P("file-nan-literal", lambda c: (c.tmp / "n.json").write_text(json.dumps(
            {**c.files["classes"], "mu2": NAN})) and eqrec.load_design(c.tmp / "n.json"), "mu2"),
        P("save-to-folder", lambda c: c.design.save(c.tmp), "path"),
        P("save-missing-parent", lambda c: c.design.save(c.tmp / "no" / "d.json"), "path"),
        P("save-path-int", lambda c: c.design.save(3), "path"),
        # ------------------------------------------------------------------ sizes that would hang
        P("size-global-4-800", lambda c: eqrec.design_delay_global(c.reactor, eqrec.delay_classes(
            max_delay=4, horizon=800)), "force"),
        P("size-delay-4-800", lambda c: eqrec.design_delay(c.reactor, eqrec.delay_classes(max_delay=4, horizon=800),
                                                           1.0), "force"),
        # (1, 100000) builds since delay_classes is linear in T without losses (3 s): 1e8 is the size refused
        P("size-classes-1-1e8", lambda c: eqrec.delay_classes(max_delay=1, horizon=10**8), "force"),
        P("size-classes-2-1e6-lost", lambda c: eqrec.delay_classes(max_delay=2, horizon=10**6, max_lost=1),
          "force"),
        P("size-classes-9-1e9", lambda c: eqrec.delay_classes(max_delay=9, horizon=10**9), "force"),
        P("size-full-language-30-2", lambda c: eqrec.full_delay_language(30, 2), "T"),
        P("size-full-language-60-1", lambda c: eqrec.full_delay_language(60, 1), "T"),
        P("size-missing-at-most-60-30", lambda c: eqrec.missing_words_at_most(60, 30), "T"),
        P("size-prefix-tree-huge", lambda c: eqrec.PrefixTree(eqrec.missing_words_at_most(40, 20)), "T"),
        P("size-min-level-4-800", lambda c: eqrec.min_recovery_level(c.reactor, eqrec.delay_classes(
            max_delay=4, horizon=800)), "force"),
        P("size-info-limit-1e5", lambda c: eqrec.information_limit(c.acc, ArrivalTrace(np.zeros(10**5, int)), 0.5),
          "force"),
        P("size-consistent-1e5", lambda c: eqrec.consistent_set(c.acc, ArrivalTrace(np.zeros(10**5, int)),
                                                                np.zeros((10**5, c.acc.p)), 0.5), "force"),
        P("size-zono-max-delay-1e9", lambda c: eqrec.ZonotopeEstimator(c.acc, max_delay=10**9), "max_delay"),
        P("size-zono-window-1e9", lambda c: eqrec.ZonotopeEstimator(c.acc, window=10**9), "window"),
        P("size-zono-iterations-1e9", lambda c: eqrec.ZonotopeEstimator(c.acc, iterations=10**9), "iterations"),
        P("size-exactset-max-delay-1e9", lambda c: eqrec.ExactSetEstimator(c.acc, max_delay=10**9), "max_delay"),
        P("size-exactset-window-1e9", lambda c: eqrec.ExactSetEstimator(c.acc, window=10**9), "window"),
        P("size-exact-bound-steps-1e12", lambda c: eqrec.exact_bound(
            __import__("eqrec.estimators.kalman", fromlist=["x"]).TimestampedKalman(c.plant, c.gauss),
            c.plant, 0.5, steps=10**12).reset([0.0, 0.0]).step([0.0]), "steps"),
        P("size-monte-carlo-1e9", lambda c: eqrec.monte_carlo(c.plant, c.design.schedule, ["1111", "1011"], 1.0,
                                                              10**9, 0), "runs"),
        P("size-loss-coverage-1e9", lambda c: eqrec.loss_coverage(2, 10**9, 0.1), "horizon"),
        P("size-delay-words-huge-D", lambda c: eqrec.delay_classes(max_delay=10**6, horizon=3), "max_delay"),
        # ------------------------------------------------------------------ silent inputs
        P("trace-never-overflow", lambda c: ArrivalTrace([0, 2**63 - 1]).arrival_times(), "delays"),
        P("trace-negative-2", lambda c: ArrivalTrace([0, -2]), "delays"),
        P("trace-nan", lambda c: ArrivalTrace(np.array([0.0, NAN])), "delays"),
        P("trace-string", lambda c: ArrivalTrace("0101"), "delays"),
        P("trace-2d", lambda c: ArrivalTrace(np.zeros((2, 2), int)), "delays"),
        P("trace-bool", lambda c: ArrivalTrace(np.array([True, False])), "delays"),
        P("info-cache-key", _info_cache, "", accept=_cache_check),
        P("info-x0-1e300", lambda c: eqrec.information_limit(c.acc, c.trace, 1e300), "x0_radius"),
        P("info-x0-nan", lambda c: eqrec.information_limit(c.acc, c.trace, NAN), "x0_radius"),
        P("info-x0-negative", lambda c: eqrec.information_limit(c.acc, c.trace, -1.0), "x0_radius"),
        P("info-x0-length", lambda c: eqrec.information_limit(c.acc, c.trace, [1.0, 2.0]), "x0_radius"),
        P("info-trace-list", lambda c: eqrec.information_limit(c.acc, [0, 0, 1], 0.5), "trace"),
        P("info-window-0", lambda c: eqrec.information_limit(c.acc, c.trace, 0.5, window=0), "window"),
        P("info-window-float", lambda c: eqrec.information_limit(c.acc, c.trace, 0.5, window=2.5), "window"),
        P("info-solver-unknown", lambda c: eqrec.information_limit(c.acc, c.trace, 0.5, solver="x"), "solver"),
        P("info-system-string", lambda c: eqrec.information_limit("acc", c.trace, 0.5), "system"),
        P("consistent-data-nan", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data + NAN, 0.5), "data"),
        P("consistent-data-shape", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data[:, :1], 0.5), "data"),
        P("consistent-data-short", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data[:3], 0.5), "data"),
        P("consistent-data-dict-key", lambda c: eqrec.consistent_set(c.acc, c.trace, {"a": [0, 0]}, 0.5), "data"),
        P("consistent-x0-nan", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, NAN), "x0_radius"),
        P("consistent-x0-1e300", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 1e300), "x0_radius"),
        P("consistent-centre-length", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 0.5, [0, 0]),
          "x0_centre"),
        P("consistent-centre-1e308", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 0.5, [1e308] * 3),
          "x0_centre"),
        P("consistent-inputs-shape", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 0.5,
                                                                    inputs=np.zeros((10, 3))), "inputs"),
        P("consistent-inputs-nan", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 0.5,
                                                                  inputs=np.full((10, 1), NAN)), "inputs"),
        P("zono-tv-reset-t0-negative", lambda c: eqrec.ZonotopeEstimator(c.tv).reset([0.0, 0.0], t0=-3), "t0"),
        P("zono-tv-reset-t0-past", lambda c: eqrec.ZonotopeEstimator(c.tv).reset([0.0, 0.0], t0=6), "t0"),
        P("zono-reset-overflow", _reset_overflow("zonotope"), "xhat0"),
        P("exactset-reset-overflow", _reset_overflow("exactset"), "xhat0"),
        P("guaranteed-reset-overflow", _reset_overflow("guaranteed"), "xhat0"),
        P("classest-reset-overflow", _reset_overflow("classest"), "xhat0"),
        P("kalman-reset-overflow", _reset_overflow("kalman"), "xhat0"),
        P("guaranteed-tv-reset-t0-negative", _tv_period_time, "", accept=_same_runs),
        P("zono-x0-radius-nan", lambda c: eqrec.ZonotopeEstimator(c.acc, x0_radius=NAN), "x0_radius"),
        P("zono-x0-radius-negative", lambda c: eqrec.ZonotopeEstimator(c.acc, x0_radius=-1), "x0_radius"),
        P("zono-x0-radius-1e308", lambda c: eqrec.ZonotopeEstimator(c.acc, x0_radius=1e308).reset(
            np.zeros(3)).step([0.0, 0.0]), ("x0_radius", "xhat0")),
        P("zono-max-delay-negative", lambda c: eqrec.ZonotopeEstimator(c.acc, max_delay=-1), "max_delay"),
        P("zono-max-delay-float", lambda c: eqrec.ZonotopeEstimator(c.acc, max_delay=1.5), "max_delay"),
        P("zono-gain-unknown", lambda c: eqrec.ZonotopeEstimator(c.acc, gain="kalman"), "gain"),
        P("zono-gain-empty", lambda c: eqrec.ZonotopeEstimator(c.acc, gain=()), "gain"),
        P("zono-reduction-unknown", lambda c: eqrec.ZonotopeEstimator(c.acc, reduction="box"), "reduction"),
        P("zono-order-0.5", lambda c: eqrec.ZonotopeEstimator(c.acc, order=0.5), "order"),
        P("zono-order-nan", lambda c: eqrec.ZonotopeEstimator(c.acc, order=NAN), "order"),
        P("zono-window-0", lambda c: eqrec.ZonotopeEstimator(c.acc, window=0), "window"),
        P("zono-iterations-negative", lambda c: eqrec.ZonotopeEstimator(c.acc, iterations=-1), "iterations"),
        P("zono-system-string", lambda c: eqrec.ZonotopeEstimator("acc"), "system"),
        P("zono-stale-packet", _stale_packet, "", accept=_stale_check),
        P("exactset-order-0", lambda c: eqrec.ExactSetEstimator(c.acc, order=0), "order"),
        P("exactset-x0-inf", lambda c: eqrec.ExactSetEstimator(c.acc, x0_radius=INF), "x0_radius"),
        P("exact-bound-x0-nan", lambda c: eqrec.exact_bound(c.design.estimator(), c.plant, NAN), "x0_radius"),
        P("exact-bound-estimator-string", lambda c: eqrec.exact_bound("kalman", c.plant, 0.5), "estimator"),
        P("exact-bound-order-0", lambda c: eqrec.exact_bound(c.design.estimator(), c.plant, 0.5, order=0),
          "order"),
        P("state-bounds-strict", _state_bounds, "", accept=_state_bounds_check),
        P("loss-coverage-loss-1.5", lambda c: eqrec.loss_coverage(2, 10, 1.5), "loss"),
        P("loss-coverage-coverage-0", lambda c: eqrec.loss_coverage(2, 10, 0.1, coverage=0), "coverage"),
        P("loss-coverage-burst-0.5", lambda c: eqrec.loss_coverage(2, 10, 0.1, burst=0.5), "burst"),
        P("loss-coverage-horizon-0", lambda c: eqrec.loss_coverage(2, 0, 0.1), "horizon"),
        P("loss-coverage-D-negative", lambda c: eqrec.loss_coverage(-1, 10, 0.1), "max_delay"),
        P("loss-coverage-loss-nan", lambda c: eqrec.loss_coverage(2, 10, NAN), "loss"),
        P("classes-max-lost-negative", lambda c: eqrec.delay_classes(max_delay=1, horizon=4, max_lost=-1),
          "max_lost"),
        P("classes-max-lost-over-T", lambda c: eqrec.delay_classes(max_delay=1, horizon=4, max_lost=5),
          "max_lost"),
        P("classes-force-string", lambda c: eqrec.delay_classes(max_delay=1, horizon=4, force="yes"), "force"),
        P("packet-time-float", lambda c: c.est("zonotope").step(eqrec.Packet(1.5, [0.0])), "y"),
        P("packet-y-nan", lambda c: c.est("guaranteed").step(eqrec.Packet(2, [NAN])), "y"),
        P("sys-V-nan", lambda c: eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], V=[[NAN]], eta_w=0.1,
                                                    eta_v=0.1), "V"),
        P("sys-V-huge-with-bound", lambda c: eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], V=[[1e308]],
                                                               eta_w=0.1, eta_v=1e308).__class__ and
          eqrec.ZonotopeEstimator(eqrec.AffineSystem(A=[[1.0]], C=[[1.0]], E=[[1.0]], V=[[1e308]], eta_w=0.1,
                                                     eta_v=1e308), 1.0).reset([0.0]).step([1.0]), ("eta_v", "y")),
        P("info-force-string", lambda c: eqrec.information_limit(c.acc, c.trace, 0.5, force="no"), "force"),
        P("consistent-force-string", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 0.5, force="no"),
          "force"),
        P("global-force-string", lambda c: eqrec.design_delay_global(c.plant, ["0000", "1000"], kind="delay",
                                                                     force="no"), "force"),
        P("min-level-force-string", lambda c: eqrec.min_recovery_level(c.plant, ["1111", "1011"], kind="missing",
                                                                       force="no"), "force"),
        P("mc-force-string", lambda c: eqrec.monte_carlo(c.plant, c.design.schedule, ["1111", "1011"], 1.0, 3, 0,
                                                         force="no"), "force"),
        P("size-monte-carlo-1e7", lambda c: eqrec.monte_carlo(c.plant, c.design.schedule, ["1111", "1011"], 1.0,
                                                              10**7, 0), "runs"),
        P("load-system-name-list", lambda c: (c.tmp / "named.yaml").write_text(_yaml(name="[1, 2]")) and
          eqrec.load_system(c.tmp / "named.yaml"), "name"),
        P("consistent-centre-1e20", lambda c: eqrec.consistent_set(c.acc, c.trace, c.data, 0.5, [1e20] * 3),
          "x0_centre"),
        P("acc-Ts-negative", lambda c: ac(Ts=-0.5), "Ts"),
        P("acc-m-zero", lambda c: ac(m=0.0), "m"),
        P("two-mass-eta-w-nan", lambda c: eqrec.two_mass(eta_w=(NAN, 0.1)), "eta_w"),
        P("reactor-Ts-nan", lambda c: eqrec.batch_reactor(Ts=NAN), "Ts"),
        P("delay-design-force-string", lambda c: eqrec.design_delay(c.plant, ["0000", "1000"], 1.0, kind="delay",
                                                                    force="no"), "force"),
    ]
    return cases


def _yaml(**change):
    base = {"A": "[[1.0, 0.1], [0.0, 1.0]]", "C": "[[1.0, 0.0]]", "E": "[[0.1, 0.0], [0.0, 0.1]]", "eta_w": "0.1",
            "eta_v": "0.05"}
    return "".join(f"{k}: {v}\n" for k, v in {**base, **change}.items() if v is not None)


def _cli_cases() -> list[Cli]:
    K = Cli
    CMP = "compare {sys} --loss 0.1 --max-delay 1 --horizon 4 --runs 2 --periods 2 --out {tmp}/cmp"
    D = "design {sys} --method delay"
    W = "design {sys} --words 1111,1011,1101"
    cases = [
        # ------------------------------------------------------------------ compare: sizes (refused < 5 s)
        K("compare-runs-1e5", CMP.replace("--runs 2", "--runs 100000"), 1, "runs"),
        K("compare-periods-1e4", CMP.replace("--periods 2", "--periods 10000"), 1, "periods"),
        K("compare-acc-4-30", "compare {sys} --loss 0.1 --max-delay 4 --horizon 30 --out {tmp}/cmp", 1, "force",
          system=ACC.read_text().replace("T: 6", "")),
        K("compare-acc-T-6-horizon-30", "compare {sys} --loss 0.1 --max-delay 4 --horizon 30 --out {tmp}/cmp", 1, "T",
          system=ACC.read_text()),
        K("compare-reactor-9-30", "compare {sys} --loss 0.1 --max-delay 9 --horizon 30 --out {tmp}/cmp", 1, "force",
          system=REACTOR.read_text()),
        # ------------------------------------------------------------------ compare: values
        K("compare-loss-1.5", CMP.replace("--loss 0.1", "--loss 1.5"), 1, "loss"),
        K("compare-loss-1", CMP.replace("--loss 0.1", "--loss 1"), 1, "loss"),
        K("compare-loss-nan", CMP.replace("--loss 0.1", "--loss nan"), 1, "loss"),
        K("compare-loss-negative", CMP.replace("--loss 0.1", "--loss -0.1"), 1, "loss"),
        K("compare-loss-text", CMP.replace("--loss 0.1", "--loss much"), 2, "--loss"),
        K("compare-max-delay-negative", CMP.replace("--max-delay 1", "--max-delay -1"), 1, "max_delay"),
        K("compare-max-delay-10", CMP.replace("--max-delay 1", "--max-delay 10"), 1, "max_delay"),
        K("compare-horizon-0", CMP.replace("--horizon 4", "--horizon 0"), 1, "horizon"),
        K("compare-horizon-31", CMP.replace("--horizon 4", "--horizon 31"), 1, "horizon"),
        K("compare-horizon-float", CMP.replace("--horizon 4", "--horizon 4.5"), 2, "--horizon"),
        K("compare-runs-0", CMP.replace("--runs 2", "--runs 0"), 1, "runs"),
        K("compare-runs-negative", CMP.replace("--runs 2", "--runs -3"), 1, "runs"),
        K("compare-periods-0", CMP.replace("--periods 2", "--periods 0"), 1, "periods"),
        K("compare-burst-0.5", CMP + " --burst 0.5", 1, "burst"),
        K("compare-burst-nan", CMP + " --burst nan", 1, "burst"),
        K("compare-seed-negative", CMP + " --seed -1", 1, "seed"),
        K("compare-seed-text", CMP + " --seed abc", 2, "--seed"),
        K("compare-weights-length", CMP + " --state-weights 1,2,3", 1, "--state-weights"),
        K("compare-weights-negative", CMP + " --state-weights 1,-1", 1, "state_weights"),
        K("compare-weights-nan", CMP + " --state-weights 1,nan", 1, "state_weights"),
        K("compare-coverage-0", CMP + " --coverage 0", 1, "coverage"),
        K("compare-coverage-1.5", CMP + " --coverage 1.5", 1, "coverage"),
        K("compare-coverage-nan", CMP + " --coverage nan", 1, "coverage"),
        K("compare-solver-gurobi", CMP + " --solver gurobi", 1, "solver"),
        K("compare-out-missing-parent", CMP.replace("{tmp}/cmp", "{tmp}/no/cmp"), 1, "--out"),
        K("compare-out-a-file", CMP.replace("{tmp}/cmp", "{sys}"), 1, "--out"),
        K("compare-loss-missing", CMP.replace("--loss 0.1 ", ""), 2, "--loss"),
        K("compare-gaussian-Qw-shape", CMP, 1, "Qw", system=_yaml(gaussian="{Qw: [[1.0]]}")),
        K("compare-gaussian-Qw-negative", CMP, 1, "Qw", system=_yaml(gaussian="{Qw: [[-1.0, 0], [0, 1.0]]}")),
        K("compare-gaussian-Qv-nan", CMP, 1, "Qv", system=_yaml(gaussian="{Qv: [[.nan]]}")),
        K("compare-gaussian-not-mapping", CMP, 1, "gaussian", system=_yaml(gaussian="[1, 2]")),
        K("compare-gaussian-unknown-key", CMP, 1, "gaussian", system=_yaml(gaussian="{Q: [[1.0]]}")),
        K("compare-gaussian-x0-asym", CMP, 1, "x0_cov", system=_yaml(gaussian="{x0_cov: [[1.0, 0.5], [0, 1.0]]}")),
        K("compare-system-missing", CMP.replace("{sys}", "{tmp}/none.yaml"), 1, "none.yaml"),
        K("compare-system-A-nan", CMP, 1, "'A'", system=_yaml(A="[[.nan, 0.1], [0.0, 1.0]]")),
        K("compare-system-T", CMP, 1, "T", system=_yaml(T="9")),
        # ------------------------------------------------------------------ design: sizes
        K("design-4-800", f"{D} --max-delay 4 --horizon 800", 1, "--force", system=REACTOR.read_text()),
        K("design-2-1e6-lost", f"{D} --max-delay 2 --horizon 1000000 --max-lost 1", 1, "--force"),
        K("design-1-1e5", f"{D} --max-delay 1 --horizon 100000", 1, "--force"),
        K("design-9-1e9", f"{D} --max-delay 9 --horizon 1000000000", 1, "--force"),
        K("design-free-4-800", f"{D} --max-delay 4 --horizon 800 --mu1 free", 1, "--force"),
        K("design-node-gains-huge", f"{D} --max-delay 3 --horizon 20 --node-gains", 1, "--node-gains"),
        K("design-tree-huge", f"{D} --max-delay 3 --horizon 20 --engine tree", 1, "--engine"),
        K("design-max-lost-negative", f"{D} --max-delay 1 --horizon 4 --max-lost -1", 1, "--max-lost"),
        K("design-max-lost-over-T", f"{D} --max-delay 1 --horizon 4 --max-lost 5", 1, "--max-lost"),
        K("design-max-lost-text", f"{D} --max-delay 1 --horizon 4 --max-lost a", 2, "--max-lost"),
        K("design-max-lost-alone", f"{D} --delays 0000,1000 --max-lost 1", 1, "--max-lost"),
        K("design-max-lost-prefix", f"{W} --max-lost 1", 1, "--max-lost"),
        K("design-jobs-0", f"{D} --max-delay 1 --horizon 4 --jobs 0", 1, "--jobs"),
        K("design-jobs-negative", f"{D} --max-delay 1 --horizon 4 --jobs -2", 1, "--jobs"),
        K("design-jobs-text", f"{D} --max-delay 1 --horizon 4 --jobs many", 2, "--jobs"),
        K("design-scheduler-bogus", f"{D} --max-delay 1 --horizon 4 --scheduler nothing://x", 1, "--scheduler"),
        K("design-force-time", f"{W} --method time --force", 1, "--force"),
        K("design-max-delay-negative", f"{D} --max-delay -1 --horizon 4", 1, "--max-delay"),
        K("design-horizon-negative", f"{D} --max-delay 1 --horizon -4", 1, "--horizon"),
        K("design-max-delay-alone", f"{D} --max-delay 1", 1, "--horizon"),
        K("design-delays-and-max-delay", f"{D} --delays 0000 --max-delay 1 --horizon 4", 1, "--delays"),
        K("design-delays-x-letter", f"{D} --delays 0x00,0000", 1, "--delays"),
        K("design-delays-empty", f"{D} --delays ,", 1, "--delays"),
        K("design-mu1-inf", f"{W} --mu1 inf", 1, "--mu1"),
        K("design-mu1-zero", f"{W} --mu1 0", 1, "--mu1"),
        K("design-weights-zero", f"{W} --state-weights 0,1", 1, "--state-weights"),
        K("design-weights-inf", f"{W} --state-weights inf,1", 1, "--state-weights"),
        K("design-s0-length", f"{W} --method augmented --s0 [0,0,0]", 1, "s0"),
        K("design-poles-nan", f"{W} --method augmented --poles nan,0.1", 1, "poles"),
        K("design-poles-count", f"{W} --method augmented --poles 0.1", 1, "poles"),
        K("design-sys-V-shape", W, 1, "'V'", system=_yaml(V="[[1.0], [0.0]]")),
        K("design-sys-V-nan", W, 1, "'V'", system=_yaml(V="[[.nan]]")),
        K("design-sys-eta_v-per-channel-long", W, 1, "'eta_v'", system=_yaml(eta_v="[0.1, 0.2]")),
        K("design-sys-A-huge", W, 1, "'A'", system=_yaml(A="[[1e308, 1e308], [1e308, 1e308]]")),
        K("design-sys-tv-length", "design {sys} --words 111,101", 1, "'A'", system=_yaml(
            A="[[[1.0, 0.1], [0.0, 1.0]], [[1.0, 0.1], [0.0, 1.0]]]", T="3")),
        K("design-sys-name-number", W, 1, "name", system=_yaml(name="3")),
        K("design-sys-E-nan", W, 1, "'E'", system=_yaml(E="[[.nan, 0.0], [0.0, 0.1]]")),
        K("design-sys-B-nan", W, 1, "'B'", system=_yaml(B="[[.nan], [0.1]]")),
        K("design-sys-dt-negative", W, 1, "dt", system=_yaml(dt="-1")),
        K("design-sys-name-list", W, 1, "name", system=_yaml(name="[1, 2]")),
        K("design-words-delay-letters", f"{W.split(' --')[0]} --words 1211", 1, "--words"),
        K("design-out-unwritable", f"{W} --out /proc/x.json", 1, "--out"),
        K("cli-no-command", "", 2, "usage"),
        K("cli-unknown-command", "simulate {sys}", 2, "simulate"),
    ]
    return cases


# ============================================================================================ running a case
def _named(exc: BaseException, field: "str | tuple[str, ...]") -> bool:
    if isinstance(field, tuple):
        return any(_named(exc, f) for f in field)
    return getattr(exc, "field", None) == field or (getattr(exc, "field", None) or "").startswith(field) \
        or field in str(exc)


def _run_python(case: Py, ctx: Ctx) -> tuple[str, str]:
    try:
        result = case.call(ctx)
    except AtomicityBroken as exc:
        return "silent", f"not atomic: {exc}"
    except EqrecError as exc:
        if case.accept is not None:
            return "raw", f"{type(exc).__name__}: {exc}"[:300]
        if not _named(exc, case.field):
            return "raw", f"{type(exc).__name__} not naming {case.field!r}: {exc}"[:300]
        return "clear", f"{type(exc).__name__}: {exc}"[:200]
    except Exception as exc:  # noqa: BLE001 - the census looks at whatever is raised
        tb = traceback.extract_tb(exc.__traceback__)[-1]
        return "raw", f"{type(exc).__name__}: {str(exc)[:200]} ({Path(tb.filename).name}:{tb.lineno})"
    if case.accept is not None:
        wrong = case.accept(ctx, result)
        return ("silent", wrong) if wrong else ("clear", "accepted, right")
    return "silent", f"accepted: {repr(result)[:200]}"


def _run_cli(case: Cli, ctx: Ctx, folder: Path) -> tuple[str, str]:
    argv, out_dir = _cli_argv(case, folder)
    from eqrec.cli import main
    err, out = io.StringIO(), io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(out):
            code = main(argv)
    except SystemExit as exc:
        code = exc.code if isinstance(exc.code, int) else (0 if exc.code is None else 1)
    except Exception as exc:  # noqa: BLE001 - a traceback
        return "raw", f"traceback {type(exc).__name__}: {str(exc)[:200]}"
    return _judge_cli(case, code, err.getvalue(), folder, out_dir)


def _cli_argv(case: Cli, folder: Path) -> tuple[list[str], Path]:
    system = folder / "system.yaml"
    system.write_text(case.system if case.system is not None else _yaml())
    out_dir = folder / "out"
    out_dir.mkdir(exist_ok=True)
    args = case.args.replace("{sys}", str(system)).replace("{tmp}", str(folder)).split()
    if args and args[0] == "design" and "--out" not in args:
        args += ["--out", str(out_dir / "design.json")]
    return args, out_dir


def _judge_cli(case: Cli, code: int, stderr: str, folder: Path, out_dir: Path) -> tuple[str, str]:
    last = (stderr.strip().splitlines() or [""])[-1][:200]
    if "Traceback" in stderr:
        return "raw", f"traceback: {last}"
    wrote = list(out_dir.iterdir()) or (folder / "cmp").exists() and any((folder / "cmp").iterdir())
    if code == 0:
        return "silent", f"exit 0{' (wrote output)' if wrote else ''}: {last}"
    if code != case.code or case.text not in stderr:
        return "raw", f"exit {code} (want {case.code}, {case.text!r}): {last}"
    if wrote:
        return "silent", f"exit {code} but wrote output"
    return "clear", f"exit {code}: {last}"


def _fork(fn: Callable[[], tuple[str, str]], limit: float) -> tuple[str, str, float]:
    """Run ``fn`` in a forked child; ``("hang", ...)`` past ``limit`` seconds (the child is killed)."""
    read, write = os.pipe()
    start = time.perf_counter()
    pid = os.fork()
    if pid == 0:  # the child
        os.close(read)
        try:
            os.setpgid(0, 0)
            outcome = fn()
        except BaseException as exc:  # noqa: BLE001
            outcome = ("raw", f"{type(exc).__name__}: {exc}"[:300])
        with os.fdopen(write, "wb") as f:
            f.write(pickle.dumps(outcome))
        os._exit(0)
    os.close(write)
    chunks = []
    deadline = start + limit
    import select
    while True:
        left = deadline - time.perf_counter()
        if left <= 0:
            break
        ready, _, _ = select.select([read], [], [], left)
        if ready:
            chunk = os.read(read, 1 << 16)
            if not chunk:
                break
            chunks.append(chunk)
    elapsed = time.perf_counter() - start
    os.close(read)
    done, _ = os.waitpid(pid, os.WNOHANG)
    if not done:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(pid, signal.SIGKILL)
        with contextlib.suppress(ProcessLookupError):
            os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
    if elapsed >= limit and not chunks:
        return "hang", f"no answer within {limit:g} s", elapsed
    try:
        status, note = pickle.loads(b"".join(chunks))
    except Exception:  # noqa: BLE001 - the child died
        return "raw", "the process died without an answer", elapsed
    return status, note, elapsed


def _subprocess_cli(case: Cli, folder: Path, limit: float) -> tuple[str, str, float]:
    argv, out_dir = _cli_argv(case, folder)
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    start = time.perf_counter()
    run = subprocess.run(["timeout", "-s", "KILL", f"{limit:g}", sys.executable, "-m", "eqrec", *argv],
                         capture_output=True, text=True, env=env)
    elapsed = time.perf_counter() - start
    if run.returncode in (124, 137, -9):
        return "hang", f"no answer within {limit:g} s", elapsed
    return (*_judge_cli(case, run.returncode, run.stderr, folder, out_dir), elapsed)


def all_cases() -> list["Py | Cli"]:
    return _python_cases() + _step_cases() + _cli_cases()


def run(cases, *, limit: float = LIMIT, subprocess_cli: bool = False, tmp: "Path | None" = None,
        verbose: bool = True) -> list[dict]:
    import tempfile
    tmp = Path(tempfile.mkdtemp(prefix="census-")) if tmp is None else tmp
    ctx = Ctx(tmp)
    startup = 0.0
    if subprocess_cli:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "eqrec", "--version"], capture_output=True,
                       env={**os.environ, "PYTHONPATH": str(ROOT / "src")})
        startup = time.perf_counter() - start
        if verbose:
            print(f"interpreter start-up (python -m eqrec --version): {startup:.2f} s; CLI limit {limit + startup:.1f} s")
    rows = []
    for i, case in enumerate(cases):
        folder = tmp / f"case{i}"
        folder.mkdir()
        if isinstance(case, Py):
            status, note, elapsed = _fork(lambda: _run_python(case, ctx), limit)
        elif subprocess_cli:
            status, note, elapsed = _subprocess_cli(case, folder, limit + startup)
        else:
            status, note, elapsed = _fork(lambda: _run_cli(case, ctx, folder), limit)
        rows.append({"id": case.id, "group": case.group, "status": status, "seconds": elapsed, "note": note})
        if verbose and status != "clear":
            print(f"  {status:6s} {case.group:11s} {case.id}: {note}  [{elapsed:.1f} s]", flush=True)
    return rows


def table(rows: list[dict]) -> str:
    groups = ["python", "python-step", "cli"]
    lines = [f"{'':12s} {'cases':>6s} {'clear':>6s} {'raw':>5s} {'silent':>7s} {'hang':>5s} {'max s':>6s}"]
    for g in groups + ["all"]:
        sel = [r for r in rows if g == "all" or r["group"] == g]
        if not sel:
            continue
        n = {s: sum(r["status"] == s for r in sel) for s in ("clear", "raw", "silent", "hang")}
        lines.append(f"{g:12s} {len(sel):6d} {n['clear']:6d} {n['raw']:5d} {n['silent']:7d} {n['hang']:5d} "
                     f"{max(r['seconds'] for r in sel):6.1f}")
    return "\n".join(lines)


def main(argv: "list[str] | None" = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("-k", default="", help="only the cases whose id contains this")
    parser.add_argument("--subprocess-cli", action="store_true", help="the CLI cases as real processes")
    parser.add_argument("--json", help="write the rows to this JSON file")
    args = parser.parse_args(argv)
    os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")
    cases = [c for c in all_cases() if args.k in c.id]
    ids = [c.id for c in cases]
    assert len(ids) == len(set(ids)), "duplicate ids"
    start = time.perf_counter()
    rows = run(cases, subprocess_cli=args.subprocess_cli)
    print(table(rows))
    print(f"({len(rows)} cases in {time.perf_counter() - start:.0f} s; limit {LIMIT:g} s per case)")
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=1))
    return 0 if all(r["status"] == "clear" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
