"""Compiled point loops of the inelastic layer kernel (Numba, ``cache=True``, GIL released).

Imported lazily by :mod:`layershell.element.inelastic_kernel`. The material law is not evaluated
here: these loops give the strain at the points, and from the law's stress S and tangent D there
the internal force f = Σ Bᵀ S dV and the operands of K = Σ Bᵀ (D dV) B + the geometric term
(``kernel.py``, ``mitc.py`` for the equations; D may be unsymmetric). The MITC9 pass
(:func:`mitc_bulk`) and the sheets (:func:`sheet_add`) form K themselves with ``np.dot`` on each
element's rows: SciPy's BLAS, held to one thread with the others by
:func:`layershell.threads.blas_single_thread`.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ._jit import add_geometric, mitc_terms

_VMAP = np.array([[0, 5, 4], [5, 1, 3], [4, 3, 2]], dtype=np.int64)  # Voigt index of (J, K)
#: rows × columns of B per BLAS product Bᵀ G of a MITC9 element (longer ones split and summed): OpenBLAS
#: took 68 µs for 222 rows × 81 columns at once and 57 µs in two halves (53 against 42 GFlop/s)
PRODUCT_ENTRIES = 12000


@njit(cache=True, nogil=True, fastmath=True)
def full_strains(g, U, nonlinear, E):  # pragma: no cover
    """Voigt Green-Lagrange strain (engineering shear) E (e, q, 6) of the full element at its
    points from the basis gradients g (e, q, a, 3) and the nodal vectors U (e, a, 3)."""
    ne, nq, na = g.shape[0], g.shape[1], g.shape[2]
    H = np.empty((3, 3))
    for e in range(ne):
        for q in range(nq):
            for i in range(3):
                for J in range(3):
                    H[i, J] = 0.0
            for a in range(na):
                for i in range(3):
                    u = U[e, a, i]
                    for J in range(3):
                        H[i, J] += u * g[e, q, a, J]
            for V in range(6):
                I = (0, 1, 2, 1, 0, 0)[V]
                J = (0, 1, 2, 2, 2, 1)[V]
                s = H[I, J] + H[J, I]
                if nonlinear:
                    s += H[0, I] * H[0, J] + H[1, I] * H[1, J] + H[2, I] * H[2, J]
                E[e, q, V] = 0.5 * s if V < 3 else s


@njit(cache=True, nogil=True, fastmath=True)
def full_terms(g, dV, S, D, U, nonlinear, want_k, want_geo, f, W, GS, GT):  # pragma: no cover
    """Per point of the full element, with the law's stress S (e, q, 6) and tangent D (e, q, 6, 6):
    internal force f (e, a, 3) = Σ_q Bᵀ S dV; on request the operands W (e, 3, 3, q, 3, a) of the
    material stiffness in gradient form, K_(a i)(b k) = Σ_(q, K) g_aK W[i, k, q, K, b], and the
    geometric operands GS = g S dV, GT = g (e, a, q, 3).

    As in ``_jit.point_terms``: B_V,(a i) = Σ_K g_aK Φ_VKi with Φ_VKi = Σ_J F_iJ [Voigt(J, K) = V]
    and (D dV B)_V,(b k) = Σ_L g_bL Ψ_VLk with Ψ_VLk = Σ_J F_kJ (D dV)_V,Voigt(J, L), so that
    Bᵀ D B dV = Σ_(K, L) g_aK A_iKkL g_bL with the 9 × 9 A_iKkL = Σ_V Φ_VKi Ψ_VLk, and
    W[i, k, q, K, b] = Σ_L A_iKkL g_bL: 9 products of a × 3q by 3q × a per element, half the
    work of Bᵀ (D B) over the 6q Voigt rows."""
    ne, nq, na = g.shape[0], g.shape[1], g.shape[2]
    H = np.empty((3, 3))
    F = np.empty((3, 3))
    Sm = np.empty((3, 3))
    P = np.empty((3, 3))
    Phi = np.empty((6, 3, 3))
    Psi = np.empty((6, 3, 3))
    A = np.empty((3, 3, 3, 3))
    for e in range(ne):
        for a in range(na):
            for i in range(3):
                f[e, a, i] = 0.0
        for q in range(nq):
            for i in range(3):
                for J in range(3):
                    H[i, J] = 0.0
            if nonlinear:
                for a in range(na):
                    for i in range(3):
                        u = U[e, a, i]
                        for J in range(3):
                            H[i, J] += u * g[e, q, a, J]
            for I in range(3):
                for J in range(3):
                    F[I, J] = (1.0 if I == J else 0.0) + H[I, J]
            w = dV[e, q]
            Sm[0, 0], Sm[1, 1], Sm[2, 2] = S[e, q, 0] * w, S[e, q, 1] * w, S[e, q, 2] * w
            Sm[1, 2] = Sm[2, 1] = S[e, q, 3] * w
            Sm[0, 2] = Sm[2, 0] = S[e, q, 4] * w
            Sm[0, 1] = Sm[1, 0] = S[e, q, 5] * w
            for K in range(3):
                for i in range(3):
                    P[K, i] = Sm[K, 0] * F[i, 0] + Sm[K, 1] * F[i, 1] + Sm[K, 2] * F[i, 2]
            for a in range(na):
                g0, g1, g2 = g[e, q, a, 0], g[e, q, a, 1], g[e, q, a, 2]
                for i in range(3):
                    f[e, a, i] += g0 * P[0, i] + g1 * P[1, i] + g2 * P[2, i]
            if want_k:
                for V in range(6):
                    for K in range(3):
                        for i in range(3):
                            Phi[V, K, i] = 0.0
                            s = 0.0
                            for J in range(3):
                                X = _VMAP[J, K]
                                s += F[i, J] * D[e, q, V, X]
                                if X == V:
                                    Phi[V, K, i] += F[i, J]
                            Psi[V, K, i] = s * w
                _gradient_form(Phi, Psi, g[e, q], A, W[e], q)
            if want_geo:
                for a in range(na):
                    g0, g1, g2 = g[e, q, a, 0], g[e, q, a, 1], g[e, q, a, 2]
                    for K in range(3):
                        GS[e, a, q, K] = g0 * Sm[0, K] + g1 * Sm[1, K] + g2 * Sm[2, K]
                        GT[e, a, q, K] = g[e, q, a, K]


@njit(cache=True, nogil=True, fastmath=True)
def _gradient_form(Phi, Psi, gq, A, We, q):  # pragma: no cover
    """One point's share of :func:`full_terms`' W: A_iKkL = Σ_V Φ_VKi Ψ_VLk (into ``A``), then
    W[i, k, q, K, b] = Σ_L A_iKkL g_bL with the point's gradients ``gq`` (a, 3)."""
    for i in range(3):
        for K in range(3):
            for k in range(3):
                for L in range(3):
                    s = 0.0
                    for V in range(6):
                        s += Phi[V, K, i] * Psi[V, L, k]
                    A[i, K, k, L] = s
    for i in range(3):
        for k in range(3):
            for K in range(3):
                a0, a1, a2 = A[i, K, k, 0], A[i, K, k, 1], A[i, K, k, 2]
                for b in range(gq.shape[0]):
                    We[i, k, q, K, b] = a0 * gq[b, 0] + a1 * gq[b, 1] + a2 * gq[b, 2]


