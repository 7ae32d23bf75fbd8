"""Double cantilever beam (mode I) with a cohesive interface against corrected beam theory
(Williams 1989), examples/dcb_cohesive.toml."""
import numpy as np
import pytest

from helpers import run_example

# inputs of examples/dcb_cohesive.toml
E11, E22, G13 = 150000.0, 11000.0, 6000.0
B, H, A0, GIC = 20.0, 1.98, 55.0, 0.352


def chi() -> float:
    """Crack-length correction of corrected beam theory, Williams (1989)."""
    gamma = 1.18 * np.sqrt(E11 * E22) / G13
    return float(np.sqrt(E11 / (11 * G13) * (3 - 2 * (gamma / (1 + gamma)) ** 2)))


def cbt_compliance(a: float) -> float:
    """Opening / load of both arms, C = 8 (a + χh)³ / (E11 b h³)."""
    return 8 * (a + chi() * H) ** 3 / (E11 * B * H**3)


def cbt_load(a: float) -> float:
    """Load at G = G_Ic: P = b / (a + χh) sqrt(G_Ic E11 h³ / 12)."""
    return B / (a + chi() * H) * np.sqrt(GIC * E11 * H**3 / 12)


def opening(step) -> float:
    p = step["probes"]
    return p["w_upper"] - p["w_lower"]


def test_dcb_initial_compliance_against_corrected_beam_theory():
    """Below the onset of damage the opening/load ratio of the DCB (55 mm initial crack) is
    within 3 % of corrected beam theory."""
    r = run_example("dcb_cohesive", {"nx = 150": "nx = 75", "factors = [0.01, 0.02, 0.05,": "factors = [0.05] #"})
    st = r.summary["steps"][0]
    C = opening(st) / st["probes"]["P"]
    assert C == pytest.approx(cbt_compliance(A0), rel=0.03)
    assert r.summary["first_damage_load_factor"] is None  # nothing damaged yet at 5 N


#: examples/dcb_cohesive.toml under displacement control: the arms' bottom faces at x = 0 opened by
#: λ × 5 mm each (rotation free), the opening force as the reaction on one arm
DISPLACEMENT_CONTROL = {
    '[[loads]]                 # upper arm pulled up': '[[supports]]\ntype = "fix"\nwhere = "near(x, 0)"\nlayer = "upper"\n'
    'components = ["z"]\nvalue = [5.0]\n\n[[supports]]\ntype = "fix"\nwhere = "near(x, 0)"\nlayer = "lower"\n'
    'components = ["z"]\nvalue = [-5.0]\n\n[[loads]]                 # upper arm pulled up',
    '[[probes]]\nname = "P"               # opening force, N\nquantity = "load_factor"\nscale = 100.0':
    '[[probes]]\nname = "P"\nquantity = "reaction"\nwhere = "near(x, 0)"\nlayer = "upper"\ncomponent = "z"\n\n'
    '[[probes]]\nname = "P_lower"\nquantity = "reaction"\nwhere = "near(x, 0)"\nlayer = "lower"\ncomponent = "z"\n\n'
    '[[probes]]\nname = "P_all"\nquantity = "reaction"\nwhere = "near(x, 0)"\ncomponent = "z"',
    "distribution = \"where(t > 1.98, 2.5252525, 0.0)\"": "distribution = 0.0",
    "distribution = \"where(t < 1.98, 2.5252525, 0.0)\"": "distribution = 0.0",
}


