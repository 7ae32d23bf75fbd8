"""Delamination and contact through the whole pipeline (MODEL.md §9-§10, issue 4)."""
import re
import warnings

import numpy as np

import pytest
from helpers import EXAMPLES, TIGHT_BOUND, TIGHT_STEPS, example_spec, run_example, stopped_and_restarted

from layershell.delamination import InterfaceLaw
from layershell.interfaces import interface_state, interfaces
from layershell.io.build import build, parse
from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import Fix, Layer, Model, SurfaceLoad
from layershell.solver.interface_state import contact_move_message
from layershell.solver.newton import contact_hint, load_steps
from layershell.solver.problem import Problem


def _block(released_all=True, pressure=1.0, rule="gauss"):
    """Two layers on a vertically supported base; the upper layer pressed by ``pressure`` on top
    (``rule``: the contact's face points)."""
    mesh = rectangle(2.0, 1.0, 2, 1)
    x = mesh.nodes
    H2 = 0.05
    layers = [Layer("base", Orthotropic.isotropic(1e4, 0.0), 2, np.full(mesh.n_nodes, 0.2)),
              Layer("top", Orthotropic.isotropic(2e4, 0.0), 2, np.full(mesh.n_nodes, H2))]
    n0 = np.flatnonzero(np.isclose(x[:, 0], 0) & np.isclose(x[:, 1], 0))
    n1 = np.flatnonzero(np.isclose(x[:, 0], 2) & np.isclose(x[:, 1], 0))
    m = Model(mesh, layers, [(0, 1)], np.zeros(mesh.n_elements, int),
              fixes=[Fix(np.arange(mesh.n_nodes), 0, (0,), (2,)), Fix(n0, 0, (0,), (0, 1)), Fix(n1, 0, (0,), (1,))],
              surface_loads=[SurfaceLoad(np.arange(mesh.n_elements), "top", np.array([0, 0, -1.0]),
                                         lambda x, y, z: pressure + 0 * x)])
    m.interface_laws = {1: InterfaceLaw(1.0, 1.0, mu0=0.5, rule=rule)}
    if released_all:
        m.initially_debonded = {1: np.arange(mesh.n_nodes)}
    # tangential restraint of the released top layer: fix its in-plane motion at two nodes
    m.fixes += [Fix(n0, 1, (0,), (0, 1)), Fix(n1, 1, (0,), (1,))]
    return m, H2


@pytest.mark.parametrize("rule", ["gauss", "lobatto"])
def test_closing_contact_carries_the_pressure_without_penetration(rule):
    """A fully debonded top layer pressed onto the base: the penalty contact carries the
    pressure and the penetration stays below 1e-3 of the layer thickness, with the contact at
    the face Gauss points (the thesis's) or at the nodes."""
    m, H2 = _block(pressure=5.0, rule=rule)
    pb = Problem.build(m)
    st = list(load_steps(pb, np.array([1.0]), on_step_end=pb.interfaces.update))[-1]
    blk = pb.interfaces.runs[0].block
    g = blk.gap(st.u)
    assert blk.released.all()
    assert np.all(g < 0) and np.abs(g).max() < 1e-3 * H2
    t = interface_state(m, pb.dm, st.u, interfaces(m)[0]).traction()
    assert np.allclose(t[:, 2], -5.0, rtol=1e-3)


def test_opening_transmits_nothing():
    """After debonding, a rigid lift of the upper layer (pure opening) gives zero normal contact
    force and stiffness and zero traction in the upper layer; once the opening exceeds the
    interlock distance (0.1 H) the next commit switches the friction off too."""
    m, H2 = _block(pressure=0.0)
    pb = Problem.build(m)
    blk = pb.assembler.extra[0]
    u = np.zeros(pb.dm.n_full)
    u[pb.dm.layer_dofs[1][:, 0, 2]] = 0.2 * H2  # u_0 of the top layer lifted by 0.2 H
    assert np.all(blk.gap(u) > 0.1 * H2)
    cap = blk.cap
    blk.cap = np.zeros_like(cap)  # normal contact alone
    f, K = blk.response(u)
    assert np.allclose(f, 0) and np.allclose(K, 0)
    blk.cap = cap
    pb.interfaces.update(pb, u, 0.0)  # commit the opened state
    assert np.all(blk.cap == 0)
    f, K = blk.response(u)
    assert np.allclose(f, 0) and np.allclose(K, 0)
    t = interface_state(m, pb.dm, u, interfaces(m)[0]).traction()
    assert np.allclose(t, 0, atol=1e-12)


def test_pure_opening_debonds_at_sigma_max_and_stays_open():
    """The interface fails in pure tension when σ33 reaches σ_max: a top-face suction load on a
    bonded block; the bond holds at 90 % of σ_max and fails at 110 % (then nothing is
    transmitted: the re-solution would lift the layer off, so we check the release itself)."""
    m, H2 = _block(released_all=False, pressure=-0.9)
    m.fixes += [Fix(np.arange(m.mesh.n_nodes), 1, (0,), (2,))]  # hold the top layer (it would lift off)
    pb = Problem.build(m)
    st = list(load_steps(pb, np.array([1.0]), on_step_end=pb.interfaces.update))[-1]
    assert pb.interfaces.first_failure() is None
    m2, _ = _block(released_all=False, pressure=-1.1)
    m2.fixes += [Fix(np.arange(m2.mesh.n_nodes), 1, (0,), (2,))]
    pb2 = Problem.build(m2)
    list(load_steps(pb2, np.array([1.0]), on_step_end=pb2.interfaces.update))
    assert pb2.interfaces.first_failure() == 1.0
    assert not pb2.bonded[1].any()


def test_irreversible_under_unloading():
    """Thesis 5.1 plate (strong friction) loaded past first debonding and unloaded: bond flags
    never come back and the debonded area never shrinks."""
    res = run_example("cantilever_plate_strong", {"n = 24": "factors = [0.5, 0.6, 0.7, 0.4, 0.1]"})
    areas = [a["concrete/trc"] for a in res.summary["debonded_area"]]
    assert areas[1] > 0 and all(b >= a for a, b in zip(areas, areas[1:]))
    assert res.converged