@njit(cache=True, nogil=True, fastmath=True)
def mitc_strain(nat, thL, G, M, pts, off, nt, nonlinear, w, v, T, Dg, E):  # pragma: no cover
    """The strain pass of the MITC9 layer from the natural derivatives of the nodal vectors at the
    sampling points, ``nat`` (P, 3, e, d + 1, 3) = Σ_n (∂_ξ N_n, ∂_η N_n, N_n) U_(n, l) (one
    product over the elements, :func:`.inelastic_kernel._natural`): per level and point the
    derivatives along the frame directions ∂u/∂F_b = Σ_l pw_l (M_0b nat_0l + M_1b nat_1l)
    + dpw_l M_2b nat_2l (pw_l = (Θ³)^l, dpw_l its derivative) into ``Dg`` (e, z, P, 3, 3) [b, k]
    (the rows pass takes them from there), the tie-space strains E_k from them (as
    ``_jit.mitc_terms``) and the Cartesian tied strain E (e, z, 9, 6) = T Ẽ at the Gauss points,
    Ẽ_c(q) = Σ_t (w[c, q, t] + v[e, z, k]) E_k, k = off[c] + t (v the consistency correction,
    zeros without it)."""
    ne, nz, P = thL.shape[0], thL.shape[1], thL.shape[2]
    nd, nT = nat.shape[3], off[6]
    A = np.empty((3, 3))
    Ek, Et, pw, dpw = np.empty(nT), np.empty(6), np.empty(nd), np.empty(nd)
    pi, pj = (0, 1, 2, 1, 0, 0), (0, 1, 2, 2, 2, 1)
    for e in range(ne):
        for z in range(nz):
            for p in range(P):
                th = thL[e, z, p]
                pw[0], dpw[0] = 1.0, 0.0
                for l in range(1, nd):
                    pw[l] = pw[l - 1] * th
                    dpw[l] = l * pw[l - 1]
                for k in range(3):
                    A[0, k] = A[1, k] = A[2, k] = 0.0
                    for l in range(nd):
                        A[0, k] += pw[l] * nat[p, 0, e, l, k]
                        A[1, k] += pw[l] * nat[p, 1, e, l, k]
                        A[2, k] += dpw[l] * nat[p, 2, e, l, k]
                for b in range(3):
                    m0, m1, m2 = M[e, z, p, 0, b], M[e, z, p, 1, b], M[e, z, p, 2, b]
                    for k in range(3):
                        Dg[e, z, p, b, k] = m0 * A[0, k] + m1 * A[1, k] + m2 * A[2, k]
            Dz = Dg[e, z]
            for c in range(6):
                i, j = pi[c], pj[c]
                for t in range(nt[c]):
                    p = pts[c, t]
                    s = 0.0
                    for k in range(3):
                        s += 0.5 * (G[e, z, p, k, i] * Dz[p, j, k] + Dz[p, i, k] * G[e, z, p, k, j])
                        if nonlinear:
                            s += 0.5 * Dz[p, i, k] * Dz[p, j, k]
                    Ek[off[c] + t] = s if i == j else 2.0 * s
            for q in range(9):
                for c in range(6):
                    s = 0.0
                    for t in range(nt[c]):
                        k = off[c] + t
                        s += (w[c, q, t] + v[e, z, k]) * Ek[k]
                    Et[c] = s
                for V in range(6):
                    s = 0.0
                    for c in range(6):
                        s += T[e, z, q, V, c] * Et[c]
                    E[e, z, q, V] = s


