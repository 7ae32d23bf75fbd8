"""Ply stacks inside one layer: the element integrates the layer ply by ply (Gauss points per
ply, C per point from its ply's material and angle) under the layer's own directors.

References: classical laminate theory computed here from the engineering constants (the
plane-stress reduced stiffness Q, its rotation Q̄ by Jones' formulas, A, B, D as exact sums over
the plies); Pagano's exact 3D solution of the [0/90/0] plate (layershell.analytic.pagano) and
the same plate modelled as three layers."""
import subprocess
import sys

import numpy as np
import pytest

from layershell.element.kernel import layer_block, layer_response
from layershell.element.shape import NODE_XI
from layershell.material import Orthotropic

# carbon/epoxy ply (E1, E2 = E3, G12 = G13, G23, ν12 = ν13, ν23)
CFRP = dict(E1=140e3, E2=10e3, G12=5e3, G23=3.5e3, nu12=0.3, nu23=0.45)
CFRP_MAT = Orthotropic.from_nu13(CFRP["E1"], CFRP["E2"], CFRP["E2"], CFRP["G12"], CFRP["G23"], CFRP["G12"],
                                 CFRP["nu12"], CFRP["nu23"], CFRP["nu12"])


def clt_abd(angles, thicknesses):
    """A, B, D (3 × 3 each, order xx, yy, xy with engineering shear) of classical laminate theory:
    Q from E1, E2, ν12, G12; Q̄ = Q rotated by the ply angle (Jones, Mechanics of Composite
    Materials, (2.85)); A = Σ Q̄ t, B = Σ Q̄ t z̄, D = Σ Q̄ (t³/12 + t z̄²), z̄ from the mid-plane."""
    E1, E2, G12, n12 = CFRP["E1"], CFRP["E2"], CFRP["G12"], CFRP["nu12"]
    n21 = n12 * E2 / E1
    Q11, Q22, Q12, Q66 = E1 / (1 - n12 * n21), E2 / (1 - n12 * n21), n12 * E2 / (1 - n12 * n21), G12
    t = np.asarray(thicknesses, float)
    ztop = np.cumsum(t) - t.sum() / 2
    zbar = ztop - t / 2
    A, B, D = np.zeros((3, 3)), np.zeros((3, 3)), np.zeros((3, 3))
    for ang, tk, zk in zip(angles, t, zbar):
        m, n = np.cos(np.deg2rad(ang)), np.sin(np.deg2rad(ang))
        q11 = Q11 * m**4 + 2 * (Q12 + 2 * Q66) * m**2 * n**2 + Q22 * n**4
        q22 = Q11 * n**4 + 2 * (Q12 + 2 * Q66) * m**2 * n**2 + Q22 * m**4
        q12 = (Q11 + Q22 - 4 * Q66) * m**2 * n**2 + Q12 * (m**4 + n**4)
        q66 = (Q11 + Q22 - 2 * Q12 - 2 * Q66) * m**2 * n**2 + Q66 * (m**4 + n**4)
        q16 = (Q11 - Q12 - 2 * Q66) * m**3 * n + (Q12 - Q22 + 2 * Q66) * m * n**3
        q26 = (Q11 - Q12 - 2 * Q66) * m * n**3 + (Q12 - Q22 + 2 * Q66) * m**3 * n
        Qb = np.array([[q11, q12, q16], [q12, q22, q26], [q16, q26, q66]])
        A += Qb * tk
        B += Qb * tk * zk
        D += Qb * (tk**3 / 12 + tk * zk**2)
    return A, B, D


def _unit_square(H):
    X = np.zeros((1, 9, 3))
    X[0, :, :2] = 0.5 * (NODE_XI + 1.0)
    return X, np.zeros((1, 9)), np.full((1, 9), H)


