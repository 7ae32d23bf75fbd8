"""Path following (issue 13 item 2): displacement control, arc length, step control.

References are independent of the method under test: the force-controlled solution of the same
model (uniqueness of the equilibrium), analytic limit points and analytic softening curves.
"""
from __future__ import annotations

import numpy as np
import pytest

from layershell.io.build import build, parse
from layershell.runner import run
from layershell.solver.problem import Problem

from helpers import stopped_and_restarted

CANTILEVER = """
[model]
title = "cantilever"
nonlinear = {nonlinear}
[mesh]
type = "rectangle"
lx = 10.0
ly = 1.0
nx = 4
ny = 1
[materials.m]
type = "isotropic"
E = 1000.0
nu = 0.0
[[layers]]
name = "beam"
material = "m"
thickness = 0.5
directors = 1
[[supports]]
type = "fix"
where = "near(x, 0)"
directors = "all"
{tip}
[steps]
n = {n}
{steps}
[[probes]]
name = "w"
quantity = "displacement"
point = [10, 0, 0]
component = "z"
"""
FORCE_TIP = """
[[loads]]
type = "edge"
where = "near(x, 10)"
direction = [0, 0, 1]
distribution = {P}
face = "reference"
"""
DISP_TIP = """
[[supports]]
type = "fix"
where = "near(x, 10)"
components = ["z"]
value = [{w}]
"""


def _spec(tip: str, nonlinear: bool = False, n: int = 1, steps: str = ""):
    return build(parse(CANTILEVER.format(nonlinear=str(nonlinear).lower(), tip=tip, n=n, steps=steps)))


def _tip_dofs(spec, problem):
    nodes = np.flatnonzero(np.isclose(spec.model.mesh.nodes[:, 0], 10.0))
    return problem.dm.layer_dofs[0][nodes, 0, 2]


@pytest.mark.parametrize("nonlinear", [False, True])
def test_displacement_control_reproduces_force_control(nonlinear):
    """Prescribing the tip deflection of a force-controlled run gives back its solution, and the
    reaction f_int − F_ext at the prescribed DOFs sums to the applied force (ν = 0: the tip
    deflection is uniform across the width, so the force-controlled solution satisfies the
    displacement condition and is the unique solution of the displacement-controlled problem)."""
    P = 0.02 if not nonlinear else 0.15  # line force per width; nonlinear: w/l ≈ 0.4
    n = 1 if not nonlinear else 4
    fs = _spec(FORCE_TIP.format(P=P), nonlinear, n)
    rf = run(fs)
    assert rf.converged
    wdofs = _tip_dofs(fs, rf.problem)
    w = rf.u[wdofs]
    assert np.ptp(w) <= 1e-9 * abs(w).max()  # uniform tip deflection
    if not nonlinear:  # and the independent beam answer: w = P l³ / (3 E I) per width
        assert w[0] == pytest.approx(P * 10.0**3 / (3 * 1000.0 * 0.5**3 / 12), rel=0.02)
    ds = _spec(DISP_TIP.format(w=float(w[0])), nonlinear, n)
    rd = run(ds)
    assert rd.converged
    assert np.allclose(rd.u, rf.u, rtol=0, atol=1e-7 * abs(rf.u).max())
    R = rd.problem.reactions(rd.u, 1.0)
    assert R[_tip_dofs(ds, rd.problem)].sum() == pytest.approx(P * 1.0, rel=1e-6)  # line force × width
    # at a free DOF there is no reaction (equilibrium)
    free = rd.problem.op.independent
    assert np.abs(R[free]).max() <= 1e-6 * P
    # the load factor scales the prescribed value: half-way the deflection is half (linear)
    if not nonlinear:
        assert rd.summary["probes"]["w"] == pytest.approx(w[0], rel=1e-12)


def test_prescribed_value_needs_one_number_per_component():
    from layershell.io.build import InputError

    with pytest.raises(InputError, match=r"supports\[1\].value"):
        _spec(DISP_TIP.format(w="1.0, 2.0"))


# ------------------------------------------------------------------ softening: bar + cohesive spring
# A membrane strip (only the axial displacements free: y, z of every director and x of director 1
# fixed; ν = 0) of compliance c_e = L/(E b t) in series with a softening spring between its end
# x = 0 and the ground. Spring: bilinear in δ = Σ w_i u_x,i over the end nodes (w = 1/6, 4/6, 1/6,
# the consistent weights of the edge), F_s = k0 δ up to δ0 = F_p/k0, then linear softening to zero
# at δ_f; damage with secant unloading, irreversible (history κ updated at converged steps). Load:
# F = λ F̂ at x = L. Analytic path: u_L = c_e F + δ with F = F_s(δ): snap-back where
# c_e > (δ_f − δ0)/F_p, and the total dissipation is ½ F_p δ_f.
STRIP = """
[model]
title = "strip"
nonlinear = false
[mesh]
type = "rectangle"
lx = 10.0
ly = 1.0
nx = 2
ny = 1
[materials.m]
type = "isotropic"
E = 1000.0
nu = 0.0
[[layers]]
name = "bar"
material = "m"
thickness = 1.0
directors = 1
[[supports]]
type = "fix"
where = "x > -1"
directors = "all"
components = ["y", "z"]
[[supports]]
type = "fix"
where = "x > -1"
directors = [1]
components = ["x"]
[[loads]]
type = "edge"
where = "near(x, 10)"
direction = [1, 0, 0]
distribution = 1.0
face = "reference"
[steps]
n = 10
{steps}
[[probes]]
name = "u_end"
quantity = "displacement"
point = [10, 0, 0]
component = "x"
"""
C_E = 10.0 / (1000.0 * 1.0 * 1.0)  # L / (E b t)
K0, FP, DF = 1000.0, 1.0, 0.006  # spring stiffness, peak force (λ = 1), separation at zero force
D0 = FP / K0


class SofteningSpring:
    """Element-like block (assembly.Assembler.add_blocks): one spring on δ = w · u[dofs]."""

    symmetric = True

    def __init__(self, dofs, w, df):
        self.dofs = np.asarray(dofs)[None, :]
        self.w = np.asarray(w, float)
        self.df = df
        self.kappa = 0.0  # history: largest δ at a converged step

    def law(self, d):
        """(force, tangent) of the damage law at δ = d with the current history; at the peak
        (κ = δ0 within the solver's tolerance, 10⁻⁶) the tangent of further loading is the
        softening one. (With 10⁻⁹ the increment that ends at the peak, converged to a residual of
        5·10⁻⁹, left κ 5.8·10⁻⁹ below δ0 with numpy 2.4 / MKL 2026.2: the spring stayed elastic
        and no later increment converged.)"""
        DF = self.df
        k = max(self.kappa, d)
        at_peak = d >= self.kappa and k >= D0 * (1 - 1e-6)
        if k < D0 and not at_peak:
            return K0 * d, K0
        k = max(k, D0)
        soft = max(FP * (DF - k) / (DF - D0), 1e-9 * FP)  # force on the envelope at κ
        sec = soft / k
        if d >= self.kappa:  # loading on the softening envelope
            return (soft if d >= D0 else K0 * d), (-FP / (DF - D0) if soft > 1e-9 * FP else 0.0)
        return sec * d, sec  # secant unloading

    def response(self, u, tangent=True):
        d = float(self.w @ u[self.dofs[0]])
        F, k = self.law(d)
        fe = (F * self.w)[None, :]
        Ke = (k * np.outer(self.w, self.w))[None] if tangent else None
        return fe, Ke

    def commit(self, u):
        self.kappa = max(self.kappa, float(self.w @ u[self.dofs[0]]))
        return False


def _strip(df: float, steps: str = "", text: str = STRIP):
    """The strip (``text``: its model file) with the softening spring at x = 0: spec, problem,
    spring and the DOFs of the end x = L."""
    spec = build(parse(text.format(steps=steps)))
    pb = Problem.build(spec.model)
    x = spec.model.mesh.nodes
    end = np.flatnonzero(np.isclose(x[:, 0], 0.0))
    end = end[np.argsort(x[end, 1])]
    spring = SofteningSpring(pb.dm.layer_dofs[0][end, 0, 0], [1 / 6, 4 / 6, 1 / 6], df)
    pb.assembler.add_blocks([spring])
    tip = np.flatnonzero(np.isclose(x[:, 0], 10.0))
    tip = tip[np.argsort(x[tip, 1])]
    return spec, pb, spring, pb.dm.layer_dofs[0][tip, 0, 0]


def _trace(control: str, df: float, **kw):
    from layershell.solver.arclength import PathSettings, path_steps

    spec, pb, spring, tipdofs = _strip(df)
    ps = PathSettings(control=control, lambda_end=2.0, increment=0.1, max_steps=400, **kw)
    pts = []
    for st in path_steps(pb, spec.newton, ps, on_step_end=lambda p, u, lam: spring.commit(u)):
        d = float(spring.w @ st.u[spring.dofs[0]])
        ul = float(np.array([1 / 6, 4 / 6, 1 / 6]) @ st.u[tipdofs])
        pts.append((st.load_factor, d, ul, st.state.mode, st.dissipation, st.iterations))
    return pts, spring


