"""9-node quadrilateral surface meshes and generators.

A mesh describes the **reference surface** (a face of the shell). Element node order is the
VTK ``quad9`` order (see :mod:`layershell.element.shape`); the normal A_3 = A_1 × A_2 must
point from the reference face into the material (MODEL.md §2, orientation rule) — the
generators take care of it through their ``normal`` argument.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .element.geometry import surface_points
from .element.shape import NODE_XI


class MeshError(ValueError):
    """Invalid mesh data."""


@dataclass
class Mesh:
    nodes: np.ndarray  # (n_nodes, 3)
    elements: np.ndarray  # (n_elements, 9) node indices
    node_sets: dict[str, np.ndarray] = field(default_factory=dict)
    element_sets: dict[str, np.ndarray] = field(default_factory=dict)
    notes: list[str] = field(default_factory=list)

    @property
    def n_nodes(self) -> int:
        return len(self.nodes)

    @property
    def n_elements(self) -> int:
        return len(self.elements)

    def size(self) -> float:
        """Diagonal of the bounding box (for tolerances)."""
        return float(np.linalg.norm(np.ptp(self.nodes, axis=0))) or 1.0

    def normals_at_centres(self) -> np.ndarray:
        sp = surface_points(self.nodes[self.elements], np.zeros(1), np.zeros(1))
        return sp.A3[:, 0]

    def flip(self, mask: np.ndarray) -> None:
        """Reverse the orientation (normal) of the elements in ``mask`` (mirror xi)."""
        perm = np.array([1, 0, 3, 2, 4, 7, 6, 5, 8])
        self.elements[mask] = self.elements[mask][:, perm]

    def check(self) -> None:
        """Reject inverted or degenerate elements, naming them and their Jacobians."""
        e = self.elements
        if e.ndim != 2 or e.shape[1] != 9:
            raise MeshError(f"elements must have 9 nodes each, got shape {e.shape}")
        if e.min() < 0 or e.max() >= self.n_nodes:
            raise MeshError("element connectivity refers to nodes that do not exist")
        from .element.quadrature import gauss_2d

        pts, _ = gauss_2d(3)
        sp = surface_points(self.nodes[e], pts[:, 0], pts[:, 1])
        ref = self.normals_at_centres()
        cosang = np.einsum("eqi,ei->eq", sp.A3, ref)
        jac = sp.sqrtA
        bad = np.where((jac.min(1) <= 1e-12 * jac.max()) | (cosang.min(1) < 0.5))[0]
        if bad.size:
            raise MeshError(
                f"{bad.size} element(s) are inverted or badly distorted: ids {bad[:10].tolist()}"
                f"{' ...' if bad.size > 10 else ''}; area Jacobians {np.round(jac[bad[:10]].min(1), 6).tolist()}"
                "; fix the node order or the element shape"
            )


def _structured(nx: int, ny: int, fn, edge_names=("s0", "s1", "t0", "t1")) -> Mesh:
    """Structured (2nx+1) x (2ny+1) grid of quad9 elements; ``fn(s, t)`` maps [0,1]^2 to 3D.
    The four boundary edges become node sets named ``edge_names`` (s = 0, s = 1, t = 0, t = 1)."""
    s = np.linspace(0.0, 1.0, 2 * nx + 1)
    t = np.linspace(0.0, 1.0, 2 * ny + 1)
    S, T = np.meshgrid(s, t, indexing="xy")
    nodes = fn(S.ravel(), T.ravel())
    idx = np.arange(S.size).reshape(T.shape[0], S.shape[1])  # [row j (t), col i (s)]
    elems = []
    for j in range(ny):
        for i in range(nx):
            i0, j0 = 2 * i, 2 * j
            loc = [(i0 + int(x + 1), j0 + int(y + 1)) for x, y in NODE_XI]
            elems.append([idx[jj, ii] for ii, jj in loc])
    sets = {edge_names[0]: idx[:, 0], edge_names[1]: idx[:, -1], edge_names[2]: idx[0, :], edge_names[3]: idx[-1, :]}
    return Mesh(np.asarray(nodes, float), np.asarray(elems, dtype=np.int64), {k: np.array(v) for k, v in sets.items()})


def _orient(mesh: Mesh, normal_fn) -> Mesh:
    """Flip elements whose normal disagrees with ``normal_fn(centre)``."""
    c = mesh.nodes[mesh.elements[:, 8]]
    want = normal_fn(c)
    mesh.flip(np.einsum("ei,ei->e", mesh.normals_at_centres(), want) < 0)
    return mesh


def rectangle(lx: float, ly: float, nx: int, ny: int, origin=(0.0, 0.0, 0.0), normal: str = "+z") -> Mesh:
    """Flat rectangular plate in the x-y plane; ``normal`` '+z' (reference face at the bottom)
    or '-z' (reference face on top, material below)."""
    o = np.asarray(origin, float)
    mesh = _structured(nx, ny, lambda s, t: np.stack([o[0] + lx * s, o[1] + ly * t, o[2] + 0 * s], -1),
                       ("xmin", "xmax", "ymin", "ymax"))
    sign = -1.0 if normal.strip().startswith("-") else 1.0
    return _orient(mesh, lambda c: np.tile([0.0, 0.0, sign], (len(c), 1)))


def cylinder(radius: float, angle_start: float, angle_end: float, width: float, n_arc: int, n_width: int,
             normal: str = "inward", axis: str = "z") -> Mesh:
    """Cylindrical panel / ring sector (angles in degrees) of reference-face radius ``radius``.

    ``axis='z'``: the arc lies in the x-y plane (angle from +x towards +y), width along z.
    ``axis='y'``: the arc lies in the x-z plane (angle from +x towards +z), width along y.
    ``normal='inward'`` puts the reference face on the outer face (A_3 towards the axis),
    ``'outward'`` on the inner face.
    """
    a0, a1 = np.deg2rad(angle_start), np.deg2rad(angle_end)

    def fn(s, t):
        ph = a0 + (a1 - a0) * s
        w = width * t
        if axis == "z":
            return np.stack([radius * np.cos(ph), radius * np.sin(ph), w], -1)
        return np.stack([radius * np.cos(ph), w, radius * np.sin(ph)], -1)

    mesh = _structured(n_arc, n_width, fn, ("start", "end", "bottom", "top"))
    sign = -1.0 if normal == "inward" else 1.0

    def want(c):
        r = c.copy()
        r[:, 2 if axis == "z" else 1] = 0.0
        return sign * r / np.linalg.norm(r, axis=1, keepdims=True)

    return _orient(mesh, want)


def revolution(meridian_r, meridian_z, n_meridian: int, n_circ: int, angle: float = 360.0,
               normal: str = "inward") -> Mesh:
    """Shell of revolution about the z axis from a meridian polyline (r_k, z_k).

    The meridian is resampled by arc length to ``2 n_meridian + 1`` points. ``normal``
    'inward' or 'outward' relative to the axis (for a dome with the reference surface on the
    inner face use 'outward'). Node sets: 'first'/'last' (the circles at the first and last
    meridian point), 'start'/'end' (the meridians at angle 0 and ``angle``; merged when closed).
    """
    r = np.asarray(meridian_r, float)
    z = np.asarray(meridian_z, float)
    if r.shape != z.shape or r.size < 2:
        raise MeshError("meridian: r and z need the same length >= 2")
    sl = np.concatenate([[0.0], np.cumsum(np.hypot(np.diff(r), np.diff(z)))])
    closed = abs(angle - 360.0) < 1e-9

    def fn(s, t):
        rr = np.interp(t * sl[-1], sl, r)
        zz = np.interp(t * sl[-1], sl, z)
        ph = np.deg2rad(angle) * s
        return np.stack([rr * np.cos(ph), rr * np.sin(ph), zz], -1)

    mesh = _structured(n_circ, n_meridian, fn, ("start", "end", "first", "last"))
    if closed:
        mesh = merge_coincident(mesh)
    sign = -1.0 if normal == "inward" else 1.0
    return _orient_revolution(mesh, sign)


def _orient_revolution(mesh: Mesh, sign: float) -> Mesh:
    n = mesh.normals_at_centres()
    c = mesh.nodes[mesh.elements[:, 8]]
    rc = np.hypot(c[:, 0], c[:, 1])
    er = np.stack([c[:, 0], c[:, 1], 0 * rc], -1) / np.maximum(rc, 1e-300)[:, None]
    # radial part decides; for a horizontal (flat) ring use the vertical part
    rad = np.einsum("ei,ei->e", n, er)
    key = np.where(np.abs(rad) > 1e-6, rad, n[:, 2])
    mesh.flip(sign * key < 0)
    return mesh


def merge_coincident(mesh: Mesh, tol: float | None = None) -> Mesh:
    """Merge nodes closer than ``tol`` (default 1e-9 × mesh size)."""
    tol = tol if tol is not None else 1e-9 * mesh.size()
    key = np.round(mesh.nodes / tol).astype(np.int64)
    _, first, inv = np.unique(key, axis=0, return_index=True, return_inverse=True)
    order = np.argsort(first)
    remap = np.empty_like(order)
    remap[order] = np.arange(order.size)
    nodes = mesh.nodes[first[order]]
    elements = remap[inv.ravel()][mesh.elements]
    sets = {k: np.unique(remap[inv.ravel()][v]) for k, v in mesh.node_sets.items()}
    return Mesh(nodes, elements, sets, dict(mesh.element_sets), list(mesh.notes))
