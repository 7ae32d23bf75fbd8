"""`layershell check` before a run: the layers that a support does not hold (connected to the
supported layer only through a cohesive or delaminating interface), and the cohesive process zone
against the node spacing. The command line runs in-process (typer's CliRunner) on a small
two-layer strip written into a temporary folder: 100 mm × 20 mm, two carbon/epoxy layers of
1.5 mm (E1 = 130 GPa, E3 = 9 GPa), a cohesive interface (σ_max = 57 MPa, G_Ic = 0.28 N/mm)."""
from __future__ import annotations

from pathlib import Path

import pytest
from typer.testing import CliRunner

from layershell.cli import app

STRIP = """
[model]
title = "two-layer strip"
units = "N, mm"
nonlinear = false

[mesh]
type = "rectangle"
lx = 100.0
ly = 20.0
nx = {nx}
ny = 1

[materials.cfrp]
type = "orthotropic"
E1 = 130000.0
E2 = 9000.0
E3 = 9000.0
G12 = 6000.0
G31 = 6000.0
G23 = 3500.0
nu12 = 0.3
nu31 = 0.0208
nu23 = 0.45

[[layers]]
name = "lower"
material = "cfrp"
thickness = 1.5

[[layers]]
name = "upper"
material = "cfrp"
thickness = 1.5

[[supports]]
type = "fix"
where = "near(x, 0)"
{support}

[[loads]]
type = "edge"
where = "near(x, 100)"
direction = [1, 0, 0]
distribution = 10.0

{interface}
"""

COHESIVE = """[[interfaces]]
layer = "upper"
law = "cohesive"
G_Ic = 0.28
G_IIc = 0.8
sigma_max = 57.0
tau_max = 80.0
"""

STRESS = """[[interfaces]]
layer = "upper"
sigma_max = 57.0
tau_max = 80.0
"""


PUSHED = 'layer = "lower"\ncomponents = ["x", "y", "z"]\nvalue = [0.5, 0.0, 0.0]'  # pulled along the strip


def _check(tmp_path: Path, nx: int = 200, support: str = PUSHED, interface: str = COHESIVE) -> str:
    (tmp_path / "strip.toml").write_text(STRIP.format(nx=nx, support=support, interface=interface))
    res = CliRunner().invoke(app, ["check", str(tmp_path / "strip.toml")])
    assert res.exit_code == 0, res.output
    assert "Traceback" not in res.output and "OK" in res.output
    return " ".join(res.output.split())


def _warnings(text: str, what: str) -> list[str]:
    return [w for w in text.split("warning: ")[1:] if what in w]


@pytest.mark.parametrize("interface, law", [(COHESIVE, "cohesive"), (STRESS, "stress criterion")])
def test_support_on_one_layer_names_the_layer_it_does_not_hold(tmp_path, interface, law):
    """The end x = 0 pulled along the strip by a prescribed displacement of the lower layer only:
    the upper layer is there, connected to it only through the interface, and no support holds
    it: a warning names the support, the layer it does not hold, the interface and its law, and
    the fix (layer = "all" or a support on the upper layer). Before, `check` said OK and nothing
    else."""
    text = _check(tmp_path, interface=interface)
    w = _warnings(text, "do(es) not hold")
    assert len(w) == 1, text
    assert "supports[0] on layer 'lower'" in w[0] and "['upper']" in w[0]
    assert f"interfaces[0] ('lower/upper', {law})" in w[0]
    assert 'layer = "all" in supports[0]' in w[0] and "at 3 of the 3 support node(s)" in w[0]


@pytest.mark.parametrize("support", [
    PUSHED.replace('"lower"', '"all"'),  # every layer moved
    PUSHED + '\n\n[[supports]]\ntype = "fix"\nwhere = "near(x, 0)"\nlayer = "upper"\ncomponents = ["x", "y", "z"]\n'
             'value = [0.5, 0.0, 0.0]',  # a support per layer
    'layer = "lower"',  # a clamp on one layer (the set-up of the thesis's plates): no shear pushed in
    'layer = "lower"\ncomponents = ["z"]\nvalue = [0.5]',  # moved along the normal only (a DCB arm)
])
def test_support_that_holds_every_layer_gives_no_warning(tmp_path, support):
    """The same prescribed displacement on all layers or one per layer moves the whole stack; a
    clamp at zero or a displacement along the normal pushes no shear into the interface: no
    warning."""
    assert not _warnings(_check(tmp_path, support=support), "do(es) not hold")


def test_support_across_a_bonded_interface_gives_no_warning(tmp_path):
    """Without an interface law the layers are bonded: a support on the lower one holds both."""
    assert not _warnings(_check(tmp_path, interface=""), "do(es) not hold")


def test_process_zone_against_the_node_spacing(tmp_path):
    """The strip's interface has a mode-I zone of 0.35 mm (thick-body estimate, M E'_I G_Ic/σ²,
    M = 1/π, E'_I = 12.8 GPa: the carbon/epoxy's crack-tip modulus; tests/test_process_zone.py
    measures 0.35 mm in a DCB of these arms), a mode-II zone of M E'_II G_IIc/τ² = 1.93 mm.
    200 elements along 100 mm have a node spacing of 0.25 mm: 1.40 spacings in the mode-I zone,
    fewer than 3: a warning with the node spacing needed (0.117 mm, elements of 0.234 mm);
    mode II spans 7.7 (no advice for it). 1000 elements
    (node spacing 0.05 mm): 7 spacings, no warning. Before, `check` gave no warning; the run
    warned when damage started, with a zone of 0.013 mm and elements of 0.009 mm."""
    w = _warnings(_check(tmp_path, nx=200), "process zone")
    assert len(w) == 1
    assert "interfaces[0] ('lower/upper')" in w[0]
    assert "mode I 0.3505 (thick-body estimate" in w[0] and "node spacing of 0.25 along" in w[0]
    assert "opens (mode I) the zone spans 1.40 node spacings" in w[0]
    assert "at most 0.117 (elements of 0.234)" in w[0] and "slides (mode II)" not in w[0]
    assert not _warnings(_check(tmp_path, nx=1000), "process zone")