def _check_on_analytic_path(pts, df):
    """Every converged point lies on the analytic equilibrium path: F = F_s(δ) on the elastic
    line or the softening envelope, and u_L = c_e F + δ."""
    for lam, d, ul, *_ in pts:
        assert ul == pytest.approx(C_E * lam + d, abs=1e-9)
        if d <= D0 * (1 + 1e-9):
            assert lam == pytest.approx(K0 * d, abs=1e-8)
        else:
            assert lam == pytest.approx(max(FP * (df - d) / (df - D0), 0.0), abs=1e-8)


def _corner(pts):
    """The limit point from the traced path: the intersection of the line through two points
    before the peak with the line through two points after it (the path is piecewise linear in
    (δ, λ))."""
    lam = np.array([p[0] for p in pts])
    d = np.array([p[1] for p in pts])
    pre = np.flatnonzero(d < D0 * (1 - 1e-9))[-2:]
    post = np.flatnonzero((d > D0 * (1 + 1e-9)) & (lam > 1e-3))[:2]
    s1 = np.polyfit(d[pre], lam[pre], 1)
    s2 = np.polyfit(d[post], lam[post], 1)
    dc = (s2[1] - s1[1]) / (s1[0] - s2[0])
    return float(np.polyval(s1, dc))


def test_arc_length_traces_softening_past_the_limit_point():
    """Crisfield's cylindrical arc length (no dissipation switch) on the softening bar without
    snap-back (δ_f = 0.03: softening compliance 0.029 > c_e = 0.01)."""
    df = 0.03
    pts, _ = _trace("arc_length", df, dissipation=False)
    _check_on_analytic_path(pts, df)
    lam = np.array([p[0] for p in pts])
    assert lam.max() <= 1.0 + 1e-9
    assert _corner(pts) == pytest.approx(1.0, rel=1e-6)  # the analytic limit point λ = F_p / F̂
    assert lam[-1] <= 1e-3 * lam.max()  # traced to complete separation
    assert {p[3] for p in pts} == {"arc"}


def test_dissipation_control_traces_the_snap_back():
    """Snap-back (δ_f = 0.006: c_e = 0.01 > (δ_f − δ0)/F_p = 0.005): the dissipation-based
    constraint takes over at the peak and traces the branch on which the end displacement
    u_L decreases with the load down to complete separation; Σ ΔG = ½ F_p δ_f."""
    df = 0.006
    pts, _ = _trace("arc_length", df, dissipation=True)
    _check_on_analytic_path(pts, df)
    lam = np.array([p[0] for p in pts])
    d = np.array([p[1] for p in pts])
    ul = np.array([p[2] for p in pts])
    i = int(np.argmax(lam))
    assert lam[i] <= 1.0 + 1e-9
    assert _corner(pts) == pytest.approx(1.0, rel=1e-6)
    assert np.all(np.diff(d[i:]) >= -1e-12)  # the crack only opens
    assert np.all(np.diff(ul[i:]) <= 1e-12)  # snap-back: the loaded end moves back
    assert ul[i] - ul[-1] == pytest.approx((C_E - (df - D0) / FP) * lam[i], rel=0.01)
    assert lam[-1] <= 1e-3 * lam.max()
    assert "dissipation" in {p[3] for p in pts}
    G = sum(p[4] for p in pts)
    assert G == pytest.approx(0.5 * FP * df, rel=0.01)
    assert all(p[4] >= -1e-12 for p in pts)


def test_arc_length_on_a_geometrically_nonlinear_cantilever_matches_load_control():
    """Stable branch: the arc-length path of the large-deflection cantilever passes through the
    load-controlled solutions (every traced point solved again under load control at its λ
    stays where it is) and ends exactly at λ_end with the load-controlled answer."""
    from layershell.solver.arclength import PathSettings, path_steps
    from layershell.solver.newton import newton

    fs = _spec(FORCE_TIP.format(P=0.15), True, 4)
    rf = run(fs)
    pb = Problem.build(fs.model)
    ps = PathSettings(control="arc_length", lambda_end=1.0, increment=0.25)
    pts = list(path_steps(pb, fs.newton, ps))
    assert pts[-1].load_factor == 1.0 and pts[-1].state.finished
    assert np.allclose(pts[-1].u, rf.u, rtol=0, atol=1e-8 * abs(rf.u).max())
    lams = [p.load_factor for p in pts]
    assert np.all(np.diff(lams) > 0)
    for p in pts[:-1]:
        pb2 = Problem.build(fs.model)
        u2, res = newton(pb2, p.u, p.load_factor, fs.newton)
        assert res.converged and res.iterations <= 1
        assert np.allclose(u2, p.u, rtol=0, atol=1e-8 * abs(rf.u).max())


ARC_STEPS = 'control = "arc_length"\nmax_steps = 40'


def _restart_matches_uninterrupted(spec, tmp_path):
    """Run ``spec`` through; run it again, interrupted after step 2, and restart it from its
    checkpoint: the same load factors, iterations and displacements (returns the first run)."""
    full = run(spec, tmp_path / "full", write_vtu=False)
    assert full.converged
    lams = [s["load_factor"] for s in full.summary["steps"]]
    assert lams[-1] == 1.0 and len(lams) >= 3 and full.summary["path_end"] == "lambda_end"

    part, again = stopped_and_restarted(spec, tmp_path / "part", 2)
    assert part.interrupted and len(part.summary["steps"]) == 2
    assert again.converged
    assert [s["load_factor"] for s in again.summary["steps"]] == pytest.approx(lams, rel=1e-12)
    assert [s["iterations"] for s in again.summary["steps"]] == [s["iterations"] for s in full.summary["steps"]]
    assert np.allclose(again.u, full.u, rtol=0, atol=1e-12 * abs(full.u).max())
    return full


def test_arc_length_run_from_the_model_file_and_restart(tmp_path):
    """[steps] control = 'arc_length' through the runner; a run interrupted after step 2 and
    restarted from its checkpoint (arc length, last increment, λ) ends with the same steps and
    displacements as an uninterrupted run."""
    _restart_matches_uninterrupted(_spec(FORCE_TIP.format(P=0.15), True, 4, ARC_STEPS), tmp_path)


def test_arc_length_without_a_scaled_load_is_bad_input():
    from layershell.io.build import InputError

    fixed_tip = DISP_TIP.format(w=1.0) + "scaled = false\n"  # neither a force nor a displacement scaled by λ
    with pytest.raises(InputError, match="steps.control"):
        _spec(fixed_tip, False, 4, ARC_STEPS)
    with pytest.raises(InputError, match="steps.factors"):
        _spec(FORCE_TIP.format(P=0.1), False, 4, ARC_STEPS + "\nfactors = [0.5, 1.0]")


def test_adaptive_steps_reach_the_end_in_fewer_steps():
    """Automatic step size on the large-deflection cantilever (w/l ≈ 0.7): from the same first
    increment (1/20) it reaches λ = 1 in fewer steps and Newton iterations than 20 fixed steps,
    with the same answer."""
    res = {}
    for key, extra in (("fixed", ""), ("adaptive", "adaptive = true")):
        r = run(_spec(FORCE_TIP.format(P=0.5), True, 20, extra))
        assert r.converged
        st = r.summary["steps"]
        res[key] = (len(st), sum(s["iterations"] for s in st), r.summary["probes"]["w"], st[-1]["load_factor"])
    assert res["fixed"][0] == 20
    assert res["adaptive"][3] == 1.0
    assert res["adaptive"][0] <= 10 and res["adaptive"][1] < res["fixed"][1]
    assert res["adaptive"][2] == pytest.approx(res["fixed"][2], rel=1e-9)


def test_target_iterations_sets_the_step_size_control():
    """``[steps] target_iterations`` reaches the step-size control: the adaptive cantilever with
    a target of 16 iterations per step takes fewer, longer steps than with the default 8, to the
    same answer; 0 is bad input naming the field."""
    from layershell.io.build import InputError

    res = {}
    for target in (8, 16):
        spec = _spec(FORCE_TIP.format(P=0.5), True, 20, f"adaptive = true\ntarget_iterations = {target}")
        assert spec.path_following.target_iterations == target
        r = run(spec)
        assert r.converged and r.summary["steps"][-1]["load_factor"] == 1.0
        res[target] = (len(r.summary["steps"]), r.summary["probes"]["w"])
    assert res[16][0] < res[8][0]
    assert res[16][1] == pytest.approx(res[8][1], rel=1e-9)
    with pytest.raises(InputError, match="target_iterations"):
        _spec(FORCE_TIP.format(P=0.5), True, 20, "adaptive = true\ntarget_iterations = 0")


