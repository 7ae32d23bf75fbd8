"""End-notched flexure (ENF, mode II) with a cohesive interface against beam theory
(examples/enf_cohesive.toml), and a mixed-mode point of the FE model against the
Benzeggagh–Kenane fracture energy (issue 13)."""
import numpy as np
import pytest

from helpers import run_example
from layershell.io.build import build, parse
from layershell.runner import run

# inputs of examples/enf_cohesive.toml (T300/977-2, as examples/dcb_cohesive.toml)
E11, E22, G13 = 150000.0, 11000.0, 6000.0
B_W, H = 20.0, 1.98  # width, arm thickness
G_IC, G_IIC, ETA = 0.352, 1.002, 2.284
SIGMA_MAX = 30.0


def chi() -> float:
    """Crack-length correction of corrected beam theory, Williams (1989)."""
    gamma = 1.18 * np.sqrt(E11 * E22) / G13
    return float(np.sqrt(E11 / (11 * G13) * (3 - 2 * (gamma / (1 + gamma)) ** 2)))


def bk(B: float) -> float:
    """Benzeggagh & Kenane (1996): G_c = G_Ic + (G_IIc - G_Ic) B^η, B = G_II / G_T."""
    return G_IC + (G_IIC - G_IC) * B**ETA


# ---------------------------------------------------------------------- mixed mode, FE patch
def _patch_text(B: float, u_end: float, factors) -> str:
    """One 10 × 10 mm element, two CFRP layers joined by the cohesive interface of the ENF
    example. The lower layer is held (every director), the upper layer's bottom face (director
    u_0, the interface face) is moved by λ u_end in the fixed direction (sqrt(B), 0, sqrt(1-B)):
    every interface point follows the same proportional separation path with
    δ_s² / (δ_n² + δ_s²) = B, the mode ratio G_II / G_T of a cohesive law with one stiffness for
    both modes."""
    ux, uz = float(u_end * np.sqrt(B)), float(u_end * np.sqrt(1 - B))
    return f"""
[model]
element = "full"
title = "mixed-mode patch"
nonlinear = false
[mesh]
type = "rectangle"
lx = 10.0
ly = 10.0
nx = 1
ny = 1
[materials.cfrp]
type = "orthotropic"
E1 = {E11}
E2 = {E22}
E3 = {E22}
G12 = {G13}
G31 = {G13}
G23 = 3700.0
nu12 = 0.25
nu31 = 0.0183
nu23 = 0.45
[[layers]]
name = "lower"
material = "cfrp"
thickness = {H}
[[layers]]
name = "upper"
material = "cfrp"
thickness = {H}
[[supports]]
type = "fix"
where = "x > -1"
layer = "lower"
directors = "all"
[[supports]]
type = "fix"
where = "x > -1"
layer = "upper"
value = [{ux!r}, 0.0, {uz!r}]
[[interfaces]]
layer = "upper"
law = "cohesive"
G_Ic = {G_IC}
G_IIc = {G_IIC}
eta = {ETA}
sigma_max = {SIGMA_MAX}
tau_max = {SIGMA_MAX}
[steps]
factors = [{", ".join(repr(float(f)) for f in factors)}]
[[probes]]
name = "Px"
quantity = "reaction"
where = "x > -1"
layer = "upper"
component = "x"
[[probes]]
name = "Pz"
quantity = "reaction"
where = "x > -1"
layer = "upper"
component = "z"
"""