@njit(cache=True, nogil=True, fastmath=True)
def _correct(v, comp, tangent, sl, Cl, S0, R, L, C0):  # pragma: no cover
    """Add the consistency correction ``v (nT,)`` of one level to its tie stresses ``sl`` and, with
    ``tangent``, to its tied stiffness ``Cl`` (:func:`_tie_level`, which gives them for h_q = W_q);
    nothing where v = 0. With h_q = W_q + V, V[c, k] = v[k] for c = comp[k] (the same at every q):
    Ĉ = Ĉ₀ + Vᵀ R + L V + Vᵀ C0 V with Ĉ₀ = Σ_q W_qᵀ C̃_q W_q, R = Σ_q C̃_q W_q = Uᵀ Ĉ₀,
    L = Σ_q W_qᵀ C̃_q = Ĉ₀ U and C0 = Σ_q C̃_q = Uᵀ Ĉ₀ U (U the component indicator: the tying
    functions of a component sum to 1 at every point), and likewise σ = σ₀ + Vᵀ Uᵀ σ₀."""
    nT = sl.shape[0]
    anyv = False
    for k in range(nT):
        if v[k] != 0.0:
            anyv = True
    if not anyv:
        return
    S0[:] = 0.0
    for k in range(nT):  # the sums over the ties of a component: W_q reproduces constants
        S0[comp[k]] += sl[k]
    for k in range(nT):
        sl[k] += v[k] * S0[comp[k]]
    if not tangent:
        return
    R[:] = 0.0
    L[:] = 0.0
    C0[:] = 0.0
    for k in range(nT):  # R = Uᵀ Ĉ₀, L = Ĉ₀ U, C0 = Uᵀ Ĉ₀ U (U the component indicator)
        ck = comp[k]
        for l in range(nT):
            x = Cl[k, l]
            R[ck, l] += x
            L[k, comp[l]] += x
            C0[ck, comp[l]] += x
    for k in range(nT):
        vk, ck = v[k], comp[k]
        for l in range(nT):
            vl, cl = v[l], comp[l]
            Cl[k, l] += vk * R[ck, l] + L[k, cl] * vl + vk * C0[ck, cl] * vl


