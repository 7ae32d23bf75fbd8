"""The shell-of-revolution generator (mesh.revolution): geometry against analytic areas, segments
(straight/arc), element and node sets, thickness per meridian point, the hoop material axis, and
the model-file errors; plus a linear hemispherical dome against the membrane solution."""
from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import quad

from layershell.element.geometry import surface_points
from layershell.element.kernel import material_frame
from layershell.element.quadrature import gauss_2d
from layershell.io.build import InputError, build, parse
from layershell.mesh import MeridianSegment, MeshError, revolution
from layershell.runner import run

R, R_OPEN = 6.64, 1.5
Z_OPEN = float(np.sqrt(R**2 - R_OPEN**2))


def _areas(mesh) -> np.ndarray:
    pts, w = gauss_2d(3)
    sp = surface_points(mesh.nodes[mesh.elements], pts[:, 0], pts[:, 1])
    return (sp.sqrtA * w).sum(1)


def _dome(n_dome=4, n_circ=20, thickness=None):
    """Lower ring (vertical, 1 row) + spherical zone (arc, n_dome rows) + upper ring (1 row)."""
    return revolution([R, R, R_OPEN, R_OPEN], [-0.6, 0.0, Z_OPEN, Z_OPEN + 0.3], None, n_circ, 360.0, "outward",
                      segments=[MeridianSegment(1, "lower_ring"), MeridianSegment(n_dome, "dome", (0.0, 0.0)),
                                MeridianSegment(1, "upper_ring")], thickness=thickness)


def test_spherical_zone_area_and_nodes_on_the_sphere():
    m = _dome()
    m.check()
    dome = m.element_sets["dome"]
    # analytic area of a spherical zone: 2 π R (z1 - z0); quadratic elements on exact arc nodes
    area = _areas(m)[dome].sum()
    assert area == pytest.approx(2 * np.pi * R * Z_OPEN, rel=2e-4)
    nodes = np.unique(m.elements[dome])
    assert np.allclose(np.linalg.norm(m.nodes[nodes], axis=1), R, rtol=1e-12)
    # the rings: vertical cylinders of heights 0.6 and 0.3
    assert _areas(m)[m.element_sets["lower_ring"]].sum() == pytest.approx(2 * np.pi * R * 0.6, rel=2e-4)
    assert _areas(m)[m.element_sets["upper_ring"]].sum() == pytest.approx(2 * np.pi * R_OPEN * 0.3, rel=2e-4)


def test_polyline_meridian_is_resampled_by_arc_length():
    # a cone frustum: area π (r0 + r1) s
    m = revolution([2.0, 1.0], [0.0, 1.0], 3, 12, 360.0, "outward")
    m.check()
    assert _areas(m).sum() == pytest.approx(np.pi * 3.0 * np.sqrt(2.0), rel=1e-3)
    assert m.element_sets == {} and "h_meridian" not in m.node_fields


def test_sets_counts_and_closed_seam():
    m = _dome()
    assert m.n_elements == 120
    assert {k: v.size for k, v in m.element_sets.items()} == {"lower_ring": 20, "dome": 80, "upper_ring": 20}
    assert sorted(np.concatenate(list(m.element_sets.values()))) == list(range(120))
    # closed: 40 nodes around, 2 * 6 + 1 = 13 node circles
    assert m.n_nodes == 40 * 13
    z = {k: np.unique(np.round(m.nodes[m.node_sets[f"meridian_point_{k}"], 2], 9)) for k in range(4)}
    assert [float(v[0]) for v in z.values()] == pytest.approx([-0.6, 0.0, Z_OPEN, Z_OPEN + 0.3])
    assert all(m.node_sets[f"meridian_point_{k}"].size == 40 for k in range(4))
    assert np.array_equal(np.sort(m.node_sets["first"]), np.sort(m.node_sets["meridian_point_0"]))
    assert np.array_equal(np.sort(m.node_sets["last"]), np.sort(m.node_sets["meridian_point_3"]))
    # element centres of the sets lie where they should
    c = m.nodes[m.elements[:, 8]]
    assert np.all(c[m.element_sets["lower_ring"], 2] < 0)
    assert np.all(c[m.element_sets["upper_ring"], 2] > Z_OPEN)
    dz = c[m.element_sets["dome"], 2]
    assert np.all((dz > 0) & (dz < Z_OPEN))


