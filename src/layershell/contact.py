"""Inner contact between a debonded layer and the layer below, MODEL.md §10 / thesis (4.37)-(4.59).

Points are the 9 face Gauss points of the upper layer (the "integration points of layer L",
(3.48)); each belongs to the region of its nearest node (§9 rule 1) and is released when that
node is released at this interface. Pairing is along the common undeformed normal A3 of S1
(no search, (4.37)-(4.38)). With nodal thicknesses (exact at nodes, A6) the relative
displacement of the upper layer's bottom face to the lower layer's top face is

    Δu(q) = Σ_n N_n(q) (u_0L,n - Σ_l H_(L-1),n^l u_l(L-1),n)         (4.43)-(4.44)

and the normal gap ḡ_N = Δu · A3 (4.45). Penalty contact acts where ḡ_N ≤ 0 with the energy
½ α_N ḡ_N² per area: f = α_N ḡ_N ∂ḡ/∂u, K = α_N ∂ḡ/∂u ⊗ ∂ḡ/∂u (4.56)-(4.59); the gap is linear
in u, so there is no second-order term.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dofs import DofMap
from .element.geometry import shell_basis, surface_points
from .element.quadrature import gauss_2d
from .element.shape import NODE_XI
from .interfaces import Interface
from .model import Model

#: shape of the slip limit in the friction return mapping: ``inf`` (default) is the exact
#: penalty return mapping f(x) = min(x, 1) (elastic stick with the penalty α_T, sliding at the
#: limit); a finite n gives the smooth f(x) = x/(1 + x^n)^(1/n) (f(1) = 0.917 for n = 8). Newton
#: on the smooth form converges slowly when many points pass the limit (like Newton on arctan):
#: the pull-off example needs about 3x the iterations; the §5.1 plate gives the same w_front_max
#: (to 4 digits) with both
FRICTION_SHARPNESS = float("inf")


def friction_shape(x: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """f(x)/x and f'(x) of the friction limit shape f (x = |t_trial| / slip limit)."""
    k = FRICTION_SHARPNESS
    if np.isinf(k):
        return 1.0 / np.maximum(x, 1.0), (x < 1.0).astype(float)
    return (1.0 + x**k) ** (-1.0 / k), (1.0 + x**k) ** (-1.0 / k - 1.0)


def friction_shape_inverse(ratio: np.ndarray | float):
    """x with f(x) = ratio (0 ≤ ratio < 1)."""
    k = FRICTION_SHARPNESS
    if np.isinf(k):
        return ratio
    return ratio / (1.0 - ratio**k) ** (1.0 / k)


def face_rule(rule: str = "gauss") -> tuple[np.ndarray, np.ndarray]:
    """Interface integration rule on the element face: the 3×3 Gauss points (the thesis's face
    points (3.48)) or the 3×3 Lobatto (nodal Newton–Cotes/Simpson) rule, whose points are the
    nodes (no traction oscillations with stiff interface penalties, Schellekens & de Borst 1993).
    Points (9, 2) eta-major as :func:`gauss_2d`, weights (9,)."""
    if rule == "gauss":
        return gauss_2d(3)
    x, w = np.array([-1.0, 0.0, 1.0]), np.array([1.0, 4.0, 1.0]) / 3.0
    xi, eta = np.meshgrid(x, x, indexing="xy")
    return np.stack([xi.ravel(), eta.ravel()], axis=-1), np.outer(w, w).ravel()


def point_regions(rule: str = "gauss") -> np.ndarray:
    """Element node (VTK order) whose region contains each 3×3 face point (§9 rule 1: the
    nearest node; for the nodal rule the node itself)."""
    pts, _ = face_rule(rule)
    sgn = np.sign(np.round(pts, 12))
    return np.array([int(np.flatnonzero((NODE_XI == s).all(1))[0]) for s in sgn])


