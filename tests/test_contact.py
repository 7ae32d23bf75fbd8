"""Inner contact kernel: gap, penalty tangent, friction tangent (MODEL.md §10, (4.43)-(4.59))."""
import numpy as np
import pytest
from helpers import fd_reduced_tangent

from layershell.contact import ContactBlock
from layershell.delamination import InterfaceLaw
from layershell.interfaces import interfaces
from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import Fix, Layer, Model
from layershell.solver.problem import Problem


def _two_layer(nonlinear=True, curved=True):
    mesh = rectangle(1.0, 0.8, 1, 1)
    if curved:
        mesh.nodes[:, 2] = 0.2 * mesh.nodes[:, 0] ** 2
    th = np.full(mesh.n_nodes, 0.1)
    layers = [Layer("a", Orthotropic.isotropic(100.0, 0.2), 2, th),
              Layer("b", Orthotropic.isotropic(300.0, 0.3), 3, 0.5 * th + 0.01 * mesh.nodes[:, 0])]
    return Model(mesh, layers, [(0, 1)], np.zeros(1, int), fixes=[Fix(np.array([0, 3]), 0, (0,), (0, 1, 2))],
                 nonlinear=nonlinear)


@pytest.mark.parametrize("rule", ["gauss", "lobatto"])
@pytest.mark.parametrize("friction", [False, True])
def test_contact_tangent_matches_finite_differences(rng, friction, rule):
    m = _two_layer()
    m.interface_laws = {1: InterfaceLaw(1.0, 1.0, alpha_N=5e3, rule=rule)}
    m.initially_debonded = {1: np.arange(m.mesh.n_nodes)}  # everything released
    pb = Problem.build(m)
    blk = pb.assembler.extra[0]
    assert blk.released.all()
    ur = 2e-3 * rng.standard_normal(pb.op.n_red)
    if friction:
        gp = 1e-3 * rng.standard_normal(blk.g_p.shape)
        P = blk.projector()
        blk.g_p = np.einsum("eqij,eqj->eqi", P, gp)  # anchors lie in the tangent plane
        t_tr = blk.alpha_T * (np.einsum("eqij,eqj->eqi", P, blk.relative_displacement(pb.op.T @ ur)) - blk.g_p)
        # slip limits 15-50 % above or below the trial traction: sticking and sliding points
        factor = rng.uniform(1.15, 2.0, blk.w.shape) ** rng.choice([-1, 1], blk.w.shape)
        blk.cap = np.linalg.norm(t_tr, axis=-1) * factor
    else:
        blk.cap = np.zeros(blk.w.shape)
    g = blk.gap(pb.op.T @ ur)
    assert (g < 0).any() and (g > 0).any()  # both contact states occur
    if friction:  # the exact return mapping: both sticking and sliding points occur
        x = np.linalg.norm(t_tr, axis=-1) / blk.cap
        assert (x < 0.9).any() and (x > 1.1).any()
    Kr, Kfd = fd_reduced_tangent(pb, ur, h=1e-7)
    assert np.abs(Kr - Kfd).max() < 1e-6 * np.abs(Kr).max()
    assert np.allclose(Kr, Kr.T, atol=1e-9 * np.abs(Kr).max())


def test_gap_is_zero_where_bonded_and_measures_separation(rng):
    m = _two_layer(curved=False)
    pb = Problem.build(m)
    itf = interfaces(m)[0]
    blk = ContactBlock.build(m, pb.dm, itf, 1.0)
    u = pb.op.T @ rng.standard_normal(pb.op.n_red)
    assert np.allclose(blk.relative_displacement(u), 0.0, atol=1e-12)  # bonded: continuous
    # lift the upper layer's bottom face by 0.01 along A3 = +z
    d = pb.dm.layer_dofs[1][:, 0, 2]
    u2 = u.copy()
    u2[d] += 0.01
    assert np.allclose(blk.gap(u2), 0.01)


