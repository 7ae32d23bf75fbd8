"""Compiled hot spots of the spectral split (:mod:`layershell.laws.spectral`; Numba, ``cache=True``).

:func:`eigh3`: the eigen-decomposition of many symmetric 3 × 3 matrices by cyclic Jacobi sweeps
(LAPACK's batched ``eigh`` spends about 1 µs per 3 × 3 matrix, mostly call overhead; the sweeps
about 0.3 µs). :func:`isotropic_derivative3`: the 6 × 6 derivative of an isotropic tensor function
from the eigenvectors (as NumPy, the basis and the batched product cost about 1 µs per point). Jacobi
rotations give the eigenvalues to round-off of the matrix norm and orthonormal eigenvectors (Golub &
Van Loan, Matrix Computations, 4th ed., §8.5); each rotation zeroes one off-diagonal entry with the
stable small-angle formula, and the sweeps stop once every off-diagonal entry is negligible against
its two diagonal entries (it then is set to zero) or after ``MAX_SWEEPS``.
"""
from __future__ import annotations

import numpy as np
from numba import njit

MAX_SWEEPS = 30  # Jacobi converges quadratically: 3 × 3 matrices need 4-6 sweeps; a cap against NaN input
_PAIRS = ((0, 1), (0, 2), (1, 2))
_R2 = np.sqrt(2.0)


@njit(cache=True, nogil=True)
def eigh3(A, w, V, P):  # pragma: no cover
    """Eigenvalues ``w (n, 3)`` ascending and unit eigenvectors ``V (n, 3, 3)`` (columns) of the
    symmetric ``A (n, 3, 3)`` (its upper triangle is read); where ``P`` has n rows, also the
    projections P (n, 3, 6) = v_k ⊗ v_k in Voigt order [11, 22, 33, 23, 13, 12]."""
    a = np.empty((3, 3))
    v = np.empty((3, 3))
    for n in range(A.shape[0]):
        for i in range(3):
            for j in range(3):
                a[i, j] = A[n, min(i, j), max(i, j)]
                v[i, j] = 1.0 if i == j else 0.0
        for _ in range(MAX_SWEEPS):
            if a[0, 1] == 0.0 and a[0, 2] == 0.0 and a[1, 2] == 0.0:
                break
            for p, q in _PAIRS:
                apq = a[p, q]
                if apq == 0.0:
                    continue
                g = 100.0 * abs(apq)
                if abs(a[p, p]) + g == abs(a[p, p]) and abs(a[q, q]) + g == abs(a[q, q]):
                    a[p, q] = a[q, p] = 0.0  # below round-off of both diagonal entries
                    continue
                theta = (a[q, q] - a[p, p]) / (2.0 * apq)
                if abs(theta) > 1e150:
                    t = 0.5 / theta
                else:
                    t = (1.0 if theta >= 0.0 else -1.0) / (abs(theta) + np.sqrt(theta * theta + 1.0))
                c = 1.0 / np.sqrt(t * t + 1.0)
                s = t * c
                a[p, p] -= t * apq
                a[q, q] += t * apq
                a[p, q] = a[q, p] = 0.0
                r = 3 - p - q  # the third index
                arp, arq = a[r, p], a[r, q]
                a[r, p] = a[p, r] = c * arp - s * arq
                a[r, q] = a[q, r] = s * arp + c * arq
                for k in range(3):
                    vkp, vkq = v[k, p], v[k, q]
                    v[k, p] = c * vkp - s * vkq
                    v[k, q] = s * vkp + c * vkq
        i0, i1, i2 = 0, 1, 2  # ascending order
        if a[i0, i0] > a[i1, i1]:
            i0, i1 = i1, i0
        if a[i1, i1] > a[i2, i2]:
            i1, i2 = i2, i1
        if a[i0, i0] > a[i1, i1]:
            i0, i1 = i1, i0
        w[n, 0], w[n, 1], w[n, 2] = a[i0, i0], a[i1, i1], a[i2, i2]
        for k in range(3):
            V[n, k, 0], V[n, k, 1], V[n, k, 2] = v[k, i0], v[k, i1], v[k, i2]
        if P.shape[0] == A.shape[0]:
            for k in range(3):
                x, y, z = V[n, 0, k], V[n, 1, k], V[n, 2, k]
                P[n, k, 0], P[n, k, 1], P[n, k, 2] = x * x, y * y, z * z
                P[n, k, 3], P[n, k, 4], P[n, k, 5] = y * z, x * z, x * y


def eigh(A: np.ndarray, projections: bool = False):
    """``numpy.linalg.eigh`` of a stack of symmetric 3 × 3 matrices ``(n, 3, 3)``: (w, V), and with
    ``projections`` the projections P (n, 3, 6) = v_k ⊗ v_k (Voigt) too."""
    A = np.ascontiguousarray(A, dtype=np.float64)
    n = A.shape[0]
    w, V = np.empty((n, 3)), np.empty((n, 3, 3))
    P = np.empty((n, 3, 6) if projections else (0, 3, 6))
    eigh3(A, w, V, P)
    return (w, V, P) if projections else (w, V)


@njit(cache=True, nogil=True, inline="always")
def voigt_basis(V, n, B):  # pragma: no cover
    """B (6, 6): row b the Mandel vector of the eigenbasis dyad v_i ⊗ v_j of point n (b < 3: i = j = b;
    b ≥ 3: the pair _PAIRS[b − 3], symmetrised and scaled by √2), in Voigt strain order."""
    for b in range(6):
        if b < 3:
            i = j = b
            f = 1.0
        else:
            i, j = _PAIRS[b - 3]
            f = _R2
        xi, yi, zi = V[n, 0, i], V[n, 1, i], V[n, 2, i]
        xj, yj, zj = V[n, 0, j], V[n, 1, j], V[n, 2, j]
        B[b, 0], B[b, 1], B[b, 2] = f * xi * xj, f * yi * yj, f * zi * zj
        B[b, 3] = 0.5 * f * (yi * zj + zi * yj)
        B[b, 4] = 0.5 * f * (xi * zj + zi * xj)
        B[b, 5] = 0.5 * f * (xi * yj + yi * xj)


@njit(cache=True, nogil=True)
def isotropic_derivative3(V, c, out):  # pragma: no cover
    """out (n, 6, 6) = Bᵀ diag(c) B · diag(1, 1, 1, 2, 2, 2) per point, B the rows v_k ⊗ v_k
    (k = 0, 1, 2) and √2 sym(v_i ⊗ v_j) ((i, j) = (0, 1), (0, 2), (1, 2)) in Voigt order, from the
    eigenvectors V (n, 3, 3) (columns) and the coefficients c (n, 6)
    (:func:`layershell.laws.spectral.isotropic_derivative`)."""
    B = np.empty((6, 6))
    for n in range(V.shape[0]):
        voigt_basis(V, n, B)
        for a in range(6):
            for d in range(6):
                s = 0.0
                for b in range(6):
                    s += B[b, a] * c[n, b] * B[b, d]
                out[n, a, d] = s * (1.0 if d < 3 else 2.0)
