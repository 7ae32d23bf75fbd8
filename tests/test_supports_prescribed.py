"""Supports mean what they say: prescribed displacements, supports on bonded layers, on faces,
heights and directions, and on layers absent at their nodes.

The reference is statics of a strip (linear analysis, ν = 0) clamped through its whole thickness at
x = 0 and held at x = L by the support under test:
- a support that translates the whole section (``layer = "all"``, ``directors = "all"``) carries
  P = EA v / L, exactly, since a uniform strain lies in the element's space;
- a support that holds one point at height z₀ (a face, a height, director 0 of a layer) of a
  cantilever whose end may rotate and deflect carries the eccentric axial force of beam theory,
  P = v / (L (1/EA + e²/EI)), e = z₀ − z_c: u(z₀) = P L/EA + θ e with θ = P e L / EI; the shell
  adds the end zone's own flexibility (Saint-Venant, of the order t/L), measured at ≤ 1.3 %;
- in every case the held point moves by the prescribed value, the support forces at the two ends
  are equal and opposite, and a bonded interface stays closed.
"""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from layershell.io.build import build, parse
from layershell.io.errors import InputError
from layershell.runner import run

L, B, E = 100.0, 10.0, 1000.0  # strip length, width, Young's modulus (N, mm)

STRIP = '''
[model]
title = "strip held at x = L by the support under test"
units = "N, mm"
nonlinear = false
[mesh]
type = "rectangle"
lx = 100.0
ly = 10.0
nx = {nx}
ny = 1
[materials.m]
type = "isotropic"
E = 1000.0
nu = 0.0
[[layers]]
name = "lower"
material = "m"
thickness = 0.5
directors = {d}
[[layers]]
name = "upper"
material = "m"
thickness = 0.5
directors = {d}
[[supports]]
type = "fix"
where = "near(x, 0)"
{clamp}
[[supports]]
type = "fix"
where = "near(x, 100)"
{pull}
[steps]
n = 1
[[probes]]
name = "Px"
quantity = "reaction"
where = "near(x, 100)"
component = "x"
[[probes]]
name = "Px0"
quantity = "reaction"
where = "near(x, 0)"
component = "x"
[[probes]]
name = "Pz"
quantity = "reaction"
where = "near(x, 100)"
component = "z"
[[probes]]
name = "Pz0"
quantity = "reaction"
where = "near(x, 0)"
component = "z"
[[probes]]
name = "ux"
quantity = "displacement"
point = [100, 5, 0]
theta3 = {z0}
component = "x"
[[probes]]
name = "uz"
quantity = "displacement"
point = [100, 5, 0]
theta3 = {z0}
component = "z"
[[probes]]
name = "lower_top"
quantity = "displacement"
point = [100, 5, 0]
layer = "lower"
theta3 = 0.5
component = "x"
[[probes]]
name = "upper_bottom"
quantity = "displacement"
point = [100, 5, 0]
layer = "upper"
theta3 = 0.5
component = "x"
'''

CLAMP_ALL = 'layer = "all"\ndirectors = "all"'


def _solve(pull: str, z0: float, clamp: str = CLAMP_ALL, nx: int = 8, d: int = 1) -> dict:
    spec = build(parse(STRIP.format(pull=pull, z0=z0, clamp=clamp, nx=nx, d=d), "strip.toml"), ".")
    res = run(spec, None, write_vtu=False)
    assert res.converged, res.message
    return {k: (v[-1] if isinstance(v, list) else v) for k, v in res.summary["probes"].items()}


def _beam_force(v: float, z0: float) -> float:
    """Eccentric axial force of a cantilever (1 mm thick, centroid at 0.5) whose point at height
    z₀ of the free end is moved by v along the axis."""
    EA, EI = E * B * 1.0, E * B / 12.0
    e = z0 - 0.5
    return v / (L * (1.0 / EA + e * e / EI))


def test_a_prescribed_value_survives_a_support_through_all_layers():
    """The clamp uses layer = "all": the pulled section's value must still act (it was dropped)."""
    r = _solve('layer = "all"\ndirectors = "all"\ncomponents = ["x"]\nvalue = [1.0]', 0.5)
    assert r["ux"] == pytest.approx(1.0, abs=1e-9)
    assert r["Px"] == pytest.approx(E * B * 1.0 / L, rel=1e-8)  # EA v / L = 100 N
    assert r["Px0"] == pytest.approx(-r["Px"], rel=1e-8)


