"""Cohesive interface block in structures (issue 13): penalty stiffness against the bonded
model, consistent tangent of the assembled block, energy balance, bad input, nodal vs Gauss
integration."""
import numpy as np
import pytest

from helpers import example_spec, run_example
from layershell.io.build import InputError, build, parse
from layershell.runner import run
from layershell.solver.problem import Problem

STRIP = """
[model]
title = "two-layer strip"
units = "N, mm"
nonlinear = {nonlinear}
[mesh]
type = "rectangle"
lx = 100.0
ly = 20.0
nx = {nx}
ny = 1
normal = "+z"
[materials.m]
type = "isotropic"
E = 30000.0
nu = 0.2
[[layers]]
name = "lower"
material = "m"
thickness = 5.0
directors = 3
[[layers]]
name = "upper"
material = "m"
thickness = 3.0
directors = 3
[[supports]]
type = "fix"
where = "near(x, 0)"
layer = "lower"
directors = "all"
[[supports]]
type = "fix"
where = "near(x, 0)"
layer = "upper"
directors = "all"
[[loads]]
type = "edge"
where = "near(x, 100)"
direction = [0, 0, -1]
distribution = {load}
[steps]
n = {steps}
[[probes]]
name = "w_tip"
quantity = "displacement"
where = "near(x, 100)"
component = "z"
reduce = "min"
scale = -1.0
"""

COHESIVE = """
[[interfaces]]
layer = "upper"
law = "cohesive"
sigma_max = {smax}
tau_max = {tmax}
G_Ic = 0.5
G_IIc = 1.0
{extra}
"""


def strip(nonlinear="false", nx=4, load="1.0", steps=1, cohesive=None, **kw):
    text = STRIP.format(nonlinear=nonlinear, nx=nx, load=load, steps=steps)
    if cohesive is not None:
        text += COHESIVE.format(**{"smax": 1e6, "tmax": 1e6, "extra": "", **cohesive})
    return build(parse(text, "strip"))


def test_default_penalty_softens_bonded_strip_less_than_1_percent():
    """A cantilever two-layer strip whose layers are bonded (constraint) and the same strip with
    an undamaged cohesive interface with the default K0 = 50 E3/H: tip deflections within 1 %
    (the bending stiffness depends on the shear coupling of the layers through K0)."""
    bonded = run(strip(), None, write_vtu=False).summary["probes"]["w_tip"]
    coh = run(strip(cohesive={}), None, write_vtu=False).summary["probes"]["w_tip"]
    assert coh > bonded  # an extra compliance
    assert (coh - bonded) / bonded < 0.01
    # the comparison can fail: a penalty far below the default (bypassing the input check) softens it
    import dataclasses

    spec = strip(cohesive={})
    (k, law), = spec.model.interface_laws.items()
    spec.model.interface_laws[k] = dataclasses.replace(law, K0=1.0)
    soft = run(spec, None, write_vtu=False).summary["probes"]["w_tip"]
    assert (soft - bonded) / bonded > 0.01


def test_bad_input_names_the_field():
    with pytest.raises(InputError, match=r"fracture energies G_IIc"):
        build(parse(STRIP.format(nonlinear="false", nx=2, load="1.0", steps=1)
                    + '[[interfaces]]\nlayer = "upper"\nlaw = "cohesive"\nsigma_max = 1.0\ntau_max = 1.0\nG_Ic = 0.5\n',
                    "strip"))
    with pytest.raises(InputError, match=r"G_Ic.*must be a positive"):
        build(parse(
            STRIP.format(nonlinear="false", nx=2, load="1.0", steps=1)
            + '[[interfaces]]\nlayer = "upper"\nlaw = "cohesive"\nsigma_max = 1.0\ntau_max = 1.0\nG_Ic = 0.0\n'
              'G_IIc = 1.0\n', "strip"))
    with pytest.raises(InputError, match=r"K0.*softens the bonded structure"):
        strip(cohesive={"extra": "K0 = 100.0"})


def _damaged_problem(rule, extra=""):
    spec = strip(nonlinear="true", nx=2, cohesive={"smax": 1.0, "tmax": 2.0, "extra": f'rule = "{rule}"\n{extra}'})
    pb = Problem.build(spec.model)
    rng = np.random.default_rng(3)
    blk = pb.extra_blocks[0]
    # a state with every kind of point: undamaged, softening (loading), unloading, compressed
    blk.d_old = rng.uniform(0.0, 0.6, blk.d_old.shape) * (rng.random(blk.d_old.shape) < 0.5)
    blk.dv_old = 0.8 * blk.d_old  # the viscous damage lags (used only with a viscosity)
    blk.lam_old, blk.lam_trial = 0.5, 0.6
    ur = rng.normal(size=pb.op.n_red)
    # scaled so that the typical separation is a few onset separations λ0 = σ_max / K0
    lam = np.linalg.norm(blk.separation(pb.op.T @ ur), axis=-1)
    ur *= 3.0 * (1.0 / blk.K) / np.median(lam)
    return pb, blk, ur


@pytest.mark.parametrize("rule,friction,viscosity", [("lobatto", False, 0), ("gauss", False, 0),
                                                      ("lobatto", True, 0), ("lobatto", True, 0.05)])
def test_block_tangent_against_finite_differences(rule, friction, viscosity):
    """The assembled reduced tangent of a strip with a partly damaged cohesive interface in a
    state with loading, softening, unloading and compressed points equals central differences
    of the internal force."""
    from helpers import fd_reduced_tangent

    pb, blk, ur = _damaged_problem(rule, f"viscosity = {viscosity}")
    if friction:  # slip limits on the damaged share, some points sticking, some sliding, with the
        # stick penalty per point (cohesive.stick_penalty)
        from layershell.cohesive import stick_penalty

        rng = np.random.default_rng(5)
        blk.contact.cap = rng.uniform(0.0, 0.05, blk.d_old.shape)
        blk.contact.alpha_T = stick_penalty(blk.K, blk.contact.cap, blk.law.tau_max)
        assert np.ptp(blk.contact.alpha_T) > 0
        blk.contact.g_p = rng.normal(size=blk.contact.g_p.shape) * 1e-6
    delta = blk.separation(pb.op.T @ ur)
    _, _, d, _ = blk.point_state(pb.op.T @ ur)
    assert (d > blk.d_old).any() and (d == blk.d_old).any()  # damage grows at some points only
    assert (np.einsum("eqi,eqi->eq", delta, blk.contact.A3) < 0).any()
    Kr, Kfd = fd_reduced_tangent(pb, ur, h=1e-5 * np.abs(ur).max())
    scale = np.abs(Kr).max()
    np.testing.assert_allclose(Kr, Kfd, atol=1e-7 * scale)



