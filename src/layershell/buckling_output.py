"""Files of ``layershell buckle``: buckling.json and buckling.csv (the load factors), one VTU per
mode (the reference surface with the mode's director fields, :func:`export.surface_mesh`),
buckling_modes.npz (the modes' reference-face displacements at the nodes, read by
``[imperfection]``) and buckling_modes.png (each mode's normal displacement over the mesh, on the
layer face that moves most: the reference face, or the bottom face of a layer above it where a
mode is local to that layer, as the sub-laminate over a delamination)."""
from __future__ import annotations

import csv
import json
from pathlib import Path

import numpy as np

from .buckling import BucklingResult

MODES_FILE = "buckling_modes.npz"
#: the figure shows the reference face unless another face moves more than 1 / FACE_SHARE times
#: as much (a mode local to a layer above it); near-equal faces: the reference face, as imperfections use
FACE_SHARE = 0.5


def normal_components(nodes: np.ndarray, elements: np.ndarray, displacement: np.ndarray) -> np.ndarray:
    """(k, n_nodes) displacement along the averaged nodal normal of the reference surface."""
    from .io.build import nodal_normals
    from .mesh import Mesh

    n = nodal_normals(Mesh(nodes, elements))
    return np.einsum("kni,ni->kn", displacement, n)


def write_buckling(out_dir: Path, result: BucklingResult, info: dict, figure: bool = True) -> list[str]:
    """Write the files into ``out_dir`` (created); returns their names."""
    from .export import _write_vtu, reference_displacement, surface_mesh

    out_dir.mkdir(parents=True, exist_ok=True)
    pb = result.problem
    model = pb.model
    names = []
    modes = []
    for k, (lam, phi) in enumerate(zip(result.load_factors, result.modes), start=1):
        name = f"buckling_mode_{k}.vtu"
        _write_vtu(out_dir / name, surface_mesh(model, pb.dm, phi))
        names.append(name)
        modes.append({"mode": k, "load_factor": float(lam), "file": name})
    ref = np.stack([reference_displacement(model, pb.dm, phi) for phi in result.modes])
    np.savez(out_dir / MODES_FILE, nodes=np.asarray(model.mesh.nodes, float),
             elements=np.asarray(model.mesh.elements, np.int64), displacement=ref,
             load_factors=np.asarray(result.load_factors, float))
    names.append(MODES_FILE)
    summary = {**info, "n_dofs": int(pb.op.n_red), "n_dofs_full": int(pb.dm.n_full),
               "load_factors": [float(v) for v in result.load_factors], "modes": modes,
               "analysis": "linear eigenvalue buckling of the layer stack, bonded except the initially debonded "
                           "zones (open, no contact): (K0 + lambda K1) phi = 0, K1 the stress stiffness of the "
                           "linear state at lambda = 1; the modes are scaled to a largest face translation of 1"}
    (out_dir / "buckling.json").write_text(json.dumps(summary, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    with open(out_dir / "buckling.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(["mode", "load_factor"])
        for m in modes:
            w.writerow([m["mode"], repr(m["load_factor"])])
    names += ["buckling.json", "buckling.csv"]
    if figure:
        faces = [moving_face(pb, phi) for phi in result.modes]
        names.append(_figure(out_dir, model.mesh, np.stack([f[1] for f in faces]), result.load_factors,
                             [f[0] for f in faces]))
    return names


def moving_face(pb, phi: np.ndarray) -> tuple[str, np.ndarray]:
    """The name and (n_nodes, 3) displacement of the layer bottom face (director 0, zero where
    the layer is absent) with the largest normal displacement in mode ``phi``; 'reference face'
    where that is the reference face's."""
    from .export import reference_displacement

    model, dm = pb.model, pb.dm
    X, E = np.asarray(model.mesh.nodes, float), np.asarray(model.mesh.elements)
    faces = [reference_displacement(model, dm, phi)]
    for k in range(len(model.layers)):
        faces.append(np.where(dm.present[k][:, None], phi[dm.layer_dofs[k][:, 0, :]], 0.0))
    m = np.abs(normal_components(X, E, np.stack(faces))).max(axis=1)
    best = 0 if m[0] >= FACE_SHARE * m.max() else int(np.argmax(m))
    name = "reference face" if best == 0 else f"bottom face of layer '{model.layers[best - 1].name}'"
    return name, faces[best]


def _figure(out_dir: Path, mesh, ref: np.ndarray, load_factors: np.ndarray, where: list[str]) -> str:
    """Each mode's normal displacement over the mesh (``ref``: on the face named in ``where``),
    drawn in the plane of its two widest axes."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import matplotlib.tri as mtri

    X = np.asarray(mesh.nodes, float)
    axes = np.argsort(-np.ptp(X, axis=0))[:2]
    w = normal_components(X, np.asarray(mesh.elements), ref)
    # each 9-node quadrilateral as 8 triangles around its centre node
    E = np.asarray(mesh.elements)
    ring = [0, 4, 1, 5, 2, 6, 3, 7]
    tris = np.concatenate([np.stack([E[:, ring[i]], E[:, ring[(i + 1) % 8]], E[:, 8]], 1) for i in range(8)])
    tri = mtri.Triangulation(X[:, axes[0]], X[:, axes[1]], tris)
    k = len(load_factors)
    fig, axs = plt.subplots(k, 1, figsize=(6, 2.6 * k), squeeze=False)
    for i, ax in enumerate(axs[:, 0]):
        top = float(np.abs(w[i]).max()) or 1.0
        c = ax.tripcolor(tri, w[i], shading="gouraud", cmap="RdBu_r", vmin=-top, vmax=top)
        ax.set_aspect("equal")
        ax.set_title(f"mode {i + 1}: load factor {load_factors[i]:.5g} ({where[i]})", fontsize=9)
        ax.set_xlabel("xyz"[axes[0]])
        ax.set_ylabel("xyz"[axes[1]])
        fig.colorbar(c, ax=ax, label="normal displacement")
    fig.tight_layout()
    name = "buckling_modes.png"
    fig.savefig(out_dir / name, dpi=110)
    plt.close(fig)
    return name