def test_a_support_on_a_bonded_upper_layer_keeps_the_bond():
    """The upper layer held (x, y, z) at x = 0 and pulled at x = L: both layers stretch together."""
    held_z = '\n[[supports]]\ntype = "fix"\nwhere = "near(x, 100)"\nlayer = "upper"\ncomponents = ["z"]'
    r = _solve('layer = "upper"\ncomponents = ["x"]\nvalue = [1.0]' + held_z, 0.5, clamp='layer = "upper"')
    assert r["upper_bottom"] == pytest.approx(1.0, abs=1e-9)
    assert r["lower_top"] == pytest.approx(r["upper_bottom"], abs=1e-12)  # the bond holds
    # held and pulled on the centroid (z0 = 0.5), both ends on rollers: the axial stiffness EA/L = 100 N
    assert r["Px"] == pytest.approx(E * B * 1.0 / L, rel=0.02)


PULLS = {  # (the pulled support's lines, height of the held point, force reference)
    "section": ('layer = "all"\ndirectors = "all"\n{dirs}\nvalue = [{v}]', 0.5, "section"),
    "all layers, director 0": ('layer = "all"\n{dirs}\nvalue = [{v}]', 0.0, None),
    "lower layer": ('layer = "lower"\n{dirs}\nvalue = [{v}]', 0.0, "point"),
    "upper layer": ('layer = "upper"\n{dirs}\nvalue = [{v}]', 0.5, "point"),
    "upper layer, director 0": ('layer = "upper"\ndirectors = [0]\n{dirs}\nvalue = [{v}]', 0.5, "point"),
    "upper layer, all directors": ('layer = "upper"\ndirectors = "all"\n{dirs}\nvalue = [{v}]', 0.5, None),
    "top face": ('layer = "upper"\nface = "top"\n{dirs}\nvalue = [{v}]', 1.0, "point"),
    "bottom face of upper": ('layer = "upper"\nface = "bottom"\n{dirs}\nvalue = [{v}]', 0.5, "point"),
    "height": ('height = 0.25\n{dirs}\nvalue = [{v}]', 0.25, "point"),
    "height in upper": ('layer = "upper"\nheight = 0.8\n{dirs}\nvalue = [{v}]', 0.8, "point"),
}
CLAMPS = {
    "all layers, all directors": CLAMP_ALL,
    "each layer's directors": 'layer = "lower"\ndirectors = "all"\n[[supports]]\ntype = "fix"\n'
                              'where = "near(x, 0)"\nlayer = "upper"\ndirectors = "all"',
    "a face and a height": 'layer = "lower"\nface = "bottom"\n[[supports]]\ntype = "fix"\n'
                           'where = "near(x, 0)"\nheight = 1.0\n[[supports]]\ntype = "fix"\n'
                           'where = "near(x, 0)"\nheight = 0.5',
}


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(pull=st.sampled_from(sorted(PULLS)), clamp=st.sampled_from(sorted(CLAMPS)),
       oblique=st.booleans(), scaled=st.booleans(), d=st.sampled_from([1, 2]),
       v=st.floats(-2.0, 2.0).filter(lambda x: abs(x) > 1e-3))
def test_every_support_combination_moves_its_point_and_balances(pull, clamp, oblique, scaled, d, v):
    """Any support form with a value: the held point moves by v (along the held direction), the
    supports' forces balance, the bond stays closed, and the force matches statics."""
    text, z0, kind = PULLS[pull]
    dirs = 'direction = [1, 0, 1]' if oblique else 'components = ["x"]'
    lines = text.format(dirs=dirs, v=v) + ("" if scaled else "\nscaled = false")
    r = _solve(lines, z0, clamp=CLAMPS[clamp], d=d)
    moved = (r["ux"] + r["uz"]) / np.sqrt(2.0) if oblique else r["ux"]
    assert moved == pytest.approx(v, abs=1e-9 * max(1.0, abs(v)))
    scale = max(abs(r["Px"]), abs(r["Pz"]), 1.0)
    assert abs(r["Px"] + r["Px0"]) < 1e-7 * scale and abs(r["Pz"] + r["Pz0"]) < 1e-7 * scale
    assert r["lower_top"] == pytest.approx(r["upper_bottom"], abs=1e-10 * max(1.0, abs(v)))
    if oblique or clamp != "all layers, all directors" or (kind == "point" and d > 1):
        return  # statics references for the clamped strip pulled along x (d = 1: the beam's kinematics)
    if kind == "section":
        assert r["Px"] == pytest.approx(E * B * 1.0 * v / L, rel=1e-8)
    elif kind == "point":
        assert r["Px"] == pytest.approx(_beam_force(v, z0), rel=0.02)