def mixed_mode_patch(B: float):
    """Run the patch at mode ratio B to 0.995 of the separation of complete failure; return the
    external work per area (trapezoid of the reactions over the prescribed displacement), the
    dissipated energy per area (summary.json), the peak and the last reaction and the summary.

    The end point comes from the law's inputs alone: onset by the thesis's criterion (4.15),
    τ = τ_max sqrt(1 - σ/σ_max) with τ/σ = sqrt(B/(1-B)) (one stiffness K = 50 E3/t), and the
    bilinear law's final separation λf = 2 G_c(B) / (K λ0). (Complete separation itself is not
    reached: the reactions vanish there and the Newton tolerance, relative to them, cannot be met
    - see the report of issue 13.)"""
    K = 50 * E22 / H  # the default penalty (Turon et al. 2007), both layers alike
    r2 = B / (1 - B)
    sig = (-SIGMA_MAX + np.sqrt(SIGMA_MAX**2 + 4 * r2 * SIGMA_MAX**2)) / (2 * r2)
    lam0 = sig * np.sqrt(1 + r2) / K
    lamf = 2 * bk(B) / (K * lam0)
    u_end = 0.995 * lamf
    f0 = lam0 / u_end  # the onset (peak) at this fraction of the path: fine steps up to 2 f0
    factors = np.r_[np.linspace(0, 2 * f0, 11)[1:], np.linspace(2 * f0, 1, 41)[1:]]
    spec = build(parse(_patch_text(B, u_end, factors), "mixed_mode_patch.toml"), None)
    r = run(spec, None, write_vtu=False)
    st = r.summary["steps"]
    lam = np.r_[0.0, [s["load_factor"] for s in st]]
    Px = np.r_[0.0, [s["probes"]["Px"] for s in st]]
    Pz = np.r_[0.0, [s["probes"]["Pz"] for s in st]]
    ux, uz = u_end * np.sqrt(B), u_end * np.sqrt(1 - B)
    W = float(np.sum(0.5 * (Px[1:] + Px[:-1]) * np.diff(lam) * ux + 0.5 * (Pz[1:] + Pz[:-1]) * np.diff(lam) * uz))
    A = 100.0
    P = np.hypot(Px, Pz)
    return {"W": W / A, "D": r.summary["energy"]["dissipated_fracture"] / A, "P_peak": P.max(), "P_end": P[-1],
            "summary": r.summary, "converged": r.converged}


@pytest.mark.parametrize("B", [0.2, 0.5, 0.8])
def test_mixed_mode_point_dissipates_bk_fracture_energy(B):
    """A mixed-mode point on the FE model (element, interface integration, supports, reactions,
    energy ledger): the interface of a patch is separated along a fixed mode ratio B = G_II/G_T
    to (nearly) complete failure. The work of the reactions on the prescribed displacement per
    area - independent of the law's own dissipation formula - equals the Benzeggagh–Kenane
    fracture energy G_c(B) within 0.1 % (measured -2.5e-5 at B = 0.2, 0.5, 0.8; at B = 0.5
    W/A = 0.48545 N/mm against G_c = 0.48546 N/mm), and the dissipated energy of summary.json
    within 1 % (measured -0.50 %: at 0.995 λf the last 0.5 % is still stored in the springs and
    the external work is their sum to round-off)."""
    res = mixed_mode_patch(B)
    assert res["converged"]
    assert res["P_end"] < 0.01 * res["P_peak"]  # (nearly) fully separated: the stored rest is < 1e-4 G_c
    assert res["W"] == pytest.approx(bk(B), rel=1e-3)
    assert res["D"] == pytest.approx(bk(B), rel=0.01)
    assert abs(res["summary"]["energy"]["balance_error"]) < 0.01


def test_complete_separation_under_prescribed_displacements_converges_without_false_jumps():
    """The patch separated past complete failure (to 4 λf at B = 0.5) under prescribed
    displacements: once nothing is attached, the reactions - the residual's scale under
    displacement control - vanish, and Newton chased round-off ("no convergence towards load
    factor 0.74", residual 4e-12). The scale now has a floor, 10⁻³ of the largest force scale of
    the run: every step converges. The reactions are then round-off (|P| < 1e-9 of the peak), and
    their ratio from step to step is no 'jump' warning any more (before: a dozen)."""
    import warnings

    from layershell.runner import JumpWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run(build(parse(_patch_text(0.5, 0.05, np.linspace(0.01, 1, 100)), "patch.toml")), None,
                write_vtu=False)
    assert r.converged and len(r.summary["steps"]) == 100
    P = np.array([np.hypot(s["probes"]["Px"], s["probes"]["Pz"]) for s in r.summary["steps"]])
    assert P[-1] < 1e-9 * P.max()
    jumps = [str(w.message) for w in caught if issubclass(w.category, JumpWarning)]
    assert not [m for m in jumps if "probe" in m], jumps
    assert len(jumps) == 1 and "debonded area" in jumps[0]  # the real jump: the patch fails at once


