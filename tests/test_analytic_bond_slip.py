"""The closed-form single-lap shear reference (layershell.analytic.bond_slip, Yuan et al. 2004)
against an independent numerical integration of the same bond equation, and its known limits."""
import numpy as np
import pytest
from scipy.integrate import solve_ivp

from layershell.analytic.bond_slip import BondedJoint

#: CFRP sheet on concrete (N, mm): E_p t_p = 38 kN/mm, bilinear law τ_f = 5 MPa, G_f = 0.5 N/mm
JOINT = BondedJoint(E_p=230e3, t_p=0.165, b_p=50.0, tau_f=5.0, delta_1=0.02, delta_f=0.2,
                    E_c=30e3, t_c=100.0, b_c=150.0)


def _shoot(j: BondedJoint, d0: float, L: float) -> tuple[float, float]:
    """P and loaded-end slip by integrating δ'' = β τ(δ) from the free end (δ(0) = δ₀, δ'(0) = 0)."""
    def tau(d):
        if d <= j.delta_1:
            return j.tau_f * d / j.delta_1
        return j.tau_f * (j.delta_f - d) / (j.delta_f - j.delta_1) if d <= j.delta_f else 0.0

    sol = solve_ivp(lambda x, y: [y[1], j.beta * tau(y[0])], [0.0, L], [d0, 0.0], rtol=1e-11, atol=1e-14,
                    max_step=L / 2000)
    return j.b_p * sol.y[1, -1] / j.beta, sol.y[0, -1]


@pytest.mark.parametrize("d0", [1e-5, 5e-3, 0.019, 0.05, 0.15, 0.199])
@pytest.mark.parametrize("L", [30.0, 150.0])
def test_closed_form_equals_integrated_bond_equation(d0, L):
    P, s = JOINT.state(d0, L)
    P_ode, s_ode = _shoot(JOINT, d0, L)
    assert P[0] == pytest.approx(P_ode, rel=1e-6, abs=1e-6 * JOINT.peak_load_long())
    assert s[0] == pytest.approx(s_ode, rel=1e-6)


def test_long_bond_peak_is_the_fracture_energy_formula():
    """P_u = b √(2 G_f E t) on a rigid substrate, b √(2 G_f / β) with the substrate's compliance."""
    rigid = BondedJoint(E_p=230e3, t_p=0.165, b_p=50.0, tau_f=5.0, delta_1=0.02, delta_f=0.2)
    assert rigid.peak_load_long() == pytest.approx(50.0 * np.sqrt(2 * 0.5 * 230e3 * 0.165), rel=1e-14)
    for j in (rigid, JOINT):
        assert j.peak_load(1000.0) == pytest.approx(j.peak_load_long(), rel=1e-9)
    assert JOINT.peak_load_long() < rigid.peak_load_long()


def test_effective_bond_length_plateau_and_snap_back():
    """The peak load grows with the bond length up to a plateau (the effective bond length) and
    the long bond's path snaps back: past the peak the load and the loaded-end slip both fall."""
    L = np.array([10.0, 20.0, 40.0, 60.0, 80.0, 120.0, 200.0])
    Pu = np.array([JOINT.peak_load(x) for x in L])
    assert np.all(np.diff(Pu) > 0)
    assert Pu[0] < 0.5 * JOINT.peak_load_long() and Pu[-1] > 0.9999 * JOINT.peak_load_long()
    d0 = np.geomspace(1e-6, JOINT.delta_f, 2000)
    P, s = JOINT.state(d0, 200.0)
    i = int(np.argmax(P))
    assert s[-1] < s[i] and P[-1] < 0.01 * P[i]  # slip at full debonding below the slip at the peak


def test_bad_law_is_refused():
    with pytest.raises(ValueError, match="delta_1 < delta_f"):
        BondedJoint(E_p=1.0, t_p=1.0, b_p=1.0, tau_f=1.0, delta_1=0.3, delta_f=0.2)
