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
    their rows at the tying points (only the frame directions a point is tied in), tied to the
    Gauss points; internal force f (e, m) with m = 3a (DOF index 3·a + k), on request
    X (e, z·9, 6, m) = Lᵀ B̃ (L the lower factor of the covariant stiffness C̃ when ``lower``,
    else any map) and the geometric operands GS = ∂phi σ, GT = ∂phi (e, a, columns)."""
    ne, nz, P = thL.shape[0], thL.shape[1], thL.shape[2]
    nd = d + 1
    na = 9 * nd
    m = 3 * na
    T = pts.shape[1]
    dphi = np.empty((P, na, 3))
    gg = np.empty((P, 3, 3))
    D = np.empty((P, 3, 3))
    Ect = np.empty((6, T))
    Bc = np.empty((6, T, m))
    Bt = np.empty((6, m))
    sig = np.empty((6, T))
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
                for r in range(ndir[p]):
                    b = dirs[p, r]
                    m0, m1, m2 = M[e, z, p, 0, b], M[e, z, p, 1, b], M[e, z, p, 2, b]
                    D0 = 0.0
                    D1 = 0.0
                    D2 = 0.0
                    for n in range(9):
                        dn = dNn[p, n, 0] * m0 + dNn[p, n, 1] * m1
                        nn = Nn[p, n] * m2
                        for l in range(nd):
                            a = n * nd + l
                            v = dn * pw[l] + nn * dpw[l]  # derivative of phi_a along F_b
                            dphi[p, a, b] = v
                            D0 += v * U[e, a, 0]
                            D1 += v * U[e, a, 1]
                            D2 += v * U[e, a, 2]
                    D[p, b, 0], D[p, b, 1], D[p, b, 2] = D0, D1, D2
                    for k in range(3):
                        gg[p, b, k] = G[e, z, p, k, b] + (D[p, b, k] if nonlinear else 0.0)
            for c in range(6):
                i, j = pi[c], pj[c]
                for t in range(nt[c]):
                    p = pts[c, t]
                    s = 0.0
                    for k in range(3):
                        s += 0.5 * (G[e, z, p, k, i] * D[p, j, k] + D[p, i, k] * G[e, z, p, k, j])
                        if nonlinear:
                            s += 0.5 * D[p, i, k] * D[p, j, k]
                    Ect[c, t] = s if i == j else 2.0 * s
                    sig[c, t] = 0.0
                    gi0, gi1, gi2 = gg[p, i, 0], gg[p, i, 1], gg[p, i, 2]
                    gj0, gj1, gj2 = gg[p, j, 0], gg[p, j, 1], gg[p, j, 2]
                    if i == j:
                        for a in range(na):
                            di = dphi[p, a, i]
                            Bc[c, t, 3 * a] = gi0 * di
                            Bc[c, t, 3 * a + 1] = gi1 * di
                            Bc[c, t, 3 * a + 2] = gi2 * di
                    else:
                        for a in range(na):
                            di, dj = dphi[p, a, i], dphi[p, a, j]
                            Bc[c, t, 3 * a] = gi0 * dj + gj0 * di
                            Bc[c, t, 3 * a + 1] = gi1 * dj + gj1 * di
                            Bc[c, t, 3 * a + 2] = gi2 * dj + gj2 * di
            for q in range(9):
                for c in range(6):
                    s = 0.0
                    for t in range(nt[c]):
                        s += w[c, q, t] * Ect[c, t]
                    Et[c] = s
                for c in range(6):
                    s = 0.0
                    for c2 in range(6):
                        s += Ct[e, z, q, c, c2] * Et[c2]
                    S[c] = s
                    for t in range(nt[c]):
                        sig[c, t] += w[c, q, t] * s
                if want_x:
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
            # internal force from the tied stresses at the tying points: f = Σ σ_ct B_ct
            for c in range(6):
                for t in range(nt[c]):
                    v = sig[c, t]
                    for r in range(m):
                        f[e, r] += v * Bc[c, t, r]
            if want_geo:
                for p in range(P):
                    for r in range(ndir[p]):
                        K = dirs[p, r]
                        for a in range(na):
                            GS[e, a, col] = 0.0
                            GT[e, a, col] = dphi[p, a, K]
                        for c in range(6):  # Σ_J dphi_J σ_JK over the components tied at p
                            i, j = pi[c], pj[c]
                            if i != K and j != K:
                                continue
                            J = j if i == K else i
                            for t in range(nt[c]):
                                if pts[c, t] == p:
                                    v = sig[c, t]
                                    for a in range(na):
                                        GS[e, a, col] += v * dphi[p, a, J]
                        col += 1
