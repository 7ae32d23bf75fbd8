"""Issue 2 acceptance: the thesis's analytic single-layer examples (MODEL.md V1, V2, V4)."""
import numpy as np
import pytest
from helpers import run_example


def rel(a, b):
    return abs(a - b) / abs(b)


def test_cantilever_thick_timoshenko():
    """V2 (thesis 3.5.1): w_tip within 2.5 % of 4.0336 cm (Timoshenko with shear)."""
    res = run_example("cantilever_thick")
    assert res.converged
    w = res.summary["probes"]["w_tip"]
    assert rel(w, 4.0336) < 0.025
    assert rel(w, 4.0336) < 0.006  # measured: 4.0205 (-0.32 %); full element 4.0125 (-0.52 %)


def test_cantilever_full_clamp_is_stiffer():
    """Clamping every component of every director suppresses the Poisson contraction at the wall
    (ν = 0.4): a 3D effect beam theory ignores; the tip deflects less than with the plane-section
    clamp of the example (measured 3.81 vs 4.01 cm with 5 elements)."""
    full = run_example("cantilever_thick", {
        'type = "symmetry"\nwhere = "near(x, 0)"\nnormal = [1, 0, 0]':
            'type = "fix"\nwhere = "near(x, 0)"\ndirectors = "all"\ncomponents = ["x", "y"]',
        'components = ["z"]': 'directors = "all"\ncomponents = ["z"]'})
    w = full.summary["probes"]["w_tip"]
    assert 3.7 < w < 3.9


def test_ring_lame():
    """V1 (thesis 2.10): Lamé ring, 9 elements, d = 3, geometrically nonlinear.

    σ_φ(a), σ_φ(b) are within 2 % of -2.667, -1.667. σ_r(b) recovered (the default) is the
    applied pressure -1.0 (equilibrium through the thickness); sampled raw it is -0.9703 (2.97 %
    from -1.0): the limit of a *cubic* displacement through 2.5 m of a thick ring, see
    test_ring_sigma_r_is_the_exact_cubic_director_solution."""
    res = run_example("ring")
    p = res.summary["probes"]
    assert res.converged
    assert rel(p["sigma_phi_inner"], -2.6667) < 0.02
    assert rel(p["sigma_phi_outer"], -1.6667) < 0.02
    assert rel(p["sigma_r_outer"], -1.0) < 0.035


def _ritz_ring(d, a=2.5, b=5.0, p=1.0):
    """Independent 1D Ritz solution of the axisymmetric ring (ν = 0, E = 1) with a degree-d
    polynomial u_r(t), t = b - r: the exact solution of the d-director model for this problem."""
    x, w = np.polynomial.legendre.leggauss(40)
    r = 0.5 * (b - a) * (x + 1) + a
    w = 0.5 * (b - a) * w
    t = b - r
    P = np.stack([t**k for k in range(d + 1)], 1)
    dP = np.stack([-k * t ** max(k - 1, 0) for k in range(d + 1)], 1)
    K = np.einsum("g,gi,gj->ij", w * r, dP, dP) + np.einsum("g,gi,gj->ij", w / r, P, P)
    f = np.zeros(d + 1)
    f[0] = -p * b
    c = np.linalg.solve(K, f)
    return -c[1]  # σ_r(b) = E u_r'(b) = -E du/dt at t = 0


@pytest.mark.parametrize("d", [3, 4])
def test_ring_sigma_r_is_the_exact_cubic_director_solution(d):
    """The element reproduces the independent Ritz solution of the d-director model to 0.1 %:
    σ_r(b) = -0.9712 for d = 3 and -1.0071 for d = 4. So the 2 % target on σ_r(b) of the issue
    is out of reach for d = 3 by the mathematics of the model, not the implementation (raw
    sampling; the recovered σ_r, the default, meets the applied pressure on the face exactly)."""
    ritz = _ritz_ring(d)
    res = run_example("ring", {"directors = 3": f"directors = {d}", "n = 1": "n = 1", **_RAW_SIGMA_R})
    fe = res.summary["probes"]["sigma_r_outer"]
    assert rel(fe, ritz) < 1e-3
    if d == 4:
        assert rel(fe, -1.0) < 0.02


def test_curved_beam_one_layer_girkmann():
    """Thesis 3.5.2 geometry, one layer, d = 3, 9 elements: σ_φ(a), σ_φ(b) within 5 % of 1.241,
    -0.787 (MODEL.md E7). σ_r,max = 0.1614 (-5.6 % from 0.171) is again the cubic-in-thickness
    limit over 2.5 m (with d = 4 it is 0.1716, +0.4 %). σ_r sampled raw: the recovered value
    (default, 0.180) reflects the in-plane σ_φ of the 9 elements instead (test_layers.py)."""
    res = run_example("curved_beam_1layer", _RAW_SIGMA_R)
    p = res.summary["probes"]
    assert rel(p["sigma_phi_inner"], 1.241) < 0.05
    assert rel(p["sigma_phi_outer"], -0.787) < 0.05
    assert rel(p["sigma_r_max"], 0.171) < 0.06


_RAW_SIGMA_R = {'component = "33"': 'component = "33"\nsampling = "raw"'}


def test_curved_beam_one_layer_d4_meets_all_bounds():
    res = run_example("curved_beam_1layer", {"directors = 3": "directors = 4", **_RAW_SIGMA_R})
    p = res.summary["probes"]
    assert rel(p["sigma_phi_inner"], 1.241) < 0.05
    assert rel(p["sigma_phi_outer"], -0.787) < 0.05
    assert rel(p["sigma_r_max"], 0.171) < 0.05


def test_girkmann_reference_values_erratum_E7():
    """(3.94)-(3.95) give σ_φ(b) = -0.787 and σ_r,max = 0.171 at r ≈ 3.40 (not -0.780/0.168)."""
    a, b, M, h = 2.5, 5.0, 0.1, 0.1
    D = (b**2 - a**2) ** 2 - 4 * a**2 * b**2 * np.log(b / a) ** 2
    r = np.linspace(a, b, 200001)
    sr = -4 * M / (h * D) * (-(a**2) * np.log(r / a) + b**2 * np.log(r / b) + a**2 * b**2 / r**2 * np.log(b / a))
    sp = lambda r: -4 * M / (h * D) * ((b**2 - a**2) - a**2 * np.log(r / a) + b**2 * np.log(r / b)
                                       - a**2 * b**2 / r**2 * np.log(b / a))
    assert round(sp(a), 3) == 1.241 and round(sp(b), 3) == -0.787
    assert round(sr.max(), 3) == 0.171 and abs(r[np.argmax(sr)] - 3.40) < 0.01