def test_normal_and_hoop_material_axis():
    m = _dome()
    sp = surface_points(m.nodes[m.elements], np.zeros(1), np.zeros(1))
    c = m.nodes[m.elements[:, 8]]
    er = c * [1, 1, 0] / np.hypot(c[:, 0], c[:, 1])[:, None]
    # 'outward': A3 points away from the axis (reference face = inner face)
    assert np.all(np.einsum("ei,ei->e", sp.A3[:, 0], er) > 0.2)
    # the element's first coordinate line is the hoop direction: axis 1 of a layer without 'direction'
    M1 = material_frame(sp)[:, 0, 0]
    hoop = np.cross([0, 0, 1.0], er)
    assert np.allclose(np.abs(np.einsum("ei,ei->e", M1, hoop)), 1.0, atol=1e-9)
    m_in2 = revolution([R, R_OPEN], [0.0, Z_OPEN], None, 8, 360.0, "inward",
                       segments=[MeridianSegment(2, "dome", (0.0, 0.0))])
    sp2 = surface_points(m_in2.nodes[m_in2.elements], np.zeros(1), np.zeros(1))
    c2 = m_in2.nodes[m_in2.elements[:, 8]]
    assert np.all(np.einsum("ei,ei->e", sp2.A3[:, 0], c2 * [1, 1, 0]) < 0)  # 'inward'


def test_thickness_per_meridian_point_is_linear_along_the_arc():
    m = _dome(thickness=[0.86, 0.86, 0.14, 0.30])
    h = m.node_fields["h_meridian"]
    assert h.shape == (m.n_nodes,)
    x = m.nodes
    ring = x[:, 2] < -1e-9
    assert np.allclose(h[ring], 0.86)
    # on the sphere: linear in the meridian angle from 0.86 at the equator to 0.14 at the opening
    on = (x[:, 2] >= -1e-9) & (x[:, 2] <= Z_OPEN + 1e-9)
    ang = np.arctan2(x[on, 2], np.hypot(x[on, 0], x[on, 1]))
    top = np.arctan2(Z_OPEN, R_OPEN)
    assert np.allclose(h[on], 0.86 + (0.14 - 0.86) * ang / top, atol=1e-12)
    upper = x[:, 2] > Z_OPEN + 1e-9
    assert np.allclose(h[upper], 0.14 + 0.16 * (x[upper, 2] - Z_OPEN) / 0.3)


DOME_TOML = f"""
[model]
nonlinear = false
[mesh]
type = "revolution"
normal = "outward"
n_circ = 8
meridian_r = [{R}, {R}, {R_OPEN}]
meridian_z = [-0.5, 0.0, {Z_OPEN!r}]
meridian_thickness = [0.5, 0.5, 0.14]
segments = [{{ elements = 1, set = "ring" }}, {{ elements = 2, set = "dome", arc_center = [0.0, 0.0] }}]
[materials.c]
type = "isotropic"
E = 1.0e7
nu = 0.2
[[layers]]
name = "c"
material = "c"
thickness = "h_meridian"
directors = 2
[[layers]]
name = "t"
material = "c"
thickness = 0.015
directors = 2
[[stacks]]
layers = ["c", "t"]
set = "dome"
[[stacks]]
layers = ["c"]
set = "ring"
[[supports]]
type = "fix"
set = "first"
"""


def test_model_file_thickness_table_and_sets():
    spec = build(parse(DOME_TOML, "dome"))
    m = spec.model.mesh
    assert np.allclose(spec.model.layers[0].thickness, m.node_fields["h_meridian"])
    assert spec.model.layers[0].thickness.max() == pytest.approx(0.5)
    assert spec.model.layers[0].thickness.min() == pytest.approx(0.14)
    assert np.array_equal(np.flatnonzero(spec.model.element_stack == 0), m.element_sets["dome"])


@pytest.mark.parametrize("old, new, words", [
    ("meridian_thickness = [0.5, 0.5, 0.14]", "meridian_thickness = [0.5, 0.14]", ["meridian_thickness", "3"]),
    ("meridian_thickness = [0.5, 0.5, 0.14]", "meridian_thickness = [0.5, -0.5, 0.14]", ["meridian_thickness"]),
    ('{ elements = 1, set = "ring" }, ', "", ["segments", "2"]),
    ("n_circ = 8", "n_circ = 8\nn_meridian = 3", ["n_meridian", "segments"]),
    ("arc_center = [0.0, 0.0]", "arc_center = [0.0, 1.0]", ["segments[1].arc_center", "equally far"]),
    ("arc_center = [0.0, 0.0]", "arc_center = [0.0]", ["arc_center"]),
    ('thickness = "h_meridian"', 'thickness = "h_meridan"', ["layers[0].thickness", "h_meridian"]),
])
def test_model_file_errors_name_the_field(old, new, words):
    assert old in DOME_TOML
    with pytest.raises(InputError) as exc:
        build(parse(DOME_TOML.replace(old, new), "dome"))
    for w in words:
        assert w in str(exc.value), str(exc.value)


def test_half_circle_arc_is_rejected():
    with pytest.raises(MeshError, match="half circle"):
        revolution([1.0, 1.0], [-1.0, 1.0], None, 8, 360.0, "outward", segments=[MeridianSegment(2, None, (1.0, 0.0))])