def test_displacement_control_reaction_on_one_arm_equals_force_control():
    """The DCB opened by prescribed displacements (λ × 5 mm per arm) before damage: the reaction
    on the upper arm's loaded end (a `layer` reaction probe) is the opening force. Independent
    check: the force-controlled DCB's compliance (opening / applied load) gives the same force
    for the same opening (linear, undamaged); the lower arm carries the
    opposite force, so the reaction over all layers is zero."""
    lam = 0.02  # δ = 0.2 mm, P ≈ 2.9 N: far below the onset
    rd = run_example("dcb_cohesive", {"nx = 150": "nx = 75", "factors = [0.01, 0.02, 0.05,": f"factors = [{lam}] #",
                                      **DISPLACEMENT_CONTROL})
    rf = run_example("dcb_cohesive", {"nx = 150": "nx = 75", "factors = [0.01, 0.02, 0.05,": "factors = [0.05] #"})
    assert rd.converged and rf.converged and rd.summary["first_damage_load_factor"] is None
    pd, sf = rd.summary["steps"][0]["probes"], rf.summary["steps"][0]
    # the probes sit at the arms' mid-thickness, the prescribed faces at their bottom faces
    assert opening(rd.summary["steps"][0]) == pytest.approx(10.0 * lam, rel=1e-3)
    C = opening(sf) / sf["probes"]["P"]  # force control: compliance at the same probes
    # the same to 2e-3: force control spreads the load over the end faces, displacement control
    # pins the bottom face (measured 5e-4; a reaction summing the wrong DOFs is off by O(1))
    assert pd["P"] > 0 and pd["P"] == pytest.approx(opening(rd.summary["steps"][0]) / C, rel=2e-3)
    # equal and opposite up to the residual the run is solved to (relative 1e-8 of the reaction
    # norm, summed over the edge's nodes): 1e-6
    assert pd["P_lower"] == pytest.approx(-pd["P"], rel=1e-6)
    assert abs(pd["P_all"]) < 1e-6 * pd["P"]


def check_peak(steps) -> dict:
    """The last converged state under force control (the peak): its load P, the crack length that
    corrected beam theory infers from its secant compliance, and the beam-theory load there."""
    last = steps[-1]
    P, d = last["probes"]["P"], opening(last)
    a_plus = (d / P * E11 * B * H**3 / 8) ** (1 / 3)  # a + χh from C = 8 (a + χh)³ / (E b h³)
    return {"P": P, "a": a_plus - chi() * H, "P_cbt": B / a_plus * np.sqrt(GIC * E11 * H**3 / 12)}


@pytest.mark.slow
def test_dcb_peak_under_force_control_against_corrected_beam_theory():
    """Under force control the DCB (150 elements, 2 node spacings in the process zone) runs to
    its peak and stops there. The peak state lies on the corrected-beam-theory propagation curve:
    the load is within 3 % of P_CBT at the crack length inferred from the state's compliance
    (measured: 62.0 N at the last completed step against 60.6 N, +2.3 %), and the crack has
    started to grow (a = 57.4 mm). (The beam-theory load at the initial crack, 63.1 N, is 4.9 %
    higher: the process zone has already moved the effective crack tip.)"""
    r = run_example("dcb_cohesive")
    assert not r.summary["converged"]  # force control cannot pass the peak
    pk = check_peak(r.summary["steps"])
    assert pk["a"] > A0
    assert pk["P"] == pytest.approx(pk["P_cbt"], rel=0.03)
    assert r.summary["first_delamination_load_factor"] is not None
    e = r.summary["energy"]
    assert abs(e["balance_error"]) < 0.01


def displacement_controlled(nx: int, element: str = "full"):
    """examples/dcb_cohesive.toml with ``nx`` elements along its length (and ``element``), opened
    under displacement control (DISPLACEMENT_CONTROL) to δ = 10 mm with adaptive steps: the load P
    (reaction on the upper arm), the opening δ and the summary."""
    r = run_example("dcb_cohesive", {**DISPLACEMENT_CONTROL, "nx = 150": f"nx = {nx}",
                                     'element = "full"': f'element = "{element}"',
                                     "factors = [0.01, 0.02, 0.05,": "n = 100\nadaptive = true\nincrement_max = 0.02 #"})
    steps = r.summary["steps"]
    P = np.array([s["probes"]["P"] for s in steps])
    d = np.array([opening(s) for s in steps])
    return P, d, r.summary


@pytest.fixture(scope="module")
def dcb_200():
    """The displacement-controlled DCB on 200 elements (node spacing 0.375 mm; the process zone,
    about 1.1 mm between the onset and full damage along the middle of the width, spans 3 of them;
    partly damaged points spread over about 2 mm across the curved front)."""
    return displacement_controlled(200)


def cbt_load_at(P: np.ndarray, d: np.ndarray) -> np.ndarray:
    """Beam-theory load P(a) at the crack length that corrected beam theory infers from the
    secant compliance C = δ/P of each state (Williams 1989)."""
    a_plus = (d / P * E11 * B * H**3 / 8) ** (1 / 3)  # a + χh
    return B / a_plus * np.sqrt(GIC * E11 * H**3 / 12)