def element_abd(angles, thicknesses, element, d=2, n_thickness=2):
    """A, B, D that the element integrates on a flat unit square: the plane-stress condensation
    Q = C_pp − C_p3 C_3p / C_33 of the block's stiffness at each integration point, summed with the
    block's volume weights dV and the point's height z = Θ_L³ − H/2. The height is read back from
    the block: MITC9 stores Θ_L³ per level; the fully integrated block's gradients of N_n Θ_L³
    and N_n give Θ_L³ as their ratio."""
    t = np.asarray(thicknesses, float)
    H = t.sum()
    X, Hb, Hn = _unit_square(H)
    plies = [(CFRP_MAT, a, tk / H) for a, tk in zip(angles, t)]
    blk = layer_block(X, Hb, Hn, d, None, 0.0, n_thickness=n_thickness, element=element, plies=plies)
    C, dV = blk.C[0], blk.dV[0]
    if element == "mitc":
        z = np.repeat(blk.thL[0][:, 16], 9)  # level-major; point 16 = the first Gauss point
    else:
        g = blk.gradphi[0]  # (q·z, 9·(d+1), 3), basis a = node·(d+1) + l
        a0 = np.arange(9) * (d + 1)
        n = np.argmax(np.abs(g[:, a0, 0]), axis=1)  # per point a node with a non-zero ∂N/∂x
        r = np.arange(g.shape[0])
        z = g[r, a0[n] + 1, 0] / g[r, a0[n], 0]
    z = z - H / 2
    p = [0, 1, 5]
    Q = C[:, p][:, :, p] - C[:, p, 2][:, :, None] * C[:, 2, p][:, None, :] / C[:, 2, 2][:, None, None]
    A = np.einsum("q,qij->ij", dV, Q)
    B = np.einsum("q,qij->ij", dV * z, Q)
    D = np.einsum("q,qij->ij", dV * z * z, Q)
    return A, B, D


STACKS = {
    "[0/90]s": ([0, 90, 90, 0], [0.125] * 4),
    "[+45/-45]s": ([45, -45, -45, 45], [0.125] * 4),
    "[0/45/-45/90]s": ([0, 45, -45, 90, 90, -45, 45, 0], [0.125] * 8),
    "unsymmetric [0/30/90] (B != 0)": ([0, 30, 90], [0.1, 0.25, 0.15]),
}


@pytest.mark.parametrize("element", ["mitc", "full"])
@pytest.mark.parametrize("stack", list(STACKS))
def test_abd_of_one_layer_matches_classical_laminate_theory(stack, element):
    """A, B, D of one ply-stack layer equal CLT's to 1e-8 (of the largest entry of each matrix;
    B of the symmetric stacks to 1e-8 of A·h); the [±45]s stack has D16 ≠ 0 of the sign CLT gives,
    the unsymmetric one B ≠ 0."""
    angles, t = STACKS[stack]
    h = sum(t)
    A, B, D = clt_abd(angles, t)
    Ae, Be, De = element_abd(angles, t, element)
    assert np.abs(Ae - A).max() < 1e-8 * np.abs(A).max()
    assert np.abs(De - D).max() < 1e-8 * np.abs(D).max()
    assert np.abs(Be - B).max() < 1e-8 * np.abs(A).max() * h
    if stack.startswith("[+45"):
        assert abs(D[0, 2]) > 0.05 * D[0, 0] and np.sign(De[0, 2]) == np.sign(D[0, 2])
    if stack.startswith("unsym"):
        assert np.abs(B).max() > 0.01 * np.abs(A).max() * h


@pytest.mark.parametrize("element", ["mitc", "full"])
def test_two_equal_plies_are_the_plain_layer(element):
    """A layer of two identical plies (same material and angle) gives the linear stiffness and
    internal force of the same layer without plies to round-off (the ply rule integrates the
    same polynomials exactly), and the ply-rule weights sum to the layer's volume."""
    X, Hb, Hn = _unit_square(0.3)
    one = layer_block(X, Hb, Hn, 2, CFRP_MAT, 30.0, n_thickness=3, element=element)
    two = layer_block(X, Hb, Hn, 2, None, 0.0, n_thickness=3, element=element,
                      plies=[(CFRP_MAT, 30.0, 0.4), (CFRP_MAT, 30.0, 0.6)])
    assert two.C.shape[1] == 2 * one.C.shape[1]
    assert abs(two.dV.sum() - 0.3) < 1e-14
    U = np.random.default_rng(0).normal(size=(1, 27, 3)) * 1e-3
    f1, K1 = layer_response(one, U, nonlinear=False)
    f2, K2 = layer_response(two, U, nonlinear=False)
    assert np.abs(K2 - K1).max() < 1e-12 * np.abs(K1).max()
    assert np.abs(f2 - f1).max() < 1e-12 * np.abs(f1).max()


