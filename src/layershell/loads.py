"""External loads as consistent director forces, MODEL.md §6 / thesis (2.158)-(2.202), (2.256).

Every load is reduced to director forces per layer, F_(a,l,L) = ∫ (Θ_L³)^l F_a dΘ_L³ (2.168),
(3.37), and integrated over the element with the shape functions (2.256)-(2.258). As in the
thesis the shifter μ is neglected in the through-thickness integrals (A5), except for volume
(gravity) loads, which are integrated over the true volume with μ.
"""
from __future__ import annotations

import numpy as np

from .dofs import DofMap
from .element.geometry import surface_points
from .element.quadrature import gauss_1d, gauss_2d
from .element.shape import EDGES, line3
from .model import EdgeLoad, Model, NodalLoad, SurfaceLoad


class LoadError(ValueError):
    """A load that cannot be applied to the model."""


# ---------------------------------------------------------------- director-force vectors
def director_vector_power(H, k: int, d: int, from_opposite: bool = False) -> np.ndarray:
    """Director-force vector / P* of the load p*(Θ/H)^k (2.179) or p*((H-Θ)/H)^k (2.174),
    each normalised by its resultant P* = p* H / (k+1). Returns ``(d+1,)``."""
    H = float(H)
    t, w = gauss_1d(k + d + 2)
    th = 0.5 * H * (t + 1.0)
    shape = ((H - th) / H) ** k if from_opposite else (th / H) ** k
    res = H / (k + 1)
    return np.array([np.sum(w * 0.5 * H * th**l * shape) / res for l in range(d + 1)])


def director_vector_face(H: np.ndarray, d: int, face: str) -> np.ndarray:
    """(…, d+1) factors for a face load: reference/bottom face [1,0,..] (2.175), opposite
    face [1,H,H²,..] (2.180)."""
    H = np.asarray(H, float)
    l = np.arange(d + 1)
    if face == "bottom":
        return np.broadcast_to((l == 0).astype(float), H.shape + (d + 1,)).copy()
    return H[..., None] ** l


def director_vector_volume(H: np.ndarray, d: int) -> np.ndarray:
    """(…, d+1) factors ∫_0^H Θ^l dΘ = H^(l+1)/(l+1) of a constant volume load (2.183)."""
    H = np.asarray(H, float)[..., None]
    l = np.arange(d + 1)
    return H ** (l + 1) / (l + 1)


