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

:func:`layer_response` evaluates this in factored form (C dV = L Lᵀ, K_mat = (B L)(B L)ᵀ as one
BLAS syrk per element; point loops compiled with Numba in ``_jit.py``; elements split over
``LAYERSHELL_THREADS`` threads). :func:`layer_response_reference` is the literal NumPy form,
kept as the independent check (tests/test_kernel_fast.py) and for benchmarks/kernel.py.
"""
from __future__ import annotations

import os
import threading
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from dataclasses import dataclass

import numpy as np

from ..material import Orthotropic, rotate_stiffness
from ..threads import blas_single_thread
from .geometry import SurfacePoints, shell_basis, surface_points
from .quadrature import gauss_2d, ply_rule

_I3 = np.eye(3)


@dataclass(frozen=True)
class LayerBlock:
    """Reference-configuration data of one layer over a group of elements (computed once).

    gradphi (e, q, a, 3): material gradients of the basis functions
    dV (e, q): volume weights μ √A κ H_L/2 (3.47); C (e, q, 6, 6): Cartesian stiffness
    L (e, q, 6, 6): lower Cholesky factor of C·dV (C dV = L Lᵀ), or None where C·dV is not
    positive definite at some point (the kernel then uses the general product B (C dV) Bᵀ)
    """

    d: int
    gradphi: np.ndarray
    dV: np.ndarray
    C: np.ndarray
    L: np.ndarray | None = None

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


def ply_stiffness(sp: SurfacePoints, plies, direction, ply: np.ndarray) -> np.ndarray:
    """Cartesian stiffness ``(e, q, z, 6, 6)`` at the thickness points of ply index ``ply (z,)``,
    each from its ply's material and angle (``plies``: (material, angle, fraction) per ply)."""
    per_ply = np.stack([rotate_stiffness(mat.stiffness(), material_frame(sp, ang, direction))
                        for mat, ang, _ in plies])  # (plies, e, q, 6, 6)
    return np.moveaxis(per_ply[ply], 0, 2)


def thickness_rule(plies, material, angle_deg: float, n: int):
    """The ply table (one ply of ``material`` and ``angle_deg`` without ``plies``) and its
    thickness rule (:func:`.quadrature.ply_rule`)."""
    plies = ((material, angle_deg, 1.0),) if plies is None else tuple(plies)
    return plies, ply_rule(n, [f for _, _, f in plies])


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
    element: str = "full",
    plies=None,
    keep_map: bool = False,
):
    """Precompute one layer for elements with nodal coordinates ``X (e, 9, 3)``.

    ``H_below (e, 9)`` is the nodal offset Σ_{K<L} H_K of the layer's bottom face from the
    reference surface, ``H (e, 9)`` the nodal layer thickness (2.214), (3.6).
    ``element``: "full" (fully integrated, this module) or "mitc" (assumed strain,
    :mod:`.mitc`; returns a :class:`~.mitc.MitcBlock` and uses at least d + 1 thickness points,
    with fewer the (Θ_L)^d director of d ≥ 3 has zero-energy modes once the shear is tied).
    ``plies``: (material, angle, thickness fraction) per ply, bottom to top, instead of
    ``material`` and ``angle_deg``: ``n_thickness`` Gauss points in each ply, C per point from
    its ply (:meth:`layershell.model.Layer.ply_table`). ``keep_map``: the MITC9 block keeps the
    map T from tied covariant to Cartesian strains (inelastic layers, :mod:`.inelastic`).
    """
    if element == "mitc":
        from .mitc import mitc_block

        if n_inplane != 3:
            raise ValueError("the MITC9 element needs the 3 x 3 in-plane rule")
        return mitc_block(X, H_below, H, d, material, angle_deg, direction, max(n_thickness, d + 1), plies=plies,
                          keep_map=keep_map)
    if element != "full":
        raise ValueError(f"element: unknown element {element!r} (use 'mitc' or 'full')")
    pts, w2 = gauss_2d(n_inplane)
    plies, (zeta, wz, ply) = thickness_rule(plies, material, angle_deg, n_thickness)
    sp = surface_points(X, pts[:, 0], pts[:, 1])
    Hq = sp.interpolate(H)  # (e, q)
    Hb = sp.interpolate(H_below)
    thetaL = 0.5 * Hq[..., None] * (zeta + 1.0)  # (e, q, z)
    G, Ginv, detG = shell_basis(sp, Hb[..., None] + thetaL)
    g = basis_gradients(sp, Ginv, thetaL, d)
    dV = detG * (w2[:, None] * wz[None, :]) * (0.5 * Hq[..., None])
    e, q, z = dV.shape
    C = np.ascontiguousarray(ply_stiffness(sp, plies, direction, ply).reshape(e, q * z, 6, 6))
    dV = dV.reshape(e, q * z)
    return LayerBlock(d, np.ascontiguousarray(g.reshape(e, q * z, -1, 3)), dV, C, stiffness_factor(C, dV))


