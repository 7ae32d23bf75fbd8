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


@pytest.mark.parametrize("friction", [False, True])
def test_contact_tangent_matches_finite_differences(rng, friction):
    m = _two_layer()
    m.interface_laws = {1: InterfaceLaw(1.0, 1.0, alpha_N=5e3)}
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
