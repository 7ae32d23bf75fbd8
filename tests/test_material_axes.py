"""Material axis 1 of a layer without `direction` in a mesh file follows the node numbering: a
mesh numbered clockwise (normal -z) has it along y, so "σ11" is σ_yy. `check` and `run` say so and
name the fix (direction = [1, 0, 0]), which makes "σ11" σ_xx again."""
from __future__ import annotations

import meshio
import numpy as np
import pytest

from layershell.io.build import build, parse
from layershell.io.material_axes import first_line_directions
from layershell.mesh import rectangle
from layershell.runner import run

CLOCKWISE = np.array([0, 3, 2, 1, 7, 6, 5, 4, 8])  # quad9 corners and mid-sides in reverse order, node 0 first

# a slab strip 2 m × 0.5 m spanning along x, simply supported on its soffit at x = 0 and x = 2,
# a pressure on its top face; the mesh file's reference face is the top face (normal -z)
MODEL = """
[model]
title = "strip from a mesh file"
units = "kN, m"
nonlinear = false

[mesh]
type = "file"
path = "strip.msh"

[materials.concrete]
type = "isotropic"
E = 3.0e7
nu = 0.2

[[layers]]
name = "concrete"
material = "concrete"
thickness = 0.1
directors = 2
{direction}

[[supports]]
type = "fix"
where = "near(x, 0)"
height = 0.1
components = ["x", "y", "z"]

[[supports]]
type = "fix"
where = "near(x, 2)"
height = 0.1
components = ["z"]

[[supports]]
type = "fix"
point = [2, 0, 0]
height = 0.1
components = ["y"]

[[loads]]
type = "surface"
direction = [0, 0, -1]
magnitude = 10.0

[[probes]]
name = "s11"
quantity = "stress"
point = [1.0, 0.25, 0.0]
theta3 = 0.1
component = "11"

[[probes]]
name = "sxx"
quantity = "stress"
point = [1.0, 0.25, 0.0]
theta3 = 0.1
component = "11"
frame = "global"
"""


def write_strip(folder, clockwise: bool):
    """The strip's 8 × 2 mesh as a Gmsh file: numbered clockwise seen from +z (A_1 along +y, normal
    -z), or counter-clockwise from the generator (A_1 along +x, normal +z)."""
    m = rectangle(2.0, 0.5, 8, 2)
    cells = m.elements[:, CLOCKWISE] if clockwise else m.elements
    meshio.write(folder / "strip.msh", meshio.Mesh(m.nodes, [("quad9", cells)]), file_format="gmsh22", binary=False)


def spec_of(folder, clockwise: bool, direction: str = ""):
    write_strip(folder, clockwise)
    return build(parse(MODEL.format(direction=direction), "strip.toml"), folder)


def test_clockwise_mesh_file_is_noted(tmp_path):
    spec = spec_of(tmp_path, clockwise=True)
    assert set(first_line_directions(spec.model)) == {"+y"}
    notes = [w for w in spec.warnings if "has no 'direction'" in w]
    assert len(notes) == 1, spec.warnings
    assert "layer 'concrete'" in notes[0] and "global +y in 16 of 16 elements" in notes[0]
    assert "direction = [1, 0, 0]" in notes[0]


def test_counter_clockwise_or_with_direction_no_note(tmp_path):
    assert not [w for w in spec_of(tmp_path, clockwise=False).warnings if "has no 'direction'" in w]
    spec = spec_of(tmp_path, clockwise=True, direction="direction = [1, 0, 0]")
    assert not [w for w in spec.warnings if "has no 'direction'" in w]


def test_the_named_fix_makes_sigma11_sigma_xx(tmp_path):
    """On the clockwise mesh "σ11" at the soffit is σ_yy (about 0 in a strip free to contract
    sideways); with the fix the note names it is σ_xx, within 3 % of the simple beam's bending
    stress 6 M/(b h²), M = q b l²/8: 3000 kN/m² (measured 3025; σ_yy 67)."""
    plain = run(spec_of(tmp_path, clockwise=True), None, write_vtu=False).summary["probes"]
    fixed = run(spec_of(tmp_path, clockwise=True, direction="direction = [1, 0, 0]"), None,
                write_vtu=False).summary["probes"]
    beam = 6 * (10.0 * 2.0**2 / 8) / 0.1**2
    assert fixed["sxx"] == pytest.approx(beam, rel=0.03)
    assert fixed["s11"] == pytest.approx(fixed["sxx"], rel=1e-9)
    assert abs(plain["s11"]) < 0.1 * beam  # σ_yy, not σ_xx
    assert plain["sxx"] == pytest.approx(fixed["sxx"], rel=1e-9)
