"""Exact 3D elasticity solution of a simply supported cross-ply laminate under a double-sine load.

Pagano, N. J. (1970), "Exact solutions for rectangular bidirectional composites and sandwich
plates", J. Compos. Mater. 4, 20-34 (and Pagano 1969 for cylindrical bending), solved here by
the state-space / transfer-matrix method (e.g. Fan & Ye 1990; Zenkour 2007): in each ply the
amplitudes of the state vector s = [U, V, W, X, Y, Z] (u, v, w, τxz, τyz, σzz) obey the linear
ODE s' = A s, so s(z_top) = exp(A h) s(z_bot); continuity of s at the interfaces and the face
tractions close the problem.

Plate 0 ≤ x ≤ a, 0 ≤ y ≤ b, 0 ≤ z ≤ h (z from the bottom face), plies of specially orthotropic
material (principal axes along x and y: 0° or 90° plies), edges simply supported in the 3D sense
(w = 0, σ_nn = 0 and the tangential displacement zero along the whole edge face), bottom face
free, top face loaded by the normal traction σzz(x, y, h) = -q0 sin(πx/a) sin(πy/b) (a
pressure q0 pushing down, towards -z). Fields (p = mπ/a, q = nπ/b)::

    u = U(z) cos px sin qy,   v = V(z) sin px cos qy,   w = W(z) sin px sin qy,
    σxx, σyy, σzz ∝ sin px sin qy,   τxy ∝ cos px cos qy,
    τxz = X(z) cos px sin qy, τyz = Y(z) sin px cos qy.

Voigt order of the 6 × 6 stiffness matrices: xx, yy, zz, yz, xz, xy (as :mod:`layershell.material`).
Pure functions over arrays; nothing here knows the finite-element model.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.linalg import expm

_SWAP_XY = np.array([1, 0, 2, 4, 3, 5])  # Voigt permutation exchanging the x and y axes


def ply_stiffness(c_material: np.ndarray, angle: float) -> np.ndarray:
    """Stiffness (6, 6) of a ply in plate axes: fibre (material axis 1) along x for 0°, along y
    for 90°. Other angles make the ply monoclinic (C16 ≠ 0) and the double-sine solution inexact."""
    a = float(angle) % 180.0
    if np.isclose(a, 0.0) or np.isclose(a, 180.0):
        return np.array(c_material, float)
    if np.isclose(a, 90.0):
        return np.array(c_material, float)[np.ix_(_SWAP_XY, _SWAP_XY)]
    raise ValueError(f"ply angle {angle}°: the exact double-sine solution needs 0° or 90° plies")


def system_matrix(C: np.ndarray, p: float, q: float) -> np.ndarray:
    """A (6, 6) of s' = A s for one ply with plate-axis stiffness ``C`` (derivation: the module
    docstring's fields put into εzz, γxz, γyz = C⁻¹σ and the three equilibrium equations)."""
    c11, c22, c33 = C[0, 0], C[1, 1], C[2, 2]
    c12, c13, c23 = C[0, 1], C[0, 2], C[1, 2]
    c44, c55, c66 = C[3, 3], C[4, 4], C[5, 5]
    # σxx = -Q11 p U - Q12 q V + (c13/c33) Z,  σyy = -Q12 p U - Q22 q V + (c23/c33) Z
    Q11, Q12, Q22 = c11 - c13**2 / c33, c12 - c13 * c23 / c33, c22 - c23**2 / c33
    A = np.zeros((6, 6))
    # U' = X/c55 - p W ; V' = Y/c44 - q W ; W' = (Z + p c13 U + q c23 V)/c33
    A[0, 2], A[0, 3] = -p, 1 / c55
    A[1, 2], A[1, 4] = -q, 1 / c44
    A[2, 0], A[2, 1], A[2, 5] = p * c13 / c33, q * c23 / c33, 1 / c33
    # X' = -p σxx + q τxy ; Y' = p τxy - q σyy ; Z' = p X + q Y   (τxy = c66 (q U + p V))
    A[3, 0] = p * p * Q11 + q * q * c66
    A[3, 1] = p * q * (Q12 + c66)
    A[3, 5] = -p * c13 / c33
    A[4, 0] = p * q * (Q12 + c66)
    A[4, 1] = q * q * Q22 + p * p * c66
    A[4, 5] = -q * c23 / c33
    A[5, 3], A[5, 4] = p, q
    return A


