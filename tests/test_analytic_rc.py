"""The plane-sections RC reference (layershell.analytic.rc_section) against hand calculations of
the textbook slab strip, its limiting cases and its fibre convergence; the IC debonding formulas
(layershell.analytic.ic_debonding) against their published forms.

The strip (N, mm, per metre width): b = 1000, h = 160, d = 130, 5 Ø10 per metre
(A_s = 5 π 10²/4 = 392.7 mm²), B500 (E_s = 200 000, f_y = 500); C30/37 with the fib Model Code
2010 mean values: f_cm = f_ck + 8 = 38, f_ctm = 0.3 f_ck^(2/3) = 2.90, E_ci = 21 500 (f_cm/10)^(1/3)
= 33 540 (eqs. 5.1-3, 5.1-21), ε_c1 = 2.3 ‰, ε_c,lim = 3.5 ‰ (Table 5.1-8).
"""
import numpy as np
import pytest

from layershell.analytic import ic_debonding as ic
from layershell.analytic.rc_section import (Concrete, RCSection, Rebar, Strengthening,
                                            cracked_stiffness, cracking_moment,
                                            moment_at_strengthening_strain, moment_curvature,
                                            neutral_axis, ultimate_moment, yield_moment)
from layershell.material import MaterialError

F_C, F_CT, E_C = 38.0, 2.90, 33540.0
A_S = 5 * np.pi * 10.0**2 / 4
H, B, D = 160.0, 1000.0, 130.0
ELASTIC = 1e9  # a yield stress never reached: linear steel


def strip(curve="sargin", tension="brittle", fibres=400, f_y=500.0, E_h=0.0, eps_su=None,
          strengthening=None, **kw):
    c = Concrete(f_c=F_C, f_ct=F_CT, E_c=E_C, curve=curve, tension=tension, **kw)
    bar = Rebar(depth=D, area=A_S, E_s=200e3, f_y=f_y, E_h=E_h, eps_su=eps_su)
    return RCSection(h=H, b=B, concrete=c, rebars=(bar,), strengthening=strengthening,
                     fibres=fibres)


# ---------------------------------------------------------------- material laws
def test_concrete_laws_hit_their_defining_points():
    s = Concrete(F_C, F_CT, E_C, curve="sargin")
    assert s.stress(-0.0023) == pytest.approx(-F_C, rel=1e-12)  # peak at ε_c1
    e = 1e-9
    assert -s.stress(-e) / e == pytest.approx(E_C, rel=1e-6)  # initial tangent E_ci
    p = Concrete(F_C, F_CT, E_C, curve="parabola-rectangle")
    assert p.stress([-0.002, -0.003, -0.0035]) == pytest.approx([-F_C] * 3, rel=1e-12)
    assert p.stress(-0.001) == pytest.approx(-F_C * (1 - 0.5**2), rel=1e-12)  # EC2 (3.17)
    # tension: linear to f_ct, then 0 (brittle) or linear to 0 at ε_tu (softening)
    eps_cr = F_CT / E_C
    assert s.stress(eps_cr * 0.999) == pytest.approx(F_CT * 0.999)
    assert s.stress(eps_cr * 1.001) == 0.0
    soft = Concrete(F_C, F_CT, E_C, tension="softening", eps_tu=3 * eps_cr)
    assert soft.stress(2 * eps_cr) == pytest.approx(F_CT / 2, rel=1e-12)
    assert p.stress(-0.0036) == 0.0  # crushed beyond ε_cu


# ---------------------------------------------------------------- uncracked: Mcr, EI_I
def test_cracking_moment_and_uncracked_stiffness_by_hand():
    """α_e = 200 000/33 540 = 5.963; transformed area A = 160 000 + 5.963·392.7 = 162 342 mm²;
    z̄ = (1000·160²/2 + 2341.7·130)/A = 80.72 mm; I_I = 1000·160³/12 + 160 000·0.72²
    + 2341.7·49.28² = 347.10e6 mm⁴; M_cr = f_ctm I_I/(h − z̄) = 2.90·347.10e6/79.28
    = 12.70 kNm/m (the plain section's f_ctm b h²/6 = 12.37); EI_I = 11 642 kNm²/m."""
    Mcr, EI1 = cracking_moment(strip())
    assert Mcr == pytest.approx(12.70e6, rel=1e-3)
    assert EI1 == pytest.approx(11.642e12, rel=1e-3)
    assert Mcr / (F_CT * B * H**2 / 6) == pytest.approx(1.027, abs=2e-3)  # the bar's share


