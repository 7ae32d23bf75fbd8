"""MITC9 assumed-strain element (issue 14): kernel checks, rank, patch tests, thin-shell benchmarks."""
import sys
from pathlib import Path

import numpy as np
import pytest
from conftest import curved_element, flat_distorted_element

from layershell.element.kernel import layer_block, layer_response, layer_response_reference
from layershell.element.mitc import mitc_block, mitc_response_reference, tying
from layershell.material import Orthotropic

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import shell_benchmarks as sb  # noqa: E402

ORTHO = Orthotropic(100.0, 50.0, 30.0, 20.0, 15.0, 10.0, 0.25, 0.3, 0.1)


def _layer(rng, n=1):
    H = np.full((n, 9), 0.2) + 0.02 * rng.standard_normal((n, 9))
    return np.full((n, 9), 0.1), H


def _rel(a, b):
    return np.abs(a - b).max() / np.abs(b).max()


@pytest.mark.parametrize("d", [0, 1, 2, 3, 4])
def test_every_component_at_the_gauss_points_is_the_full_element(rng, d):
    """With all strain components "tied" at the Gauss points themselves, the covariant detour
    (frame, tying operator, covariant stiffness Tᵀ C T) must give the fully integrated element of
    kernel.py exactly: an independent check of the frame algebra and of f and K."""
    X = curved_element(rng)
    Hb, H = _layer(rng)
    U = 0.05 * rng.standard_normal((1, 9 * (d + 1), 3))
    nz = max(3, d)
    ref = layer_block(X, Hb, H, d, ORTHO, 20.0, n_thickness=nz, element="full")
    for frame in ("natural", "center"):
        blk = mitc_block(X, Hb, H, d, ORTHO, 20.0, n_thickness=nz, full=True, frame=frame)
        for nonlinear in (True, False):
            f0, K0 = layer_response_reference(ref, U, nonlinear)
            f1, K1 = mitc_response_reference(blk, U, nonlinear)
            assert _rel(f1, f0) < 1e-12 and _rel(K1, K0) < 1e-12


def test_tying_functions_interpolate_the_tying_points():
    """The MITC9 tying functions are Lagrange interpolants: a strain field of the assumed form
    (linear in r × quadratic in s for E_11, E_13; swapped for E_22, E_23; bilinear for E_12) is
    reproduced exactly at the Gauss points."""
    t = tying()
    gp = t.points[16:]
    fields = {0: lambda r, s: 1 + 2 * r + 3 * s + 4 * r * s * s - s * s,
              1: lambda r, s: 1 - r + 2 * s + 5 * r * r * s + r * r,
              5: lambda r, s: 2 + r - s + 3 * r * s}
    fields[4], fields[3], fields[2] = fields[0], fields[1], lambda r, s: r ** 2 * s ** 2
    H = t.dense()
    for c, fn in fields.items():
        vals = fn(t.points[:, 0], t.points[:, 1])
        assert np.allclose(H[c] @ vals, fn(gp[:, 0], gp[:, 1]), atol=1e-13)


@pytest.mark.parametrize("d", [0, 1, 2, 3, 4])
def test_tangent_matches_finite_differences(rng, d):
    """Consistent tangent of the tied strains (material + geometric part from the second
    derivatives of the tied covariant strains) = central FD of the internal force, nonlinear,
    on a distorted curved element at a large displacement."""
    X = curved_element(rng, distort=0.15)
    Hb, H = _layer(rng)
    blk = layer_block(X, Hb, H, d, ORTHO, 20.0, element="mitc")
    U = 0.08 * rng.standard_normal((1, 9 * (d + 1), 3))
    _, K = layer_response(blk, U)
    h, m = 1e-6, U.size
    Kfd = np.zeros((m, m))
    for j in range(m):
        Up, Um = U.copy().reshape(-1), U.copy().reshape(-1)
        Up[j] += h
        Um[j] -= h
        Kfd[:, j] = (layer_response(blk, Up.reshape(U.shape), tangent=False)[0]
                     - layer_response(blk, Um.reshape(U.shape), tangent=False)[0])[0] / (2 * h)
    assert _rel(K[0], Kfd) < 1e-7
    assert _rel(K[0], K[0].T) < 1e-13