def stiffness_factor(C: np.ndarray, dV: np.ndarray) -> np.ndarray | None:
    """Lower Cholesky factor L of C·dV per point (``(e, q, 6, 6)``), None if not positive definite.

    With it the material tangent Bᵀ (C dV) B = (B L)(B L)ᵀ is a symmetric rank-k product (2.268).
    """
    if not np.all(dV > 0):
        return None
    try:
        return np.linalg.cholesky(C * dV[..., None, None])
    except np.linalg.LinAlgError:
        return None


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


def layer_response_reference(
    block: LayerBlock,
    U: np.ndarray,
    nonlinear: bool = True,
    tangent: bool = True,
    sl: slice = slice(None),
    stress=None,
):
    """Plain NumPy form of :func:`layer_response` (Voigt B and C, (2.267)-(2.268) literally).

    Kept as the independent second computation the fast kernel is tested against, and the form
    of inelastic layers: ``stress(E) -> (S, D)`` gives the stress and the tangent dS/dE
    (``(e, q, 6)``, ``(e, q, 6, 6)``, Cartesian Voigt) from the Green-Lagrange strain ``E (e, q,
    6)`` at the block's points in place of S = C E (:mod:`.inelastic`).
    """
    if not isinstance(block, LayerBlock):  # MITC9 block
        from .mitc import mitc_response_reference

        return mitc_response_reference(block, U, nonlinear, tangent, sl, stress)
    g, dV, C = block.gradphi[sl], block.dV[sl], block.C[sl]
    Hgrad = np.einsum("eai,eqaJ->eqiJ", U, g)
    F = _I3 + Hgrad if nonlinear else np.broadcast_to(_I3, Hgrad.shape)
    Ev = green_lagrange(Hgrad, nonlinear)
    if stress is None:
        S = np.einsum("eqvw,eqw->eqv", C, Ev)
    else:
        S, C = stress(Ev)
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


# --------------------------------------------------------------------------------------------
# Fast kernel. Per point (2.267)-(2.268) with B_(ai)V = Σ_JK Q_V,JK F_iJ g_aK (Q: Voigt map):
#   f_ai  = Σ_q Σ_K g_aK (S dV F ᵀ)_Ki
#   K_mat = Σ_q (B L)(B L)ᵀ with C dV = L Lᵀ: stacking the points, X_e = [B_q L_q]_q is a
#           (6q × m) matrix and K_mat = X_eᵀ X_e is one symmetric rank-k BLAS product (syrk,
#           half the flops of the general product), (B L)_(ai)W = Σ_K g_aK Φ_WKi with
#           Φ_WKi = Σ_J F_iJ L_Q(J,K),W
#   K_geo = δ_ik Σ_q g_aJ (S dV)_JK g_bK: one GEMM (a × 3q)(3q × a) per element.
# The point work is compiled (Numba, no GIL); elements are split over threads with BLAS
# itself single-threaded (small products parallelise better over elements than inside BLAS).
# --------------------------------------------------------------------------------------------

_SUB = 8  # elements per sub-block: its X (8 × 140 kB for d = 3) stays in cache for the product

_IDENTITY6 = np.eye(6)