@pytest.mark.slow
def test_dcb_propagation_branch_against_corrected_beam_theory(dcb_200):
    """Propagation branch under displacement control (200 elements): the run opens the DCB to
    δ = 10 mm (the crack grows from 55 to about 84 mm), and at every state past the peak the load is
    within 3 % of the beam-theory load at the crack length inferred from its compliance
    (measured: within -0.3 ... +1.8 %, a saw-tooth as the front passes node by node; on 150
    elements -0.1 ... +3.0 %). The energy dissipated by fracture equals G_Ic times the crack area that beam
    theory infers from the final compliance, within 3 % (the crack front is a process zone,
    not a line)."""
    P, d, summary = dcb_200
    assert summary["converged"] and d[-1] == pytest.approx(10.0, rel=1e-3)
    peak = int(np.argmax(P))
    assert peak < len(P) - 10, "no propagation branch traced"
    ratio = P[peak + 1:] / cbt_load_at(P[peak + 1:], d[peak + 1:])
    assert np.all(np.abs(ratio - 1) < 0.03), ratio
    a_end = (d[-1] / P[-1] * E11 * B * H**3 / 8) ** (1 / 3) - chi() * H
    assert a_end > 75.0
    e = summary["energy"]
    assert e["dissipated_fracture"] == pytest.approx(GIC * B * (a_end - A0), rel=0.03)  # measured -1.6 %
    # external work (the reaction's work on the prescribed opening, trapezoid over the steps) =
    # strain energy + interface energy + dissipation: measured 0.9 % (the trapezoid over-counts
    # the steps in which the load drops as the front passes a node; 1.9 % on 150 elements)
    assert abs(e["balance_error"]) < 0.01


def branch_deviation(P: np.ndarray, d: np.ndarray) -> float:
    """The largest deviation of the load past the peak from beam theory at the compliance-inferred crack length."""
    peak = int(np.argmax(P))
    return float(np.abs(P[peak + 1:] / cbt_load_at(P[peak + 1:], d[peak + 1:]) - 1).max())


@pytest.mark.slow
def test_dcb_branch_converges_on_three_meshes(dcb_200):
    """Mesh convergence of the DCB under displacement control on 150, 200 and 300 elements
    (node spacings 0.5, 0.375, 0.25 mm; the process zone along the middle of the width, 1.0-1.25 mm,
    spans 2, 3 and 5 of them): every
    run reaches δ = 10 mm, and the largest deviation of the propagation branch from beam theory
    falls monotonically, at an observed order above 1 in the node spacing (measured 3.0, 1.7 and
    0.48 %: orders 2.0 and 3.1 - the saw-tooth of the front passing node by node), to within
    1 % on 300 elements. On 300 elements the run needs the active-set loop's consistency
    tolerance (solver/newton.py ActiveSetLoop): without it the run stopped at δ = 5.2 mm, where
    no loading set was consistent as the front passed a node; the accepted states violate the
    damage law by less than 10⁻³ of the strength, and the energy balance closes within 1 %
    (measured 0.08 %). About 10 CPU minutes."""
    h = [0.5, 0.375, 0.25]
    runs = [displacement_controlled(150), dcb_200, displacement_controlled(300)]
    for P, d, summary in runs:
        assert summary["converged"] and d[-1] == pytest.approx(10.0, rel=1e-3)
        assert abs(summary["energy"]["balance_error"]) < 0.02
    dev = [branch_deviation(P, d) for P, d, _ in runs]
    assert dev[0] > dev[1] > dev[2] and dev[2] < 0.01, dev
    orders = [np.log(dev[0] / dev[1]) / np.log(h[0] / h[1]), np.log(dev[1] / dev[2]) / np.log(h[1] / h[2])]
    assert min(orders) > 1.0, orders
    fine = runs[2][2]
    assert abs(fine["energy"]["balance_error"]) < 0.01
    assert fine.get("active_set", {}).get("largest_violation", 0.0) <= 1e-3