def test_energy_balance_with_damage():
    """External work (path integral of λF·du) = strain energy of the layers (path integral of
    their internal forces) + elastic energy of the cohesive springs + fracture dissipation
    (closed form of the bilinear law) + friction, within 1 %, along a loading path on which the
    interface damages (first damage at λ = 0.7 with the MITC9 element, 0.6 with the fully
    integrated one, whose strip is stiffer in shear; a fifth of the work dissipated)."""
    spec = strip(nonlinear="false", nx=6, load="0.5", steps=10, cohesive={"smax": 0.3, "tmax": 0.6})
    s = run(spec, None, write_vtu=False).summary
    assert s["converged"] and 0.0 < s["first_damage_load_factor"] < 1.0
    e = s["energy"]
    assert e["dissipated_fracture"] > 0.1 * e["external_work"]
    stored = e["strain_energy"] + e["interface_elastic_energy"]
    dissipated = e["dissipated_fracture"] + e["dissipated_friction"] + e["dissipated_viscous"]
    assert abs(e["external_work"] - stored - dissipated) < 0.01 * e["external_work"]
    assert s["peak_load_factor"] == 1.0


def test_state_round_trip_for_restart():
    """The interface state (damage, friction, energies) saved for checkpoints and step cutting is
    restored exactly on a freshly built problem."""
    spec = strip(nonlinear="false", nx=2, load="0.5", steps=1, cohesive={"smax": 0.3, "tmax": 0.6})
    pb = Problem.build(spec.model)
    ctl = pb.interfaces
    rng = np.random.default_rng(0)
    u = rng.normal(size=pb.dm.n_full) * 1e-4
    ctl.update(pb, u, 0.5)
    state = ctl.state(pb)
    pb2 = Problem.build(spec.model)
    pb2.interfaces.restore(pb2, state)
    r1, r2 = ctl.runs[0], pb2.interfaces.runs[0]
    assert np.array_equal(r1.block.d_old, r2.block.d_old) and r1.block.d_old.max() > 0
    assert np.array_equal(r1.energy, r2.energy) and np.array_equal(ctl.energy, pb2.interfaces.energy)
    assert np.array_equal(r1.fracture, r2.fracture) and r1.fracture.max() > 0  # per point (the VTU's)
    assert float(r2.first_damage) == 0.5
    f1, _ = pb.assembler.evaluate(u, tangent=False)
    f2, _ = pb2.assembler.evaluate(u, tangent=False)
    np.testing.assert_array_equal(f1, f2)


def test_viscous_regularisation_reports_its_dissipation():
    """With a viscosity the damage lags the rate-independent one (less fracture energy at a given
    load), the extra dissipation is reported as dissipated_viscous (> 0), and the energy balance
    still closes within 1 %; without it dissipated_viscous is 0."""
    plain = run(strip(nonlinear="false", nx=6, load="0.5", steps=10, cohesive={"smax": 0.3, "tmax": 0.6}),
                None, write_vtu=False).summary
    visc = run(strip(nonlinear="false", nx=6, load="0.5", steps=10,
                     cohesive={"smax": 0.3, "tmax": 0.6, "extra": "viscosity = 0.1"}), None, write_vtu=False).summary
    assert plain["energy"]["dissipated_viscous"] == 0.0
    e = visc["energy"]
    assert visc["converged"] and e["dissipated_viscous"] > 0
    assert e["dissipated_fracture"] < plain["energy"]["dissipated_fracture"]
    assert abs(e["balance_error"]) < 0.01


def test_process_zone_warning():
    """The process zone (layershell.process_zone) against the node spacing, checked when damage
    starts with the mode of the damaging points. Strip (E = 30 GPa, layers 5 and 3 mm, strengths
    10 N/mm², G_IIc = 1 N/mm) bent as a cantilever: damage starts at the clamp in shear
    (G_II/G = 1.00) and the mode-II zone is 26.2 mm (shear lag, tan(λl) = sqrt(r)); with 2
    elements along the strip the node spacing is 10 mm (half the 20 mm width, the shorter
    side): 2.62 spacings, a warning naming the interface and the mode; with 16 elements
    (h = 3.125 mm) none."""
    import warnings

    from layershell.runner import CohesiveWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        bad = run(strip(nx=2, load="12.0", steps=6, cohesive={"smax": 10.0, "tmax": 10.0}), None,
                  write_vtu=False).summary
    zone = [w for w in bad["warnings"] if "process zone" in w]
    assert bad["first_damage_load_factor"] == 0.5
    assert len(zone) == 1 and "lower/upper" in zone[0] and "G_II/G = 1.00" in zone[0]
    assert "estimated at 26.17" in zone[0] and "2.62 node spacings" in zone[0]
    assert any(issubclass(c.category, CohesiveWarning) for c in caught)  # on the console too
    ok = run(strip(nx=16, load="12.0", steps=6, cohesive={"smax": 10.0, "tmax": 10.0}), None,
             write_vtu=False).summary
    assert ok["first_damage_load_factor"] == 0.5
    assert not [w for w in ok.get("warnings", []) if "process zone" in w]


def test_set_violation_is_the_traction_change_of_the_actual_sets():
    """The violation measure of a frozen active set (the criterion under which a cycling loop may
    accept a state) equals, independently computed, the largest change of the traction between
    the frozen response and the response with the actual sets, per point over its strength
    K λ0(B); and it is 0 where the sets are those of the state."""
    from layershell.cohesive import onset, point_response, separation_measures

    pb, blk, ur = _damaged_problem("lobatto")
    u0 = pb.op.T @ ur
    blk.freeze(u0)
    assert blk.set_violation(u0) == 0.0 and not blk.set_changed(u0)
    rng = np.random.default_rng(11)
    u1 = u0 + pb.op.T @ (0.3 * rng.normal(size=ur.shape) * np.abs(ur).max())
    n = blk.contact.A3
    delta = blk.separation(u1)
    tf, _, _ = point_response(delta, n, blk.d_old, blk.K, blk.law, tangent=False, frozen=blk.frozen)
    ta, _, _ = point_response(delta, n, blk.d_old, blk.K, blk.law, tangent=False)
    _, _, _, B, _, _ = separation_measures(delta, n)
    l0, _ = onset(B, blk.K, blk.law)
    expected = (np.linalg.norm(tf - ta, axis=-1) / (blk.K * l0)).max()
    v = blk.set_violation(u1)
    assert blk.set_changed(u1) and expected > 1e-3  # points changed their state
    assert v == pytest.approx(expected, rel=1e-9)
    blk.unfreeze()