def _response_range(g, dV, C, L, U, nonlinear: bool, tangent: bool, f, K, lo: int, hi: int) -> None:
    """Fill ``f[lo:hi]``, ``K[lo:hi]`` sub-block by sub-block (one thread's share)."""
    from . import _jit  # Numba is imported on the first evaluation only (keeps CLI start-up fast)

    q, a = g.shape[1], g.shape[2]
    m = 3 * a
    geo = tangent and nonlinear
    for s in range(lo, hi, _SUB):
        t = min(s + _SUB, hi)
        nb = t - s
        X = np.empty((nb, q, 6, a, 3) if tangent else (0, 0, 0, 0, 0))
        GS = np.empty((nb, a, q, 3) if geo else (0, 0, 0, 0))
        GT = np.empty_like(GS)
        if L is not None:
            Lf = L[s:t]
        else:  # any factor works for f; for K the fallback below pairs B (C dV) with B
            Lf = np.ascontiguousarray(C[s:t] * dV[s:t, :, None, None])
        _jit.point_terms(g[s:t], dV[s:t], C[s:t], Lf, U[s:t], nonlinear, tangent, geo, f[s:t], X, GS, GT)
        if not tangent:
            continue
        Xr = X.reshape(nb, 6 * q, m)
        if L is not None:  # Xᵀ X: NumPy dispatches a matrix times its own transpose to BLAS syrk
            np.matmul(Xr.transpose(0, 2, 1), Xr, out=K[s:t])
        else:  # C dV not positive definite: K = Bᵀ (B C dV), B from the identity "factor"
            B = np.empty_like(X)
            _jit.point_terms(g[s:t], dV[s:t], C[s:t], np.ascontiguousarray(np.broadcast_to(_IDENTITY6, Lf.shape)),
                             U[s:t], nonlinear, True, False, np.empty((nb, a, 3)), B, GS, GT)
            np.matmul(B.reshape(nb, 6 * q, m).transpose(0, 2, 1), Xr, out=K[s:t])
        if geo:
            Kg = np.matmul(GS.reshape(nb, a, 3 * q), GT.reshape(nb, a, 3 * q).transpose(0, 2, 1))
            _jit.add_geometric(K[s:t], Kg)


def kernel_threads() -> int:
    """Threads for the element kernel: ``LAYERSHELL_THREADS``, else ``NUMBA_NUM_THREADS`` /
    ``OMP_NUM_THREADS`` (set to 1 by sweep workers), else the CPUs this process may use."""
    for var in ("LAYERSHELL_THREADS", "NUMBA_NUM_THREADS", "OMP_NUM_THREADS"):
        v = os.environ.get(var, "").strip()
        if v.isdigit() and int(v) > 0:
            return int(v)
    try:
        return max(1, len(os.sched_getaffinity(0)))
    except AttributeError:  # pragma: no cover - not Linux
        return max(1, os.cpu_count() or 1)


_POOLS: dict[int, ThreadPoolExecutor] = {}
_LOCK = threading.Lock()


def _pool(n: int) -> ThreadPoolExecutor:
    with _LOCK:
        if n not in _POOLS:
            _POOLS[n] = ThreadPoolExecutor(n, thread_name_prefix="layershell-kernel")
        return _POOLS[n]


def layer_response(
    block: LayerBlock,
    U: np.ndarray,
    nonlinear: bool = True,
    tangent: bool = True,
    sl: slice = slice(None),
):
    """Internal force ``(e, a*3)`` and tangent ``(e, a*3, a*3)`` of a layer block (2.267)-(2.268).

    ``U (e, a, 3)`` are the element's nodal director vectors; ``sl`` restricts to an
    element range (for chunked assembly). Same results as :func:`layer_response_reference`
    to round-off. A :class:`~.mitc.MitcBlock` is evaluated by :func:`.mitc.mitc_response`.
    """
    if not isinstance(block, LayerBlock):
        from .mitc import mitc_response

        return mitc_response(block, U, nonlinear, tangent, sl)
    g, dV, C = (np.ascontiguousarray(x[sl], dtype=np.float64) for x in (block.gradphi, block.dV, block.C))
    L = np.ascontiguousarray(block.L[sl]) if block.L is not None else None
    U = np.ascontiguousarray(U, dtype=np.float64)
    nonlinear, tangent = bool(nonlinear), bool(tangent)
    e, _, a = g.shape[:3]
    m = 3 * a
    f = np.empty((e, a, 3))
    K = np.empty((e, m, m)) if tangent else None
    n_threads = min(kernel_threads(), max(1, e // _SUB))
    with blas_single_thread() if tangent else nullcontext():
        if n_threads == 1:
            _response_range(g, dV, C, L, U, nonlinear, tangent, f, K, 0, e)
        else:
            bounds = np.linspace(0, e, n_threads + 1).astype(int)
            jobs = [_pool(n_threads).submit(_response_range, g, dV, C, L, U, nonlinear, tangent, f, K, lo, hi)
                    for lo, hi in zip(bounds[:-1], bounds[1:])]
            for j in jobs:
                j.result()
    return f.reshape(e, m), K