@pytest.mark.slow
def test_cantilever_plate_friction_laws():
    """Thesis §5.1 (MODEL.md V5): w_front_max of the four variants and first debonding.

    Measured (return-mapping friction, 24 steps): bonded 0.05291 (thesis 0.05364, -1.4 %),
    strong 0.05509 (0.05368, +2.6 %), slip 0.05864 (0.05810, +0.9 %), weak 0.05864 (0.06639,
    -11.7 %); first debonding at λ = 0.542 (thesis ≈ 0.5). The weak case misses the issue's 8 %
    band and equals the slip case: the debonded zone stops after the first cascade (2.5 m²)
    instead of reaching mid-plate, and the slip case's softening limit (4.76) has fallen to about
    1 % of τ_max (slips up to 0.5 mm = 10 g_T^μ), like the weak law's 0.01 τ_Delam. On 6 × 6
    elements the zone reaches mid-plate and weak gives 0.06704 (+1.0 %), but onset drops to
    λ = 0.21 (mesh-dependent stress criterion, docs/limits.md).

    The contact between debonded layers acts at the face Gauss points, as in the thesis
    (rule = "gauss"; the strong and slip cases settle one re-solution at λ = 0.542). With the
    rule left open, whether that re-solution's contact set cycles, and so whether the contact
    moves to the nodes, follows round-off: with the libraries installed on 29 Nov 2026 the
    strong case moves there and gives the nodal rule's 0.05570 (+3.8 %)."""
    w = {v: run_example(f"cantilever_plate_{v}", GAUSS_CONTACT if v != "bonded" else None)
         for v in ("bonded", "strong", "slip", "weak")}
    p = {v: r.summary["probes"]["w_front_max"] for v, r in w.items()}
    assert abs(p["bonded"] / 0.05364 - 1) < 0.03
    assert abs(p["strong"] / 0.05368 - 1) < 0.03
    assert abs(p["slip"] / 0.05810 - 1) < 0.08
    assert p["weak"] >= p["strong"] >= p["bonded"] and p["slip"] > p["strong"]
    for v in ("strong", "slip", "weak"):
        assert 0.42 <= w[v].summary["first_delamination_load_factor"] <= 0.58


@pytest.mark.slow
@pytest.mark.parametrize("front", [1.0, 1.5])
def test_weak_case_reaches_the_thesis_deflection_once_its_zone_reaches_mid_plate(front):
    """Thesis §5.1 (a): the weak-friction deflection 6.639 cm goes with a zone "evenly up to
    mid-plate" (Fig. 5.3a). On the 3 × 3 mesh the stress criterion stops this model's zone after
    the first cascade (2.5 m², the mid-side node row y = 0.5 still bonded and anchoring the
    layer; test above). Given the thesis's zone instead (the node rows up to y = 1.0 or 1.5
    debonded from the start, the rendering of Fig. 5.3a lies between them), the same contact and
    friction model gives the thesis's deflection within the issue's 8 % (measured 0.06540 and
    0.06684 m, -1.5 % and +0.7 %). So the missing 12 % of the weak case is the zone extent, not
    the post-fracture mechanics. Also measured: the debonded TRC flap, free at the clamp and
    weightless, stays straight and lifts off the curved plate (gap 10 / 16 mm at y = 0.11 for the
    1.0 / 1.5 m zone; the thesis's Fig. 5.3c shows it lying on), so friction does not act there
    and the three laws come close (1.5 m zone: slip 0.06684, strong 0.06399 m): the thesis's
    strong case (5.368 cm) needs friction in a zone that this model opens."""
    zone = f'initially_debonded = [{{ where = "y < {front + 0.01}" }}]\n\n[steps]'
    res = run_example("cantilever_plate_weak", {"[steps]": zone})
    assert res.converged
    w = res.summary["probes"]["w_front_max"]
    assert abs(w / 0.06639 - 1) < 0.08
    # the prescribed zone is the debonded area at the end: the node regions up to the front
    area = res.summary["debonded_area"][-1]["concrete/trc"]
    assert area > 3.0 * front
    run = res.problem.interfaces.runs[0]
    X, gap = run.block.X0.reshape(-1, 3), run.gap.ravel()
    clamp_row = np.isclose(X[:, 1], 0.5 - 0.5 * np.sqrt(0.6))
    assert gap[clamp_row].min() > 0.1 * 0.01  # open beyond the contact tolerance: no friction there


def test_open_gap_from_the_model_file_decides_where_friction_acts():
    """``[[interfaces]] open_gap``: a debonded point whose gap exceeds it transmits no friction.
    The §5.1 strong case with its first metre debonded from the start: with the default
    (0.1 × 10 mm) the TRC flap lifts off at the clamp and friction stops there; with 1 m no
    gap counts as open, the flap keeps μ0 τ_max = 1149.5 kN/m² (τ_Delam at zero pressure) and
    follows the plate more closely, so the plate is stiffer. A non-positive value is refused
    with a message naming the field."""
    from layershell.io.build import InputError, build, parse

    repl = {"[steps]": 'initially_debonded = [{ where = "y < 1.01" }]\n\n[steps]', "n = 24": "factors = [0.25, 0.5]"}
    res = {og: run_example("cantilever_plate_strong", {**repl, "p = 2.0": f"p = 2.0\nopen_gap = {og}"} if og else repl)
           for og in (None, 1.0)}
    clamp = {}
    for og, r in res.items():
        run = r.problem.interfaces.runs[0]
        row = np.isclose(run.block.X0.reshape(-1, 3)[:, 1], 0.5 - 0.5 * np.sqrt(0.6))
        clamp[og] = run.gap.ravel()[row], run.block.cap.ravel()[row]
    gap, cap = clamp[None]
    assert gap.min() > 1e-3 and np.all(cap == 0)
    gap, cap = clamp[1.0]
    assert np.allclose(cap, 0.95 * 1210.0)
    assert res[1.0].summary["probes"]["w_front_max"] < 0.9 * res[None].summary["probes"]["w_front_max"]
    text = (EXAMPLES / "cantilever_plate_strong.toml").read_text().replace("p = 2.0", "p = 2.0\nopen_gap = -1.0")
    with pytest.raises(InputError, match=r"interfaces\[0\]\.open_gap"):
        build(parse(text, "x.toml"))


_AREA_PROBES = '''[[probes]]
name = "area"
quantity = "debonded_area"
layer = "trc"

[[probes]]
name = "area_clamp_row"
quantity = "debonded_area"
layer = "trc"
where = "y < 0.8"
scale = 0.3333333333333333

[[probes]]
name = "load"
quantity = "load_factor"
scale = 48.0

[[probes]]'''


