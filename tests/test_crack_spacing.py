"""Crack spacing after EN 1992-1-1 §7.3.4: the in-plane crack band of a concrete layer with bars
(the bars' mean crack spacing where elements are shorter), its input, and the notes where a layer
keeps the element band.

References: the spacing worked by hand; the fracture energy (a layer cracked through at the
spacing s dissipates G_F per crack area, G_F/s per unit volume, on any mesh)."""
import math
from pathlib import Path

import numpy as np
import pytest

from layershell.analytic.crack_spacing import max_crack_spacing, mean_crack_spacing
from layershell.element.inelastic import in_plane_band
from layershell.io.build import build, load, parse
from layershell.io.errors import InputError
from layershell.laws import ConcreteLaw
from layershell.material import MaterialError
from layershell.runner import run
from test_strengthened_strip import TRC

EXAMPLE = Path(__file__).resolve().parents[1] / "examples" / "rc_strip.toml"


def test_max_crack_spacing_by_hand():
    """The RC strip's 5 Ø10/m at 30 mm from the soffit of a 160 mm slab, worked by hand: c = 25 mm,
    h_c,ef = min(2.5 · 30, 80) = 75 mm, ρ = (π 25/200)/75 = 0.0052360, s_r,max = 3.4 · 25 +
    0.8 · 0.5 · 0.425 · 10/0.0052360 = 85 + 324.68 = 409.68 mm; s_rm = 409.68/1.7 = 240.99 mm."""
    a = math.pi * 25.0 / 200.0
    assert max_crack_spacing(25.0, 10.0, a, 160.0) == pytest.approx(409.68, abs=0.01)
    assert mean_crack_spacing(25.0, 10.0, a, 160.0) == pytest.approx(240.99, abs=0.01)
    # a thin slab: h/2 limits the effective depth (2.5 · 30 = 75 > 60/2 = 30), pure tension k2 = 1
    assert max_crack_spacing(25.0, 10.0, a, 60.0, k2=1.0) == pytest.approx(85 + 0.8 * 0.425 * 10 / (a / 30), rel=1e-12)
    with pytest.raises(MaterialError, match="'cover'"):
        max_crack_spacing(0.0, 10.0, a, 160.0)


def strip_file(tmp_path, nx: int, layer_line: str = "", rebar: tuple[str, str] | None = None) -> Path:
    """examples/rc_strip.toml with ``nx`` elements, ``layer_line`` added to its layer and the
    reinforcement text ``rebar`` replaced."""
    text = EXAMPLE.read_text(encoding="utf-8").replace("nx = 6\n", f"nx = {nx}\n")
    text = text.replace("directors = 2\n", f"directors = 2\n{layer_line}\n")
    if rebar:
        assert rebar[0] in text
        text = text.replace(*rebar)
    model = tmp_path / "strip.toml"
    model.write_text(text, encoding="utf-8")
    return model


def test_layer_with_bars_takes_their_mean_crack_spacing(tmp_path):
    """The strip's layer takes s_rm = 240.99 mm (worked above); given, crack_spacing replaces it;
    0 keeps the element band; concrete layers without steel bars (the IC debonding example's, the
    TRC strip's mortar with its textile) keep it."""
    law = load(strip_file(tmp_path, 6)).model.layers[0].law
    assert law.crack_spacing == pytest.approx(240.99, abs=0.01)
    assert load(strip_file(tmp_path, 6, "crack_spacing = 150.0")).model.layers[0].law.crack_spacing == 150.0
    assert load(strip_file(tmp_path, 6, "crack_spacing = 0")).model.layers[0].law.crack_spacing == 0.0
    ic = load(EXAMPLE.with_name("rc_strip_ic_debonding.toml")).model
    assert [ly.law.crack_spacing for ly in ic.layers if hasattr(ly.law, "f_ct")] == [0.0, 0.0]
    trc = build(parse(TRC.replace("crack_spacing = 0 ", "# "))).model  # the TRC strip, its slab on the bars
    assert [ly.law.crack_spacing for ly in trc.layers] == [pytest.approx(240.99, abs=0.01), 0.0]  # mortar: textile


def test_crack_band_is_the_spacing_where_elements_are_shorter():
    """In-plane tension cracks take max(h_in, s), cracks parallel to the surface h_z, crushing
    h_in; a concrete without spacing keeps h_in (uniaxial stress states of the law)."""
    plain = ConcreteLaw.from_class(30.0, 1.0, 1e-3)
    rc = ConcreteLaw.from_class(30.0, 1.0, 1e-3, crack_spacing=200.0)
    z = np.array([[0.0, 0.0, 1.0]] * 3)
    eps_x = np.array([[2e-4, 0, 0, 0, 0, 0], [-5e-3, 0, 0, 0, 0, 0], [0, 0, 2e-4, 0, 0, 0]])  # x, x, z
    h_in, h_z = np.array([50.0, 50.0, 50.0]), np.array([20.0, 20.0, 20.0])
    for law, band in ((rc, 200.0), (plain, 50.0)):
        _, _, trial = law.response(eps_x, law.state(3), h_in, h_z, z, tangent=False)
        assert trial.h_t[0] == pytest.approx(band) and trial.h_t[2] == pytest.approx(20.0)
        assert trial.h_c[1] == 50.0
    wide = ConcreteLaw.from_class(30.0, 1.0, 1e-3, crack_spacing=400.0)
    _, _, trial = wide.response(eps_x[:1], wide.state(1), [500.0], [20.0], z[:1], tangent=False)
    assert trial.h_t[0] == pytest.approx(500.0)  # elements longer than the spacing keep their band


