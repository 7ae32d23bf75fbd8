"""The plate-with-a-circle generator ([mesh] type = "plate_with_circle",
:func:`layershell.mesh_circle.plate_with_ellipse`): a rectangle with a circular or elliptical
front along element edges, a refined ring outside it and a butterfly grid inside.

References: the ellipse's equation (front nodes), the arc length of a circle (R Δθ) and of an
ellipse (scipy's adaptive quadrature, independent of the generator's Gauss rule), the areas
lx·ly and π a b, the constant-stress patch test (exact), Navier's double sine series for the
simply supported plate (Timoshenko & Woinowsky-Krieger §30) and the same model on the rectangle
generator's mesh, and the node selection of [[interfaces]] initially_debonded circle.
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import quad
from test_bad_input import _assert_error, _outcome
from test_cli import Case

from layershell.element.quadrature import gauss_2d
from layershell.element.shape import quad9
from layershell.io.build import build, parse
from layershell.mesh_circle import plate_with_ellipse
from layershell.runner import run

# (lx, ly, center, semi-axes, front_size, ring_width, ring_layers): centred circle, off-centre
# ellipse on a non-square plate, ellipse elongated along y, circle whose ring ends 0.5 from an edge
CASES = [
    (100.0, 100.0, (30.0, 80.0), (15.0, 15.0), 2.0, 4.5, 2),
    (150.0, 150.0, (75.0, 75.0), (20.0, 20.0), 2.0, 5.0, 3),
    (150.0, 100.0, (60.0, 55.0), (25.0, 12.0), 3.0, 5.0, 3),
    (36.0, 24.0, (10.0, 12.0), (3.0, 7.5), 1.0, 1.5, 2),
]


def _areas(m, elements=None) -> np.ndarray:
    """Area of each element (3×3 Gauss, exact for the quad9 map's Jacobian on a flat mesh)."""
    X = m.nodes[m.elements if elements is None else m.elements[elements]]
    pts, w = gauss_2d(3)
    _, dN, _ = quad9(pts[:, 0], pts[:, 1])
    A = np.einsum("qna,eni->eqai", dN, X)
    return np.einsum("eq,q->e", np.cross(A[:, :, 0], A[:, :, 1])[..., 2], w)


def _mesh(case, **kw):
    lx, ly, c, ab, h, w, nr = case
    return plate_with_ellipse(lx, ly, c, ab, h, w, nr, **kw)


@pytest.mark.parametrize("case", CASES)
def test_front_nodes_lie_on_the_ellipse_and_elements_are_valid(case):
    """Every front node (corner and mid-side) on the ellipse to 1e-12; signed Jacobians positive
    at every Gauss point and node with min/max ≥ 0.05 (Mesh.check); normal +z everywhere."""
    m = _mesh(case)
    _, _, (cx, cy), (a, b), *_ = case
    f = m.nodes[m.node_sets["front"]]
    assert f.shape[0] % 4 == 0 and f.shape[0] >= 16
    assert np.abs(((f[:, 0] - cx) / a) ** 2 + ((f[:, 1] - cy) / b) ** 2 - 1).max() < 1e-12
    m.check()
    jg, jn = m.jacobians()
    assert jg.min() > 0 and jn.min() > 0
    assert np.allclose(m.normals_at_centres(), [0, 0, 1])
    m2 = _mesh(case, normal="-z")
    assert np.allclose(m2.normals_at_centres(), [0, 0, -1])


@pytest.mark.parametrize("case", CASES)
def test_areas_and_sets(case):
    """Total area lx·ly to round-off (straight outer edges, shared quadratic inner edges); the
    inside set's area π a b within the quadratic edges' error (< 3e-5 here); every edge node on
    its edge and the edge sets complete; the sets partition the elements."""
    lx, ly, (cx, cy), (a, b), *_ = case
    m = _mesh(case)
    area = _areas(m)
    assert area.min() > 0
    assert abs(area.sum() / (lx * ly) - 1) < 1e-13
    inside = _areas(m, m.element_sets["inside"]).sum()
    assert abs(inside / (math.pi * a * b) - 1) < 3e-5
    x, y = m.nodes[:, 0], m.nodes[:, 1]
    for name, on in (("xmin", x == 0), ("xmax", x == lx), ("ymin", y == 0), ("ymax", y == ly)):
        assert np.array_equal(np.sort(m.node_sets[name]), np.flatnonzero(np.isclose(np.where(on, 0, 1), 0)))
    es = m.element_sets
    assert np.array_equal(np.sort(np.concatenate([es["inside"], es["ring"], es["outer"]])), np.arange(m.n_elements))
    assert np.array_equal(np.sort(np.concatenate([es["ring"], es["outer"]])), es["outside"])
    centres = m.nodes[m.elements[:, 8]]
    r2 = ((centres[:, 0] - cx) / a) ** 2 + ((centres[:, 1] - cy) / b) ** 2
    assert np.all(r2[es["inside"]] < 1) and np.all(r2[es["outside"]] > 1)
    ring_out = ((centres[:, 0] - cx) / (a + case[5])) ** 2 + ((centres[:, 1] - cy) / (b + case[5])) ** 2
    assert np.all(ring_out[es["ring"]] < 1) and np.all(ring_out[es["outer"]] > 1)
    assert len(es["ring"]) == case[6] * m.node_sets["front"].size // 2


def test_inside_area_converges_at_fourth_order():
    """The area inside a circle of radius 20 enclosed by the quadratic front: the error against
    π R² falls as h⁴ (the interpolation error of a quadratic arc is O(h³) and cancels to O(h⁵)
    per element over its symmetric cubic shape), measured rate 3.8-4.2."""
    errors, sizes = [], [4.0, 2.0, 1.0]
    for h in sizes:
        m = plate_with_ellipse(100.0, 100.0, (50.0, 50.0), (20.0, 20.0), h, 4.0, 2)
        errors.append(abs(_areas(m, m.element_sets["inside"]).sum() - math.pi * 400.0))
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((rates > 3.8) & (rates < 4.2)), (errors, rates)


def test_front_spacing_is_the_asked_size():
    """Circle R = 20 with front_size = 2π R / 40 (ten elements per quarter): every corner-to-corner
    arc R Δθ equals front_size to 1e-12, the mid-side nodes halve it. An ellipse: within each
    quarter the arcs are equal (scipy quad, 1e-9) and at most front_size, the fewest that are."""
    h = 2 * math.pi * 20 / 40
    m = plate_with_ellipse(100.0, 100.0, (40.0, 50.0), (20.0, 20.0), h, 4.0, 2)
    f = m.nodes[m.node_sets["front"]]
    theta = np.sort(np.mod(np.arctan2(f[:, 1] - 50.0, f[:, 0] - 40.0), 2 * math.pi))
    assert f.shape[0] == 80
    dtheta = np.diff(np.concatenate([theta, [theta[0] + 2 * math.pi]]))
    assert np.abs(20 * dtheta - h / 2).max() < 1e-12 * h
    a, b, h = 30.0, 10.0, 2.5
    m = plate_with_ellipse(100.0, 60.0, (50.0, 30.0), (a, b), h, 4.0, 2)
    f = m.nodes[m.node_sets["front"]] - [50.0, 30.0, 0.0]
    t = np.sort(np.mod(np.arctan2(f[:, 1] / b, f[:, 0] / a) + math.pi / 4, 2 * math.pi) - math.pi / 4)
    speed = lambda s: math.hypot(a * math.sin(s), b * math.cos(s))  # noqa: E731
    corners = np.concatenate([t[0::2], [t[0] + 2 * math.pi]])
    arcs = np.array([quad(speed, s0, s1, epsabs=1e-13, epsrel=1e-13)[0] for s0, s1 in zip(corners, corners[1:])])
    mids = np.array([quad(speed, s0, s1, epsabs=1e-13)[0] for s0, s1 in zip(corners[:-1], t[1::2])])
    assert np.allclose(mids, arcs / 2, rtol=1e-9)
    quarter = [quad(speed, -math.pi / 4 + k * math.pi / 2, math.pi / 4 + k * math.pi / 2)[0] for k in range(2)]
    counts = [math.ceil(q / h) for q in quarter]
    start = np.cumsum([0] + [counts[k % 2] for k in range(4)])
    for k in range(4):
        piece = arcs[start[k]:start[k + 1]]
        assert piece.size == counts[k % 2] and np.allclose(piece, quarter[k % 2] / counts[k % 2], rtol=1e-9)
        assert piece.max() <= h and quarter[k % 2] / (counts[k % 2] - 1) > h


# ------------------------------------------------------------------ through the model file
_PLATE = """
[model]
title = "simply supported square plate, uniform pressure"
units = "N, mm"
nonlinear = false

[mesh]
{mesh}

[materials.alu]
type = "isotropic"
E = 70000.0
nu = 0.3

[[layers]]
name = "plate"
material = "alu"
thickness = {h}
directors = 2

[[supports]]
type = "fix"
where = "near(x, 0) or near(x, 100) or near(y, 0) or near(y, 100)"
components = ["z"]

[[supports]]
type = "fix"
point = [0, 0, 0]
components = ["x", "y"]

[[supports]]
type = "fix"
point = [100, 0, 0]
components = ["y"]

{extra}

[steps]
n = 1

[[probes]]
name = "w"
quantity = "displacement"
point = [50, 50, 0]
component = "z"
"""

_CIRCLE_MESH = """type = "plate_with_circle"
lx = 100.0
ly = 100.0
center = [50.0, 50.0]
radius = 15.0
front_size = {size}
ring_width = 5.0
ring_layers = 2
outer_layers = {outer}"""


def _run(tmp_path: Path, mesh: str, extra: str = "", h: float = 1.0):
    text = _PLATE.format(mesh=mesh, extra=extra, h=h)
    spec = build(parse(text, "plate.toml"), tmp_path)
    return spec, run(spec, tmp_path / "out", write_vtu=False)


def _navier_centre(q: float, a: float, D: float, terms: int = 99) -> float:
    """Centre deflection of a simply supported a × a plate under q (double sine series)."""
    k = np.arange(1, terms + 1, 2)
    m, n = np.meshgrid(k, k)
    sign = (-1.0) ** ((m - 1) // 2 + (n - 1) // 2)
    return float(16 * q / (math.pi ** 6 * D) * np.sum(sign / (m * n * (m ** 2 / a ** 2 + n ** 2 / a ** 2) ** 2)))


def test_simply_supported_plate_matches_navier_and_the_rectangle_mesh(tmp_path):
    """Uniform pressure on a simply supported 100 × 100 × 1 mm plate (a/h = 100) meshed with a
    centred circle of radius 15 (276 elements): the centre deflection within 1 % of Navier's series
    (Kirchhoff; measured +0.08 %) and within 1 % of the same model on a 12 × 12 rectangle mesh
    (measured -0.17 %; the rectangle +0.26 % against Navier)."""
    q, E, nu, H = 1e-3, 70000.0, 0.3, 1.0
    load = f'[[loads]]\ntype = "surface"\ndirection = [0, 0, -1]\nmagnitude = {q}'
    _, circ = _run(tmp_path / "c", _CIRCLE_MESH.format(size=4.0, outer=6), load)
    _, rect = _run(tmp_path / "r", 'type = "rectangle"\nlx = 100.0\nly = 100.0\nnx = 12\nny = 12', load)
    navier = _navier_centre(q, 100.0, E * H ** 3 / (12 * (1 - nu ** 2)))
    w_circ, w_rect = -circ.summary["probes"]["w"], -rect.summary["probes"]["w"]
    assert abs(w_circ / navier - 1) < 0.01, (w_circ, navier)
    assert abs(w_circ / w_rect - 1) < 0.01, (w_circ, w_rect)


_PATCH = """
[model]
title = "constant membrane stress"
units = "N, mm"
nonlinear = false
element = "{element}"

[mesh]
{mesh}

[materials.alu]
type = "isotropic"
E = 70000.0
nu = 0.3

[[layers]]
name = "plate"
material = "alu"
thickness = 0.1
directors = 2

[[supports]]
type = "symmetry"
set = "xmin"
normal = [1, 0, 0]

[[supports]]
type = "symmetry"
set = "ymin"
normal = [0, 1, 0]

[[supports]]
type = "fix"
set = "ymin"
components = ["z"]

[[loads]]
type = "edge"
set = "xmax"
direction = [1, 0, 0]
distribution = "{sigma}"

[steps]
n = 1
"""

#: probe points in the core, the inner O-ring, on the front, in the ring and in the transition
_POINTS = [(50.0, 52.0), (58.0, 47.0), (61.2, 61.2), (50.0, 67.0), (70.0, 80.0), (95.0, 5.0), (35.6, 43.1)]


@pytest.mark.parametrize("element", ["mitc", "full"])
def test_constant_membrane_stress_patch(tmp_path, element):
    """Traction σ = 2 on x = 100 of the plate with the circle, symmetry planes x = 0 and y = 0:
    on the butterfly core, the curved ring and the distorted transition σ_xx = σ at every probe
    to 1e-8 and u_x = σ x / E at the nearest node (isoparametric elements reproduce a linear
    displacement field).
    The layer has no 'direction', and its '11' in the material frame is σ_xx too: on this mesh
    axis 1 is the projection of global x, not the elements' first coordinate line (which turns
    around the front and would report σ_θθ there)."""
    sig, E = 2.0, 70000.0
    text = _PATCH.format(element=element, mesh=_CIRCLE_MESH.format(size=5.0, outer=3), sigma=sig)
    for i, (x, y) in enumerate(_POINTS):
        text += (f'[[probes]]\nname = "s{i}"\nquantity = "stress"\npoint = [{x}, {y}, 0]\ncomponent = "11"\n'
                 f'frame = "global"\nsampling = "raw"\ntheta3 = 0.05\n[[probes]]\nname = "u{i}"\n'
                 f'quantity = "displacement"\npoint = [{x}, {y}, 0]\ncomponent = "x"\n')
    for i, (x, y) in enumerate(_POINTS):  # material frame: axis 1 along x on this mesh without 'direction'
        text += (f'[[probes]]\nname = "m{i}"\nquantity = "stress"\npoint = [{x}, {y}, 0]\ncomponent = "11"\n'
                 'sampling = "raw"\ntheta3 = 0.05\n')
    spec = build(parse(text, "patch.toml"), tmp_path)
    probes = run(spec, tmp_path / "out", write_vtu=False).summary["probes"]
    assert all(abs(probes[f"m{i}"] / sig - 1) < 1e-8 for i in range(len(_POINTS))), probes
    nodes = spec.model.mesh.nodes
    for i, (x, y) in enumerate(_POINTS):
        assert abs(probes[f"s{i}"] / sig - 1) < 1e-8, (x, y, probes[f"s{i}"])
        at = nodes[np.argmin(np.hypot(nodes[:, 0] - x, nodes[:, 1] - y)), 0]  # a displacement probe's node
        assert abs(probes[f"u{i}"] - sig * at / E) < 1e-8 * sig * 100 / E, (x, y, probes[f"u{i}"])


def test_inside_set_is_what_initially_debonded_circle_selects(tmp_path):
    """The nodes of the 'inside' elements (front included) are exactly the nodes that
    [[interfaces]] initially_debonded = [{circle = [x, y, R]}] selects on this mesh."""
    mesh = _CIRCLE_MESH.format(size=5.0, outer=3)
    layers = ('[[layers]]\nname = "top"\nmaterial = "alu"\nthickness = 0.2\ndirectors = 1\n'
              '[[interfaces]]\nlayer = "top"\nsigma_max = 30.0\ntau_max = 60.0\n'
              'initially_debonded = [{circle = [50.0, 50.0, 15.0]}]\n')
    text = _PLATE.format(mesh=mesh, extra="", h=1.0).replace("[[supports]]", layers + "[[supports]]", 1)
    spec = build(parse(text, "zone.toml"), tmp_path)
    m = spec.model.mesh
    debonded = np.unique(spec.model.initially_debonded[1])
    assert np.array_equal(debonded, np.unique(m.elements[m.element_sets["inside"]]))
    assert np.array_equal(debonded, np.sort(m.node_sets["inside"]))
    assert np.array_equal(np.sort(m.node_sets["interior"]), np.setdiff1d(debonded, m.node_sets["front"]))
    r = np.hypot(m.nodes[m.node_sets["interior"], 0] - 50.0, m.nodes[m.node_sets["interior"], 1] - 50.0)
    assert r.max() < 15.0 * (1 - 1e-3)


def test_blister_example_matches_the_clamped_circular_plate():
    """examples/laminate_circular_delamination.toml (1088 elements, about 10 s): the sub-laminate
    over the 40 mm delamination lifted by p = 0.001 N/mm² deflects w0 = p R⁴ / (64 D) at the
    centre (clamped circular plate) within 1.5 %, above it (the bonded front holds the bottom face,
    not the mid-surface; measured +1.0 %), and the held base does not move."""
    from helpers import run_example

    res = run_example("laminate_circular_delamination")
    E, nu, t, R, p = 50000.0, 0.3, 0.25, 20.0, 0.001
    w0 = p * R ** 4 / (64 * E * t ** 3 / (12 * (1 - nu ** 2)))
    w = res.summary["probes"]["w_blister"]
    assert 0 < w / w0 - 1 < 0.015, (w, w0)
    assert res.summary["probes"]["w_base"] == 0.0


# ------------------------------------------------------------------ bad input (CLI, exit 2)
_GOOD = {"type": "plate_with_circle", "lx": 10.0, "ly": 1.0, "center": [5.0, 0.5], "radius": 0.3,
         "front_size": 0.1, "ring_width": 0.1, "ring_layers": 2}


def _circle_mesh(**keys):
    def mutate(d):
        d["mesh"] = {k: v for k, v in {**_GOOD, **keys}.items() if v is not None}
    return mutate


def test_good_circle_mesh_is_accepted(tmp_path):
    o = _outcome(tmp_path, "good", Case("cantilever_thick.toml", _circle_mesh(), inprocess=True))
    assert o.returncode == 0, o.stderr


@pytest.mark.parametrize("name, keys, fields", [
    ("leaves_x", {"center": [9.8, 0.5]}, ("mesh", "circle", "leaves the plate", "xmax", "move center or reduce radius")),
    ("leaves_y", {"center": [5.0, 0.2]}, ("mesh", "leaves the plate", "ymin")),
    ("ellipse_leaves", {"radius": None, "semi_axes": [6.0, 0.3]}, ("semi_axes", "leaves the plate", "reduce semi_axes")),
    ("ring_too_wide", {"ring_width": 0.25}, ("ring_width = 0.25", "wider than the space", "ring_width below 0.2")),
    ("size_zero", {"front_size": 0.0}, ("mesh.front_size", "greater than 0")),
    ("radius_negative", {"radius": -1.0}, ("mesh.radius", "greater than 0")),
    ("ring_negative", {"ring_width": -0.1}, ("mesh.ring_width", "greater than 0")),
    ("layers_zero", {"ring_layers": 0}, ("mesh.ring_layers", "greater than 0")),
    ("both", {"semi_axes": [0.3, 0.2]}, ("radius", "semi_axes", "not both")),
    ("neither", {"radius": None}, ("radius", "semi_axes", "not both or neither")),
    ("infinite", {"lx": float("inf")}, ("lx must be a finite number",)),
    ("too_coarse", {"front_size": 0.3}, ("front_size", "too few elements", "smaller front_size")),
    ("folds", {"radius": 0.45, "ring_width": 0.0499}, ("64 element(s) would fold", "in the outer",
                                                        "move the centre towards the middle")),
])
def test_bad_circle_mesh_is_one_clear_paragraph(tmp_path, name, keys, fields):
    o = _outcome(tmp_path, name, Case("cantilever_thick.toml", _circle_mesh(**keys), inprocess=True))
    _assert_error(o, fields)
