"""Director forces and consistent nodal loads, MODEL.md §6 / thesis (2.158)-(2.202), (2.256)-(2.265)."""
import numpy as np
import pytest

from layershell.dofs import number_dofs
from layershell.loads import (director_forces_distribution, director_vector_face, director_vector_power,
                              director_vector_volume, external_forces)
from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import EdgeLoad, Layer, Model, SurfaceLoad

H = 1.7


@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_load_from_opposite_power_2_174(k):
    want = [1, H / (k + 2), 2 * H**2 / ((k + 2) * (k + 3)), 6 * H**3 / ((k + 2) * (k + 3) * (k + 4))]
    assert np.allclose(director_vector_power(H, k, 3, from_opposite=True), want)


@pytest.mark.parametrize("k", [0, 1, 2, 3])
def test_load_power_2_179(k):
    want = [1, (k + 1) / (k + 2) * H, (k + 1) / (k + 3) * H**2, (k + 1) / (k + 4) * H**3]
    assert np.allclose(director_vector_power(H, k, 3), want)


def test_special_rows():
    assert np.allclose(director_vector_power(H, 1, 3, True), [1, H / 3, H**2 / 6, H**3 / 10])  # (2.176)
    assert np.allclose(director_vector_power(H, 1, 3), [1, 2 / 3 * H, 2 / 4 * H**2, 2 / 5 * H**3])  # (2.181)
    assert np.allclose(director_vector_power(H, 0, 3), [1, H / 2, H**2 / 3, H**3 / 4])  # (2.182)
    assert np.allclose(director_vector_face(np.array(H), 3, "bottom"), [1, 0, 0, 0])  # (2.175)
    assert np.allclose(director_vector_face(np.array(H), 3, "top"), [1, H, H**2, H**3])  # (2.180)
    assert np.allclose(director_vector_volume(np.array(H), 3), [H, H**2 / 2, H**3 / 3, H**4 / 4])  # (2.183)
    # truncation for smaller d
    assert np.allclose(director_vector_face(np.array(H), 1, "top"), [1, H])


@pytest.mark.parametrize("coeffs, want", [
    ([16, -120, 240, -140], [1, 0, 0, 0]),       # (2.192)
    ([-120, 1200, -2700, 1680], [0, 1, 0, 0]),   # (2.196) with +1200 t (erratum E4)
    ([240, -2700, 6480, -4200], [0, 0, 1, 0]),   # (2.198)
    ([-140, 1680, -4200, 2800], [0, 0, 0, 1]),   # (2.200)
    ([-4, 60, -180, 140], [1, 1, 1, 1]),         # (2.202)
])
def test_inverse_relation_cubic_loads(coeffs, want):
    """The cubic loads of (2.184)-(2.202) (H = 1) give back unit director forces."""
    fn = lambda theta3, **kw: sum(c * theta3**i for i, c in enumerate(coeffs))
    assert np.allclose(director_forces_distribution(fn, 0.0, 1.0, 3), want, atol=1e-9)


def test_erratum_E4_sign_matters():
    fn = lambda theta3, **kw: -120 - 1200 * theta3 - 2700 * theta3**2 + 1680 * theta3**3  # as printed
    assert not np.allclose(director_forces_distribution(fn, 0.0, 1.0, 3), [0, 1, 0, 0], atol=1e-3)


def test_4_1_minus_t_cubed_2_193():
    fn = lambda theta3, **kw: 4 * (1 - theta3) ** 3
    assert np.allclose(director_forces_distribution(fn, 0.0, 1.0, 3), [1, 0.2, 1 / 15, 1 / 35])


def test_parabolic_end_shear_3_92():
    p = 100.0
    fn = lambda theta3, **kw: 6 * p * (0.25 - (theta3 - 0.5) ** 2)
    assert np.allclose(director_forces_distribution(fn, 0.0, 1.0, 3), [p, 0.5 * p, 0.3 * p, 0.2 * p])


def _square_model(d=3, **kw):
    mesh = rectangle(1.0, 1.0, 1, 1)
    ly = Layer("l", Orthotropic.isotropic(1.0, 0.2), d, np.full(mesh.n_nodes, 0.2))
    return Model(mesh, [ly], [(0,)], np.zeros(1, int), **kw)


def test_consistent_nodal_loads_unit_square_2_263():
    """Constant unit load on a unit square: 1/36 at corners, 4/36 mid-sides, 16/36 centre."""
    m = _square_model(surface_loads=[SurfaceLoad(np.array([0]), "reference", np.array([0, 0, 1.0]),
                                                 lambda x, y, z: np.ones_like(x))])
    dm = number_dofs(m)
    F, _ = external_forces(m, dm)
    Fz = F[dm.layer_dofs[0][m.mesh.elements[0], 0, 2]]
    assert np.allclose(Fz * 36, [1, 1, 1, 1, 4, 4, 4, 4, 16])
    assert np.allclose(F[dm.layer_dofs[0][:, 1:]], 0)  # reference-face load: slot 0 only


def test_top_face_load_uses_powers_of_H():
    m = _square_model(surface_loads=[SurfaceLoad(np.array([0]), "top", None, lambda x, y, z: 2.0 + 0 * x)])
    dm = number_dofs(m)
    F, _ = external_forces(m, dm)
    tot = F[dm.layer_dofs[0][:, :, 2]].sum(0)
    assert np.allclose(tot, 2.0 * 0.2 ** np.arange(4))


def test_edge_load_constant_on_straight_edge():
    mesh_edge = np.array([[1, 5, 2]])  # x = 1 edge of the unit square (VTK order: nodes 1, 5, 2)
    m = _square_model()
    m.edge_loads.append(EdgeLoad(m.mesh.elements[0][mesh_edge], np.array([1.0, 0, 0]),
                                 lambda theta3, **kw: 3.0 + 0 * theta3))
    dm = number_dofs(m)
    F, _ = external_forces(m, dm)
    q = 3.0 * 0.2  # force per edge length in slot 0
    Fx = F[dm.layer_dofs[0][m.mesh.elements[0][[1, 5, 2]], 0, 0]]
    assert np.allclose(Fx, np.array([1 / 6, 2 / 3, 1 / 6]) * q * 1.0)