@dataclass(frozen=True)
class PaganoPlate:
    """The solved plate: ply stiffnesses (n, 6, 6) in plate axes, ply bottom heights ``z0 (n,)``
    and thicknesses ``t (n,)``, wave numbers p, q, and the state at each ply bottom ``s0 (n, 6)``."""

    C: np.ndarray
    z0: np.ndarray
    t: np.ndarray
    p: float
    q: float
    s0: np.ndarray

    @property
    def h(self) -> float:
        return float(self.t.sum())

    def state(self, z: np.ndarray) -> np.ndarray:
        """State amplitudes [U, V, W, X, Y, Z] at heights ``z`` (…,) → (…, 6). On an interface the
        ply below is used (the state is continuous)."""
        z = np.asarray(z, float)
        flat = z.ravel()
        ply = np.clip(np.searchsorted(self.z0, flat, side="left") - 1, 0, len(self.t) - 1)
        out = np.empty((flat.size, 6))
        for k in np.unique(ply):
            sel = np.flatnonzero(ply == k)
            A = system_matrix(self.C[k], self.p, self.q)
            T = expm(A[None] * (flat[sel] - self.z0[k])[:, None, None])
            out[sel] = T @ self.s0[k]
        return out.reshape(z.shape + (6,))

    def fields(self, x, y, z) -> dict[str, np.ndarray]:
        """Displacements u, v, w and stresses sxx, syy, szz, txy, txz, tyz at points (broadcast)."""
        x, y, z = np.broadcast_arrays(*(np.asarray(v, float) for v in (x, y, z)))
        s = self.state(z)
        flat = z.ravel()
        ply = np.clip(np.searchsorted(self.z0, flat, side="left") - 1, 0, len(self.t) - 1).reshape(z.shape)
        C = self.C[ply]
        U, V, W, X, Y, Z = np.moveaxis(s, -1, 0)
        p, q = self.p, self.q
        Wz = (Z + p * C[..., 0, 2] * U + q * C[..., 1, 2] * V) / C[..., 2, 2]
        Sx = -C[..., 0, 0] * p * U - C[..., 0, 1] * q * V + C[..., 0, 2] * Wz
        Sy = -C[..., 0, 1] * p * U - C[..., 1, 1] * q * V + C[..., 1, 2] * Wz
        T = C[..., 5, 5] * (q * U + p * V)
        sx, cx, sy, cy = np.sin(p * x), np.cos(p * x), np.sin(q * y), np.cos(q * y)
        return {"u": U * cx * sy, "v": V * sx * cy, "w": W * sx * sy,
                "sxx": Sx * sx * sy, "syy": Sy * sx * sy, "szz": Z * sx * sy,
                "txy": T * cx * cy, "txz": X * cx * sy, "tyz": Y * sx * cy}


def solve(C_plies, thicknesses, a: float, b: float, q0: float = 1.0, m: int = 1, n: int = 1) -> PaganoPlate:
    """Solve the laminate (plies listed bottom to top) under σzz(top) = -q0 sin(mπx/a) sin(nπy/b)
    with a traction-free bottom face: transfer matrix P = Π exp(A_k t_k), then the three unknown
    bottom displacement amplitudes from the three top traction conditions."""
    C = np.asarray(C_plies, float)
    t = np.asarray(thicknesses, float)
    if C.shape != (t.size, 6, 6):
        raise ValueError("one 6 × 6 stiffness per ply thickness")
    p, q = m * np.pi / a, n * np.pi / b
    Ts = [expm(system_matrix(C[k], p, q) * t[k]) for k in range(t.size)]
    P = np.eye(6)
    for T in Ts:
        P = T @ P
    # s_bot = [U0, V0, W0, 0, 0, 0]; top: X = Y = 0, Z = -q0
    u0 = np.linalg.solve(P[3:, :3], np.array([0.0, 0.0, -q0]))
    s = np.concatenate([u0, np.zeros(3)])
    s0 = np.empty((t.size, 6))
    for k, T in enumerate(Ts):
        s0[k] = s
        s = T @ s
    z0 = np.concatenate([[0.0], np.cumsum(t)[:-1]])
    return PaganoPlate(C, z0, t, p, q, s0)


def classical_plate_deflection(D: np.ndarray, a: float, b: float, q0: float = 1.0) -> float:
    """Kirchhoff (classical laminated plate) amplitude of w for a specially orthotropic plate with
    bending stiffnesses D = [D11, D12, D22, D66]: w = q0 / (D11 p⁴ + 2 (D12 + 2 D66) p² q² + D22 q⁴)."""
    p, q = np.pi / a, np.pi / b
    D11, D12, D22, D66 = D
    return q0 / (D11 * p**4 + 2 * (D12 + 2 * D66) * p**2 * q**2 + D22 * q**4)
