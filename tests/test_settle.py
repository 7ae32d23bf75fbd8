"""Pseudo-transient settling at a fixed load (src/layershell/solver/newton.py ``settle``): the
last resort of a re-solution after new releases, which cannot be cut into load increments.

References, independent of the settling: the cantilever elastica (Timoshenko & Gere §2.7,
tests/test_stability.py), the fall of the potential energy between the two states (a straight
line integral of the internal forces, exact for Green-Lagrange strains with a linear material:
f_int is cubic in u), and the inertia of the tangent (a stable state has no negative
eigenvalue). The model: examples/column_buckling.toml with a lateral tip load of 10⁻⁵ P_E (the
imperfection), whose Newton solves from its straight state beyond P_E converge onto the unstable
branch that deflects against the imperfection, or not at all."""
from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from layershell.io.build import build, parse
from layershell.solver import newton as nw
from layershell.solver.problem import Problem
from test_stability import B, L, P_EULER, T, column_text, elastica_deflection


def column(nx: int, eps: float = 1e-5):
    """(problem, equilibrium at 0.99 P_E, the tip's lateral DOF) of the imperfect column on
    ``nx`` elements; the problem records settlements in a stand-in controller."""
    text = column_text(nx, "factors = [1.0]") + f"""
[[loads]]
type = "edge"
where = "near(x, {L})"
direction = [0, 0, 1]
distribution = {eps * P_EULER / (B * T)!r}
"""
    spec = build(parse(text))
    pb = Problem.build(spec.model)
    *_, last = nw.load_steps(pb, np.array([0.5, 0.99]), spec.newton)
    pb.interfaces = SimpleNamespace(settlements=[])
    tip = int(np.argmin(np.linalg.norm(spec.model.mesh.nodes - [L, 0.0, 0.0], axis=1)))
    return pb, last.u, pb.dm.layer_dofs[0][tip, 0, 2], spec.newton


def potential_fall(pb: Problem, a: np.ndarray, b: np.ndarray, lam: float) -> float:
    """Π(a) − Π(b) at load factor ``lam``: the work of F_ext − f_int along the straight line from
    ``a`` to ``b`` (three-point Gauss-Legendre, exact for a cubic f_int)."""
    x, w = np.polynomial.legendre.leggauss(3)
    d = b - a
    F = pb.external(lam)
    return sum(0.5 * wi * float((F - pb.assembler.evaluate(a + 0.5 * (xi + 1) * d, tangent=False)[0]) @ d)
               for xi, wi in zip(x, w))


def test_settling_beyond_the_buckling_load_reaches_the_stable_elastica_on_three_meshes():
    """At 1.5 P_E, from the equilibrium at 0.99 P_E (nearly straight): Newton finds no
    equilibrium in 25 iterations; settling reaches one whose tangent has no negative eigenvalue
    and whose tip deflection is that of the elastica (|w|: measured +0.1 / +0.7 / +0.7 % on 4, 8
    and 16 elements, the load-stepped path's −0.0 / +0.7 / +0.7 %, tests/test_stability.py). The
    energy it reports released is the fall of the potential energy from the start to the end,
    computed along a straight line instead of its damped path (measured to 10⁻¹²), and converges
    with the mesh (3.658, 3.761, 3.768 N·mm)."""
    ratios, energies = [], []
    for nx in (4, 8, 16):
        pb, u0, w_dof, s = column(nx)
        _, plain = nw.newton(pb, u0, 1.5, s)
        assert not plain.converged
        u, res = nw.settle(pb, u0, 1.5, s, why="a test")
        assert res.converged and res.message == "settled"
        assert pb.inertia_at(u) == 0
        (ev,) = pb.interfaces.settlements
        assert ev["load_factor"] == 1.5 and ev["reason"] == "a test" and ev["increments"] > 1
        assert ev["largest_displacement_change"] == pytest.approx(np.abs(u - u0).max())
        assert ev["energy_released"] == pytest.approx(potential_fall(pb, u0, u, 1.5), rel=1e-8)
        ratios.append(abs(u[w_dof]) / elastica_deflection(1.5))
        energies.append(ev["energy_released"])
    assert abs(ratios[0] - 1) < 0.02 and abs(ratios[1] - 1) < 0.01 and abs(ratios[2] - 1) < 0.01, ratios
    assert abs(energies[2] - energies[1]) < abs(energies[1] - energies[0]), energies