def test_increments_whose_iterations_do_not_depend_on_their_size_grow():
    """arclength.size_insensitive, the exception to the step-size rule Δλ × target/its: an
    increment 10 % longer than the last that took at most one iteration more, or one 10 %
    shorter that took at most one fewer, says the count does not follow the size (then the next
    grows by INSENSITIVE_GROWTH, where the increment was cut below INSENSITIVE_BELOW of the
    first); not beyond twice the target, not without a last increment. The Gmsh plate that it
    lets reach λ = 1: tests/test_delamination.py. Under the arc length it compares with the last
    two increments (arclength.ARC_WINDOW): the shortest and the most iterations of them."""
    from layershell.solver.arclength import size_insensitive

    assert size_insensitive(1.2e-5, 8, [(1e-5, 7)], 8)  # longer, one iteration more
    assert not size_insensitive(1.2e-5, 9, [(1e-5, 7)], 8)  # two more: the size matters
    assert size_insensitive(0.8e-5, 7, [(1e-5, 8)], 8)  # shorter, one fewer: the cut did not pay
    assert not size_insensitive(0.8e-5, 6, [(1e-5, 8)], 8)  # two fewer: it did
    assert not size_insensitive(1.05e-5, 7, [(1e-5, 7)], 8)  # the size barely changed
    assert not size_insensitive(2e-5, 17, [(1e-5, 17)], 8)  # more than twice the target
    assert not size_insensitive(2e-5, 5, [(0.0, 0)], 8)  # the first increment
    assert not size_insensitive(2e-5, 5, [], 8)
    # the arc length's window of two: counts that alternate (the 16 x 12 slab: 9, 7, 9, ...)
    # against the shortest and the most of the last two
    assert not size_insensitive(1.02e-5, 9, [(0.89e-5, 7)], 8)  # against the last alone: +2
    assert size_insensitive(1.02e-5, 9, [(1e-5, 9), (0.89e-5, 7)], 8)
    assert not size_insensitive(1.02e-5, 11, [(1e-5, 9), (0.89e-5, 7)], 8)  # +2 on the most
    assert size_insensitive(0.8e-5, 6, [(1e-5, 9), (0.95e-5, 7)], 8)  # shorter, one fewer than the fewest
    assert not size_insensitive(0.8e-5, 5, [(1e-5, 9), (0.95e-5, 7)], 8)


def test_jump_warnings_unit():
    from layershell.solver.arclength import jump_warnings

    assert jump_warnings(3, 0.75, 0.5, 0.30, 0.05, None, None, 0.2, 3.0)  # 25 % of the interface at once
    assert not jump_warnings(3, 0.75, 0.5, 0.20, 0.05, None, None, 0.2, 3.0)
    # a probe 5× larger while λ grew 1.5× (5 > 3 · 1.5): a jump; 4× while λ grew 2× (4 < 3 · 2): none
    assert jump_warnings(3, 0.75, 0.5, None, None, {"w": 5.0}, {"w": 1.0}, 0.2, 3.0)
    assert not jump_warnings(3, 1.0, 0.5, None, None, {"w": 4.0}, {"w": 1.0}, 0.2, 3.0)
    assert not jump_warnings(3, 0.75, 0.5, None, None, {"w": 4.0}, {"w": 0.0}, 0.2, 3.0)  # from zero: no ratio
    assert not jump_warnings(3, 0.75, 0.5, 0.9, 0.0, {"w": 40.0}, {"w": 1.0}, None, None)  # switched off


@pytest.mark.slow
def test_debonding_jump_is_warned_and_cut():
    """§5.1 plate with strong friction, 3 × 3: 4 fixed steps debond 27.8 % of the interface in
    one step - a warning in summary.json; adaptive steps cut that step (5 halvings, to
    Δλ = 1/128) and, as the jump stays (the stress criterion releases the zone at once), accept it
    with the warning at the onset load."""
    import warnings

    from helpers import run_example

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run_example("cantilever_plate_strong", {"n = 24": "n = 4"})
    assert r.converged
    w = r.summary["warnings"]
    assert len(w) == 1 and "step 3" in w[0] and "27.8 %" in w[0]
    assert any("debonded area jumped" in str(c.message) for c in caught)  # on the console too
    r = run_example("cantilever_plate_strong", {"n = 24": "n = 4\nadaptive = true"})
    assert r.converged and r.summary["steps"][-1]["load_factor"] == 1.0
    w = r.summary["warnings"]
    assert len(w) == 1
    lam_jump = float(w[0].split("λ = ")[1].split(")")[0])
    assert 0.5 < lam_jump < 0.5 + 0.25 / 2**4  # cut down near the onset (between 0.5 and 0.75)


def test_displacement_control_restart(tmp_path):
    """A displacement-controlled run stopped after step 2 and restarted ends where the
    uninterrupted run ends (the prescribed part of u is imposed again at every load factor)."""
    spec = _spec(DISP_TIP.format(w=3.0), True, 4)
    full = run(spec, tmp_path / "full", write_vtu=False)

    part, again = stopped_and_restarted(spec, tmp_path / "part", 2)
    assert part.interrupted
    assert again.converged and full.converged
    assert np.allclose(again.u, full.u, rtol=0, atol=1e-12 * abs(full.u).max())
    assert again.summary["probes"]["w"] == pytest.approx(3.0, rel=1e-12)


def test_stagnation_detects_stalled_and_cycling_newton_only():
    """`stagnates` (arc-length increments with frozen cohesive sets give up on it): a stalled
    residual (the DCB's frozen loading point that ping-pongs across δ_n = 0: 2566 N in every
    iteration) and a two-cycle are detected after n iterations without progress; quadratic
    convergence, and convergence after a few iterations of growth, are not."""
    from layershell.solver.newton import stagnates

    def first(res, n=3):  # the first iteration at which the check fires, or None
        return next((k for k in range(len(res) + 1) if stagnates(res[:k], n)), None)

    assert first([3.2e3, 1.5e3, 1.0e4, 2566.0, 2566.0, 2566.0, 2566.0, 2566.0]) == 5
    assert first([8.4e3, 2.8e3, 8.6e3, 9.7e3, 1.9e4, 1.87e3, 2.15e4, 1.87e3, 2.15e4, 1.87e3, 2.15e4]) == 5
    assert first([1e3, 3e2, 2e1, 1e-1, 1e-5, 1e-12]) is None
    assert first([1.0, 5.0, 3.0, 0.5, 1e-3, 1e-8]) is None  # grows first, then converges
    assert first([2566.0] * 10, 0) is None  # off


def test_a_stalled_path_after_the_peak_ends_as_complete_failure():
    """The arc length ends a path that no longer moves far below its peak (the DCB on 200
    elements crawled at λ = 0.00906, 1.5 % of its peak 0.61, for 1700 increments): 25 increments
    within end_fraction × the peak of each other, all below 5 % of it. Not near the peak (a hard
    crack front there is not the end), not while λ still changes, not before 25 increments."""
    from layershell.solver.arclength import stalled

    crawl = list(0.00906 + 1e-5 * np.linspace(1, 0, 25))
    assert stalled(crawl, 25, 0.61, 1e-3)
    assert not stalled(crawl[1:], 25, 0.61, 1e-3)  # too few
    assert not stalled(crawl, 25, 0.15, 1e-3)  # 6 % of the peak: not yet
    assert not stalled(list(0.5 + 1e-5 * np.linspace(1, 0, 25)), 25, 0.61, 1e-3)  # near the peak
    assert not stalled(list(np.linspace(0.02, 0.01, 25)), 25, 0.61, 1e-3)  # still falling
    assert not stalled(crawl, 0, 0.61, 1e-3)  # switched off


def test_complete_failure_needs_a_dissipating_increment():
    """The path ends by complete failure where λ falls below end_fraction of its peak in an
    increment that dissipates; elastic unloading to λ ≈ 0 (ΔG at round-off, here ±1e-15 of the
    energy dissipated so far) does not end it, nor does a rising or still large load."""
    from layershell.solver.arclength import complete_failure

    assert complete_failure(1e-4, -0.01, 0.6, 0.02, 10.0, 1e-3)
    assert not complete_failure(1e-4, -0.01, 0.6, 1e-14, 10.0, 1e-3)
    assert not complete_failure(1e-4, -0.01, 0.6, -1e-14, 10.0, 1e-3)
    assert not complete_failure(1e-4, +0.01, 0.6, 0.02, 10.0, 1e-3)
    assert not complete_failure(0.3, -0.01, 0.6, 0.02, 10.0, 1e-3)