# --------------------------------------------------------------------- Pagano's [0/90/0] plate
def _pagano(s, n=8, nt=3, one_layer=True):
    """The simply supported square [0/90/0] plate of tests/test_recovery.py (quarter model, a/h = s,
    d = 3, double-sine top pressure) as three layers, or as one layer holding the three plies
    under one set of directors (same supports on its u_1..u_3 and u_0). Returns (model, problem,
    u, exact solution)."""
    from test_recovery import PLY, cross_ply_plate

    from layershell.material import laminate_equivalent
    from layershell.model import Fix, Layer, Model, Ply
    from layershell.solver.newton import load_steps
    from layershell.solver.problem import Problem

    m3, pb3, u3, ex = cross_ply_plate(s, n=n, d=3)
    if not one_layer:
        return m3, pb3, u3, ex
    table = [(PLY, a, 1 / 3) for a in (0.0, 90.0, 0.0)]
    ly = Layer("laminate", laminate_equivalent(table), 3, np.full(m3.mesh.n_nodes, 1.0), 0.0, None,
               tuple(Ply(*p) for p in table))
    fixes = [Fix(f.nodes, 0, f.directors, f.components) for f in m3.fixes if f.layer == 0]
    m = Model(m3.mesh, [ly], [(0,)], m3.element_stack, fixes=fixes, symmetries=m3.symmetries,
              surface_loads=m3.surface_loads, nonlinear=False, n_thickness=nt)
    pb = Problem.build(m)
    return m, pb, list(load_steps(pb, np.array([1.0])))[-1].u, ex


def _centre_values(m, pb, u, s, one_layer):
    """w at mid-thickness, σxx at the top (0° ply), σyy at z = 2h/3 in the 90° ply (its σ11:
    the stress takes the ply's material frame), at the plate centre (h = 1)."""
    from test_recovery import _at

    from layershell.results import evaluate_points

    a = float(s)
    c = _at(m, [a / 2, a / 2, 0])
    lay = (lambda k: [0]) if one_layer else (lambda k: [k])
    w = evaluate_points(m, pb.dm, u, *c, [0.5], lay(1)).u[0, 2]
    sxx = evaluate_points(m, pb.dm, u, *c, [1.0], lay(2)).pk2_physical[0, 0, 0]
    syy = evaluate_points(m, pb.dm, u, *c, [2 / 3], lay(1)).pk2_physical[0, 0, 0]
    return np.array([w, sxx, syy])


def _exact(ex, s):
    a = float(s)
    return np.array([ex.fields(a / 2, a / 2, 0.5)["w"], ex.fields(a / 2, a / 2, 1.0)["sxx"],
                     ex.fields(a / 2, a / 2, 2 / 3)["syy"]])


@pytest.mark.parametrize("s", [10, 100])
def test_pagano_cross_ply_one_layer_against_three_layers_and_exact(s):
    """[0/90/0], a/h = s, 8 × 8 quarter mesh, d = 3, raw stresses. Three layers (layerwise
    kinematics): w, σxx, σyy within 0.5 % of Pagano's exact solution. One layer with three plies
    (one cubic displacement through the laminate: no zig-zag of the in-plane displacement, no
    slope change of u at the ply interfaces): at a/h = 10 it is 5.0 % too stiff in w, σxx 0.8 %
    and σyy (in the 90° ply, at its top) 5.3 % low, the price of the kinematics it gives up; at
    a/h = 100 (classical laminate theory holds) all three within 0.5 % of the exact solution."""
    ref = _exact(*_pagano(s, one_layer=False)[3:], s)
    three = _centre_values(*_pagano(s, one_layer=False)[:3], s, one_layer=False)
    one = _centre_values(*_pagano(s)[:3], s, one_layer=True)
    e3, e1 = three / ref - 1, one / ref - 1
    print(f"a/h = {s}: three layers {e3}, one layer {e1}")
    assert np.abs(e3).max() < 0.005
    if s == 10:
        assert -0.055 < e1[0] < -0.045
        assert -0.012 < e1[1] < -0.004
        assert -0.058 < e1[2] < -0.048
    else:
        assert np.abs(e1).max() < 0.005