def test_debonded_area_and_load_factor_probes():
    """Probes of the delamination state, per step in probes.csv: at λ = 0.6 the §5.1 plate's zone
    is the regions of the node rows y = 0 and y = 1 (2.5 m², the first cascade). The whole
    interface's probe equals summary.json's debonded area; below y = 0.8 only the Gauss row
    y = 0.113 of the clamp elements counts: width 3 m × its weight 5/18 m, here divided by the
    3 m width (scale) into a debonded length. The load_factor probe is λ × scale."""
    res = run_example("cantilever_plate_slip", {"[[probes]]": _AREA_PROBES, "n = 24": "factors = [0.5, 0.6]"})
    first, last = (s["probes"] for s in res.summary["steps"])
    assert first["area"] == first["area_clamp_row"] == 0.0
    assert last["area"] == pytest.approx(res.summary["debonded_area"][-1]["concrete/trc"]) == pytest.approx(2.5)
    assert last["area_clamp_row"] == pytest.approx(5 / 18)
    assert (first["load"], last["load"]) == pytest.approx((24.0, 28.8))


@pytest.mark.parametrize("probe, message", [
    ('quantity = "debonded_area"', "needs the layer above the interface"),
    ('quantity = "debonded_area"\nlayer = "concrete"', "has no [[interfaces]] entry"),
    ('quantity = "debonded_area"\nlayer = "trc"\nwhere = "y > 5"', "selects no node"),
    ('quantity = "load_factor"\ncomponent = "z"', "takes no 'component'"),
    ('quantity = "stress"\npoint = [1, 1, 0]', "needs a component"),
])
def test_state_probe_input_errors(probe, message):
    from layershell.io.build import InputError, build, parse

    text = (EXAMPLES / "cantilever_plate_slip.toml").read_text().replace(
        "[[probes]]", f'[[probes]]\nname = "bad"\n{probe}\n\n[[probes]]')
    with pytest.raises(InputError, match=re.escape(message)) as err:
        build(parse(text, "x.toml"))
    assert "probes[0]" in str(err.value)


@pytest.mark.slow
def test_slip_case_step_size_independence():
    """Halving the load step changes w_front_max of the slip case by < 2 % (measured 0.01 %)."""
    a = run_example("cantilever_plate_slip").summary["probes"]["w_front_max"]
    b = run_example("cantilever_plate_slip", {"n = 24": "n = 48"}).summary["probes"]["w_front_max"]
    assert abs(a / b - 1) < 0.02


def test_step_cutting_on_debonding_jumps():
    """[delamination] max_debond_fraction: the first debonding step of the §5.1 plate releases a
    large zone at once (a cascade of re-solutions). With the cap the step is undone and halved
    (reported as bisections), the state is rolled back exactly (same result at the first step,
    whose sub-steps debond nothing), release stays irreversible, and the zone at the end is
    the same order as without cutting (the cascade is physical, it only starts from a closer
    load level)."""
    steps = {"n = 24": "factors = [0.5, 0.7]"}
    plain = run_example("cantilever_plate_slip", steps)
    cut = run_example("cantilever_plate_slip", {**steps, "[steps]": "[delamination]\nmax_debond_fraction = 0.02\n"
                                                "max_debond_cuts = 3\n\n[steps]"})
    assert plain.converged and cut.converged
    a_plain = [a["concrete/trc"] for a in plain.summary["debonded_area"]]
    a_cut = [a["concrete/trc"] for a in cut.summary["debonded_area"]]
    assert a_plain[0] == a_cut[0] == 0.0
    # the first step releases nothing, so both runs do the same operations on the same machine up
    # to it (cutting only takes snapshots): equal to round-off of identical arithmetic
    assert cut.summary["steps"][0]["probes"]["w_front_max"] == pytest.approx(
        plain.summary["steps"][0]["probes"]["w_front_max"], rel=1e-12)
    assert plain.summary["steps"][1]["bisections"] == 0
    assert cut.summary["steps"][1]["bisections"] >= 1  # the jump was cut
    assert a_cut[1] > 0 and 0.5 < a_cut[1] / a_plain[1] < 2.0


def test_semismooth_contact_newton_equals_frozen_active_sets():
    """Newton with contact: the semi-smooth iterations (contact set from the current gap in every
    iteration) reach the same equilibrium as the active-set loop with frozen sets (the penalty
    problem has one solution per state) - through the first debonding of the §5.1 plate, with
    fewer iterations."""
    steps = {"n = 24": "factors = [0.5, 0.6, 0.7]"}
    semi = run_example("cantilever_plate_slip", steps)
    frozen = run_example("cantilever_plate_slip", steps, newton={"semismooth_iterations": 0})
    assert semi.converged and frozen.converged
    for a, b in zip(semi.summary["steps"], frozen.summary["steps"]):
        assert a["debonded_area"] == b["debonded_area"]
    assert semi.summary["debonded_area"][-1]["concrete/trc"] > 0
    its = [sum(s["iterations"] for s in r.summary["steps"]) for r in (semi, frozen)]
    assert its[0] <= its[1], its
    # The same equilibrium: the two methods take different iteration paths, so each result is only
    # as close to the equilibrium as the tolerance makes it (1e-8 on the residual, amplified by up
    # to ~30 into a probe on these plates, tests/test_plate_gmsh.py). Solved to 1e-12 (with room
    # for the extra contact iterations), they must agree to TIGHT_BOUND (measured here: 1e-14).
    tight = {"n = 24": "factors = [0.5, 0.6, 0.7]\n" + TIGHT_STEPS}
    semi = run_example("cantilever_plate_slip", tight)
    frozen = run_example("cantilever_plate_slip", tight, newton={"semismooth_iterations": 0})
    assert semi.converged and frozen.converged
    for a, b in zip(semi.summary["steps"], frozen.summary["steps"]):
        assert a["debonded_area"] == b["debonded_area"]
        assert a["probes"]["w_front_max"] == pytest.approx(b["probes"]["w_front_max"], rel=TIGHT_BOUND)


