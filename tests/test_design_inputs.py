"""What the design entries take (issue 24, sections 1 and 5): one reading of a word in Python and on the command
line, every bad input an InputError naming its field, per-channel noise bounds, per-state weights, μ1 free for
the prefix method and the true smallest μ1 in an infeasibility message."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import eqrec
from eqrec.cli import main
from eqrec.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
ACC_FILE = ROOT / "examples" / "acc_system.yaml"
L1 = ["101111", "110111", "111011", "111101"]
L1_AS_DELAYS = ["060000", "006000", "000600", "000060"]  # the delayed-data paper's spelling of L1 (P3-ACC)
ZERO_ONE = ["0111", "1011", "1101"]


@pytest.fixture(scope="module")
def acc():
    return eqrec.acc_system()


# --- 1. one rule for what a word means ----------------------------------------------------------------------------

@pytest.mark.parametrize("entry", ["design_delay", "design_delay_global", "min_recovery_level", "as_language"])
def test_a_zero_one_word_list_is_refused_where_both_readings_apply(acc, entry):
    calls = {"design_delay": lambda: eqrec.design_delay(acc, ZERO_ONE, 1.0),
             "design_delay_global": lambda: eqrec.design_delay_global(acc, ZERO_ONE),
             "min_recovery_level": lambda: eqrec.min_recovery_level(acc, ZERO_ONE),
             "as_language": lambda: eqrec.as_language(ZERO_ONE)}
    with pytest.raises(InputError) as info:
        calls[entry]()
    text = str(info.value)
    assert "missing-data words" in text and "delay words" in text
    assert "kind='missing'" in text and "kind='delay'" in text and "eqrec.missing_words" in text


def test_the_missing_reading_is_the_prefix_design_of_the_same_words(acc):
    prefix = eqrec.design_prefix(acc, L1, 1.0)
    by_kind = eqrec.design_delay(acc, L1, 1.0, kind="missing", cost="max")
    typed = eqrec.design_delay(acc, eqrec.missing_words(L1), 1.0, cost="max")
    spelled_as_delays = eqrec.design_delay(acc, L1_AS_DELAYS, 1.0, cost="max")  # digit 6: delay words, no kind
    assert set(by_kind.patterns) == set(prefix.patterns) == set(typed.patterns) == set(spelled_as_delays.patterns)
    assert by_kind.mu2 == pytest.approx(prefix.mu2, rel=1e-9)
    assert typed.mu2 == by_kind.mu2 == spelled_as_delays.mu2


def test_the_delay_reading_is_another_language(acc):
    missing = eqrec.design_delay_global(acc, ZERO_ONE, kind="missing")
    delay = eqrec.design_delay_global(acc, ZERO_ONE, kind="delay")
    typed = eqrec.design_delay_global(acc, eqrec.delay_words(ZERO_ONE))
    # as delay words 0111 is "y(0) on time, y(1), y(2) one step late, y(3) past the horizon"
    assert eqrec.delay_words(["0111"])[0].arrivals == (0, 2, 3, None)
    assert eqrec.missing_words(["0111"])[0].arrivals == (None, 1, 2, 3)
    assert set(delay.design.patterns) == set(typed.design.patterns) != set(missing.design.patterns)
    assert delay.mu1 == typed.mu1 != pytest.approx(missing.mu1, rel=1e-3)
    assert missing.mu1 == pytest.approx(eqrec.min_recovery_level(acc, ZERO_ONE, kind="missing").upper, rel=1e-12)


def test_unknown_kind_is_refused(acc):
    with pytest.raises(InputError, match="unknown word kind") as info:
        eqrec.design_delay(acc, ZERO_ONE, 1.0, kind="late")
    assert info.value.field == "kind"


def test_missing_data_entries_read_zero_one_strings_as_missing_data(acc):
    assert eqrec.validate_language(ZERO_ONE) == tuple(ZERO_ONE)
    with pytest.raises(InputError, match="outside the alphabet"):
        eqrec.design_prefix(acc, ["0120"], 1.0)  # a delay word is not a missing-data word
    d = eqrec.design_prefix(acc, eqrec.delay_words(L1_AS_DELAYS), 1.0)  # typed delay patterns are accepted
    assert d.mu2 == pytest.approx(eqrec.design_prefix(acc, L1, 1.0).mu2, rel=1e-9)


MIXED = ["1111", "011"]


@pytest.mark.parametrize("entry", ["design_prefix", "design_time_based", "design_augmented"])
def test_words_of_mixed_lengths_are_refused_as_on_the_command_line(acc, entry, tmp_path, capsys):
    with pytest.raises(InputError) as info:
        getattr(eqrec, entry)(acc, MIXED, 1.0)
    assert info.value.field == "words"
    python_text = str(info.value).split("field 'words': ", 1)[1]
    assert main(["design", str(ACC_FILE), "--words", ",".join(MIXED), "--method",
                 {"design_prefix": "prefix", "design_time_based": "time", "design_augmented": "augmented"}[entry]]) == 1
    cli_text = capsys.readouterr().err.split("field '--words': ", 1)[1].strip()
    assert python_text == cli_text == "words of mixed lengths [3, 4] in a fixed-length language: ['1111', '011']"


def test_delay_words_of_mixed_lengths_are_refused_as_on_the_command_line(acc, capsys):
    with pytest.raises(InputError) as info:
        eqrec.design_delay(acc, ["0600", "06000"], 1.0)
    assert main(["design", str(ACC_FILE), "--method", "delay", "--delays", "0600,06000"]) == 1
    cli_text = capsys.readouterr().err.split("field '--delays': ", 1)[1].strip()
    assert str(info.value).split("field 'patterns': ", 1)[1] == cli_text


def test_a_finite_length_language_is_designed_when_asked(acc):
    d = eqrec.design_prefix(acc, ["1011", "11011", "111011"], 1.0, fixed_length=False)
    assert sorted(len(w) for w in d.words) == [4, 5, 6] and d.certificate.terminal <= 1.0 + 1e-6
    with pytest.raises(InputError, match="mixed lengths"):
        eqrec.design_prefix(acc, eqrec.PrefixTree(["1011", "11011"]), 1.0)  # a tree is checked too


# --- 2. every bad Python input is an InputError naming its field ------------------------------------------------

def _plant(**changes):
    fields = dict(A=[[1.0, 0.1], [0.0, 1.0]], C=[[1.0, 0.0]], E=[[0.0], [0.1]], eta_w=0.1, eta_v=0.05)
    fields.update(changes)
    return eqrec.AffineSystem(**{k: v for k, v in fields.items() if v is not _DROP})


_DROP = object()
NAN, INF = float("nan"), float("inf")

BAD_SYSTEMS = [
    ({"eta_w": _DROP}, "eta_w", "missing required field"), ({"eta_v": _DROP}, "eta_v", "missing required field"),
    ({"A": _DROP}, "A", "missing required field"),
    ({"A": "[[1, 0], [0, 1]]"}, "A", "numbers"), ({"C": [["1", "0"]]}, "C", "numbers"),
    ({"E": [[0.0], [NAN]]}, "E", "NaN"), ({"A": [[1.0, INF], [0.0, 1.0]]}, "A", "NaN or infinite"),
    ({"f": "x"}, "f", "numbers"), ({"f": [0.0, NAN]}, "f", "NaN"), ({"B": [[0.0], [INF]]}, "B", "NaN"),
    ({"eta_w": NAN}, "eta_w", "finite"), ({"eta_v": INF}, "eta_v", "finite"), ({"eta_w": -0.1}, "eta_w", "non-negative"),
    ({"eta_w": "0.1"}, "eta_w", "number"), ({"eta_v": True}, "eta_v", "number"), ({"E": [[1j], [0.0]]}, "E", "complex"),
    ({"name": 3}, "name", "string"),
]


@pytest.mark.parametrize("changes, field, text", BAD_SYSTEMS, ids=[f"{f}-{t}" for _, f, t in BAD_SYSTEMS])
def test_a_bad_system_is_an_input_error_naming_the_field(changes, field, text):
    with pytest.raises(InputError, match=text) as info:
        _plant(**changes)
    assert info.value.field == field


def _bad_design_calls(acc):
    w = ["101111", "110111"]
    return [
        (lambda: eqrec.design_prefix(acc, w, 1.0, solver="gurobi"), "solver"),
        (lambda: eqrec.design_time_based(acc, w, 1.0, solver="gurobi"), "solver"),
        (lambda: eqrec.design_delay(acc, L1_AS_DELAYS, 1.0, solver="gurobi"), "solver"),
        (lambda: eqrec.design_delay_global(acc, L1_AS_DELAYS, solver=["highs"]), "solver"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, solver="gurobi"), "solver"),
        (lambda: eqrec.design_prefix(acc, w, "one"), "mu1"),
        (lambda: eqrec.design_prefix(acc, w, None), "mu1"),
        (lambda: eqrec.design_prefix(acc, w, True), "mu1"),
        (lambda: eqrec.design_prefix(acc, w, -1.0, engine="tree"), "mu1"),
        (lambda: eqrec.design_time_based(acc, w, NAN), "mu1"),
        (lambda: eqrec.design_delay(acc, L1_AS_DELAYS, "1"), "mu1"),
        (lambda: eqrec.design_delay(acc, L1_AS_DELAYS, INF, engine="tree"), "mu1"),
        (lambda: eqrec.design_augmented(acc, w, "1"), "mu1"),
        (lambda: eqrec.design_prefix("acc.yaml", w, 1.0), "system"),
        (lambda: eqrec.design_delay_global(None, L1_AS_DELAYS), "system"),
        (lambda: eqrec.design_prefix(acc, 101111, 1.0), "words"),
        (lambda: eqrec.design_prefix(acc, None, 1.0), "words"),
        (lambda: eqrec.design_prefix(acc, w, 1.0, engine="tree", form="robust"), "form"),
        (lambda: eqrec.design_prefix(acc, w, 1.0, engine="tree", T="6"), "T"),
        (lambda: eqrec.design_delay_global(acc, L1_AS_DELAYS, rtol="small"), "rtol"),
        (lambda: eqrec.min_recovery_level(acc, L1_AS_DELAYS, lower_rtol=2.0), "lower_rtol"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, L=[["a", "b"]] * 3), "L"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, L=np.full((3, 2), NAN)), "L"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, s0=["0", "0", "0"]), "s0"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, s0=[NAN, 0.0, 0.0]), "s0"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, poles=["a", "b", "c"]), "poles"),
        (lambda: eqrec.design_augmented(acc, w, 1.0, poles=[INF, 0.0, 0.0]), "poles"),
    ]


def test_bad_design_inputs_are_input_errors_naming_the_field(acc):
    for k, (call, field) in enumerate(_bad_design_calls(acc)):
        with pytest.raises(InputError) as info:
            call()
        assert info.value.field == field, (k, field, str(info.value))


def test_an_unknown_solver_lists_the_choices_and_is_still_a_value_error(acc):
    with pytest.raises(ValueError) as info:
        eqrec.design_prefix(acc, L1, 1.0, solver="gurobi")
    assert isinstance(info.value, InputError) and info.value.field == "solver"
    assert "'gurobi'" in str(info.value) and all(name in str(info.value) for name in ("highs", "clarabel", "ipopt"))


# --- 3. per-channel noise bounds ----------------------------------------------------------------------------------

MOTOR = dict(A=[[1.0, 0.1, 0.0], [0.0, 0.95, 0.08], [0.0, -0.05, 0.6]], C=[[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]],
             E=np.eye(3))
ETA_W = [0.01, 0.05, 0.2]
ETA_V = [0.02, 0.1]


def test_per_channel_bounds_are_the_design_of_the_rescaled_system():
    vec = eqrec.AffineSystem(**MOTOR, eta_w=ETA_W, eta_v=ETA_V)
    rescaled = eqrec.AffineSystem(**{**MOTOR, "E": np.eye(3) @ np.diag(ETA_W)}, V=np.diag(ETA_V), eta_w=1.0,
                                  eta_v=1.0)
    assert np.array_equal(vec.E, rescaled.E) and np.array_equal(vec.V, rescaled.V)
    assert vec.eta_w == vec.eta_v == 1.0
    d_vec = eqrec.design_prefix(vec, ["1011", "1101"], 3.0)
    d_rescaled = eqrec.design_prefix(rescaled, ["1011", "1101"], 3.0)
    assert np.array_equal(d_vec.class_levels, d_rescaled.class_levels)
    assert d_vec.certificate.mu2 == d_rescaled.certificate.mu2
    # the box lies strictly between the scalar boxes of the smallest and the largest bound
    levels = [eqrec.min_recovery_level(plant, ["1011", "1101"], kind="missing").upper for plant in (
        eqrec.AffineSystem(**MOTOR, eta_w=min(ETA_W), eta_v=min(ETA_V)), vec,
        eqrec.AffineSystem(**MOTOR, eta_w=max(ETA_W), eta_v=max(ETA_V)))]
    assert levels[0] < levels[1] < levels[2]


def test_a_scalar_bound_keeps_the_matrices_and_equal_entries_are_the_scalar():
    plant = eqrec.AffineSystem(**MOTOR, eta_w=0.05, eta_v=0.1)
    assert plant.eta_w == 0.05 and np.array_equal(plant.E, np.eye(3)) and np.array_equal(plant.V, np.eye(2))
    same = eqrec.AffineSystem(**MOTOR, eta_w=[0.05] * 3, eta_v=np.array([0.1, 0.1]))
    assert same == plant


@pytest.mark.parametrize("changes, field, text", [
    ({"eta_w": [0.1, 0.2]}, "eta_w", "3 entries"), ({"eta_v": [0.1, 0.2, 0.3]}, "eta_v", "2 entries"),
    ({"eta_w": [0.1, -0.2, 0.3]}, "eta_w", "non-negative"), ({"eta_w": [0.1, NAN, 0.3]}, "eta_w", "NaN"),
    ({"eta_v": ["0.1", "0.2"]}, "eta_v", "numbers"), ({"eta_w": [[0.1, 0.2, 0.3]]}, "eta_w", "dimensions")])
def test_a_bad_bound_vector_names_the_field(changes, field, text):
    with pytest.raises(InputError, match=text) as info:
        eqrec.AffineSystem(**{**MOTOR, "eta_w": ETA_W, "eta_v": ETA_V, **changes})
    assert info.value.field == field


SYSTEM_FILE = """A: [[1, 0.1, 0], [0, 0.95, 0.08], [0, -0.05, 0.6]]
C: [[1, 0, 0], [0, 0, 1]]
E: [[1, 0, 0], [0, 1, 0], [0, 0, 1]]
eta_w: {eta_w}
eta_v: [0.02, 0.1]
"""


def test_per_channel_bounds_in_a_system_file(tmp_path, capsys):
    good = tmp_path / "motor.yaml"
    good.write_text(SYSTEM_FILE.format(eta_w="[0.01, 0.05, 0.2]"))
    system, _ = eqrec.load_system(good)
    assert system == eqrec.AffineSystem(**MOTOR, eta_w=ETA_W, eta_v=ETA_V, name="motor")
    assert main(["design", str(good), "--words", "1011,1101"]) == 0
    out = capsys.readouterr().out
    assert '"mu2"' in out
    for value, text in (("[0.01, 0.05]", "3 entries"), ("[0.01, -0.05, 0.2]", "non-negative"),
                        ("[0.01, 1e-9, 0.2]", "below"), ("[[0.01], [0.05], [0.2]]", "flat list")):
        bad = tmp_path / "bad.yaml"
        bad.write_text(SYSTEM_FILE.format(eta_w=value))
        with pytest.raises(InputError, match=text) as info:
            eqrec.load_system(bad)
        assert info.value.field == "eta_w" and info.value.source == str(bad)
        assert main(["design", str(bad), "--words", "1011,1101"]) == 1
        err = capsys.readouterr().err
        assert "bad.yaml: field 'eta_w'" in err and "Traceback" not in err


# --- 4. per-state weights for the bound ---------------------------------------------------------------------------

WEIGHTS = np.array([1.0, 2.0, 0.5])


def test_a_weighted_design_is_the_design_of_the_scaled_system(acc):
    weighted = eqrec.design_prefix(acc, L1, 1.0, state_weights=WEIGHTS)
    scaled = eqrec.design_prefix(acc.scaled(WEIGHTS), L1, 1.0)
    assert weighted.mu2 == scaled.mu2 and weighted.system == acc.scaled(WEIGHTS)
    assert np.array_equal(weighted.state_weights, WEIGHTS) and scaled.state_weights is None
    assert weighted.mu2 != pytest.approx(eqrec.design_prefix(acc, L1, 1.0).mu2, rel=1e-3)
    S = acc.scaled(WEIGHTS)
    W = np.diag(WEIGHTS)
    assert np.allclose(S.A, W @ acc.A @ np.linalg.inv(W)) and np.allclose(S.C, acc.C @ np.linalg.inv(W))
    assert np.allclose(S.B, W @ acc.B) and np.allclose(S.E, W @ acc.E) and np.allclose(S.f, W @ acc.f)
    entries = (lambda plant, w: eqrec.design_time_based(plant, L1, 1.0, state_weights=w),
               lambda plant, w: eqrec.design_delay(plant, L1_AS_DELAYS, 1.0, cost="max", state_weights=w),
               lambda plant, w: eqrec.design_delay_global(plant, L1_AS_DELAYS, state_weights=w).design)
    for entry in entries:
        d = entry(acc, WEIGHTS)
        reference = entry(acc.scaled(WEIGHTS), None)
        assert (d.mu1, d.mu2) == (reference.mu1, reference.mu2) and np.array_equal(d.state_weights, WEIGHTS)


@pytest.mark.parametrize("weights, text", [([1.0, 2.0], "3 positive"), ([1.0, 0.0, 1.0], "positive"),
                                           ([1.0, -2.0, 1.0], "positive"), ([1.0, NAN, 1.0], "NaN"),
                                           (["1", "2", "3"], "numbers")])
def test_bad_state_weights_name_the_field(acc, weights, text):
    with pytest.raises(InputError, match=text) as info:
        eqrec.design_prefix(acc, L1, 1.0, state_weights=weights)
    assert info.value.field == "state_weights"


@pytest.mark.parametrize("method", ["prefix", "delay"])
def test_monte_carlo_the_weighted_error_stays_within_the_bound(acc, method):
    if method == "prefix":
        design = eqrec.design_prefix(acc, L1, 1.0, state_weights=WEIGHTS)
    else:
        design = eqrec.design_delay_global(acc, L1_AS_DELAYS, state_weights=WEIGHTS).design
    rng = np.random.default_rng(24)
    T, worst = design.T, 0.0
    for run in range(40):
        x = rng.normal(size=3) * 5.0
        e0 = rng.choice([-1.0, 1.0], size=3) * design.mu1 / WEIGHTS  # a corner of max_i w_i |e_i| <= mu1
        est = design.estimator().reset(x - e0)
        for period in range(3):
            word = L1[rng.integers(len(L1))]
            for t in range(T):
                u = np.array([rng.uniform(-1.0, 1.0)])
                y = acc.C @ x + acc.V @ rng.choice([-1.0, 1.0], size=acc.nv) * acc.eta_v
                xhat, bound = est.step(y if word[t] == "1" else None, u)
                x = acc.A @ x + acc.B @ u + acc.f + acc.E @ rng.choice([-1.0, 1.0], size=acc.nw) * acc.eta_w
                ratio = np.max(WEIGHTS * np.abs(x - xhat)) / bound
                worst = max(worst, ratio)
                assert ratio <= 1.0 + 1e-9, (run, period, t)
                assert np.array_equal(xhat, est.x) and np.all(np.abs(x - xhat) <= est.state_bounds * (1 + 1e-9))
    assert worst > 0.3  # the bound is not vacuous on these runs
    assert est.time == 3 * T and est.mu1 == design.mu1  # the wrapped estimator's own attributes pass through


def test_the_cli_writes_a_weighted_design_in_the_files_coordinates(tmp_path):
    import json

    from eqrec.bounds.gains import schedule_from_word_gains
    from eqrec.estimators.guaranteed import GuaranteedEstimator

    out = tmp_path / "w.json"
    assert main(["design", str(ACC_FILE), "--words", ",".join(L1), "--state-weights", "1,2,0.5",
                 "--out", str(out)]) == 0
    record = json.loads(out.read_text())
    acc, _ = eqrec.load_system(ACC_FILE)
    design = eqrec.design_prefix(acc, L1, 1.0, state_weights=WEIGHTS)
    assert record["state_weights"] == WEIGHTS.tolist() and record["mu2"] == design.mu2
    for row, K in zip(record["classes"], design.class_gains.K):
        assert np.allclose(np.asarray(row["K"]).reshape(K.shape), K / WEIGHTS[:, None], rtol=1e-12, atol=0)
    # the file's gains run on the file's system give the weighted design's estimates
    gains = {w: (np.asarray(g["F"]), np.asarray(g["u0"])) for w, g in record["gains"].items()}
    schedule = schedule_from_word_gains(eqrec.PrefixTree(list(gains), kind="missing"), gains, acc.n, acc.p)
    plain = GuaranteedEstimator(acc, schedule, lambda prefix: design.mu2, design.mu1).reset(np.ones(3))
    weighted = design.estimator().reset(np.ones(3))
    rng = np.random.default_rng(3)
    for t, bit in enumerate("101111" * 2):
        y = rng.normal(size=2) if bit == "1" else None
        u = rng.normal(size=1)
        assert np.allclose(plain.step(y, u)[0], weighted.step(y, u)[0], rtol=1e-9, atol=1e-12), t


def test_the_cli_refuses_bad_state_weights(capsys):
    for args in (["--state-weights", "1,2"], ["--state-weights", "1,x,2"], ["--state-weights", "1,0,2"],
                 ["--method", "augmented", "--state-weights", "1,1,1"]):
        assert main(["design", str(ACC_FILE), "--words", ",".join(L1), *args]) == 1
        assert "field '--state-weights'" in capsys.readouterr().err


# --- 5. mu1 free for the prefix (and time-based) method -----------------------------------------------------------

def test_prefix_mu1_free_is_the_class_engines_global_optimum(acc):
    free = eqrec.design_prefix(acc, L1, "free")
    mm = eqrec.min_recovery_level(acc, L1, kind="missing")
    # the stored μ1 is the LP's upper end raised, if at all, to what the gains certify (no tolerance on that side)
    assert mm.upper <= free.mu1 <= mm.upper * (1 + 1e-12) and free.mu1_free.mu1_min_lower == mm.lower
    assert free.mu1_free.route == "global" and free.mu1_free.binding == mm.binding
    assert free.mu2 == eqrec.design_prefix(acc, L1, mm.upper).mu2
    assert free.mu2 == pytest.approx(0.3991, abs=5e-5)  # the delayed-data paper's footnote on the same language
    # the same μ1 as the delayed-data route on the same language, and nothing below it is feasible
    assert free.mu1 == pytest.approx(eqrec.design_delay_global(acc, L1, kind="missing").mu1, rel=1e-12)
    with pytest.raises(eqrec.InfeasibleDesign):
        eqrec.design_prefix(acc, L1, mm.lower)
    assert free.certificate.terminal <= free.mu1
    tree = eqrec.design_prefix(acc, L1, "free", engine="tree")
    assert tree.mu1 == pytest.approx(free.mu1, rel=1e-12) and tree.mu2 == pytest.approx(free.mu2, rel=1e-7)
    time_based = eqrec.design_time_based(acc, L1, "free")
    assert time_based.mu1 == eqrec.min_recovery_level(acc, [time_based.worst_case_word], kind="missing").upper


def test_cli_prefix_mu1_free(tmp_path, capsys):
    import json

    out = tmp_path / "free.json"
    assert main(["design", str(ACC_FILE), "--words", ",".join(L1), "--mu1", "free", "--out", str(out)]) == 0
    record = json.loads(out.read_text())
    system, _ = eqrec.load_system(ACC_FILE)
    upper = eqrec.min_recovery_level(system, L1, kind="missing").upper
    assert upper <= record["mu1"] <= upper * (1 + 1e-12)  # raised, if at all, to what the gains certify
    assert record["mu1_free"]["mu1_min"]["lower"] < record["mu1_free"]["mu1_min"]["upper"] <= record["mu1"]
    assert record["certified_terminal"] <= record["mu1"]
    assert main(["design", str(ACC_FILE), "--words", ",".join(L1), "--method", "augmented", "--mu1", "free"]) == 1
    assert "'free' applies to --method prefix, time, delay only" in capsys.readouterr().err


# --- 6. an infeasible μ1 names the true smallest feasible μ1 -------------------------------------------------------

def _number_after(text: str, before: str) -> str:
    import re

    found = re.search(re.escape(before) + r" ([0-9][0-9.e+-]*[0-9])", text)
    assert found is not None, text
    return found.group(1)


@pytest.mark.parametrize("engine", ["classes", "tree"])
def test_retrying_at_the_printed_smallest_mu1_succeeds(engine):
    plant = eqrec.AffineSystem(**MOTOR, eta_w=0.01, eta_v=0.02)
    words = ["1011", "1101"]
    with pytest.raises(eqrec.InfeasibleDesign) as info:
        eqrec.design_prefix(plant, words, 0.1, engine=engine)
    text = str(info.value)
    printed = _number_after(text, "the smallest feasible mu1 is")
    assert f"retry with mu1 >= {printed} or --mu1 free" in text
    mu1_min = eqrec.min_recovery_level(plant, words, kind="missing").upper
    assert float(printed) >= mu1_min and float(printed) == pytest.approx(mu1_min, rel=1e-5)
    if engine == "classes":  # the class's worst case at the requested μ1 is not a level to retry at
        worst = float(_number_after(text, "has smallest worst case"))
        assert worst < mu1_min
        with pytest.raises(eqrec.InfeasibleDesign):
            eqrec.design_prefix(plant, words, worst, engine=engine)
    last_digit = 10.0 ** (np.floor(np.log10(float(printed))) - 5)  # one unit of the last printed digit
    for retry in (float(printed), float(printed) + last_digit):
        assert eqrec.design_prefix(plant, words, retry, engine=engine).certificate.terminal <= retry * (1 + 1e-6)


def test_the_delay_design_and_the_cli_name_the_smallest_mu1(tmp_path, capsys):
    plant = eqrec.AffineSystem(**MOTOR, eta_w=0.01, eta_v=0.02)
    with pytest.raises(eqrec.InfeasibleDesign, match="the smallest feasible mu1 is") as info:
        eqrec.design_delay(plant, ["0200", "0020"], 0.01)
    printed = float(_number_after(str(info.value), "the smallest feasible mu1 is"))
    assert eqrec.design_delay(plant, ["0200", "0020"], printed).mu1 == printed
    system, _ = eqrec.load_system(ACC_FILE)
    assert main(["design", str(ACC_FILE), "--words", "101111", "--mu1", "0.05"]) == 3
    err = capsys.readouterr().err
    printed = float(_number_after(err, "the smallest feasible mu1 is"))
    assert printed == pytest.approx(eqrec.min_recovery_level(system, ["101111"], kind="missing").upper, rel=1e-5)
    out = tmp_path / "retry.json"
    assert main(["design", str(ACC_FILE), "--words", "101111", "--mu1", str(printed), "--out", str(out)]) == 0


# --- 7. small items -----------------------------------------------------------------------------------------------

def test_help_explains_certified_terminal():
    import subprocess
    import sys

    text = subprocess.run([sys.executable, "-m", "eqrec", "design", "--help"], capture_output=True, text=True,
                          check=True).stdout
    explained = " ".join(text.split()).split("certified_terminal (", 1)[1]
    assert explained.startswith("the worst case of the error norm ||x(T) - xhat(T)||_inf at the end of the horizon")
    assert "recomputed from the gains alone: equalized recovery holds when it is at most mu1" in explained


def test_delay_classes_and_packet_are_public(acc):
    from eqrec.estimators.causal import Packet
    from eqrec.design.delay.design import delay_classes

    assert eqrec.delay_classes is delay_classes and eqrec.Packet is Packet
    assert "delay_classes" in eqrec.__all__ and "Packet" in dir(eqrec)
    classes = eqrec.delay_classes(max_delay=2, horizon=5)
    assert len(classes) == 18 and classes.words == 243
    design = eqrec.design_delay_global(acc, ["100000", "000000"], kind="delay").design  # y(0) on time or late
    late = design.estimator().reset(np.zeros(3))
    on_time = design.estimator().reset(np.zeros(3))
    y0, y1 = np.array([1.0, 2.0]), np.array([1.5, 2.5])
    x_late, _ = late.step(None)  # y(0) one step late ...
    x_on_time, _ = on_time.step(y0)
    assert not np.allclose(x_late, x_on_time)
    xhat_late, bound_late = late.step([eqrec.Packet(0, y0), eqrec.Packet(1, y1)])  # ... arrives with y(1)
    xhat, bound = on_time.step(y1)
    assert late.time == on_time.time == 2
    # the same data by time 1: one class, one level (the rounding allowances differ in the last bits: they follow the data)
    assert np.allclose(xhat_late, xhat, rtol=1e-12) and bound_late == pytest.approx(bound, rel=1e-12)
