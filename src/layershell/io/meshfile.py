"""Read 9-node quadrilateral meshes with meshio (Gmsh .msh, VTU, ...).

Gmsh physical groups (``cell_sets``) become named sets: the nodes of every group are a node set,
and the quadrilaterals of a surface group an element set. 8-node and 4-node quadrilaterals are
converted to 9-node elements (centre and mid-side nodes added on straight lines / the serendipity
interpolation), with a note in ``Mesh.notes``. Triangles (or other polygons) next to the
quadrilaterals are an error, never dropped.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..mesh import Mesh, MeshError, merge_coincident

QUAD_TYPES = ("quad9", "quad8", "quad")
_NODES = {"quad9": 9, "quad8": 8, "quad": 4}


def _to_quad9(kind: str, cells: np.ndarray, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Convert quad (4) / quad8 cells to quad9 by adding nodes; returns (points, cells9)."""
    if kind == "quad9":
        return points, cells
    n = len(cells)
    pts = [points]
    count = len(points)
    c9 = np.zeros((n, 9), np.int64)
    c9[:, :4] = cells[:, :4]
    if kind == "quad":
        X = points[cells]  # (n, 4, 3)
        mids = 0.5 * (X + np.roll(X, -1, axis=1))  # edges 0-1, 1-2, 2-3, 3-0
        pts.append(mids.reshape(-1, 3))
        c9[:, 4:8] = count + np.arange(4 * n).reshape(n, 4)
        count += 4 * n
        centre = X.mean(1)
    else:
        c9[:, 4:8] = cells[:, 4:8]
        X = points[cells]
        # serendipity centre: N_9 position of the 8-node map at (0, 0)
        centre = -0.25 * X[:, :4].sum(1) + 0.5 * X[:, 4:8].sum(1)
    pts.append(centre)
    c9[:, 8] = count + np.arange(n)
    return np.concatenate(pts), c9


def read_mesh(path: str | Path, scale: float = 1.0) -> Mesh:
    import meshio

    path = Path(path)
    if not path.is_file():
        raise MeshError(f"mesh file '{path}' does not exist")
    try:
        m = meshio.read(path)
    except Exception as exc:  # meshio raises many types
        raise MeshError(f"mesh file '{path}' could not be read by meshio: {exc}") from None
    blocks = [(i, cb) for i, cb in enumerate(m.cells) if cb.type in QUAD_TYPES]
    if not blocks:
        raise MeshError(f"mesh file '{path}' has no quadrilateral cells (found: "
                        f"{sorted({cb.type for cb in m.cells})}); layershell needs 9-node quadrilaterals "
                        "(Gmsh: Mesh.ElementOrder = 2, Mesh.RecombineAll = 1, Mesh.SecondOrderIncomplete = 0)")
    others = {}  # surface cells that are not quadrilaterals: a mesh must not lose them silently
    for cb in m.cells:
        if cb.type.startswith(("triangle", "polygon")):
            others[cb.type] = others.get(cb.type, 0) + len(cb.data)
    if others:
        found = ", ".join(f"{n} '{t}'" for t, n in others.items())
        quads = sum(len(cb.data) for _, cb in blocks)
        raise MeshError(f"mesh file '{path}' has {found} cells besides its {quads} quadrilaterals; layershell needs "
                        "a mesh of quadrilaterals only (9-node, or 4/8-node converted) and does not drop the other "
                        "cells silently: recombine the whole surface into quadrilaterals (Gmsh: Mesh.RecombineAll "
                        "= 1, Mesh.ElementOrder = 2, Mesh.SecondOrderIncomplete = 0, and if triangles remain "
                        "Mesh.SubdivisionAlgorithm = 1)")
    points = np.asarray(m.points, float) * scale
    if points.shape[1] == 2:
        points = np.column_stack([points, np.zeros(len(points))])
    notes = []
    elements, owner = [], []
    for i, cb in blocks:
        if cb.type != "quad9":
            how = ("mid-side and centre nodes on straight lines between the corners" if cb.type == "quad" else
                   "centre nodes from the 8-node (serendipity) map")
            notes.append(f"mesh file '{path.name}': {len(cb.data)} {_NODES[cb.type]}-node quadrilaterals "
                         f"('{cb.type}') converted to 9-node elements ({how}); layershell needs 9-node "
                         "quadrilaterals, and curved surfaces are represented better by a quad9 mesh "
                         "(Gmsh: Mesh.ElementOrder = 2, Mesh.SecondOrderIncomplete = 0)")
        points, c9 = _to_quad9(cb.type, np.asarray(cb.data, np.int64), points)
        elements.append(c9)
        owner.append(np.full(len(c9), i))
    elements = np.concatenate(elements)
    owner = np.concatenate(owner)
    node_sets: dict[str, np.ndarray] = {}
    element_sets: dict[str, np.ndarray] = {}
    offsets = {}
    start = 0
    for i, cb in blocks:
        offsets[i] = start
        start += len(cb.data)
    # meshio's own bookkeeping (e.g. 'gmsh:bounding_entities' of Gmsh 4.1) is not a physical group
    groups = {k: v for k, v in (m.cell_sets or {}).items() if not k.startswith("gmsh:")}
    phys = (m.cell_data or {}).get("gmsh:physical")
    if phys is not None and m.field_data:  # Gmsh 2.2: physical tags per cell + names in field_data
        for name, (tag, _dim) in ((k, tuple(v[:2])) for k, v in m.field_data.items()):
            if name not in groups:
                groups[name] = [np.flatnonzero(np.asarray(p) == tag) for p in phys]
    for name, per_block in groups.items():
        nodes = []
        els = []
        for i, idx in enumerate(per_block):
            if idx is None or len(idx) == 0:
                continue
            idx = np.asarray(idx, np.int64)
            if i in offsets:
                els.append(offsets[i] + idx)
                nodes.append(elements[offsets[i] + idx].ravel())
            else:
                nodes.append(np.asarray(m.cells[i].data)[idx].ravel())
        if nodes:
            node_sets[name] = np.unique(np.concatenate(nodes))
        if els:
            element_sets[name] = np.unique(np.concatenate(els))
    mesh = Mesh(points, elements, node_sets, element_sets)
    if len(blocks) > 1 or any(cb.type != "quad9" for _, cb in blocks):
        mesh = merge_coincident(mesh)
    used = np.unique(mesh.elements)
    if used.size < len(mesh.nodes):  # drop nodes of other cell types (vertices of lines only, ...)
        remap = -np.ones(len(mesh.nodes), np.int64)
        remap[used] = np.arange(used.size)
        mesh = Mesh(mesh.nodes[used], remap[mesh.elements],
                    {k: remap[v][remap[v] >= 0] for k, v in mesh.node_sets.items()}, mesh.element_sets)
    mesh.notes = notes
    return mesh