def test_a_force_path_that_unloads_without_damage_is_stopped():
    """``unloading``: on a force path by arc length the load and its conjugate displacement fall
    together only where interfaces debond (a snap-back) or after complete failure. Once λ lies
    more than 5 % of its peak below the last increment that damaged, in an increment in which
    λ and F̂·u both fell, the path follows elastic or frictional unloading (a variant of the
    release of closed points, not kept, took the cohesive slab of tests/test_slab_trc_soffit.py
    from its snap-back at λ = 278 down to 0 so, reported as complete failure). Not past an
    elastic limit point (the load falls, the displacement grows), not within 5 %, not before
    any damage, not while the load rises."""
    from layershell.solver.arclength import UNLOADING_FRACTION, unloading

    peak, lam_d = 327.0, 278.0
    below = lam_d - 1.2 * UNLOADING_FRACTION * peak
    assert unloading(below, -2.0, -1.0, lam_d, peak)
    assert not unloading(below, -2.0, +1.0, lam_d, peak)  # snap-through: the displacement grows
    assert not unloading(lam_d - 0.8 * UNLOADING_FRACTION * peak, -2.0, -1.0, lam_d, peak)  # not yet
    assert not unloading(below, -2.0, -1.0, float("nan"), peak)  # nothing damaged yet
    assert not unloading(below, +2.0, -1.0, lam_d, peak)  # the load rises


def test_ledger_books_damage_apart_from_friction():
    """``ledger_booked``: (all, by damage) the energy the cohesive interfaces' ledger has booked.
    A dissipation-controlled increment must be booked in all (elastic unloading meets the
    constraint without any); only damage marks the branch on which the interfaces debond, since
    friction dissipates on unloading paths too (``unloading`` above)."""
    from test_cohesive_interface import strip

    from layershell.solver.arclength import ledger_booked

    spec = strip(nonlinear="false", nx=2, load="0.5", steps=1, cohesive={"smax": 0.3, "tmax": 0.6})
    pb = Problem.build(spec.model)
    (r,) = pb.interfaces.runs
    assert ledger_booked(pb) == (0.0, 0.0)
    r.energy = np.array([1.5, 7.0, 0.25])  # fracture, friction, viscous
    assert ledger_booked(pb) == (8.75, 1.75)


def test_a_path_that_no_longer_advances_is_stopped():
    """``crawling``: 25 increments within end_fraction × the peak of λ that together dissipated
    less than end_fraction of the energy dissipated so far - the increments have been cut to
    nothing (the nonlinear §5.1 plate with friction crawled at λ = 0.8953 through increments of
    10⁻⁷ of the first). Not on a plateau of the load that dissipates (a long bond debonding at
    P_u), not while λ moves, not before 25 increments, not when switched off."""
    from layershell.solver.arclength import crawling

    lam = list(0.8953 + 1e-7 * np.arange(25))
    tiny = [2e-7] * 25
    assert crawling(lam, tiny, 25, 0.8953, 0.06, 1e-3)
    assert not crawling(lam, [2e-4] * 25, 25, 0.8953, 0.06, 1e-3)  # a dissipating plateau
    assert not crawling(list(np.linspace(0.88, 0.8953, 25)), tiny, 25, 0.8953, 0.06, 1e-3)  # λ moves
    assert not crawling(lam[1:], tiny[1:], 25, 0.8953, 0.06, 1e-3)  # too few
    assert not crawling(lam, tiny, 0, 0.8953, 0.06, 1e-3)  # switched off


def test_energy_error_of_an_increment_and_when_the_step_control_acts():
    """arclength.increment_energy_error and energy_control on ledger terms (W, D, E, E/S): the
    error an increment adds relative to the larger of its work and its dissipation (a floor of
    ENERGY_FLOOR × W for increments without energy); the control acts only where the run's balance
    error is above 0.5 % and the increment made it larger, and its tolerance falls from the full
    value at 0.5 % to a tenth at 1 %."""
    from layershell.solver.arclength import ENERGY_FLOOR, energy_control, increment_energy_error

    assert increment_energy_error((100.0, 10.0, 0.6, 0.006), (110.0, 14.0, 0.8, 0.8 / 110)) == pytest.approx(0.02)
    # a snap-back: the work falls by 2 while 5 are dissipated - the dissipation is the scale
    assert increment_energy_error((100.0, 10.0, 0.5, 0.005), (98.0, 15.0, 0.6, 0.006)) == pytest.approx(0.1 / 5)
    assert increment_energy_error((100.0, 10.0, -0.5, -0.005), (98.0, 15.0, -0.6, -0.006)) == pytest.approx(0.1 / 5)
    assert increment_energy_error((100.0, 10.0, 0.5, 0.005), (100.0, 10.0, 0.5 + 1e-6, 0.005)) == pytest.approx(
        1e-6 / (ENERGY_FLOOR * 100.0))
    assert increment_energy_error(None, (1.0, 0.0, 0.0, 0.0)) == 0.0
    # no action below 0.5 %, nor where the increment reduced the error
    assert energy_control((100.0, 10.0, 0.3, 0.003), (110.0, 14.0, 0.5, 0.5 / 110), 0.02) == 0.0
    assert energy_control((100.0, 10.0, 0.8, 0.008), (110.0, 14.0, 0.7, 0.7 / 110), 0.02) == 0.0
    assert energy_control(None, (110.0, 14.0, 0.7, 0.7 / 110), 0.02) == 0.0
    # 2 % of the increment's work at a run error of 0.6 %: the tolerance there is 0.8 × 2 %
    assert energy_control((100.0, 10.0, 0.4, 0.004), (110.0, 14.0, 0.6, 0.006), 0.02) == pytest.approx(1 / 0.8)
    assert energy_control((100.0, 10.0, -0.4, -0.004), (110.0, 14.0, -0.6, -0.006), 0.02) == pytest.approx(1 / 0.8)
    # at or beyond 1 %: a tenth of the tolerance
    assert energy_control((100.0, 10.0, 1.0, 0.01), (110.0, 14.0, 1.2, 0.012), 0.02) == pytest.approx(10.0)


# ------------------------------------------------------------------ displacement control by arc length
U_BAR = 0.02  # prescribed end displacement at λ = 1


def _strip_displacement(df: float):
    """The softening strip with its end x = L pulled by a prescribed displacement u_L = λ ū
    (a [[supports]] 'fix' with 'value') instead of the end force."""
    load = STRIP[STRIP.index("[[loads]]"):STRIP.index("[steps]")]
    return _strip(df, text=STRIP.replace(load, f'[[supports]]\ntype = "fix"\nwhere = "near(x, 10)"\n'
                                               f'components = ["x"]\nvalue = [{U_BAR}]\n'))


def test_displacement_control_by_arc_length_traces_the_snap_back():
    """Arc length on a prescribed displacement (λ scales u_L = λ ū, the load vector of the bordered
    system is Tᵀ(F̂ − K g)). The strip with the snap-back (δ_f = 0.006): past the peak
    (u_L = c_e F_p + δ0 = 0.011, λ = 0.55) the equilibrium path needs u_L to fall while the spring
    softens, to u_L = δ_f = 0.006 (λ = 0.3) where the force has vanished - no prescribed
    displacement that only grows can follow it. Independent reference: the analytic path (the
    reaction F at the pulled end equals the spring force F_s(δ), u_L = c_e F + δ), the total
    dissipation ½ F_p δ_f of the dissipation constraint (here with the reaction's work terms
    ½(R₀Δλ − λ₀ΔR)); after complete separation the path goes on elastically, by the arc length
    again, to λ_end = 1 with no force."""
    from layershell.solver.arclength import PathSettings, path_steps

    df = 0.006
    spec, pb, spring, tipdofs = _strip_displacement(df)
    ps = PathSettings(control="arc_length", lambda_end=1.0, increment=0.05, max_steps=200)
    pts = []
    for st in path_steps(pb, spec.newton, ps, on_step_end=lambda p, u, lam: spring.commit(u)):
        d = float(spring.w @ st.u[spring.dofs[0]])
        F = float(pb.reactions(st.u, st.load_factor)[tipdofs].sum())
        assert np.allclose(st.u[tipdofs], st.load_factor * U_BAR, rtol=0, atol=1e-15)  # prescribed
        pts.append((st.load_factor, d, F, st.state.mode, st.dissipation, st.end, st.iterations))
    lam = np.array([p[0] for p in pts])
    d = np.array([p[1] for p in pts])
    F = np.array([p[2] for p in pts])
    for lam_k, d_k, F_k in zip(lam, d, F):  # on the analytic path
        assert lam_k * U_BAR == pytest.approx(C_E * F_k + d_k, abs=1e-9)
        law = K0 * d_k if d_k <= D0 * (1 + 1e-9) else max(FP * (df - d_k) / (df - D0), 0.0)
        assert F_k == pytest.approx(law, abs=1e-7)
    i = int(np.argmax(F))
    assert F[i] == pytest.approx(FP, rel=1e-6) and lam[i] == pytest.approx((C_E * FP + D0) / U_BAR, rel=1e-6)
    # the snap-back: λ (the prescribed displacement) falls to u_L = δ_f while the spring softens
    j = i + int(np.argmin(lam[i:]))
    assert lam[j] == pytest.approx(df / U_BAR, rel=1e-6) and np.all(np.diff(lam[i:j + 1]) < 0)
    assert np.all(np.diff(d[i:]) >= -1e-12)  # the crack only opens
    assert sum(p[4] for p in pts) == pytest.approx(0.5 * FP * df, rel=1e-6)
    # no increment dissipates a negative energy beyond the equilibrium tolerance: the elastic
    # increment to the peak, converged to a residual of 5·10⁻⁹, books -2.2·10⁻¹² (7·10⁻¹⁰ of the
    # total) with numpy 2.4 / MKL 2026.2 (the bound was -10⁻¹² absolute before)
    assert all(p[4] >= -1e-8 * 0.5 * FP * df for p in pts)
    assert "dissipation" in {p[3] for p in pts} and pts[-1][3] == "arc"
    assert lam[-1] == 1.0 and pts[-1][5] == "lambda_end" and abs(F[-1]) <= 1e-8 * FP  # (the spring keeps 1e-9 F_p)
    # past the separation the dissipation constraint is not tried again and again: its predictor
    # would move λ by more than its peak (measured 1-2 iterations an increment; 326 in the first
    # increment before that rule)
    assert sum(p[6] for p in pts[j + 1:]) <= 10


