"""Issue 41, section 1: a design file cannot lie.

A design JSON (written by ``eqrec design --out`` or :meth:`eqrec.Design.save`) is input: :func:`eqrec.load_design`
certifies every design kind again from the gains and the file's system alone, refuses a stored level, ``μ1`` or
``μ2`` that the gains do not earn, and names the field of every malformed file.  Designs of plants with ``V != I``,
per-channel noise bounds, time-varying matrices and state weights go through a file and back with the same
estimates and bounds.
"""
from __future__ import annotations

import copy
import json
from pathlib import Path

import numpy as np
import pytest

import eqrec
from eqrec.cli import main
from eqrec.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
ACC = ROOT / "examples" / "acc_system.yaml"
REACTOR = ROOT / "examples" / "batch_reactor.yaml"
L1 = "101111,110111,111011,111101"


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """Genuine design files of the CLI: a tree (node gains) design, a class design, a delay tree design."""
    folder = tmp_path_factory.mktemp("designs")
    out = {}
    for name, args in (("tree", f"{ACC} --words {L1} --engine tree"), ("classes", f"{ACC} --words {L1}"),
                       ("delay", f"{REACTOR} --method delay --max-delay 1 --horizon 4 --mu1 2 --engine tree")):
        path = folder / f"{name}.json"
        assert main(["design", *args.split(), "--out", str(path)]) == 0
        out[name] = json.loads(path.read_text())
    return out


def _times(data, factor):
    for gains in data["gains"].values():
        gains["F"] = (factor * np.asarray(gains["F"])).tolist()


def _edit(path):
    def edit(data):
        *keys, last = path
        for k in keys:
            data = data[k]
        data[last] = edit.value
    return edit


#: (genuine file, edit, the field named): every edit is refused.
TAMPERED = {
    "tree: A[0][0] 0.9964 -> 1.2": ("tree", lambda d: d["system"]["A"][0].__setitem__(0, 1.2), "mu2"),
    "tree: every F times 1.3": ("tree", lambda d: _times(d, 1.3), "mu2"),
    "tree: mu2 -> 0.6": ("tree", lambda d: d.__setitem__("mu2", 0.6), "mu2"),
    "tree: mu2 -> 5 (above what the gains earn)": ("tree", lambda d: d.__setitem__("mu2", 5.0), "mu2"),
    "tree: certified_mu2 edited": ("tree", lambda d: d.__setitem__("certified_mu2", 0.9), "certified_mu2"),
    "tree: V = 0.5 I": ("tree", lambda d: d["system"].__setitem__("V", (0.5 * np.eye(2)).tolist()), "mu2"),
    "tree: a gain NaN": ("tree", lambda d: next(iter(d["gains"].values()))["F"][0].__setitem__(0, float("nan")),
                         "gains"),
    "classes: K NaN": ("classes", lambda d: d["classes"][1]["K"][0].__setitem__(0, float("nan")), "classes[1].K"),
    "classes: certified NaN": ("classes", lambda d: d["classes"][1].__setitem__("certified", float("nan")),
                               "classes[1].certified"),
    "classes: certified edited": ("classes", lambda d: d["classes"][1].__setitem__("certified", 0.5),
                                  "classes[1].certified"),
    "classes: level below its worst case": ("classes", lambda d: d["classes"][1].__setitem__("level", 0.5),
                                            "classes[1].level"),
    "classes: mu2 -> 0.6": ("classes", lambda d: d.__setitem__("mu2", 0.6), "mu2"),
    "classes: mu1 -> 2": ("classes", lambda d: d.__setitem__("mu1", 2.0), "classes"),
    "classes: mu1 NaN": ("classes", lambda d: d.__setitem__("mu1", float("nan")), "mu1"),
    "classes: state_weights 'abc'": ("classes", lambda d: d.__setitem__("state_weights", "abc"), "state_weights"),
    "classes: state_weights negative": ("classes", lambda d: d.__setitem__("state_weights", [1, -1, 1]),
                                        "state_weights"),
    "classes: k = 99": ("classes", lambda d: d["classes"][0].__setitem__("k", 99), "classes[0].k"),
    "classes: k missing": ("classes", lambda d: d["classes"][0].pop("k"), "classes[0].k"),
    "classes: data past k": ("classes", lambda d: d["classes"][0].__setitem__("data", [5]), "classes[0].data"),
    "classes: T 6 -> 5": ("classes", lambda d: d.__setitem__("T", 5), "classes[14].k"),
    "classes: V = 3 I": ("classes", lambda d: d["system"].__setitem__("V", (3 * np.eye(2)).tolist()), "classes"),
    "classes: a level above mu2": ("classes", lambda d: d["classes"][3].__setitem__("level", 3.0), "classes[3].level"),
    "classes: J a string": ("classes", lambda d: d.__setitem__("J", "abc"), "J"),
    "delay: a levels row without k": ("delay", lambda d: d["levels"][1].pop("k"), "levels[1].k"),
    "delay: a level halved": ("delay", lambda d: d["levels"][2].__setitem__("level", 1.0), "levels"),
    "delay: a certified level edited": ("delay", lambda d: d["levels"][2].__setitem__("certified", 1.0), "levels"),
    "delay: T 4 -> 3": ("delay", lambda d: d.__setitem__("T", 3), "T"),
    # issue 41 census: accepted before
    "tree: a word with a bad letter": ("tree", lambda d: d.__setitem__("words", ["1x1111"]), "words"),
    "tree: a word dropped": ("tree", lambda d: d["words"].pop(), "words"),
    "classes: a class row dropped": ("classes", lambda d: d["classes"].pop(3), "classes"),
    "classes: a word dropped": ("classes", lambda d: d["words"].pop(), "classes"),
    "delay: J edited": ("delay", lambda d: d.__setitem__("J", 0.1), "J"),
    "delay: J_certified edited": ("delay", lambda d: d.__setitem__("J_certified", 2 * d["J_certified"]),
                                  "J_certified"),
}