@pytest.mark.parametrize("d", [0, 1, 2, 3, 4])
@pytest.mark.parametrize("nonlinear", [True, False])
def test_fast_kernel_equals_reference(rng, d, nonlinear):
    """Compiled MITC9 kernel = NumPy form (f, K) over many elements and on an element range."""
    n = 19
    X = np.concatenate([curved_element(rng) for _ in range(n)])
    Hb, H = _layer(rng, n)
    blk = layer_block(X, Hb, H, d, ORTHO, 20.0, element="mitc")
    U = 0.05 * rng.standard_normal((n, 9 * (d + 1), 3))
    f0, K0 = layer_response_reference(blk, U, nonlinear)
    f1, K1 = layer_response(blk, U, nonlinear)
    assert _rel(f1, f0) < 1e-12 and _rel(K1, K0) < 1e-12
    f2, K2 = layer_response(blk, U[4:13], nonlinear, sl=slice(4, 13))
    assert _rel(f2, f0[4:13]) < 1e-12 and _rel(K2, K0[4:13]) < 1e-12


@pytest.mark.parametrize("d", [1, 3])
@pytest.mark.parametrize("nonlinear", [True, False])
def test_fast_kernel_force_only_equals_reference(rng, d, nonlinear):
    """Without the tangent the compiled kernel skips the strain rows; f is bit-for-bit the f
    computed with the tangent (a line search compares residuals of both)."""
    n = 11
    X = np.concatenate([curved_element(rng) for _ in range(n)])
    Hb, H = _layer(rng, n)
    blk = layer_block(X, Hb, H, d, ORTHO, 20.0, element="mitc")
    U = 0.05 * rng.standard_normal((n, 9 * (d + 1), 3))
    f0, _ = layer_response_reference(blk, U, nonlinear, False)
    f1, K1 = layer_response(blk, U, nonlinear, False)
    assert K1 is None and _rel(f1, f0) < 1e-12
    assert np.array_equal(f1, layer_response(blk, U, nonlinear, True)[0])


def test_block_diagonal_factor_and_the_general_factor_agree(rng):
    """Ĉ does not couple the transverse shear ties with the others when the material's third axis
    is the normal (always, here): the block keeps L̂ block diagonal (``split``); the kernel with
    the dense-factor product (split = 0) gives the same f and K, both equal to the reference."""
    import dataclasses

    n = 7
    X = np.concatenate([curved_element(rng, distort=0.15) for _ in range(n)])
    Hb, H = _layer(rng, n)
    blk = layer_block(X, Hb, H, 3, ORTHO, 20.0, element="mitc", direction=(1.0, 0.3, 0.2))
    h = blk.tie.n_normal
    assert blk.split == h == 25
    assert np.all(blk.L[..., h:, :h] == 0.0)
    U = 0.05 * rng.standard_normal((n, 36, 3))
    f0, K0 = layer_response_reference(blk, U)
    for b in (blk, dataclasses.replace(blk, split=0)):
        f1, K1 = layer_response(b, U)
        assert _rel(f1, f0) < 1e-12 and _rel(K1, K0) < 1e-12


def test_fast_kernel_without_factor(rng):
    """C̃ not positive definite (a negative volume weight): the general product path."""
    import dataclasses

    X = np.concatenate([curved_element(rng) for _ in range(3)])
    Hb, H = _layer(rng, 3)
    blk = layer_block(X, Hb, H, 2, ORTHO, 20.0, element="mitc")
    blk = dataclasses.replace(blk, L=None)
    U = 0.05 * rng.standard_normal((3, 27, 3))
    f0, K0 = layer_response_reference(blk, U)
    f1, K1 = layer_response(blk, U)
    assert _rel(f1, f0) < 1e-12 and _rel(K1, K0) < 1e-12


