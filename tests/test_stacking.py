import numpy as np

from eqrec.bounds.stacking import Stacking


def test_open_loop_equals_paper_stacked_form(acc):
    # ξ = J ξ0 + S Ē w when u_e = 0 (eq. (13) with Q = 0, r = 0)
    st = Stacking(acc, 6)
    G, c = st.error_map_from_Q("111111", np.zeros((18, 12)), np.zeros(18))
    np.testing.assert_allclose(st.open_loop.reshape(-1, st.layout.size), G, atol=1e-13)
    np.testing.assert_allclose(c, 0)


def test_output_maps_include_measurement_noise(acc):
    st = Stacking(acc, 3)
    lay = st.layout
    Y = st.output_maps
    np.testing.assert_allclose(Y[1][:, lay.v(1)], np.eye(2))
    np.testing.assert_allclose(Y[1][:, lay.v(0)], 0)
    np.testing.assert_allclose(Y[2][:, lay.xi0], acc.C @ acc.A @ acc.A)


def test_layout_roundtrip():
    st_lay = Stacking.__new__(Stacking)
    from eqrec.bounds.stacking import UncertaintyLayout

    lay = UncertaintyLayout(T=3, nw=1, nv=2, n=3)
    d = np.arange(lay.size, dtype=float)
    w, v, x0 = lay.split(d)
    assert w.shape == (3, 1) and v.shape == (3, 2) and x0.shape == (3,)
    np.testing.assert_allclose(np.concatenate([w.ravel(), v.ravel(), x0]), d)
    assert lay.radius(1, 2, 3).tolist() == [1] * 3 + [2] * 6 + [3] * 3
