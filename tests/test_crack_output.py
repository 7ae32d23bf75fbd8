"""Outputs of concrete layers that engineers read: the plan figure of the crack pattern, and the
surface files' crack normal, minimum principal stress and reinforcement state per element."""
from __future__ import annotations

from types import SimpleNamespace

import meshio
import numpy as np
import pytest

from layershell import material_output as mo
from layershell.analytic.rc_section import transformed_uncracked
from layershell.crack_plot import plot_cracks
from layershell.element.inelastic import BAND_FRACTION
from layershell.export import material_cell_fields
from layershell.io.build import build, parse
from layershell.mesh import rectangle
from layershell.runner import run
from test_concrete_layer import B500, C30, section, strip_model

ANGLE = 30.0  # degrees of the bar's axis from x
LENGTH, WIDTH, NX, PULL = 400.0, 100.0, 4, 0.2  # mm; the end's displacement at λ = 1


def bar_model(n: int) -> str:
    """A plain concrete bar 400 × 100 × 50 mm along the direction d at ANGLE from x (mesh file
    bar.vtu), its ends' sections held and pulled apart by PULL along d (implicit damage: the
    reaction and the crack widths of the same state)."""
    c, s = np.cos(np.deg2rad(ANGLE)), np.sin(np.deg2rad(ANGLE))
    end = f'type = "fix"\ndirection = [{c}, {s}, 0]\ndirectors = "all"'
    return f"""
[model]
units = "N, mm"
nonlinear = false
[mesh]
type = "file"
path = "bar.vtu"
[materials.c30]
type = "concrete"
strength_class = "C30/37"
[[layers]]
name = "plate"
material = "c30"
thickness = 50.0
directors = 1
[[supports]]
{end}
where = "near({c}*x + {s}*y, 0)"
[[supports]]
{end}
where = "near({c}*x + {s}*y, {LENGTH})"
value = [{PULL}]
[[supports]]
type = "fix"
point = [0, 0, 0]
components = ["x", "y"]
[[supports]]
type = "fix"
where = "z < 1"
components = ["z"]
[steps]
n = {n}
integration = "implicit"
[[probes]]
name = "crack"
quantity = "crack_width"
layer = "plate"
[[probes]]
name = "R"
quantity = "reaction"
where = "near({c}*x + {s}*y, {LENGTH})"
component = "x"
"""


def test_cracks_of_a_bar_pulled_at_an_angle_lie_across_the_load(tmp_path):
    """Uniaxial tension along d at 30° from x: every point cracks with its normal along d, the
    figure's segments run along d's normal in plan, the surface files' crack normal is ±d; the
    widths are the probe's and, the crack spread evenly over the bar (uniform stress), the
    opening δ − N L/(E A) shared out over the bands: w = (δ − N L/(E A)) h/L."""
    c, s = np.cos(np.deg2rad(ANGLE)), np.sin(np.deg2rad(ANGLE))
    m = rectangle(LENGTH, WIDTH, NX, 1)
    rot = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    meshio.write(tmp_path / "bar.vtu", meshio.Mesh(m.nodes @ rot.T, [("quad9", m.elements)]))
    res = run(build(parse(bar_model(10)), tmp_path), tmp_path / "out", write_vtu=False)
    assert res.converged
    model = res.problem.model
    last = res.summary["steps"][-1]["probes"]
    path, info = plot_cracks(tmp_path / "cracks.png", model, 0, 1.0)
    assert path.stat().st_size > 0
    pat = mo.crack_pattern(model, 0)
    d = np.array([c, s, 0.0])
    assert info["cracked_points"] == pat.width.size == NX * 9 and np.all(pat.width > 0)
    assert np.allclose(np.abs(pat.normal @ d), 1.0, atol=1e-9)
    seg = info["segments"][:, 1] - info["segments"][:, 0]
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    assert np.allclose(np.abs(seg @ [-s, c]), 1.0, atol=1e-9)
    cells = material_cell_fields(model)
    assert np.allclose(np.abs(cells["crack_normal_plate"] @ d), 1.0, atol=1e-9)
    assert info["max_width"] == pytest.approx(last["crack"], rel=1e-12)
    N = last["R"] / c  # the end's reaction is along d
    h = BAND_FRACTION * np.sqrt(LENGTH / NX * WIDTH)
    w_ref = (PULL - N * LENGTH / (C30.E * WIDTH * 50.0)) * h / LENGTH
    assert pat.width == pytest.approx(w_ref, rel=1e-6)
    # uniaxial: the other principal stresses are zero (compared with the axial one)
    assert np.abs(cells["min_principal_plate"]).max() < 1e-9 * N / (WIDTH * 50.0)