def test_viscous_dissipation_closes_the_energy_balance():
    """Viscous regularisation on the mixed-mode patch (B = 0.5, separated past complete failure
    in 100 steps): the viscous dissipation is the work of the cohesive tractions less the change
    of their stored energy less the rate-independent fracture energy, with the rule of the
    external work (trapezoid), so the ledger closes (measured 0 to round-off; the trapezoid of
    ½Kλ² over the damage increment used before gave -2.5 % at η = 0.01 and -34 % on the DCB). The
    viscous share grows with η (η = 0.01: 18.5 of 67.0; η = 0.1: 811 of 862), and the
    rate-independent fracture energy is G_c(B) × area."""
    out = []
    for eta in (0.01, 0.1):
        text = _patch_text(0.5, 0.05, np.linspace(0.01, 1, 100)).replace(
            'law = "cohesive"', f'law = "cohesive"\nviscosity = {eta}')
        r = run(build(parse(text, "patch.toml")), None, write_vtu=False)
        e = r.summary["energy"]
        assert r.converged and abs(e["balance_error"]) < 1e-6
        assert e["dissipated_viscous"] > 0
        out.append(e["dissipated_viscous"] / e["external_work"])
    assert out[1] > out[0] > 0.1
    assert e["dissipated_fracture"] == pytest.approx(bk(0.5) * 100.0, rel=0.05)  # 0.1: not yet fully damaged


# ---------------------------------------------------------------------- ENF against beam theory
L_HALF, A0 = 50.0, 35.0  # half span, initial crack of examples/enf_cohesive.toml
W_END = 1.95  # prescribed deflection at λ = 1


def crack_plus(a):
    """a + 0.42 χh, the crack length with the correction of Wang & Williams (1992)."""
    return a + 0.42 * chi() * H


def enf_compliance(a):
    """C(a) = (3 (a + 0.42 χh)³ + 2 L³) / (8 E11 b h³) + 3 L / (10 G13 b h): Russell & Street
    (1985) with the crack-length correction of Wang & Williams (1992) and the arms' transverse
    shear (de Moura & de Morais 2008)."""
    return (3 * crack_plus(a) ** 3 + 2 * L_HALF**3) / (8 * E11 * B_W * H**3) + 3 * L_HALF / (10 * G13 * B_W * H)


def enf_crack_from_compliance(C):
    """The crack length a whose beam-theory compliance is C (inverse of :func:`enf_compliance`)."""
    C_bend = np.asarray(C) - 3 * L_HALF / (10 * G13 * B_W * H)
    return ((8 * E11 * B_W * H**3 * C_bend - 2 * L_HALF**3) / 3) ** (1 / 3) - 0.42 * chi() * H


def enf_load(a):
    """Load at G_II = G_IIc: P(a) = 4 b / (3 (a + 0.42 χh)) sqrt(E11 h³ G_IIc)."""
    return 4 * B_W / (3 * crack_plus(a)) * np.sqrt(E11 * H**3 * G_IIC)


def test_enf_initial_compliance_against_beam_theory():
    """ENF (examples/enf_cohesive.toml) before damage: deflection under the load / load within
    2 % of beam theory with the Wang & Williams (1992) crack-length correction and the arms'
    transverse shear (:func:`enf_compliance`; measured +0.3 %). Without the shear term the
    shell model is 3 % softer than beam theory (it has the transverse shear that Euler-Bernoulli
    arms leave out). At λ = 0.02 (w = 0.039 mm, P ≈ 18 N), far below the onset."""
    r = run_example("enf_cohesive", {"n = 40\nadaptive = true": "factors = [0.02]\n#"})
    st = r.summary["steps"][0]
    assert r.summary["first_damage_load_factor"] is None
    C = st["probes"]["w_load"] / st["probes"]["P"]
    assert st["probes"]["w_load"] == pytest.approx(0.02 * W_END, rel=1e-3)  # the probe sits on the pushed face
    assert C == pytest.approx(enf_compliance(A0), rel=0.02)
    C_no_shear = enf_compliance(A0) - 3 * L_HALF / (10 * G13 * B_W * H)
    assert C > 1.02 * C_no_shear