def test_contact_iteration_cap_from_the_model_file(monkeypatch):
    """[steps] max_contact_iterations reaches the Newton settings: a cap of 8 makes the runner
    bisect the first increment of the §5.1 plate (14 iterations otherwise, no bisection). The
    re-equilibration after the first debonding cannot be bisected: it gets
    REEQUILIBRATION_BUDGET (4) times the cap and converges. With the Gauss points asked for
    (rule = "gauss") and a budget of 5 iterations for the re-solutions, below what the one whose
    contact set cycles needs (7 with MKL 2026.2, more than 8 with the earlier libraries: the
    load step's own budget of 8, which this test used before, no longer makes it fail
    everywhere), the re-solution fails; pseudo-transient settling (newton.settle) then finds the
    equilibrium that the full budget finds (w_front_max to 10⁻⁹; measured 3·10⁻¹⁵), and
    summary.json 'settlements' and a warning say so. Without settling the run stops with a
    message that names the setting, and the converged step is kept; with the rule left open the
    contact moves to the nodes there (contact_to_nodes), the run reaches its end, and
    summary.json and a warning say where."""
    from dataclasses import replace

    from layershell.runner import ContactRuleWarning, JumpWarning
    from layershell.solver import newton

    case = {"n = 24": "factors = [0.5, 0.6]\nmax_contact_iterations = 8"}
    budget = run_example("cantilever_plate_slip", case)
    assert budget.converged and budget.summary["steps"][0]["bisections"] >= 1
    assert "contact_moved_to_nodes" not in budget.summary
    full = run_example("cantilever_plate_slip", {**case, **GAUSS_CONTACT})
    assert full.converged and "settlements" not in full.summary
    monkeypatch.setattr(newton, "reequilibration_settings",
                        lambda st: replace(st, max_iterations=5, max_contact_iterations=5))
    with pytest.warns(JumpWarning, match="at load factor 0.6 after new releases found no equilibrium by Newton"):
        settled = run_example("cantilever_plate_slip", {**case, **GAUSS_CONTACT})
    assert settled.converged and settled.summary["steps"][-1]["load_factor"] == 0.6
    assert settled.summary["settlements"]
    for ev in settled.summary["settlements"]:
        assert (ev["step"], ev["load_factor"], ev["pushes"]) == (2, 0.6, 0)
        assert "max_contact_iterations" in ev["reason"] and ev["energy_released"] > 0
    assert settled.summary["probes"]["w_front_max"] == pytest.approx(full.summary["probes"]["w_front_max"], rel=1e-9)
    monkeypatch.setattr(newton, "settle", _no_settling)
    capped = run_example("cantilever_plate_slip", {**case, **GAUSS_CONTACT})
    assert not capped.converged and "max_contact_iterations" in capped.message
    assert 'rule = "lobatto"' in capped.message
    assert capped.summary["steps"][0]["bisections"] >= 1
    with warnings.catch_warnings(record=True) as said:
        warnings.simplefilter("always")
        moved = run_example("cantilever_plate_slip", case)
    if not moved.converged:  # the nodal contact's re-solution is at 5 iterations' edge (residual 1.5e-5 with MKL
        # 2026.2.1): the stop must then name the move it made
        assert "had moved from the face Gauss points to the nodes at load factor 0.6" in moved.message
    else:
        assert any(isinstance(w.message, ContactRuleWarning)
                   and "at load factor 0.6 the contact between debonded layers" in str(w.message) for w in said)
        assert moved.summary["steps"][-1]["load_factor"] == 0.6
        (move,) = moved.summary["contact_moved_to_nodes"]
        assert move["step"] == 2 and move["load_factor"] == 0.6 and move["interfaces"] == ["trc"]
        assert move["reason"].startswith("its re-solution after new releases: no equilibrium after 5 iterations")
        assert any("acts at the nodes" in w for w in moved.summary["warnings"])
    monkeypatch.undo()  # the re-solutions' own budget and settling again
    plain = run_example("cantilever_plate_slip", {"n = 24": "factors = [0.5, 0.6]"})
    assert plain.converged and all(st["bisections"] == 0 for st in plain.summary["steps"])


def _no_settling(problem, u, lam, s, why=""):
    """A stand-in for newton.settle that gives up at once (the behaviour without it)."""
    from layershell.solver.newton import NewtonResult

    return u, NewtonResult(False, 0, message="settling switched off")


@pytest.mark.parametrize("name", ["cantilever_plate_bonded", "cantilever_plate_slip"])
def test_every_assembled_tangent_is_used_by_a_solve(name, monkeypatch):
    """Newton assembles K only where an iteration goes on (forces first): every tangent
    evaluation is followed by one linear solve - none is thrown away at convergence or by the
    line search - with and without contact."""
    from layershell.assembly import Assembler
    from layershell.solver.linear import LinearSolver

    counts = {"tangent": 0, "solve": 0}
    ev, so = Assembler.evaluate_reduced, LinearSolver.solve

    def evaluate_reduced(self, *a, **k):
        counts["tangent"] += 1
        return ev(self, *a, **k)

    def solve(self, *a, **k):
        counts["solve"] += 1
        return so(self, *a, **k)

    monkeypatch.setattr(Assembler, "evaluate_reduced", evaluate_reduced)
    monkeypatch.setattr(LinearSolver, "solve", solve)
    r = run_example(name, {"n = 24": "factors = [0.5, 0.6]"})
    assert r.converged
    its = sum(s["iterations"] for s in r.summary["steps"])
    assert counts["solve"] > 0 and counts["tangent"] == counts["solve"]
    assert counts["solve"] <= its + 2 * len(r.summary["steps"])  # round-off-floor exits solve once more


def test_without_reequilibration_releases_act_from_the_next_step():
    """[delamination] reequilibrate = false (the thesis's procedure, MODEL.md §9): no
    re-solution at the load level of a release. The step where the §5.1 plate first debonds
    then reports the equilibrium before the release - equal to the bonded plate's - while the
    default re-solves it with the released strip (softer)."""
    from layershell.io.build import InputError, build, parse

    # solved to 1e-12 so that "equal to the bonded plate's" can be checked at TIGHT_BOUND (the two
    # models iterate differently: the delaminating one has contact blocks and a line search)
    steps = {"n = 24": "factors = [0.5, 0.55, 0.6]\n" + TIGHT_STEPS}
    thesis = run_example("cantilever_plate_slip", {**steps, "[steps]": "[delamination]\nreequilibrate = false\n\n[steps]"})
    default = run_example("cantilever_plate_slip", steps)
    bonded = run_example("cantilever_plate_bonded", steps)
    assert thesis.converged and default.converged
    assert all(s["resolves"] == 0 for s in thesis.summary["steps"])
    assert sum(s["resolves"] for s in default.summary["steps"]) > 0
    assert thesis.summary["first_delamination_load_factor"] == default.summary["first_delamination_load_factor"] == 0.55

    def w(r, i):
        return r.summary["steps"][i]["probes"]["w_front_max"]

    assert w(thesis, 1) == pytest.approx(w(bonded, 1), rel=TIGHT_BOUND)  # λ = 0.55: released, not yet re-solved
    assert w(default, 1) > w(bonded, 1) * (1 + 1e-4)
    assert w(thesis, 2) > w(bonded, 2) * (1 + 1e-4)  # λ = 0.6 is solved with the released strip
    # step cutting measures the re-solutions, which this procedure has not: refused with a clear message
    text = (EXAMPLES / "cantilever_plate_slip.toml").read_text().replace(
        "[steps]", "[delamination]\nreequilibrate = false\nmax_debond_fraction = 0.1\n\n[steps]")
    with pytest.raises(InputError, match="reequilibrate"):
        build(parse(text, "x.toml"))