@pytest.mark.parametrize("nonlinear", [False, True])
def test_displacement_control_by_arc_length_matches_load_control(nonlinear):
    """A stable path: the cantilever with its tip deflection prescribed, traced by arc length,
    passes through the displacement-controlled (load control) solutions: each traced point solved
    again by Newton at its λ stays where it is, and the path ends at λ_end with the
    load-controlled answer."""
    from layershell.solver.arclength import PathSettings, path_steps
    from layershell.solver.newton import newton

    ds = _spec(DISP_TIP.format(w=4.0 if nonlinear else 1.0), nonlinear, 4)
    rd = run(ds)
    assert rd.converged
    pb = Problem.build(ds.model)
    pts = list(path_steps(pb, ds.newton, PathSettings(control="arc_length", lambda_end=1.0, increment=0.25)))
    assert pts[-1].load_factor == 1.0 and pts[-1].state.finished
    assert np.allclose(pts[-1].u, rd.u, rtol=0, atol=1e-8 * abs(rd.u).max())
    assert np.all(np.diff([p.load_factor for p in pts]) > 0)
    for p in pts[:-1]:
        u2, res = newton(Problem.build(ds.model), p.u, p.load_factor, ds.newton)
        assert res.converged and res.iterations <= 1
        assert np.allclose(u2, p.u, rtol=0, atol=1e-8 * abs(rd.u).max())


def test_displacement_control_by_arc_length_restart(tmp_path):
    """A model-file run whose prescribed tip deflection is traced by arc length, interrupted after
    step 2 and restarted from its checkpoint, ends with the same steps, iterations and
    displacements as the uninterrupted run (the prescribed part of u follows λ, which the
    checkpoint restores with the path state)."""
    _restart_matches_uninterrupted(_spec(DISP_TIP.format(w=4.0), True, 4, ARC_STEPS), tmp_path)


@pytest.mark.parametrize("nonlinear", [False, True])
def test_load_column_of_prescribed_displacements_is_the_tangent_times_g(nonlinear):
    """The arc length's load column for prescribed displacements, −∂r/∂λ = F̂ − K(u) g, takes K g
    from a forward difference of the internal forces along g (``stiffness_along``). Independent
    reference: the assembled full tangent times g, at a deformed state (the tip lifted 4 at λ = 1,
    a random displacement of the free DOFs): to round-off on the linear model (measured 2·10⁻⁹ of
    the largest entry, the step being 10⁻⁷ of the displacements), to the difference's truncation
    on the geometrically nonlinear one (1.3·10⁻⁷)."""
    from layershell.solver.arclength import load_rate, prescribed_direction, stiffness_along

    spec = _spec(DISP_TIP.format(w=4.0), nonlinear, 4)
    pb = Problem.build(spec.model)
    g = prescribed_direction(pb)
    assert g is not None and np.array_equal(g, pb.op.g_scaled)
    rng = np.random.default_rng(1)
    u = pb.impose(pb.op.expand(0.1 * rng.standard_normal(pb.op.n_red)), 0.7)
    _, K = pb.assembler.evaluate(u, tangent=True)
    Kg = K @ g
    assert np.abs(Kg).max() > 0
    err = np.abs(stiffness_along(pb, u, g) - Kg).max() / np.abs(Kg).max()
    assert err < (1e-7 if not nonlinear else 1e-5), err
    assert np.allclose(load_rate(pb, u), pb.F_scaled - stiffness_along(pb, u, g), rtol=0, atol=1e-12 * np.abs(Kg).max())



def _path_stand_ins(monkeypatch, al, **patches) -> None:
    """Stand-ins for the problem-side helpers of arclength.path_steps (no interfaces, no
    prescribed displacements, nothing dissipated, no active-set blocks), plus ``patches``
    (name: stand-in)."""
    common = {"check_path": lambda p, ps: None, "interface_form": lambda p: False,
              "prescribed_direction": lambda p: None, "dissipation_so_far": lambda p: 0.0,
              "dissipation_increment": lambda *a: 0.0, "conjugates": lambda p, u: (0.0, 0.0),
              "check_stabilised_step": lambda *a: None, "active_set_blocks": lambda p: ([], False),
              "friction_excess": lambda p, u, gradient=False: (0.0, None)}
    for name, value in {**common, **patches}.items():
        monkeypatch.setattr(al, name, value)


def _stand_in_problem(booked: dict | None = None):
    """A two-DOF stand-in for the Problem that arclength.path_steps sees (F̂ = (1, 1)); with
    ``booked`` ({"damage": ...}, the stand-in ledger) cohesive interfaces whose state is that
    dict (snapshot and restore copy it)."""
    from types import SimpleNamespace

    pb = SimpleNamespace(interfaces=None, dm=SimpleNamespace(n_full=2), F_scaled=np.ones(2), start_inertia=None,
                         begin_step=lambda: None)
    if booked is not None:
        pb.interfaces = SimpleNamespace(cohesive=lambda: True, dissipation=lambda: [booked["damage"]])
        pb.snapshot, pb.restore = (lambda: dict(booked)), booked.update
        pb.op = SimpleNamespace(independent=np.arange(2))
    return pb


