import numpy as np
import pytest
import scipy.linalg as sla

from eqrec.errors import InputError
from eqrec.systems.examples import ACC_CONSTANTS, acc_system
from eqrec.systems.files import load_system, system_from_mapping
from eqrec.systems.affine import AffineSystem


def test_acc_matches_exact_zoh_of_continuous_model():
    # Independent derivation: ZOH of  m dve = u - k0 - k1 ve,  dh = vL - ve,  dvL = w  via the matrix exponential.
    c = ACC_CONSTANTS
    Ac = np.array([[-c["k1"] / c["m"], 0, 0], [-1, 0, 1], [0, 0, 0]])
    Bc = np.array([[1 / c["m"], 0.0], [0, 0], [0, 1]])  # columns: force u (f = -k0 u-channel), lead accel w
    M = np.zeros((5, 5))
    M[:3, :3], M[:3, 3:] = Ac, Bc
    Md = sla.expm(M * c["Ts"])
    Ad, Bd = Md[:3, :3], Md[:3, 3:]
    s = acc_system()
    np.testing.assert_allclose(s.A, Ad, atol=1e-12)
    np.testing.assert_allclose(s.B[:, 0], Bd[:, 0], atol=1e-12)
    np.testing.assert_allclose(s.f, -c["k0"] * Bd[:, 0], atol=1e-12)
    # E of the paper is the ZOH of a constant lead acceleration only for the vL row;
    # the headway row Ts^2/2 is the exact double integral of it.
    np.testing.assert_allclose(s.E[:, 0], [0, c["Ts"] ** 2 / 2, c["Ts"]])
    np.testing.assert_allclose(Bd[1:, 1], [c["Ts"] ** 2 / 2, c["Ts"]], atol=1e-12)


def test_dimensions(acc):
    assert (acc.n, acc.p, acc.nw, acc.nv, acc.m) == (3, 2, 1, 2, 1)


@pytest.mark.parametrize("field,kwargs", [
    ("A", dict(A=np.ones((2, 3)))),
    ("C", dict(C=np.ones((2, 4)))),
    ("E", dict(E=np.ones((2, 1)))),
    ("eta_w", dict(eta_w=-1.0)),
    ("V", dict(V=np.ones((3, 3)))),
])
def test_bad_shapes_name_the_field(field, kwargs):
    base = dict(A=np.eye(3), C=np.eye(3)[:2], E=np.ones((3, 1)), eta_w=0.1, eta_v=0.1)
    base.update(kwargs)
    with pytest.raises(InputError, match=f"'{field}'"):
        AffineSystem(**base, source="sys.yaml")


