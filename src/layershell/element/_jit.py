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
def mitc_terms(Nn, dNn, thL, G, M, pts, off, nt, dirs, ndir, gn, gk, gJ, Lh, U, d, nonlinear, want_b, want_geo, lower,
               f, B, GS, GT, mode, sig_in, E_out, Dg):  # pragma: no cover
    """MITC9 layer kernel per element and thickness level (``mitc.py``), in the tie space: the
    covariant strains E_k and their rows B_k (k = tie (c, t), k = off[c] + t) at the tying points
    (only the frame directions a point is tied in), the tied stresses σ = Ĉ E with the level's
    tied stiffness Ĉ = Σ_q H_qᵀ C̃_q H_q (``Lh`` its lower factor L̂ when ``lower``, else Ĉ);
    internal force f (e, m) = Σ_k σ_k B_k = Σ_p Σ_K GS_K g_K with m = 3a (DOF index 3·a + k); on
    request the rows B (e, z, nT, m) (``want_b``; else B is unused) and the geometric operands
    GS = ∂phi σ, GT = ∂phi (e, columns, a). ``gn, gk, gJ``: for the r-th tied direction K of
    point p, the ties k and the directions J with σ_JK(p) = σ_k. ``mode`` 0: as above; 1: only the
    tie strains, into E_out (e, z, nT) (f gets zeros, nothing else is written); 2: the tie
    stresses σ given as sig_in (e, z, nT), Lh unused, and the displacement derivatives
    ∂u/∂F_b = Dg (e, z, P, 3, 3) [b, k] given (inelastic layers, :mod:`.inelastic_kernel`, whose
    strain pass forms them); Dg is unused in modes 0 and 1."""
    ne, nz, P = thL.shape[0], thL.shape[1], thL.shape[2]
    nT = off[6]
    nd = d + 1
    na = 9 * nd
    m = 3 * na
    dphi = np.empty((P, 3, na))
    gg = np.empty((P, 3, 3))
    D = np.empty((P, 3, 3))
    Ek = np.empty(nT)
    yk = np.empty(nT)
    sig = np.empty(nT)
    pw = np.empty(nd)
    dpw = np.empty(nd)
    pi = np.array([0, 1, 2, 1, 0, 0])
    pj = np.array([0, 1, 2, 2, 2, 1])
    Ut = np.empty((3, na))
    gsa = np.empty(na)
    ft = np.empty((3, na))
    for e in range(ne):
        for a in range(na):
            Ut[0, a], Ut[1, a], Ut[2, a] = U[e, a, 0], U[e, a, 1], U[e, a, 2]
            ft[0, a] = ft[1, a] = ft[2, a] = 0.0
        col = 0
        for z in range(nz):
            for p in range(P):
                th = thL[e, z, p]
                pw[0] = 1.0
                dpw[0] = 0.0
                for l in range(1, nd):
                    pw[l] = pw[l - 1] * th
                    dpw[l] = l * pw[l - 1]
                for r in range(ndir[p]):
                    b = dirs[p, r]
                    m0, m1, m2 = M[e, z, p, 0, b], M[e, z, p, 1, b], M[e, z, p, 2, b]
                    for n in range(9):
                        dn = dNn[p, n, 0] * m0 + dNn[p, n, 1] * m1
                        nn = Nn[p, n] * m2
                        for l in range(nd):
                            dphi[p, b, n * nd + l] = dn * pw[l] + nn * dpw[l]  # derivative of phi_a along F_b
                    if mode == 2:
                        D0, D1, D2 = Dg[e, z, p, b, 0], Dg[e, z, p, b, 1], Dg[e, z, p, b, 2]
                    else:
                        D0 = 0.0
                        D1 = 0.0
                        D2 = 0.0
                        for a in range(na):
                            v = dphi[p, b, a]
                            D0 += v * Ut[0, a]
                            D1 += v * Ut[1, a]
                            D2 += v * Ut[2, a]
                    D[p, b, 0], D[p, b, 1], D[p, b, 2] = D0, D1, D2
                    for k in range(3):
                        gg[p, b, k] = G[e, z, p, k, b] + (D[p, b, k] if nonlinear else 0.0)
            for c in range(6):
                i, j = pi[c], pj[c]
                for t in range(nt[c]):
                    k0 = off[c] + t
                    p = pts[c, t]
                    if mode != 2:  # the tie strain (mode 2: σ given)
                        s = 0.0
                        for k in range(3):
                            s += 0.5 * (G[e, z, p, k, i] * D[p, j, k] + D[p, i, k] * G[e, z, p, k, j])
                            if nonlinear:
                                s += 0.5 * D[p, i, k] * D[p, j, k]
                        Ek[k0] = s if i == j else 2.0 * s
                    if not want_b:
                        continue
                    gi0, gi1, gi2 = gg[p, i, 0], gg[p, i, 1], gg[p, i, 2]
                    gj0, gj1, gj2 = gg[p, j, 0], gg[p, j, 1], gg[p, j, 2]
                    if i == j:
                        for a in range(na):
                            di = dphi[p, i, a]
                            B[e, z, k0, 3 * a] = gi0 * di
                            B[e, z, k0, 3 * a + 1] = gi1 * di
                            B[e, z, k0, 3 * a + 2] = gi2 * di
                    else:
                        for a in range(na):
                            di, dj = dphi[p, i, a], dphi[p, j, a]
                            B[e, z, k0, 3 * a] = gi0 * dj + gj0 * di
                            B[e, z, k0, 3 * a + 1] = gi1 * dj + gj1 * di
                            B[e, z, k0, 3 * a + 2] = gi2 * dj + gj2 * di
            if mode == 1:
                for k in range(nT):
                    E_out[e, z, k] = Ek[k]
                continue
            # tied stresses σ = Ĉ E = L̂ (L̂ᵀ E)
            if mode == 2:
                for k in range(nT):
                    sig[k] = sig_in[e, z, k]
            elif lower:
                for W in range(nT):
                    yk[W] = 0.0
                for k in range(nT):  # y = L̂ᵀ E row by row (contiguous rows of L̂)
                    v = Ek[k]
                    for W in range(k + 1):
                        yk[W] += Lh[e, z, k, W] * v
                for k in range(nT):
                    s = 0.0
                    for W in range(k + 1):
                        s += Lh[e, z, k, W] * yk[W]
                    sig[k] = s
            else:
                for k in range(nT):
                    s = 0.0
                    for k2 in range(nT):
                        s += Lh[e, z, k, k2] * Ek[k2]
                    sig[k] = s
            # f_a = Σ_k σ_k B_k = Σ_p Σ_K GS_K g_K with GS_K = Σ_J ∂_J phi σ_JK (the geometric
            # operand), per tied direction and without the rows: the same arithmetic with and
            # without the tangent (the residual of a line search equals that of the Newton step)
            for p in range(P):
                for r in range(ndir[p]):
                    K = dirs[p, r]
                    g0, g1, g2 = gg[p, K, 0], gg[p, K, 1], gg[p, K, 2]
                    v = sig[gk[p, r, 0]]
                    J = gJ[p, r, 0]
                    for a in range(na):
                        gsa[a] = v * dphi[p, J, a]
                    for h in range(1, gn[p, r]):
                        v = sig[gk[p, r, h]]
                        J = gJ[p, r, h]
                        for a in range(na):
                            gsa[a] += v * dphi[p, J, a]
                    for a in range(na):
                        ft[0, a] += gsa[a] * g0
                        ft[1, a] += gsa[a] * g1
                        ft[2, a] += gsa[a] * g2
                    if want_geo:
                        for a in range(na):
                            GS[e, col, a] = gsa[a]
                            GT[e, col, a] = dphi[p, K, a]
                        col += 1
        for a in range(na):
            f[e, 3 * a], f[e, 3 * a + 1], f[e, 3 * a + 2] = ft[0, a], ft[1, a], ft[2, a]
