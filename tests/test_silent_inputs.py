"""Issue 33, sections 3 and 4: designs that load back, messages that say what to do, inputs once accepted silently.

Section 3: a design JSON of ``eqrec design --out`` is read back by :func:`eqrec.load_design` into a design whose
estimator gives the same estimates and bounds (compared with ``==``) as the design that wrote it; the
infeasibility message carries ``mu1_min``; the ``--mu1 free`` summary prints ``mu1``; ``estimator_iosys`` runs
weighted designs; a misspelt system key is named.  Section 4 (the census of ``SILENT`` below): inputs that used
to be accepted without a word, each with its outcome now.
"""
from __future__ import annotations

import json
import socket
from pathlib import Path

import numpy as np
import pytest

import eqrec
from eqrec.cli import main
from eqrec.errors import InfeasibleDesign, InputError

ROOT = Path(__file__).resolve().parents[1]
ACC = ROOT / "examples" / "acc_system.yaml"
REACTOR = ROOT / "examples" / "batch_reactor.yaml"
L1 = "101111,110111,111011,111101"


# --- 3. designs that load back ----------------------------------------------------------------------------------

def _designed_by_cli(monkeypatch, tmp_path, system_file, args):
    """Run ``eqrec design`` in this process; return the JSON's path and the Design the command made."""
    import eqrec.design.augmented.design as aug
    import eqrec.design.delay.design as delay
    import eqrec.design.prefix.design as prefix
    import eqrec.design.prefix.time_based as time_based

    made = []

    def recording(module, name):
        original = getattr(module, name)

        def wrapper(*a, **kw):
            result = original(*a, **kw)
            made.append(getattr(result, "design", result))  # design_delay_global returns a FreeMu1Result
            return result

        monkeypatch.setattr(module, name, wrapper)

    for module, name in ((prefix, "design_prefix"), (time_based, "design_time_based"), (aug, "design_augmented"),
                         (delay, "design_delay"), (delay, "design_delay_global")):
        recording(module, name)
    out = tmp_path / "design.json"
    assert main(["design", str(system_file), *args.split(), "--out", str(out)]) == 0
    return out, made[-1]


def _trace(design, rng, periods=4):
    """What arrives at each step over ``periods`` periods (packets of an in-language word each period)."""
    system, T = design.system, design.T
    steps = []
    for _ in range(periods):
        word = design.patterns[rng.integers(len(design.patterns))] if design.patterns else None
        arrivals = [[] for _ in range(T)]
        for i in range(T):
            at = None if word is None else word.arrivals[i]
            if at is not None:
                arrivals[at].append(i)
        for t in range(T):
            u = rng.normal(size=system.m) if system.m else None
            packets = [(len(steps) - t + i, rng.normal(size=system.p)) for i in arrivals[t]]
            steps.append((packets, u))
    return steps


def _run(estimator, x0, steps):
    estimator.reset(x0)
    xs, bounds = [], []
    for packets, u in steps:
        xhat, bound = estimator.step(packets or None, u)
        xs.append(xhat)
        bounds.append(bound)
    return np.array(xs), np.array(bounds)