def _scaled_stiffness(X, d, H0=1.0, element="mitc"):
    H = np.full((1, 9), H0)
    blk = layer_block(X, -H / 2, H, d, ORTHO, 20.0, element=element)
    _, K = layer_response(blk, np.zeros((1, 9 * (d + 1), 3)), nonlinear=False)
    s = 1 / np.sqrt(np.diag(K[0]))
    return K[0] * s[:, None] * s[None]  # Jacobi scaling: the (Θ_L)^l directors have small entries


@pytest.mark.parametrize("d", [1, 2, 3, 4])
@pytest.mark.parametrize("shape", ["flat", "flat_distorted"])
def test_free_flat_element_has_exactly_six_zero_eigenvalues(rng, d, shape):
    """Rank: a free flat element (regular or distorted) has exactly the 6 rigid-body zero modes;
    the 7th eigenvalue is far from round-off (no spurious modes). With only d thickness points
    the (Θ_L)^d director of d ≥ 3 would add 6 zero modes once E_α3 is tied — hence d + 1 points."""
    X = flat_distorted_element(rng, 0.0 if shape == "flat" else 0.15)
    for H0 in (0.2, 1.0):
        ev = np.linalg.eigvalsh(_scaled_stiffness(X, d, H0))
        ev = ev / ev.max()
        assert np.all(np.abs(ev[:6]) < 1e-12)
        assert ev[6] > 1e-9


@pytest.mark.parametrize("d", [1, 2, 3, 4])
def test_free_curved_element_has_no_spurious_modes(rng, d):
    """A curved element's rigid rotations are only approximately strain-free (the normal A_3 is
    not in the span of the nodal basis; the same in the full element), so: 3 exact translations,
    and after removing the 6 softest modes of the full element, the MITC9 stiffness is as far
    from singular as the full element's (ratio of the smallest eigenvalues > 1e-2)."""
    X = curved_element(rng, distort=0.15)
    Km, Kf = _scaled_stiffness(X, d), _scaled_stiffness(X, d, element="full")
    ev = np.linalg.eigvalsh(Km) / np.abs(Km).max()
    assert np.sum(np.abs(ev) < 1e-12) == 3
    w, V = np.linalg.eigh(Kf)
    P = V[:, 6:]  # complement of the 6 (near) rigid modes
    lm = np.linalg.eigvalsh(P.T @ Km @ P)[0]
    lf = np.linalg.eigvalsh(P.T @ Kf @ P)[0]
    assert lm > 1e-2 * lf


# ----------------------------------------------------------------------------- thin-shell benchmarks
def test_scordelis_lo_4x4():
    """Scordelis-Lo roof, quarter model 4 × 4 (d = 2, the self-weight as a body force): within 3 %
    of 0.3024 (-0.82 %; the full element -18.7 %, the figure of issue 14)."""
    w = sb.scordelis_lo(4, "mitc", 2)
    assert abs(w / sb.SCORDELIS_REF - 1) < 0.03


def test_pinched_cylinder_8x8():
    """Pinched cylinder octant 8 × 8 (d = 2): within 5 % of 1.8248e-5 (full element: −45 %)."""
    w = sb.pinched_cylinder(8, "mitc", 2)
    assert abs(w / sb.PINCHED_REF - 1) < 0.05


