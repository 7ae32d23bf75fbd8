"""Patch tests through the whole pipeline (constraints, loads, assembly, solver, recovery)."""
import numpy as np
import pytest

from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import EdgeLoad, Fix, Layer, Model, Symmetry
from layershell.results import evaluate_points
from layershell.runner import RunResult  # noqa: F401  (import check)
from layershell.solver.newton import load_steps
from layershell.solver.problem import Problem
from layershell.io.build import boundary_edges


def _distorted_plate(rng, lx=2.0, ly=1.0, nx=3, ny=2, straight=False):
    """Distorted plate mesh: inner nodes moved at random (curved element edges), or with
    ``straight`` the inner corner nodes moved and the other nodes placed on the bilinear map of
    each element (straight-edged quadrilaterals, the MacNeal-Harder patch-test kind)."""
    m = rectangle(lx, ly, nx, ny)
    x = m.nodes
    inner = (x[:, 0] > 1e-9) & (x[:, 0] < lx - 1e-9) & (x[:, 1] > 1e-9) & (x[:, 1] < ly - 1e-9)
    if not straight:
        m.nodes[inner, :2] += 0.08 * rng.uniform(-1, 1, (inner.sum(), 2))
    else:
        from layershell.element.shape import NODE_XI

        corners = np.unique(m.elements[:, :4])
        corners = corners[inner[corners]]
        m.nodes[corners, :2] += 0.12 * rng.uniform(-1, 1, (corners.size, 2))
        xi, eta = NODE_XI[4:, 0], NODE_XI[4:, 1]
        N4 = 0.25 * np.stack([(1 - xi) * (1 - eta), (1 + xi) * (1 - eta), (1 + xi) * (1 + eta),
                              (1 - xi) * (1 + eta)], -1)
        for el in m.elements:
            m.nodes[el[4:]] = N4 @ m.nodes[el[:4]]
    m.check()
    return m


def _edges(m, mask):
    be = boundary_edges(m)
    return be[mask[be].all(1)]


@pytest.mark.parametrize("d", [1, 2, 3])
@pytest.mark.parametrize("nonlinear", [False])
@pytest.mark.parametrize("element", ["mitc", "full"])
def test_membrane_patch_constant_stress(rng, d, nonlinear, element):
    """Uniaxial traction σ on the x = lx edge of a distorted mesh with curved element edges
    (inner nodes moved at random): the stress is σ at every point (exact), the other components
    vanish, and u_x = σ x / E.

    Both elements are exact. The MITC9 element needs two things for it: strains tied in the
    rotated centre frame (constant on a flat element; the natural-frame MITC9 of Bucalem & Bathe
    misses even straight-edged distortion, 3e-5, tests/test_mitc.py) and the consistency
    correction of its tying (mitc.tie_correction): without it the tied B̃ no longer integrates to
    the B of a constant stress once the edges are curved (0.3 % error of u_x on this mesh,
    exact on straight-edged distortion; tests/test_mitc.py
    test_consistency_correction_gives_the_constant_stress_nodal_forces)."""
    m = _distorted_plate(rng)
    E, nu, H, sig = 1000.0, 0.3, 0.1, 2.0
    x = m.nodes
    ly = Layer("p", Orthotropic.isotropic(E, nu), d, np.full(m.n_nodes, H))
    x0 = np.flatnonzero(np.isclose(x[:, 0], 0))
    y0 = np.flatnonzero(np.isclose(x[:, 1], 0))
    corner = np.flatnonzero(np.isclose(x[:, 0], 2.0) & np.isclose(x[:, 1], 0))
    model = Model(m, [ly], [(0,)], np.zeros(m.n_elements, int),
                  fixes=[Fix(x0, 0, (0,), (2,)), Fix(corner, 0, (0,), (2,))],
                  symmetries=[Symmetry(x0, np.array([1.0, 0, 0])), Symmetry(y0, np.array([0, 1.0, 0]))],
                  edge_loads=[EdgeLoad(_edges(m, np.isclose(x[:, 0], 2.0)), np.array([1.0, 0, 0]),
                                       lambda theta3, **kw: sig + 0 * theta3)],
                  nonlinear=nonlinear, element=element)
    pb = Problem.build(model)
    st = list(load_steps(pb, np.array([1.0])))[-1]
    n = 40
    el = rng.integers(0, m.n_elements, n)
    ps = evaluate_points(model, pb.dm, st.u, el, rng.uniform(-1, 1, n), rng.uniform(-1, 1, n), rng.uniform(0, H, n))
    want = np.zeros((n, 3, 3))
    want[:, 0, 0] = sig
    assert np.allclose(ps.sigma, want, atol=1e-8 * sig)
    assert np.allclose(ps.u[:, 0], sig * ps.X[:, 0] / E, rtol=1e-8, atol=1e-12)
    assert np.allclose(ps.u[:, 1], -nu * sig * ps.X[:, 1] / E, rtol=1e-8, atol=1e-12)


