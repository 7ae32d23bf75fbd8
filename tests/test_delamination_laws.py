"""Failure surface and friction laws, MODEL.md §9-§10 (4.15)-(4.85)."""
import numpy as np
import pytest
from hypothesis import given, strategies as st

from layershell.delamination import (InterfaceLaw, failure_function, return_map_at_fracture, tau_delam,
                                     tau_slide, tau_slide_start)

LAW = InterfaceLaw(sigma_max=1.98, tau_max=6.0, p=2, mu0=0.95, mu=0.2, gT_mu=0.2)


def test_limits_of_the_failure_surface():
    V, failed = failure_function(np.array([[0, 0, 1.98], [6.0, 0, 0], [0, 5.999, 0], [3, 4, 0]]), LAW)
    assert failed[0]  # pure tension at σ_max
    assert np.isclose(V[1], 0) and failed[1]  # pure shear at τ_max
    assert V[2] < 0 and not failed[2]
    assert np.isclose(V[3], 5 - 6) and not failed[3]  # resultant |τ| = 5
    # tension just below σ_max with no shear: bonded
    V, failed = failure_function(np.array([0, 0, 1.97]), LAW)
    assert not failed


def test_p1_is_a_cone_and_p2_a_parabola():
    cone = InterfaceLaw(2.0, 6.0, p=1)
    s = np.linspace(-4, 2, 13)
    assert np.allclose(tau_delam(s, cone), 6.0 * (1 - s / 2.0))
    assert np.allclose(tau_delam(s, LAW), 6.0 * np.sqrt(np.clip(1 - s / 1.98, 0, None)))
    # no compressive cut-off: the admissible shear keeps growing under compression
    assert tau_delam(-10.0, LAW) > tau_delam(-1.0, LAW) > tau_delam(0.0, LAW) == 6.0


def test_erratum_E16_larger_p_admits_more_in_tension():
    """Larger p shrinks the admissible set only for σ33 < 0; for 0 < σ33 < σ_max it grows."""
    lo, hi = InterfaceLaw(2.0, 6.0, p=1), InterfaceLaw(2.0, 6.0, p=4)
    assert tau_delam(1.0, hi) > tau_delam(1.0, lo)
    assert tau_delam(-1.0, hi) < tau_delam(-1.0, lo)


def test_slip_softening_4_77():
    """τ^Gleit_max starts at μ0 τ_Delam, equals μ μ0 τ_Delam at g = g_T^μ, decreases to 0."""
    s33 = -0.5
    t0 = tau_slide_start(s33, LAW)
    assert np.isclose(t0, 0.95 * tau_delam(s33, LAW))
    assert np.isclose(tau_slide(s33, 0.0, LAW), t0)
    assert np.isclose(tau_slide(s33, 0.2, LAW), 0.2 * t0)
    g = np.linspace(0, 5, 50)
    v = tau_slide(s33, g, LAW)
    assert np.all(np.diff(v) < 0) and v[-1] < 0.01 * t0
    # thesis §5.1 law (b): 0.95 × 0.2 = 0.19 τ_Delam at a slip of 0.05 mm
    b = InterfaceLaw(1.98, 1.21, 2, mu0=0.95, mu=0.2, gT_mu=0.05e-3)
    assert np.isclose(tau_slide(0.0, 0.05e-3, b), 0.19 * 1.21)


def test_constant_friction_for_infinite_gT_mu():
    weak = InterfaceLaw(1.98, 1.21, 2, mu0=0.01)
    assert np.allclose(tau_slide(-0.3, [0, 1, 100], weak), 0.01 * tau_delam(-0.3, weak))


def test_tension_gives_the_zero_pressure_limit():
    """σ33 := min(σ33, 0): adhesive friction acts without pressure, tension does not raise it."""
    assert np.isclose(tau_slide_start(1.0, LAW), 0.95 * 6.0)


def test_coulomb_fallback_E11():
    law = InterfaceLaw(1.98, 6.0, 2, mu0=0.95, mu=0.2, gT_mu=0.2, mu_coulomb=0.6)
    # far along the softening branch Coulomb governs: μ_C |σ33|
    assert np.isclose(tau_slide(-10.0, 100.0, law), 6.0)


@given(st.floats(-20, 1.97), st.floats(-30, 30), st.floats(-30, 30))
def test_return_mapping_keeps_normal_stress_and_direction(s33, t1, t2):
    t = np.array([t1, t2, s33])
    m = return_map_at_fracture(t, LAW)
    assert np.isclose(m[2], min(s33, 0.0))
    lim = tau_slide_start(min(s33, 0.0), LAW)
    shear = np.hypot(t1, t2)
    if shear > 1e-12 * LAW.tau_max:
        assert np.isclose(np.hypot(m[0], m[1]), lim)
        assert np.allclose(m[:2] / lim, t[:2] / shear, atol=1e-9)
    else:
        assert np.allclose(m[:2], 0.0)


def test_law_validation():
    with pytest.raises(ValueError, match="p = 0.5"):
        InterfaceLaw(1.0, 1.0, p=0.5).check()
    with pytest.raises(ValueError, match="mu0"):
        InterfaceLaw(1.0, 1.0, mu0=1.5).check()