def test_strip_shows_flexural_cracks_and_its_compression(tmp_path):
    """The RC strip: after the run a cracks_slab.png; in the constant-moment zone (x > 1 m)
    every in-plane point cracked and each crack a line across the strip (along y), the surface
    files' crack normal along x there. Elastic (0.5 mm): the most compressive principal stress of
    the element at midspan is the transformed section's at the uppermost thickness point."""
    res = run(build(parse(strip_model(6, 6, value=-6.0))), tmp_path / "cracked", write_vtu=True)
    assert res.converged and (tmp_path / "cracked" / "cracks_slab.png").stat().st_size > 0
    model = res.problem.model
    pat = mo.crack_pattern(model, 0)
    zone = pat.x[:, 0] > 1000.0
    assert zone.sum() == 18 and np.all(pat.width[zone] > 0)
    assert np.all(np.abs(pat.line[zone, 1]) > 0.999)
    assert pat.width.max() == pytest.approx(res.summary["steps"][-1]["probes"]["crack"], rel=1e-12)
    surf = meshio.read(sorted((tmp_path / "cracked").glob("surface_*.vtu"))[-1])
    nrm = surf.cell_data["crack_normal_slab"][0]
    centre_x = model.mesh.nodes[model.mesh.elements[:, 8], 0]
    assert np.all(np.abs(nrm[centre_x > 1000.0, 0]) > 0.999)
    assert np.all(nrm[surf.cell_data["crack_width_slab"][0] == 0] == 0.0)
    state = surf.cell_data["rebar_state_slab_b500_1"][0]
    assert np.array_equal(state, np.zeros(6))  # the bars' stress stays below f_y (340 MPa at 6 mm)

    el = run(build(parse(strip_model(6, 1, value=-0.5))), tmp_path / "elastic", write_vtu=False)
    assert el.summary.get("first_cracking_step") is None
    m = el.summary["steps"][-1]["probes"]["R"] * 1000.0 / 250.0  # N mm / mm at midspan
    z_bar, I_I = transformed_uncracked(section("none", 50.0))
    z_top = 80.0 * (1.0 - np.polynomial.legendre.leggauss(8)[0].max())  # depth of the uppermost point
    sigma_ref = -m * (z_bar - z_top) / (I_I / 1000.0)
    cells = material_cell_fields(el.problem.model)["min_principal_slab"]
    assert cells[5] == pytest.approx(sigma_ref, rel=0.01)  # the element at midspan, away from the load: -0.2 %


def test_reinforcement_state_is_elastic_yielded_or_ruptured():
    """Bars strained below f_y/E, beyond it and beyond eps_u: states 0, 1, 2; per element the
    largest."""
    eps = np.array([0.5, 0.9, 1.5, 3.0, 0.2, 1.0, 0.99, 1.2, 2.0]) * np.r_[[B500.f_y / B500.E] * 4, [B500.eps_u] * 5]
    _, _, st = B500.response(eps, B500.state(eps.size))
    sheet = SimpleNamespace(name="bars", law=B500, w=np.ones((1, 9)))
    blk = SimpleNamespace(sheets=(sheet,))
    model = SimpleNamespace(point_states={0: [(np.array([1]), blk, SimpleNamespace(sheets=(st,),
                                                                                      sheet_stress=(eps,)))]})
    codes, el = mo.sheet_states(model, 0, "bars")
    expect = np.where(eps >= B500.eps_u, 2, np.where(eps > B500.f_y / B500.E, 1, 0))
    assert np.array_equal(codes, expect) and np.array_equal(el, np.ones(9))
    assert np.array_equal(mo.per_element(3, codes, el), [np.nan, 2.0, np.nan], equal_nan=True)