@pytest.mark.parametrize("case", list(TAMPERED))
def test_a_file_that_lies_is_refused_naming_the_field(files, tmp_path, case):
    name, edit, field = TAMPERED[case]
    data = copy.deepcopy(files[name])
    edit(data)
    path = tmp_path / "edited.json"
    path.write_text(json.dumps(data))
    with pytest.raises(InputError) as exc:
        eqrec.load_design(path)
    assert exc.value.field == field or exc.value.field.startswith(field + "["), str(exc.value)
    assert exc.value.source == str(path)


@pytest.mark.parametrize("name", ["tree", "classes", "delay"])
def test_the_genuine_files_load_with_their_levels(files, tmp_path, name):
    path = tmp_path / "genuine.json"
    path.write_text(json.dumps(files[name]))
    loaded = eqrec.load_design(path)
    assert (loaded.mu1, loaded.mu2) == (files[name]["mu1"], files[name]["mu2"])
    if loaded.schedule is not None:  # the node gains were certified on loading, exactly
        assert loaded.certificate is not None and loaded.certificate.mu2 <= loaded.mu2
        assert loaded.certificate.terminal <= loaded.mu1


# --- round trips: V != I, per-channel bounds, time-varying matrices, weights ------------------------------------

def _plant(kind):
    A = [[0.9, 0.2, 0.0], [0.0, 0.8, 0.1], [0.1, 0.0, 0.7]]
    C = [[1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    E = [[1.0, 0.0], [0.0, 1.0], [0.5, 0.0]]
    if kind == "V":  # a measurement-noise map that mixes the channels
        return eqrec.AffineSystem(A=A, C=C, E=E, V=[[0.5, 0.2], [0.0, 1.5]], eta_w=0.05, eta_v=0.1, name="V")
    if kind == "channels":  # one bound per noise channel
        return eqrec.AffineSystem(A=A, C=C, E=E, V=[[2.0, 0.0], [0.3, 1.0]], eta_w=[0.05, 0.2],
                                  eta_v=[0.1, 0.01], name="channels")
    T = 4  # time-varying matrices over the horizon
    As = [np.asarray(A) * (1.0 + 0.05 * t) for t in range(T)]
    Vs = [np.eye(2) * (1.0 + 0.5 * t) for t in range(T)]
    return eqrec.AffineSystem(A=As, C=[C] * T, E=[E] * T, V=Vs, eta_w=0.05, eta_v=0.1, name="tv")


WORDS = ["1011", "1101", "0111"]
DESIGNS = {
    "prefix-classes": lambda s, w: eqrec.design_prefix(s, WORDS, 10.0, state_weights=w),
    "prefix-tree": lambda s, w: eqrec.design_prefix(s, WORDS, 10.0, engine="tree", state_weights=w),
    "time": lambda s, w: eqrec.design_time_based(s, WORDS, 10.0, state_weights=w),
    "delay": lambda s, w: eqrec.design_delay(s, ["1000", "0000", "2100"], 10.0, kind="delay", state_weights=w),
}


def _steps(design, rng, periods=3):
    T, system = design.T, design.system
    steps = []
    for _ in range(periods):
        word = design.patterns[rng.integers(len(design.patterns))]
        arrivals = [[] for _ in range(T)]
        for i in range(T):
            if word.arrivals[i] is not None:
                arrivals[word.arrivals[i]].append(i)
        for t in range(T):
            steps.append([(len(steps) - t + i, rng.normal(size=system.p)) for i in arrivals[t]] or None)
    return steps


def _run(estimator, x0, steps):
    estimator.reset(x0)
    out = [estimator.step(packets) for packets in steps]
    return np.array([x for x, _ in out]), np.array([b for _, b in out])


@pytest.mark.parametrize("plant", ["V", "channels", "tv"])
@pytest.mark.parametrize("method", list(DESIGNS))
@pytest.mark.parametrize("weighted", [False, True], ids=["unweighted", "weighted"])
def test_a_saved_design_loads_back_with_the_same_estimates_and_bounds(tmp_path, plant, method, weighted):
    system = _plant(plant)
    weights = np.array([1.0, 3.0, 0.5]) if weighted else None
    design = DESIGNS[method](system, weights)
    path = design.save(tmp_path / "design.json")
    loaded = eqrec.load_design(path)
    assert loaded.method == design.method and loaded.T == design.T
    rng = np.random.default_rng(41)
    steps = _steps(design, rng)
    x0 = rng.uniform(-0.5, 0.5, system.n)
    xs, bounds = _run(design.estimator(), x0, steps)
    xs_loaded, bounds_loaded = _run(loaded.estimator(), x0, steps)
    if weights is None:  # bit for bit
        assert (loaded.mu1, loaded.mu2) == (design.mu1, design.mu2)
        assert loaded.system == design.system
        assert np.array_equal(xs, xs_loaded) and np.array_equal(bounds, bounds_loaded)
    else:  # the file's gains are divided by the weights; multiplying back rounds
        np.testing.assert_allclose(xs_loaded, xs, rtol=1e-10, atol=1e-12)
        assert np.all(bounds_loaded >= bounds) and np.allclose(bounds_loaded, bounds, rtol=1e-10)
    # the file's V and bounds are read: the same file with V = I (or the bounds dropped to 1) is another plant
    data = json.loads(Path(path).read_text())
    assert data["system"]["V"] != np.eye(2).tolist()
    data["system"]["V"] = np.eye(2).tolist() if plant != "tv" else [np.eye(2).tolist()] * design.T
    (tmp_path / "identity.json").write_text(json.dumps(data))
    with pytest.raises(InputError):
        eqrec.load_design(tmp_path / "identity.json")


def test_design_save_writes_what_the_cli_writes(tmp_path):
    cli = tmp_path / "cli.json"
    assert main(["design", str(ACC), "--words", L1, "--out", str(cli)]) == 0
    design = eqrec.design_prefix(eqrec.load_system(ACC)[0], L1.split(","), 1.0)
    saved = design.save(tmp_path / "saved.json")
    assert json.loads(Path(saved).read_text()) == json.loads(cli.read_text())
    assert eqrec.load_design(saved).mu2 == eqrec.load_design(cli).mu2


def test_design_save_refuses_a_path_it_cannot_write(tmp_path):
    design = eqrec.design_prefix(eqrec.acc_system(), ["101111", "110111"], 1.0)
    for path, field in ((tmp_path, "path"), (tmp_path / "no" / "x.json", "path"), (3, "path")):
        with pytest.raises(InputError) as exc:
            design.save(path)
        assert exc.value.field == field
    assert list(tmp_path.iterdir()) == []



@pytest.mark.parametrize("D,T,listed", [(1, 4, True), (2, 10, False)], ids=["words listed", "words counted"])
def test_a_max_delay_class_file_is_checked_against_its_language(tmp_path, D, T, listed):
    """A ``--max-delay`` file's classes are checked against ``delay_classes`` of its ``max_delay``, ``horizon``
    and ``max_lost`` (issue 41 census: a class row dropped was accepted); its listed words and node gains write a
    lost measurement as ``x`` and load (they were refused as "not digits")."""
    path = tmp_path / "window.json"
    assert main(["design", str(REACTOR), "--method", "delay", "--max-delay", str(D), "--horizon", str(T),
                 "--max-lost", "1", "--mu1", "2", "--out", str(path)]) == 0
    data = json.loads(path.read_text())
    assert isinstance(data["words"], list) == listed and data["max_lost"] == 1
    assert not listed or any("x" in w for w in data["words"])
    assert eqrec.load_design(path).J == data["J"]
    for edit in (lambda d: d["classes"].pop(5), lambda d: d.__setitem__("max_lost", 0)):
        edited = copy.deepcopy(data)
        edit(edited)
        (tmp_path / "edited.json").write_text(json.dumps(edited))
        with pytest.raises(InputError) as exc:
            eqrec.load_design(tmp_path / "edited.json")
        assert exc.value.field == "classes"