def test_fibre_model_starts_on_EI_I_and_cracks_at_Mcr():
    """Below cracking the fibre model with linear compression is the transformed section; with
    Sargin's law the initial stiffness is the same (tangent E_ci); the soffit reaches f_ct at
    κ_cr = f_ct/(E_c (h − z̄)) where M = M_cr, and just past it the moment drops."""
    Mcr, EI1 = cracking_moment(strip())
    k_cr = F_CT / (E_C * (H - 80.72))
    lin = moment_curvature(strip(curve="linear", fibres=4000), [0.5 * k_cr, 0.999 * k_cr])
    assert lin.M == pytest.approx(EI1 * lin.kappa, rel=1e-5)
    sar = moment_curvature(strip(fibres=4000), [1e-3 * k_cr, 0.999 * k_cr, 1.05 * k_cr])
    assert sar.M[0] == pytest.approx(EI1 * sar.kappa[0], rel=1e-5)
    # Sargin's secant at the top fibre (−8.8e-5) is 1.9 % below E_ci: M 0.8 % below M_cr
    assert sar.M[1] == pytest.approx(0.999 * Mcr, rel=1e-2)
    assert sar.M[2] < sar.M[1]


# ---------------------------------------------------------------- fully cracked: EI_II, My
def test_state_II_by_hand():
    """b x²/2 = α_e A_s (d − x): 500 x² + 2341.7 x − 304 421 = 0, x_II = 22.44 mm;
    I_II = 1000·22.44³/3 + 2341.7·107.56² = 30.86e6 mm⁴, EI_II = 1035 kNm²/m (EI_I/EI_II = 11.2)."""
    x, EI2 = cracked_stiffness(strip())
    assert x == pytest.approx(22.44, rel=1e-3)
    assert EI2 == pytest.approx(1.035e12, rel=1e-3)


@pytest.mark.parametrize("with_layer", [False, True])
def test_linear_cracked_section_is_EI_II_kappa(with_layer):
    """No concrete tension, linear concrete and steel (and strengthening): M = E_c I_II κ and
    x = x_II at any curvature, to 1e-6 (the fibre containing the neutral axis is the only
    integration error, O(Δz²))."""
    layer = Strengthening(t_f=0.1646, E_f=230e3, f_fu=1e9, depth=165.0) if with_layer else None
    sec = strip(curve="linear", tension="none", f_y=ELASTIC, strengthening=layer, fibres=20000)
    x2, EI2 = cracked_stiffness(sec)
    k = np.array([1e-7, 1e-6, 1e-5, 5e-5])
    st = moment_curvature(sec, k)
    assert st.M == pytest.approx(EI2 * k, rel=1e-6)
    assert st.x == pytest.approx(x2, rel=1e-6)


def test_yield_moment_by_hand():
    """First yield with linear concrete: M_y = A_s f_y (d − x_II/3) = 196 350·122.52
    = 24.06 kNm/m at κ_y = ε_y/(d − x_II) = 0.0025/107.56 = 2.324e-5 /mm. With Sargin's law the
    concrete (17.5 MPa at the top by the linear formula, 46 % of f_cm) is softer, x grows and
    M_y falls slightly: within 1 %."""
    M_lin, k_lin = yield_moment(strip(curve="linear", tension="none", fibres=4000))
    assert M_lin == pytest.approx(24.06e6, rel=1e-3)
    assert k_lin == pytest.approx(2.324e-5, rel=1e-3)
    M_s, k_s = yield_moment(strip())
    assert M_s == pytest.approx(24.06e6, rel=1e-2)
    assert M_s < M_lin and k_s > k_lin


def test_cracked_branch_lies_between_EI_II_and_EI_I():
    """Past cracking (linear compression, brittle tension) the moment lies between EI_II κ and
    EI_I κ: the band of uncracked concrete below the neutral axis (strains up to f_ct/E_c) adds
    to the bare cracked section, less and less as κ grows; under curvature control the brittle
    law makes the moment drop after M_cr (to 0.35 M_cr here) before it rises again."""
    sec = strip(curve="linear")
    Mcr, EI1 = cracking_moment(sec)
    _, EI2 = cracked_stiffness(sec)
    M_y, k_y = yield_moment(sec)
    k_cr = Mcr / EI1
    k = np.linspace(1.05 * k_cr, 0.99 * k_y, 25)
    M = moment_curvature(sec, k).M
    assert np.all(M > EI2 * k) and np.all(M < EI1 * k)
    excess = M / (EI2 * k) - 1
    assert np.all(np.diff(excess) <= 1e-12) and excess[-1] < 0.03  # plateaus: fibre steps
    assert M.min() < 0.5 * Mcr
    bare = moment_curvature(strip(curve="linear", tension="none"), k).M
    assert np.all(M > bare)