def test_thin_plate_regular_and_straight_edged_distorted_mesh():
    """Mesh-distortion sensitivity (benchmarks/distortion.py, its table): clamped square plate,
    a/t = 1000, uniform load, 4 × 4, d = 2; centre deflection over the Kirchhoff value
    w_K = 0.00126532 q a⁴ / D (independent of both elements). Regular mesh: MITC9 within 5 % of
    w_K (measured 0.968), the fully integrated element locks (0.762). Straight-edged distortion
    (inner element corners moved by up to ± 0.2 element sizes, seed 5; mid-side nodes at the
    edge midpoints): MITC9 keeps more than 60 % of its regular-mesh deflection (measured 0.686 /
    0.968 = 71 %; the full element 25 %), so a change that made MITC9 more distortion-sensitive
    fails. Curved-edge distortion, which brings the locking back (0.027), is not pinned here."""
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
    import distortion

    w = {(mesh, e): distortion.plate(4, 1000.0, mesh, e, amount=0.2, seed=5)[0]
         for mesh in ("regular", "straight") for e in ("mitc", "full")}
    assert abs(w["regular", "mitc"] - 1) < 0.05
    assert w["regular", "full"] < 0.85
    assert w["straight", "mitc"] > 0.6 * w["regular", "mitc"]
    assert w["straight", "mitc"] > 2 * w["straight", "full"]


# ----------------------------------------------------------------------------- patch tests
def _patch_models():
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    import test_patch

    return test_patch


def _bending_tip_distorted(rng, d, nu, element="mitc", E=1e5, M=100.0):
    """Pure bending (linear end traction, moment M per width) of a plate strip 10 × 1 × 1 on a
    straight-edged distorted 5 × 2 mesh, symmetry plane at x = 0: deflection difference between
    the corners (10, 0) and (0, 0) at mid-depth; exact 3D value M l²/(2EI) (quadratic field)."""
    from layershell.element.shape import NODE_XI
    from layershell.model import EdgeLoad, Fix, Layer, Model, Symmetry
    from layershell.results import evaluate_points
    from layershell.solver.newton import load_steps
    from layershell.solver.problem import Problem

    tp = _patch_models()
    m = tp._distorted_plate(rng, 10.0, 1.0, 5, 2, straight=True)
    x = m.nodes
    ly = Layer("b", Orthotropic.isotropic(E, nu), d, np.ones(m.n_nodes))
    x0 = np.flatnonzero(np.isclose(x[:, 0], 0))
    n0 = np.flatnonzero(np.isclose(x[:, 0], 0) & np.isclose(x[:, 1], 0))
    model = Model(m, [ly], [(0,)], np.zeros(m.n_elements, int), fixes=[Fix(n0, 0, (0,), (1, 2))],
                  symmetries=[Symmetry(x0, np.array([1.0, 0, 0]))],
                  edge_loads=[EdgeLoad(tp._edges(m, np.isclose(x[:, 0], 10.0)), np.array([1.0, 0, 0]),
                                       lambda theta3, **kw: 12 * M * (theta3 - 0.5))],
                  nonlinear=False, element=element)
    pb = Problem.build(model)
    st = list(load_steps(pb, np.array([1.0])))[-1]
    out = []
    for corner in ([10.0, 0.0], [0.0, 0.0]):
        node = int(np.argmin(np.linalg.norm(x[:, :2] - corner, axis=1)))
        el, loc = np.argwhere(m.elements == node)[0]
        ps = evaluate_points(model, pb.dm, st.u, [el], NODE_XI[loc, 0], NODE_XI[loc, 1], [0.5])
        out.append(ps.u[0, 2])
    return abs(out[0] - out[1])


@pytest.mark.parametrize("d", [2, 3])
def test_bending_patch_on_distorted_mesh_is_exact(rng, d):
    """Bending patch test (ν = 0.4) on a straight-edged distorted mesh: exact to round-off."""
    w = _bending_tip_distorted(rng, d, 0.4)
    assert np.isclose(w, 100.0 * 100 / (2 * 1e5 / 12), rtol=1e-9)