def test_the_beam_force_converges_with_the_mesh():
    """The eccentric pull on three meshes: the force approaches beam theory's (the end zone's
    flexibility is a fixed fraction, not a mesh artefact), and the held point moves exactly v."""
    got = [_solve('layer = "upper"\nface = "top"\ncomponents = ["x"]\nvalue = [1.0]', 1.0, nx=nx)
           for nx in (4, 8, 16)]
    P = np.array([g["Px"] for g in got])
    assert np.all(np.abs(P / _beam_force(1.0, 1.0) - 1.0) < 0.01)
    assert abs(P[2] - P[1]) <= abs(P[1] - P[0]) + 1e-9 * P[0]
    assert all(g["ux"] == pytest.approx(1.0, abs=1e-9) for g in got)


def test_contradicting_supports_are_refused():
    """Two supports prescribe different displacements at the same point: a clear error."""
    from layershell.constraints import ConstraintError

    pull = ('layer = "all"\ndirectors = "all"\ncomponents = ["x"]\nvalue = [1.0]\n[[supports]]\ntype = "fix"\n'
            'where = "near(x, 100)"\nlayer = "upper"\nface = "bottom"\ncomponents = ["x"]\nvalue = [2.0]')
    with pytest.raises(ConstraintError, match="different displacements"):
        _solve(pull, 0.5)


STACKED = '''
[model]
title = "strip with a plate that stops short of the support"
units = "N, mm"
nonlinear = false
[mesh]
type = "rectangle"
lx = 100.0
ly = 10.0
nx = 10
ny = 1
[materials.m]
type = "isotropic"
E = 1000.0
nu = 0.0
[[layers]]
name = "plate"
material = "m"
thickness = 0.2
[[layers]]
name = "core"
material = "m"
thickness = 1.0
[[stacks]]
where = "x > 10"
layers = ["plate", "core"]
[[stacks]]
layers = ["core"]
[[supports]]
type = "fix"
where = "near(x, 100)"
layer = "all"
directors = "all"
[[supports]]
type = "fix"
where = "near(x, 0)"
{support}
'''


@pytest.mark.parametrize("support", [
    'layer = "plate"',
    'layer = "plate"\nface = "bottom"\ndirection = [0, 0, 1]',
    'height = 0.1\ndirection = [0, 0, 1]',
])
def test_a_support_on_a_layer_absent_at_its_nodes_is_refused(support):
    with pytest.raises(InputError, match="plate|no layer"):
        build(parse(STACKED.format(support=support), "stacked.toml"), ".")


def test_a_support_without_layer_holds_the_layer_present_there():
    """Where the first stack's bottom layer is absent, a support without 'layer' holds the lowest
    layer present (the core), so the model is supported and solves."""
    spec = build(parse(STACKED.format(support='components = ["z"]'), "stacked.toml"), ".")
    fx = [f for f in spec.model.fixes if 0.0 in spec.model.mesh.nodes[f.nodes, 0]]
    assert [spec.model.layers[f.layer].name for f in fx] == ["core"]


@pytest.mark.parametrize("normal, face, warned", [("-z", "bottom", True), ("-z", "top", True),
                                                   ("+z", "bottom", False), ("+z", "top", False)])
def test_a_face_support_under_a_downward_normal_says_which_side_it_is(normal, face, warned):
    """'bottom'/'top' count along Θ³: with normal = "-z" they are the physical top/bottom."""
    text = STRIP.format(pull=f'layer = "upper"\nface = "{face}"\ncomponents = ["x"]\nvalue = [1.0]', z0=0.5,
                        clamp=CLAMP_ALL, nx=4, d=1).replace('ny = 1\n', f'ny = 1\nnormal = "{normal}"\n', 1)
    spec = build(parse(text, "strip.toml"), ".")
    notes = [w for w in spec.warnings if "supports[1].face" in w]
    assert bool(notes) == warned
    if warned:
        assert "physically " + ("upper" if face == "bottom" else "lower") in notes[0]