def test_a_stuck_arc_length_is_passed_by_one_load_controlled_increment(monkeypatch):
    """Where the arc length's increments fail at their smallest size (or crawl), one
    load-controlled increment is tried from the last state (Newton with its own active-set loop);
    where it converges the run warns and goes on by load-controlled increments (a stretch) until
    one fails, then by arc length again; where it does not (here beyond
    λ = 0.5, as past a peak; its cuts cannot reach 0.5 exactly) the run stops with the arc length's message and says that a
    load-controlled increment found no equilibrium either. Stand-ins: constrained iterations that
    never converge, and a Newton solve with equilibria up to λ = 0.5 only."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import ConvergenceError, NewtonResult, NewtonSettings

    def never(problem, u, lam, size, *a, **k):
        return al.Attempt(False, u, lam, 3, [1.0], message="stand-in: no constrained solution")

    def newton_to_half(problem, u, lam, s):
        ok = lam <= 0.5 + 1e-12
        return u + 1.0, NewtonResult(ok, 2, [1e-10 if ok else 1e-3], message="" if ok else "diverged")

    _path_stand_ins(monkeypatch, al, arc_attempt=never, newton=newton_to_half)
    pb = _stand_in_problem()
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         jump_area=None, jump_ratio=None, dissipation=False)
    seen = []
    with pytest.raises(ConvergenceError) as err:
        for st in al.path_steps(pb, NewtonSettings(), ps, lam0=0.1, u0=np.zeros(2)):
            seen.append((st.load_factor, st.warnings))
    # 0.1 + 0.25 by the rescue; then a stretch of load-controlled increments: + 0.5 and + 0.25
    # fail (STRETCH_CUTS), so the arc length again, which fails, and a rescue from 0.35: + 0.25
    # fails, + 0.125 passes; from 0.475 the stretch fails, the arc length, and the rescue too
    assert [lam for lam, _ in seen] == pytest.approx([0.35, 0.475])
    for _, ws in seen:
        assert any("one load-controlled increment passed it" in w and "go on while they converge" in w for w in ws)
    assert any("load-controlled increments took the path from load factor 0.1 to 0.35; from there the arc "
               "length again" in w for w in seen[1][1])
    msg = str(err.value)
    assert msg.startswith("step 3: no equilibrium from load factor 0.475")
    assert "a load-controlled increment from it found no equilibrium either" in msg
    ps.load_rescue = False  # without the rescue the first failure stops the run
    with pytest.raises(ConvergenceError) as err:
        list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.1, u0=np.zeros(2)))
    assert "either" not in str(err.value) and "from load factor 0.1" in str(err.value)
    # a rescue may not jump: where the load-controlled increment converges only with a probe jump
    # at every size (a snap-back passed dynamically), the run stops and says so
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         max_jump_cuts=2, jump_area=None, jump_ratio=3.0, dissipation=False)
    seen = []
    with pytest.raises(ConvergenceError) as err:
        for st in al.path_steps(pb, NewtonSettings(), ps, lam0=0.1, u0=np.zeros(2),
                                watch=lambda u, lam: {"p": 1.0 if lam <= 0.36 else 100.0}):
            seen.append(st.load_factor)
    assert seen == pytest.approx([0.35]) and "a load-controlled increment from it jumps (probe jump" in str(err.value)
    # nor with a debonding jump that only the converged increment shows: a rescue's Newton solve
    # updates the cohesive sets itself, so no re-solution sees the area jump (on CI the slab by arc
    # length passed its end-debonding snap-back so, half of its interface debonding in one rescue,
    # and went on to the second peak at 376.6 kN/m²)
    last = {"lam": 0.1}

    def newton_recorded(problem, u, lam, s):
        last["lam"] = lam
        return newton_to_half(problem, u, lam, s)

    monkeypatch.setattr(al, "newton", newton_recorded)
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         max_jump_cuts=2, jump_area=0.2, jump_ratio=None, dissipation=False)
    seen = []
    with pytest.raises(ConvergenceError) as err:
        for st in al.path_steps(pb, NewtonSettings(), ps, lam0=0.1, u0=np.zeros(2),
                                measure=lambda p: 0.0 if last["lam"] <= 0.36 else 0.5):
            seen.append(st.load_factor)
    assert seen == pytest.approx([0.35]) and "a load-controlled increment from it jumps (debonding jump" in str(err.value)


def test_a_rising_branch_on_which_the_arc_length_needs_cuts_is_taken_by_load_control(monkeypatch):
    """On a force path, an arc-length increment that needed cuts and raised λ above its peak so
    far hands over to load-controlled increments (a stretch: Newton with its own active-set loop
    steps over the single points' local snap-backs that the arc length traces one by one; the
    cohesive slab on 16 × 12 rose by 5-40 kN/m² per load-controlled increment where its arc
    lengths advanced 0.04-0.5). The stretch ends after a load-controlled increment that needed a
    halving, or where one fails within STRETCH_CUTS halvings (here above λ = 0.6, as at a peak):
    the arc length again from the last state, and no new stretch until λ passes the load that
    the failed increment aimed at.
    Stand-ins: arc-length increments that converge up to Δl = 0.5 (λ + 0.05 each), a Newton
    solve with equilibria up to λ = 0.6."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonResult, NewtonSettings

    def arc_to_half(problem, u, lam, size, *a, **k):
        ok = size <= 0.5 + 1e-12
        return al.Attempt(ok, u + 0.1, lam + 0.05, 2, [1e-10 if ok else 1.0], message="" if ok else "stand-in")

    calls = []

    def newton_to_06(problem, u, lam, s):
        calls.append(lam)
        ok = lam <= 0.6 + 1e-12
        return u + 1.0, NewtonResult(ok, 8, [1e-10 if ok else 1e-3], message="" if ok else "diverged")

    _path_stand_ins(monkeypatch, al, arc_attempt=arc_to_half, newton=newton_to_06, full_weights=lambda p: 1.0)
    pb = _stand_in_problem()
    ps = al.PathSettings(control="arc_length", lambda_end=10.0, increment=0.25, arc_length=1.0, max_cuts=4,
                         jump_area=None, jump_ratio=None, dissipation=False)
    steps = []
    for st in al.path_steps(pb, NewtonSettings(), ps, lam0=0.1, u0=np.zeros(2)):
        steps.append(st)
        if len(steps) == 8:
            break
    lams = [st.load_factor for st in steps]
    # the arc length (Δl 1 fails, 0.5 passes: a cut on a rising branch), then load control (8
    # iterations: the size stays): + 0.25; + 0.25 fails and + 0.125 passes, which ends the stretch;
    # the arc length, + 0.05 per increment, each after a cut from here
    assert lams[:5] == pytest.approx([0.15, 0.4, 0.525, 0.575, 0.625])
    assert [st.state.mode for st in steps] == ["load", "load", "arc", "arc", "arc", "arc", "load", "arc"]
    assert any("from load factor 0.15" in w and "load-controlled increments go on" in w for w in steps[1].warnings)
    assert any("load-controlled increments took the path from load factor 0.15 to 0.525" in w
               for w in steps[2].warnings)
    # a new stretch only above the load the halved increment left out (0.525 + 0.125), after an
    # increment with a cut: from 0.725; its first increment fails at both sizes (0.975, 0.85): the
    # arc length again, not warned
    assert lams[5:] == pytest.approx([0.675, 0.725, 0.775])
    tried = [lam for lam in calls if lam > 0.6]
    assert tried == pytest.approx([0.65, 0.975, 0.85])
    assert all(not any("took the path" in w for w in st.warnings) for st in steps[3:])
    # not where λ falls, not below the peak, not below the block, not without cuts, not on a
    # displacement path, not without the rescue
    assert al.stretch_may_start(ps, True, False, 1, 0.5, 0.05, 0.45, -np.inf)
    for args in ((True, False, 1, 0.5, -0.05, 0.45, -np.inf), (True, False, 1, 0.5, 0.05, 0.55, -np.inf),
                 (True, False, 1, 0.5, 0.05, 0.45, 0.6), (True, False, 0, 0.5, 0.05, 0.45, -np.inf),
                 (True, True, 1, 0.5, 0.05, 0.45, -np.inf), (False, False, 1, 0.5, 0.05, 0.45, -np.inf)):
        assert not al.stretch_may_start(ps, *args), args


def test_a_dissipation_increment_met_by_friction_while_the_load_falls_is_refused(monkeypatch):
    """On a force path a dissipation-controlled increment in which λ falls while the interfaces'
    ledger books no damage is friction's work on unloading, not a snap-back: refused (cut, then
    the arc length, which here rises). The cohesive slab on 16 × 12 fell from 180.8 to 168 kN/m²
    so with its fracture energy flat to 10⁻⁷, while load control rises through 180 smoothly
    (docs/performance.md). Stand-ins: the dissipation constraint converges with λ falling, the
    arc length with λ rising, a ledger that books nothing (the same increment with damage booked
    is accepted, falling)."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonSettings

    def attempt(problem, u, lam, size, mode, *a, **k):
        return al.Attempt(True, u + 1e-3, lam - 0.01 if mode == "dissipation" else lam + 0.01, 3, [1e-10])

    booked = {"damage": 0.0}
    _path_stand_ins(monkeypatch, al, arc_attempt=attempt, arc_weights=lambda p: 1.0,
                    ledger_booked=lambda p: (booked["damage"], booked["damage"]))

    def on_step_end(problem, u, lam):  # commits the state: damage booked where asked
        booked["damage"] += damage_per_increment
        return False

    pb = _stand_in_problem(booked)
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         jump_area=None, jump_ratio=None, energy_tolerance=None, max_steps=1)
    for damage_per_increment, expected in ((0.0, 0.51), (1.0, 0.49)):
        booked["damage"] = 0.0
        st0 = al.PathState(mode="dissipation", size=0.1, arc_length=1.0, lam_peak=0.5, arc_length0=1.0)
        steps = list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.5, u0=np.zeros(2), state=st0,
                                   on_step_end=on_step_end))
        assert [s.load_factor for s in steps] == pytest.approx([expected])
        # the step's path state (what a checkpoint keeps) carries the last load with damage growth
        assert steps[0].state.lam_damaged == pytest.approx(0.49) if damage_per_increment else np.isnan(
            steps[0].state.lam_damaged)


def test_a_dissipation_increment_too_short_to_damage_is_grown_where_friction_acts(monkeypatch):
    """Where friction acts on a cohesive interface, a dissipation-controlled increment refused as
    friction's (FRICTION_REFUSED: λ falls, the ledger books less than half of Δτ as damage) may be
    too short to damage: the constraint, which takes unloading to be secant, is then met by the
    energy that the stick springs and the contact give back (the TRC slab on 16 × 12 crawled so on
    its snap-back at 305.90 kN/m²: Δτ = 10⁻¹¹-10⁻⁷ booked 2·10⁻¹¹-4·10⁻¹⁰, while 10⁻⁶-10⁻³ booked
    81-100 %). It is grown GROW_FACTOR times, at most GROW_REFUSED times, before it is cut; without
    friction, where growing does not help, or where the refused increment is already longer than
    the last accepted one (it went astray: the slab at 300.14 kN/m², Δτ = 8·10⁻⁵ to 143.7 kN/m²,
    grown to -305 and -132), the refusal goes on as before (cut, then the arc length, which here
    rises). Stand-ins: the dissipation constraint converges with λ falling, the
    arc length with λ rising, a ledger that books an increment's Δτ as damage from ``least`` on."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonSettings

    tried = []

    def attempt(problem, u, lam, size, mode, *a, **k):
        tried.append((mode, size))
        return al.Attempt(True, u + 1e-3, lam - 0.01 if mode == "dissipation" else lam + 0.01, 3, [1e-10])

    booked = {"damage": 0.0}
    acts = {"friction": True}
    _path_stand_ins(monkeypatch, al, arc_attempt=attempt, arc_weights=lambda p: 1.0,
                    ledger_booked=lambda p: (booked["damage"], booked["damage"]),
                    active_set_blocks=lambda p: ([], True), friction_acts=lambda blocks: acts["friction"])

    def on_step_end(problem, u, lam):  # commits the state: Δτ booked as damage from ``least`` on
        mode, size = tried[-1]
        booked["damage"] += size if mode == "dissipation" and size >= least else 1e-12
        return False

    pb = _stand_in_problem(booked)
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         jump_area=None, jump_ratio=None, energy_tolerance=None, max_steps=1)
    # the refused increments are 1e-3 per DOF long (1.41e-3); the last accepted one was 1 long, or
    # 1e-3 in the last case: a refused increment longer than that went astray and is cut at once
    for friction, least, expected, grown, last in ((True, 1e-3, 0.49, 3, 1.0), (False, 1e-3, 0.51, 0, 1.0),
                                                   (True, 1e3, 0.51, al.GROW_REFUSED, 1.0),
                                                   (True, 1e-3, 0.51, 0, 1e-3)):
        booked["damage"], acts["friction"], tried[:] = 0.0, friction, []
        st0 = al.PathState(mode="dissipation", size=1e-5, arc_length=last, lam_peak=0.5, arc_length0=1.0)
        steps = list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.5, u0=np.zeros(2), state=st0,
                                   on_step_end=on_step_end))
        assert [s.load_factor for s in steps] == pytest.approx([expected])
        sizes = [size for mode, size in tried if mode == "dissipation"]
        assert sizes[:grown + 1] == pytest.approx([1e-5 * al.GROW_FACTOR**k for k in range(grown + 1)])
        if expected < 0.5:  # accepted after growing
            assert len(sizes) == grown + 1 and tried[-1][0] == "dissipation"
        else:  # not grown further: cut from the refused size (1e-5), then the arc length
            assert all(size <= 1e-5 for size in sizes[grown + 1:]) and tried[-1][0] == "arc"