def _slip_plate(rule: str | None = None, law: str = "thesis") -> Problem:
    """The §5.1 plate with slip-softening friction (examples/cantilever_plate_slip.toml), built,
    with ``[[interfaces]] rule`` if given (and, ``law = "cohesive"``, a cohesive interface)."""
    text = (EXAMPLES / "cantilever_plate_slip.toml").read_text()
    if rule is not None:
        text = text.replace("[[interfaces]]", f'[[interfaces]]\nrule = "{rule}"')
    if law == "cohesive":
        text = text.replace("mu0 = 0.95", 'law = "cohesive"\nG_Ic = 0.14\nG_IIc = 0.5\nmu0 = 0.95')
    return Problem.build(build(parse(text, str(EXAMPLES / "slip.toml")), EXAMPLES).model)


def test_thesis_contact_rule_from_the_model_file_and_the_hint_of_a_failed_solve():
    """[[interfaces]] rule reaches the thesis law's contact block: "lobatto" puts its points on
    the element's nodes (the default "gauss": on the face Gauss points, the thesis's (3.48)),
    each point still in its node's region; both rules integrate the 3 m × 3 m face exactly. A
    failed solve of the Gauss rule's contact names the setting (newton.contact_hint), the nodal
    rule's and a cohesive interface's do not."""
    for rule in (None, "lobatto"):
        pb = _slip_plate(rule)
        assert pb.model.interface_laws[1].rule == (rule or "gauss")
        blk = pb.interfaces.runs[0].block
        region_nodes = pb.model.mesh.nodes[blk.conn[:, blk.region]]
        assert np.allclose(blk.X0, region_nodes) == (rule == "lobatto")
        assert blk.w0.sum() == pytest.approx(9.0, rel=1e-12)
    assert 'rule = "lobatto"' in contact_hint(_slip_plate())
    assert contact_hint(_slip_plate("lobatto")) == ""
    assert contact_hint(_slip_plate("gauss", law="cohesive")) == ""


def _debonded_state(pb: Problem, seed: int = 3) -> np.ndarray:
    """Release the nodes of the §5.1 plate's clamped half (x ≤ 1.5) and give the released points
    a friction state (slip limit, committed traction, stick anchor); returns a displacement u
    (full space) at which some released points are closed and some open."""
    rng = np.random.default_rng(seed)
    nodes = np.flatnonzero(pb.model.mesh.nodes[:, 0] <= 1.5 + 1e-9)
    pb.bonded[1][nodes] = False
    pb.rebuild_constraints()
    pb.interfaces.sync(pb)
    blk = pb.interfaces.runs[0].block
    rel = blk.released
    assert rel.any() and not rel.all()
    blk.cap = np.where(rel, 50.0 + 100.0 * rng.random(rel.shape), 0.0)
    blk.t_n = np.where(rel[..., None], rng.normal(0, 20.0, rel.shape + (3,)), 0.0)
    blk.g_p = np.where(rel[..., None], rng.normal(0, 1e-6, rel.shape + (3,)), 0.0)
    return rng.normal(0.0, 1e-5, pb.dm.n_full)


def test_thesis_contact_moves_from_the_gauss_points_to_the_nodes():
    """InterfaceController.contact_to_nodes, which load_steps calls where the Gauss points'
    contact set finds no equilibrium: the moved block is the nodal rule's (its points are the
    region nodes), point q keeps its released flag, slip limit and committed traction, and its
    trial friction traction α_T (P Δu - g_p) at the committed state is unchanged. The forces
    the assembler then gives equal those of the same state built with rule = "lobatto" from the
    start (an independent build), at the committed state and elsewhere; the move survives a
    checkpoint (state/restore into a fresh Gauss-rule problem). Only a rule the model file left
    open moves, and only once."""
    pb = _slip_plate()
    u = _debonded_state(pb)
    old = pb.interfaces.runs[0].block
    P = old.projector()
    trial_old = old.alpha_T * (np.einsum("eqij,eqj->eqi", P, old.relative_displacement(u)) - old.g_p)
    f_gauss, _ = pb.assembler.evaluate(u, tangent=False)
    assert pb.interfaces.contact_to_nodes(pb, u, 0.375)
    r = pb.interfaces.runs[0]
    new = r.block
    assert r.law.rule == "lobatto" and pb.extra_blocks == [new]
    assert np.allclose(new.X0, pb.model.mesh.nodes[new.conn[:, new.region]])
    assert np.array_equal(new.released, old.released)
    assert np.array_equal(new.cap, old.cap) and np.array_equal(new.t_n, old.t_n)
    trial_new = new.alpha_T * (np.einsum("eqij,eqj->eqi", new.projector(), new.relative_displacement(u)) - new.g_p)
    rel = new.released
    assert np.allclose(trial_new[rel], trial_old[rel], rtol=1e-12, atol=1e-9 * np.abs(trial_old).max())
    assert pb.interfaces.contact_moves == [{"load_factor": 0.375, "interfaces": ["trc"], "reason": ""}]
    assert "rule = \"lobatto\"" in contact_move_message(pb.interfaces.contact_moves[0])
    assert "had moved from the face Gauss points to the nodes at load factor 0.375" in contact_hint(pb)
    assert not pb.interfaces.contact_to_nodes(pb, u, 0.4)  # moved once

    ref = _slip_plate("lobatto")
    _debonded_state(ref)
    for name in ("cap", "t_n", "g_p"):
        setattr(ref.interfaces.runs[0].block, name, getattr(new, name).copy())
    v = u + np.random.default_rng(5).normal(0.0, 1e-6, u.size)
    for w in (u, v):
        f_moved, _ = pb.assembler.evaluate(w, tangent=False)
        f_ref, _ = ref.assembler.evaluate(w, tangent=False)
        assert np.allclose(f_moved, f_ref, rtol=0, atol=1e-10 * np.abs(f_ref).max())
    assert not np.allclose(f_moved, f_gauss, rtol=0, atol=1e-6 * np.abs(f_ref).max())  # the rule matters here

    fresh = _slip_plate()  # a restart: the checkpoint's state moves a fresh Gauss-rule build
    fresh.interfaces.restore(fresh, pb.interfaces.state(pb))
    assert fresh.interfaces.runs[0].law.rule == "lobatto"
    f_restart, _ = fresh.assembler.evaluate(v, tangent=False)
    assert np.allclose(f_restart, f_moved, rtol=0, atol=1e-10 * np.abs(f_ref).max())

    explicit = _slip_plate("gauss")  # asked for: stays at the Gauss points
    _debonded_state(explicit)
    assert not explicit.interfaces.contact_to_nodes(explicit, u, 0.375)
    assert explicit.interfaces.runs[0].law.rule == "gauss"