@pytest.mark.parametrize("s, tol", [(10, 0.045), (20, 0.02)])
def test_recovered_transverse_stresses_of_a_ply_stack(s, tol):
    """Recovery integrates the equilibrium ply by ply (levels in each ply, each ply's stress a
    polynomial): the one-layer [0/90/0] plate's recovered τxz at the edge x = 0 and τyz at y = 0,
    at both ply interfaces and mid-thickness, within 4.5 % (a/h = 10; measured +2.3 %, -3.9 %) and
    2 % (a/h = 20; +0.6 %, -1.6 %) of the exact ones, the error of its in-plane stresses (above);
    σzz at (a/4, a/4) within 0.5 % of q0. Three layers: within 0.1 % (tests/test_recovery.py)."""
    from test_recovery import _at

    from layershell.recovery import Recovery

    m, pb, u, ex = _pagano(s)
    a = float(s)
    rec = Recovery(m, pb.dm)
    z = np.array([1 / 3, 0.5, 2 / 3])
    lay = np.zeros(z.size, int)
    for comp, point, i in (("txz", [0, a / 2, 0], 0), ("tyz", [a / 2, 0, 0], 1)):
        el, xi, eta = _at(m, point, z.size)
        err = rec.points(u, el, xi, eta, z, lay).S[:, i, 2] / ex.fields(point[0], point[1], z)[comp] - 1
        assert np.abs(err).max() < tol, (comp, err)
    el, xi, eta = _at(m, [a / 4, a / 4, 0], z.size)
    s33 = rec.points(u, el, xi, eta, z, lay).S[:, 2, 2]
    assert np.abs(s33 - ex.fields(a / 4, a / 4, z)["szz"]).max() < 0.005


def test_ply_stack_converges_with_mesh_and_thickness_points():
    """One [0/90/0] layer, a/h = 10, centre deflection: 4, 5, 6 thickness points per ply give the
    same w to 1e-9 (each ply's polynomial integrand is integrated exactly by d + 1 = 4 points),
    and on 2 × 2, 4 × 4, 8 × 8 quarter meshes w converges: each refinement changes it by less than
    a quarter of the previous change (measured 0.0499, 0.0040), the last by less than 1e-4 of w."""
    s = 10
    w_nt = [_centre_values(*_pagano(s, n=4, nt=nt)[:3], s, True)[0] for nt in (4, 5, 6)]
    assert np.ptp(w_nt) < 1e-9 * abs(w_nt[0])
    w = [_centre_values(*_pagano(s, n=n)[:3], s, True)[0] for n in (2, 4, 8)]
    d = np.abs(np.diff(w))
    assert d[1] < 0.25 * d[0]
    assert d[1] < 1e-4 * abs(w[2])


# --------------------------------------------------------------------- model file and CLI
MODEL = """
[model]
units = "N, mm"
nonlinear = false

[mesh]
type = "rectangle"
lx = 100.0
ly = 20.0
nx = 4
ny = 1

[materials.cfrp]
type = "orthotropic"
E1 = 140000.0
E2 = 10000.0
E3 = 10000.0
G12 = 5000.0
G23 = 3500.0
G31 = 5000.0
nu12 = 0.3
nu23 = 0.45
nu13 = 0.3

[[layers]]
name = "laminate"
{layer}
directors = 2

[[supports]]
type = "fix"
where = "near(x, 0)"
layer = "all"
directors = "all"

[[loads]]
type = "surface"
face = "top"
direction = [0, 0, -1]
magnitude = 0.01

[steps]
n = 1

[[probes]]
name = "w_tip"
quantity = "displacement"
point = [100, 10, 0]
component = "z"

[[probes]]
name = "s11_top"
quantity = "stress"
point = [25, 10, 0]
theta3 = 1.0
component = "11"

[[profiles]]
name = "s13"
point = [50, 10, 0]
component = "13"
"""
PLIES = ('plies = [{material = "cfrp", angle = 0, thickness = 0.25}, {material = "cfrp", angle = 90, '
         'thickness = 0.5}, {material = "cfrp", angle = 0, thickness = 0.25}]')