def test_frozen_opening_point_jumps_at_closure_and_is_released():
    """Within frozen sets an opening, loading point keeps the softening line t = K λ0 (λf - λ)/
    (λf - λ0) along δ/|δ|: its normal traction reverses across δ_n = 0, from +K λ0 (λf - ε)/
    (λf - λ0) at δ_n = ε to the negative at -ε (ε = λ0/100 here; the bilinear law's parameters
    computed here), within a band of about 10⁻³ λ0 where the continuation's damage is bounded
    at -10³ - practically a jump, which Newton iterates crossing it cannot pass (the
    force-loaded DCB's failed arc-length increments). Closed (out of both sets) the point's
    traction K δ_n is continuous and monotone there. ``release_closed`` takes exactly the
    opening, loading points that an iterate closes out of both sets and leaves every other
    point as it was."""
    from layershell.cohesive import onset, point_response

    pb, blk, ur = _damaged_problem("lobatto")
    K, law = blk.K, blk.law
    n = np.array([[0.0, 0.0, 1.0]])
    d_old = np.array([0.3])
    l0 = float(onset(np.zeros(1), K, law)[0][0])
    lf = 2.0 * law.G_Ic / (K * l0)
    eps = 0.01 * l0
    jump = 2.0 * K * l0 * (lf - eps) / (lf - l0)
    frozen_open = (np.array([True]), np.array([True]))
    tp, _, _ = point_response(np.array([[0.0, 0.0, eps]]), n, d_old, K, law, tangent=False, frozen=frozen_open)
    tm, _, _ = point_response(np.array([[0.0, 0.0, -eps]]), n, d_old, K, law, tangent=False, frozen=frozen_open)
    assert tp[0, 2] - tm[0, 2] == pytest.approx(jump, rel=1e-6)
    closed = (np.array([False]), np.array([False]))
    tp, _, _ = point_response(np.array([[0.0, 0.0, eps]]), n, d_old, K, law, tangent=False, frozen=closed)
    tm, _, _ = point_response(np.array([[0.0, 0.0, -eps]]), n, d_old, K, law, tangent=False, frozen=closed)
    assert tp[0, 2] - tm[0, 2] == pytest.approx(2.0 * K * eps, rel=1e-9)

    u0 = pb.op.T @ ur
    blk.freeze(u0)
    tension, loading = (a.copy() for a in blk.frozen)
    assert blk.release_closed(u0) == 0  # nothing frozen opening is closed at the freezing state
    assert all(np.array_equal(a, b) for a, b in zip(blk.frozen, (tension, loading)))
    u1 = -u0  # every separation reversed: the opening points close
    crossed = tension & loading & (blk.gap(u1) < 0)
    assert crossed.sum() >= 2
    assert blk.release_closed(u1) == crossed.sum()
    assert np.array_equal(blk.frozen[0], tension & ~crossed) and np.array_equal(blk.frozen[1], loading & ~crossed)
    assert blk.release_closed(u1) == 0  # done: the closed points stay closed within the solve
    blk.unfreeze()
    assert blk.release_closed(u1) == 0  # nothing frozen


def test_partial_symmetry_check_equals_the_full_pass():
    """A linear model's K_r differs from the layers' constant tangent only where the cohesive
    block writes, so the solver's symmetry check reads only the pairs there
    (assembly._PartialSymmetry); its (largest mirror difference, largest entry) equal the full
    pass over every entry - in an undamaged state and with growing mixed-mode damage, where K_r
    is not symmetric - and so does the solver's decision."""
    from layershell import _assembly_jit as J
    from layershell.solver.linear import is_symmetric

    spec = strip(nonlinear="false", nx=2, cohesive={"smax": 1.0, "tmax": 2.0})
    pb = Problem.build(spec.model)
    blk = pb.extra_blocks[0]
    rng = np.random.default_rng(5)
    ur = rng.normal(size=pb.op.n_red)
    lam = np.linalg.norm(blk.separation(pb.op.T @ ur), axis=-1)
    decisions = []
    for scale, d_old in ((1e-3, 0.0), (3.0, 0.2)):  # elastic; softening and unloading points
        blk.d_old = np.full(blk.d_old.shape, d_old)
        u = pb.op.T @ (ur * scale / (blk.K * np.median(lam)))
        _, K = pb.assembler.evaluate_reduced(u, pb.op)
        assert K.partial_symmetry is not None and K.partial_symmetry.upper.size < K.scatter.upper_pos.size
        rs = K.scatter
        full = J.mirror_difference_and_max(K.data, rs.upper_pos, rs.mirror_pos)
        assert K.symmetry_check() == (float(full[0]), float(full[1]))
        decisions.append(is_symmetric(K))
        assert is_symmetric(K) == (full[0] <= 1e-12 * full[1])
    assert decisions == [True, False]


def test_active_set_loop_accepts_a_cycling_state_only_within_the_tolerance():
    """ActiveSetLoop: a converged state with sets violated by less than the tolerance is
    accepted (and counted) when the loop fails; one violated by more is not."""
    from types import SimpleNamespace

    from layershell.solver.newton import ActiveSetLoop

    class Fake:
        CONSISTENCY_TOL = 1e-3
        smooth_when_frozen = True
        v = 0.0

        def set_violation(self, u):
            return self.v

    for v, accepted in ((5e-4, True), (2e-3, False)):
        b = Fake()
        loop = ActiveSetLoop([b], True)
        pb = SimpleNamespace(accepted_sets=0, accepted_violation=0.0)
        b.v = 1e-2
        assert not loop.consistent(None, "far")
        b.v = v
        assert not loop.consistent(None, "near")
        b.v = 0.5
        assert not loop.consistent(None, "farther")
        assert loop.accept(pb) == ("near" if accepted else None)
        assert pb.accepted_sets == int(accepted) and pb.accepted_violation == (v if accepted else 0.0)
        b.v = 0.0
        assert loop.consistent(None, "exact")


