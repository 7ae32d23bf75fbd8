"""Assumed-strain (MITC9) layer kernel: tied covariant Green-Lagrange strains at every Θ³ level.

Within one layer the multi-director shell is a 3D continuum with the tensor-product basis
``phi_(n,l) = N_n(Θ¹,Θ²) (Θ_L³)^l`` (thesis (3.13)); the mixed interpolation of tensorial
components of Bucalem & Bathe (1993, "Higher-order MITC general shell elements", IJNME 36) acts on
its covariant Green-Lagrange components E_ij = ½(g_i·g_j − G_i·G_j), g_i = G_i + ∂_i u, at each
thickness integration point (same natural Θ³ level ζ, same in-plane tying points in every
level):

* E_11, E_13 tied at r = ±a, s ∈ {−b, 0, b}; interpolated linearly in r, quadratically in s
* E_22, E_23 tied at r ∈ {−b, 0, b}, s = ±a (the same with r, s swapped)
* E_12 tied at r, s = ±a, bilinear
* E_33 taken at the Gauss point itself (the multi-director thickness strain is not tied)

with a = 1/√3, b = √(3/5). The tied covariant strain Ẽ at the 3 × 3 Gauss points is mapped to
the Cartesian strain of the material law by the contravariant base vectors there,
E_IJ = (G^i)_I Ẽ_ij (G^j)_J; equivalently the kernel works with the covariant stiffness
C̃ = Tᵀ C T dV (T the Voigt form of that map), so that with S̃ = C̃ Ẽ

* f_ak = Σ_q Σ_c S̃_c ∂Ẽ_c/∂U_ak,    ∂E_ij/∂U_ak = ½(g_ik ∂_j phi_a + g_jk ∂_i phi_a)
* K = Σ_q B̃ᵀ C̃ B̃ + δ_kl Σ_p ∂_i phi_a σ_ij(p) ∂_j phi_b,  σ_c(p) = Σ_q h_c(q, p) S̃_c(q)

(the geometric part from the exact second derivatives of the tied strains; h_c the tying
functions). The compiled kernel (:func:`mitc_response`) evaluates this in the tie space: with the
37 tie strains E and rows B of a level, Σ_q B̃ᵀ C̃ B̃ = Bᵀ Ĉ B and f = Bᵀ Ĉ E, Ĉ = Σ_q H_qᵀ C̃_q H_q
(:func:`tied_stiffness`, factored once per block). The total-Lagrangian form of the full
element (``kernel.py``) is the special case "every component sampled at the Gauss point";
:func:`tying` with ``full=True`` gives it (test).

The components are taken in a frame F_b (:func:`strain_frames`): by default the centre frame
transported to each point (constant on a flat element, so that a constant strain is tied
exactly on a distorted element), or the natural convected basis G_i of the original MITC9
(``frame="natural"``); the formulas above hold with G_i → F_b and ∂_i → the derivative along
F_b. At least d + 1 thickness points are used. :func:`tied_strain` gives the same tied strain at
any point (probes, profiles, delamination criterion via ``results.evaluate_points``).

Consistency correction (:func:`tie_correction`, on by default). A constant tied strain is not
enough for the membrane patch test: equilibrium with the consistent nodal forces of a constant
stress needs Σ_q dV_q B̃_q = ∫ B dV. The tied rows give tie t of component c the weight
W_t = Σ_q dV_q h_t(q), while ∫ B dV is integrated exactly by the product Gauss rule of the tying
points themselves (2 × 3, 3 × 2, 2 × 2) with the weights w̄_t = w_t ρ(p_t), ρ = detG H/2: on a
flat element ρ times an in-plane row is a polynomial of degree 3 in each natural coordinate. The
two agree where ρ is bilinear (straight edges), not with curved edges (0.3 % error of the
membrane patch test of tests/test_patch.py without the correction). Each tie strain of component
c is therefore replaced by E'_t = E_t + v_cᵀ E_c, v_t = (w̄_t − W_t)/V with w̄ scaled to
Σ_t w̄_t = V (so Σ_t v_t = 0, V = Σ_q dV_q): since the tying functions reproduce constants, this
is the same shift at every Gauss point, Ẽ' = Ẽ + (Σ_t w̄_t E_t − Σ_q dV_q Ẽ_q)/V, the mean of
the tied field moved to the tying-point quadrature of the strain (a mean correction like the
B-bar method's, Hughes 1980, towards a rule the MITC sampling points already carry). Then
Σ_q dV_q B̃'_q = Σ_t w̄_t B_t = ∫ B dV for the in-plane rows and the membrane patch test is exact
on curved-edged elements. Not covered, before or after: a constant transverse shear σ_α3 on
curved edges (the rows of E_α3 hold N_n itself, and ρ N_n has degree 5 in the two-point
direction; about 1 % of the nodal forces on a curved-edged element), and the bending patch
with curved edges, whose quadratic displacement the isoparametric space does not contain (the
full element misses it too). In the tie space the correction is the invertible map P = I + U Vᵀ
(U the component indicator, det P = 1): the kernel is unchanged, Ĉ → Pᵀ Ĉ P once per block
(:func:`tied_stiffness`). It keeps the element free of locking: Ẽ' = H P E vanishes exactly
where Ẽ = H E does (P invertible), so the displacements free of tied shear and membrane strain
— the thin-limit constraint set — are the plain MITC9's, and the zero-energy modes are the
same; v = 0 on straight-edged flat elements and to round-off on the regular cylinder meshes of
examples/shell_benchmarks.py (Scordelis-Lo and the pinched cylinder unchanged to 1e-10, distorted
thin plates and roofs to 1e-3 of the deflection). For comparison: the corrected shape functions
of Celia & Gray (1984) in MITC9i (Wisniewski & Turska 2018, Comput. Mech. 62) make the 9-node
shell pass the patch tests for mid-side nodes moved along straight sides and any centre node,
not for curved sides.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..material import Orthotropic
from .geometry import shell_basis, surface_points
from .quadrature import gauss_1d, gauss_2d

A_TIE = 1.0 / np.sqrt(3.0)
B_TIE = np.sqrt(0.6)
_PAIRS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))  # Voigt order 11, 22, 33, 23, 13, 12


def _lagrange(nodes: np.ndarray, x: np.ndarray) -> np.ndarray:
    """1D Lagrange polynomials through ``nodes`` at ``x``: ``(len(x), len(nodes))``."""
    L = np.ones((len(x), len(nodes)))
    for j, xj in enumerate(nodes):
        for k, xk in enumerate(nodes):
            if k != j:
                L[:, j] *= (x - xk) / (xj - xk)
    return L


@dataclass(frozen=True)
class Tying:
    """Sampling points and tying functions (constant for all elements).

    points (P, 2): in-plane sampling points (the tying points, then the 3 × 3 Gauss points)
    pts (6, T) int: point index of tie t of Voigt component c (padded), n (6,): ties per component
    w (6, 9, T): weight of tie t of component c at Gauss point q (Ẽ_c(q) = Σ_t w E_c(pts[c, t]))
    dirs (P, 3) int, ndir (P,): the directions K with non-zero rows of the tied stress at point p
    off (7,) int: tie t of component c is entry k = off[c] + t of the tie space (nT = off[6] ties),
    ordered E_11, E_22, E_33, E_12 (the first ``n_normal`` entries), then E_23, E_13 (the transverse
    shear, decoupled from the others where the material's third axis is the normal)
    gn (P, 3), gk, gJ (P, 3, 3) int: for the r-th direction K = dirs[p, r], the gn ties k and the
    directions J with σ_JK(p) = σ_k (the geometric term's stress rows)
    rule (6, T): weight of tie t of component c in the product Gauss rule its tying points form
    (2 × 3, 3 × 2, 2 × 2; the 3 × 3 rule where a component is taken at the Gauss points), used by
    :func:`tie_correction`
    """

    points: np.ndarray
    pts: np.ndarray
    n: np.ndarray
    w: np.ndarray
    dirs: np.ndarray
    ndir: np.ndarray
    off: np.ndarray
    gn: np.ndarray
    gk: np.ndarray
    gJ: np.ndarray
    rule: np.ndarray

    @property
    def n_normal(self) -> int:
        return int(self.n[[0, 1, 2, 5]].sum())

    def tie_space(self) -> np.ndarray:
        """H (9, 6, nT): Ẽ_c(q) = Σ_k H[q, c, k] E_k, E_k the tie-space strains."""
        H = np.zeros((9, 6, int(self.off[-1])))
        for c in range(6):
            H[:, c, self.off[c]:self.off[c] + self.n[c]] = self.w[c, :, :self.n[c]]
        return H

    def component(self) -> np.ndarray:
        """(nT,) int: the Voigt component c of each tie-space entry."""
        c = np.empty(int(self.off[-1]), np.int64)
        for k in range(6):
            c[self.off[k]:self.off[k] + self.n[k]] = k
        return c

    def dense(self) -> np.ndarray:
        """H (6, 9, P): Ẽ_c(q) = Σ_p H[c, q, p] E_c(p)."""
        H = np.zeros((6, 9, len(self.points)))
        for c in range(6):
            for t in range(self.n[c]):
                H[c, :, self.pts[c, t]] += self.w[c, :, t]
        return H


@lru_cache(maxsize=None)
def tying(full: bool = False) -> Tying:
    """MITC9 tying of Bucalem & Bathe (1993); ``full=True``: all components at the Gauss points
    (reproduces the fully integrated element, used as a check)."""
    gp, w2 = gauss_2d(3)
    a, b = A_TIE, B_TIE
    la, lb = np.array([-a, a]), np.array([-b, 0.0, b])
    wa, wb = gauss_1d(2)[1], gauss_1d(3)[1]
    if full:
        sets = {c: (gp, np.eye(9)) for c in range(6)}
        points = gp
        index = {c: np.arange(9) for c in range(6)}
        rules = {c: w2 for c in range(6)}
    else:
        PA = np.array([(r, s) for r in la for s in lb])  # E_11, E_13
        PB = np.array([(r, s) for r in lb for s in la])  # E_22, E_23
        PC = np.array([(r, s) for r in la for s in la])  # E_12
        hA = np.einsum("qi,qj->qij", _lagrange(la, gp[:, 0]), _lagrange(lb, gp[:, 1])).reshape(9, 6)
        hB = np.einsum("qi,qj->qij", _lagrange(lb, gp[:, 0]), _lagrange(la, gp[:, 1])).reshape(9, 6)
        hC = np.einsum("qi,qj->qij", _lagrange(la, gp[:, 0]), _lagrange(la, gp[:, 1])).reshape(9, 4)
        points = np.concatenate([PA, PB, PC, gp])
        iA, iB, iC, iG = np.arange(6), 6 + np.arange(6), 12 + np.arange(4), 16 + np.arange(9)
        index = {0: iA, 4: iA, 1: iB, 3: iB, 5: iC, 2: iG}
        sets = {0: (PA, hA), 4: (PA, hA), 1: (PB, hB), 3: (PB, hB), 5: (PC, hC), 2: (gp, np.eye(9))}
        rA, rB, rC = np.outer(wa, wb).ravel(), np.outer(wb, wa).ravel(), np.outer(wa, wa).ravel()
        rules = {0: rA, 4: rA, 1: rB, 3: rB, 5: rC, 2: w2}
    T = max(len(index[c]) for c in range(6))
    pts = np.zeros((6, T), np.int64)
    n = np.zeros(6, np.int64)
    w = np.zeros((6, 9, T))
    rule = np.zeros((6, T))
    P = len(points)
    used = np.zeros((P, 3), bool)
    for c in range(6):
        k = len(index[c])
        pts[c, :k] = index[c]
        n[c] = k
        w[c, :, :k] = sets[c][1]
        rule[c, :k] = rules[c]
        i, j = _PAIRS[c]
        used[index[c], i] = used[index[c], j] = True
    ndir = used.sum(axis=1).astype(np.int64)
    dirs = np.zeros((P, 3), np.int64)
    for p in range(P):
        dd = np.flatnonzero(used[p])
        dirs[p, :len(dd)] = dd
    off = np.zeros(7, np.int64)
    order = (0, 1, 2, 5, 3, 4)  # normal and in-plane shear components first, transverse shear last
    for c0, c1 in zip(order[:-1], order[1:]):
        off[c1] = off[c0] + n[c0]
    off[6] = n.sum()
    gn = np.zeros((P, 3), np.int64)
    gk = np.zeros((P, 3, 3), np.int64)
    gJ = np.zeros((P, 3, 3), np.int64)
    for p in range(P):
        for r in range(ndir[p]):
            K = dirs[p, r]
            for c in range(6):
                i, j = _PAIRS[c]
                if K not in (i, j):
                    continue
                for t in np.flatnonzero(pts[c, :n[c]] == p):
                    gk[p, r, gn[p, r]] = off[c] + t
                    gJ[p, r, gn[p, r]] = j if i == K else i
                    gn[p, r] += 1
    for x in (points, pts, n, w, dirs, ndir, off, gn, gk, gJ, rule):
        x.setflags(write=False)
    return Tying(points, pts, n, w, dirs, ndir, off, gn, gk, gJ, rule)


def covariant_map(Ginv: np.ndarray) -> np.ndarray:
    """T (..., 6, 6): Cartesian Voigt strain (engineering shear) = T · covariant Voigt strain,
    E_IJ = (G^i)_I E_ij (G^j)_J with ``Ginv`` rows G^i."""
    T = np.empty(Ginv.shape[:-2] + (6, 6))
    for c, (i, j) in enumerate(_PAIRS):
        # unit covariant engineering component c -> tensor E_ij = E_ji = ½ (shear) or 1
        Gi, Gj = Ginv[..., i, :], Ginv[..., j, :]
        if i == j:
            E = np.einsum("...I,...J->...IJ", Gi, Gj)
        else:
            E = 0.5 * (np.einsum("...I,...J->...IJ", Gi, Gj) + np.einsum("...I,...J->...IJ", Gj, Gi))
        for V, (I, J) in enumerate(_PAIRS):
            T[..., V, c] = E[..., I, J] * (1.0 if I == J else 2.0)
    return T


@dataclass(frozen=True)
class MitcBlock:
    """Reference data of one layer over a group of elements for the MITC9 kernel.

    N (P, 9), dN (P, 9, 2): shape functions at the sampling points; thL (e, z, P): Θ_L³ there
    G (e, z, P, 3, 3): the strain frame vectors F_b (columns) there; M (e, z, P, 3, 3) = G⁻¹F
    Ct (e, z, 9, 6, 6): covariant stiffness Tᵀ C T dV at the Gauss points; L (e, z, nT, nT): the
    lower Cholesky factor of the level's tied stiffness Ĉ (:func:`tied_stiffness`), or None where
    Ĉ is not positive definite; C (e, z·9, 6, 6), dV (e, z·9): Cartesian stiffness and volume
    weights (z-major); split: ``tie.n_normal`` where Ĉ does not couple the transverse shear ties
    with the others (L block diagonal: two smaller factor products), else 0; v (e, z, nT): the
    consistency correction of the ties (:func:`tie_correction`, in Ĉ and L), or None without it
    """

    d: int
    tie: Tying
    N: np.ndarray
    dN: np.ndarray
    thL: np.ndarray
    G: np.ndarray
    M: np.ndarray
    Ct: np.ndarray
    L: np.ndarray | None
    C: np.ndarray
    dV: np.ndarray
    split: int = 0
    v: np.ndarray | None = None
    T: np.ndarray | None = None  # (e, z, 9, 6, 6) Cartesian = T · covariant strain (inelastic layers only)

    @property
    def n_dof(self) -> int:
        return 27 * (self.d + 1)


def _rotation(n0: np.ndarray, n1: np.ndarray) -> np.ndarray:
    """Smallest rotation taking unit vectors ``n0`` to ``n1`` (..., 3, 3) (Rodrigues)."""
    v = np.cross(n0, n1)
    c = np.sum(n0 * n1, axis=-1)
    Z = np.zeros_like(c)
    W = np.stack([np.stack([Z, -v[..., 2], v[..., 1]], -1), np.stack([v[..., 2], Z, -v[..., 0]], -1),
                  np.stack([-v[..., 1], v[..., 0], Z], -1)], -2)
    return np.eye(3) + W + (W @ W) / (1.0 + c)[..., None, None]


def strain_frames(X, H_below, H, points, zeta, frame: str = "center"):
    """Covariant bases in which strains are tied, at in-plane ``points (P, 2)`` and thickness
    levels ``zeta``: ``(F, M, G, Ginv, detG, sp, thL)`` with F (e, P, z, 3, 3) the frame vectors
    F_b as columns and M = G⁻¹F (so that the derivative along F_b is Σ_i M_ib ∂_i).

    ``frame = "natural"``: F = G, the convected base vectors (Bucalem & Bathe 1993).
    ``frame = "center"``: F_α = R(p) G_α(centre), F_3 = A_3(p), with R(p) the smallest rotation
    taking the normal at the element centre to the normal at p (same natural level ζ). On a flat
    element the frame is constant, so a constant strain is tied exactly on any distorted mesh
    (patch test); on a regular curved element (cylinder) it equals the natural frame. The
    constant-Jacobian idea of the MITC9i element (Wisniewski & Turska 2018, Comput. Mech. 62).
    """
    sp = surface_points(X, points[:, 0], points[:, 1])
    Hp, Hbp = sp.interpolate(H), sp.interpolate(H_below)  # (e, P)
    thL = 0.5 * Hp[..., None] * (zeta + 1.0)  # (e, P, z)
    G, Ginv, detG = shell_basis(sp, Hbp[..., None] + thL)  # (e, P, z, 3, 3)
    if frame == "natural":
        F = G
    elif frame == "center":
        sc = surface_points(X, np.zeros(1), np.zeros(1))
        tc = 0.5 * sc.interpolate(H)[..., None] * (zeta + 1.0)
        Gc, _, _ = shell_basis(sc, sc.interpolate(H_below)[..., None] + tc)  # (e, 1, z, 3, 3)
        R = _rotation(sc.A3, sp.A3)  # (e, P, 3, 3)
        Fa = np.einsum("epij,ezja->epzia", R, Gc[:, 0, :, :, :2])
        F = np.concatenate([Fa, np.broadcast_to(sp.A3[:, :, None, :, None], Fa.shape[:-1] + (1,))], axis=-1)
    else:
        raise ValueError(f"unknown strain frame {frame!r}")
    M = np.einsum("epziJ,epzJb->epzib", Ginv, F)
    return F, M, G, Ginv, detG, sp, thL


def mitc_block(X, H_below, H, d: int, material: Orthotropic, angle_deg: float = 0.0, direction=None,
               n_thickness: int = 3, full: bool = False, frame: str = "center", consistent: bool = True,
               plies=None, keep_map: bool = False) -> MitcBlock:
    """Precompute one layer for elements ``X (e, 9, 3)`` (arguments as :func:`kernel.layer_block`;
    ``frame`` see :func:`strain_frames`; ``consistent=False`` leaves out the consistency
    correction of the tying, module docstring, for comparison). With ``plies`` the thickness
    levels are those of :func:`.quadrature.ply_rule`, each tied as any level, C from its ply."""
    from .kernel import ply_stiffness, thickness_rule

    tie = tying(full)
    plies, (zeta, wz, ply) = thickness_rule(plies, material, angle_deg, n_thickness)
    gp, w2 = gauss_2d(3)
    F, M, _, _, detP, spP, thL = strain_frames(X, H_below, H, tie.points, zeta, frame)  # sampling points
    v = np.ascontiguousarray(tie_correction(tie, detP, spP.interpolate(H))) if consistent else None
    Fq, _, _, _, detG, sg, _ = strain_frames(X, H_below, H, gp, zeta, frame)  # Gauss points
    Hq = sg.interpolate(H)
    dV = detG * (w2[:, None] * wz[None, :]) * (0.5 * Hq[..., None])  # (e, q, z)
    C = ply_stiffness(sg, plies, direction, ply)  # (e, q, z, 6, 6)
    T = covariant_map(np.linalg.inv(Fq))  # (e, q, z, 6, 6): rows of F⁻¹ = dual vectors F^i
    Ct = np.einsum("eqzVc,eqzVW,eqzWd->ezqcd", T, C, T) * dV.transpose(0, 2, 1)[..., None, None]
    Ct = np.ascontiguousarray(0.5 * (Ct + np.swapaxes(Ct, -1, -2)))
    L, split = None, 0
    if np.all(dV > 0):
        Ch = tied_stiffness(Ct, tie, v)
        nO = tie.n_normal
        coupling = np.abs(Ch[..., :nO, nO:]).max(axis=(-1, -2))
        if np.all(coupling <= 1e-12 * np.abs(Ch).max(axis=(-1, -2))):  # round-off: material axis 3 = normal
            Ch[..., :nO, nO:] = 0.0
            Ch[..., nO:, :nO] = 0.0
            split = nO
        try:
            L = np.ascontiguousarray(np.linalg.cholesky(Ch))
        except np.linalg.LinAlgError:
            L, split = None, 0
    e, q, z = dV.shape
    Cz = np.ascontiguousarray(C.transpose(0, 2, 1, 3, 4).reshape(e, z * q, 6, 6))
    N, dN, _ = _quad9(tie.points)
    return MitcBlock(d, tie, N, dN, np.ascontiguousarray(thL.transpose(0, 2, 1)),
                     np.ascontiguousarray(F.transpose(0, 2, 1, 3, 4)), np.ascontiguousarray(M.transpose(0, 2, 1, 3, 4)),
                     Ct, L, Cz, np.ascontiguousarray(dV.transpose(0, 2, 1).reshape(e, z * q)), split, v,
                     np.ascontiguousarray(T.transpose(0, 2, 1, 3, 4)) if keep_map else None)


def tie_correction(tie: Tying, detG: np.ndarray, Hp: np.ndarray) -> np.ndarray:
    """v (e, z, nT): the consistency correction of the tying (module docstring), from the volume
    Jacobian ``detG (e, P, z)`` and the layer thickness ``Hp (e, P)`` at the sampling points.

    Per level and component c, with ρ = detG H/2 (volume per unit natural area and level), the
    Gauss weights dV_q = w_q ρ(q), V = Σ_q dV_q, the weights the tied field gives its ties
    W_t = Σ_q dV_q h_t(q), and those of the product Gauss rule of the tying points
    w̄_t = rule_t ρ(p_t) (scaled so that Σ_t w̄_t = V): v_t = (w̄_t − W_t)/V. Zero where ρ is
    bilinear (straight-edged flat elements of constant thickness) and for ties at the Gauss points
    (E_33, or every component with ``tying(full=True)``)."""
    gq = tie.pts[2, :9]  # the Gauss points (E_33 is taken there)
    _, w2 = gauss_2d(3)
    rho = detG * (0.5 * Hp)[..., None]  # (e, P, z)
    dV = w2[:, None] * rho[:, gq]  # (e, q, z)
    V = dV.sum(axis=1)  # (e, z)
    W = np.einsum("eqz,cqt->ezct", dV, tie.w)
    wb = tie.rule[None, None] * rho[:, tie.pts].transpose(0, 3, 1, 2)  # (e, z, c, T)
    wb *= (V[..., None] / wb.sum(axis=-1))[..., None]
    v = (wb - W) / V[..., None, None]
    out = np.empty(v.shape[:2] + (int(tie.off[-1]),))
    for c in range(6):
        out[..., tie.off[c]:tie.off[c] + tie.n[c]] = v[..., c, :tie.n[c]]
    return out


def tied_stiffness(Ct: np.ndarray, tie: Tying, v: np.ndarray | None = None) -> np.ndarray:
    """Ĉ (e, z, nT, nT) = Σ_q H_qᵀ C̃_q H_q: the level's stiffness in the tie space (H_q = the
    tying functions at Gauss point q, :meth:`Tying.tie_space`). With the tie-space strains E and
    rows B (nT = 37 for MITC9, against 6 × 9 = 54 Gauss-point rows), Σ_q B̃_qᵀ C̃_q B̃_q = Bᵀ Ĉ B
    and Σ_q B̃_qᵀ S̃_q = Bᵀ (Ĉ E): the material tangent is one syrk with 37 instead of 54 rows per
    level. Positive definite where every C̃_q is (each H_c has full column rank). With the
    consistency correction ``v`` (:func:`tie_correction`) the tied field is H_q P with
    P = I + U Vᵀ (U (nT, 6) the component indicator, column c of V the v of component c's ties:
    each tie strain plus the same combination v_cᵀE_c of its component's ties; invertible,
    det P = Π_c (1 + v_cᵀ1) = 1) and Ĉ = Pᵀ (Σ_q H_qᵀ C̃_q H_q) P, a rank-12 update."""
    H = tie.tie_space()
    C = np.einsum("qck,ezqcd,qdl->ezkl", H, Ct, H, optimize=True)
    if v is not None:  # Pᵀ C P = C + A Vᵀ + V (Aᵀ + Uᵀ A Vᵀ), A = C U
        U = (tie.component()[:, None] == np.arange(6)).astype(float)  # (nT, 6)
        V = v[..., None] * U  # (e, z, nT, 6)
        A = C @ U
        C = C + A @ np.swapaxes(V, -1, -2) + V @ (np.swapaxes(A, -1, -2) + (U.T @ A) @ np.swapaxes(V, -1, -2))
    return 0.5 * (C + np.swapaxes(C, -1, -2))


def _quad9(points):
    from .shape import quad9

    return quad9(points[:, 0], points[:, 1])


def _dense_correction(tie: Tying, v: np.ndarray) -> np.ndarray:
    """The correction ``v (e, z, nT)`` per component and sampling point, ``(e, z, 6, P)``."""
    Vd = np.zeros(v.shape[:2] + (6, len(tie.points)))
    for c in range(6):
        for t in range(tie.n[c]):
            Vd[:, :, c, tie.pts[c, t]] += v[:, :, tie.off[c] + t]
    return Vd


def natural_gradients(block: MitcBlock, sl: slice = slice(None)) -> np.ndarray:
    """∂_i phi_a at the sampling points, ``(e, z, P, a, 3)`` (i = Θ¹, Θ², Θ³)."""
    d = block.d
    l = np.arange(d + 1)
    t = block.thL[sl][..., None]  # (e, z, P, 1)
    pw = t ** l
    dpw = np.where(l > 0, l * t ** np.maximum(l - 1, 0), 0.0)
    d12 = np.einsum("pna,ezpl->ezpnla", block.dN, pw)
    d3 = np.einsum("pn,ezpl->ezpnl", block.N, dpw)[..., None]
    dphi = np.concatenate([d12, d3], axis=-1)
    e, z, P = dphi.shape[:3]
    return dphi.reshape(e, z, P, 9 * (d + 1), 3)


def mitc_response_reference(block: MitcBlock, U: np.ndarray, nonlinear: bool = True, tangent: bool = True,
                            sl: slice = slice(None), stress=None):
    """Plain NumPy form of the MITC9 layer response (module docstring): ``f (e, m)``, ``K (e, m, m)``.

    ``stress(E) -> (S, D)``: the Cartesian stress and tangent at the Gauss points (``(e, z·9, 6)``,
    ``(e, z·9, 6, 6)``, z-major as ``block.dV``) from the Cartesian tied strain E = T Ẽ, in place
    of S̃ = C̃ Ẽ (inelastic layers, :mod:`.inelastic`; needs ``block.T``)."""
    dphi = np.einsum("ezpai,ezpib->ezpab", natural_gradients(block, sl), block.M[sl])  # along F_b
    Gc = np.swapaxes(block.G[sl], -1, -2)  # (e, z, P, i, k): G_i components k
    Ct = block.Ct[sl]
    H = block.tie.dense()  # (c, q, P)
    D = np.einsum("ezpai,eak->ezpik", dphi, U)  # ∂_i u
    g = Gc + D if nonlinear else Gc
    GD = np.einsum("ezpik,ezpjk->ezpij", Gc, D)
    E = 0.5 * (GD + np.swapaxes(GD, -1, -2))
    if nonlinear:
        E = E + 0.5 * np.einsum("ezpik,ezpjk->ezpij", D, D)
    Ev = np.stack([E[..., i, j] * (1.0 if i == j else 2.0) for i, j in _PAIRS], axis=-1)  # (e, z, P, c)
    # B (e, z, P, c, a, k) = fac (g_ik dphi_aj + g_jk dphi_ai)
    B = np.stack([(0.5 if i == j else 1.0) * (np.einsum("ezpk,ezpa->ezpak", g[..., i, :], dphi[..., j])
                                              + np.einsum("ezpk,ezpa->ezpak", g[..., j, :], dphi[..., i]))
                  for i, j in _PAIRS], axis=3)
    Et = np.einsum("cqp,ezpc->ezqc", H, Ev)
    Bt = np.einsum("cqp,ezpcak->ezqcak", H, B)
    if block.v is not None:  # consistency correction: the same combination of the ties at every q
        Vd = _dense_correction(block.tie, block.v[sl])  # (e, z, c, P)
        Et = Et + np.einsum("ezcp,ezpc->ezc", Vd, Ev)[:, :, None]
        Bt = Bt + np.einsum("ezcp,ezpcak->ezcak", Vd, B)[:, :, None]
    if stress is None:
        S = np.einsum("ezqcd,ezqd->ezqc", Ct, Et)
    else:  # Cartesian E = T Ẽ; S̃ = Tᵀ S dV, C̃ = Tᵀ D T dV
        T = block.T[sl]
        ne, nz, nq = Et.shape[:3]
        Sc, D = stress(np.einsum("ezqVc,ezqc->ezqV", T, Et).reshape(ne, nz * nq, 6))
        dV = block.dV[sl].reshape(ne, nz, nq)
        S = np.einsum("ezqVc,ezqV->ezqc", T, Sc.reshape(ne, nz, nq, 6)) * dV[..., None]
        if tangent:
            Ct = np.einsum("ezqVc,ezqVW,ezqWd->ezqcd", T, D.reshape(ne, nz, nq, 6, 6), T,
                           optimize=True) * dV[..., None, None]
    e, a = U.shape[:2]
    m = 3 * a
    f = np.einsum("ezqcak,ezqc->eak", Bt, S).reshape(e, m)
    if not tangent:
        return f, None
    Bm = Bt.reshape(Bt.shape[:4] + (m,))
    K = np.einsum("ezqcm,ezqcd,ezqdn->emn", Bm, Ct, Bm, optimize=True)
    if nonlinear:
        sv = np.einsum("cqp,ezqc->ezpc", H, S)
        if block.v is not None:
            sv = sv + np.einsum("ezcp,ezqc->ezpc", Vd, S)
        sig = np.stack([np.stack([sv[..., 0], sv[..., 5], sv[..., 4]], -1),
                        np.stack([sv[..., 5], sv[..., 1], sv[..., 3]], -1),
                        np.stack([sv[..., 4], sv[..., 3], sv[..., 2]], -1)], -2)
        Kg = np.einsum("ezpai,ezpij,ezpbj->eab", dphi, sig, dphi, optimize=True)
        K = K.reshape(e, a, 3, a, 3) + Kg[:, :, None, :, None] * np.eye(3)[None, None, :, None, :]
        K = K.reshape(e, m, m)
    return f, K




_SUB = 8  # elements per sub-block (as in kernel.py)


_NONE3 = np.empty((0, 0, 0))  # the compiled kernel's σ input and strain output, unused by the elastic layer
_NONE5 = np.empty((0, 0, 0, 0, 0))  # its displacement derivatives input, likewise
_GEMM_BELOW = 60  # m below which Xᵀ X is faster as a general product (d ≤ 1: OpenBLAS syrk is slow for small m)


def _mitc_range(block: MitcBlock, sl0: int, U, nonlinear, tangent, f, K, lo: int, hi: int) -> None:
    """Fill ``f[lo:hi]``, ``K[lo:hi]`` (element indices relative to the block slice start ``sl0``).

    Material tangent in the tie space: K_mat = Σ_z B_zᵀ Ĉ_z B_z = Xᵀ X with X_z = L̂_zᵀ B_z (one
    batched BLAS product) stacked over the levels (nT = 37 rows per level against the 54 rows of
    the 9 Gauss points)."""
    from . import _jit

    tie = block.tie
    d = block.d
    a = 9 * (d + 1)
    m = 3 * a
    nz = block.thL.shape[1]
    nT = int(tie.off[-1])
    ncol = nz * int(tie.ndir.sum())
    geo = tangent and nonlinear
    lower = block.L is not None
    for s in range(lo, hi, _SUB):
        t = min(s + _SUB, hi)
        nb = t - s
        g0, g1 = sl0 + s, sl0 + t
        B = np.empty((nb, nz, nT, m) if tangent else (1, 1, 1, 1))
        GS = np.empty((nb, ncol, a) if geo else (0, 0, 0))
        GT = np.empty_like(GS)
        Lh = block.L[g0:g1] if lower else np.ascontiguousarray(
            tied_stiffness(block.Ct[g0:g1], tie, None if block.v is None else block.v[g0:g1]))
        _jit.mitc_terms(block.N, block.dN, block.thL[g0:g1], block.G[g0:g1], block.M[g0:g1], tie.pts, tie.off,
                        tie.n, tie.dirs, tie.ndir, tie.gn, tie.gk, tie.gJ, Lh, U[s:t], d, nonlinear, tangent, geo,
                        lower, f[s:t], B, GS, GT, 0, _NONE3, _NONE3, _NONE5)
        if not tangent:
            continue
        Br = B.reshape(nb, nz * nT, m).transpose(0, 2, 1)
        if lower:
            Lt = Lh.transpose(0, 1, 3, 2)
            if block.split:  # L̂ block diagonal: normal/in-plane ties and transverse shear ties apart
                h = block.split
                X = np.empty_like(B)
                np.matmul(Lt[:, :, :h, :h], B[:, :, :h], out=X[:, :, :h])
                np.matmul(Lt[:, :, h:, h:], B[:, :, h:], out=X[:, :, h:])
                X = X.reshape(nb, nz * nT, m)
            else:
                X = np.matmul(Lt, B).reshape(nb, nz * nT, m)
            if m < _GEMM_BELOW:
                np.matmul(X.transpose(0, 2, 1), X.copy(), out=K[s:t])
            else:  # NumPy dispatches a matrix times its own transpose to BLAS syrk
                np.matmul(X.transpose(0, 2, 1), X, out=K[s:t])
        else:  # Ĉ not positive definite: K = Σ_z Bᵀ (Ĉ B)
            np.matmul(Br, np.matmul(Lh, B).reshape(nb, nz * nT, m), out=K[s:t])
        if geo:
            _jit.add_geometric(K[s:t], np.matmul(GS.transpose(0, 2, 1), GT))


def mitc_response(block: MitcBlock, U: np.ndarray, nonlinear: bool = True, tangent: bool = True,
                  sl: slice = slice(None)):
    """Internal force ``(e, m)`` and tangent ``(e, m, m)`` of a MITC9 layer block (compiled point
    work, one BLAS syrk per element for the material part, elements over threads as in
    :func:`kernel.layer_response`); equal to :func:`mitc_response_reference` to round-off."""
    from ..threads import blas_single_thread
    from .kernel import _pool, kernel_threads
    from contextlib import nullcontext

    n_all = block.thL.shape[0]
    lo0, hi0, step = sl.indices(n_all)
    if step != 1:
        raise ValueError("mitc_response: the element range must be contiguous")
    U = np.ascontiguousarray(U, dtype=np.float64)
    nonlinear, tangent = bool(nonlinear), bool(tangent)
    e = hi0 - lo0
    a = 9 * (block.d + 1)
    m = 3 * a
    f = np.empty((e, m))
    K = np.empty((e, m, m)) if tangent else None
    n_threads = min(kernel_threads(), max(1, e // _SUB))
    with blas_single_thread() if tangent else nullcontext():
        if n_threads == 1:
            _mitc_range(block, lo0, U, nonlinear, tangent, f, K, 0, e)
        else:
            bounds = np.linspace(0, e, n_threads + 1).astype(int)
            jobs = [_pool(n_threads).submit(_mitc_range, block, lo0, U, nonlinear, tangent, f, K, lo, hi)
                    for lo, hi in zip(bounds[:-1], bounds[1:])]
            for j in jobs:
                j.result()
    return f, K


def tying_functions(xi: np.ndarray, eta: np.ndarray) -> list[np.ndarray]:
    """MITC9 tying functions at arbitrary points: per Voigt component c the weights
    ``(s, n_c)`` of its ties (E_33: none, it is taken at the point itself)."""
    a, b = A_TIE, B_TIE
    la, lb = np.array([-a, a]), np.array([-b, 0.0, b])
    s = len(xi)
    hA = np.einsum("qi,qj->qij", _lagrange(la, xi), _lagrange(lb, eta)).reshape(s, 6)
    hB = np.einsum("qi,qj->qij", _lagrange(lb, xi), _lagrange(la, eta)).reshape(s, 6)
    hC = np.einsum("qi,qj->qij", _lagrange(la, xi), _lagrange(la, eta)).reshape(s, 4)
    return [hA, hB, None, hB, hA, hC]


def tied_strain(X: np.ndarray, H_below: np.ndarray, H: np.ndarray, d: int, U: np.ndarray, xi: np.ndarray,
                eta: np.ndarray, thL: np.ndarray, nonlinear: bool = True, frame: str = "center",
                groups: np.ndarray | None = None) -> np.ndarray:
    """Cartesian Voigt Green-Lagrange strain (engineering shear) of the MITC9 element at points
    ``(xi, eta, Θ_L)`` of elements ``X (s, 9, 3)`` with nodal vectors ``U (s, a, 3)``: the strain
    the element's stress is computed from (tied E_11, E_22, E_12, E_13, E_23 interpolated from the
    tying points at the point's natural thickness level, E_33 at the point), so probes, profiles
    and the delamination criterion see the element's own strain field. ``groups`` (s,): the
    element of each point; points of one element at one natural level then share the strains at
    the tying points, computed once (the stress recovery asks for 9 points per element and level:
    9 times fewer tying-point evaluations)."""
    tie = tying()
    s = len(xi)
    zeta = (2.0 * thL / np.einsum("sn,sn->s", _quad9(np.stack([xi, eta], -1))[0], H) - 1.0)[:, None, None]
    if groups is None:
        rows, inv = np.arange(s), np.arange(s)
    else:
        _, rows, inv = np.unique(np.stack([np.asarray(groups, float), zeta[:, 0, 0]], -1), axis=0,
                                 return_index=True, return_inverse=True)
        inv = inv.ravel()
    Ffr, M, _, _, detP, spP, thp = strain_frames(X[rows], H_below[rows], H[rows], tie.points[:16], zeta[rows], frame)
    detQ, HQ = _volume_jacobian(X[rows], H_below[rows], H[rows], tie.points[16:], zeta[rows])  # Gauss points
    v = tie_correction(tie, np.concatenate([detP, detQ], 1),
                       np.concatenate([spP.interpolate(H[rows]), HQ], 1))[:, 0]  # (u, nT), the point's level
    N, dN, _ = _quad9(tie.points[:16])
    Ev_tie = _strains(Ffr[:, :16, 0], M[:, :16, 0], thp[:, :16, 0], np.broadcast_to(N, (rows.size,) + N.shape),
                      np.broadcast_to(dN, (rows.size,) + dN.shape), U[rows], d, nonlinear)  # (u, 16, 6)
    # the point itself: evaluate per element at its (xi, eta)
    Fp, Mp, _, _, _, _, thq = _point_frames(X, H_below, H, xi, eta, zeta, frame)
    Nq, dNq, _ = _quad9(np.stack([xi, eta], -1))
    Ev_pt = _strains(Fp, Mp, thq, Nq[:, None], dNq[:, None], U, d, nonlinear)  # (s, 1, 6)
    Ev = np.concatenate([Ev_tie[inv], Ev_pt], axis=1)  # (s, 17, 6)
    h = tying_functions(xi, eta)
    idx = {0: slice(0, 6), 4: slice(0, 6), 1: slice(6, 12), 3: slice(6, 12), 5: slice(12, 16)}
    Et = np.empty((s, 6))
    for c in range(6):
        if c == 2:
            Et[:, c] = Ev[:, 16, c]
        else:  # tying functions plus the consistency correction of the point's element and level
            hc = h[c] + v[inv, tie.off[c]:tie.off[c] + tie.n[c]]
            Et[:, c] = np.einsum("st,st->s", hc, Ev[:, idx[c], c])
    T = covariant_map(np.linalg.inv(Fp[:, 0]))
    return np.einsum("sVc,sc->sV", T, Et)


def _volume_jacobian(X, H_below, H, points, zeta):
    """detG (e, P, z) = √A det(I − Θ¹ B) at in-plane ``points`` and levels ``zeta`` (as
    :func:`strain_frames` returns it, without the frames) and the layer thickness Hp (e, P)."""
    sp = surface_points(X, points[:, 0], points[:, 1])
    Hp = sp.interpolate(H)
    t = sp.interpolate(H_below)[..., None] + 0.5 * Hp[..., None] * (zeta + 1.0)  # Θ¹ (e, P, z)
    B = sp.Bmix
    trB, detB = B[..., 0, 0] + B[..., 1, 1], B[..., 0, 0] * B[..., 1, 1] - B[..., 0, 1] * B[..., 1, 0]
    return sp.sqrtA[..., None] * (1.0 - t * trB[..., None] + t * t * detB[..., None]), Hp


def _strains(F: np.ndarray, M: np.ndarray, th: np.ndarray, N: np.ndarray, dN: np.ndarray, U: np.ndarray, d: int,
             nonlinear: bool) -> np.ndarray:
    """Covariant Voigt Green-Lagrange strains (s, p, 6) in the frames ``F`` (s, p, 3, 3) at points
    with shape functions ``N (s, p, 9)``, ``dN (s, p, 9, 2)``, layer coordinates ``th (s, p)`` and the
    maps ``M`` of :func:`strain_frames`, for nodal vectors ``U (s, a, 3)``."""
    s, p = th.shape
    l = np.arange(d + 1)
    pw, dpw = th[..., None] ** l, np.where(l > 0, l * th[..., None] ** np.maximum(l - 1, 0), 0.0)
    # D_ik = Σ_a ∂φ_a,i U_ak with ∂φ_(n,l) = (∂_α N_n Θ^l, N_n l Θ^(l-1)) M: contract the
    # directors first (W_n = Σ_l Θ^l U_nl, V_n = Σ_l l Θ^(l-1) U_nl), then the nodes, then M -
    # small batched products instead of the (s, p, 9(d+1), 3) gradient array (the stress recovery
    # evaluates this at every Gauss point of every level)
    U4 = U.reshape(s, 9, d + 1, 3)
    W = np.swapaxes(np.matmul(pw[:, None], U4), 1, 2)  # (s, p, 9, 3)
    V = np.swapaxes(np.matmul(dpw[:, None], U4), 1, 2)
    C = np.concatenate([np.matmul(np.swapaxes(dN, -1, -2), W), np.matmul(N[..., None, :], V)], axis=-2)  # (s, p, 3, 3)
    D = np.matmul(np.swapaxes(M, -1, -2), C)  # D_ik = Σ_a dphi_ai U_ak
    Gc = np.swapaxes(F, -1, -2)
    GD = np.matmul(Gc, np.swapaxes(D, -1, -2))
    E = 0.5 * (GD + np.swapaxes(GD, -1, -2))
    if nonlinear:
        E = E + 0.5 * np.matmul(D, np.swapaxes(D, -1, -2))
    return np.stack([E[..., i, j] * (1.0 if i == j else 2.0) for i, j in _PAIRS], axis=-1)


def _point_frames(X, H_below, H, xi, eta, zeta, frame):
    """:func:`strain_frames` at one point per element ``(xi[s], eta[s])`` (level ``zeta (s,1,1)``)."""
    sp = surface_points(X, xi[:, None], eta[:, None], per_element=True)
    Hp, Hbp = sp.interpolate(H), sp.interpolate(H_below)  # (s, 1)
    thL = 0.5 * Hp[..., None] * (zeta + 1.0)  # (s, 1, 1)
    G, Ginv, _ = shell_basis(sp, Hbp[..., None] + thL)
    if frame == "natural":
        F = G
    else:
        sc = surface_points(X, np.zeros(1), np.zeros(1))
        tc = 0.5 * sc.interpolate(H)[..., None] * (zeta + 1.0)
        Gcen, _, _ = shell_basis(sc, sc.interpolate(H_below)[..., None] + tc)
        R = _rotation(sc.A3, sp.A3)
        Fa = np.einsum("epij,ezja->epzia", R, Gcen[:, 0, :, :, :2])
        F = np.concatenate([Fa, np.broadcast_to(sp.A3[:, :, None, :, None], Fa.shape[:-1] + (1,))], axis=-1)
    M = np.einsum("epziJ,epzJb->epzib", Ginv, F)
    return F[:, :, 0], M[:, :, 0], None, None, None, None, thL[:, :, 0]
