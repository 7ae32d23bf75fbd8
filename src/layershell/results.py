"""Results at arbitrary points (ξ, η, Θ_1³) of elements: displacements, strains, stresses.

MODEL.md §3 / thesis (2.81)-(2.114): PK2 and Cauchy stresses as physical components in the
orthonormal material-aligned bases M_k (undeformed) and m_k (deformed), principal stresses,
the surface traction vector σ·m_3.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .dofs import DofMap
from .element.geometry import shell_basis, surface_points
from .element.kernel import basis_gradients, green_lagrange, material_frame, voigt_to_matrix
from .element.quadrature import ply_of
from .material import rotate_stiffness
from .model import Model


def cauchy_stress(F: np.ndarray, S: np.ndarray) -> np.ndarray:
    """σ = J⁻¹ F S Fᵀ (2.88) for batched ``F, S (..., 3, 3)``."""
    J = np.linalg.det(F)
    return np.einsum("...iI,...IJ,...kJ->...ik", F, S, F) / J[..., None, None]


@dataclass(frozen=True)
class PointState:
    """Everything at a set of points (axis p); tensors in Cartesian components."""

    X: np.ndarray  # (p, 3) undeformed position
    u: np.ndarray  # (p, 3) displacement
    F: np.ndarray  # (p, 3, 3)
    E: np.ndarray  # (p, 3, 3) Green-Lagrange strain
    S: np.ndarray  # (p, 3, 3) 2nd Piola-Kirchhoff
    sigma: np.ndarray  # (p, 3, 3) Cauchy
    M: np.ndarray  # (p, 3, 3) rows M_1, M_2, M_3 (undeformed material frame)
    m: np.ndarray  # (p, 3, 3) rows m_1, m_2, m_3 (deformed frame (2.101)-(2.104))
    layer: np.ndarray  # (p,) layer index

    @property
    def pk2_physical(self) -> np.ndarray:
        """M_k · S · M_l (2.106)."""
        return np.einsum("pki,pij,plj->pkl", self.M, self.S, self.M)

    @property
    def cauchy_physical(self) -> np.ndarray:
        """σ_m^kl = m_k · σ · m_l (2.107)."""
        return np.einsum("pki,pij,plj->pkl", self.m, self.sigma, self.m)

    def stress(self, measure: str = "cauchy", frame: str = "material") -> np.ndarray:
        """Stress tensors (p, 3, 3): Cauchy or PK2, in the material frame (physical components
        (2.106)/(2.107); in a 90° ply σ13 is τ_yz) or in global Cartesian axes x, y, z."""
        if frame == "global":
            return self.sigma if measure == "cauchy" else self.S
        return self.cauchy_physical if measure == "cauchy" else self.pk2_physical

    def principal(self, measure: str = "cauchy") -> np.ndarray:
        """Principal stresses, descending (p, 3)."""
        t = self.cauchy_physical if measure == "cauchy" else self.pk2_physical
        return np.linalg.eigvalsh(t)[:, ::-1]

    def traction(self, frame: str = "material") -> np.ndarray:
        """Surface traction σ·m_3 per point: components σ_m^{k3} (2.114) [σ13, σ23, σ33] in the
        material frame, or its global x, y, z components (``frame = "global"``)."""
        if frame == "global":
            return np.einsum("pij,pj->pi", self.sigma, self.m[:, 2])
        return self.cauchy_physical[:, :, 2]


def layer_at(model: Model, element: int, theta1: float, layer: int | None = None, tol: float = 1e-9) -> int:
    """The layer of ``element`` containing Θ_1³ (the lower one on an interface)."""
    stack = model.stacks[model.element_stack[element]]
    if layer is not None:
        if layer not in stack:
            raise ValueError(f"element {element} has no layer '{model.layers[layer].name}'")
        return layer
    conn = model.mesh.elements[element]
    for k in stack:
        lo = model.offset(k)[conn].min()
        hi = (model.offset(k) + model.layers[k].thickness)[conn].max()
        if lo - tol <= theta1 <= hi + tol:
            return k
    return stack[-1]


def evaluate_points(
    model: Model,
    dm: DofMap,
    u_full: np.ndarray,
    elements: np.ndarray,
    xi: np.ndarray,
    eta: np.ndarray,
    theta1: np.ndarray,
    layers: np.ndarray | None = None,
    local_theta: bool = False,
) -> PointState:
    """Evaluate the state at points ``(element, ξ, η, Θ)``.

    ``theta1`` is Θ_1³ from the reference face, or the layer coordinate Θ_L³ when
    ``local_theta`` (then ``layers`` is required).
    """
    elements = np.atleast_1d(np.asarray(elements, np.int64))
    p = elements.size
    xi, eta, theta1 = (np.broadcast_to(np.asarray(v, float), (p,)) for v in (xi, eta, theta1))
    if layers is None:
        layers = np.array([layer_at(model, e, t) for e, t in zip(elements, theta1)])
    layers = np.broadcast_to(np.asarray(layers, np.int64), (p,))
    out = {k: np.zeros((p, 3, 3)) for k in ("F", "E", "S", "sigma", "M", "m")}
    X = np.zeros((p, 3))
    u = np.zeros((p, 3))
    for k in np.unique(layers):
        sel = np.flatnonzero(layers == k)
        ly = model.layers[k]
        conn = model.mesh.elements[elements[sel]]
        sp = surface_points(model.mesh.nodes[conn], xi[sel, None], eta[sel, None], per_element=True)
        off = sp.interpolate(model.offset(k)[conn])[:, 0]
        thL = theta1[sel] if local_theta else theta1[sel] - off
        th1 = thL + off
        G, Ginv, _ = shell_basis(sp, th1[:, None, None])
        U = u_full[dm.element_dofs(model, k, elements[sel])].reshape(len(sel), -1, 3)
        phi = (sp.N[:, 0, :, None] * thL[:, None, None] ** np.arange(ly.directors + 1)).reshape(len(sel), -1)
        u[sel] = np.einsum("sa,sai->si", phi, U)
        X[sel] = sp.X0[:, 0] + th1[:, None] * sp.A3[:, 0]
        mitc = getattr(model, "element", "full") == "mitc"
        if model.nonlinear or not mitc:  # the displacement gradient (MITC9 linear: strains tied, F = I)
            g = basis_gradients(sp, Ginv, thL[:, None, None], ly.directors)[:, 0, 0]  # (s, a, 3)
            Hg = np.einsum("sai,saJ->siJ", U, g)
        F = np.eye(3) + Hg if model.nonlinear else np.broadcast_to(np.eye(3), (len(sel), 3, 3))
        if mitc:  # the element's own (tied) strain field
            from .element.mitc import tied_strain

            Ev = tied_strain(model.mesh.nodes[conn], model.offset(k)[conn], ly.thickness[conn], ly.directors, U,
                             xi[sel], eta[sel], thL, model.nonlinear, groups=elements[sel])
        else:
            Ev = green_lagrange(Hg, model.nonlinear)
        M, C = _ply_law(ly, sp, thL / sp.interpolate(ly.thickness[conn])[:, 0])
        if ly.law is None:
            S = voigt_to_matrix(np.einsum("svw,sw->sv", C, Ev))
        else:  # the law's stress with the committed state of the nearest integration point
            from .element.inelastic import point_stress

            S = voigt_to_matrix(point_stress(model, k, elements[sel], xi[sel], eta[sel],
                                             thL / sp.interpolate(ly.thickness[conn])[:, 0], Ev))
        sig = cauchy_stress(F, S)
        # deformed frame (2.101)-(2.104): m1 = F M1/|F M1|, m3 = n = g1 x g2/|.|
        gcov = np.einsum("siJ,sJa->sia", F, G[:, 0, 0])
        n = np.cross(gcov[..., 0], gcov[..., 1])
        n /= np.linalg.norm(n, axis=1, keepdims=True)
        m1 = np.einsum("siJ,sJ->si", F, M[:, 0])
        m1 /= np.linalg.norm(m1, axis=1, keepdims=True)
        m = np.stack([m1, np.cross(n, m1), n], axis=1)
        out["F"][sel], out["S"][sel], out["sigma"][sel], out["M"][sel], out["m"][sel] = F, S, sig, M, m
        out["E"][sel] = voigt_to_matrix(Ev * np.array([1, 1, 1, 0.5, 0.5, 0.5]))
    return PointState(X, u, out["F"], out["E"], out["S"], out["sigma"], out["M"], out["m"], layers.copy())


def _ply_law(ly, sp, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Material frame (p, 3, 3) and Cartesian stiffness (p, 6, 6) at layer fractions ``s`` (p,)
    of layer ``ly``: those of the ply there (the lower one on a ply boundary)."""
    table = ly.ply_table()
    ply = ply_of([f for _, _, f in table], s)
    M, C = np.empty((s.size, 3, 3)), np.empty((s.size, 6, 6))
    for j in np.unique(ply):
        mat, ang, _ = table[j]
        at = ply == j
        Mj = material_frame(sp, ang, ly.direction)[:, 0]
        M[at], C[at] = Mj[at], rotate_stiffness(mat.stiffness(), Mj[at])
    return M, C