@dataclass
class ContactBlock:
    """Reference data and state of the contact of one interface over its elements.

    dofs (e, m): [upper u_0 (9 × 3), lower u_l (9 × (d+1) × 3)] full-space DOFs
    C (e, q, 3, m): Δu_i = C_iM U_M;  b (e, q, m): ∂ḡ_N/∂U = A3 · C
    w (e, q): contact weights μ(Ĥ) √A κ;  w0 (e, q): load weights √A κ (μ neglected, (4.74))
    released (e, q): region released (set by the interface state); alpha: penalty α_N
    """

    itf: Interface
    conn: np.ndarray
    dofs: np.ndarray
    C: np.ndarray
    b: np.ndarray
    A3: np.ndarray
    w: np.ndarray
    w0: np.ndarray
    region: np.ndarray  # (q,) node of each point
    alpha: float
    released: np.ndarray
    active: np.ndarray | None = None  # frozen contact set during a Newton solve (None: from the gap)
    # traction scale of set violations (the interface's tensile strength σ_max; None: not measured)
    strength: float | None = None
    # penalty-regularised friction (return mapping): None = friction only as external loads
    alpha_T: float | np.ndarray | None = None  # a number, or one per point (e, q) (cohesive.stick_penalty)
    cap: np.ndarray | None = None  # (e, q) slip limit of the current step (0: no friction)
    t_n: np.ndarray | None = None  # (e, q, 3) converged tangential traction (upper on lower)
    g_p: np.ndarray | None = None  # (e, q, 3) slip anchor: t = α_T (P Δu - g_p) while sticking
    X0: np.ndarray | None = None  # (e, q, 3) reference positions of the points (results)
    # (e, q) stick state frozen during a cohesive active-set solve (CohesiveBlock.freeze): a point
    # frozen sticking keeps the stick law beyond its slip limit (the loop checks it afterwards),
    # the others follow the return mapping; None: the return mapping everywhere
    stick_frozen: np.ndarray | None = None
    # c (e, q, k), k = m/3: C = c ⊗ I₃ (C_iM = c_k δ_ij for M = 3k + j), the scalar weights of the
    # nodal directors in Δu; the response works with c (a third of C's size, 1/9 of its products)
    c: np.ndarray | None = None
    #: the tangent is symmetric (normal penalty α_N b⊗b, friction α_T P or α_T cap/|t_tr| (I-e⊗e)P
    #: with e in the tangent plane): PARDISO's symmetric mode needs no check
    symmetric = True
    #: ``response(..., compact=True)`` gives the tangent of the elements with released points only
    compact_tangent = True

    def __post_init__(self) -> None:
        if self.c is None:
            self.c = np.ascontiguousarray(self.C[:, :, 0, 0::3])
        self._point_form()

    def _point_form(self) -> None:
        """Point-wise assembly where each face point sees only its own node (the nodal rule:
        N_n(q) = δ_nq): K_e = Σ_q c_q ⊗ c_q ⊗ M_q is then block diagonal with one block per point
        over that node's DOFs (the upper u_0 and the lower u_l: 3 (d + 2) of them), so the
        assembler scatters ``assembly_dofs`` (e·q, 3 s) rows of (3 s)² entries instead of the
        element's m² (1/9 of them: the DCB's interface tangent 3.6 M → 0.4 M entries per
        evaluation). ``assembly_dofs`` stays None for the Gauss rule (every point sees every node)."""
        self.assembly_dofs = self.c_points = None
        ne, nq, nk = self.c.shape
        if ne == 0:
            return
        nz = np.abs(self.c).max(axis=0) > 0  # (q, k): which nodal DOF triples point q sees
        s = nz.sum(axis=1)
        if np.any(nz.sum(axis=0) > 1) or np.any(s != s[0]) or s[0] == nk:
            return
        sel = np.array([np.flatnonzero(r) for r in nz])  # (q, s)
        self.c_points = np.ascontiguousarray(np.take_along_axis(self.c, sel[None], axis=2))  # (e, q, s)
        self.assembly_dofs = self.dofs.reshape(ne, nk, 3)[:, sel, :].reshape(ne * nq, -1)

    def point_matrices(self, T: np.ndarray, M: np.ndarray | None, rows: np.ndarray | None = None):
        """Point-wise force (e·q, 3 s) and tangent (r, 3 s, 3 s) of the point form
        (``assembly_dofs``) from the point vectors T (e, q, 3) and matrices M (e, q, 3, 3) (or
        (r, 3, 3) for the point ``rows`` r of e·q): f_(a,i) = c_a T_i, K_(a,i)(b,j) = c_a c_b M_ij."""
        ne, nq, ns = self.c_points.shape
        cp = self.c_points.reshape(ne * nq, ns)
        f = (cp[:, :, None] * T.reshape(ne * nq, 1, 3)).reshape(ne * nq, 3 * ns)
        if M is None:
            return f, None
        c = cp if rows is None else cp[rows]
        M = M.reshape(-1, 3, 3)
        K = (c[:, :, None, None, None] * c[:, None, None, :, None] * M[:, None, :, None, :])
        return f, K.reshape(-1, 3 * ns, 3 * ns)

    @classmethod
    def build(cls, model: Model, dm: DofMap, itf: Interface, alpha: float, rule: str = "gauss") -> "ContactBlock":
        """``rule``: the face points (:func:`face_rule`); the thesis's contact uses "gauss"."""
        el = itf.elements
        conn = model.mesh.elements[el]
        pts, wq = face_rule(rule)
        sp = surface_points(model.mesh.nodes[conn], pts[:, 0], pts[:, 1])
        lo = model.layers[itf.lower]
        d = lo.directors
        H = lo.thickness[conn]  # (e, 9) nodal thickness of the lower layer
        off = model.offset(itf.upper)[conn]
        _, _, detG = shell_basis(sp, sp.interpolate(off)[..., None])
        ne, nq = len(el), len(wq)
        # c: the weights of the upper layer's u_0 (N_n) and of the lower layer's directors at its
        # top face (-N_n H_n^l) in Δu; C = c ⊗ I₃ (4.43)-(4.44)
        c = np.ascontiguousarray(np.concatenate(
            [np.broadcast_to(sp.N, (ne, nq, 9)),
             -np.einsum("qn,enl->eqnl", sp.N, H[..., None] ** np.arange(d + 1)).reshape(ne, nq, -1)], axis=2))
        C = np.einsum("eqk,ij->eqikj", c, np.eye(3)).reshape(ne, nq, 3, -1)
        b = np.einsum("eqi,eqim->eqm", sp.A3, C)
        dofs = np.concatenate([dm.layer_dofs[itf.upper][conn][:, :, 0, :].reshape(ne, -1),
                               dm.layer_dofs[itf.lower][conn].reshape(ne, -1)], axis=1)
        return cls(itf, conn, dofs, C, b, sp.A3, detG[..., 0] * wq, sp.sqrtA * wq, point_regions(rule), alpha,
                   np.zeros((ne, nq), bool), X0=sp.X0, c=c)

    # ------------------------------------------------------------------ kinematics
    def relative_displacement(self, u_full: np.ndarray) -> np.ndarray:
        """Δu (e, q, 3) of the upper layer's bottom face relative to the lower layer's top face."""
        return np.einsum("eqim,em->eqi", self.C, u_full[self.dofs])

    def gap(self, u_full: np.ndarray) -> np.ndarray:
        """Normal gap ḡ_N (e, q) along the undeformed normal (4.43)."""
        return np.einsum("eqm,em->eq", self.b, u_full[self.dofs])

    # ------------------------------------------------------------------ assembly
    def freeze(self, u_full: np.ndarray) -> None:
        """Fix the contact set (released points with ḡ_N ≤ 0) and the stick/slip states for the
        following iterations."""
        self.active = None
        self.active = self.released & (self.gap(u_full) <= 0.0)

    def set_changed(self, u_full: np.ndarray) -> bool:
        """After convergence with frozen states: do they still match the solution (no released
        point penetrates outside the contact set, none in it is pulled open, stick points stay
        below the slip limit, sliding points still push against it)?"""
        want = self.released & (self.gap(u_full) <= 0.0)
        return bool(np.any(want != (self.active if self.active is not None else want)))

    def unfreeze(self) -> None:
        self.active = None

    def set_violation(self, u_full: np.ndarray) -> float:
        """How far the frozen contact set is from holding at ``u_full``, as a traction error in
        units of ``strength``: α_N times the largest opening of a point in the set (a spurious
        tension) or penetration of a released point outside it (a missing pressure); 0 where the
        set holds, infinite where it does not and no strength is known."""
        if self.active is None or not self.released.any():
            return 0.0
        g = self.gap(u_full)
        inside, outside = self.active & self.released, self.released & ~self.active
        worst = max(float(g[inside].max()) if inside.any() else 0.0, float(-g[outside].min()) if outside.any() else 0.0)
        if worst <= 0.0:
            return 0.0
        return self.alpha * worst / self.strength if self.strength else float("inf")

    def projector(self) -> np.ndarray:
        """P = I - A3 ⊗ A3: tangential part along the undeformed normal, (e, q, 3, 3)."""
        return np.eye(3) - np.einsum("eqi,eqj->eqij", self.A3, self.A3)

    def _penalty(self):
        """α_T broadcastable against (e, q, 3): the number, or (e, q, 1) for one per point."""
        aT = np.asarray(self.alpha_T, float)
        return aT[..., None] if aT.ndim else aT

    def trial_traction(self, u_full: np.ndarray, du: np.ndarray | None = None, anchored: bool = True,
                       P: np.ndarray | None = None) -> np.ndarray:
        """Trial friction traction t_tr = α_T (P Δu - g_p) (e, q, 3) (``du``: Δu at ``u_full`` and
        ``P``: :meth:`projector`, if known); not ``anchored``: α_T P Δu, the change of t_tr for an
        increment ``u_full``."""
        P = self.projector() if P is None else P
        du = self.relative_displacement(u_full) if du is None else du
        gT = np.einsum("eqij,eqj->eqi", P, du)
        return self._penalty() * (gT - self.g_p if anchored else gT)

    def slip_ratio(self, u_full: np.ndarray, du: np.ndarray | None = None) -> np.ndarray:
        """x = |t_tr| / cap (e, q): above 1 the point slides (0 where no friction acts)."""
        n = np.linalg.norm(self.trial_traction(u_full, du), axis=-1)
        on = self.released & (self.cap > 0)
        return np.where(on, n / np.where(on, self.cap, 1.0), 0.0)

    def friction_traction(self, u_full: np.ndarray, du: np.ndarray | None = None):
        """Penalty friction by return mapping: with the trial t_tr = α_T (P Δu - g_p) the traction is
        t = cap f(|t_tr|/cap) t_tr/|t_tr| with f(x) = min(x, 1) (FRICTION_SHARPNESS = inf): stick
        with the stiffness α_T below the slip limit ``cap``, sliding at the limit beyond, i.e. the
        backward-Euler return mapping from the anchor g_p of the last converged state (an
        addition to the thesis, which applies friction as loads). Returns t (e, q, 3) (force of
        the upper layer on the lower one per area) and its consistent tangent dt/dΔu (e, q, 3, 3):
        α_T P sticking, α_T cap/|t_tr| (I - e⊗e) P sliding (symmetric: e lies in the tangent
        plane). α_T is a number or one per point (e, q). ``du``: the relative displacement at
        ``u_full`` if already known. Points frozen sticking (``stick_frozen``) keep the stick law
        t = t_tr beyond the limit."""
        P = self.projector()
        t_tr = self.trial_traction(u_full, du, P=P)
        aT = self._penalty()
        n = np.linalg.norm(t_tr, axis=-1)
        on = self.released & (self.cap > 0)
        cap = np.where(on, self.cap, 1.0)
        x = n / cap
        f_over_x, fprime = friction_shape(x)
        if self.stick_frozen is not None:
            f_over_x = np.where(self.stick_frozen, 1.0, f_over_x)
            fprime = np.where(self.stick_frozen, 1.0, fprime)
        e = t_tr / np.where(n > 0, n, 1.0)[..., None]
        ee = np.einsum("eqi,eqj->eqij", e, e)
        dtdtr = f_over_x[..., None, None] * (np.eye(3) - ee) + fprime[..., None, None] * ee
        D = aT[..., None] * np.einsum("eqij,eqjk->eqik", dtdtr, P) * on[..., None, None]
        return t_tr * (f_over_x * on)[..., None], D

    def response(self, u_full: np.ndarray, tangent: bool = True, compact: bool = False, points: bool = False):
        """Penalty contact (and, with return-mapping friction, the tangential traction): internal
        force (e, m) and tangent (e, m, m) at released points (None when not ``tangent``).
        ``compact``: the tangent as ``(K_sub, elements)`` for the elements with a released
        point only (the others contribute nothing; the assembler scatters just these).
        ``points``: force and tangent in the point form (``assembly_dofs``, nodal rule), the
        tangent as ``(K_sub, point rows)`` of the released points.

        With C = c ⊗ I₃ both are sums over the points of one 3-vector T_q and one 3×3 matrix
        M_q: f_(k,i) = Σ_q c_qk T_qi and K_(k,i)(l,j) = Σ_q c_qk c_ql M_qij, where
        T = a ḡ_N A3 + w0 t and M = a A3⊗A3 + w0 dt/dΔu (a = α_N w at contact points)."""
        ne, nq, nk = self.c.shape
        U = u_full[self.dofs].reshape(ne, nk, 3)
        du = np.matmul(self.c, U)  # (e, q, 3) relative displacement (4.43)
        g = np.einsum("eqi,eqi->eq", self.A3, du)  # ḡ_N (4.45)
        active = self.released & (g <= 0.0) if self.active is None else self.active & self.released
        a = self.alpha * self.w * active
        T = (a * g)[..., None] * self.A3
        friction = self.alpha_T is not None and self.cap is not None
        if friction:
            t, D = self.friction_traction(u_full, du)
            T += self.w0[..., None] * t
        if points:  # the point form (assembly_dofs): the released points only
            rows = np.flatnonzero(self.released.ravel())
            if not tangent:
                return self.point_matrices(T, None)[0], None
            A = self.A3.reshape(-1, 3)[rows]
            M = (a.ravel()[rows])[:, None, None] * A[:, :, None] * A[:, None, :]
            if friction:
                M += self.w0.ravel()[rows][:, None, None] * D.reshape(-1, 3, 3)[rows]
            f, Kp = self.point_matrices(T, M, rows)
            return f, (Kp, rows)
        f = np.matmul(self.c.transpose(0, 2, 1), T).reshape(ne, 3 * nk)
        if not tangent:
            return f, None
        el = np.flatnonzero(self.released.any(axis=1))
        M = a[el, :, None, None] * self.A3[el, :, :, None] * self.A3[el, :, None, :]
        if friction:
            M += self.w0[el, :, None, None] * D[el]
        # Σ_q c_q ⊗ (c_q ⊗ M_q) as one batched product over the points, in (k, i, l, j) order
        c = self.c[el]
        cM = (c[:, :, None, :, None] * M[:, :, :, None, :]).reshape(el.size, nq, 9 * nk)
        Ks = np.matmul(c.transpose(0, 2, 1), cM).reshape(el.size, 3 * nk, 3 * nk)
        if compact:
            return f, (Ks, el)
        K = np.zeros((ne, 3 * nk, 3 * nk))
        K[el] = Ks
        return f, K

    def load_vector(self, traction: np.ndarray, F: np.ndarray) -> None:
        """Add the director forces of an interface traction τ' (e, q, 3) (force of the upper layer
        on the lower one, per area): the lower layer's top face gets +τ', the upper layer's
        bottom face -τ' (4.74)-(4.75)."""
        fe = -np.einsum("eq,eqim,eqi->em", self.w0, self.C, traction)
        np.add.at(F, self.dofs.ravel(), fe.ravel())
