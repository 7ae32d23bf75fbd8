"""Compiled bulk kernel of inelastic layers: the layer kernels with a material law in place of S = C E.

Three steps per element range: the strain at the points (compiled), the law's stress S and tangent
D = dS/dE there (vectorised over all points of the range, one call), then f = Σ Bᵀ S dV and
K = Σ Bᵀ (D dV) B + the geometric term of S (compiled point work and BLAS products per element;
D may be unsymmetric, so general products instead of the elastic kernels' syrk with a Cholesky
factor). Elements are split over the kernels' threads (:func:`.kernel.kernel_threads`) in the
last step. Reinforcement sheets (:func:`.inelastic.sheet_terms`) are added in the same step.

* Full element (:class:`.kernel.LayerBlock`): E from the basis gradients and U at each point,
  then in gradient form K_mat,(a i)(b k) = Σ_q Σ_(K, L) g_aK A_iKkL g_bL with the 9 × 9
  A = Φᵀ (D dV) Ψ of each point (B = g Φ, F in Φ): per (i, k) one product of the gradients
  (a × 3q) with W_ik = A_ik g (3q × a), half the multiplications of Bᵀ (D B) over 6q Voigt rows
  (about those of the elastic kernel's symmetric product); sheets by ``_jit_inelastic.sheet_add``.
* MITC9 (:class:`.mitc.MitcBlock`): the displacement derivatives along the frame directions at
  the sampling points (from the natural derivatives of the nodal vectors, once per element for
  all levels; kept for the rows), the tie-space strains E_k of each level, the Cartesian tied
  strain T Ẽ at the Gauss points (Ẽ_c(q) = Σ_t (h_t(q) + v_t) E_(c,t), the tying functions and
  the consistency correction), then element by element in one compiled pass
  (``_jit_inelastic.mitc_bulk``): in the tie space σ_k = Σ_q (h_k(q) + v_k) (Tᵀ S dV)_c and
  Ĉ = Σ_q h_qᵀ (Tᵀ D T dV) h_q (unsymmetric), the rows B_k and f = Σ_k σ_k B_k, and
  K_mat = Σ_z B_zᵀ (Ĉ_z B_z) as BLAS products on the element's rows while they are in cache;
  a sheet's points are further rows of the same products.

:func:`.kernel.layer_response_reference` / :func:`.mitc.mitc_response_reference` with the same
``stress`` callable are the plain NumPy forms of both (tests/test_inelastic_layer.py).
"""
from __future__ import annotations

from contextlib import nullcontext

import numpy as np

from ..threads import blas_single_thread
from .kernel import LayerBlock, _pool, kernel_threads

_SUB = 8  # elements per sub-block of the full element (as the elastic kernels: 16 measured no faster) and per thread
V_ROUNDOFF = 1e-13  # |v| of the tie correction below this is round-off (v = 0 on flat straight-edged elements)
_NONE3 = np.empty((0, 0, 0))  # the compiled loops' array arguments that a call does not use
_NONE4 = np.empty((0, 0, 0, 0))
_NONE6 = np.empty((0, 0, 0, 0, 0, 0))


def bulk_response(block, U: np.ndarray, nonlinear: bool, tangent: bool, sl: slice, stress, sheets=()):
    """Forces ``(e, m)`` and tangent ``(e, m, m)`` (None without ``tangent``) of the elements ``sl``
    (contiguous) of a layer block with ``stress(E) -> (S, D)``: E ``(e, P, 6)`` the Cartesian
    Green-Lagrange strain at the block's P points (MITC9: tied; ``block.dV`` order), S ``(e, P, 6)``,
    D ``(e, P, 6, 6)`` or None without ``tangent``. ``sheets``: the point terms of reinforcement
    sheets in the layer (``(ga, Fa, sw, cw)`` each, :func:`.inelastic.sheet_terms`), added."""
    lo, hi, step = sl.indices(block.dV.shape[0])
    if step != 1:
        raise ValueError("bulk_response: the element range must be contiguous")
    U = np.ascontiguousarray(U, dtype=np.float64)
    nonlinear, tangent = bool(nonlinear), bool(tangent)
    if not isinstance(block, LayerBlock):  # BLAS single-threaded: the strain pass's product is small too
        with blas_single_thread():
            return _mitc(block, U, nonlinear, tangent, lo, hi, stress, sheets)
    f, K = _full(block, U, nonlinear, tangent, lo, hi, stress)
    if sheets:
        from . import _jit_inelastic as jit

        ga, Fa, sw, cw = _stacked(sheets, hi - lo, block.gradphi.shape[2], tangent)
        jit.sheet_add(ga, Fa, sw, cw, nonlinear, tangent, f, K if tangent else _NONE3)
    return f, K