CASES = {
    "prefix-classes": (ACC, f"--words {L1}"),
    "prefix-tree": (ACC, f"--words {L1} --engine tree"),
    "prefix-free": (ACC, "--words 101111,110111 --mu1 free"),
    "time": (ACC, f"--method time --words {L1}"),
    "augmented": (ACC, f"--method augmented --words {L1}"),
    "delay-classes": (REACTOR, "--method delay --max-delay 2 --horizon 5 --mu1 0.33"),
    "delay-delays-free": (REACTOR, "--method delay --delays 21210,00000,01010 --mu1 free"),
    "delay-tree": (REACTOR, "--method delay --max-delay 1 --horizon 4 --mu1 2 --engine tree"),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_loaded_design_estimates_bit_for_bit_as_the_design_that_wrote_it(monkeypatch, tmp_path, case):
    out, design = _designed_by_cli(monkeypatch, tmp_path, *CASES[case])
    loaded = eqrec.load_design(out)
    assert (loaded.method, loaded.T, loaded.mu1, loaded.mu2) == (design.method, design.T, design.mu1, design.mu2)
    assert loaded.system == design.system
    rng = np.random.default_rng(33)
    patterns = design.patterns or loaded.patterns
    if not patterns:  # a window-rule language: its packets come from random words of {0..D}^T
        patterns = eqrec.delay_language(max_delay=2, horizon=design.T)
    design.patterns = loaded.patterns = tuple(patterns) if design.method != "time" else design.patterns
    for _ in range(3):
        steps = _trace(design, rng)
        x0 = rng.uniform(-design.mu1, design.mu1, design.system.n)
        xs, bounds = _run(design.estimator(), x0, steps)
        xs_loaded, bounds_loaded = _run(loaded.estimator(), x0, steps)
        assert np.array_equal(xs, xs_loaded) and np.array_equal(bounds, bounds_loaded)


def test_a_weighted_design_loads_back_to_rounding(monkeypatch, tmp_path):
    out, design = _designed_by_cli(monkeypatch, tmp_path, ACC, f"--words {L1} --state-weights 1,3,0.7")
    loaded = eqrec.load_design(out)
    assert np.array_equal(loaded.state_weights, design.state_weights) and loaded.system == design.system
    steps = _trace(design, np.random.default_rng(1))
    xs, bounds = _run(design.estimator(), np.zeros(3), steps)
    xs_loaded, bounds_loaded = _run(loaded.estimator(), np.zeros(3), steps)
    # the JSON holds the gains divided by the weights (the file's coordinates); multiplying back rounds
    np.testing.assert_allclose(xs_loaded, xs, rtol=1e-12, atol=1e-12)
    assert np.all(bounds_loaded >= bounds) and np.allclose(bounds_loaded, bounds, rtol=1e-12)


def test_load_design_refuses_what_it_cannot_run(tmp_path):
    good = tmp_path / "good.json"
    assert main(["design", str(ACC), "--words", L1, "--out", str(good)]) == 0
    data = json.loads(good.read_text())
    cases = {"no-system": ({k: v for k, v in data.items() if k != "system"}, "system"),
             "no-gains": ({k: v for k, v in data.items() if k not in ("gains", "classes")}, "gains"),
             "method": ({**data, "method": "kalman"}, "method"),
             "T": ({**data, "T": 0}, "T"),
             "edited-K": ({**data, "classes": [{**row, "K": (10 * np.asarray(row["K"])).tolist()} if row["data"]
                                               else row for row in data["classes"]]}, "classes")}
    for name, (content, field) in cases.items():
        path = tmp_path / f"{name}.json"
        path.write_text(json.dumps(content))
        with pytest.raises(InputError) as exc:
            eqrec.load_design(path)
        assert exc.value.field.split("[")[0] == field, (name, str(exc.value))
    (tmp_path / "bad.json").write_text("{not json")
    for path, field in ((tmp_path / "bad.json", None), (tmp_path / "none.json", None), (3, "path")):
        with pytest.raises(InputError) as exc:
            eqrec.load_design(path)
        assert exc.value.field == field


# --- 3. messages that say what to do -----------------------------------------------------------------------------

MOTOR = dict(A=[[1.0, 0.1], [0.0, 0.9]], B=[[0.0], [0.1]], C=[[1.0, 0.0]], E=np.eye(2))


@pytest.mark.parametrize("method", ["prefix", "time", "delay"])
def test_infeasible_names_mu1_min_as_a_float_and_the_methods_own_free_entry(method):
    plant = eqrec.AffineSystem(**MOTOR, eta_w=0.01, eta_v=0.02)
    calls = {"prefix": lambda mu1: eqrec.design_prefix(plant, ["1011", "1101"], mu1),
             "time": lambda mu1: eqrec.design_time_based(plant, ["1011", "1101"], mu1),
             "delay": lambda mu1: eqrec.design_delay(plant, ["0200", "0020"], mu1)}
    with pytest.raises(InfeasibleDesign) as info:
        calls[method](0.01)
    text, mu1_min = str(info.value), info.value.mu1_min
    assert isinstance(mu1_min, float) and f"the smallest feasible mu1 is {mu1_min:.6g} " in text
    assert ("design_delay_global" in text) == (method == "delay")
    assert {"prefix": "design_prefix(..., mu1='free')", "time": "design_time_based(..., mu1='free')",
            "delay": "design_delay_global"}[method] in text
    assert calls[method](mu1_min).mu1 == mu1_min  # retrying at it succeeds
    import pickle

    assert pickle.loads(pickle.dumps(info.value)).mu1_min == mu1_min  # kept across processes


def test_the_free_summary_line_prints_mu1(tmp_path, capsys):
    assert main(["design", str(ACC), "--words", "101111,110111", "--mu1", "free", "--out",
                 str(tmp_path / "d.json")]) == 0
    line = capsys.readouterr().err.strip()
    mu1 = json.loads((tmp_path / "d.json").read_text())["mu1"]
    assert line.startswith(f"mu1 = {mu1:.6g}, mu2 = ") and mu1 < 1


def test_a_misspelt_system_key_is_named_next_to_the_missing_one(tmp_path):
    path = tmp_path / "plant.yaml"
    path.write_text("A: [[1.0]]\nC: [[1.0]]\nE: [[1.0]]\neta_W: 0.1\neta_v: 0.1\n")
    with pytest.raises(InputError) as exc:
        eqrec.load_system(path)
    assert exc.value.field == "eta_w" and "unknown field(s) ['eta_W']" in str(exc.value)
    assert "write 'eta_w', not 'eta_W'" in str(exc.value)


def test_estimator_iosys_runs_a_weighted_design_as_its_estimator():
    control = pytest.importorskip("control")
    from eqrec.interop.python_control import estimator_iosys

    acc = eqrec.acc_system()
    weights = np.array([1.0, 3.0, 0.7])
    design = eqrec.design_prefix(acc, L1.split(","), 1.0, state_weights=weights)
    io = estimator_iosys(design)
    rng = np.random.default_rng(2)
    N = 18
    u, y = rng.normal(size=(1, N)), rng.normal(size=(2, N))
    arrived = np.array([1.0 if c == "1" else 0.0 for c in "101111110111111011"])
    x0 = np.array([0.1, -0.2, 0.3])
    out = control.input_output_response(io, np.arange(N), np.vstack([u, y, arrived]), io.initial_state(x0)).outputs
    est = design.estimator().reset(x0)
    assert np.array_equal(out[:3, 0], weights * x0 / weights)  # x̂(0), through z = W x as the estimator
    for k in range(N - 1):  # column k + 1 of the response is what step(data of time k) returns
        xhat, bound = est.step(y[:, k] if arrived[k] else None, u[:, k])
        # the iosys reports the class level; the estimator adds its rounding allowance (issue 40 §2)
        assert np.array_equal(out[:3, k + 1], xhat) and out[3, k + 1] <= bound <= out[3, k + 1] * (1 + 1e-9)


# --- 4. the inputs that were accepted silently: the census ---------------------------------------------------------

def _refused(call, field):
    with pytest.raises(InputError) as exc:
        call()
    assert exc.value.field == field, str(exc.value)
    return str(exc.value)


@pytest.fixture(scope="module")
def small():
    return eqrec.design_prefix(eqrec.acc_system(), L1.split(","), 1.0)


def test_reset_refuses_a_column_estimate(small):
    _refused(lambda: small.estimator().reset(np.zeros((3, 1))), "xhat0")
    _refused(lambda: small.estimator().reset([[0.0, 0.0, 0.0]]), "xhat0")
    assert small.estimator().reset(np.zeros(3)).time == 0  # the flat vector still works


def test_step_refuses_an_input_of_shape_1_1(small):
    est = small.estimator().reset(np.zeros(3))
    text = _refused(lambda: est.step([1.0, 2.0], u=np.zeros((1, 1))), "u")
    assert "shape (1, 1)" in text and est.time == 0  # nothing changed
    est.step([1.0, 2.0], u=np.zeros(1))
    est.step(None, u=0.5)  # one input as a number is still one input


def test_delay_classes_has_the_cli_limit():
    from eqrec.arrivals.words import MAX_DELAY
    from eqrec.cli import _parser

    assert MAX_DELAY == 9 and f"D <= {MAX_DELAY}" in _parser().format_help() + "".join(
        a.help or "" for sp in _parser()._subparsers._group_actions for p in sp.choices.values()
        for a in p._actions)
    _refused(lambda: eqrec.delay_classes(max_delay=12, horizon=3), "max_delay")
    _refused(lambda: eqrec.full_delay_language(3, MAX_DELAY + 1), "max_delay")
    assert len(eqrec.delay_classes(max_delay=MAX_DELAY, horizon=3)) > 0


def test_a_packet_of_an_earlier_period_is_dropped_and_counted_under_strict():
    design = eqrec.design_delay(eqrec.load_system(REACTOR)[0], eqrec.delay_classes(max_delay=2, horizon=5), 0.33)
    for strict in (True, False):
        est = design.estimator(strict=strict).reset(np.zeros(4))
        for t in range(4):
            est.step(np.zeros(2))
        est.step(None)  # y(4) is two steps late: it arrives at time 6, in the next period (missing in this one)
        est.step(np.zeros(2))
        inner = est._est
        assert inner.dropped_packets == 0
        xhat, bound = est.step([(4, np.zeros(2)), (6, np.zeros(2))])
        assert inner.dropped_packets == 1 and inner.period_start == 5 and bound <= design.mu2


def test_scheduler_probe_refuses_an_unreachable_address():
    from eqrec.lp.parallel import check_reachable

    with socket.socket() as sock:  # a port that was free a moment ago: nothing listens there
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    _refused(lambda: check_reachable(f"tcp://127.0.0.1:{port}", timeout=2.0), "scheduler")
    with socket.socket() as server:  # a listening port is reachable
        server.bind(("127.0.0.1", 0))
        server.listen()
        check_reachable(f"tcp://127.0.0.1:{server.getsockname()[1]}")
    check_reachable(None)


#: (id, arguments after ``eqrec design <system>``, exit code, text on stderr): the command lines of section 4.
SILENT = [
    ("words-trailing-comma", f"--words {L1},", 1, "field '--words': word 5 of 5 is empty"),
    ("words-leading-comma", f"--words ,{L1}", 1, "field '--words': word 1 of 5 is empty"),
    ("words-duplicate", "--words 101111,110111,101111", 1, "field '--words': 101111 given more than once"),
    ("delays-trailing-comma", "--method delay --delays 21210,00000,", 1, "field '--delays'"),
    ("delays-duplicate", "--method delay --delays 21210,21210", 1, "field '--delays': 21210 given more than once"),
    ("max-delay-12", "--method delay --max-delay 12 --horizon 3", 1, "field '--max-delay': must be 0..9"),
    ("scheduler-unreachable", f"--words {L1} --scheduler tcp://127.0.0.1:1", 1, "field '--scheduler'"),
]


@pytest.mark.parametrize("case", SILENT, ids=[c[0] for c in SILENT])
def test_cli_inputs_once_silent(tmp_path, capsys, monkeypatch, case):
    import eqrec.lp.parallel as parallel

    _, args, code, text = case
    monkeypatch.setattr(parallel, "_distributed", lambda: None)  # dask need not be installed to reach the probe
    system = REACTOR if "--method delay" in args else ACC
    if "--delays" in args:
        system = tmp_path / "reactor.yaml"  # the reactor file has T = 5: the same plant without it
        system.write_text("".join(line + "\n" for line in REACTOR.read_text().splitlines()
                                  if not line.startswith("T:")))
    out = tmp_path / "d.json"
    assert main(["design", str(system), *args.split(), "--out", str(out)]) == code
    err = capsys.readouterr().err
    assert text in err and "Traceback" not in err, err
    assert not out.exists()


# --- issue 41 census: inputs accepted silently before -------------------------------------------------------------

@pytest.mark.parametrize("call,field", [
    (lambda: eqrec.acc_system(Ts=-0.5), "Ts"),
    (lambda: eqrec.acc_system(m=0.0), "m"),  # a raw ZeroDivisionError before
    (lambda: eqrec.acc_system(k1=float("nan")), "k1"),
    (lambda: eqrec.two_mass(m2=-1.0), "m2"),
])
def test_example_plants_check_their_constants(call, field):
    with pytest.raises(InputError) as exc:
        call()
    assert exc.value.field == field


def test_flags_given_as_strings_are_refused():
    from eqrec.arrivals.draws import ArrivalTrace

    acc = eqrec.acc_system()
    trace = ArrivalTrace([0, 1, 0])
    data = np.zeros((3, acc.p))
    plant = eqrec.AffineSystem(A=[[1.0, 0.1], [0.0, 1.0]], C=[[1.0, 0.0]], E=0.1 * np.eye(2), eta_w=0.1, eta_v=0.05)
    for call in (lambda: eqrec.information_limit(acc, trace, 0.5, force="no"),
                 lambda: eqrec.consistent_set(acc, trace, data, 0.5, force="no"),
                 lambda: eqrec.design_delay(plant, ["0000", "1000"], 1.0, kind="delay", force="no"),
                 lambda: eqrec.design_delay_global(plant, ["0000", "1000"], kind="delay", force="no")):
        with pytest.raises(InputError) as exc:
            call()
        assert exc.value.field == "force"


@pytest.mark.parametrize("centre", [1e20, 1e300])
def test_consistent_set_refuses_a_centre_the_lp_cannot_represent(centre):
    """x0_centre = 1e20 made data inconsistent with the box "consistent" (HiGHS reads 1e20 as infinite)."""
    from eqrec.arrivals.draws import ArrivalTrace

    acc = eqrec.acc_system()
    data = np.random.default_rng(0).normal(size=(4, acc.p)) * 0.01
    trace = ArrivalTrace([0, 1, 0, 0])
    with pytest.raises(InputError) as exc:
        eqrec.consistent_set(acc, trace, data, 0.5, [centre] * 3)
    assert exc.value.field == "x0_centre"
    with pytest.raises(InputError) as exc:  # a centre far from the data, within range: inconsistent, and said so
        eqrec.consistent_set(acc, trace, data, 0.5, [100.0] * 3)
    assert exc.value.field == "data"


def test_a_system_file_name_must_be_a_string(tmp_path):
    path = tmp_path / "named.yaml"
    path.write_text("A: [[1.0]]\nC: [[1.0]]\nE: [[1.0]]\neta_w: 0.1\neta_v: 0.1\nname: [1, 2]\n")
    with pytest.raises(InputError) as exc:
        eqrec.load_system(path)
    assert exc.value.field == "name"
    path.write_text("A: [[1.0]]\nC: [[1.0]]\nE: [[1.0]]\neta_w: 0.1\neta_v: 0.1\nname: plant one\n")
    assert eqrec.load_system(path)[0].name == "plant one"


def test_compare_refuses_a_system_file_whose_T_is_not_the_horizon(tmp_path, capsys):
    from eqrec.cli import main

    rc = main(["compare", str(ROOT / "examples" / "acc_system.yaml"), "--loss", "0.1", "--max-delay", "1",
               "--horizon", "4", "--runs", "2", "--periods", "2", "--out", str(tmp_path / "cmp")])
    err = capsys.readouterr().err
    assert rc == 1 and "field 'T'" in err and "--horizon 4" in err and not (tmp_path / "cmp").exists()


def test_a_short_time_varying_system_names_its_matrix():
    tv = eqrec.AffineSystem(A=[np.eye(2)] * 2, C=[[1.0, 0.0]], E=np.eye(2), eta_w=0.1, eta_v=0.1)
    with pytest.raises(InputError) as exc:
        tv.check_horizon(3)
    assert exc.value.field == "A"