def enf_branch(nx: int = 100):
    """examples/enf_cohesive.toml on ``nx`` elements (displacement control to w = 1.95 mm): the
    load P, the deflection w, the crack length inferred from each state's compliance, the
    dissipated energy per step, the summary and the x-range of the partly damaged interface
    points at the end (the process zone spread across the width of the curved front)."""
    r = run_example("enf_cohesive", {"nx = 100": f"nx = {nx}"})
    steps = r.summary["steps"]
    P = np.array([s["probes"]["P"] for s in steps])
    w = np.array([s["probes"]["w_load"] for s in steps])
    D = np.array([s["energy"]["dissipated_fracture"] for s in steps])
    blk = r.problem.extra_blocks[0]
    x_pz = blk.X0[..., 0][(blk.d_old > 0) & (blk.d_old < 1 - 1e-9)]
    return P, w, enf_crack_from_compliance(w / P), D, r.summary, (x_pz.min(), x_pz.max())


@pytest.fixture(scope="module")
def enf_100():
    return enf_branch(100)


@pytest.mark.slow
def test_enf_propagation_branch_against_beam_theory(enf_100):
    """ENF under displacement control (examples/enf_cohesive.toml, 100 elements, node spacing
    0.5 mm, 105 s): the crack grows stably from a0 = 35 mm to 46.6 mm (inferred from the
    compliance). The peak (721 N) lies on the beam-theory curve P(a) (Wang & Williams 1992) at the
    crack length inferred from its compliance, a = 38.7 mm (+0.8 %; 8.4 % below P(a0): the
    mode-II process zone, 1.5-2 mm from the onset to full damage along the middle of the width and
    spread over about 5 mm across the curved front, forms before the crack runs),
    and every state past it within 3 % (measured +0.6 ... +2.1 %). The energy dissipated from
    the peak to the end equals G_IIc b Δa within 3 % (measured +1.4 %); from the start, with the
    initial crack a0, -3.9 %: at the end the process zone has dissipated only part of its
    energy. External work = stored + dissipated within 1 % (measured 0.14 %)."""
    P, w, a, D, summary, (x0, x1) = enf_100
    assert summary["converged"] and w[-1] == pytest.approx(W_END, rel=1e-3)
    peak = int(np.argmax(P))
    assert peak < len(P) - 8, "no propagation branch traced"
    assert P[peak] == pytest.approx(enf_load(a[peak]), rel=0.03)
    ratio = P[peak + 1:] / enf_load(a[peak + 1:])
    assert np.all(np.abs(ratio - 1) < 0.03), ratio
    assert a[-1] > 45.0
    assert D[-1] - D[peak] == pytest.approx(G_IIC * B_W * (a[-1] - a[peak]), rel=0.03)
    assert D[-1] == pytest.approx(G_IIC * B_W * (a[-1] - A0), rel=0.06)
    # the partly damaged points (process zone and curved front) span at least 3 node spacings of 0.5 mm
    assert x1 - x0 >= 1.5
    assert abs(summary["energy"]["balance_error"]) < 0.01


@pytest.mark.slow
def test_enf_branch_on_a_finer_mesh(enf_100):
    """ENF on 150 elements (node spacing 0.33 mm): the run reaches its end (before the active-set
    loop's consistency tolerance it stopped at a = 45 mm, where no loading set was exactly
    consistent as the front passed a node), every state past the peak within 3 % of beam theory
    at its compliance-inferred crack length (measured -1.1 ... +1.8 %), the peak within 1.5 % of
    the 100-element one (714.3 against 721.3 N), energy balance within 1 % (0.1 %). About 2 CPU
    minutes. (On 200 elements the run reaches 99.8 % of the end in 13 minutes, then stops.)"""
    P, w, a, D, summary, _ = enf_branch(150)
    assert summary["converged"] and w[-1] == pytest.approx(W_END, rel=1e-3)
    peak = int(np.argmax(P))
    assert peak < len(P) - 8
    ratio = P[peak + 1:] / enf_load(a[peak + 1:])
    assert np.all(np.abs(ratio - 1) < 0.03), ratio
    assert a[-1] > 45.0
    assert P[peak] == pytest.approx(enf_100[0].max(), rel=0.015)
    assert abs(summary["energy"]["balance_error"]) < 0.01