def _cli(tmp_path, layer, command="check", extra=()):
    f = tmp_path / "model.toml"
    f.write_text(MODEL.format(layer=layer), encoding="utf-8")
    r = subprocess.run([sys.executable, "-m", "layershell.cli", command, str(f), *extra], capture_output=True,
                       text=True, cwd=tmp_path, timeout=300)
    return r


BAD = {
    "thicknesses do not sum": (PLIES + "\nthickness = 1.1", ["'layers[0].thickness'", "0.25 + 0.5 + 0.25 = 1", "1.1",
                                                              "leave out the layer's 'thickness'"]),
    "angle not a number": (PLIES.replace("angle = 90", 'angle = "90deg"'),
                           ["layers[0].plies[1].angle", "must be a number of degrees", "'90deg'"]),
    "unknown ply material": (PLIES.replace('"cfrp", angle = 90', '"crfp", angle = 90'),
                             ["layers[0].plies[1].material", "unknown material 'crfp'", "['cfrp']"]),
    "plies and material": ('material = "cfrp"\n' + PLIES, ["'layers[0].material'", "either one material or a ply stack",
                                                           "leave out the layer's 'material'"]),
    "formula thickness": (PLIES + '\nthickness = "1 + 0*x"', ["'layers[0].thickness'", "cannot be the formula",
                                                              "thickness = 1"]),
    "neither material nor plies": ("thickness = 1.0", ["'layers[0].material'", "required key is missing",
                                                       "plies = ["]),
    "thickness within 1e-9": (PLIES + "\nthickness = 1.0000001", ["'layers[0].thickness'", "1e-9 relative"]),
}


@pytest.mark.parametrize("case", list(BAD))
def test_bad_ply_input_is_one_paragraph_with_exit_2(tmp_path, case):
    layer, expected = BAD[case]
    r = _cli(tmp_path, layer)
    msg = r.stderr.strip()
    assert r.returncode == 2, r.stderr + r.stdout
    assert "Traceback" not in r.stderr and msg.startswith("error:") and len(msg.splitlines()) == 1, msg
    for text in expected:
        assert text in msg, (text, msg)


def test_model_file_ply_stack_runs_against_laminated_beam_theory(tmp_path):
    """A ply-stack layer from the model file, its thickness from the plies (0.25 + 0.5 + 0.25; a
    thickness within 1e-9 of the sum is accepted): the model's layer holds the three plies with
    fractions 1/4, 1/2, 1/4. 'run' of the cantilever strip (L = 100, clamped, q = 0.01 on top,
    default recovered sampling): tip deflection within 1 % of laminated beam theory
    q L⁴ (D⁻¹)₁₁ / 8 with D from CLT (above), L/h = 100 so shear adds < 1 %; the σ13 profile has
    21 points in each ply and both sides of each ply boundary, each in its ply's material axes."""
    from layershell.io.build import build, parse

    spec = build(parse(MODEL.format(layer=PLIES)))
    ly = spec.model.layers[0]
    assert [p.fraction for p in ly.plies] == [0.25, 0.5, 0.25] and [p.angle for p in ly.plies] == [0, 90, 0]
    assert np.all(ly.thickness == 1.0)
    build(parse(MODEL.format(layer=PLIES + "\nthickness = 1.0000000005")))
    r = _cli(tmp_path, PLIES, command="run", extra=("--out", "out", "--no-vtu"))
    assert r.returncode == 0, r.stderr
    import json

    w = json.loads((tmp_path / "out" / "summary.json").read_text())["probes"]["w_tip"]
    _, _, D = clt_abd([0, 90, 0], [0.25, 0.5, 0.25])
    beam = 0.01 * 100.0**4 / 8 * np.linalg.inv(D)[0, 0]
    assert abs(-w / beam - 1) < 0.01, (w, beam)
    prof = np.genfromtxt(tmp_path / "out" / "profile_s13.csv", delimiter=",", skip_header=1)
    assert prof.shape == (3 * 21, 2)  # points_per_layer in each ply
    at = np.flatnonzero(np.abs(prof[:, 0] - 0.25) < 1e-6)  # both sides of the 0/90 boundary
    lower, upper = prof[at, 1]
    assert abs(lower) > 0.1 and abs(upper) < 1e-6 * abs(lower)  # σ13 in the 90° ply's axes is τyz = 0


