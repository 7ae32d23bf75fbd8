"""Compiled point loops of the layer kernel (Numba, ``cache=True``, GIL released).

Imported lazily by :mod:`layershell.element.kernel` on the first evaluation. Equations: MODEL.md
§5 / thesis (2.54), (2.249), (2.267)-(2.268); see ``kernel.py`` for the factored form.
"""
from __future__ import annotations

import numpy as np
from numba import njit

_VMAP = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2]], dtype=np.int64)  # Voigt index of (J, K)


@njit(cache=True, nogil=True)
def point_terms(g, dV, C, L, U, nonlinear, want_x, want_geo, f, X, GS, GT):  # pragma: no cover
    """Per point: strains, PK2 stress, internal force f (e, a, 3) and, on request, the factored
    strain-displacement rows X (e, q, 6, a, 3) = B L and the geometric-term operands
    GS = g S dV, GT = g, both (e, a, q, 3). L is the factor of C dV, or any (e, q, 6, 6) map."""
    ne, nq, na = g.shape[0], g.shape[1], g.shape[2]
    H = np.empty((3, 3))
    F = np.empty((3, 3))
    Ev = np.empty(6)
    Sv = np.empty(6)
    S = np.empty((3, 3))
    P = np.empty((3, 3))
    Phi = np.empty((6, 3, 3))
    for e in range(ne):
        for a in range(na):
            for i in range(3):
                f[e, a, i] = 0.0
        for q in range(nq):
            for i in range(3):
                for J in range(3):
                    H[i, J] = 0.0
            for a in range(na):
                for i in range(3):
                    u = U[e, a, i]
                    for J in range(3):
                        H[i, J] += u * g[e, q, a, J]
            for I in range(3):
                for J in range(3):
                    F[I, J] = (1.0 if I == J else 0.0) + (H[I, J] if nonlinear else 0.0)
            # Green-Lagrange strain (2.54), Voigt with engineering shear
            for I in range(3):
                for J in range(I, 3):
                    s = 0.5 * (H[I, J] + H[J, I])
                    if nonlinear:
                        s += 0.5 * (H[0, I] * H[0, J] + H[1, I] * H[1, J] + H[2, I] * H[2, J])
                    S[I, J] = s
            Ev[0], Ev[1], Ev[2] = S[0, 0], S[1, 1], S[2, 2]
            Ev[3], Ev[4], Ev[5] = 2.0 * S[1, 2], 2.0 * S[0, 2], 2.0 * S[0, 1]
            w = dV[e, q]
            for V in range(6):
                s = 0.0
                for W in range(6):
                    s += C[e, q, V, W] * Ev[W]
                Sv[V] = s * w
            S[0, 0], S[1, 1], S[2, 2] = Sv[0], Sv[1], Sv[2]
            S[1, 2] = S[2, 1] = Sv[3]
            S[0, 2] = S[2, 0] = Sv[4]
            S[0, 1] = S[1, 0] = Sv[5]
            for K in range(3):
                for i in range(3):
                    P[K, i] = S[K, 0] * F[i, 0] + S[K, 1] * F[i, 1] + S[K, 2] * F[i, 2]
            for a in range(na):
                g0, g1, g2 = g[e, q, a, 0], g[e, q, a, 1], g[e, q, a, 2]
                for i in range(3):
                    f[e, a, i] += g0 * P[0, i] + g1 * P[1, i] + g2 * P[2, i]
            if want_x:
                for W in range(6):
                    for K in range(3):
                        for i in range(3):
                            Phi[W, K, i] = (F[i, 0] * L[e, q, _VMAP[0, K], W] + F[i, 1] * L[e, q, _VMAP[1, K], W]
                                            + F[i, 2] * L[e, q, _VMAP[2, K], W])
                for W in range(6):
                    for a in range(na):
                        g0, g1, g2 = g[e, q, a, 0], g[e, q, a, 1], g[e, q, a, 2]
                        for i in range(3):
                            X[e, q, W, a, i] = g0 * Phi[W, 0, i] + g1 * Phi[W, 1, i] + g2 * Phi[W, 2, i]
            if want_geo:
                for a in range(na):
                    g0, g1, g2 = g[e, q, a, 0], g[e, q, a, 1], g[e, q, a, 2]
                    for K in range(3):
                        GS[e, a, q, K] = g0 * S[0, K] + g1 * S[1, K] + g2 * S[2, K]
                        GT[e, a, q, K] = g[e, q, a, K]


@njit(cache=True, nogil=True)
def add_geometric(K, Kg):  # pragma: no cover
    """K[e, 3a+i, 3b+i] += Kg[e, a, b] (the δ_ik of (2.268))."""
    ne, na = Kg.shape[0], Kg.shape[1]
    for e in range(ne):
        for a in range(na):
            for b in range(na):
                v = Kg[e, a, b]
                for i in range(3):
                    K[e, 3 * a + i, 3 * b + i] += v