def test_centre_frame_passes_the_membrane_patch_test_natural_frame_does_not(rng, monkeypatch):
    """Why the strains are tied in the rotated centre frame: on a straight-edged distorted mesh
    a constant stress state is exact with it (the frame is constant on a flat element), while the
    natural convected frame of the original MITC9 (Bucalem & Bathe 1993) misses it (≈ 3e-5)."""
    from functools import partial

    from layershell.element import mitc
    from layershell.model import EdgeLoad, Fix, Layer, Model, Symmetry
    from layershell.results import evaluate_points
    from layershell.solver.newton import load_steps
    from layershell.solver.problem import Problem

    tp = _patch_models()
    errors = {}
    for frame in ("center", "natural"):
        monkeypatch.setattr(mitc, "mitc_block", partial(mitc_block, frame=frame))
        m = tp._distorted_plate(np.random.default_rng(3), straight=True)
        E, nu, H, sig = 1000.0, 0.3, 0.1, 2.0
        x = m.nodes
        ly = Layer("p", Orthotropic.isotropic(E, nu), 2, np.full(m.n_nodes, H))
        x0 = np.flatnonzero(np.isclose(x[:, 0], 0))
        y0 = np.flatnonzero(np.isclose(x[:, 1], 0))
        corner = np.flatnonzero(np.isclose(x[:, 0], 2.0) & np.isclose(x[:, 1], 0))
        model = Model(m, [ly], [(0,)], np.zeros(m.n_elements, int),
                      fixes=[Fix(x0, 0, (0,), (2,)), Fix(corner, 0, (0,), (2,))],
                      symmetries=[Symmetry(x0, np.array([1.0, 0, 0])), Symmetry(y0, np.array([0, 1.0, 0]))],
                      edge_loads=[EdgeLoad(tp._edges(m, np.isclose(x[:, 0], 2.0)), np.array([1.0, 0, 0]),
                                           lambda theta3, **kw: sig + 0 * theta3)], nonlinear=False)
        pb = Problem.build(model)
        st = list(load_steps(pb, np.array([1.0])))[-1]
        el = np.repeat(np.arange(m.n_elements), 4)
        ps = evaluate_points(model, pb.dm, st.u, el, np.tile([-1, 1, 1, -1], m.n_elements),
                             np.tile([-1, -1, 1, 1], m.n_elements), 0.05)
        errors[frame] = np.abs(ps.u[:, 0] - sig * ps.X[:, 0] / E).max() / (2 * sig / E)
    assert errors["center"] < 1e-10
    assert errors["natural"] > 1e-6


@pytest.mark.parametrize("d", [1, 2, 3])
def test_consistency_correction_gives_the_constant_stress_nodal_forces(rng, d):
    """A flat element with curved edges (mid-side and centre nodes moved) under a linear
    displacement field u = A x: its tied strains are the constant strain of A, and with the
    consistency correction its nodal forces equal the fully integrated element's (the consistent
    nodal forces of the constant stress, exact with 3 × 3 points); without it they do not (the
    0.3 % of the curved-edge membrane patch test). For stress states without transverse shear:
    the rows of E_α3 hold the shape functions themselves (∂_3 phi = N l Θ^(l−1)), whose product
    with a curved element's Jacobian the 2-point rule of the tying points does not integrate, so
    a constant σ_α3 is reproduced only on straight-edged elements (before and after the
    correction; module docstring)."""
    X = flat_distorted_element(rng, 0.15)
    H = np.full((1, 9), 0.2)
    iso = Orthotropic.isotropic(1000.0, 0.3)  # constant C (an orthotropic frame follows A_1)
    A = 0.01 * rng.standard_normal((3, 3))
    A[2, :2] = -A[:2, 2]  # no transverse shear strain (see the docstring)
    U = np.zeros((1, 9, d + 1, 3))
    U[0, :, 0] = X[0] @ A.T - 0.1 * A[:, 2]  # x = X0 + Θ¹ e_z, Θ¹ = H_below + Θ_L, H_below = −0.1
    U[0, :, 1] = A[:, 2]
    U = U.reshape(1, -1, 3)
    full = layer_block(X, -H / 2, H, d, iso, 0.0, n_thickness=d + 1, element="full")
    f_full = layer_response(full, U, nonlinear=False, tangent=False)[0]
    f = {c: layer_response(mitc_block(X, -H / 2, H, d, iso, 0.0, None, d + 1, consistent=c), U, nonlinear=False,
                           tangent=False)[0] for c in (True, False)}
    assert _rel(f[True], f_full) < 1e-12
    assert _rel(f[False], f_full) > 1e-4