def test_settling_does_not_end_on_an_unstable_equilibrium():
    """At 1.1 P_E Newton from the 0.99 P_E state converges onto the unstable near-straight branch
    (w_tip −0.0089 mm, one negative eigenvalue). Settling from the same state ends on the
    elastica instead: the steps whose damped tangent is not positive definite are refused (with
    them implicit Euler damps the unstable mode and converges onto the saddle). Started on that
    unstable equilibrium itself, where the damping force is zero, settling pushes off it along
    its unstable mode (once) and ends on the elastica too; its potential energy lies below the
    saddle's. Elastica at 1.1 P_E: 50.85 mm (8 elements: +0.3 %)."""
    pb, u0, w_dof, s = column(8)
    u_saddle, res = nw.newton(pb, u0, 1.1, s)
    assert res.converged and pb.inertia_at(u_saddle) == 1 and abs(u_saddle[w_dof]) < 0.01
    reference = elastica_deflection(1.1)
    u, res = nw.settle(pb, u0, 1.1, s)
    assert res.converged and pb.inertia_at(u) == 0
    assert abs(u[w_dof]) == pytest.approx(reference, rel=0.01)
    u, res = nw.settle(pb, u_saddle, 1.1, s)
    assert res.converged and pb.inertia_at(u) == 0
    assert abs(u[w_dof]) == pytest.approx(reference, rel=0.01)
    ev = pb.interfaces.settlements[-1]
    assert ev["pushes"] == 1
    assert ev["energy_released"] == pytest.approx(potential_fall(pb, u_saddle, u, 1.1), rel=1e-8)
    assert ev["energy_released"] > 0.0


def test_settling_that_cannot_settle_says_why(monkeypatch):
    """Where the damped increments do not settle within SETTLE_MAX_INCREMENTS the result is not
    converged, names the reason, and records nothing."""
    pb, u0, _, s = column(4)
    monkeypatch.setattr(nw, "SETTLE_MAX_INCREMENTS", 3)
    u, res = nw.settle(pb, u0, 1.5, s)
    assert not res.converged
    assert res.message == "pseudo-transient settling failed: the damped states did not settle in 3 pseudo-time increments"
    assert pb.interfaces.settlements == []
    assert math.isfinite(res.residuals[-1])


def test_damped_increments_reach_the_static_equilibrium_where_a_static_solve_only_confirms_it(monkeypatch):
    """The damped increments themselves converge to the static equilibrium: their damping force
    D (u − u_n)/Δt is the static residual of their state, and it falls as Δt grows. Once it is
    within ``tol_residual`` a static solve is tried whatever Δt, so settling ends there even
    where every static solve from farther away fails (the completely debonded CFRP plate on
    24 × 16: static Newton solves from damping forces below 1 % of the load failed again and
    again). Here no static solve is tried early (SETTLE_STATIC = 0), and the one static solve
    gets a single Newton iteration: it converges only from a state within the tolerance. The
    result is the unrestricted settling's elastica to 10⁻⁶, an equilibrium within
    ``tol_residual``, with no negative eigenvalue. (Without the tolerance rule this settling
    never tries a static solve and fails after SETTLE_MAX_INCREMENTS.)"""
    from dataclasses import replace

    pb, u0, w_dof, s = column(8)
    reference, _ = nw.settle(pb, u0, 1.5, s)
    real, static = nw.newton, []

    def one_static_iteration(problem, u, lam, st):
        if problem.pseudo is not None:
            return real(problem, u, lam, st)
        out = real(problem, u, lam, replace(st, max_iterations=1))
        static.append(out[1].converged)
        return out

    monkeypatch.setattr(nw, "newton", one_static_iteration)
    monkeypatch.setattr(nw, "SETTLE_STATIC", 0.0)
    u, res = nw.settle(pb, u0, 1.5, s)
    assert res.converged and pb.inertia_at(u) == 0
    assert static == [True]
    assert u[w_dof] == pytest.approx(reference[w_dof], rel=1e-6)
    f, _ = pb.assembler.evaluate(u, tangent=False)
    F = pb.external(1.5)
    assert np.linalg.norm(pb.op.reduce(F - f)) <= s.tol_residual * np.linalg.norm(pb.op.reduce(F))