def test_solid_vtu_has_one_lattice_per_ply_with_its_material():
    """The ParaView solid of a three-ply layer holds 8 hexahedra per element and ply, and at the
    lattice points of each ply the stress of that ply: in material axes σ11 at the middle of the
    90° ply (the centre of the plate) equals the global σyy there, and across the interface
    between the 0° and the 90° ply the global σxx jumps by the ratio of the plies' stiffness
    (more than 5x), the same as evaluate_points on either side."""
    from test_recovery import _at

    from layershell.export import solid_mesh
    from layershell.results import evaluate_points

    s = 10
    m, pb, u, _ = _pagano(s, n=4)
    mat = solid_mesh(m, pb.dm, u, sampling="raw", frame="material")
    glo = solid_mesh(m, pb.dm, u, sampling="raw", frame="global")
    ne = m.mesh.n_elements
    assert mat.cells[0].data.shape == (8 * 3 * ne, 8)
    X = mat.points
    centre = np.isclose(X[:, 0], s / 2) & np.isclose(X[:, 1], s / 2)
    mid90 = centre & np.isclose(X[:, 2], 0.5)
    assert mid90.any()
    # stress components in order 11, 22, 33, 23, 13, 12
    assert np.allclose(mat.point_data["pk2"][mid90, 0], glo.point_data["pk2"][mid90, 1], rtol=1e-10)
    below = centre & np.isclose(X[:, 2], 1 / 3, atol=1e-6) & (X[:, 2] < 1 / 3)
    above = centre & np.isclose(X[:, 2], 1 / 3, atol=1e-6) & (X[:, 2] > 1 / 3)
    sx_below, sx_above = glo.point_data["pk2"][below, 0].mean(), glo.point_data["pk2"][above, 0].mean()
    assert abs(sx_below) > 5 * abs(sx_above)
    c = _at(m, [s / 2, s / 2, 0], 2)
    ref = evaluate_points(m, pb.dm, u, *c, [1 / 3 - 1e-9, 1 / 3 + 1e-9], [0, 0]).S[:, 0, 0]
    assert np.allclose([sx_below, sx_above], ref, rtol=1e-6)


def test_homogenised_equivalent_of_a_stack():
    """The stand-in material of a ply stack (penalties, process zones, gravity): in-plane constants
    from CLT's A/h (E1 = 1/a11, E2 = 1/a22, G12 = 1/a66, ν12 = -a12/a11 with a = (A/h)⁻¹), the
    quasi-isotropic stack in-plane isotropic (E1 = E2, G12 = E1/(2(1 + ν12))), E3 and G13 of the [0/90]s stack in series,
    density the thickness average."""
    from layershell.material import laminate_equivalent

    for angles in ([0, 90, 90, 0], [0, 45, -45, 90, 90, -45, 45, 0]):
        t = [0.125] * len(angles)
        A, _, _ = clt_abd(angles, t)
        a = np.linalg.inv(A / sum(t))
        eq = laminate_equivalent([(CFRP_MAT, ang, 1.0) for ang in angles])
        assert np.allclose([eq.E1, eq.E2, eq.G12, eq.nu12], [1 / a[0, 0], 1 / a[1, 1], 1 / a[2, 2], -a[0, 1] / a[0, 0]],
                           rtol=1e-10)
        eq.check()
    assert np.isclose(eq.E1, eq.E2, rtol=1e-12) and np.isclose(eq.G12, eq.E1 / (2 * (1 + eq.nu12)), rtol=1e-12)
    soft = Orthotropic.isotropic(1000.0, 0.3, density=2.0)
    stiff = Orthotropic.isotropic(3000.0, 0.3, density=1.0)
    eq = laminate_equivalent([(soft, 0.0, 0.25), (stiff, 90.0, 0.75)])
    assert np.isclose(eq.E3, 1 / (0.25 / 1000 + 0.75 / 3000))
    assert np.isclose(eq.G31, 1 / (0.25 / soft.G31 + 0.75 / stiff.G31)) and np.isclose(eq.density, 1.25)