def test_consistency_correction_vanishes_where_the_tying_is_already_consistent(rng):
    """mitc.tie_correction: v = 0 where ρ = detG H/2 is bilinear (a straight-edged flat element
    of constant thickness: the plain MITC9 element is unchanged there), for E_33 (at the Gauss
    points) and with every component at the Gauss points; v ≠ 0 with curved edges; always
    Σ_t v_t = 0 per component (a constant tie strain stays constant: E' = P E with P 1 = 1)."""
    from layershell.element.shape import NODE_XI

    X = flat_distorted_element(rng, 0.0)
    corners = X[0, :4] + 0.3 * rng.standard_normal((4, 3)) * [1, 1, 0]
    xi, eta = NODE_XI[:, 0], NODE_XI[:, 1]
    N4 = 0.25 * np.stack([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta), (1 - xi) * (1 + eta)], -1)
    straight = (N4 @ corners)[None]
    H = np.full((1, 9), 0.2)
    tie = tying()
    for Xe, full, zero in ((straight, False, True), (flat_distorted_element(rng, 0.15), True, True),
                           (flat_distorted_element(rng, 0.15), False, False)):
        blk = mitc_block(Xe, -H / 2, H, 2, ORTHO, 20.0, None, 3, full=full)
        v = blk.v
        assert np.allclose([v[..., tie.off[c]:tie.off[c] + tie.n[c]].sum(-1) for c in range(6)], 0, atol=1e-15)
        assert np.abs(v[..., tie.off[2]:tie.off[2] + tie.n[2]]).max() < 1e-15
        assert (np.abs(v).max() < 1e-14) if zero else (np.abs(v).max() > 1e-4)


def test_tied_strain_at_points_equals_the_kernel_strain(rng):
    """tied_strain (used by probes, profiles and the delamination criterion) at the Gauss points
    and thickness levels of the kernel = the kernel's tied strain there (from its stress: C̃⁻¹ S̃
    per point, then to Cartesian axes): one strain field for the stiffness and the output."""
    from layershell.element import mitc
    from layershell.element.quadrature import gauss_1d, gauss_2d

    d, nz = 2, 3
    X = curved_element(rng, distort=0.15)
    Hb, H = _layer(rng)
    U = 0.05 * rng.standard_normal((1, 9 * (d + 1), 3))
    blk = mitc_block(X, Hb, H, d, ORTHO, 20.0, n_thickness=nz)
    # kernel's tied covariant strain at (z, q): from its internal algebra (reference form)
    dphi = np.einsum("ezpai,ezpib->ezpab", mitc.natural_gradients(blk), blk.M)
    Gc = np.swapaxes(blk.G, -1, -2)
    D = np.einsum("ezpai,eak->ezpik", dphi, U)
    GD = np.einsum("ezpik,ezpjk->ezpij", Gc, D)
    E = 0.5 * (GD + np.swapaxes(GD, -1, -2)) + 0.5 * np.einsum("ezpik,ezpjk->ezpij", D, D)
    Ev = np.stack([E[..., i, j] * (1.0 if i == j else 2.0) for i, j in mitc._PAIRS], axis=-1)
    Et = np.einsum("cqp,ezpc->ezqc", tying().dense(), Ev)  # (e, z, q, 6)
    Et = (Et + np.einsum("ezcp,ezpc->ezc", mitc._dense_correction(blk.tie, blk.v), Ev)[:, :, None])[0]  # + correction
    gp, _ = gauss_2d(3)
    zeta, _ = gauss_1d(nz)
    Fq = mitc.strain_frames(X, Hb, H, gp, zeta)[0][0]  # (q, z, 3, 3)
    want = np.einsum("qzVc,zqc->zqV", mitc.covariant_map(np.linalg.inv(Fq)), Et)
    Hq = np.einsum("qn,n->q", mitc._quad9(gp)[0], H[0])
    for z in range(nz):
        thL = 0.5 * Hq * (zeta[z] + 1)
        got = mitc.tied_strain(np.repeat(X, 9, 0), np.repeat(Hb, 9, 0), np.repeat(H, 9, 0), d,
                               np.repeat(U, 9, 0), gp[:, 0].copy(), gp[:, 1].copy(), thL)
        assert np.allclose(got, want[z], rtol=1e-10, atol=1e-12 * np.abs(want).max())
        # the points of one element at one level share the strains at the tying points (groups):
        # the same values, with those of a second element (other displacements) in the same call
        U2 = U + 0.03 * rng.standard_normal(U.shape)
        both = mitc.tied_strain(np.repeat(X, 18, 0), np.repeat(Hb, 18, 0), np.repeat(H, 18, 0), d,
                                np.concatenate([np.repeat(U, 9, 0), np.repeat(U2, 9, 0)]), np.tile(gp[:, 0], 2),
                                np.tile(gp[:, 1], 2), np.tile(thL, 2), groups=np.repeat([0, 1], 9))
        other = mitc.tied_strain(np.repeat(X, 9, 0), np.repeat(Hb, 9, 0), np.repeat(H, 9, 0), d,
                                 np.repeat(U2, 9, 0), gp[:, 0].copy(), gp[:, 1].copy(), thL)
        assert np.array_equal(both[:9], got) and np.array_equal(both[9:], other)