def _tractions_ahead_of_tip(rule: str):
    from pathlib import Path

    from helpers import EXAMPLES
    from layershell.io.build import build, parse
    from layershell.solver.newton import newton
    from layershell.solver.problem import Problem

    text = (Path(EXAMPLES) / "dcb_cohesive.toml").read_text().replace("nx = 150", "nx = 75")
    spec = build(parse(text.replace("eta = 2.284", f'eta = 2.284\nrule = "{rule}"'), "dcb"))
    pb = Problem.build(spec.model)
    u, res = newton(pb, np.zeros(pb.dm.n_full), 0.05, spec.newton)
    assert res.converged
    blk = pb.extra_blocks[0]
    T, *_ = blk.tractions(u)
    X, Y = blk.X0[..., 0], blk.X0[..., 1]
    m = (np.abs(Y - 10) < 1.0) & (X > 54.9) & (X < 66)
    o = np.argsort(X[m])
    return X[m][o], T[..., 2][m][o]


def test_nodal_integration_avoids_traction_oscillations():
    """Peel stresses ahead of the DCB crack tip with the stiff default penalty: the beam on an
    elastic foundation gives a smooth field - tension at the tip, then one change to a decaying
    compression. Nodal (Lobatto) integration reproduces that; 3×3 Gauss integration makes the
    tractions oscillate from point to point with several times the amplitude (Schellekens &
    de Borst 1993)."""
    x, t_lob = _tractions_ahead_of_tip("lobatto")
    _, t_gauss = _tractions_ahead_of_tip("gauss")
    sign_changes = lambda t: int(np.sum(np.diff(np.sign(t[np.abs(t) > 1e-9])) != 0))  # noqa: E731
    assert t_lob[0] > 0 and sign_changes(t_lob) == 1
    assert sign_changes(t_gauss) >= 4
    assert np.abs(t_gauss).max() > 3 * np.abs(t_lob).max()



def test_fracture_energy_per_point_tells_the_process_zone_from_the_debonded_zone():
    """The interface VTU's `fracture_energy` per point, on the DCB (mode I) opened under
    displacement control until the crack has grown by a few nodes (150 elements, δ = 4.5 mm).
    Independent reference: every point that debonded along its (proportional, mode I) path has
    dissipated G_Ic, the input fracture energy (closed form of the bilinear law). With the stiff
    default penalty the process-zone points ahead of them have damage d > 0.98, yet they have
    dissipated only part of G_Ic: `damage` alone makes the process zone look debonded, the
    `process_zone` flag and `fracture_energy` tell it apart. The points' energies sum, weighted by
    their areas, to the ledger's `dissipated_fracture`."""
    from layershell.export import interface_mesh
    from layershell.interfaces import interfaces

    r = run_example("dcb_cohesive", {**DISPLACEMENT_CONTROL, "factors = [0.01, 0.02, 0.05,":
                                     "factors = [0.1, 0.2, 0.3, 0.35, 0.4, 0.45] #"})
    assert r.converged
    run = r.problem.interfaces.runs[0]
    w, frac, d = run.block.contact.w, run.fracture, run.block.d_old
    assert (w * frac).sum() == pytest.approx(r.summary["energy"]["dissipated_fracture"], rel=1e-12)
    debonded = run.block.released & ~run.initial
    zone = (d > 0) & ~run.block.released
    assert debonded.sum() >= 3 and zone.sum() >= 3  # the crack has grown and a process zone leads it
    np.testing.assert_allclose(frac[debonded], GIC, rtol=1e-6)
    assert np.all(frac[run.initial] == 0.0)  # the starter crack dissipated nothing
    assert d[zone].max() > 0.98 and 0.0 < frac[zone].min() and frac[zone].max() < 0.9 * GIC
    pb = r.problem
    pd = interface_mesh(pb.model, pb.dm, r.u, interfaces(pb.model)[0], run=run, load_factor=0.45).point_data
    assert pd["process_zone"].sum() == zone.sum() and pd["debonded"].sum() == run.block.released.sum()
    assert np.sort(pd["fracture_energy"]) == pytest.approx(np.sort(frac.ravel()), abs=1e-15)