# ------------------------------------------------------------------ membrane theory check
def membrane_sphere(Rm: float, t: float, E: float, nu: float, p: float, phi0: float, phi: np.ndarray):
    """Membrane theory of a spherical zone (mid-surface radius Rm, apex angle from phi0 to the equator)
    with a free upper edge under a vertical load p per mid-surface area (Timoshenko & Woinowsky-Krieger,
    §129): N_φ = -p Rm (cos φ0 - cos φ)/sin²φ, N_θ from the normal equilibrium. Returns the horizontal
    displacement u_r(φ) = Rm sin φ ε_θ and the downward displacement of the upper edge relative to the
    equator, integrated along the meridian (du_r/ds = ε_φ cos φ + χ sin φ, du_z/ds = -ε_φ sin φ + χ cos φ)."""
    n_phi = lambda f: -p * Rm * (np.cos(phi0) - np.cos(f)) / np.sin(f) ** 2
    n_th = lambda f: p * Rm * ((np.cos(phi0) - np.cos(f)) / np.sin(f) ** 2 - np.cos(f))
    e_phi = lambda f: (n_phi(f) - nu * n_th(f)) / (E * t)
    u_r = lambda f: Rm * np.sin(f) * (n_th(f) - nu * n_phi(f)) / (E * t)

    def duz(f, h=1e-6):
        chi = ((u_r(f + h) - u_r(f - h)) / (2 * h) / Rm - e_phi(f) * np.cos(f)) / np.sin(f)
        return Rm * (-e_phi(f) * np.sin(f) + chi * np.cos(f))

    w_top = quad(duz, phi0, np.pi / 2, limit=200)[0]
    return u_r(np.asarray(phi)), w_top


def test_hemispherical_dome_matches_membrane_theory():
    """Linear spherical zone (R = 6.64 m inner, t = 0.14 m, opening r = 1.5 m) under 1 kN/m² vertical,
    held vertically at mid-thickness along the equator (sliding hinge: the membrane support):
    radial displacements away from the edges and the top-edge deflection vs membrane theory."""
    t, E, nu = 0.14, 1.41e7, 0.2
    text = f"""
[model]
nonlinear = false
[mesh]
type = "revolution"
normal = "outward"
n_circ = 12
meridian_r = [{R}, {R_OPEN}]
meridian_z = [0.0, {Z_OPEN!r}]
segments = [{{ elements = 8, set = "dome", arc_center = [0.0, 0.0] }}]
[materials.c]
type = "isotropic"
E = {E}
nu = {nu}
[[layers]]
name = "c"
material = "c"
thickness = {t}
directors = 2
[[supports]]
type = "hinge"
set = "first"
direction = [0, 0, 1]
height = {t / 2}
fixed = false
[[supports]]            # rigid-body motion in the x-y plane, leaving the radial expansion free
type = "fix"
where = "near(z, 0) and near(y, 0)"
components = ["y"]
[[supports]]
type = "fix"
where = "near(z, 0) and near(x, 0) and y > 0"
components = ["x"]
[[loads]]
type = "surface"
direction = [0, 0, -1]
magnitude = 1.0
[[probes]]
name = "w_top"
quantity = "displacement"
set = "last"
theta3 = {t / 2}
component = "z"
scale = -1.0
reduce = "mean"
"""
    spec = build(parse(text, "hemisphere"))
    res = run(spec, None, write_vtu=False)
    m, D, u = spec.model.mesh, res.problem.dm.layer_dofs[0], res.u
    Rm = R + t / 2
    p = (R / Rm) ** 2  # 1 kN/m² of the inner (reference) face per mid-surface area
    phi0 = np.arcsin(R_OPEN / R)
    # mid-surface radial displacement along the meridian y = 0, x > 0
    sel = np.flatnonzero((np.abs(m.nodes[:, 1]) < 1e-9) & (m.nodes[:, 0] > 0))
    um = u[D[sel, 0]] + t / 2 * u[D[sel, 1]] + (t / 2) ** 2 * u[D[sel, 2]]
    phi = np.arctan2(m.nodes[sel, 0], m.nodes[sel, 2])
    ur_mem, w_mem = membrane_sphere(Rm, t, E, nu, p, phi0, phi)
    inner = (phi > phi0 + np.radians(12)) & (phi < np.radians(80))  # beyond the edge bending zones
    assert inner.sum() >= 8
    err = np.abs(um[inner, 0] - ur_mem[inner]).max() / np.abs(ur_mem).max()
    assert err < 0.03, err
    # downward deflection of the free upper edge: membrane 3.79e-5 m
    assert w_mem == pytest.approx(3.792e-5, rel=1e-3)
    assert res.summary["probes"]["w_top"] == pytest.approx(w_mem, rel=0.06)
