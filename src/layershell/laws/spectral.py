"""Spectral tools for symmetric 3 × 3 tensors stored in Voigt form ``[11, 22, 33, 23, 13, 12]``.

Stress-like Voigt vectors hold tensor components; strain-like ones engineering shears. A linear
map of a stress-like argument ``dA`` is written as a row ``r`` with ``r @ dA`` where the shear
entries of ``r`` carry the factor 2 of the two tensor entries they stand for (``WEIGHT``).
"""
from __future__ import annotations

import numpy as np

WEIGHT = np.array([1.0, 1.0, 1.0, 2.0, 2.0, 2.0])  # A : dB = Σ_a A_a dB_a WEIGHT_a for stress-like A, B
PAIRS = ((0, 1), (0, 2), (1, 2))


def to_tensor(v: np.ndarray) -> np.ndarray:
    """(n, 6) stress-like Voigt -> (n, 3, 3)."""
    t = np.empty(v.shape[:-1] + (3, 3))
    t[..., 0, 0], t[..., 1, 1], t[..., 2, 2] = v[..., 0], v[..., 1], v[..., 2]
    t[..., 1, 2] = t[..., 2, 1] = v[..., 3]
    t[..., 0, 2] = t[..., 2, 0] = v[..., 4]
    t[..., 0, 1] = t[..., 1, 0] = v[..., 5]
    return t


def dyad(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Stress-like Voigt form of sym(a ⊗ b) for (n, 3) vectors a, b."""
    out = np.empty(a.shape[:-1] + (6,))
    np.multiply(a[:, :3], b[:, :3], out=out[:, :3])
    out[:, 3] = 0.5 * (a[:, 1] * b[:, 2] + a[:, 2] * b[:, 1])
    out[:, 4] = 0.5 * (a[:, 0] * b[:, 2] + a[:, 2] * b[:, 0])
    out[:, 5] = 0.5 * (a[:, 0] * b[:, 1] + a[:, 1] * b[:, 0])
    return out


def principal(v: np.ndarray):
    """Eigenvalues (n, 3) ascending, eigenvectors (n, 3, 3) as columns, projections P_k (n, 3, 6)."""
    from ._spectral_jit import eigh  # compiled (Numba): LAPACK's batched eigh costs ~1 µs per 3 × 3 matrix

    return eigh(to_tensor(v), projections=True)


def isotropic_derivative(V, a, theta):
    """d(Σ s_k P_k)/dA as a (n, 6, 6) stress-like Voigt matrix (columns weighted by ``WEIGHT``) for
    s_k depending on its own eigenvalue only.

    ``a[:, k] = ∂s_k/∂w_k`` (n, 3) and ``theta[:, p]`` the ratio (s_i - s_j)/(w_i - w_j) for the pair
    ``PAIRS[p]`` (its equal-eigenvalue limit where w_i = w_j, supplied by the caller):
    dF = Σ_k a_k P_k (P_k : dA) + Σ_(i<j) 2 θ_ij M_ij (M_ij : dA), M_ij = sym(v_i ⊗ v_j), i.e.
    Bᵀ diag(a, θ) B in the orthonormal basis B = (P_1, P_2, P_3, √2 M_12, √2 M_13, √2 M_23).
    """
    from ._spectral_jit import isotropic_derivative3  # compiled: the 6 × 6 product per point

    c = np.ascontiguousarray(np.concatenate([a, theta], axis=1), dtype=np.float64)
    out = np.empty((V.shape[0], 6, 6))
    isotropic_derivative3(np.ascontiguousarray(V, dtype=np.float64), c, out)
    return out


def eigvec_derivative_row(V, w, k, c):
    """Row r (n, 6) with r @ dA = c · dv_k for the unit eigenvector v_k of A:
    dv_k = Σ_(j≠k) v_j (v_j · dA · v_k)/(w_k - w_j). Where w_k equals another eigenvalue v_k is not
    a differentiable function of A; that pair contributes 0 there."""
    r = np.zeros((V.shape[0], 6))
    for j in range(3):
        if j != k:
            gap = w[:, k] - w[:, j]
            cj = np.einsum("ni,ni->n", c, V[:, :, j]) / np.where(gap != 0, gap, np.inf)
            r += cj[:, None] * dyad(V[:, :, j], V[:, :, k]) * WEIGHT
    return r