def test_early_refreeze_only_near_the_solution_and_beyond_the_consistency_tolerance():
    """newton.early_refreeze: a frozen solve ends early only where its residual lies above the
    tolerance (else it has converged) and within EARLY_REFREEZE times it (else it is not near its
    solution), and the sets are violated by more than the consistency tolerance (a smaller
    violation must converge, so that ActiveSetLoop can accept it where it cycles); a block without
    a violation measure counts any set change."""
    from layershell.solver.newton import EARLY_REFREEZE, early_refreeze

    class Measured:
        CONSISTENCY_TOL = 1e-3

        def __init__(self, v):
            self.v = v

        def set_violation(self, u):
            return self.v

    class Changed:
        def __init__(self, changed):
            self.changed = changed

        def set_changed(self, u):
            return self.changed

    tol = 1e-6
    inside = 10.0 * tol
    assert EARLY_REFREEZE > 10.0
    assert early_refreeze([Measured(0.1)], None, inside, tol)
    assert not early_refreeze([Measured(0.1)], None, 0.5 * tol, tol)  # converged
    assert not early_refreeze([Measured(0.1)], None, 2.0 * EARLY_REFREEZE * tol, tol)  # far from it
    assert not early_refreeze([Measured(5e-4)], None, inside, tol)  # within the consistency tolerance
    assert not early_refreeze([Measured(0.0)], None, inside, tol)
    assert early_refreeze([Measured(0.0), Changed(True)], None, inside, tol)
    assert not early_refreeze([Changed(False)], None, inside, tol)
    assert not early_refreeze([], None, inside, tol) and not early_refreeze(None, None, inside, tol)


def test_early_refreeze_only_on_linear_models_without_acting_friction():
    """newton.early_blocks: the frozen blocks may end their solves early on a linear model
    whose friction on the damaged share acts nowhere (a slip limit of 0 at every point); not on a
    geometrically nonlinear model, not where friction acts at one point (docs/performance.md: the
    lap shear with friction and the nonlinear §5.1 plate took other paths)."""
    from types import SimpleNamespace

    from layershell.solver.newton import early_blocks

    def problem(nonlinear):
        return SimpleNamespace(model=SimpleNamespace(nonlinear=nonlinear))

    def block(cap):
        return SimpleNamespace(contact=SimpleNamespace(cap=np.array(cap, float)))

    quiet = [block([0.0, 0.0])]
    assert early_blocks(problem(False), quiet) is quiet
    assert early_blocks(problem(True), quiet) is None
    assert early_blocks(problem(False), [block([0.0, 0.3])]) is None
    assert early_blocks(problem(False), []) is None


def test_early_refreeze_changes_the_cost_not_the_answer(monkeypatch):
    """The DCB (150 elements) opened by prescribed displacements in two fixed steps to its peak
    and past it (δ = 4.5 and 5 mm, the crack growing by several node rows in the second): with
    the early re-freeze of the active-set loop (EARLY_REFREEZE) and without it (a factor of 1
    switches it off) every step ends at the same state - the reaction force to 1e-7 (measured
    2e-13) - and the early exits save iterations (measured 72 → 71; on the whole
    displacement-controlled DCB of 200 elements 605 → 521, docs/performance.md)."""
    import layershell.solver.newton as N
    from test_dcb import DISPLACEMENT_CONTROL

    calls = []
    real = N.early_refreeze

    def counted(*a):
        out = real(*a)
        calls.append(out)
        return out

    monkeypatch.setattr(N, "early_refreeze", counted)
    runs = {}
    for factor in (1.0, N.EARLY_REFREEZE):
        monkeypatch.setattr(N, "EARLY_REFREEZE", factor)
        calls.clear()
        r = run_example("dcb_cohesive", {**DISPLACEMENT_CONTROL,
                                         "factors = [0.01, 0.02, 0.05,": "factors = [0.45, 0.5] #"})
        assert r.converged
        runs[factor] = ([st["probes"]["P"] for st in r.summary["steps"]],
                        sum(st["iterations"] for st in r.summary["steps"]), sum(calls))
    (P1, it1, early1), (P2, it2, early2) = runs.values()
    assert early1 == 0 and early2 > 0
    assert P2 == pytest.approx(P1, rel=1e-7)
    assert it2 < it1


def test_round_off_floor_is_accepted_whatever_the_step_size():
    """The round-off floor test of Newton (solver/newton.py, at_round_off_floor) measures the
    energy of a correction against the larger of the first correction's energy and the work
    f·u of the state. Against the first correction alone it depended on the step size: a tiny
    (bisected) step has a tiny first correction, and the cohesive §5.1 plate (MITC9, 12 × 12)
    stalled at 1.1·10⁻⁸ > 10⁻⁸ with |Δu·r| ~ 10⁻²³ through all its bisections. Here only the
    energy test may end the iterations (residual and displacement tolerances off): a full step
    and a step of 10⁻⁹ of the load both stop at the floor within a few iterations; with the
    first correction as the scale the small step would run to max_iterations."""
    from dataclasses import replace

    from layershell.solver.newton import NewtonSettings, newton_fixed_set

    spec = strip(nonlinear="true", nx=4, load="1.0", cohesive={})
    pb = Problem.build(spec.model)
    s = replace(NewtonSettings(), tol_residual=0.0, tol_displacement=0.0, line_search=False)
    u1, r1 = newton_fixed_set(pb, np.zeros(pb.dm.n_full), 1.0, s)
    assert r1.converged and "floor" in r1.message and r1.iterations <= 8
    u2, r2 = newton_fixed_set(pb, u1, 1.0 + 1e-9, s)
    assert r2.converged and "floor" in r2.message and r2.iterations <= 8
    assert np.abs(u2 - u1).max() == pytest.approx(1e-9 * np.abs(u1).max(), rel=0.5)  # the step's response