def locate(model: Model, point, tol: float | None = None) -> tuple[int, float, float, float]:
    """Element and (ξ, η) of the reference-surface point nearest to ``point``, and the distance.

    Projects by Gauss-Newton iterations (clipped to the element) on the 12 elements with the
    nearest centres at once (vectorised) and keeps the closest."""
    point = np.asarray(point, float)
    mesh = model.mesh
    centres = mesh.nodes[mesh.elements].mean(1)
    order = np.argsort(np.linalg.norm(centres - point, axis=1), kind="stable")[:12]
    X = mesh.nodes[mesh.elements[order]]  # (c, 9, 3)
    x = np.zeros((order.size, 2))
    for _ in range(30):
        sp = surface_points(X, x[:, :1], x[:, 1:], per_element=True)
        r = sp.X0[:, 0] - point  # (c, 3)
        A = sp.A[:, 0]  # (c, 3, 2)
        G = np.einsum("cia,cib->cab", A, A)
        step = -np.linalg.solve(G, np.einsum("cia,ci->ca", A, r)[..., None])[..., 0]
        x = np.clip(x + step, -1.0, 1.0)
        if np.abs(step).max() < 1e-13:
            break
    sp = surface_points(X, x[:, :1], x[:, 1:], per_element=True)
    dist = np.linalg.norm(sp.X0[:, 0] - point, axis=1)
    # the first of the (nearly) closest, in order of the element centres' distance
    k = int(np.flatnonzero(dist <= dist.min() + 1e-12)[0])
    return int(order[k]), float(x[k, 0]), float(x[k, 1]), float(dist[k])
