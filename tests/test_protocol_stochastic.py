"""One system description, the stochastic estimators in step form (the protocol of eqrec.core.protocol), and the
one simulation loop running them."""

import numpy as np
import pytest

from eqrec.core.noise import GaussianDesign, GaussianNoise, MultiplicativeNoise, NoisySystem
from eqrec.core.systems import AffineSystem
from eqrec.errors import InputError
from eqrec.filters import kalman
from eqrec.lmv.plant import Plant

EX1 = {"Phi": [[0.8, 0.0], [0.9, 0.2]], "Phi1": [[0.1, 0.05], [0.2, 0.1]], "Gamma": [1.0, 0.5],
       "H": [[1.0, 2.0]], "H1": [[1.0, 2.0]], "Qw": 1.0, "c": 1.0, "Qzeta": 1.0, "Qxi": 2.0, "Qlam": 2.0,
       "sigma0": [0.0, 0.0], "Sigma0": [[1.0, 0.0], [0.0, 1.0]], "name": "Example 1"}


@pytest.fixture(scope="module")
def ex1():
    return Plant.from_dict(EX1)


# ---------------------------------------------------------------------------- one system description

def test_plant_is_a_loader_of_the_one_description(ex1):
    desc = ex1.description()
    sysm, g, mult = desc.system, desc.gaussian, desc.multiplicative
    assert isinstance(sysm, AffineSystem) and (sysm.n, sysm.p, sysm.nw, sysm.nv, sysm.m) == (2, 1, 1, 1, 0)
    np.testing.assert_array_equal(sysm.A, ex1.Phi)
    np.testing.assert_array_equal(sysm.E, ex1.Gamma)
    np.testing.assert_array_equal(g.Qv, [[2.0]])  # v = c w + zeta: Qv = c^2 Qw + Qzeta
    np.testing.assert_array_equal(g.S, [[1.0]])
    np.testing.assert_array_equal(mult.A1, ex1.Phi1)
    assert (mult.Qxi, mult.Qlam) == (2.0, 2.0)
    back = Plant.from_description(desc)
    for key in ex1.__dataclass_fields__:
        a, b = getattr(ex1, key), getattr(back, key)
        assert a == b if isinstance(a, str) else np.array_equal(a, b), key


def test_a_bounded_error_plant_reads_as_an_lmv_plant(acc):
    desc = NoisySystem(acc, GaussianNoise.from_box(acc, mu1=1.0))
    plant = Plant.from_description(desc)
    np.testing.assert_allclose(plant.Qv, (acc.eta_v / 5) ** 2 * np.eye(acc.p))
    np.testing.assert_allclose(plant.Sigma0, np.eye(3) / 25)
    assert plant.Qxi == plant.Qlam == 0.0 and not plant.Phi1.any()
    # the Gaussian statistics of a box are those the Kalman filters are designed with (5 sigma = bound)
    d_box, d_desc = GaussianDesign.from_box(acc, 1.0), desc.design()
    for key in ("P0", "Q", "R"):
        np.testing.assert_allclose(getattr(d_desc, key), getattr(d_box, key), rtol=1e-15, atol=0)
    assert kalman.GaussianDesign is GaussianDesign  # the filters' design statistics are the one description's


@pytest.mark.parametrize("kwargs, field", [
    ({"Qw": [[1.0, 2.0], [2.0, 1.0]], "Qv": 1.0, "x0_cov": np.eye(2)}, "Qw"),
    ({"Qw": 1.0, "Qv": [[np.nan]], "x0_cov": np.eye(2)}, "Qv"),
    ({"Qw": 1.0, "Qv": 1.0, "x0_cov": np.eye(2), "S": [[2.0]]}, "S"),
    ({"Qw": 1.0, "Qv": 1.0, "x0_cov": np.eye(2), "x0_mean": [0.0]}, "x0_mean"),
    ({"Qw": "a", "Qv": 1.0, "x0_cov": np.eye(2)}, "Qw"),
])
def test_bad_gaussian_noise_names_the_field(kwargs, field):
    with pytest.raises(InputError) as exc:
        GaussianNoise(**kwargs)
    assert exc.value.field == field


def test_descriptions_must_fit_the_system(acc):
    with pytest.raises(InputError) as exc:
        NoisySystem(acc, GaussianNoise(Qw=1.0, Qv=1.0, x0_cov=np.eye(3)))  # ACC has p = 2 measurement noises
    assert exc.value.field == "Qv"
    with pytest.raises(InputError) as exc:
        NoisySystem(acc, multiplicative=MultiplicativeNoise(A1=np.zeros((2, 2)), C1=np.zeros((1, 2)), Qxi=1, Qlam=1))
    assert exc.value.field == "multiplicative"
    with pytest.raises(InputError) as exc:
        MultiplicativeNoise(A1=np.eye(2), C1=np.zeros((1, 2)), Qxi=-1.0, Qlam=0.0)
    assert exc.value.field == "Qxi"
    with pytest.raises(InputError) as exc:
        NoisySystem(acc).design()
    assert exc.value.field == "gaussian"