def _pure_bending_tip(d, nu, E=1e5, M=100.0):
    """Beam of depth 1 under an end moment M per width (linear end traction), symmetry plane at
    x = 0: deflection difference between the ends at mid-depth."""
    m = rectangle(10.0, 1.0, 5, 1, normal="-z")
    ly = Layer("b", Orthotropic.isotropic(E, nu), d, np.ones(m.n_nodes))
    x = m.nodes
    x0 = np.flatnonzero(np.isclose(x[:, 0], 0))
    n0 = np.flatnonzero(np.isclose(x[:, 0], 0) & np.isclose(x[:, 1], 0))
    model = Model(m, [ly], [(0,)], np.zeros(m.n_elements, int), fixes=[Fix(n0, 0, (0,), (1, 2))],
                  symmetries=[Symmetry(x0, np.array([1.0, 0, 0]))],
                  edge_loads=[EdgeLoad(_edges(m, np.isclose(x[:, 0], 10.0)), np.array([1.0, 0, 0]),
                                       lambda theta3, **kw: 12 * M * (theta3 - 0.5))], nonlinear=False)
    pb = Problem.build(model)
    st = list(load_steps(pb, np.array([1.0])))[-1]
    ps = evaluate_points(model, pb.dm, st.u, [4, 0], [-1.0, 1.0], [0.0, 0.0], [0.5, 0.5])  # x = 10, x = 0 (flipped)
    return ps.u[0, 2] - ps.u[1, 2]


@pytest.mark.parametrize("d", [2, 3, 4])
def test_pure_bending_is_exact(d):
    """A linear through-thickness end traction (pure bending moment M per width) on a beam of
    depth 1 with a symmetry plane at x = 0 and ν = 0.4: the 3D solution is quadratic, so the
    deflection M l²/(2EI) is reproduced to round-off for d ≥ 2."""
    assert np.isclose(_pure_bending_tip(d, 0.4), 100.0 * 100 / (2 * 1e5 / 12), rtol=1e-9)


def test_d1_shows_poisson_thickness_locking():
    """With d = 1 the thickness strain is constant through the thickness, so pure bending is
    too stiff by the factor 1 - ν² (the reason the thesis recommends d ≥ 2)."""
    nu = 0.4
    assert np.isclose(_pure_bending_tip(1, nu), 100.0 * 100 / (2 * 1e5 / 12) * (1 - nu**2), rtol=1e-6)


def test_homogeneous_large_stretch_stress_measures(rng):
    """Homogeneous finite stretch + rotation imposed on the nodes: PK2 physical components equal
    C:E in the undeformed material frame, Cauchy physical components equal F S Fᵀ/J in the
    deformed frame m_k (2.101)-(2.107)."""
    from layershell.dofs import number_dofs

    m = rectangle(1.0, 1.0, 1, 1)
    mat = Orthotropic(100.0, 50.0, 30.0, 20.0, 15.0, 10.0, 0.25, 0.3, 0.1)
    ly = Layer("p", mat, 1, np.full(m.n_nodes, 0.2), angle=0.0)
    model = Model(m, [ly], [(0,)], np.zeros(1, int))
    dm = number_dofs(model)
    lam = np.array([1.3, 0.9, 1.1])
    c, s = np.cos(0.4), np.sin(0.4)
    Q = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1.0]])
    F = Q @ np.diag(lam)
    u = np.zeros(dm.n_full)
    D = dm.layer_dofs[0]
    u[D[:, 0]] = m.nodes @ (F - np.eye(3)).T
    u[D[:, 1]] = (F - np.eye(3)) @ np.array([0, 0, 1.0])
    ps = evaluate_points(model, dm, u, [0, 0], [0.2, -0.5], [0.1, 0.7], [0.0, 0.13])
    E = 0.5 * (np.diag(lam**2) - np.eye(3))
    Sv = mat.stiffness() @ np.array([E[0, 0], E[1, 1], E[2, 2], 0, 0, 0])
    assert np.allclose(ps.pk2_physical, np.diag(Sv[:3]), atol=1e-10)
    assert np.allclose(ps.cauchy_physical, np.diag(lam**2 * Sv[:3] / lam.prod()), atol=1e-10)
    assert np.allclose(ps.m[:, 0], Q[:, 0]) and np.allclose(ps.m[:, 2], [0, 0, 1])
