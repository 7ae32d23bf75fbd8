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
    e = X.shape[0]
    q = N.shape[-2]
    # batched matrix products (BLAS) rather than einsum: this runs for every stress point of
    # the recovery and every probe; the values are the same sums
    X0 = np.matmul(N, X)  # (e, q, 3)
    D = np.concatenate([dN, ddN.reshape(ddN.shape[:-2] + (4,))], -1)  # (…, q, n, 6): ∂_a, ∂_ab
    Dt = np.swapaxes(D, -1, -2)  # (…, q, 6, n)
    if per_element:
        AD = np.matmul(Dt, X[:, None])  # (e, q, 6, 3)
    else:
        AD = np.matmul(Dt.reshape(q * 6, 9), X).reshape(e, q, 6, 3)
    A = np.swapaxes(AD[:, :, :2], -1, -2)  # (e, q, i, a)
    dA = np.moveaxis(AD[:, :, 2:].reshape(e, q, 2, 2, 3), -1, 2)  # A_{alpha,beta} (e, q, i, a, b)
    n = np.cross(A[..., 0], A[..., 1])
    sqrtA = np.linalg.norm(n, axis=-1)
    A3 = n / sqrtA[..., None]
    Acov = np.matmul(np.swapaxes(A, -1, -2), A)
    Acon = np.linalg.inv(Acov)
    Bcov = np.matmul(AD[:, :, 2:], A3[..., None])[..., 0].reshape(e, q, 2, 2)
    Bmix = np.matmul(Acon, Bcov)
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
    Ginv, detG = inv3(G)
    return G, Ginv, detG


def inv3(G: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverse and determinant of a stack of 3 × 3 matrices ``(…, 3, 3)`` by the adjugate
    (cofactors as cross products of the columns): the same values as ``numpy.linalg.inv`` /
    ``det`` to round-off, several times faster on the many small matrices of the point
    evaluations (the stress recovery inverts one per point)."""
    a, b, c = G[..., 0], G[..., 1], G[..., 2]  # columns
    bc, ca, ab = np.cross(b, c), np.cross(c, a), np.cross(a, b)
    det = np.einsum("...i,...i->...", a, bc)
    inv = np.stack([bc, ca, ab], axis=-2) / det[..., None, None]  # rows: the reciprocal basis
    return inv, det