def test_arc_length_iterations_end_at_the_round_off_floor():
    """The arc-length iterations (solver/arclength.py) share Newton's round-off floor test: with
    only the energy test on (residual and displacement tolerances off) an increment converges
    at the floor within a few iterations. Without it the cohesive §5.1 plate with MITC9 (12 × 12,
    `control = "arc_length"`) stalled at 1.1·10⁻⁸ of the load in its first increment and was cut
    nine times (residuals 9.6·10⁻⁹ ... 9.7·10⁻⁹ against a tolerance of 8·10⁻⁹)."""
    from dataclasses import replace

    from layershell.solver.arclength import PathSettings, _first_arc_length, arc_attempt
    from layershell.solver.newton import NewtonSettings

    spec = strip(nonlinear="true", nx=4, load="1.0", cohesive={})
    pb = Problem.build(spec.model)
    s = replace(NewtonSettings(), tol_residual=0.0, tol_displacement=0.0, line_search=False)
    ps = PathSettings(control="arc_length", lambda_end=1.0, increment=0.5)
    u0 = np.zeros(pb.dm.n_full)
    size = _first_arc_length(pb, u0, s, ps)
    att = arc_attempt(pb, u0, 0.0, size, "arc", None, s, ps, 1.0)
    assert att.converged and "floor" in att.message and att.iterations <= 8
    assert att.lam == pytest.approx(0.5, rel=1e-3)  # the predictor's Δλ of the first increment
    # the next increment (same direction) too
    att2 = arc_attempt(pb, att.u, att.lam, size, "arc", att.u - u0, s, ps, 1.0)
    assert att2.converged and "floor" in att2.message and att2.lam > att.lam


def test_stabilisation_switches_on_at_the_converged_state():
    """InterfaceController.stabilize (the automatic viscous stabilisation of a load step without
    equilibrium, solver/newton.py ``NewtonSettings.stabilize``): at the converged state it leaves
    the internal force unchanged (the acting damage starts at the rate-independent one), beyond
    it the damage lags the rate-independent damage, and the checkpoint/step-cut state carries the
    viscosity and where it was switched on."""
    spec = strip(nonlinear="false", nx=2, load="0.5", steps=1, cohesive={"smax": 0.3, "tmax": 0.6})
    pb = Problem.build(spec.model)
    ctl, blk = pb.interfaces, pb.extra_blocks[0]
    rng = np.random.default_rng(0)
    u = rng.normal(size=pb.dm.n_full) * 1e-4
    ctl.update(pb, u, 0.5)
    assert blk.d_old.max() > 0 and ctl.stabilized is None
    pb.external(0.5)
    f0, _ = pb.assembler.evaluate(u, tangent=False)
    assert ctl.stabilize(0.01, 0.5) and blk.law.viscosity == 0.01 == ctl.runs[0].law.viscosity
    f1, _ = pb.assembler.evaluate(u, tangent=False)
    np.testing.assert_allclose(f1, f0, rtol=0, atol=1e-12 * np.abs(f0).max())
    assert not ctl.stabilize(0.02, 0.5)  # once
    u2 = 1.5 * u
    pb.external(0.51)  # Δλ = η: the damage goes half way to the rate-independent one
    _, _, d, _ = blk.point_state(u2)
    grow = blk.last_inviscid > blk.d_old + 1e-6
    assert grow.any()
    np.testing.assert_allclose(d[grow], 0.5 * (blk.dv_old + blk.last_inviscid)[grow], rtol=1e-12)
    state = ctl.state(pb)
    pb2 = Problem.build(spec.model)
    pb2.interfaces.restore(pb2, state)
    assert pb2.extra_blocks[0].law.viscosity == 0.01 and pb2.interfaces.stabilized == {"load_factor": 0.5, "viscosity": 0.01}


class _StandInInterfaces:
    """The part of InterfaceController that the stabilisation in load_steps/path_steps uses:
    one unit of fracture energy per call of ``dissipation``, and ``viscous_per_step`` of viscous
    energy once stabilised."""

    stabilized = None

    def __init__(self, viscous_per_step: float):
        self.viscous_per_step, self.calls, self.visc = viscous_per_step, 0, 0.0

    def stabilize(self, eta, lam):
        self.stabilized = {"load_factor": lam, "viscosity": eta}
        return True

    def cohesive(self):
        return True

    def dissipation(self):  # (fracture, viscous) so far
        self.calls += 1
        self.visc += self.viscous_per_step if self.stabilized else 0.0
        return float(self.calls), self.visc


def _stand_in_problem(viscous_per_step: float = 0.01):
    from types import SimpleNamespace

    return SimpleNamespace(interfaces=_StandInInterfaces(viscous_per_step), dm=SimpleNamespace(n_full=2),
                           F_scaled=np.zeros(2), begin_step=lambda: None, start_inertia=None)


def _newton_without_equilibrium_past_half(problem, u, lam, s):
    """Newton stand-in: no equilibrium beyond λ = 0.5 until the interfaces are stabilised."""
    from layershell.solver.newton import NewtonResult

    ok = lam <= 0.5 + 1e-12 or problem.interfaces.stabilized is not None
    return u + 1.0, NewtonResult(ok, 2, [1e-10 if ok else 1e-3], message="" if ok else "diverged")


def test_load_steps_stabilise_a_step_without_equilibrium(monkeypatch):
    """load_steps: a step that fails through all its bisections is solved again with the viscous
    stabilisation switched on at the last converged load factor, η = stabilize × the step's
    increment; with stabilize = 0 the run stops there as before (ConvergenceError). (Newton is
    replaced by a stand-in that has no equilibrium beyond λ = 0.5 until the interfaces are
    stabilised; the physics: tests/test_cohesive_plate.py, the MITC9 plate on 12 × 12.)"""
    from layershell.solver import newton as nw

    monkeypatch.setattr(nw, "newton", _newton_without_equilibrium_past_half)
    targets = np.array([0.25, 0.5, 0.75, 1.0])
    pb = _stand_in_problem()
    steps = list(nw.load_steps(pb, targets, nw.NewtonSettings(max_bisections=2, stabilize=0.02)))
    assert [st.load_factor for st in steps] == [0.25, 0.5, 0.75, 1.0]
    assert pb.interfaces.stabilized == {"load_factor": 0.5, "viscosity": pytest.approx(0.02 * 0.25)}
    assert steps[2].bisections == 2  # the failed halvings; then the step again, in one piece
    pb = _stand_in_problem()
    with pytest.raises(nw.ConvergenceError, match="last converged load factor is 0.5.*stabilize = 0.02"):
        list(nw.load_steps(pb, targets, nw.NewtonSettings(max_bisections=2, stabilize=0.0)))
    # a stabilised step whose viscous dissipation exceeds stabilize_limit of the step's: a limit point
    pb = _stand_in_problem(viscous_per_step=0.2)
    done = []
    with pytest.raises(nw.ConvergenceError, match="past load factor 0.5 the rate-independent path has no equilibrium"):
        for st in nw.load_steps(pb, targets, nw.NewtonSettings(max_bisections=2, stabilize=0.02)):
            done.append(st.load_factor)
    assert done == [0.25, 0.5]


