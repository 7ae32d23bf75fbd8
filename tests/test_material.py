"""Orthotropic material, MODEL.md §4 (2.143)-(2.150)."""
import numpy as np
import pytest

from layershell.material import MaterialError, Orthotropic, rotate_stiffness, tensor_to_voigt, voigt_to_tensor

TRC = Orthotropic(31426, 26535, 25429, 11520, 11413, 11498, 0.191, 0.221, 0.166)  # data (5.2)
AS3501 = Orthotropic.from_nu13(135000, 8500, 8500, 5150, 5150, 5150, 0.317, 0.317, 0.317)  # data (5.1)


@pytest.mark.parametrize("mat", [TRC, AS3501, Orthotropic.isotropic(30000, 0.17)])
def test_stiffness_is_inverse_of_compliance(mat):
    mat.check()
    C, S = mat.stiffness(), mat.compliance()
    assert np.allclose(C @ S, np.eye(6), atol=1e-12)
    assert np.allclose(C, C.T)


def test_reciprocity_and_uniaxial_response():
    C = TRC.stiffness()
    S = np.linalg.inv(C)
    # uniaxial stress in 1: strain_2/strain_1 = -nu12, strain_3/strain_1 = -nu13 = -nu31 E1/E3
    e = S @ np.array([1.0, 0, 0, 0, 0, 0])
    assert np.isclose(e[0], 1 / TRC.E1)
    assert np.isclose(-e[1] / e[0], TRC.nu12)
    assert np.isclose(-e[2] / e[0], TRC.nu31 * TRC.E1 / TRC.E3)
    e = S @ np.array([0, 0, 1.0, 0, 0, 0])
    assert np.isclose(-e[0] / e[2], TRC.nu31)
    e = S @ np.array([0, 0, 0, 1.0, 0, 0])
    assert np.isclose(e[3], 1 / TRC.G23)


def test_isotropic_lame():
    E, nu = 210000.0, 0.3
    C = Orthotropic.isotropic(E, nu).stiffness()
    lam, mu = E * nu / ((1 + nu) * (1 - 2 * nu)), E / (2 * (1 + nu))
    assert np.isclose(C[0, 0], lam + 2 * mu) and np.isclose(C[0, 1], lam) and np.isclose(C[3, 3], mu)


@pytest.mark.parametrize("bad", [
    dict(E=1.0, nu=0.5), dict(E=1.0, nu=-1.0), dict(E=1.0, nu=0.7), dict(E=-1.0, nu=0.2)])
def test_rejects_non_positive_definite(bad):
    with pytest.raises(MaterialError, match="material"):
        Orthotropic.isotropic(**bad).check()  # raised by isotropic() or by check()


def test_rejects_orthotropic_with_named_constants():
    m = Orthotropic(100, 1, 1, 1, 1, 1, 0.9, 0.3, 0.3, name="bad")
    with pytest.raises(MaterialError, match=r"nu12=0.9"):
        m.check()


def test_voigt_tensor_round_trip():
    C = TRC.stiffness()
    t = voigt_to_tensor(C)
    assert np.allclose(tensor_to_voigt(t), C)
    assert np.allclose(t, t.transpose(1, 0, 2, 3)) and np.allclose(t, t.transpose(2, 3, 0, 1))


def test_rotation_by_90_degrees_swaps_axes():
    frame = np.array([[0.0, 1, 0], [-1, 0, 0], [0, 0, 1]])  # M1 = e_y, M2 = -e_x
    Cc = rotate_stiffness(TRC.stiffness(), frame)
    Cm = TRC.stiffness()
    assert np.isclose(Cc[1, 1], Cm[0, 0]) and np.isclose(Cc[0, 0], Cm[1, 1])
    assert np.isclose(Cc[3, 3], Cm[4, 4]) and np.isclose(Cc[4, 4], Cm[3, 3])


def test_rotation_preserves_energy(rng):
    Q, _ = np.linalg.qr(rng.standard_normal((3, 3)))
    C = TRC.stiffness()
    Cc = rotate_stiffness(C, Q)
    Em = rng.standard_normal((3, 3))
    Em = Em + Em.T
    Ec = Q.T @ Em @ Q  # material-frame tensor to Cartesian: E_c = Qᵀ E_m Q (rows of Q are M_i)
    v = lambda E: np.array([E[0, 0], E[1, 1], E[2, 2], 2 * E[1, 2], 2 * E[0, 2], 2 * E[0, 1]])
    assert np.isclose(v(Em) @ C @ v(Em), v(Ec) @ Cc @ v(Ec))