@njit(cache=True, nogil=True, fastmath=True)
def mitc_terms(Nn, dNn, thL, G, M, pts, nt, w, dirs, ndir, Ct, L, U, d, nonlinear, want_x, want_geo, lower,
               f, X, GS, GT):  # pragma: no cover
    """MITC9 layer kernel per element and thickness level (``mitc.py``): covariant strains and
    their rows at the sampling points, tied to the Gauss points; internal force f (e, m) with
    m = 3a (DOF index 3·a + k), on request X (e, z·9, 6, m) = Lᵀ B̃ (L the lower factor of the
    covariant stiffness C̃ when ``lower``, else any map) and the geometric operands
    GS = ∂phi σ, GT = ∂phi (e, a, columns)."""
    ne, nz, P = thL.shape[0], thL.shape[1], thL.shape[2]
    nd = d + 1
    na = 9 * nd
    m = 3 * na
    T = pts.shape[1]
    dphi = np.empty((P, na, 3))
    gg = np.empty((P, 3, 3))
    D = np.empty((3, 3))
    Ecov = np.empty((P, 6))
    Bc = np.empty((6, T, m))
    Bt = np.empty((6, m))
    sig = np.empty((P, 3, 3))
    Et = np.empty(6)
    S = np.empty(6)
    pw = np.empty(nd)
    dpw = np.empty(nd)
    pi = np.array([0, 1, 2, 1, 0, 0])
    pj = np.array([0, 1, 2, 2, 2, 1])
    for e in range(ne):
        for r in range(m):
            f[e, r] = 0.0
        col = 0
        for z in range(nz):
            for p in range(P):
                th = thL[e, z, p]
                for l in range(nd):
                    pw[l] = th ** l
                    dpw[l] = l * th ** (l - 1) if l > 0 else 0.0
                for n in range(9):
                    for l in range(nd):
                        a = n * nd + l
                        d0 = dNn[p, n, 0] * pw[l]
                        d1 = dNn[p, n, 1] * pw[l]
                        d2 = Nn[p, n] * dpw[l]
                        for b in range(3):  # derivative along the frame vector F_b
                            dphi[p, a, b] = d0 * M[e, z, p, 0, b] + d1 * M[e, z, p, 1, b] + d2 * M[e, z, p, 2, b]
                for i in range(3):
                    for k in range(3):
                        D[i, k] = 0.0
                for a in range(na):
                    for i in range(3):
                        da = dphi[p, a, i]
                        for k in range(3):
                            D[i, k] += da * U[e, a, k]
                for i in range(3):
                    for k in range(3):
                        gg[p, i, k] = G[e, z, p, k, i] + (D[i, k] if nonlinear else 0.0)
                for c in range(6):
                    i, j = pi[c], pj[c]
                    s = 0.0
                    for k in range(3):
                        s += 0.5 * (G[e, z, p, k, i] * D[j, k] + D[i, k] * G[e, z, p, k, j])
                        if nonlinear:
                            s += 0.5 * D[i, k] * D[j, k]
                    Ecov[p, c] = s if i == j else 2.0 * s
                for i in range(3):
                    for j in range(3):
                        sig[p, i, j] = 0.0
            for c in range(6):
                i, j = pi[c], pj[c]
                for t in range(nt[c]):
                    p = pts[c, t]
                    gi0, gi1, gi2 = gg[p, i, 0], gg[p, i, 1], gg[p, i, 2]
                    gj0, gj1, gj2 = gg[p, j, 0], gg[p, j, 1], gg[p, j, 2]
                    for a in range(na):
                        if i == j:
                            di = dphi[p, a, i]
                            Bc[c, t, 3 * a] = gi0 * di
                            Bc[c, t, 3 * a + 1] = gi1 * di
                            Bc[c, t, 3 * a + 2] = gi2 * di
                        else:
                            di, dj = dphi[p, a, i], dphi[p, a, j]
                            Bc[c, t, 3 * a] = gi0 * dj + gj0 * di
                            Bc[c, t, 3 * a + 1] = gi1 * dj + gj1 * di
                            Bc[c, t, 3 * a + 2] = gi2 * dj + gj2 * di
            for q in range(9):
                for c in range(6):
                    s = 0.0
                    for t in range(nt[c]):
                        s += w[c, q, t] * Ecov[pts[c, t], c]
                    Et[c] = s
                for c in range(6):
                    s = 0.0
                    for c2 in range(6):
                        s += Ct[e, z, q, c, c2] * Et[c2]
                    S[c] = s
                for c in range(6):
                    first = True
                    for t in range(nt[c]):
                        wt = w[c, q, t]
                        if wt != 0.0:
                            if first:
                                for r in range(m):
                                    Bt[c, r] = wt * Bc[c, t, r]
                                first = False
                            else:
                                for r in range(m):
                                    Bt[c, r] += wt * Bc[c, t, r]
                    if first:
                        for r in range(m):
                            Bt[c, r] = 0.0
                    sc = S[c]
                    for r in range(m):
                        f[e, r] += sc * Bt[c, r]
                if want_x:
                    row = z * 9 + q
                    for W in range(6):
                        c0 = W if lower else 0
                        lw = L[e, z, q, c0, W]
                        for r in range(m):
                            X[e, row, W, r] = lw * Bt[c0, r]
                        for c in range(c0 + 1, 6):
                            lw = L[e, z, q, c, W]
                            for r in range(m):
                                X[e, row, W, r] += lw * Bt[c, r]
                if want_geo:
                    for c in range(6):
                        i, j = pi[c], pj[c]
                        for t in range(nt[c]):
                            v = w[c, q, t] * S[c]
                            p = pts[c, t]
                            sig[p, i, j] += v
                            if i != j:
                                sig[p, j, i] += v
            if want_geo:
                for p in range(P):
                    for r in range(ndir[p]):
                        K = dirs[p, r]
                        for a in range(na):
                            GS[e, a, col] = dphi[p, a, 0] * sig[p, 0, K] + dphi[p, a, 1] * sig[p, 1, K] \
                                + dphi[p, a, 2] * sig[p, 2, K]
                            GT[e, a, col] = dphi[p, a, K]
                        col += 1