def test_response_equals_the_explicit_operator_form(rng):
    """The response works with C = c ⊗ I₃; it equals the explicit sums with C and b = A3·C:
    f = Σ_q α_N w ḡ_N b + w0 Cᵀ t, K = Σ_q α_N w b⊗b + w0 Cᵀ D C (4.56)-(4.59)."""
    m = _two_layer()
    m.interface_laws = {1: InterfaceLaw(1.0, 1.0, alpha_N=5e3)}
    m.initially_debonded = {1: np.arange(m.mesh.n_nodes)}
    pb = Problem.build(m)
    blk = pb.assembler.extra[0]
    u = pb.op.T @ (2e-3 * rng.standard_normal(pb.op.n_red))
    assert np.array_equal(blk.C, np.einsum("eqk,ij->eqikj", blk.c, np.eye(3)).reshape(blk.C.shape))
    blk.cap = np.full(blk.w.shape, 0.3)
    g = blk.gap(u)
    a = blk.alpha * blk.w * (g <= 0)
    t, D = blk.friction_traction(u)
    f_ref = np.einsum("eq,eqm->em", a * g, blk.b) + np.einsum("eq,eqim,eqi->em", blk.w0, blk.C, t)
    K_ref = (np.einsum("eq,eqm,eqn->emn", a, blk.b, blk.b)
             + np.einsum("eq,eqim,eqij,eqjn->emn", blk.w0, blk.C, D, blk.C))
    f, K = blk.response(u)
    assert (g < 0).any()
    assert np.allclose(f, f_ref, rtol=1e-12, atol=1e-12 * np.abs(f_ref).max())
    assert np.allclose(K, K_ref, rtol=1e-12, atol=1e-12 * np.abs(K_ref).max())
    f2, none = blk.response(u, tangent=False)
    assert none is None and np.array_equal(f2, f)


def test_compact_contact_tangent_scatters_like_the_full_one(rng, monkeypatch):
    """Only elements with released points contribute to the contact tangent; scattering just
    those (compiled and NumPy paths) gives the tangent of the full block."""
    import layershell.assembly as assembly

    mesh = rectangle(2.0, 0.8, 3, 1)
    th = np.full(mesh.n_nodes, 0.1)
    layers = [Layer("a", Orthotropic.isotropic(100.0, 0.2), 2, th), Layer("b", Orthotropic.isotropic(300.0, 0.3), 3, th)]
    m = Model(mesh, layers, [(0, 1)], np.zeros(3, int), fixes=[Fix(np.flatnonzero(mesh.nodes[:, 0] < 1e-9), 0, (0,), (0, 1, 2))],
              nonlinear=True)
    m.interface_laws = {1: InterfaceLaw(1.0, 1.0, alpha_N=5e3)}
    m.initially_debonded = {1: np.flatnonzero(mesh.nodes[:, 0] < 0.5)}  # the first element's left half
    pb = Problem.build(m)
    blk = pb.assembler.extra[0]
    assert 0 < np.count_nonzero(blk.released.any(axis=1)) < blk.released.shape[0]
    u = pb.op.T @ (2e-3 * rng.standard_normal(pb.op.n_red))
    blk.cap = np.full(blk.w.shape, 0.3)
    f1, K1 = pb.assembler.evaluate_reduced(u, pb.op)
    monkeypatch.setattr(ContactBlock, "compact_tangent", False)
    f2, K2 = pb.assembler.evaluate_reduced(u, pb.op)
    monkeypatch.setattr(ContactBlock, "compact_tangent", True)
    monkeypatch.setattr(assembly, "_jit", lambda: None)
    f3, K3 = pb.assembler.evaluate_reduced(u, pb.op)
    scale = np.abs(K2.data).max()
    assert np.abs(K1 - K2).max() <= 1e-12 * scale and np.abs(K3 - K2).max() <= 1e-12 * scale
    assert np.array_equal(f1, f2) and np.allclose(f3, f2, rtol=0, atol=1e-12 * np.abs(f2).max())