def _threads(n_el: int, work, tangent: bool) -> None:
    """``work(lo, hi)`` over element ranges, split over the kernel threads (BLAS single-threaded
    for the tangent's products, as :func:`.kernel.layer_response`)."""
    with blas_single_thread() if tangent else nullcontext():
        _split(n_el, work)


def _split(n_el: int, work) -> None:
    """``work(lo, hi)`` over element ranges, split over the kernel threads."""
    n_threads = min(kernel_threads(), max(1, n_el // _SUB))
    if n_threads == 1:
        work(0, n_el)
        return
    bounds = np.linspace(0, n_el, n_threads + 1).astype(int)
    jobs = [_pool(n_threads).submit(work, a, b) for a, b in zip(bounds[:-1], bounds[1:])]
    for j in jobs:
        j.result()


def _law(stress, E, tangent: bool):
    S, D = stress(E)
    S = np.ascontiguousarray(S, dtype=np.float64)
    D = np.ascontiguousarray(D, dtype=np.float64) if tangent else None
    return S, D


def _full(block: LayerBlock, U, nonlinear: bool, tangent: bool, lo: int, hi: int, stress):
    from . import _jit, _jit_inelastic as jit

    g, dV = block.gradphi[lo:hi], block.dV[lo:hi]
    e, q, a = g.shape[:3]
    m = 3 * a
    E = np.empty((e, q, 6))
    jit.full_strains(g, U, nonlinear, E)
    S, D = _law(stress, E, tangent)
    Dq = D if tangent else _NONE4
    f = np.empty((e, a, 3))
    K = np.empty((e, m, m)) if tangent else None
    geo = tangent and nonlinear

    def work(r0: int, r1: int) -> None:
        for s in range(r0, r1, _SUB):
            t = min(s + _SUB, r1)
            nb = t - s
            W = np.empty((nb, 3, 3, q, 3, a)) if tangent else _NONE6
            GS = np.empty((nb, a, q, 3) if geo else (0, 0, 0, 0))
            GT = np.empty_like(GS)
            jit.full_terms(g[s:t], dV[s:t], S[s:t], Dq[s:t] if tangent else Dq, U[s:t], nonlinear, tangent, geo,
                           f[s:t], W, GS, GT)
            if not tangent:
                continue
            G = GT if geo else np.ascontiguousarray(g[s:t].transpose(0, 2, 1, 3))  # (nb, a, q, 3)
            Kik = np.matmul(G.reshape(nb, 1, 1, a, 3 * q), W.reshape(nb, 3, 3, 3 * q, a))  # (nb, i, k, a, b)
            K[s:t].reshape(nb, a, 3, a, 3)[...] = Kik.transpose(0, 3, 1, 4, 2)
            if geo:
                Kg = np.matmul(GS.reshape(nb, a, 3 * q), GT.reshape(nb, a, 3 * q).transpose(0, 2, 1))
                _jit.add_geometric(K[s:t], Kg)

    _threads(e, work, tangent)
    return f.reshape(e, m), K


def _mitc_args(block, lo: int, hi: int):
    tie = block.tie
    return (block.N, block.dN, block.thL[lo:hi], block.G[lo:hi], block.M[lo:hi], tie.pts, tie.off, tie.n, tie.dirs,
            tie.ndir, tie.gn, tie.gk, tie.gJ)


def _tying_nonzeros(tie):
    """The non-zeros of the tying functions at each Gauss point q: their number (9,), component,
    tie-space index and value (9, n) each (padded), and the component of each tie (nT,). The
    tying points of E_11, E_22, E_23, E_13 lie on Gauss lines, so 13 of the 37 ties reach a point."""
    key = id(tie)
    if key in _NONZEROS and _NONZEROS[key][0] is tie:
        return _NONZEROS[key][1]
    nz = [[(c, int(tie.off[c] + t), float(tie.w[c, q, t])) for c in range(6) for t in range(int(tie.n[c]))
           if tie.w[c, q, t] != 0.0] for q in range(9)]
    width = max(len(r) for r in nz)
    qn = np.array([len(r) for r in nz], np.int64)
    qc, qk, qw = np.zeros((9, width), np.int64), np.zeros((9, width), np.int64), np.zeros((9, width))
    for q, r in enumerate(nz):
        for j, (c, k, w) in enumerate(r):
            qc[q, j], qk[q, j], qw[q, j] = c, k, w
    _NONZEROS[key] = (tie, (qn, qc, qk, qw, tie.component()))
    return _NONZEROS[key][1]


_NONZEROS: dict = {}  # id(tying) -> (tying, its non-zeros); the tyings are cached (mitc.tying)


def _mitc(block, U, nonlinear: bool, tangent: bool, lo: int, hi: int, stress, sheets):
    from . import _jit_inelastic as jit

    if block.T is None:
        raise ValueError("bulk_response: the MITC9 block has no strain map T (build it with keep_map=True)")
    tie = block.tie
    e, nz = hi - lo, block.thL.shape[1]
    nT = int(tie.off[-1])
    a = 9 * (block.d + 1)
    m = 3 * a
    v = np.zeros((e, nz, nT))
    if block.v is not None:  # levels whose correction is round-off (straight-edged flat elements): none
        keep = np.abs(block.v[lo:hi]).max(axis=-1) > V_ROUNDOFF
        v[keep] = block.v[lo:hi][keep]
    T = block.T[lo:hi]
    Dg = np.empty((e, nz, len(tie.points), 3, 3))
    Ec = np.empty((e, nz, 9, 6))
    jit.mitc_strain(_natural(block, U), block.thL[lo:hi], block.G[lo:hi], block.M[lo:hi], tie.pts, tie.off, tie.n,
                    nonlinear, tie.w, v, T, Dg, Ec)
    S, D = _law(stress, Ec.reshape(e, nz * 9, 6), tangent)
    S = S.reshape(e, nz, 9, 6)
    D = D.reshape(e, nz, 9, 6, 6) if tangent else np.empty((e, nz, 0, 6, 6))
    dV = block.dV[lo:hi].reshape(e, nz, 9)
    ga, Fa, sw, cw = _stacked(sheets, e, a, tangent)
    f = np.empty((e, m))
    K = np.empty((e, m, m)) if tangent else None
    nzw = _tying_nonzeros(tie)

    def work(r0: int, r1: int) -> None:
        jit.mitc_bulk(*_mitc_args(block, lo + r0, lo + r1), U[r0:r1], block.d, nonlinear, tangent, S[r0:r1],
                      D[r0:r1], dV[r0:r1], T[r0:r1], *nzw, v[r0:r1], ga[r0:r1], Fa[r0:r1], sw[r0:r1], cw[r0:r1],
                      Dg[r0:r1], f[r0:r1], K[r0:r1] if tangent else _NONE3)

    _split(e, work)
    return f, K


def _natural(block, U):
    """The natural derivatives of the nodal vectors at the sampling points, (P, 3, e, d + 1, 3):
    Σ_n (∂_ξ N_n, ∂_η N_n, N_n) U_(n, l) at each point p, as one product (3P × 9) (9 × 3(d + 1)e)."""
    e, nd = U.shape[0], block.d + 1
    P = block.N.shape[0]
    Nm = np.concatenate([block.dN[:, None, :, 0], block.dN[:, None, :, 1], block.N[:, None, :]], axis=1)
    Un = np.ascontiguousarray(U.reshape(e, 9, 3 * nd).transpose(1, 0, 2)).reshape(9, 3 * nd * e)
    return np.dot(Nm.reshape(3 * P, 9), Un).reshape(P, 3, e, nd, 3)


def _stacked(sheets, e: int, a: int, tangent: bool):
    """The sheets' point terms (:func:`.inelastic.sheet_terms`) stacked along the points:
    ga (e, s, a), Fa (e, s, 3), sw, cw (e, s); s = 0 without sheets."""
    if not sheets:
        return np.empty((e, 0, a)), np.empty((e, 0, 3)), np.empty((e, 0)), np.empty((e, 0))
    cat = lambda k: np.ascontiguousarray(np.concatenate([t[k] for t in sheets], axis=1))  # noqa: E731
    cw = cat(3) if tangent else np.empty((e, sum(t[2].shape[1] for t in sheets)))
    return cat(0), cat(1), cat(2), cw