def test_adaptive_steps_move_the_contact_to_the_nodes_too():
    """Adaptive load control (arclength.path_steps) moves the thesis's contact as load_steps
    does: the §5.1 plate with max_contact_iterations = 8, whose re-solution after a cascade
    fails at the Gauss points, reaches λ = 1 with the contact at the nodes; with rule = "gauss"
    the run stops there with the message that names the setting."""
    case = {"n = 24": "n = 24\nadaptive = true\nmax_contact_iterations = 8"}
    moved = run_example("cantilever_plate_slip", case)
    assert moved.converged and moved.summary["path_end"] == "lambda_end"
    assert moved.summary["steps"][-1]["load_factor"] == 1.0
    (move,) = moved.summary["contact_moved_to_nodes"]
    assert 0.5 < move["load_factor"] < 1.0 and "max_contact_iterations" in move["reason"]
    kept = run_example("cantilever_plate_slip", {**case, **GAUSS_CONTACT})
    assert not kept.converged and 'rule = "lobatto"' in kept.message
    assert "contact_moved_to_nodes" not in kept.summary


def test_a_path_that_ends_at_max_steps_before_lambda_end_is_warned():
    """A run that stops at [steps] max_steps before lambda_end is converged (every increment an
    equilibrium) but says that the load asked for was not reached; one that reaches lambda_end
    does not. The Gmsh plate with adaptive steps: after its debonding jump at λ = 0.496 every
    increment from 10⁻⁵ up takes 6-12 Newton iterations (the thesis's friction relaxing), so the
    rule Δλ × target/its held the increments near 10⁻⁵ and 1000 of them ended at λ = 0.4998;
    with the growth of cut increments whose iterations do not depend on their size
    (arclength.size_insensitive) it reaches λ = 1 within max_steps = 200 (74 increments with
    the libraries of 28 Nov 2026, 105 with those installed on 29 Nov: the thesis law's
    debonding cascades, and so the cuts, follow round-off)."""
    from layershell.runner import JumpWarning

    adaptive = "[steps]\nn = 8\nadaptive = true"
    with pytest.warns(JumpWarning, match="the path ended after \\[steps\\] max_steps = 8 increments"):
        r = run_example("plate_gmsh", {"[steps]\nn = 8": adaptive + "\nmax_steps = 8"})
    assert r.converged and r.summary["path_end"] == "max_steps"
    assert r.summary["steps"][-1]["load_factor"] < 0.5
    assert any("before lambda_end = 1" in w for w in r.summary["warnings"])
    full = run_example("plate_gmsh", {"[steps]\nn = 8": adaptive + "\nmax_steps = 200"})
    assert full.converged and full.summary["path_end"] == "lambda_end"
    assert full.summary["steps"][-1]["load_factor"] == 1.0 and len(full.summary["steps"]) <= 200
    assert not any("max_steps" in w for w in full.summary.get("warnings", []))


def test_contact_set_violation_is_the_traction_error_in_units_of_the_strength():
    """ContactBlock.set_violation, by which a contact set that still changes after the allowed
    active-set loops is accepted or not: 0 where the frozen set holds; α_N × the opening of a
    point in the set, or the penetration of a released point outside it, over σ_max."""
    pb = _slip_plate()
    u = _debonded_state(pb)
    blk = pb.interfaces.runs[0].block
    blk.freeze(u)
    assert blk.set_violation(u) == 0.0
    g = blk.gap(u)
    inside, outside = blk.active & blk.released, blk.released & ~blk.active
    assert inside.any() and outside.any()
    # the same state with the set flipped at one point each way
    e, q = np.argwhere(inside)[np.argmin(g[inside])]
    blk.active[e, q] = False  # a closed point (ḡ < 0) outside the set: a missing pressure
    assert blk.set_violation(u) == pytest.approx(blk.alpha * -g[e, q] / 1980.0, rel=1e-12)
    blk.active[e, q] = True
    e, q = np.argwhere(outside)[np.argmax(g[outside])]
    blk.active[e, q] = True  # an open point in the set: a spurious tension
    assert blk.set_violation(u) == pytest.approx(blk.alpha * g[e, q] / 1980.0, rel=1e-12)
    blk.strength = None
    assert blk.set_violation(u) == np.inf


def test_a_cycling_contact_set_is_not_accepted_with_interpenetration(monkeypatch):
    """examples/plate_gmsh.toml, whose Gauss-point contact set cycles at λ = 0.5 (re-solution):
    before, a contact set still changing after the allowed active-set loops was accepted as it
    was, and the run reported states with released points interpenetrating by up to 0.24 mm (λ
    = 0.875) or pulled open in the set (λ = 0.5: a tension of 1.3 σ_max under α_N). Now such a
    state is accepted only within CONTACT_SET_TOL of the strength: with rule = "gauss" and
    without pseudo-transient settling the run stops at λ = 0.5 naming the violation; with the
    rule left open the contact moves to the nodes there and the run reaches λ = 1, every contact
    set holding where it converged. With rule = "gauss" and settling (newton.settle, the
    default) the re-solution settles to an equilibrium whose contact set holds, and the run
    reaches λ = 1 on the Gauss points' rule (w_front_max 0.06095 m). The deflections of the two
    rules at λ = 1 agree only roughly: round-off decides how far the last cascade runs, and the two
    rules carry the debonded zone's contact differently (where the contact moved to the nodes,
    w_front_max was 0.06154 m with 2.83 m² debonded against the Gauss rule's 3.87 m², and 0.06487 m
    with the whole interface debonded under other library versions), so they are held within 10 %
    of each other, not ordered by their debonded areas."""
    from layershell.solver import newton
    from layershell.solver.newton import CONTACT_SET_TOL

    settled = run_example("plate_gmsh", GAUSS_CONTACT)
    assert settled.converged and settled.summary["steps"][-1]["load_factor"] == 1.0
    assert "contact_moved_to_nodes" not in settled.summary and "active_set" not in settled.summary
    assert len(settled.summary["settlements"]) >= 1
    assert all("violates the contact condition" in ev["reason"] for ev in settled.summary["settlements"])
    monkeypatch.setattr(newton, "settle", _no_settling)
    gauss = run_example("plate_gmsh", GAUSS_CONTACT)
    assert not gauss.converged and gauss.summary["steps"][-1]["load_factor"] < 1.0
    m = re.search(r"violates the contact condition by a traction of ([0-9.e+-]+) × the interface strength",
                  gauss.message)
    assert m and float(m.group(1)) > 100 * CONTACT_SET_TOL
    moved = run_example("plate_gmsh")
    assert moved.converged and moved.summary["steps"][-1]["load_factor"] == 1.0
    # where the Gauss points' set cycles (round-off decides which re-solution cycles first: λ =
    # 0.5 with numpy 1.26-2.3, 0.875 with numpy 2.4 / MKL 2026.2; either stops the Gauss run)
    assert [mv["load_factor"] for mv in moved.summary["contact_moved_to_nodes"]] == [gauss.failure["load_factor"]]
    assert "active_set" not in moved.summary  # every contact set held exactly where it converged
    w = [r.summary["probes"]["w_front_max"] for r in (settled, moved)]
    assert w[1] == pytest.approx(w[0], rel=0.10), w