def test_adaptive_load_steps_stabilise_a_step_without_equilibrium(monkeypatch):
    """The adaptive load path (solver/arclength.py ``path_steps``, control = "load") stabilises as
    load_steps does: where the increment has been cut below its smallest size it switches the
    viscous regularisation on (η = stabilize × the first increment) and goes on from the
    converged state; with stabilize = 0 it stops there; a stabilised increment whose viscous
    share exceeds stabilize_limit stops the run (the displacement-controlled DCB on 100 elements
    went on to δ = 10 mm with 28 % of its dissipation viscous and its branch 27 % above beam
    theory without that check; with it, it stops at 5.55 mm instead of 5.45). Newton is a
    stand-in without equilibrium beyond λ = 0.5 until the interfaces are stabilised."""
    from layershell.solver import arclength as al
    from layershell.solver import newton as nw

    monkeypatch.setattr(al, "newton", _newton_without_equilibrium_past_half)
    ps = al.PathSettings(control="load", lambda_end=1.0, increment=0.25, max_cuts=2, jump_area=None, jump_ratio=None)

    def path(stabilize, viscous=0.01):
        pb = _stand_in_problem(viscous_per_step=viscous)
        lams = []
        try:
            for st in al.path_steps(pb, nw.NewtonSettings(stabilize=stabilize), ps):
                lams.append(st.load_factor)
        except nw.ConvergenceError as exc:
            return lams, pb, str(exc)
        return lams, pb, None

    lams, pb, err = path(0.02)
    assert err is None and lams[-1] == 1.0 and lams[:2] == [0.25, 0.5]
    assert pb.interfaces.stabilized == {"load_factor": 0.5, "viscosity": pytest.approx(0.02 * 0.25)}
    lams, pb, err = path(0.0)
    assert lams == [0.25, 0.5] and "no equilibrium from load factor 0.5" in err
    lams, pb, err = path(0.02, viscous=0.2)
    assert lams == [0.25, 0.5] and "past load factor 0.5 the rate-independent path has no equilibrium" in err


#: examples/cantilever_plate_cohesive.toml with the thesis's fully integrated element: the friction
#: checks below need its state at λ = 1 on 6 × 6, where friction dissipates 0.1 % of the fracture
#: energy or more (with the MITC9 default 0.06 %, and other points at their slip limit)
FULL = {"nonlinear = true": 'nonlinear = true\nelement = "full"'}


def test_friction_stick_penalty_per_point_and_its_checkpoint():
    """The friction on the damaged share of a cohesive interface sticks with α_T min(1, cap/τ_max)
    per point (cohesive.stick_penalty; α_T = K0 = 50 E3/H by default, 1.7·10¹¹ for the §5.1
    plate's TRC layer, from the example's numbers), so every point sticks elastically over at
    least τ_max/α_T of slip whatever its slip limit: with K0 throughout, the points of low
    pressure stuck over 10⁻¹¹-10⁻¹⁰ m only (rigid-plastic) and the cohesive slab stalled at its
    end-debonding peak (docs/performance.md). Checked on the 6 × 6 plate at λ = 1, where friction
    acts: the penalty of every point with a slip limit, and a snapshot restored (as a checkpoint
    is) gives the same penalties."""
    from layershell.cohesive import stick_penalty
    from layershell.solver import newton as nw

    spec = example_spec("cantilever_plate_cohesive", FULL)
    pb = Problem.build(spec.model)
    (blk,) = [b for b in pb.assembler.extra if hasattr(b, "contact")]
    K, tau = blk.K, blk.law.tau_max
    assert K == pytest.approx(50 * 3.4e7 / 0.01, rel=1e-12) and tau == 1210.0
    ctl = pb.interfaces
    *_, last = nw.load_steps(pb, spec.load_factors, spec.newton, on_step_end=lambda p, u, lam: ctl.update(p, u, lam))
    assert last.load_factor == 1.0
    cb = blk.contact
    on = cb.cap > 0
    assert on.sum() >= 5 and np.any(cb.cap[on] < 0.5 * tau)  # friction acts (10 points), some below τ_max
    np.testing.assert_allclose(cb.alpha_T[on], K * np.minimum(cb.cap[on] / tau, 1.0), rtol=1e-14)
    np.testing.assert_array_equal(cb.alpha_T[~on], K)
    assert stick_penalty(2.0, np.array([0.0, 0.5, 1.0, 3.0]), 2.0).tolist() == [2.0, 0.5, 1.0, 2.0]
    # the stick range cap/α_T of every point with friction is at least τ_max/K0
    assert np.all(cb.cap[on] / cb.alpha_T[on] >= tau / K * (1 - 1e-12))
    snap = pb.snapshot()
    alpha = cb.alpha_T.copy()
    cb.alpha_T = K
    pb.restore(snap)
    np.testing.assert_array_equal(blk.contact.alpha_T, alpha)


def test_friction_stick_penalty_of_the_cohesive_law_only_regularises():
    """The stick penalty only regularises: the plate with friction on 6 × 6 to λ = 1 (friction
    dissipating) gives the same w_front_max and friction dissipation with the default α_T = K0,
    with G13/H of the thinner layer (1.453·10⁹, the thesis law's default: stick ranges 117 ×
    longer) and with 100 K0 (100 × shorter); measured: w_front_max equal to 3·10⁻¹¹, the friction
    dissipation to 4·10⁻⁷ (G13/H) and 4·10⁻⁹ (100 K0)."""
    runs = {a: run_example("cantilever_plate_cohesive", {**FULL, **({"mu0 = 0.95 ": f"alpha_T = {a}\nmu0 = 0.95 "} if a else {})})
            .summary for a in (None, "1.453e9", "1.7e13")}
    ref = runs[None]
    assert ref["energy"]["dissipated_friction"] > 1e-3 * ref["energy"]["dissipated_fracture"]  # friction acts
    for other in runs.values():
        assert other["converged"]
        assert other["probes"]["w_front_max"] == pytest.approx(ref["probes"]["w_front_max"], rel=1e-8)
        assert other["energy"]["dissipated_friction"] == pytest.approx(ref["energy"]["dissipated_friction"], rel=1e-5)