def director_vector_volume_shifted(off: np.ndarray, H: np.ndarray, trB: np.ndarray, detB: np.ndarray,
                                   d: int) -> np.ndarray:
    """(…, d+1) factors ∫_0^H (Θ_L)^l μ(off + Θ_L) dΘ_L of a constant volume load with the
    shifter μ(Θ³) = det(δ − Θ³ B) = 1 − Θ³ tr B + (Θ³)² det B ((2.31), (2.183) without the
    thesis's μ ≈ 1): the load per reference area is that of the true volume (exact, Gauss)."""
    t, w = gauss_1d(d // 2 + 3)
    H = np.asarray(H, float)[..., None]
    th = 0.5 * H * (t + 1.0)  # (…, g)
    z = np.asarray(off, float)[..., None] + th
    mu = 1.0 - z * np.asarray(trB)[..., None] + z**2 * np.asarray(detB)[..., None]
    return np.einsum("...g,...gl->...l", 0.5 * H * w * mu, th[..., None] ** np.arange(d + 1))


def director_forces_distribution(fn, offset, H, d: int, n_gauss: int = 12, **xyz) -> np.ndarray:
    """q_l = ∫_0^H (Θ_L)^l t(offset + Θ_L) dΘ_L for a through-thickness traction ``fn(theta3,
    **xyz)`` (Θ_1³ measured from the reference face), (2.167)/(3.97). Shapes broadcast over
    ``offset``/``H`` (…); returns (…, d+1)."""
    t, w = gauss_1d(n_gauss)
    H = np.asarray(H, float)[..., None]
    off = np.asarray(offset, float)[..., None]
    th = 0.5 * H * (t + 1.0)  # (…, g)
    xyz_b = {k: np.asarray(v, float)[..., None] for k, v in xyz.items()}
    val = np.broadcast_to(fn(theta3=off + th, **xyz_b), th.shape)
    l = np.arange(d + 1)
    return np.einsum("...g,...gl->...l", 0.5 * H * w * val, th[..., None] ** l)


# ---------------------------------------------------------------- assembly into the full space
def _scatter(F: np.ndarray, dofs: np.ndarray, values: np.ndarray) -> None:
    np.add.at(F, dofs.ravel(), values.ravel())


def _face_layer(model: Model, stack: tuple[int, ...], face: str) -> tuple[int, str]:
    if face == "reference":
        return stack[0], "bottom"
    if face == "top":
        return stack[-1], "top"
    if face.startswith("layer:"):
        k = int(face.split(":", 1)[1])
        if k not in stack:
            raise LoadError(f"surface load on the bottom face of layer '{model.layers[k].name}', "
                            "which some of the loaded elements do not have")
        return k, "bottom"
    raise LoadError(f"unknown face '{face}'; use 'reference', 'top', 'volume' or 'layer:<name>'")


def surface_load_vector(model: Model, dm: DofMap, load: SurfaceLoad, F: np.ndarray) -> None:
    """Add the consistent nodal director forces of a surface or volume load to ``F``."""
    pts, w = gauss_2d(3)
    mesh = model.mesh
    for si, stack in enumerate(model.stacks):
        el = load.elements[model.element_stack[load.elements] == si]
        if el.size == 0:
            continue
        conn = mesh.elements[el]
        sp = surface_points(mesh.nodes[conn], pts[:, 0], pts[:, 1])
        X = sp.X0
        mag = np.broadcast_to(load.magnitude(x=X[..., 0], y=X[..., 1], z=X[..., 2]), X.shape[:2])
        vec = (sp.A3 if load.direction is None else np.broadcast_to(load.direction, X.shape)) * mag[..., None]
        dA = sp.sqrtA * w  # (e, q)
        if load.face == "volume":
            targets = [k for k in stack if load.layer is None or k == load.layer]
            trB = np.trace(sp.Bmix, axis1=-2, axis2=-1)
            detB = np.linalg.det(sp.Bmix)
            facs = [director_vector_volume_shifted(sp.interpolate(model.offset(k)[conn]),
                                                   sp.interpolate(model.layers[k].thickness[conn]), trB, detB,
                                                   model.layers[k].directors) for k in targets]
        else:
            k, kind = _face_layer(model, stack, load.face)
            targets = [k]
            facs = [director_vector_face(sp.interpolate(model.layers[k].thickness[conn]), model.layers[k].directors, kind)]
        for k, fac in zip(targets, facs):
            # (e, n, l, i) = Σ_q N_qn fac_eql vec_eqi dA_eq
            val = np.einsum("qn,eql,eqi,eq->enli", sp.N, fac, vec, dA)
            _scatter(F, dm.layer_dofs[k][conn], val)


def edge_lookup(model: Model) -> dict[tuple[int, int, int], tuple[int, int]]:
    """(start, mid, end) node triple (either direction) -> (element, local edge)."""
    out = {}
    for e, conn in enumerate(model.mesh.elements):
        for k, tri in enumerate(EDGES):
            a, m, b = conn[tri]
            out[(a, m, b)] = (e, k)
            out[(b, m, a)] = (e, k)
    return out


def edge_load_vector(model: Model, dm: DofMap, load: EdgeLoad, F: np.ndarray, lookup=None) -> None:
    """Add the director forces of a through-thickness edge traction (MODEL.md §6, (3.97))."""
    lookup = lookup if lookup is not None else edge_lookup(model)
    s, w = gauss_1d(4)
    N, dN = line3(s)  # (g, 3)
    mesh = model.mesh
    direction = np.asarray(load.direction, float)
    for tri in np.asarray(load.edges):
        key = tuple(int(v) for v in tri)
        if key not in lookup:
            raise LoadError(f"edge load: nodes {key} are not an element edge")
        e, _ = lookup[key]
        stack = model.stacks[model.element_stack[e]]
        X = mesh.nodes[tri]  # (3, 3)
        xs = N @ X
        ds = np.linalg.norm(dN @ X, axis=1) * w  # (g,)
        at = None
        if load.at_height is not None:  # the layer containing the height (from the top: the upper at an interface)
            tol = 1e-9 * max(float(model.total_thickness()[tri].max()), 1e-300)
            at = next((k for k in stack[::-1] if np.all(model.offset(k)[tri] <= load.at_height + tol)), None)
            if at is None or np.any(model.offset(at)[tri] + model.layers[at].thickness[tri] < load.at_height - tol):
                raise LoadError(f"edge load at Θ³ = {load.at_height:g}: outside the shell at edge {key}")
        for k in stack:
            ly = model.layers[k]
            off = N @ model.offset(k)[tri]
            H = N @ ly.thickness[tri]
            if at is not None:  # line force at a height: director forces (Θ_L³)^l q
                if k != at:
                    continue
                mag = np.broadcast_to(load.distribution(theta3=np.full(H.shape, load.at_height), x=xs[:, 0],
                                                        y=xs[:, 1], z=xs[:, 2]), H.shape)
                q = (load.at_height - off)[:, None] ** np.arange(ly.directors + 1) * mag[:, None]
            elif load.at_face is not None:  # line force on a face: (2.175) / (2.180)
                if k != (stack[-1] if load.at_face == "top" else stack[0]):
                    continue
                mag = np.broadcast_to(load.distribution(theta3=off, x=xs[:, 0], y=xs[:, 1], z=xs[:, 2]), H.shape)
                q = director_vector_face(H, ly.directors, "top" if load.at_face == "top" else "bottom") * mag[:, None]
            else:
                q = director_forces_distribution(load.distribution, off, H, ly.directors,
                                                 x=xs[:, 0], y=xs[:, 1], z=xs[:, 2])  # (g, l)
            val = np.einsum("gn,gl,g,i->nli", N, q, ds, direction)
            _scatter(F, dm.layer_dofs[k][tri], val)


def nodal_load_vector(model: Model, dm: DofMap, load: NodalLoad, F: np.ndarray) -> None:
    ly = model.layers[load.layer]
    if load.director > ly.directors:
        raise LoadError(f"nodal load on director {load.director} of layer '{ly.name}', which has only "
                        f"directors 0..{ly.directors}")
    D = dm.layer_dofs[load.layer][load.nodes, load.director]
    if np.any(D < 0):
        raise LoadError(f"nodal load: layer '{ly.name}' does not exist at some of the selected nodes")
    _scatter(F, D, np.broadcast_to(load.values, D.shape))


def external_forces(model: Model, dm: DofMap) -> tuple[np.ndarray, np.ndarray]:
    """Full-space load vectors (scaled by the load factor, constant)."""
    Fs = np.zeros(dm.n_full)
    Fc = np.zeros(dm.n_full)
    lookup = edge_lookup(model) if model.edge_loads else None
    for ld in model.surface_loads:
        surface_load_vector(model, dm, ld, Fs if ld.scaled else Fc)
    for ld in model.edge_loads:
        edge_load_vector(model, dm, ld, Fs if ld.scaled else Fc, lookup)
    for ld in model.nodal_loads:
        nodal_load_vector(model, dm, ld, Fs if ld.scaled else Fc)
    return Fs, Fc