NODAL_CONTACT = {"[[interfaces]]": '[[interfaces]]\nrule = "lobatto"'}
GAUSS_CONTACT = {"[[interfaces]]": '[[interfaces]]\nrule = "gauss"'}
REFINED = {"nx = 3": "nx = 12", "ny = 3": "ny = 12"}


@pytest.mark.slow
def test_refined_thesis_plate_with_the_contact_at_the_nodes(monkeypatch):
    """The §5.1 plate with slip-softening friction refined to 12 × 12 (issue 13, robustness), with
    the budget of a load step for its re-solutions (REEQUILIBRATION_BUDGET = 1, as before it)
    and without pseudo-transient settling (newton.settle, which would take that re-solution on):
    with the contact at the face Gauss points the contact set of the re-solution after the first
    cascade cycles (a stiff penalty at Gauss points: its tractions oscillate from point to point,
    Schellekens & de Borst 1993) and the run stops (at λ = 0.375 or 0.5) with a message that names the
    setting (rule = "gauss" asked for); with the contact at the nodes it reaches λ = 1. The
    default (with the default budget, REEQUILIBRATION_BUDGET = 4) starts at the Gauss points,
    moves to the nodes where a re-solution's contact set cycles (a set frozen for the third
    time, at λ = 0.5; contact_to_nodes; with the libraries of 29 Nov 2026 a set still changing
    after the allowed loops, its last state violating the contact condition) and reaches λ = 1
    with the nodal rule's deflection. The criterion stays at the Gauss points: the first
    debonding (λ = 0.125 on 12 × 12; the thesis law's onset falls with the mesh) is the same on
    every rule."""
    from layershell.solver import newton

    moved = run_example("cantilever_plate_slip", REFINED)
    assert moved.converged and moved.summary["steps"][-1]["load_factor"] == 1.0
    (move,) = moved.summary["contact_moved_to_nodes"]
    # a cycle, or a set still changing after the allowed loops (with the libraries of 29 Nov 2026)
    assert 0.125 < move["load_factor"] < 1.0
    assert "cycles" in move["reason"] or "contact set still changing" in move["reason"]
    monkeypatch.setattr(newton, "REEQUILIBRATION_BUDGET", 1)
    monkeypatch.setattr(newton, "settle", _no_settling)
    gauss = run_example("cantilever_plate_slip", {**REFINED, **GAUSS_CONTACT})
    assert not gauss.converged and 'rule = "lobatto"' in gauss.message
    # it stops at a re-solution after a cascade: at λ = 0.375 with the default threads, at 0.5 in the
    # slow suite on one MKL/OpenMP thread (round-off decides which set cycles first, as in the test above)
    assert 0.125 < gauss.failure["load_factor"] < 1.0
    assert gauss.summary["steps"][-1]["load_factor"] == pytest.approx(gauss.failure["load_factor"] - 1 / 24)
    nodal = run_example("cantilever_plate_slip", {**REFINED, **NODAL_CONTACT})
    assert nodal.converged and nodal.summary["steps"][-1]["load_factor"] == 1.0
    w = [r.summary["probes"]["w_front_max"] for r in (moved, nodal)]
    assert w[0] == pytest.approx(w[1], rel=0.01)
    for r in (gauss, nodal, moved):
        assert r.summary["first_delamination_load_factor"] == pytest.approx(0.125)


@pytest.mark.slow
def test_refined_thesis_plate_with_strong_friction_needs_the_budget_of_its_re_solutions(monkeypatch):
    """The §5.1 plate with strong friction on 12 × 12, contact at the nodes: after the first
    cascade at λ = 0.5 the step's re-solutions take 314-338 iterations, the longest frozen solve
    30 (numpy 1.26-2.3) or 24 (numpy 2.4.6 / MKL 2026.2) of them. With the budget of a load step
    (and without pseudo-transient settling, newton.settle) the run stops there; with the
    re-solutions' budget (REEQUILIBRATION_BUDGET = 4: a
    re-solution at the same load cannot be bisected) it reaches λ = 1. The test runs with
    ``max_iterations = 12``, so that both budgets are a factor of 2 away from the longest solve
    (12 and 48 against 24-30): with the default 25 round-off decided whether that solve fit
    within one load step's budget."""
    from layershell.solver import newton

    case = {**REFINED, **NODAL_CONTACT, "[steps]": "[steps]\nmax_iterations = 12"}
    full = run_example("cantilever_plate_strong", case)
    assert full.converged and full.summary["steps"][-1]["load_factor"] == 1.0
    monkeypatch.setattr(newton, "REEQUILIBRATION_BUDGET", 1)
    monkeypatch.setattr(newton, "settle", _no_settling)
    step = run_example("cantilever_plate_strong", case)
    assert not step.converged and step.summary["steps"][-1]["load_factor"] == pytest.approx(0.5 - 1 / 24)