def _plate_with_friction_at_full_load():
    """The §5.1 cohesive plate (6 × 6) at λ = 1, where friction acts on the damaged share."""
    from layershell.solver import newton as nw

    spec = example_spec("cantilever_plate_cohesive", FULL)
    pb = Problem.build(spec.model)
    (blk,) = [b for b in pb.assembler.extra if hasattr(b, "contact")]
    ctl = pb.interfaces
    *_, last = nw.load_steps(pb, spec.load_factors, spec.newton, on_step_end=lambda p, u, lam: ctl.update(p, u, lam))
    assert last.load_factor == 1.0 and np.any(blk.contact.cap > 0)
    return pb, blk, last.u


def test_friction_stick_state_is_frozen_with_the_cohesive_sets():
    """The cohesive active-set loop freezes the friction's stick state with the tension and
    loading sets (CohesiveBlock.freeze): a point frozen sticking keeps the stick law beyond its slip
    limit, so that a frozen solve is smooth where points start at their limit (every point that
    slid in the last increment does); the set check reports the excess d (|t_tr| - cap) in units
    of τ_max, and unfreezing gives back the return mapping (the traction capped at the limit).
    Checked on a point of the 6 × 6 plate at λ = 1 whose anchor is moved to twice its limit."""
    pb, blk, u = _plate_with_friction_at_full_load()
    cb = blk.contact
    blk.freeze(u)
    x = cb.slip_ratio(u)
    np.testing.assert_array_equal(cb.stick_frozen, x < 1.0)
    assert blk.set_violation(u) == 0.0 or blk.set_violation(u) <= blk.CONSISTENCY_TOL  # the converged state
    e, q = np.argwhere((cb.cap > 0) & cb.stick_frozen & (blk.d_old > 0))[0]
    t_tr = cb.trial_traction(u)[e, q]
    # move the anchor so that the trial traction is twice the slip limit, along the same direction
    n = t_tr / np.linalg.norm(t_tr) if np.linalg.norm(t_tr) > 0 else np.cross(cb.A3[e, q], [0.0, 0.0, 1.0] if abs(cb.A3[e, q, 2]) < 0.9 else [1.0, 0.0, 0.0])
    n = n / np.linalg.norm(n)
    aT = np.asarray(cb.alpha_T, float)[e, q]
    cb.g_p[e, q] += (t_tr - 2.0 * cb.cap[e, q] * n) / aT
    t, D = cb.friction_traction(u)
    np.testing.assert_allclose(t[e, q], 2.0 * cb.cap[e, q] * n, rtol=1e-9, atol=1e-12 * cb.cap[e, q])
    P = np.eye(3) - np.outer(cb.A3[e, q], cb.A3[e, q])
    np.testing.assert_allclose(D[e, q], aT * P, rtol=1e-12)  # the stick tangent
    d = blk.d_old[e, q]
    assert blk.set_violation(u) >= cb.cap[e, q] * d / blk.law.tau_max * (1 - 1e-9)
    blk.unfreeze()
    assert cb.stick_frozen is None
    t, _ = cb.friction_traction(u)
    np.testing.assert_allclose(t[e, q], cb.cap[e, q] * n, rtol=1e-9, atol=1e-12 * cb.cap[e, q])


def _push_over_limit(cb, u, e, q, factor):
    """Move the anchor of point (e, q) so that its trial traction is ``factor`` × its slip limit."""
    t_tr = cb.trial_traction(u)[e, q]
    n = t_tr / np.linalg.norm(t_tr)
    cb.g_p[e, q] += (t_tr - factor * cb.cap[e, q] * n) / np.asarray(cb.alpha_T, float)[e, q]


def test_the_cycle_key_of_the_active_set_loop_holds_the_friction_stick_state():
    """The active-set loop counts how often it froze each state and gives up on a third time
    (freeze_sets: a cycle). The friction's stick state is frozen with the cohesive sets
    (CohesiveBlock.freeze), so it belongs to the state: counted by (tension, loading) only, a loop
    in which the loading sets held and only stick points went over their limits was 'cycling'
    after its second refreeze (the sampled ones 1.0-7.6·10⁻³ of the strength from consistency,
    against the tolerance of 10⁻³), and the TRC slab on its snap-back refused most of
    its small increments so (8 × 6: 319 of 406 refusals in its first 390 increments). Now the
    key (CohesiveBlock.frozen_key) holds the stick state: freezes that differ in it are different
    states, the same frozen state a third time still is a cycle, and the loading sets stay known
    to the loop's limited refreeze (ActiveSetLoop). Checked on the 6 × 6 plate at λ = 1 with
    anchors moved as a solve would move the points."""
    from layershell.solver.newton import _sets_key, freeze_sets

    pb, blk, u = _plate_with_friction_at_full_load()
    cb = blk.contact
    seen: dict = {}
    assert freeze_sets([blk], u, seen)
    sticking = np.argwhere((cb.cap > 0) & cb.stick_frozen & (blk.d_old > 0))
    assert len(sticking) >= 2
    (e1, q1), (e2, q2) = sticking[:2]
    sets = _sets_key([blk.frozen])
    for e, q in ((e1, q1), (e2, q2)):  # a solve carried one more stick point over its limit
        _push_over_limit(cb, u, e, q, 1.5)
        assert blk.set_violation(u) > blk.CONSISTENCY_TOL
        assert freeze_sets([blk], u, seen)  # the same loading sets, another stick state: no repeat
        assert not cb.stick_frozen[e, q] and _sets_key([blk.frozen]) == sets
    assert sets in seen and _sets_key([blk.actual_sets(u)]) in seen  # for the limited refreeze
    # the same frozen state again: the second time is allowed, the third is a cycle
    assert freeze_sets([blk], u, seen)
    assert not freeze_sets([blk], u, seen)
    # a loop without friction counts as before: (tension, loading)
    blk.unfreeze()
    blk.freeze(u)
    cb.stick_frozen = None
    assert blk.frozen_key() == sets