@pytest.mark.parametrize("layer_line, field, fix", [
    ("crack_spacing = -5.0", "layers[0].crack_spacing", "greater than or equal to 0"),
    ("crack_spacing = 1200.0", "layers[0].crack_spacing", "snap-back limit"),
])
def test_bad_crack_spacing_names_the_field_and_the_fix(tmp_path, layer_line, field, fix):
    with pytest.raises((InputError, ValueError)) as err:
        load(strip_file(tmp_path, 6, layer_line))
    assert field in str(err.value) and fix in str(err.value), str(err.value)


def test_crack_spacing_needs_a_concrete_layer(tmp_path):
    text = strip_file(tmp_path, 6, "crack_spacing = 100.0").read_text(encoding="utf-8")
    text = text.replace('type = "concrete"\nstrength_class = "C30/37"', 'type = "isotropic"\nE = 30000.0\nnu = 0.2')
    (tmp_path / "elastic.toml").write_text(text, encoding="utf-8")
    with pytest.raises(InputError, match=r"'layers\[0\].crack_spacing': .*no concrete material"):
        load(tmp_path / "elastic.toml")


@pytest.mark.parametrize("nx, layer_line, noted", [(6, "", False), (15, "", False), (6, "crack_spacing = 0", False),
                                                   (12, "crack_spacing = 0", False), (15, "crack_spacing = 0", True)])
def test_note_on_elements_shorter_than_the_crack_spacing(tmp_path, nx, layer_line, noted):
    """On the bars' spacing no mesh is noted; with crack_spacing = 0 bands of 181 and 128 mm pass,
    114 mm (< s_rm/2 = 120.5 mm) gets the note with s_rm."""
    notes = [w for w in load(strip_file(tmp_path, nx, layer_line)).warnings if "mean crack spacing" in w]
    assert bool(notes) == noted
    if noted:
        assert "241" in notes[0] and "layer 'slab'" in notes[0]


def test_bars_given_by_area_are_noted(tmp_path):
    """Bars by area give no spacing: the layer keeps the element band and the run says so; a
    given crack_spacing takes its place."""
    area = ("bar_diameter = 10.0, spacing = 200.0", f"area = {math.pi * 25.0 / 200.0}")
    spec = load(strip_file(tmp_path, 6, rebar=area))
    assert spec.model.layers[0].law.crack_spacing == 0.0
    assert any("given by area" in w and "crack_spacing" in w for w in spec.warnings)
    spec = load(strip_file(tmp_path, 6, "crack_spacing = 241.0", rebar=area))
    assert not any("given by area" in w for w in spec.warnings)


def tie_model(nx: int, layer_line: str = "") -> str:
    """A reinforced concrete tie 400 mm long, 100 mm thick (one Ø10 bar per 100 mm at mid-depth),
    its ends pulled apart through the thickness by 0.8 mm (a mean strain of 0.002, the bars below
    yield); nx square elements along it, one across."""
    return f"""
[model]
units = "N, mm"
nonlinear = false
thickness_points = 4

[mesh]
type = "rectangle"
lx = 400.0
ly = {400.0 / nx}
nx = {nx}
ny = 1

[materials.c30]
type = "concrete"
strength_class = "C30/37"

[materials.b500]
type = "steel"
grade = "B500B"

[[layers]]
name = "tie"
material = "c30"
thickness = 100.0
directors = 1
reinforcement = [{{material = "b500", height = 50.0, bar_diameter = 10.0, spacing = 100.0, direction = [1, 0, 0]}}]
{layer_line}

[[supports]]
type = "fix"
where = "near(x, 0)"
components = ["x"]
directors = "all"

[[supports]]
type = "fix"
where = "near(x, 0) and near(y, 0)"
components = ["y"]

[[supports]]
type = "fix"
where = "near(x, 0) or near(x, 400)"
components = ["z"]

[[supports]]
type = "fix"
where = "near(x, 400)"
components = ["x"]
directors = "all"
value = [0.8]

[steps]
n = 20
tolerance = 1e-6
"""


def tie_energy(nx: int, layer_line: str = "") -> float:
    """The energy the tie dissipates per unit volume (the bars stay elastic: all of it the concrete's)."""
    spec = build(parse(tie_model(nx, layer_line)))
    res = run(spec, None, write_vtu=False)
    assert res.converged
    st = res.problem.assembler.materials.committed[0]
    f_y = spec.model.layers[0].reinforcement[0].law.f_y
    assert st.sheet_stress[0].max() < f_y  # no steel dissipation
    return res.summary["steps"][-1]["dissipated_material"] / (400.0 / nx * 100.0 * 400.0)


def test_reinforced_tie_dissipates_G_F_per_crack_spacing_on_any_mesh():
    """The tie cracked through on elements of 200, 100 and 50 mm (bands 144, 72, 36 mm, below the
    bars' s_rm of 154 mm: cover 45 mm, h_c,ef = 50 mm, k2 = 0.5) dissipates G_F/s_rm per unit volume
    (one crack area per s_rm of length; the residual tension at a mean strain of 0.002 leaves
    0.9 to 1.5 % undissipated), the three within 2 % of each other. On the element band
    (crack_spacing = 0) the 50 mm elements dissipate G_F per element band instead: over twice."""
    s_rm = mean_crack_spacing(45.0, 10.0, math.pi * 25.0 / 100.0, 100.0)
    ref = ConcreteLaw.from_class(30.0, 1.0, 1e-3).G_F / s_rm
    e = np.array([tie_energy(nx) for nx in (2, 4, 8)]) / ref
    assert np.all((e > 0.95) & (e < 1.0)), e
    assert e.max() - e.min() < 0.02, e
    assert tie_energy(8, "crack_spacing = 0") / ref > 2.0