def test_load_system_errors_name_file_and_field(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text("A: [[1, 0], [0, 1]]\nC: [[1, 0]]\nE: [[0], [1]]\neta_w: 0.1\n")
    with pytest.raises(InputError, match=r"s\.yaml.*eta_v"):
        load_system(p)
    p.write_text("A: [[1, 0], [0, 1]]\nC: [[1, 0]]\nE: [[0], [1]]\neta_w: 0.1\neta_v: 0.1\nT: -2\n")
    with pytest.raises(InputError, match="'T'"):
        load_system(p)
    p.write_text("A: [[1, 0], [0, 1]]\nC: [[1, 0]]\nE: [[0], [1]]\neta_w: 0.1\neta_v: 0.1\nZ: 3\n")
    with pytest.raises(InputError, match="unknown field"):
        load_system(p)
    p.write_text(": : :")
    with pytest.raises(InputError, match="YAML"):
        load_system(p)


def test_time_varying_access():
    A = np.stack([np.eye(2) * (1 + k) for k in range(4)])
    s, _ = system_from_mapping(dict(A=A.tolist(), C=[[1, 0]], E=[[1], [0]], eta_w=0.1, eta_v=0.1))
    assert s.is_time_varying and s.horizon_limit == 4
    np.testing.assert_allclose(s.A_at(2), 3 * np.eye(2))
    with pytest.raises(InputError, match="horizon"):
        s.check_horizon(5)


SMALL = "A: [[1, 0.1], [0, 0.9]]\nC: [[1, 0]]\nE: [[0], [0.1]]\neta_v: 0.05\n"


@pytest.mark.parametrize("line", ['eta_w: "0.1"', "eta_w: '0.1'", "eta_w: true", "eta_w: null"])
def test_quoted_or_non_numeric_noise_bound_is_rejected(tmp_path, line):
    p = tmp_path / "s.yaml"
    p.write_text(SMALL + line + "\n")
    with pytest.raises(InputError, match=r"s\.yaml: field 'eta_w': value must be a number"):
        load_system(p)


def test_quoted_matrix_entry_is_rejected_with_its_position(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text(SMALL.replace("[0, 0.9]", '[0, "0.9"]') + "eta_w: 0.1\n")
    with pytest.raises(InputError, match=r"field 'A': entry \[1\]\[1\] must be a number, got '0.9' \(a quoted"):
        load_system(p)
    with pytest.raises(InputError, match="'C'.*strings"):  # programmatic systems too
        AffineSystem(A=np.eye(2), C=[["1", "0"]], E=np.ones((2, 1)), eta_w=0.1, eta_v=0.1)


@pytest.mark.parametrize("value,msg", [("1e308", "exceeds 1e\\+06 in magnitude"), ("1.0e+308", "exceeds"),
                                       (".inf", "must be finite"), (".nan", "must be finite"),
                                       ("1e-12", "below 1e-06")])
def test_noise_bound_out_of_double_precision_lp_range(tmp_path, value, msg):
    # eta_w: 1e308 used to reach the solver and stop with status 'Not Set'
    p = tmp_path / "s.yaml"
    p.write_text(SMALL + f"eta_w: {value}\n")
    with pytest.raises(InputError, match=rf"s\.yaml: field 'eta_w': .*{msg}"):
        load_system(p)


def test_huge_matrix_entry_is_rejected(tmp_path):
    p = tmp_path / "s.yaml"
    p.write_text(SMALL.replace("0.9]", "1.0e+9]") + "eta_w: 0.1\n")
    with pytest.raises(InputError, match=r"field 'A': entry \[1\]\[1\] 1e\+09 exceeds"):
        load_system(p)


def test_exponent_without_dot_is_a_number(tmp_path):
    # YAML 1.1 (PyYAML) reads 5e-2 as a string; the loader reads it as YAML 1.2 does
    p = tmp_path / "s.yaml"
    p.write_text(SMALL.replace("eta_v: 0.05", "eta_v: 5e-2") + "eta_w: 1E-1\n")
    s, _ = load_system(p)
    assert (s.eta_v, s.eta_w) == (0.05, 0.1)
    p.write_text(SMALL + "eta_w: 0\n")  # zero noise is allowed
    assert load_system(p)[0].eta_w == 0.0


def test_mapping_with_arrays_still_loads():
    s, _ = system_from_mapping(dict(A=np.eye(2), C=np.array([[1.0, 0.0]]), E=np.ones((2, 1)),
                                    eta_w=np.float64(0.1), eta_v=np.int64(0)))
    assert s.n == 2 and s.eta_v == 0.0


def test_per_channel_noise_bounds_are_kept_as_given():
    """Issue 33 §3: ``load_system`` keeps the per-channel ``eta_w``/``eta_v`` as given (read-only), next to the
    folded description every computation uses; a scalar bound leaves them ``None``; ``scaled`` keeps them."""
    import eqrec

    plant, _ = eqrec.load_system("examples/two_mass.yaml")
    assert plant.eta_w_channels.tolist() == [0.01, 0.02] and plant.eta_v_channels is None
    assert plant.eta_w == 1.0 and np.array_equal(plant.E[[1, 3]], np.diag([0.01, 0.02]))  # the folded form
    assert not plant.eta_w_channels.flags.writeable
    assert plant.scaled([1.0, 2.0, 3.0, 4.0]).eta_w_channels.tolist() == [0.01, 0.02]
    both = eqrec.AffineSystem(A=np.eye(2), C=[[1.0, 0.0], [0.0, 1.0]], E=np.eye(2), eta_w=0.1,
                              eta_v=[0.05, 0.2])
    assert both.eta_w_channels is None and both.eta_v_channels.tolist() == [0.05, 0.2]
    assert both.eta_v == 1.0 and np.array_equal(both.V, np.diag([0.05, 0.2]))
    same = eqrec.AffineSystem(A=np.eye(2), C=[[1.0, 0.0]], E=np.eye(2), eta_w=[0.3, 0.3], eta_v=0.1)
    assert same.eta_w == 0.3 and same.eta_w_channels is None  # equal entries: the scalar bound