# ---------------------------------------------------------------- ultimate
@pytest.mark.parametrize("f_c, f_y, M_pr_hand, M_rb_hand", [
    (F_C, 500.0, 25.00e6, 25.02e6),                # mean concrete, nominal steel
    (0.85 * 30 / 1.5, 500 / 1.15, 21.33e6, 21.35e6),  # EC2 design values: α_cc f_ck/γ_c, f_yk/γ_s
])
def test_ultimate_parabola_rectangle_against_stress_blocks(f_c, f_y, M_pr_hand, M_rb_hand):
    """EC2 parabola–rectangle (n = 2, ε_c2 = 2 ‰, ε_cu2 = 3.5 ‰), steel elastic–perfectly
    plastic without a strain limit: crushing governs. With ρ = ε_c2/ε_cu = 4/7 the block's mean
    stress is α_R f_c, α_R = 1 − ρ/3 = 0.8095, and its resultant lies k_a x below the top,
    k_a = 1 − (1/2 − ρ²/12)/α_R = 0.4160; x = A_s f_y/(α_R f_c b), M_u = A_s f_y (d − k_a x).
    EC2 3.1.7(3) rectangular block (λ = 0.8, η = 1): x = A_s f_y/(0.8 f_c b),
    M_u = A_s f_y (d − 0.4 x).
    Mean values (f_c = 38, f_y = 500): x = 6.383 mm (steel strain 68 ‰, yielded), M_u = 25.00
    kNm/m; the block gives x = 6.459 mm, 25.02 kNm/m. Design values (f_cd = 0.85·30/1.5 = 17,
    f_yd = 434.8): x = 12.41 mm, M_Rd = 21.33 kNm/m; the block 12.56 mm, 21.35 kNm/m.
    The block is 0.06 % and 0.11 % above: its moment term 0.8·0.4 = 0.32 x² replaces the
    parabola–rectangle's α_R k_a = 0.3367 x², and with the lever arm at 96-98 % of d (0.30 %
    reinforcement) the block's shape hardly matters. α_cc scales both blocks alike. Concrete
    tension is left out, as in the blocks (the band below the neutral axis would add 0.3 %)."""
    rho = 0.002 / 0.0035
    a_r = 1 - rho / 3
    k_a = 1 - (0.5 - rho**2 / 12) / a_r
    x_pr = A_S * f_y / (a_r * f_c * B)
    M_pr = A_S * f_y * (D - k_a * x_pr)
    x_rb = A_S * f_y / (0.8 * f_c * B)
    M_rb = A_S * f_y * (D - 0.4 * x_rb)
    assert M_pr == pytest.approx(M_pr_hand, rel=1e-3) and M_rb == pytest.approx(M_rb_hand, rel=1e-3)
    c = Concrete(f_c=f_c, f_ct=F_CT, E_c=E_C, curve="parabola-rectangle", tension="none")
    sec = RCSection(h=H, b=B, concrete=c, rebars=(Rebar(depth=D, area=A_S, f_y=f_y),),
                    fibres=4000)
    Mu, ku, mode = ultimate_moment(sec)
    assert mode == "concrete crushing"
    assert neutral_axis(sec, ku) == pytest.approx(x_pr, rel=2e-3)
    assert Mu == pytest.approx(M_pr, rel=1e-4)
    assert Mu == pytest.approx(M_rb, rel=2e-3)


def test_ultimate_by_rupture_of_the_bars():
    """B500B with hardening (f_t/f_y = 1.08 at ε_uk = 5 %: E_h = 40/0.0475 = 842 MPa): at this
    low ratio the bars rupture before the top reaches 3.5 ‰; the moment then is the bars'
    force 540·392.7 = 212 kN times a lever arm between 0.95 d and d."""
    sec = strip(E_h=842.0, eps_su=0.05)
    Mu, ku, mode = ultimate_moment(sec)
    assert mode == "rebar rupture"
    st = moment_curvature(sec, [ku])
    assert st.eps_points[0, 0] == pytest.approx(0.05, rel=1e-9)
    assert -st.eps_top[0] < 0.0035
    F = A_S * (500.0 + 842.0 * (0.05 - 0.0025))
    assert 0.95 * D * F < Mu < D * F