def _ledger_on_turning_path(n: int):
    """A single cohesive point whose separation turns from pure opening to pure shear while it
    grows from 0 to 0.03 mm in ``n`` steps (non-proportional: the mode ratio changes while the
    point softens): the fracture energy booked by the ledger's rule
    (:func:`~layershell.cohesive.path_dissipation`, solver/interface_state.py) and by the
    earlier rule, the closed form :func:`~layershell.cohesive.dissipated` at the mode ratio of
    each step's end."""
    from layershell.cohesive import (CohesiveLaw, dissipated, path_dissipation, point_response,
                                     separation_measures)

    law = CohesiveLaw(G_Ic=G_IC, G_IIc=G_IIC, sigma_max=SIGMA_MAX, tau_max=SIGMA_MAX, eta=ETA)
    K = 50 * E22 / H
    nrm = np.array([[0.0, 0.0, 1.0]])

    def path(s):
        th, r = 0.5 * np.pi * s, 0.03 * s
        return np.array([[r * np.sin(th), 0.0, r * np.cos(th)]])

    d_old, booked, end_ratio = np.zeros(1), 0.0, 0.0
    x_prev = path(0.0)
    for s in np.linspace(0, 1, n + 1)[1:]:
        x = path(s)
        _, d, _ = point_response(x, nrm, d_old, K, law, tangent=False)
        B = separation_measures(x, nrm)[3]
        d = np.maximum(d, d_old)
        booked += float(path_dissipation(x_prev, x, nrm, d_old, d, K, law).sum())
        end_ratio += float(np.where(d > d_old, dissipated(d, B, K, law) - dissipated(d_old, B, K, law), 0.0).sum())
        x_prev, d_old = x, d
    return booked, end_ratio, float(d_old[0])


def test_fracture_ledger_converges_on_a_turning_mode_ratio():
    """The ledger integrates a point's damage along the straight separation path between the
    converged states in sub-steps, each at its own mode ratio. On a path whose mode ratio turns
    from I to II while the point softens (to d = 0.998) it is of second order in the step
    against a 1000-step reference (measured 9.5e-5 and 6.1e-6 of the dissipation at 50 and 200
    steps), where the closed form at the step's end ratio - the earlier ledger - is of first
    order (5.1e-3, 1.3e-3)."""
    ref, _, d_end = _ledger_on_turning_path(1000)
    assert 0.99 < d_end < 1.0
    (b50, e50, _), (b200, e200, _) = _ledger_on_turning_path(50), _ledger_on_turning_path(200)
    err = [abs(b50 - ref) / ref, abs(b200 - ref) / ref]
    assert err[0] < 5e-4 and err[1] < err[0] / 8
    assert abs(e50 - ref) / ref > 10 * err[0]  # the earlier rule, first order


@pytest.mark.slow
def test_enf_keeps_the_full_element_because_mitc9_stops_before_the_crack_grows():
    """Why examples/enf_cohesive.toml sets element = "full": with MITC9 (100 elements) the run
    stops at λ = 0.8997 (w = 1.754 mm, P = 773 N, above the full element's peak of 721 N, the
    crack not yet grown): through 7 step cuts the contact sets keep changing after the allowed
    active-set loops. The runner's message names the ways past such a step (arc length, relax,
    viscous stabilisation). About 85 s."""
    r = run_example("enf_cohesive", {'element = "full"': 'element = "mitc"'})
    assert not r.converged
    assert 0.85 < r.failure["load_factor"] < 0.95
    assert "contact set still changing" in r.summary["error"]
    steps = r.summary["steps"]
    assert max(s["probes"]["P"] for s in steps) > 721.3
    assert steps[-1]["probes"]["A_debonded"] == steps[0]["probes"]["A_debonded"]
