"""Batched Total-Lagrangian layer kernel: strains, PK2 stress, internal force, tangent.

MODEL.md §2, §5 / thesis (2.49)-(2.57), (2.249)-(2.272). Within one layer the multi-director
shell is a 3D continuum with the tensor-product basis ``phi_(n,l) = N_n(Θ¹,Θ²) (Θ_L³)^l``
(3.13), so with the material gradient ``g_aJ = ∂_i phi_a (G^i)_J`` and the nodal vectors U_ai:

* F_iJ = δ_iJ + U_ai g_aJ,  E = ½(FᵀF − I)  (exact Green-Lagrange strain (2.54))
* S = C : E  (2.249) with C rotated to Cartesian axes (2.150)
* f_ai = ∫ B_aiV S_V dV,  B_aiJK = ½(F_iJ g_aK + F_iK g_aJ) = ∂E_JK/∂U_ai  (2.267)
* K_aibk = ∫ B_aiV C_VW B_bkW + δ_ik g_aJ S_JK g_bK dV  (2.268)

Axes: ``e`` element, ``q`` integration point, ``a`` basis function (node-major, then
director), ``i`` Cartesian DOF direction, ``V`` Voigt index [11, 22, 33, 23, 13, 12].
Element DOF order = (node, director, direction), i.e. direction fastest (2.271).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..material import Orthotropic, rotate_stiffness
from .geometry import SurfacePoints, shell_basis, surface_points
from .quadrature import gauss_1d, gauss_2d

_I3 = np.eye(3)


@dataclass(frozen=True)
class LayerBlock:
    """Reference-configuration data of one layer over a group of elements (computed once).

    gradphi (e, q, a, 3): material gradients of the basis functions
    dV (e, q): volume weights μ √A κ H_L/2 (3.47); C (e, q, 6, 6): Cartesian stiffness
    """

    d: int
    gradphi: np.ndarray
    dV: np.ndarray
    C: np.ndarray

    @property
    def n_dof(self) -> int:
        return self.gradphi.shape[2] * 3


def material_frame(sp: SurfacePoints, angle_deg: float = 0.0, direction=None) -> np.ndarray:
    """Orthonormal material frame M_i per point, rows in Cartesian components (2.91)-(2.100).

    M_3 = A_3. M_1 is the tangent-plane projection of the global ``direction`` (or A_1 if
    none is given), rotated by ``angle_deg`` about the normal; M_2 = M_3 × M_1.
    """
    A3 = sp.A3
    if direction is None:
        ref = sp.A[..., 0]
    else:
        v = np.broadcast_to(np.asarray(direction, dtype=float), A3.shape)
        ref = v - np.sum(v * A3, axis=-1, keepdims=True) * A3
        bad = np.linalg.norm(ref, axis=-1) < 1e-8 * np.linalg.norm(v, axis=-1)
        if np.any(bad):
            ref = np.where(bad[..., None], sp.A[..., 0], ref)
    ref = ref / np.linalg.norm(ref, axis=-1, keepdims=True)
    w = np.deg2rad(angle_deg)
    M1 = np.cos(w) * ref + np.sin(w) * np.cross(A3, ref)
    M2 = np.cross(A3, M1)
    return np.stack([M1, M2, A3], axis=-2)


def basis_gradients(sp: SurfacePoints, Ginv: np.ndarray, thetaL: np.ndarray, d: int) -> np.ndarray:
    """Material gradients of phi_(n,l) = N_n (Θ_L)^l at points, ``(e, q, z, 9*(d+1), 3)``."""
    l = np.arange(d + 1)
    t = thetaL[..., None]  # (e, q, z, 1)
    pw = t ** l  # (Θ_L)^l
    dpw = np.where(l > 0, l * t ** np.maximum(l - 1, 0), 0.0)  # l (Θ_L)^(l-1)
    N, dN = sp.N, sp.dN
    if N.ndim == 2:
        N = np.broadcast_to(N, sp.sqrtA.shape + (9,))
        dN = np.broadcast_to(dN, sp.sqrtA.shape + (9, 2))
    d12 = np.einsum("eqna,eqzl->eqznla", dN, pw)
    d3 = np.einsum("eqn,eqzl->eqznl", N, dpw)[..., None]
    dphi = np.concatenate([d12, d3], axis=-1)  # ∂_i phi, i = Θ¹, Θ², Θ³
    g = np.einsum("eqznli,eqziJ->eqznlJ", dphi, Ginv)
    e, q, z = g.shape[:3]
    return g.reshape(e, q, z, 9 * (d + 1), 3)


def layer_block(
    X: np.ndarray,
    H_below: np.ndarray,
    H: np.ndarray,
    d: int,
    material: Orthotropic,
    angle_deg: float = 0.0,
    direction=None,
    n_thickness: int = 3,
    n_inplane: int = 3,
) -> LayerBlock:
    """Precompute one layer for elements with nodal coordinates ``X (e, 9, 3)``.

    ``H_below (e, 9)`` is the nodal offset Σ_{K<L} H_K of the layer's bottom face from the
    reference surface, ``H (e, 9)`` the nodal layer thickness (2.214), (3.6).
    """
    pts, w2 = gauss_2d(n_inplane)
    zeta, wz = gauss_1d(n_thickness)
    sp = surface_points(X, pts[:, 0], pts[:, 1])
    Hq = sp.interpolate(H)  # (e, q)
    Hb = sp.interpolate(H_below)
    thetaL = 0.5 * Hq[..., None] * (zeta + 1.0)  # (e, q, z)
    G, Ginv, detG = shell_basis(sp, Hb[..., None] + thetaL)
    g = basis_gradients(sp, Ginv, thetaL, d)
    dV = detG * (w2[:, None] * wz[None, :]) * (0.5 * Hq[..., None])
    frame = material_frame(sp, angle_deg, direction)  # (e, q, 3, 3)
    C = rotate_stiffness(material.stiffness(), frame)  # (e, q, 6, 6)
    e, q, z = dV.shape
    C = np.broadcast_to(C[:, :, None], (e, q, z, 6, 6)).reshape(e, q * z, 6, 6)
    return LayerBlock(d, g.reshape(e, q * z, -1, 3), dV.reshape(e, q * z), np.ascontiguousarray(C))


def green_lagrange(Hgrad: np.ndarray, nonlinear: bool = True) -> np.ndarray:
    """Voigt Green-Lagrange strain (engineering shear) from the displacement gradient."""
    E = 0.5 * (Hgrad + np.swapaxes(Hgrad, -1, -2))
    if nonlinear:
        E = E + 0.5 * np.einsum("...kI,...kJ->...IJ", Hgrad, Hgrad)
    return np.stack(
        [E[..., 0, 0], E[..., 1, 1], E[..., 2, 2], 2 * E[..., 1, 2], 2 * E[..., 0, 2], 2 * E[..., 0, 1]], axis=-1
    )


def voigt_to_matrix(S: np.ndarray) -> np.ndarray:
    """(..., 6) stress in Voigt order -> symmetric (..., 3, 3)."""
    return np.stack(
        [
            np.stack([S[..., 0], S[..., 5], S[..., 4]], -1),
            np.stack([S[..., 5], S[..., 1], S[..., 3]], -1),
            np.stack([S[..., 4], S[..., 3], S[..., 2]], -1),
        ],
        -2,
    )


def strain_displacement(F: np.ndarray, g: np.ndarray) -> np.ndarray:
    """B_(a i),V = ∂E_V/∂U_ai (Voigt, engineering shear) in the layout ``(e, a, i, q, 6)``
    (element DOF major, then point and Voigt index), built from nine (e, a, i, q) products
    F_iJ g_aK so that the element stiffness is one contiguous batched GEMM."""
    P = {}
    for J in range(3):
        for K in range(3):
            P[J, K] = np.einsum("eqi,eqa->eaiq", F[..., :, J], g[..., :, K])
    return np.stack(
        [P[0, 0], P[1, 1], P[2, 2], P[1, 2] + P[2, 1], P[0, 2] + P[2, 0], P[0, 1] + P[1, 0]], axis=-1)


def layer_response(
    block: LayerBlock,
    U: np.ndarray,
    nonlinear: bool = True,
    tangent: bool = True,
    sl: slice = slice(None),
):
    """Internal force ``(e, a*3)`` and tangent ``(e, a*3, a*3)`` of a layer block.

    ``U (e, a, 3)`` are the element's nodal director vectors; ``sl`` restricts to an
    element range (for chunked assembly).
    """
    g, dV, C = block.gradphi[sl], block.dV[sl], block.C[sl]
    Hgrad = np.einsum("eai,eqaJ->eqiJ", U, g)
    F = _I3 + Hgrad if nonlinear else np.broadcast_to(_I3, Hgrad.shape)
    Ev = green_lagrange(Hgrad, nonlinear)
    S = np.einsum("eqvw,eqw->eqv", C, Ev)
    B = strain_displacement(F, g)  # (e, a, i, q, 6)
    e, q, a = g.shape[:3]
    m = a * 3
    Bm = B.reshape(e, m, q, 6)
    f = np.einsum("emqv,eqv->em", Bm, S * dV[..., None])
    if not tangent:
        return f, None
    # K = (B C) Bᵀ: both operands in (e, m, q·6) layout, the second as a transposed view (BLAS)
    BC = np.matmul(Bm.transpose(0, 2, 1, 3), C * dV[..., None, None])  # (e, q, m, 6)
    BC = BC.transpose(0, 2, 1, 3).reshape(e, m, q * 6)
    K = np.matmul(BC, Bm.reshape(e, m, q * 6).transpose(0, 2, 1))
    if nonlinear:
        Kg = np.einsum("eqaJ,eqJK,eqbK->eab", g, voigt_to_matrix(S) * dV[..., None, None], g, optimize=True)
        K = K.reshape(e, a, 3, a, 3)
        K += Kg[:, :, None, :, None] * _I3[None, None, :, None, :]
        K = K.reshape(e, m, m)
    return f, K