# ---------------------------------------------------------------- convergence and options
def test_convergence_with_the_number_of_fibres():
    """Refining the fibres, against 102 400 of them: the bare cracked section (Sargin, a kink
    at the neutral axis) converges as O(1/n²), the error falling by 4 per doubling; with the
    brittle tension the stress jump inside one fibre leaves an error below 1e-4 that does not
    fall regularly; the ultimate moment (parabola–rectangle) is within 1.5e-4 at 200 fibres."""
    n = [200, 400, 800, 1600, 3200]
    k = 1.2e-5

    def errors(**kw):
        ref = moment_curvature(strip(fibres=102400, **kw), [k]).M[0]
        return np.array([abs(moment_curvature(strip(fibres=m, **kw), [k]).M[0] / ref - 1)
                         for m in n])

    bare = errors(tension="none")
    assert np.all(bare[:-1] / bare[1:] == pytest.approx(4.0, rel=0.1))
    assert errors().max() < 1e-4
    Mu = [ultimate_moment(strip(curve="parabola-rectangle", fibres=m))[0] for m in (200, 12800)]
    assert Mu[0] == pytest.approx(Mu[1], rel=1.5e-4)


def test_tension_softening_carries_more_than_brittle():
    eps_cr = F_CT / E_C
    k = np.array([0.5e-5, 1.2e-5, 2e-5])
    brittle = moment_curvature(strip(), k).M
    soft = moment_curvature(strip(tension="softening", eps_tu=10 * eps_cr), k).M
    assert np.all(soft > brittle)
    pre = 0.5 * eps_cr / (H - 80.72)
    assert moment_curvature(strip(tension="softening", eps_tu=10 * eps_cr), [pre]).M[0] == \
        pytest.approx(moment_curvature(strip(), [pre]).M[0], rel=1e-12)


# ---------------------------------------------------------------- strengthened section
#: TRC: 4 plies of an epoxy-impregnated carbon textile with 800 tex yarns at 10.8 mm (textile G2a
#: of Adv. Civ. Eng. 2018:4650102, Table 1) in a 10 mm layer: fibre area 4·800/1.80/10.8
#: = 164.6 mm²/m (carbon density 1.80 g/cm³), E_f = 230 GPa (a standard-modulus 12K carbon
#: yarn); the textile at mid-thickness of the layer, 165 mm below the top.
TRC = Strengthening(t_f=4 * 800 / 1.80 / 10.8 / 1000, E_f=230e3, f_fu=2500.0, depth=165.0)


def test_strengthened_transformed_sections_by_hand():
    """α_f = 230 000/33 540 = 6.857, α_f A_f = 1128.8 mm²: x_II from
    500 x² + (2341.7 + 1128.8) x − (2341.7·130 + 1128.8·165) = 0 → x_II = 28.05 mm;
    I_II = 1000 x³/3 + 2341.7 (130 − x)² + 1128.8 (165 − x)² = 52.87e6 mm⁴ (EI_II = 1773
    kNm²/m, 1.71 times the bare strip's)."""
    x, EI2 = cracked_stiffness(strip(strengthening=TRC))
    assert TRC.t_f * 1000 == pytest.approx(164.6, rel=1e-3)
    assert x == pytest.approx(28.05, rel=1e-3)
    assert EI2 == pytest.approx(E_C * 52.87e6, rel=1e-3)
    # first yield, linear concrete: κ_y = 0.0025/(130 − 28.05) = 2.452e-5 /mm, the textile at
    # κ_y (165 − 28.05) = 3.36 ‰ (772 MPa), M_y = EI_II κ_y = 43.48 kNm/m (1.81 × the bare strip)
    M_y, k_y = yield_moment(strip(curve="linear", tension="none", strengthening=TRC, fibres=4000))
    assert k_y == pytest.approx(2.452e-5, rel=1e-3)
    assert M_y == pytest.approx(43.48e6, rel=1e-3)


