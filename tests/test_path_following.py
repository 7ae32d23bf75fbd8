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
