"""Reaction and stress-resultant probes, supports on faces / through the thickness, loads at a
height, the shifter in volume loads, mid-surface meshes (issue 15)."""
from __future__ import annotations

import numpy as np
import pytest

from layershell.io.build import InputError, build, parse
from layershell.runner import run

CANTILEVER = """
[model]
units = "kN, m"
nonlinear = false

[mesh]
type = "rectangle"
lx = 1.0
ly = 3.0
nx = 1
ny = 6

[materials.a]
type = "isotropic"
E = 3.0e7
nu = 0.0

[materials.b]
type = "isotropic"
E = 7.0e7
nu = 0.0

[[layers]]
name = "bottom"
material = "b"
thickness = 0.02
directors = 2

[[layers]]
name = "top"
material = "a"
thickness = 0.14
directors = 3

[[supports]]
type = "fix"
where = "near(y, 0)"
layer = "bottom"
directors = "all"

[[supports]]
type = "fix"
where = "near(y, 0)"
layer = "top"
directors = [1, 2, 3]

[[loads]]
type = "surface"
face = "top"
direction = [0, 0, -1]
magnitude = 48.0

[[probes]]
name = "Rz"
quantity = "reaction"
where = "near(y, 0)"
component = "z"

[[probes]]
name = "Mx"
quantity = "reaction"
where = "near(y, 0)"
component = "mx"

[[probes]]
name = "Ry"
quantity = "reaction"
where = "near(y, 0)"
component = "y"

[[probes]]
name = "m"
quantity = "resultant"
point = [0.5, 1.0, 0]
direction = [0, 1, 0]
component = "m"

[[probes]]
name = "q"
quantity = "resultant"
point = [0.5, 1.0, 0]
direction = [0, 1, 0]
component = "q"

[[probes]]
name = "n"
quantity = "resultant"
point = [0.5, 1.0, 0]
direction = [0, 1, 0]
component = "n"
"""


def _run(text):
    return run(build(parse(text)), None, write_vtu=False)


def test_reaction_and_resultant_of_a_cantilever_strip():
    """A clamped strip (ν = 0: cylindrical bending) under 48 kN/m² on its top face, 1 m wide,
    3 m long: statics gives R_z = 144 kN, the moment about the x axis through the origin
    M_x = -q·b·L²/2 (the load's lever arm about the x axis is y) → the support moment +216,
    and at y = 1 m the section moment m = q (L − y)²/2 = 96 kNm/m (top in tension) and no
    normal force."""
    res = _run(CANTILEVER)
    p = res.summary["probes"]
    assert p["Rz"] == pytest.approx(144.0, rel=1e-8)
    assert abs(p["Ry"]) < 1e-8 * 144
    # the load acts at z = H (top face); its moment about the x axis: Σ y × F_z = -q b L²/2
    assert p["Mx"] == pytest.approx(48.0 * 3.0**2 / 2, rel=1e-8)
    assert p["m"] == pytest.approx(96.0, rel=5e-3)  # mean of the two elements at the node line: 96.27
    assert abs(p["n"]) < 1e-3 * 96.0 / 0.16


def test_reaction_probe_rejects_bad_component():
    text = CANTILEVER.replace('component = "mx"', 'component = "w"')
    with pytest.raises(InputError, match="reaction probe needs component"):
        build(parse(text))