@njit(cache=True, nogil=True, fastmath=True)
def _tie_level(S, D, dV, T, qn, qc, qk, qw, comp, v, tangent, sl, Cl, w):  # pragma: no cover
    """One level's tie stresses ``sl (nT,)`` = Σ_q h_qᵀ S̃_q and, with ``tangent``, its unsymmetric
    tied stiffness ``Cl (nT, nT)`` = Σ_q h_qᵀ C̃_q h_q from the law's Cartesian S (9, 6) and
    D (9, 6, 6) at the level's Gauss points: S̃ = Tᵀ S dV, C̃ = Tᵀ D T dV. h_q = W_q + V: the tying
    functions W_q at Gauss point q by their non-zeros (qn[q] entries: component qc, tie qk, value
    qw; 13 of the 37 ties reach a point, so W_qᵀ C̃_q W_q is 13 × 13 scattered entries) and the
    consistency correction V[c, k] = v[k] for c = comp[k] (:func:`_correct`). ``w``: scratch
    (:func:`_level_scratch`)."""
    St, DT, Cq, R, R6, L6, C6 = w
    sl[:] = 0.0
    if tangent:
        Cl[:] = 0.0
    for q in range(9):
        wq, Tq = dV[q], T[q]
        for c in range(6):
            s = 0.0
            for V in range(6):
                s += Tq[V, c] * S[q, V]
            St[c] = s * wq
        n = qn[q]
        for j in range(n):
            sl[qk[q, j]] += qw[q, j] * St[qc[q, j]]
        if not tangent:
            continue
        for V in range(6):  # D T dV, then Tᵀ (D T dV): the inner loops along rows (vectorised)
            d0, d1, d2 = D[q, V, 0] * wq, D[q, V, 1] * wq, D[q, V, 2] * wq
            d3, d4, d5 = D[q, V, 3] * wq, D[q, V, 4] * wq, D[q, V, 5] * wq
            for c in range(6):
                DT[V, c] = (d0 * Tq[0, c] + d1 * Tq[1, c] + d2 * Tq[2, c] + d3 * Tq[3, c] + d4 * Tq[4, c]
                            + d5 * Tq[5, c])
        for c in range(6):
            t0, t1, t2, t3, t4, t5 = Tq[0, c], Tq[1, c], Tq[2, c], Tq[3, c], Tq[4, c], Tq[5, c]
            for c2 in range(6):
                Cq[c, c2] = (t0 * DT[0, c2] + t1 * DT[1, c2] + t2 * DT[2, c2] + t3 * DT[3, c2] + t4 * DT[4, c2]
                             + t5 * DT[5, c2])
        for c in range(6):  # the columns of C̃_q at the point's ties, weighted
            for j in range(n):
                R[c, j] = Cq[c, qc[q, j]] * qw[q, j]
        for j1 in range(n):
            k, c, w1 = qk[q, j1], qc[q, j1], qw[q, j1]
            for j2 in range(n):
                Cl[k, qk[q, j2]] += w1 * R[c, j2]
    _correct(v, comp, tangent, sl, Cl, St, R6, L6, C6)


@njit(cache=True, nogil=True)
def _level_scratch(nT, width):  # pragma: no cover
    """The scratch arrays of :func:`_tie_level`."""
    return (np.empty(6), np.empty((6, 6)), np.empty((6, 6)), np.empty((6, width)), np.empty((6, nT)),
            np.empty((nT, 6)), np.empty((6, 6)))