def test_restart_hash_sees_the_plies():
    """A restart file belongs to one model: a changed ply angle changes the model hash."""
    from layershell.checkpoint import model_hash
    from layershell.io.build import build, parse

    h0 = model_hash(build(parse(MODEL.format(layer=PLIES))))
    h1 = model_hash(build(parse(MODEL.format(layer=PLIES.replace("angle = 90", "angle = 80")))))
    assert h0 != h1


@pytest.mark.parametrize("element", ["mitc", "full"])
def test_nonlinear_tangent_of_a_ply_stack_matches_finite_differences(element):
    """Green-Lagrange kinematics, [0/45/90] in one layer, d = 2, a distorted curved element: the
    tangent equals central differences of the internal force (step 1e-6) to 1e-6 of its norm."""
    rng = np.random.default_rng(3)
    X, Hb, Hn = _unit_square(0.2)
    X = X + rng.normal(scale=0.03, size=X.shape) * np.array([1.0, 1.0, 2.0])
    plies = [(CFRP_MAT, 0.0, 0.3), (CFRP_MAT, 45.0, 0.3), (CFRP_MAT, 90.0, 0.4)]
    blk = layer_block(X, Hb, Hn, 2, None, 0.0, n_thickness=3, element=element, plies=plies)
    U = rng.normal(scale=0.02, size=(1, 27, 3))
    f, K = layer_response(blk, U, nonlinear=True)
    h = 1e-6
    Kfd = np.empty_like(K[0])
    for j in range(81):
        dU = np.zeros(81)
        dU[j] = h
        fp, _ = layer_response(blk, U + dU.reshape(1, 27, 3), nonlinear=True, tangent=False)
        fm, _ = layer_response(blk, U - dU.reshape(1, 27, 3), nonlinear=True, tangent=False)
        Kfd[:, j] = (fp[0] - fm[0]) / (2 * h)
    assert np.abs(Kfd - K[0]).max() < 1e-6 * np.abs(K[0]).max()


@pytest.mark.slow
def test_cfrp_circular_plate_with_its_middle_plies_in_one_layer():
    """examples/cfrp_circular_plies.toml against examples/cfrp_circular.toml (the thesis's
    homogenised layers): the same delaminated oval, longer along x2 (x1 = 7.5, x2 = 9.34 mm, on the
    mesh's point rows), reached two load factors earlier, and more global deflection before it:
    classical laminate theory puts the ply plate's D22 28 % below the homogenised one's (D11
    +1.6 %), so it bends more easily across the load."""
    from helpers import run_example

    plies, homog = run_example("cfrp_circular_plies"), run_example("cfrp_circular")
    assert plies.converged and homog.converged

    def extent(res, lam):
        step = next(s for s in res.summary["steps"] if abs(s["load_factor"] - lam) < 1e-9)
        e = step["debonded_extent"]["II/III"]
        return e["x_max"], e["y_max"], step["probes"]["w_bottom_absmax"]

    x30, y30, _ = extent(plies, 30.0)
    x32, y32, _ = extent(homog, 32.0)
    assert x30 == pytest.approx(x32, abs=1e-9) and y30 == pytest.approx(y32, abs=1e-9) and y30 > x30 + 1.0
    assert extent(homog, 30.0)[0] < x30  # the homogenised zone has not grown there yet
    w_plies, w_homog = extent(plies, 28.0)[2], extent(homog, 28.0)[2]
    assert w_plies < 1.5 * w_homog < 0  # deflections are negative: the ply plate deflects > 1.5 times as much