def test_the_damped_tangent_keeps_the_pattern_of_the_tangent():
    """PseudoViscosity.tangent adds D/Δt on the diagonal of K_r in K_r's own pattern (the solver
    keeps its symbolic analysis and upper-triangle map): equal to K_r + diag(D/Δt) entry for
    entry (to the last bit of the product), the same index arrays, and K_r itself unchanged."""
    import scipy.sparse as sp

    pb, u0, _, _ = column(4)
    _, Kr = pb.assembler.evaluate_reduced(u0, pb.op, forces=False)
    D = np.abs(Kr.diagonal()) * np.linspace(0.5, 2.0, Kr.shape[0])
    damped = nw.PseudoViscosity(D, u0, 1.0 / 3.0).tangent(Kr)
    assert damped.indices is Kr.indices and damped.indptr is Kr.indptr
    assert abs(damped - (Kr + sp.diags(D / 3.0))).max() <= 1e-15 * abs(Kr).max()  # (1/3)·D against D/3
    assert np.array_equal(Kr.diagonal(), pb.assembler.evaluate_reduced(u0, pb.op, forces=False)[1].diagonal())  # K_r untouched


def free_column(nx: int = 4):
    """(problem, zero state, z DOFs of the reference face) of the column of :func:`column` whose
    clamp holds x and y only: a rigid translation in z costs no energy, and the lateral tip load
    (10⁻² P_E) has no equilibrium, at any load factor."""
    text = column_text(nx, "factors = [1.0]").replace('components = ["x", "y", "z"]', 'components = ["x", "y"]')
    assert 'components = ["x", "y"]' in text
    text += f"""
[[loads]]
type = "edge"
where = "near(x, {L})"
direction = [0, 0, 1]
distribution = {1e-2 * P_EULER / (B * T)!r}
"""
    spec = build(parse(text))
    pb = Problem.build(spec.model)
    pb.interfaces = SimpleNamespace(settlements=[])
    z = pb.dm.layer_dofs[0][:, 0, 2]
    return pb, np.zeros(pb.dm.n_full), z[z >= 0], spec.newton


def test_settling_stops_early_where_the_state_moves_without_stiffness(monkeypatch):
    """A mechanism has no equilibrium: the column free to translate in z under a lateral load
    (at 0.5 P_E). Settling says so ("no equilibrium: the state moves without stiffness") once
    the damping force has stopped falling while Δt grew and the state has moved farther than
    the model's size - a rigid translation in z (every node within 1 % of the mean). Without
    the rule it runs to SETTLE_MAX_INCREMENTS (the completely debonded CFRP plate on 24 × 16
    did, its loose sublaminate drifting 5·10⁵ mm), at three times the iterations (351 against
    117: the drifted state's increments converge at its round-off floor, solver.newton)."""
    pb, u0, z, s = free_column()
    u, res = nw.settle(pb, u0, 0.5, s)
    assert not res.converged and pb.interfaces.settlements == []
    assert res.message.startswith("pseudo-transient settling failed: no equilibrium: the state moves without stiffness")
    assert "more than the model's size 100" in res.message
    drift = u[z]
    assert drift.mean() > 100.0 and np.ptp(drift) < 0.01 * drift.mean()
    monkeypatch.setattr(nw, "SETTLE_RUNAWAY", 10**9)
    _, without = nw.settle(pb, u0, 0.5, s)
    assert not without.converged and "did not settle in 200 pseudo-time increments" in without.message
    assert without.iterations > 2 * res.iterations