def test_trc_matrix_in_the_uncracked_section_and_its_cracking():
    """The TRC's 10 mm matrix (E_m = 34 000 as the package's thesis TRC, f_ct,m = 2.90) with the
    textile at its mid-depth: α_m = 34 000/33 540 = 1.0137; transformed areas and centroids
    160 000 @ 80, 10 137 @ 165 (own I 84 480), 2341.7 @ 130, 1128.8 @ 165: A = 173 608 mm²,
    z̄ = 86.19 mm, I_I = 422.0e6 mm⁴ (EI_I = 14 154 kNm²/m). The concrete soffit would crack
    at 2.90 I_I/(160 − z̄) = 16.58 kNm/m, the matrix's bottom face first, at
    2.90 I_I/(α_m (170 − z̄)) = 14.41 kNm/m. The fibre model (linear compression) follows
    EI_I up to there and drops past it; in state II the matrix carries nothing."""
    matrix = Concrete(f_c=60.0, f_ct=F_CT, E_c=34000.0, curve="linear")
    trc = Strengthening(t_f=TRC.t_f, E_f=230e3, f_fu=2500.0, matrix=matrix, t_m=10.0)
    sec = strip(curve="linear", strengthening=trc, fibres=16000)
    assert sec.strengthening_depth == 165.0
    Mcr, EI1 = cracking_moment(sec)
    assert EI1 == pytest.approx(14.154e12, rel=1e-3)
    assert Mcr == pytest.approx(14.41e6, rel=1e-3)
    k_cr = Mcr / EI1
    st = moment_curvature(sec, [0.5 * k_cr, 0.999 * k_cr, 1.01 * k_cr])
    assert st.M[:2] == pytest.approx(EI1 * st.kappa[:2], rel=1e-4)
    assert st.M[2] < st.M[1]
    assert cracked_stiffness(sec) == pytest.approx(cracked_stiffness(strip(strengthening=TRC)))


def test_moment_at_a_strengthening_strain_on_the_linear_section():
    """Linear, no tension: the layer's strain ε at depth z_f is κ (z_f − x_II), so
    M = EI_II ε/(z_f − x_II)."""
    sec = strip(curve="linear", tension="none", f_y=ELASTIC, strengthening=TRC, fibres=20000)
    x2, EI2 = cracked_stiffness(sec)
    M, k = moment_at_strengthening_strain(sec, 0.004)
    assert k == pytest.approx(0.004 / (165.0 - x2), rel=1e-8)
    assert M == pytest.approx(EI2 * k, rel=1e-6)


def test_strip_with_trc_fails_by_the_textile():
    sec = strip(E_h=842.0, eps_su=0.05, strengthening=TRC)
    Mu, ku, mode = ultimate_moment(sec)
    assert mode == "strengthening rupture"
    st = moment_curvature(sec, [ku])
    assert st.sigma_points[0, 1] == pytest.approx(2500.0, rel=1e-9)
    M_db, k_db, eps_db = ic.ic_debonding_moment(sec)
    assert yield_moment(sec)[0] < Mu and cracking_moment(sec)[0] < M_db < Mu
    assert moment_curvature(sec, [k_db]).eps_points[0, 1] == pytest.approx(eps_db, rel=1e-9)


# ---------------------------------------------------------------- IC debonding formulas
def test_teng_ic_strain_is_chen_teng_bond_model_as_a_strain():
    """ε_db (Teng et al. 2003) = (0.48/0.427) · P_u/(b_f t_f E_f) of Chen & Teng (2001) for a
    bond longer than L_e: the IC model is the anchorage model with α refitted."""
    f_c, E_f, t_f, b_f, b_c = np.array([25.0, 38.0, 60.0]), 230e3, 0.33, 100.0, 200.0
    L = 2 * ic.effective_bond_length(f_c, E_f, t_f)
    P = ic.chen_teng_anchorage(f_c, E_f, t_f, b_f, b_c, L)
    assert ic.teng_ic_strain(f_c, E_f, t_f, b_f, b_c) == \
        pytest.approx(0.48 / 0.427 * P / (b_f * t_f * E_f), rel=1e-13)