def test_an_arc_increment_that_unloads_elastically_from_a_debonding_state_is_refused(monkeypatch):
    """From a state whose increment damaged an interface, an arc-length increment in which the load
    and its conjugate displacement fall while the ledger books no damage has found the elastic
    unloading branch (both are equilibria there): refused, and the dissipation constraint, which
    demands damage, takes the increment. On CI (2 threads) the MMB on 100 elements, its crack past
    the load point, went so from λ = 0.6078 to 0.6007 (the work criterion's direction at an
    indefinite tangent) and on down, 'unloads without damage', while on 1 thread it reached λ = 1.
    From a state whose increment did not damage (here: none did), the same increment is
    accepted. Stand-ins: the arc length converges with λ and u falling, booking nothing; the
    dissipation constraint with λ rising, booking damage."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonSettings

    booked = {"damage": 0.0}
    tried = []

    def attempt(problem, u, lam, size, mode, *a, **k):
        tried.append(mode)
        if mode == "dissipation":
            booked["damage"] += 1.0
            return al.Attempt(True, u + 1e-3, lam + 0.01, 3, [1e-10])
        return al.Attempt(True, u - 1e-3, lam - 0.01, 3, [1e-10])

    _path_stand_ins(monkeypatch, al, arc_attempt=attempt, arc_weights=lambda p: 1.0,
                    ledger_booked=lambda p: (booked["damage"], booked["damage"]))
    pb = _stand_in_problem(booked)
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         jump_area=None, jump_ratio=None, energy_tolerance=None, max_steps=1)
    for lam_damaged, expected, modes in ((0.5, 0.51, ["arc", "dissipation"]), (float("nan"), 0.49, ["arc"])):
        booked["damage"], tried[:] = 0.0, []
        st0 = al.PathState(mode="arc", size=0.1, arc_length=0.1, lam_peak=0.6, arc_length0=1.0, changed=True,
                           lam_damaged=lam_damaged)
        steps = list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.5, u0=np.zeros(2), state=st0,
                                   on_step_end=lambda problem, u, lam: False))
        assert [s.load_factor for s in steps] == pytest.approx([expected]) and tried == modes
    # the check itself: the load and F̂·Δu fall, no damage booked since the start's ledger
    assert al.elastic_unloading(pb, -0.01, -np.ones(2), (0.0, booked["damage"]))
    assert not al.elastic_unloading(pb, -0.01, np.ones(2), (0.0, booked["damage"]))  # the displacement grows
    assert not al.elastic_unloading(pb, +0.01, -np.ones(2), (0.0, booked["damage"]))  # the load rises
    assert not al.elastic_unloading(pb, -0.01, -np.ones(2), (0.0, booked["damage"] - 1.0))  # damage booked
    assert not al.elastic_unloading(pb, -0.01, -np.ones(2), None)  # no cohesive ledger


def test_an_increment_past_lambda_end_that_load_control_cannot_reach_is_cut(monkeypatch):
    """An arc-length increment that passes λ_end ends with a load-controlled increment from its
    start onto λ_end. Where that has no equilibrium (the increment passed a snap-back on its way:
    the MITC9 plate on 12 × 12 went from 0.982 through the flap's debonding to 1.0245 in one
    increment, and its path ended there), the increment is cut until it ends below λ_end, from
    where λ_end is reached; at most END_CUTS times in a run, then the path ends beyond λ_end as
    before. Stand-ins: arc-length increments that raise λ by 0.3 × Δl (u = λ), load control onto
    λ_end that converges only from λ ≥ 0.95 (past the snap-back)."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonResult, NewtonSettings

    def attempt(problem, u, lam, size, *a, **k):
        return al.Attempt(True, np.full(2, lam + 0.3 * size), lam + 0.3 * size, 3, [1e-10])

    def newton_past(problem, u, lam, s):
        ok = u[0] >= reach
        return np.full(2, lam), NewtonResult(ok, 5, [1e-10 if ok else 1.0], message="" if ok else "diverged")

    _path_stand_ins(monkeypatch, al, arc_attempt=attempt, newton=newton_past, full_weights=lambda p: 1.0)
    pb = _stand_in_problem()
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=6,
                         jump_area=None, jump_ratio=None, dissipation=False, load_rescue=False)
    # from 0.9: Δl = 1 (to 1.2) and 0.5 (1.05) pass λ_end where load control cannot reach it, 0.25
    # ends at 0.975; from there load control reaches λ_end
    reach = 0.95
    lams = [st.load_factor for st in al.path_steps(pb, NewtonSettings(), ps, lam0=0.9, u0=np.full(2, 0.9))]
    assert lams == pytest.approx([0.975, 1.0])
    # where no start reaches it, END_CUTS cuts in all, then the path ends beyond λ_end
    reach = np.inf
    lams = [st.load_factor for st in al.path_steps(pb, NewtonSettings(), ps, lam0=0.9, u0=np.full(2, 0.9))]
    assert lams[-1] > 1.0 and all(x < 1.0 for x in lams[:-1])
    assert len(lams) <= al.END_CUTS + 1


def test_the_path_state_survives_a_checkpoint_whole():
    """Every field of PathState, set away from its default, comes back from the arrays a
    checkpoint stores (a field that did not would be reset by a restart), also through an npz
    file; a checkpoint without some of them (written by an earlier version) keeps their defaults."""
    import io
    import math
    from dataclasses import fields

    from layershell.solver.path_state import PathState

    st = PathState(mode="arc", size=2e-4, arc_length=3e-4, du_prev=np.arange(3.0), lam_peak=2.5,
                   dissipated=0.7, finished=True, arc_length0=1e-2, changed=True,
                   lam_damaged=2.25, recent=[(1e-4, 7), (1.2e-4, 9)], recent_mode="arc",
                   dissipation_max=0.3, recent_dissipation=[(1e-2, 8), (1.5e-2, 8)],
                   recent_lams=[0.5, 0.51], recent_dG=[1e-3, 2e-3], scales={"P": 3.0, "w.top": 0.25},
                   reaction=12.5, rescue="step 7: stuck", stretch_from=0.4, stretch_accepted=3,
                   stretch_block=0.45, end_cuts=2, implex_mode="load", implex_size=0.05)
    default = PathState()
    assert all(not (getattr(st, f.name) == getattr(default, f.name)
                    or (isinstance(getattr(default, f.name), float) and math.isnan(getattr(default, f.name))
                        and math.isnan(getattr(st, f.name))))
               for f in fields(st) if f.name != "du_prev")
    buf = io.BytesIO()
    np.savez(buf, **st.to_arrays())
    buf.seek(0)
    with np.load(buf, allow_pickle=False) as z:
        back = PathState.from_arrays({k: z[k] for k in z.files})
    for f in fields(st):
        if f.name == "du_prev":
            np.testing.assert_array_equal(back.du_prev, st.du_prev)
        else:
            assert getattr(back, f.name) == getattr(st, f.name), f.name
    # a copy does not share the lists, the dict or du_prev
    c = st.copy()
    c.recent.append((1.0, 1))
    c.scales["P"] = 9.0
    c.du_prev[0] = 5.0
    assert len(st.recent) == 2 and st.scales["P"] == 3.0 and st.du_prev[0] == 0.0
    # a checkpoint written before `recent` kept the last load-controlled increment on its own
    old = {k: v for k, v in st.to_arrays().items()
           if k not in ("path.recent", "path.recent_mode", "path.recent_lams", "path.scales", "path.rescue")}
    old.update({"path.last_increment": np.array(0.01), "path.last_iterations": np.array(6)})
    back = PathState.from_arrays(old)
    assert back.recent == [(0.01, 6)] and back.recent_mode == "load"
    assert back.recent_lams == [] and back.scales == {} and back.rescue == ""
    assert PathState.from_arrays({}) is None