def test_the_stiffness_free_signature_on_a_damped_linear_mode():
    """moves_without_stiffness on one mode damped as settle damps it (implicit Euler with Δt
    doubling from 1: u ← u + (F − k u) Δt / (D + k Δt), damping force D (u − u_n)/Δt): with
    k = 0 the force never falls and the signature shows after SETTLE_RUNAWAY increments and
    stays; with k = 10⁻⁴ D it shows only while kΔt is small (up to Δt = 2¹¹, kΔt = 0.2: the
    stiffness is not yet felt) and is gone for good from Δt = 2¹², while the motion stays below
    F/k, the mode's equilibrium - settle stops only where the state has also moved farther than
    the model's size."""
    def history(k: float, n: int = 40) -> tuple[list[bool], float]:
        D, F, u, dt, hist, shows = 1.0, 1.0, 0.0, 1.0, [], []
        for _ in range(n):
            du = (F - k * u) * dt / (D + k * dt)
            hist.append((dt, D * du / dt))
            u += du
            shows.append(nw.moves_without_stiffness(hist))
            dt = min(2.0 * dt, nw.SETTLE_DT_MAX)
        return shows, u

    free, _ = history(0.0)
    assert free == [False] * nw.SETTLE_RUNAWAY + [True] * (40 - nw.SETTLE_RUNAWAY)
    stiff, u = history(1e-4)
    assert any(stiff[:12]) and not any(stiff[12:]) and u == pytest.approx(1e4, rel=1e-6)


def test_a_layer_pulled_off_completely_ends_the_run_naming_no_equilibrium_and_complete_separation(tmp_path):
    """End to end: the §5.1 plate (examples/cantilever_plate_strong.toml, 3 × 3) with its TRC
    layer pulled up by a load on its top face (10 kN/m², λ = 0.25 in the first of 4 steps) and
    interface strengths of 1 kN/m², so that the first step's releases debond every interface
    point. The loose layer, held by nothing (contact only pushes), has no equilibrium: its
    re-solution fails, settling stops on the motion without stiffness, and the run ends naming
    both (no equilibrium, complete separation at λ = 0.25); the command line's advice says that
    this is the end of the debonding, not the generic hint about supports and step sizes."""
    import json

    from typer.testing import CliRunner

    from helpers import EXAMPLES
    from layershell.cli import app

    text = (EXAMPLES / "cantilever_plate_strong.toml").read_text()
    for a, b in (("sigma_max = 1980.0", "sigma_max = 1.0"), ("tau_max = 1210.0", "tau_max = 1.0"),
                 ("[steps]\nn = 24", "[steps]\nn = 4"),
                 ("[[interfaces]]", '[[loads]]\ntype = "surface"\nface = "top"\ndirection = [0, 0, 1]\n'
                                    'magnitude = 10.0\n\n[[interfaces]]')):
        assert a in text
        text = text.replace(a, b, 1)
    model = tmp_path / "pulled_off.toml"
    model.write_text(text)
    res = CliRunner().invoke(app, ["run", str(model), "--out", str(tmp_path / "out"), "--no-vtu", "--quiet"],
                             env={"LAYERSHELL_TRACEBACK": None, "NO_COLOR": "1"})
    assert res.exit_code == 1  # the solution failed
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert not summary["converged"] and summary["steps"] == []
    said = " ".join(res.stderr.split())  # the run's message, then the command line's advice
    assert "re-equilibration at load factor 0.25 failed" in said
    assert "no equilibrium: the state moves without stiffness" in said
    assert "the run has reached complete separation at load factor 0.25" in said
    assert "the end of the debonding" in said
    assert "check that the supports prevent" not in said