@njit(cache=True, nogil=True, fastmath=True)
def _sheet_rows(ga, Fa, sw, cw, tangent, geo, f, Bs, Gs, GSs, GTs):  # pragma: no cover
    """One element's sheet points (ga (s, n), Fa (s, 3), sw, cw (s,): :func:`sheet_add`): the rows
    b_s = (g·a)(F a) into ``Bs`` (s, m), c_s b_s into ``Gs`` and f += Σ_s s_s b_s; with ``geo`` the
    geometric operands s_s (g·a) and g·a into ``GSs``, ``GTs`` (s, n)."""
    for p in range(ga.shape[0]):
        s, c = sw[p], cw[p]
        for b in range(ga.shape[1]):
            for i in range(3):
                x = ga[p, b] * Fa[p, i]
                f[3 * b + i] += s * x
                if tangent:
                    Bs[p, 3 * b + i] = x
                    Gs[p, 3 * b + i] = c * x
            if geo:
                GSs[p, b] = s * ga[p, b]
                GTs[p, b] = ga[p, b]


@njit(cache=True, nogil=True, fastmath=True)
def mitc_bulk(Nn, dNn, thL, G, M, pts, off, nt, dirs, ndir, gn, gk, gJ, U, d, nonlinear, tangent, S, D, dV, T,
              qn, qc, qk, qw, comp, v, ga, Fa, sw, cw, Dg, f, K):  # pragma: no cover
    """MITC9 forces f (e, m) and, with ``tangent``, K (e, m, m) from the law's S (e, z, 9, 6) and
    D (e, z, 9, 6, 6) at the Gauss points, element by element (the rows of one element stay in
    cache): the tie stresses and tied stiffness Ĉ_z of each level (:func:`_tie_level`), the rows
    B_z and f (``_jit.mitc_terms``, tie stresses and the strain pass's ∂u/∂F_b ``Dg`` given), then
    K = Bᵀ G with G_z = Ĉ_z B_z (BLAS) stacked over the levels (in pieces of
    :data:`PRODUCT_ENTRIES`), plus the geometric term.
    Sheets (ga (e, s, n), Fa (e, s, 3), sw, cw (e, s): :func:`sheet_add`; s = 0 without) enter as
    s more rows b_s of B, c_s b_s of G and columns of the geometric operands: the same products."""
    ne, nz = thL.shape[0], thL.shape[1]
    nT, na, ns = off[6], 9 * (d + 1), ga.shape[1]
    m, rows = 3 * na, nz * off[6]
    geo = tangent and nonlinear
    ncol = nz * ndir.sum() if geo else 0
    sig, Ch = np.empty((1, nz, nT)), np.empty((nz, nT, nT))
    w = _level_scratch(nT, qn.max())
    Bx = np.empty((rows + ns, m) if tangent else (0, m))
    Gx = np.empty_like(Bx)
    GS, GT = np.empty((ncol + ns, na)), np.empty((ncol + ns, na))
    Kg, Kt = np.empty((1, na, na)), np.empty((m, m))
    pieces = ((rows + ns) * m + PRODUCT_ENTRIES - 1) // PRODUCT_ENTRIES
    step = max((rows + ns + pieces - 1) // pieces, 1)
    E0, L0 = np.empty((0, 0, 0)), np.empty((0, 0, 0, 0))
    B = Bx[:rows].reshape(1, nz, nT, m) if tangent else np.empty((1, 1, 1, 1))
    for e in range(ne):
        for z in range(nz):
            _tie_level(S[e, z], D[e, z], dV[e, z], T[e, z], qn, qc, qk, qw, comp, v[e, z], tangent, sig[0, z],
                       Ch[z], w)
        mitc_terms(Nn, dNn, thL[e:e + 1], G[e:e + 1], M[e:e + 1], pts, off, nt, dirs, ndir, gn, gk, gJ, L0,
                   U[e:e + 1], d, nonlinear, tangent, geo, False, f[e:e + 1], B, GS[:ncol].reshape(1, ncol, na),
                   GT[:ncol].reshape(1, ncol, na), 2, sig, E0, Dg[e:e + 1])
        _sheet_rows(ga[e], Fa[e], sw[e], cw[e], tangent, geo, f[e], Bx[rows:], Gx[rows:], GS[ncol:], GT[ncol:])
        if not tangent:
            continue
        for z in range(nz):
            np.dot(Ch[z], Bx[z * nT:(z + 1) * nT], Gx[z * nT:(z + 1) * nT])
        np.dot(Bx[:step].T, Gx[:step], K[e])
        for r in range(step, rows + ns, step):
            np.dot(Bx[r:r + step].T, Gx[r:r + step], Kt)
            K[e] += Kt
        if geo:
            np.dot(GS.T, GT, Kg[0])
            add_geometric(K[e:e + 1], Kg)


@njit(cache=True, nogil=True, fastmath=True)
def sheet_strain(g, a, U, nonlinear, ga, Fa, eps):  # pragma: no cover
    """A reinforcement sheet's strain along its direction a (e, q, 3) at its points,
    ε = (∇u a)·a (+ ½ |∇u a|² with ``nonlinear``), from the basis gradients g (e, q, n, 3) and the
    nodal vectors U (e, n, 3); also g_b·a (``ga`` (e, q, n)) and F a (``Fa`` (e, q, 3); a itself
    when linear)."""
    ne, nq, na = g.shape[0], g.shape[1], g.shape[2]
    for e in range(ne):
        for q in range(nq):
            a0, a1, a2 = a[e, q, 0], a[e, q, 1], a[e, q, 2]
            h0 = h1 = h2 = 0.0
            for b in range(na):
                x = g[e, q, b, 0] * a0 + g[e, q, b, 1] * a1 + g[e, q, b, 2] * a2
                ga[e, q, b] = x
                h0 += x * U[e, b, 0]
                h1 += x * U[e, b, 1]
                h2 += x * U[e, b, 2]
            s = h0 * a0 + h1 * a1 + h2 * a2
            if nonlinear:
                s += 0.5 * (h0 * h0 + h1 * h1 + h2 * h2)
                Fa[e, q, 0], Fa[e, q, 1], Fa[e, q, 2] = a0 + h0, a1 + h1, a2 + h2
            else:
                Fa[e, q, 0], Fa[e, q, 1], Fa[e, q, 2] = a0, a1, a2
            eps[e, q] = s


@njit(cache=True, nogil=True, fastmath=True)
def sheet_add(ga, Fa, sw, cw, nonlinear, tangent, f, K):  # pragma: no cover
    """Add a sheet's forces f_(b i) += Σ_q s_q (g_b·a)(F a)_i and, with ``tangent``, its stiffness
    K_(b i)(c k) += Σ_q [c_q (g_b·a)(F a)_i (g_c·a)(F a)_k + δ_ik s_q (g_b·a)(g_c·a)] (the
    second term with ``nonlinear``) to ``f`` (e, 3n) and ``K`` (e, 3n, 3n); s = σ A_s dA
    (``sw``), c = E_t A_s dA (``cw``), both (e, q) (several sheets: their points stacked). Per
    element the rows b_q and c_q b_q (:func:`_sheet_rows`), then both terms as BLAS products."""
    ne, nq, na = ga.shape[0], ga.shape[1], ga.shape[2]
    m = 3 * na
    geo = tangent and nonlinear
    Bs, Gs, Ks = np.empty((nq, m)), np.empty((nq, m)), np.empty((m, m))
    GS, GT, Kg = np.empty((nq, na)), np.empty((nq, na)), np.empty((1, na, na))
    for e in range(ne):
        _sheet_rows(ga[e], Fa[e], sw[e], cw[e] if tangent else sw[e], tangent, geo, f[e], Bs, Gs, GS, GT)
        if not tangent:
            continue
        np.dot(Bs.T, Gs, Ks)
        K[e] += Ks
        if geo:
            np.dot(GS.T, GT, Kg[0])
            add_geometric(K[e:e + 1], Kg)