@pytest.mark.slow
def test_scordelis_lo_8x8_and_the_converged_value():
    """Scordelis-Lo 8 × 8 (MITC9, d = 2, uniform mesh) against the converged value of the same
    problem as a 3D solid (benchmarks/scordelis_solid.py, docs/vs_solid.md §3: quadratic
    hexahedra graded towards the free edge, Richardson-extrapolated; tests/test_scordelis_solid.py).

    The example applies the 90 per middle-surface area on the outer face: 3D value 0.30648
    (+1.35 % of 0.3024); 8 × 8 gives 0.30579 (-0.22 % of it, +1.12 % of 0.3024). The self-weight
    as a body force (``load = "volume"``) is the problem of the benchmark: 3D value 0.30148
    (-0.30 % of 0.3024; a load on the middle surface gives the same to 0.003 %); 8 × 8 gives
    0.30080, within issue 14's 1 % of 0.3024 (-0.53 %). The 1.66 % between the two loads is the
    eccentricity t/2 of the load's tangential component on the outer face, not an error of the
    element. (The value 0.3061 once given here as "converged" was a uniform 24 × 24 mesh: uniform
    meshes converge slowly at the free edge, whose boundary layer is ~t wide; graded meshes give
    the limits above already on 8 × 8.)"""
    w8 = sb.scordelis_lo(8, "mitc", 2, "outer")
    assert abs(w8 / sb.SCORDELIS_3D["outer"] - 1) < 0.003
    assert abs(w8 / sb.SCORDELIS_REF - 1) < 0.015
    w8v = sb.scordelis_lo(8, "mitc", 2)  # the default load: "volume"
    assert abs(w8v / sb.SCORDELIS_3D["volume"] - 1) < 0.003
    assert abs(w8v / sb.SCORDELIS_REF - 1) < 0.01


@pytest.mark.slow
def test_pinched_cylinder_16x16():
    """Pinched cylinder octant 16 × 16 (MITC9, d = 2): within 2 % of 1.8248e-5 (+0.6 %; full
    element −10 %)."""
    w = sb.pinched_cylinder(16, "mitc", 2)
    assert abs(w / sb.PINCHED_REF - 1) < 0.02
