"""Reference-surface geometry and shell-space bases, MODEL.md §2 / thesis (2.4)-(2.32).

Axis convention for batched arrays: ``e`` element, ``q`` point, ``i, j`` Cartesian (3),
``a, b`` surface index (2), ``n`` element node (9).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .shape import quad9


@dataclass(frozen=True)
class SurfacePoints:
    """Reference-surface quantities at in-plane points ``(xi, eta)`` of every element.

    Attributes (``e`` elements, ``q`` points):
      N (q|e q, 9), dN (..., 9, 2): shape functions and derivatives
      X0 (e, q, 3): position; A (e, q, 3, 2): covariant base vectors A_1, A_2 (columns)
      A3 (e, q, 3): unit normal (2.7); sqrtA (e, q): area Jacobian (2.10)
      Bmix (e, q, 2, 2): mixed curvature B^lambda_alpha as ``Bmix[..., lam, alpha]`` (2.12)
    """

    N: np.ndarray
    dN: np.ndarray
    X0: np.ndarray
    A: np.ndarray
    A3: np.ndarray
    sqrtA: np.ndarray
    Bmix: np.ndarray

    def interpolate(self, nodal: np.ndarray) -> np.ndarray:
        """Interpolate nodal values ``(e, 9, ...)`` to the points -> ``(e, q, ...)``."""
        if self.N.ndim == 2:
            return np.einsum("qn,en...->eq...", self.N, nodal)
        return np.einsum("eqn,en...->eq...", self.N, nodal)


def surface_points(X: np.ndarray, xi: np.ndarray, eta: np.ndarray, per_element: bool = False) -> SurfacePoints:
    """Evaluate the reference surface of elements with nodal coordinates ``X (e, 9, 3)``.

    ``xi, eta`` are ``(q,)`` shared by all elements, or ``(e, q)`` with ``per_element=True``.
    """
    N, dN, ddN = quad9(xi, eta)
    sub = "eqn" if per_element else "qn"
    X0 = np.einsum(f"{sub},eni->eqi", N, X)
    A = np.einsum(f"{sub}a,eni->eqia", dN, X)
    dA = np.einsum(f"{sub}ab,eni->eqiab", ddN, X)  # A_{alpha,beta}
    n = np.cross(A[..., 0], A[..., 1])
    sqrtA = np.linalg.norm(n, axis=-1)
    A3 = n / sqrtA[..., None]
    Acov = np.einsum("eqia,eqib->eqab", A, A)
    Acon = np.linalg.inv(Acov)
    Bcov = np.einsum("eqi,eqiab->eqab", A3, dA)
    Bmix = np.einsum("eqlm,eqma->eqla", Acon, Bcov)
    return SurfacePoints(N, dN, X0, A, A3, sqrtA, Bmix)


def shell_basis(sp: SurfacePoints, theta1: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Covariant basis of the shell space at thickness coordinate ``theta1`` (Θ_1³).

    ``theta1`` broadcasts against ``(e, q, z)``. Returns ``G (e, q, z, 3, 3)`` with columns
    G_1, G_2, G_3 (2.27)-(2.28), ``Ginv`` whose rows are the contravariant G^i, and
    ``detG = mu * sqrtA`` (2.31)-(2.32).
    """
    t = np.asarray(theta1, dtype=float)
    if t.ndim < 3:
        t = np.broadcast_to(t, sp.sqrtA.shape + (t.shape[-1] if t.ndim else 1,))
    # G_alpha = A_alpha - Θ B^lam_alpha A_lam
    BA = np.einsum("eqil,eqla->eqia", sp.A, sp.Bmix)
    Ga = sp.A[:, :, None] - t[..., None, None] * BA[:, :, None]
    G = np.concatenate([Ga, np.broadcast_to(sp.A3[:, :, None, :, None], Ga.shape[:-1] + (1,))], axis=-1)
    Ginv = np.linalg.inv(G)
    detG = np.linalg.det(G)
    return G, Ginv, detG