@pytest.mark.slow
def test_force_loaded_dcb_by_arc_length_to_complete_separation():
    """The force-loaded DCB on 150 elements traced by arc length (dissipation constraint) from the
    start through the peak to complete separation. Independent check: with the interface fully
    damaged from a0 to the clamped end in mode I, the energy dissipated by fracture is
    G_Ic b (L - a0) (measured -0.01 %); the energy balance closes at every step within 1 %
    (measured 0.31 %). The path never crosses λ = 0: before that was excluded under the
    dissipation constraint, an increment from λ = 0.42 'converged' at λ = -0.03 with the arms
    shut (an elastic path through crack closure meets ΔG = Δτ without damage; energy balance
    7.1 %) and the run ended there as 'complete failure'. The propagation states (opening
    growing, load above 30 % of the peak) follow corrected beam theory: their median within 1 %
    (measured 0.996-0.999), none more than 5 % above it (measured +2.8 ... +3.0 %). Below it
    the front's saw-tooth (two node spacings in the process zone: after a node row releases the
    load drops) reaches as deep as the increments happen to sample it: -2.7 % with the default
    step control on one machine, -9.3 % after a round-off change of the geometry, -16 % with
    ``target_iterations = 6`` (the same code), so the states are only held above -20 %. (Under
    displacement control on 150 elements -0.1 ... +3.0 %.) About 1.5 CPU minutes."""
    r = run_example("dcb_cohesive", {"factors = [0.01, 0.02, 0.05,":
                                     'control = "arc_length"\nn = 50\nmax_steps = 2000\n#'})
    s = r.summary
    steps = s["steps"]
    assert r.converged and s["path_end"] == "complete failure"
    lam = np.array([st["load_factor"] for st in steps])
    P = np.array([st["probes"]["P"] for st in steps])
    d = np.array([opening(st) for st in steps])
    assert lam.min() >= 0.0 and d[-1] > 5.0
    assert P[-1] < 1e-3 * P.max()
    assert s["energy"]["dissipated_fracture"] == pytest.approx(GIC * B * (150.0 - A0), rel=0.01)
    assert max(abs(st["energy"]["balance_error"]) for st in steps) < 0.01
    peak = int(np.argmax(P))
    grow = (np.arange(P.size) > peak) & (P > 0.3 * P.max()) & np.r_[True, np.diff(d) > 0]
    assert grow.sum() > 30
    ratio = P[grow] / cbt_load_at(P[grow], d[grow])
    assert abs(np.median(ratio) - 1) < 0.01, ratio
    assert np.all((ratio > 0.8) & (ratio < 1.05)), ratio


def displacement_by_arc_length(nx: int, element: str = "full"):
    """examples/dcb_displacement.toml (the DISPLACEMENT_CONTROL model with control = "arc_length":
    λ scales the prescribed opening and may fall) with ``nx`` elements, traced to δ = 10 mm: P, δ,
    λ and the summary."""
    repl = {"nx = 150": f"nx = {nx}"}
    if element != "full":
        repl['element = "full"'] = f'element = "{element}"'
    r = run_example("dcb_displacement", repl)
    steps = r.summary["steps"]
    return (np.array([s["probes"]["P"] for s in steps]), np.array([opening(s) for s in steps]),
            np.array([s["load_factor"] for s in steps]), r.summary)


def test_displacement_example_is_the_displacement_controlled_dcb():
    """examples/dcb_displacement.toml is examples/dcb_cohesive.toml with the supports, probes and
    zero loads of DISPLACEMENT_CONTROL (the model the tests above check) and arc-length steps: the
    same model, stiffness for stiffness."""
    from pathlib import Path

    from helpers import EXAMPLES
    from layershell.io.build import build, parse

    text = (Path(EXAMPLES) / "dcb_cohesive.toml").read_text()
    for a, b in DISPLACEMENT_CONTROL.items():
        text = text.replace(a, b)
    ref = build(parse(text, "ref"))
    ex = build(parse((Path(EXAMPLES) / "dcb_displacement.toml").read_text(), "ex"))
    assert ex.path_following is not None and ex.path_following.control == "arc_length"
    assert [(f.layer, f.components, f.value) for f in ex.model.fixes] == [(f.layer, f.components, f.value)
                                                                           for f in ref.model.fixes]
    assert ex.model.interface_laws == ref.model.interface_laws
    assert np.array_equal(ex.model.mesh.nodes, ref.model.mesh.nodes)