def test_a_step_that_fails_after_complete_debonding_is_named_a_limit_point():
    """newton.separated_hint: once every interface point has debonded (the pull-off refined to
    18 × 16 releases its whole bond at λ = 0.3), a load step that finds no equilibrium is the
    structure's limit point; the message says so instead of pointing at the contact rule."""
    from types import SimpleNamespace

    from layershell.solver.newton import separated_hint

    def stand_in(fraction):
        return SimpleNamespace(interfaces=SimpleNamespace(debonded_fraction=lambda: fraction))

    assert "every interface point had debonded at load factor 0.3" in separated_hint(stand_in(1.0), 0.3)
    # a re-solution that fails after the releases that completed the debonding (the CFRP plate on
    # 24 × 16 at λ = 32): complete separation, not the contact rule
    from layershell.solver.newton import NewtonResult, reequilibration_error
    failed = NewtonResult(False, 3, residuals=[1.0], message="pseudo-transient settling failed")
    done = str(reequilibration_error(stand_in(1.0), 7, 32.0, failed))
    assert "step 7: re-equilibration at load factor 32 failed" in done and "complete separation at load factor 32" in done
    assert "complete separation" not in str(reequilibration_error(stand_in(0.9), 7, 32.0, failed))
    assert separated_hint(stand_in(0.999), 0.3) == ""
    assert separated_hint(SimpleNamespace(interfaces=None), 0.3) == ""
    pb = _slip_plate()  # bonded at the start: nothing debonded
    assert separated_hint(pb, 0.0) == ""
    pb.bonded[1][:] = False
    pb.interfaces.sync(pb)
    assert "limit point" in separated_hint(pb, 1.0)


def test_the_re_solutions_budget_is_per_load_step():
    """``[delamination] max_resolves`` is the most re-solutions per load step. The pull-off
    re-solves 1, 15, 2 and 9 times in four of its steps up to λ = 0.5 (27 in all). Before, the count
    was never reset (InterfaceController.begin_step was not called), so a budget of 20 stopped
    the run at λ = 0.475 with an internal error (RuntimeError), and the weak-friction §5.1 plate on
    24 × 24 stopped so at λ = 0.625 (110 re-solutions in six steps). Now a budget of 20
    reaches the end with the default's results; a budget of 10 stops at the step that needs
    15, as a failed solution (ConvergenceError) that names the setting and keeps the converged
    steps."""
    to_half = {"0.50,\n           0.525, 0.55, 0.60, 0.65, 0.70, 0.75]": "0.50]"}  # the steps up to λ = 0.5
    ref = run_example("pulloff", to_half)
    per_step = [s["resolves"] for s in ref.summary["steps"]]
    assert max(per_step) == 15 and sum(per_step) > 20
    budget = "[steps]"
    ok = run_example("pulloff", {**to_half, budget: "[delamination]\nmax_resolves = 20\n\n" + budget})
    assert ok.converged
    assert [s["resolves"] for s in ok.summary["steps"]] == per_step
    assert ok.summary["probes"] == pytest.approx(ref.summary["probes"], rel=1e-12, abs=1e-15)
    short = run_example("pulloff", {**to_half, budget: "[delamination]\nmax_resolves = 10\n\n" + budget})
    assert not short.converged
    assert "more than 10 re-solutions" in short.message and "max_resolves" in short.message
    first = per_step.index(15)
    assert len(short.summary["steps"]) == first  # the steps before the one that needs 15


def test_a_restart_keeps_the_contact_move(tmp_path):
    """summary.json of a restarted run keeps what earlier steps recorded once: the move of the
    thesis's contact to the nodes (``contact_moved_to_nodes``) and ``peak_load_factor`` were not
    among the checkpoint's summary keys, so a run restarted after the move reported none (the
    weak-friction §5.1 plate on 24 × 24, moved at λ = 0.167 and restarted twice). The Gmsh plate
    moves in one of its steps (step 4 or 7: round-off decides where its Gauss points' contact set
    cycles first); stopped after that step and restarted, it ends with the same move record and
    the same displacements as the uninterrupted run."""
    from layershell.runner import run

    spec = example_spec("plate_gmsh")
    full = run(spec, tmp_path / "full", write_vtu=False)
    (move,) = full.summary["contact_moved_to_nodes"]
    after = move["step"]
    assert after < len(full.summary["steps"])  # a step follows the move

    part, again = stopped_and_restarted(spec, tmp_path / "part", after)
    assert part.interrupted
    assert again.converged and again.summary["restarts"][-1]["step"] == after
    assert again.summary["contact_moved_to_nodes"] == full.summary["contact_moved_to_nodes"]
    assert np.allclose(again.u, full.u, rtol=0, atol=1e-9 * abs(full.u).max())


#: the §5.1 plates with the MITC9 default instead of their element = "full"
MITC9 = {'element = "full"\n': ""}


@pytest.mark.slow
def test_thesis_plates_keep_the_full_element_because_mitc9_debonds_more_on_3_x_3():
    """Why examples/cantilever_plate_{bonded,strong,slip,weak}.toml set element = "full": their
    reference is the thesis's results, computed with its fully integrated element on this 3 × 3
    mesh. MITC9 removes that element's locking: bonded, it gives 0.05495 m, +2.4 % from the
    thesis's 0.05364 and within 0.3 % of its own 6 × 6 and 12 × 12 runs (0.05481 / 0.05485 m;
    full element 0.05291 / 0.05438 / 0.05485 on 3 × 3 / 6 × 6 / 12 × 12). But its interface
    tractions on 3 × 3 meet the stress criterion earlier and over more of the plate: first
    debonding at λ = 0.458 (full 0.542), strong friction 0.06110 m (thesis 0.05368: +13.8 %,
    debonded 2.81 m² against 2.5), weak friction 0.06156 m (thesis 0.06639: -7.3 %, full element
    -11.7 %), and with slip-softening friction the whole interface
    (9 m²) debonds at λ = 0.958, where the layers, held by contact and friction at the face
    Gauss points alone, have no equilibrium: the run stops there (full element: 0.05864 m at
    λ = 1, thesis 0.05810)."""
    bonded = run_example("cantilever_plate_bonded", MITC9).summary
    assert bonded["converged"] and abs(bonded["probes"]["w_front_max"] / 0.05364 - 1) < 0.03
    strong = run_example("cantilever_plate_strong", {**MITC9, **GAUSS_CONTACT}).summary
    assert strong["converged"] and strong["first_delamination_load_factor"] < 0.5
    assert strong["probes"]["w_front_max"] > 1.10 * 0.05368  # outside the band the thesis plates are checked to
    slip = run_example("cantilever_plate_slip", {**MITC9, **GAUSS_CONTACT})
    assert not slip.converged and slip.failure["load_factor"] == pytest.approx(23 / 24)
    assert "complete separation" in slip.summary["error"]
