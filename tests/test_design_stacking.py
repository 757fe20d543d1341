"""A design builds its stacked model once and hands it down (issue 34, "the design's data flow one way").

The LPs, the gains, the certificate, the cost and the fallback to ``μ1,min`` read the one
:class:`~eqrec.bounds.stacking.Stacking` the design built; these tests count the stackings built per design
and check that a handed-down stacking gives the same bytes as one built afresh.
"""
import pickle

import numpy as np
import pytest

import eqrec
from eqrec.bounds import stacking as stacking_module
from eqrec.bounds.certify import certify_design
from eqrec.bounds.data_classes import classes_of_tree
from eqrec.bounds.stacking import Stacking
from eqrec.design.classes.engine import class_design
from eqrec.errors import InfeasibleDesign, InputError

L1_DELAY = ["060000", "006000", "000600", "000060"]
L1_MISSING = ["101111", "110111", "111011", "111101"]


@pytest.fixture
def built(monkeypatch):
    """The horizons of the stackings built while the test runs."""
    horizons = []
    init = Stacking.__init__

    def counting(self, system, T):
        horizons.append(T)
        init(self, system, T)

    monkeypatch.setattr(stacking_module.Stacking, "__init__", counting)
    return horizons


DESIGNS = {
    "delay classes": lambda acc, br: eqrec.design_delay(acc, L1_DELAY, 1.0),
    "delay tree": lambda acc, br: eqrec.design_delay(acc, L1_DELAY, 1.0, engine="tree"),
    "delay max": lambda acc, br: eqrec.design_delay(acc, L1_DELAY, 1.0, cost="max"),
    "delay global": lambda acc, br: eqrec.design_delay_global(br, eqrec.full_delay_language(5, 2)),
    "delay global tree": lambda acc, br: eqrec.design_delay_global(acc, L1_DELAY, engine="tree"),
    "prefix classes": lambda acc, br: eqrec.design_prefix(acc, L1_MISSING, 1.0),
    "prefix tree": lambda acc, br: eqrec.design_prefix(acc, L1_MISSING, 1.0, engine="tree"),
    "prefix free": lambda acc, br: eqrec.design_prefix(acc, L1_MISSING, "free"),
    "time-based": lambda acc, br: eqrec.design_time_based(acc, L1_MISSING, 1.0),
    "augmented": lambda acc, br: eqrec.design_augmented(acc, ["101111", "110111"], 1.0),
}


@pytest.mark.parametrize("name", sorted(DESIGNS))
def test_a_design_builds_one_stacking(name, acc, built):
    DESIGNS[name](acc, eqrec.batch_reactor())
    assert len(built) == 1, f"{name}: stackings of horizons {built}"


def test_an_infeasible_design_names_mu1_min_on_the_same_stacking(built):
    # the fallback to μ1,min (eqrec.design.classes.mu1_min.infeasible_at) reads the design's stacking too
    with pytest.raises(InfeasibleDesign, match="smallest feasible mu1"):
        eqrec.design_delay(eqrec.batch_reactor(), eqrec.full_delay_language(5, 2), 0.01)
    assert built == [5]


def test_a_handed_down_stacking_gives_the_bytes_of_a_fresh_one(acc):
    classes = classes_of_tree(eqrec.PrefixTree(L1_MISSING))
    st = Stacking(acc, classes.horizon)
    st.open_loop, st.output_maps  # its maps computed before the design reads them
    shared = class_design(st, classes, 1.0, levels="sum")
    fresh = class_design(acc, classes, 1.0, levels="sum")
    assert shared.system is acc and shared.mu1 == fresh.mu1 and shared.mu2 == fresh.mu2
    assert shared.levels == fresh.levels
    assert all(a.tobytes() == b.tobytes() for a, b in zip(shared.class_gains.K, fresh.class_gains.K))
    assert shared.class_certificate.bounds.tobytes() == fresh.class_certificate.bounds.tobytes()
    for word, cert in fresh.certificate.words.items():
        assert shared.certificate.words[word].bounds.tobytes() == cert.bounds.tobytes()


def test_stacking_of_reuses_one_of_the_horizon_and_rebuilds_another(acc):
    st = Stacking(acc, 6)
    assert Stacking.of(st, 6) is st
    other = Stacking.of(st, 4)  # the layout of δ depends on T: no map of st serves it
    assert other is not st and other.T == 4 and other.system is acc
    assert Stacking.of(acc, 6) is not st and Stacking.of(acc, 6).T == 6


def test_a_pickled_stacking_ships_its_system_and_rebuilds_its_maps(acc):
    st = Stacking(acc, 6)
    maps = st.open_loop.copy()
    back = pickle.loads(pickle.dumps(st))
    assert "open_loop" not in vars(back)  # the cached maps are not shipped to a worker
    assert back.T == 6 and back.open_loop.tobytes() == maps.tobytes()


def test_certify_design_refuses_a_stacking_of_another_system(acc):
    design = eqrec.design_prefix(acc, L1_MISSING, 1.0)
    before = (design.mu1, design.mu2, dict(design.levels), design.certificate)
    other = Stacking(eqrec.batch_reactor(), design.class_gains.horizon)
    with pytest.raises(InputError) as err:
        certify_design(design, stacking=other)
    assert err.value.field == "stacking"
    assert (design.mu1, design.mu2, dict(design.levels), design.certificate) == before
    # the design's own stacking is accepted and changes nothing
    certify_design(design, stacking=Stacking(acc, design.class_gains.horizon))
    assert design.mu1 == before[0] and design.mu2 == before[1]
    assert np.all(np.isfinite(design.class_certificate.bounds))