def test_reversal_step_stops_a_sliding_point_at_its_anchor():
    """A sliding point has no stiffness along its slip, so a Newton correction can carry it through
    its stick range at once and throw its friction from +cap to -cap (the TRC slab stalled so on
    its snap-back). CohesiveBlock.reversal_step gives the fraction of a correction that takes no
    sliding point past its anchor, and arclength.reversal_step takes at least REVERSAL_STEP_MIN of it.
    Checked on one point of the 6 × 6 plate at λ = 1 made to slide at three times its limit, with
    the correction -c u chosen so that the whole of it reverses the point's trial traction to -3 cap:
    the fraction is 1/2, and there the trial traction is at the anchor."""
    from layershell.solver import arclength as al

    pb, blk, u = _plate_with_friction_at_full_load()
    cb = blk.contact
    v = cb.trial_traction(u, anchored=False)
    on = (cb.cap > 0) & (np.linalg.norm(v, axis=-1) > 0)
    e, q = np.argwhere(on)[0]
    cap = cb.cap.copy()
    cb.cap = np.where(np.arange(cap.size).reshape(cap.shape) == e * cap.shape[1] + q, cap, 0.0)  # this point only
    vn = np.linalg.norm(v[e, q])
    vhat = v[e, q] / vn
    aT = np.asarray(cb.alpha_T, float)[e, q]
    s = 3.0 * cb.cap[e, q]
    cb.g_p[e, q] = (v[e, q] - s * vhat) / aT  # t_tr = s vhat: sliding
    assert cb.slip_ratio(u)[e, q] == pytest.approx(3.0)
    c = 2.0 * s / vn  # the correction -c u changes t_tr by -c v = -2 s vhat
    eta = blk.reversal_step(u, -c * u)
    assert eta == pytest.approx(0.5, rel=1e-9)
    np.testing.assert_allclose(cb.trial_traction(u + eta * (-c * u))[e, q] @ vhat, 0.0, atol=1e-9 * s)
    assert blk.reversal_step(u, 0.25 * c * u) == 1.0  # further along the slip: no limit
    assert blk.reversal_step(u, -0.4 * c * u) == 1.0  # back into the stick range only: no limit
    assert al.reversal_step(pb, u, -1e3 * c * u) == al.REVERSAL_STEP_MIN
    cb.cap = np.zeros_like(cap)
    assert blk.reversal_step(u, -c * u) == 1.0  # no friction: no limit


def _friction_state(cap: float | None = None):
    """_damaged_problem's strip (Lobatto) with friction on the damaged share: slip limits
    ``cap`` at every point (random ones where None: some points stick, some slide), the stick
    penalty per point and random anchors in the tangent plane."""
    from layershell.cohesive import stick_penalty

    pb, blk, ur = _damaged_problem("lobatto")
    rng = np.random.default_rng(5)
    cb = blk.contact
    cb.cap = rng.uniform(0.0, 0.05, blk.d_old.shape) if cap is None else np.full(blk.d_old.shape, cap)
    cb.alpha_T = stick_penalty(blk.K, cb.cap, blk.law.tau_max)
    cb.g_p = np.einsum("eqij,eqj->eqi", cb.projector(), rng.normal(size=cb.g_p.shape)) * 1e-6
    return pb, blk, ur


def test_friction_excess_gradient_against_finite_differences():
    """∂c/∂u of CohesiveBlock.friction_excess (the secant energy of the friction on the damaged
    share less its stored energy) equals central differences of c in a state with sticking and
    sliding points whose damage grows at some of them."""
    from layershell.solver.arclength import friction_excess

    pb, blk, ur = _friction_state()
    u = pb.op.T @ ur
    x = blk.contact.slip_ratio(u)
    on = blk.contact.cap > 0
    assert (x[on] > 1).any() and (x[on] < 1).any()  # some points slide, some stick
    _, _, d, _ = blk.point_state(u)
    assert ((d > blk.d_old) & on).any()  # damage grows under friction somewhere
    c, grad = friction_excess(pb, u, True)
    assert c != 0.0
    rng = np.random.default_rng(11)
    for _ in range(3):
        v = pb.op.T @ rng.normal(size=ur.size) * (1e-7 * np.abs(ur).max())
        fd = (friction_excess(pb, u + v)[0] - friction_excess(pb, u - v)[0]) / 2.0
        assert float(grad @ v) == pytest.approx(fd, rel=1e-5, abs=1e-12 * abs(c))


def test_friction_excess_makes_an_elastic_excursion_dissipate_nothing():
    """The dissipation constraint's interface form ΔG = ½(f_I(u₀)·u₁ − f_I(u₁)·u₀) takes the
    stored energy to be the secant one. Friction's stick springs, anchored away from zero slip,
    store ½ d |t_f|²/α_T instead: an excursion on which nothing damages and nothing slides
    'dissipates' under ΔG alone. ΔG + Δc (friction_excess) is the trapezoidal work less the
    change of the stored energy: zero to round-off for these affine springs (the independent
    reference: an elastic excursion dissipates nothing)."""
    from layershell.solver.arclength import friction_excess, interface_forces

    pb, blk, ur = _friction_state(cap=1e9)  # every friction point sticks
    blk.d_old = np.full_like(blk.d_old, 0.95)  # no point's damage grows (secant unloading)
    u0 = pb.op.T @ ur
    u1 = 1.1 * u0  # scaled: no point changes from tension to compression
    for u in (u0, u1):
        assert np.all(blk.point_state(u)[2] == blk.d_old)
        assert np.all(blk.contact.slip_ratio(u) < 1)
    f0, f1 = interface_forces(pb, u0)[0], interface_forces(pb, u1)[0]
    dG = 0.5 * (float(f0 @ u1) - float(f1 @ u0))
    dc = friction_excess(pb, u1)[0] - friction_excess(pb, u0)[0]
    work = 0.5 * float((f0 + f1) @ (u1 - u0))
    assert abs(dG) > 1e-3 * abs(work)  # the secant form alone books a dissipation
    assert abs(dG + dc) < 1e-9 * abs(work)