def _check_opening_traced_to_the_end(P, d, lam, summary, branch: float, dissipated: float):
    """δ = 10 mm reached (λ_end), the energy balance within 1 % at every step, the states past the
    peak within ``branch`` of beam theory at their compliance-inferred crack length, the fracture
    energy within ``dissipated`` of G_Ic b Δa (Δa from the final compliance)."""
    assert summary["converged"] and summary["path_end"] == "lambda_end"
    assert lam[-1] == 1.0 and d[-1] == pytest.approx(10.0, rel=1e-3)
    assert max(abs(s["energy"]["balance_error"]) for s in summary["steps"] if s.get("energy")) < 0.01
    peak = int(np.argmax(P))
    assert d[peak] < 6.0 and P[-1] < 0.75 * P[peak]  # through the peak and down the branch
    ratio = P[peak + 1:] / cbt_load_at(P[peak + 1:], d[peak + 1:])
    assert np.all(np.abs(ratio - 1) < branch), ratio
    a_end = (d[-1] / P[-1] * E11 * B * H**3 / 8) ** (1 / 3) - chi() * H
    assert summary["energy"]["dissipated_fracture"] == pytest.approx(GIC * B * (a_end - A0), rel=dissipated)
    return ratio


@pytest.mark.slow
def test_prescribed_opening_by_arc_length_passes_the_snap_backs_on_three_meshes():
    """The prescribed opening of the DCB traced by arc length (λ scales the opening; the
    dissipation constraint takes over once the crack grows). Under displacement control with
    adaptive steps the 100-element run stops at δ = 5.45 mm: each node row's release is a
    snap-back of the discrete path (the opening must fall while the crack grows), which steps
    of a growing opening cannot pass. By arc length the opening falls where the path does:
    100 elements reach δ = 10 mm through snap-backs (λ falls in 163 of 277 increments), the
    energy balance within 1 % at every step (measured 0.84 % at most; load control on 150
    elements ends at 1.8 %: it converges across the jumps, whose released energy no path
    carries). Independent references: corrected beam theory (Williams 1989) for the states past
    the peak at their compliance-inferred crack length (measured -11.4 ... +7.1 % on 100 elements,
    the saw-tooth of a mesh with 2.45 node spacings in the process zone; -1.4 ... +1.7 % on 150,
    -0.8 ... +1.7 % on 200) and G_Ic times the crack area beam theory infers from the final
    compliance for the fracture energy (-3.3, -1.5, -1.6 %). The median of the branch converges:
    +3.7, -0.3, -0.2 %. About 2.5 minutes."""
    P, d, lam, s = displacement_by_arc_length(100)
    ratio = _check_opening_traced_to_the_end(P, d, lam, s, branch=0.15, dissipated=0.05)
    assert np.sum(np.diff(lam) < 0) > 20  # snap-backs: the prescribed opening falls
    medians = [np.median(ratio) - 1]
    for nx in (150, 200):
        P, d, lam, s = displacement_by_arc_length(nx)
        ratio = _check_opening_traced_to_the_end(P, d, lam, s, branch=0.03, dissipated=0.03)
        medians.append(np.median(ratio) - 1)
    assert abs(medians[1]) < 0.01 and abs(medians[2]) < 0.01 and abs(medians[0]) > abs(medians[2])


@pytest.mark.slow
def test_prescribed_opening_by_arc_length_with_mitc9():
    """The MITC9 DCB on 200 elements under displacement control stops at δ = 5.28 mm (its frozen
    cohesive sets cycling where the front passes a node); its prescribed opening traced by arc
    length reaches δ = 10 mm (measured 38 increments, 330 Newton iterations, against 6 986
    iterations with [steps] unstable = "relax"), the energy balance within 1 % at every step
    (measured 0.29 %), the branch within 1.5 % of beam theory (measured -0.85 ... +0.57 %) and
    the fracture energy within 3 % of G_Ic b Δa (measured -1.5 %). About 70 s."""
    P, d, lam, s = displacement_by_arc_length(200, element="mitc")
    _check_opening_traced_to_the_end(P, d, lam, s, branch=0.015, dissipated=0.03)


@pytest.mark.slow
def test_dcb_keeps_the_full_element_because_mitc9_stops_under_displacement_control():
    """Why examples/dcb_cohesive.toml sets element = "full": opened under displacement control
    (DISPLACEMENT_CONTROL, 150 elements, adaptive steps) the MITC9 DCB stops at δ = 7.5 mm of
    10 (λ = 0.746): no step cut finds a consistent cohesive loading set where the front passes a
    node (the full element reaches δ = 10 mm, docs/user-guide.md); by arc length on 200 elements
    MITC9 reaches the end (test above). About 90 s."""
    P, d, s = displacement_controlled(150, "mitc")
    assert not s["converged"] and 5.0 < d[-1] < 9.0
    assert "loading set cycles" in s["error"]