def _arc_from_a_length(monkeypatch, al, least: float, **patches):
    """Stand-ins for the restart-length tests: arc-length increments that converge from a length
    of ``least`` on (λ + 0.01), dissipation-controlled ones that never converge, a Newton solve
    (the load-controlled rescue) that never converges. Returns the list of tried (mode, size)
    and the stand-in problem."""
    from layershell.solver.newton import NewtonResult

    tried = []

    def attempt(problem, u, lam, size, mode, *a, **k):
        tried.append((mode, size))
        ok = mode == "arc" and size >= least
        return al.Attempt(ok, u + 1e-3, lam + 0.01, 3, [1e-10 if ok else 1.0], message="" if ok else "stand-in")

    def never(problem, u, lam, s):
        return u, NewtonResult(False, 2, [1.0], message="stand-in: diverged")

    booked = {"damage": 0.0}
    _path_stand_ins(monkeypatch, al, arc_attempt=attempt, arc_weights=lambda p: 1.0, newton=never,
                    ledger_booked=lambda p: (booked["damage"], booked["damage"]), **patches)
    return tried, _stand_in_problem(booked)


def test_the_arc_length_takes_over_a_failed_dissipation_increment_from_a_length_it_can_cut(monkeypatch):
    """Where the dissipation constraint fails at all its sizes, the arc length takes the increment
    over - from at least ARC_AFTER_DISSIPATION of its first length, not from the length of the last
    accepted increment: after a crawl of short dissipation increments that is the smallest the arc
    length may take, and it got one try before the run stopped (the cohesive TRC slab by arc length
    on 8 × 6 stopped so at 266.28 kN/m²: the arc length at 4.5·10⁻⁶ failed, where 3·10⁻⁵ to 10⁻³
    from the same state converge). Stand-ins: dissipation-controlled increments that never
    converge, arc-length increments that converge from a length of 0.05 on (λ + 0.01), a Newton
    solve (the load-controlled rescue) that never converges."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import ConvergenceError, NewtonSettings

    tried, pb = _arc_from_a_length(monkeypatch, al, 0.05)
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0, max_cuts=2,
                         jump_area=None, jump_ratio=None, energy_tolerance=None, max_steps=1)
    # the last accepted increment was as short as the arc length may be (1/1000 of the first)
    st0 = al.PathState(mode="dissipation", size=1e-6, arc_length=1e-3, lam_peak=0.6, arc_length0=1.0)
    steps = list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.5, u0=np.zeros(2), state=st0,
                               on_step_end=lambda problem, u, lam: False))
    assert [s.load_factor for s in steps] == pytest.approx([0.51])
    modes = [m for m, _ in tried]
    assert modes == ["dissipation"] * 3 + ["arc"]  # three dissipation sizes (max_cuts = 2), then the arc length
    assert tried[-1][1] == pytest.approx(al.ARC_AFTER_DISSIPATION)
    assert al.arc_length_restart(0.2, 1.0) == 0.2  # a longer last increment: its own length
    assert al.arc_length_restart(1e-3, 1.0, 0.01) == 0.01  # never above a user's arc_length_max
    # from a length below 0.05 the arc length's halvings cannot reach one that converges: the run
    # stops (the rescue by load control fails as well) after trying the arc length at its restart length
    tried[:] = []
    monkeypatch.setattr(al, "ARC_AFTER_DISSIPATION", 0.04)
    st0 = al.PathState(mode="dissipation", size=1e-6, arc_length=1e-3, lam_peak=0.6, arc_length0=1.0)
    with pytest.raises(ConvergenceError):
        list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.5, u0=np.zeros(2), state=st0,
                           on_step_end=lambda problem, u, lam: False))
    assert ("arc", pytest.approx(0.04)) in tried and all(size <= 0.04 for m, size in tried if m == "arc")


def test_the_arc_length_goes_back_to_an_increment_from_a_length_it_can_cut(monkeypatch):
    """An arc-length increment that fails hands the increment to the dissipation constraint;
    where that fails three times, the arc length takes it back, cut - from at least
    arc_length_restart (1/16 of its first length), as where the dissipation constraint fails
    through all its cuts (test above). From the length of the last accepted increment, the
    smallest after a crawl of dissipation increments of Δτ ~ 10⁻⁸, it could not be cut and the
    run stopped: the cohesive slab on 8 × 6 at 258.63 kN/m² on its plateau (restarted there with
    this rule it goes on). Stand-ins: arc-length increments that converge from a length of 0.03
    on, dissipation-controlled ones that never converge, a rescue that never converges."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonSettings

    tried, pb = _arc_from_a_length(monkeypatch, al, 0.03, _first_dissipation=lambda p, u, lam, dl: 1e-6)
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.25, arc_length=1.0,
                         jump_area=None, jump_ratio=None, energy_tolerance=None, max_steps=1)
    # the last accepted increment was as short as the arc length may be (1/1000 of the first)
    st0 = al.PathState(mode="arc", size=1e-3, arc_length=1e-3, lam_peak=0.6, arc_length0=1.0)
    steps = list(al.path_steps(pb, NewtonSettings(), ps, lam0=0.5, u0=np.zeros(2), state=st0,
                               on_step_end=lambda problem, u, lam: False))
    assert [s.load_factor for s in steps] == pytest.approx([0.51])
    assert [m for m, _ in tried] == ["arc"] + ["dissipation"] * 4 + ["arc"]
    assert tried[-1][1] == pytest.approx(al.ARC_AFTER_DISSIPATION / 2)  # taken back, cut once


def test_a_restart_from_any_increments_state_continues_a_crawl_and_its_rescue(monkeypatch):
    """path_steps restarted from the PathState of any increment (through its checkpoint arrays)
    takes the uninterrupted run's increments, here through a crawl, the load-controlled rescue
    it triggers and the stretch after it (a restart once forgot the crawl's λ history, the rescue
    decided after the step was kept and the stretch's bookkeeping). Stand-ins: arc-length
    increments of Δλ = 0.3 up to λ = 0.5 and of 10⁻⁹ beyond (the crawl; each dissipates its Δλ),
    a Newton solve that converges at every λ."""
    from layershell.solver import arclength as al
    from layershell.solver.newton import NewtonResult, NewtonSettings
    from layershell.solver.path_state import PathState

    def creeping(problem, u, lam, size, *a, **k):
        dlam = 0.3 if lam < 0.5 else 1e-9
        return al.Attempt(True, u + dlam, lam + dlam, 2, [1e-10])

    def newton_anywhere(problem, u, lam, s):
        return np.full(2, lam), NewtonResult(True, 2, [1e-10])

    _path_stand_ins(monkeypatch, al, arc_attempt=creeping, newton=newton_anywhere,
                    dissipation_increment=lambda problem, u, lam, du, dlam, *a: abs(dlam),
                    full_weights=lambda problem: np.ones(2))
    ps = al.PathSettings(control="arc_length", lambda_end=1.0, increment=0.125, arc_length=1.0, stall_increments=3,
                         jump_area=None, jump_ratio=None, dissipation=False)
    full = [(r.step, r.load_factor, r.u, r.state) for r in al.path_steps(_stand_in_problem(), NewtonSettings(), ps,
                                                                           u0=np.zeros(2))]
    lams = [lam for _, lam, _, _ in full]
    modes = [st.mode for _, _, _, st in full]
    assert "load" in modes and lams[-1] == pytest.approx(1.0)  # the rescue and its stretch reach λ_end
    assert 3 <= modes.index("load") < len(full) - 1
    for step, lam, u, st in full[:-1]:
        again = [r.load_factor for r in al.path_steps(_stand_in_problem(), NewtonSettings(), ps, u0=u, lam0=lam,
                                                      step0=step, state=PathState.from_arrays(st.to_arrays()))]
        assert again == pytest.approx(lams[step:], rel=1e-12), step