def test_chen_teng_factors():
    """β_w = 1 at b_f = b_c/2, 1/√2 at full width, → √2 for a narrow plate; β_L rises as a
    sine to 1 at L_e and stays there; L_e = √(E_f t_f/√f_c): 230 000·1.2/√38 → 211.6 mm."""
    assert ic.width_factor(50.0, 100.0) == pytest.approx(1.0, rel=1e-15)
    assert ic.width_factor(100.0, 100.0) == pytest.approx(2**-0.5, rel=1e-15)
    assert ic.width_factor(1e-9, 100.0) == pytest.approx(2**0.5, rel=1e-9)
    L_e = ic.effective_bond_length(38.0, 230e3, 1.2)
    assert L_e == pytest.approx(211.6, rel=1e-3)
    L = np.linspace(10.0, 3 * L_e, 50)
    P = ic.chen_teng_anchorage(38.0, 230e3, 1.2, 50.0, 150.0, L)
    short = L < L_e
    assert np.all(np.diff(P[short]) > 0) and np.allclose(P[~short], P[-1], rtol=1e-15)
    assert ic.length_factor(L_e * (1 - 1e-9), L_e) == pytest.approx(1.0, abs=1e-12)


def test_aci440_si_form_against_the_us_form():
    """ACI 440.2R-08 eq. (10-2) in US units, 0.083 √(f'c/(n E_f t_f)) (psi, in): for
    f'c = 4640 psi, E_f = 23 925 ksi, t_f = 0.055 in it gives 0.00493, "a limiting strain of
    0.005" (eng-tips thread 257440). The SI form with 0.41 (MPa, mm) on the same laminate
    gives 0.00483: the two published coefficients differ by 0.41/√25.4/0.083 = 0.980."""
    us = 0.083 * np.sqrt(4640.0 / (23925e3 * 0.055))
    assert us == pytest.approx(0.005, abs=1e-4)
    psi = 0.00689476  # MPa
    si = ic.aci440_strain(4640.0 * psi, 23925e3 * psi, 0.055 * 25.4)
    assert si == pytest.approx(us * 0.41 / np.sqrt(25.4) / 0.083, rel=1e-4)
    assert si == pytest.approx(us, rel=0.025)
    assert ic.aci440_strain(38.0, 230e3, 0.01, eps_fu=0.015) == pytest.approx(0.9 * 0.015)


def test_said_wu_by_hand():
    """0.23 f_c^0.2/(E_f t_f)^0.35 for a CFRP sheet (230 GPa, 0.165 mm) on f_c = 30 MPa:
    30^0.2 = 1.9744, 37 950^0.35 = 40.06: ε_db = 0.01134."""
    assert ic.said_wu_strain(30.0, 230e3, 0.165) == pytest.approx(0.01134, rel=1e-3)


# ---------------------------------------------------------------- bad input
@pytest.mark.parametrize("build, match", [
    (lambda: Concrete(f_c=-30.0, f_ct=2.9, E_c=3e4), "f_c"),
    (lambda: Concrete(f_c=30.0, f_ct=2.9, E_c=3e4, curve="hognestad"), "curve"),
    (lambda: Concrete(f_c=30.0, f_ct=2.9, E_c=3e4, tension="softening"), "eps_tu"),
    (lambda: Concrete(f_c=30.0, f_ct=2.9, E_c=1.2e4, eps_c1=0.0023), "singular"),
    (lambda: Rebar(depth=10.0, area=0.0), "area"),
    (lambda: strip(fibres=50), "fibres"),
    (lambda: RCSection(h=100.0, b=1000.0, concrete=Concrete(30.0, 2.9, 3e4),
                       rebars=(Rebar(depth=120.0, area=300.0),)), "outside"),
    (lambda: moment_curvature(strip(), [-1e-5]), "≥ 0"),
    (lambda: Strengthening(t_f=0.2, E_f=230e3, f_fu=2500.0, t_m=10.0), "matrix"),
    (lambda: strip(strengthening=Strengthening(t_f=0.2, E_f=230e3, f_fu=2500.0, depth=175.0,
                                               matrix=Concrete(60.0, 3.0, 3e4, curve="linear"),
                                               t_m=10.0)),
     "inside the TRC"),
    (lambda: moment_at_strengthening_strain(strip(strengthening=TRC), 0.0115),
     "fails first by strengthening rupture"),
    (lambda: ic.width_factor(200.0, 100.0), "b_f"),
    (lambda: ic.teng_ic_strain(38.0, 230e3, -1.0, 50.0, 100.0), "t_f"),
    (lambda: ic.section_debonding_strain(strip(strengthening=TRC), "sika"), "not known"),
])
def test_bad_input_is_refused(build, match):
    with pytest.raises(MaterialError, match=match):
        build()
