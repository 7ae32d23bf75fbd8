"""ParaView output (VTK XML unstructured grids through meshio) and ``.pvd`` time collections.

Per load step two files are written, both atomically (temporary name in the same folder,
then :func:`os.replace`):

- ``surface_{step:04d}.vtu``: the reference surface as ``quad9`` cells (our node order is the
  VTK biquadratic quad order) with the nodal director displacements of every layer;
- ``solid_{step:04d}.vtu``: the shell extruded through its thickness, each layer of each
  element sampled on a 3×3×3 lattice (in-plane at the 9 nodes, through the layer at
  Θ_L³ = 0, H_L/2, H_L) split into 8 linear hexahedra, with displacements and the physical
  stress components of MODEL.md §3 (points duplicated per element and layer because the
  stresses are discontinuous).

Points are undeformed positions; ParaView's *Warp By Vector* uses the ``displacement`` array.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .dofs import DofMap
from .io.output import atomic_write
from .element.shape import NODE_XI
from .model import Model

#: physical stress components written, as (row, column) of the 3×3 tensor: 11, 22, 33, 23, 13, 12
STRESS_COMPONENTS = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))

# lattice (i, j) in-plane index (xi = i-1, eta = j-1) -> element node (VTK quad9 order)
_NODE_OF_IJ = np.empty((3, 3), dtype=np.int64)
for _a, (_x, _y) in enumerate(NODE_XI):
    _NODE_OF_IJ[int(_x) + 1, int(_y) + 1] = _a


def _lattice_hexes() -> np.ndarray:
    """(8, 8) local lattice indices (i + 3 j + 9 m) of the hexahedra of one 3×3×3 lattice, in the
    VTK hexahedron order: bottom quad counter-clockwise about +Θ³, then the top quad."""
    def idx(i, j, m):
        return i + 3 * j + 9 * m

    hexes = []
    for m in range(2):
        for j in range(2):
            for i in range(2):
                bot = [idx(i, j, m), idx(i + 1, j, m), idx(i + 1, j + 1, m), idx(i, j + 1, m)]
                top = [idx(i, j, m + 1), idx(i + 1, j, m + 1), idx(i + 1, j + 1, m + 1), idx(i, j + 1, m + 1)]
                hexes.append(bot + top)
    return np.asarray(hexes, dtype=np.int64)


_HEXES = _lattice_hexes()
_LAT_I = np.tile(np.arange(3), 9)
_LAT_J = np.tile(np.repeat(np.arange(3), 3), 3)
_LAT_M = np.repeat(np.arange(3), 9)
_LAT_NODE = _NODE_OF_IJ[_LAT_I, _LAT_J]  # (27,) element node of each lattice point


# ----------------------------------------------------------------------------- helpers


def reference_layer(model: Model, dm: DofMap) -> np.ndarray:
    """(n_nodes,) index of the lowest layer present at each node (smallest offset Θ_1³ of the
    bottom face; ties to the lower layer index), -1 at nodes without any layer."""
    nl = len(model.layers)
    offs = np.full((nl, model.mesh.n_nodes), np.inf)
    for k in range(nl):
        offs[k] = np.where(dm.present[k], model.offset(k), np.inf)
    ref = np.argmin(offs, axis=0)
    ref[~dm.present.any(axis=0)] = -1
    return ref


def director_field(dm: DofMap, u_full: np.ndarray, layer: int, director: int) -> np.ndarray:
    """(n_nodes, 3) director ``director`` of ``layer`` at every node, zeros where absent."""
    d = dm.layer_dofs[layer][:, director, :]
    out = np.zeros(d.shape, dtype=float)
    ok = d >= 0
    out[ok] = u_full[d[ok]]
    return out


def reference_displacement(model: Model, dm: DofMap, u_full: np.ndarray) -> np.ndarray:
    """(n_nodes, 3) reference-face displacement: director 0 of the lowest layer at each node."""
    ref = reference_layer(model, dm)
    out = np.zeros((model.mesh.n_nodes, 3))
    for k in np.unique(ref[ref >= 0]):
        sel = ref == k
        out[sel] = u_full[dm.layer_dofs[k][sel, 0, :]]
    return out


def stress_components(t: np.ndarray) -> np.ndarray:
    """(p, 3, 3) tensors -> (p, 6) components 11, 22, 33, 23, 13, 12."""
    return np.stack([t[:, r, c] for r, c in STRESS_COMPONENTS], axis=1)


def von_mises(t: np.ndarray) -> np.ndarray:
    """von Mises equivalent stress of (p, 3, 3) symmetric tensors."""
    s11, s22, s33 = t[:, 0, 0], t[:, 1, 1], t[:, 2, 2]
    s23, s13, s12 = t[:, 1, 2], t[:, 0, 2], t[:, 0, 1]
    return np.sqrt(
        0.5 * ((s11 - s22) ** 2 + (s22 - s33) ** 2 + (s33 - s11) ** 2) + 3.0 * (s12**2 + s23**2 + s13**2)
    )


def _write_vtu(path: Path, mesh) -> None:
    import meshio

    atomic_write(path, lambda tmp: meshio.write(str(tmp), mesh, file_format="vtu"))


# ----------------------------------------------------------------------------- meshes


def material_cell_fields(model: Model) -> dict[str, np.ndarray]:
    """Per element of the surface mesh, in the committed state, for each concrete layer: the
    largest crack width over its points (``crack_width_<layer>``), the normal of that widest crack
    (``crack_normal_<layer>``, a 3D vector, zero where uncracked), the most compressive minimum
    principal stress of the concrete (``min_principal_<layer>``); for each reinforcement sheet the
    largest bar/yarn stress (``rebar_stress_<layer>_<sheet>``) and its state over the element's
    points (``rebar_state_<layer>_<sheet>``: 0 elastic, 1 yielded, 2 ruptured). NaN where the
    layer is absent."""
    from . import material_output as mo
    from .element.inelastic import layer_point_values

    out: dict[str, np.ndarray] = {}
    n = model.mesh.n_elements
    for k, ly in enumerate(model.layers):
        if ly.law is not None and hasattr(ly.law, "crack"):
            w, nv, el = mo.crack_points(model, k)
            out[f"crack_width_{ly.name}"] = mo.per_element(n, w, el)
            out[f"crack_normal_{ly.name}"] = mo.widest_normal(n, w, nv, el)
            out[f"min_principal_{ly.name}"] = mo.per_element(n, *mo.principal_min(model, k), how="min")
        for r in ly.reinforcement:
            tag = f"{ly.name}_{r.name}".replace(" ", "_")
            out[f"rebar_stress_{tag}"] = mo.per_element(n, *layer_point_values(model, k, "rebar_stress", r.name))
            out[f"rebar_state_{tag}"] = mo.per_element(n, *mo.sheet_states(model, k, r.name))
    return out


def surface_mesh(model: Model, dm: DofMap, u_full: np.ndarray):
    """meshio.Mesh of the reference surface with nodal director displacements."""
    import meshio

    mesh = model.mesh
    point_data = {"displacement": reference_displacement(model, dm, u_full)}
    for k, ly in enumerate(model.layers):
        for d in range(ly.directors + 1):
            point_data[f"u{d}_{ly.name}"] = director_field(dm, u_full, k, d)
    cell_data = {
        "element_id": [np.arange(mesh.n_elements, dtype=np.int64)],
        "stack": [np.asarray(model.element_stack, dtype=np.int64)],
    }
    cell_data.update({k: [v] for k, v in material_cell_fields(model).items()})
    return meshio.Mesh(
        np.asarray(mesh.nodes, float),
        [("quad9", np.asarray(mesh.elements, dtype=np.int64))],
        point_data=point_data,
        cell_data=cell_data,
    )


def _ply_lattices(ly) -> list[np.ndarray]:
    """Layer fractions Θ_L³ / H_L (27,) of the lattice points of each ply of layer ``ly``: its
    bottom, middle and top (:func:`~.element.quadrature.ply_samples`)."""
    from .element.quadrature import ply_samples

    return [row[_LAT_M] for row in ply_samples([f for _, _, f in ly.ply_table()], 3)]


def solid_mesh(model: Model, dm: DofMap, u_full: np.ndarray, sampling: str = "recovered", frame: str = "material",
               load_factor: float = 1.0):
    """meshio.Mesh of the extruded shell: per element and layer (per ply of a ply stack) a 3×3×3
    lattice, 8 hexahedra; stresses with recovered (or raw) transverse components, in material (or global) axes."""
    import meshio

    from .recovery import stress_points

    mesh = model.mesh
    element_stack = np.asarray(model.element_stack)
    pts, cells, data = [], [], {k: [] for k in ("displacement", "cauchy", "pk2", "von_mises", "principal")}
    cell_elem, cell_layer = [], []
    n_pts = 0
    for k, ly in enumerate(model.layers):
        stacks_with = [si for si, st in enumerate(model.stacks) if k in st]
        elems = np.flatnonzero(np.isin(element_stack, stacks_with))
        if elems.size == 0:
            continue
        ne = elems.size
        conn = mesh.elements[elems]  # (ne, 9)
        H = np.asarray(ly.thickness, float)[conn[:, _LAT_NODE]]  # (ne, 27) thickness at lattice nodes
        for s_lat in _ply_lattices(ly):  # one lattice per ply (the layer's own without plies)
            thL = s_lat[None, :] * H
            xi = np.broadcast_to(NODE_XI[_LAT_NODE, 0], (ne, 27))
            eta = np.broadcast_to(NODE_XI[_LAT_NODE, 1], (ne, 27))
            e_pts = np.repeat(elems, 27)
            ps = stress_points(model, dm, u_full, e_pts, xi.ravel(), eta.ravel(), thL.ravel(), layers=k,
                               local_theta=True, sampling=sampling, load_factor=load_factor)
            cau = ps.stress("cauchy", frame)
            pts.append(ps.X)
            data["displacement"].append(ps.u)
            data["cauchy"].append(stress_components(cau))
            data["pk2"].append(stress_components(ps.stress("pk2", frame)))
            data["von_mises"].append(von_mises(cau))
            data["principal"].append(np.linalg.eigvalsh(cau)[:, ::-1])
            base = n_pts + 27 * np.arange(ne)
            cells.append((base[:, None, None] + _HEXES[None]).reshape(-1, 8))
            cell_elem.append(np.repeat(elems, 8))
            cell_layer.append(np.full(8 * ne, k, dtype=np.int64))
            n_pts += 27 * ne
    if not pts:
        points = np.zeros((0, 3))
        hexes = np.zeros((0, 8), dtype=np.int64)
        point_data = {
            "displacement": np.zeros((0, 3)), "cauchy": np.zeros((0, 6)), "pk2": np.zeros((0, 6)),
            "von_mises": np.zeros(0), "principal": np.zeros((0, 3)),
        }
        cell_data = {"element_id": [np.zeros(0, np.int64)], "layer": [np.zeros(0, np.int64)]}
    else:
        points = np.concatenate(pts)
        hexes = np.concatenate(cells).astype(np.int64)
        point_data = {name: np.concatenate(v) for name, v in data.items()}
        cell_data = {
            "element_id": [np.concatenate(cell_elem).astype(np.int64)],
            "layer": [np.concatenate(cell_layer)],
        }
    return meshio.Mesh(points, [("hexahedron", hexes)], point_data=point_data, cell_data=cell_data)


# ----------------------------------------------------------------------------- public API


def export_step(out_dir: Path, step: int, model: Model, dm: DofMap, u_full: np.ndarray,
                load_factor: float, controller=None, sampling: str = "recovered",
                frame: str = "material") -> dict[str, Path]:
    """Write ``surface_{step:04d}.vtu`` and ``solid_{step:04d}.vtu`` into ``out_dir``.

    Returns ``{"surface": path, "solid": path}``. ``load_factor`` is not stored in the files
    (meshio's VTU writer drops field data); it is the time value of the ``.pvd`` collections
    (:class:`PvdWriter`) and scales the face tractions of the stress recovery. ``sampling`` and
    ``frame``: [output] sampling/frame of the solid and interface stresses.
    """
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    u_full = np.asarray(u_full, float)
    surf = surface_mesh(model, dm, u_full)
    solid = solid_mesh(model, dm, u_full, sampling, frame, load_factor)
    paths = {"surface": out_dir / f"surface_{step:04d}.vtu", "solid": out_dir / f"solid_{step:04d}.vtu"}
    _write_vtu(paths["surface"], surf)
    _write_vtu(paths["solid"], solid)
    from .interfaces import interfaces

    for itf in interfaces(model):
        if itf.elements.size:
            key = "interface_" + "".join(c if c.isalnum() else "_" for c in itf.name)
            paths[key] = out_dir / f"{key}_{step:04d}.vtu"
            run = None
            if controller is not None:
                run = next((r for r in controller.runs if r.block.itf.upper == itf.upper), None)
            _write_vtu(paths[key], interface_mesh(model, dm, u_full, itf, run, sampling, frame, load_factor))
    return paths


def interface_mesh(model: Model, dm: DofMap, u_full: np.ndarray, itf, run=None, sampling: str = "recovered",
                   frame: str = "material", load_factor: float = 1.0):
    """meshio.Mesh of one interface (quad9 per element, nodes duplicated per element) with the
    traction components σ13, σ23, σ33 of the upper layer (3.33) (recovered or raw, material axes
    or global x, y, z), the shear resultant and the displacement of the interface."""
    import meshio

    from .interfaces import face_points
    from .recovery import stress_points

    xi, eta = face_points("nodes")
    ne_ = itf.elements.size
    ps = stress_points(model, dm, u_full, np.repeat(itf.elements, 9), np.tile(xi, ne_), np.tile(eta, ne_),
                       np.zeros(9 * ne_), np.full(9 * ne_, itf.upper), local_theta=True, sampling=sampling,
                       load_factor=load_factor)
    t = ps.traction(frame)
    tm = ps.traction()
    ne = itf.elements.size
    point_data = {"traction": t, "sigma13": t[:, 0], "sigma23": t[:, 1], "sigma33": t[:, 2],
                  "shear": np.hypot(tm[:, 0], tm[:, 1]), "displacement": ps.u}
    if run is not None and hasattr(run.block, "d_old"):  # cohesive interface
        inv = np.argsort(run.block.region)
        pick = lambda a: a[:, inv].reshape(ne * 9, *a.shape[2:])  # noqa: E731
        delta = run.block.separation(u_full)
        n = run.block.contact.A3
        gap = np.einsum("eqi,eqi->eq", delta, n)
        slip = delta - gap[..., None] * n
        d = run.block.d_old
        point_data.update({"damage": pick(d), "debonded": pick(run.block.released.astype(np.int8)),
                           # softening, not yet debonded: with a stiff penalty d is close to 1 over
                           # the whole process zone, which only the energy tells apart
                           "process_zone": pick(((d > 0) & ~run.block.released).astype(np.int8)),
                           "fracture_energy": pick(run.fracture),
                           "gap": pick(gap), "slip": pick(slip), "slip_magnitude": pick(np.linalg.norm(slip, axis=-1))})
    elif run is not None:
        # delamination state lives at the 9 face Gauss points; each belongs to exactly one node
        # region (MODEL.md §9 rule 1), so it maps one-to-one onto the element's nodes
        inv = np.argsort(run.block.region)
        pick = lambda a: a[:, inv].reshape(ne * 9, *a.shape[2:])  # noqa: E731
        point_data.update({
            "debonded": pick(run.block.released.astype(np.int8)),
            "failure_V": pick(np.nan_to_num(run.V, nan=0.0)),
            "contact_pressure": pick(run.pressure),
            "gap": pick(run.gap),
            "slip": pick(run.slip),
            "slip_magnitude": pick(np.linalg.norm(run.slip, axis=-1)),
            "gT_max": pick(run.gmax),
            "friction_shear": pick(np.linalg.norm(run.tau, axis=-1) * run.block.released),
        })
    return meshio.Mesh(ps.X, [("quad9", np.arange(9 * ne, dtype=np.int64).reshape(ne, 9))],
                       point_data=point_data, cell_data={"element_id": [itf.elements.astype(np.int64)]})


_PVD_HEAD = ('<?xml version="1.0"?>\n<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">\n'
             "  <Collection>\n")
_PVD_TAIL = "  </Collection>\n</VTKFile>\n"


def _pvd_entry(t: float, f: str) -> str:
    from xml.sax.saxutils import quoteattr

    return f'    <DataSet timestep="{float(t)!r}" group="" part="0" file={quoteattr(str(f))} />\n'


def write_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """Write a ParaView collection file listing ``(timestep, file)`` pairs (file names relative
    to the ``.pvd``), atomically."""
    text = _PVD_HEAD + "".join(_pvd_entry(t, f) for t, f in entries) + _PVD_TAIL
    atomic_write(Path(path), lambda tmp: tmp.write_text(text, encoding="utf-8"))


def append_pvd(path: Path, entries: list[tuple[float, str]]) -> None:
    """Add ``entries`` to a collection file written by :func:`write_pvd` at constant cost: one
    write at the position of the closing tags (new entries and the closing tags again), so the
    file is never without its closing tags on disk (the write only extends it). Falls back to
    rewriting when the file does not end as :func:`write_pvd` leaves it."""
    path = Path(path)
    tail = _PVD_TAIL.encode()
    data = "".join(_pvd_entry(t, f) for t, f in entries).encode("utf-8") + tail
    with open(path, "r+b", buffering=0) as f:
        size = f.seek(0, os.SEEK_END)
        if size >= len(tail):
            f.seek(size - len(tail))
            if f.read(len(tail)) == tail:
                f.seek(size - len(tail))
                f.write(data)  # one unbuffered write
                return
    raise ValueError(f"{path} does not end with the closing tags of a collection")


class PvdWriter:
    """Keeps the surface and solid series of a run and updates ``surface.pvd``, ``solid.pvd``
    (and one ``<key>.pvd`` per further series) in ``out_dir`` after each :meth:`add`: the new
    entries are appended (:func:`append_pvd`), so a step costs the same however long the run."""

    def __init__(self, out_dir: Path):
        self.out_dir = Path(out_dir)
        self.series: dict[str, list[tuple[float, str]]] = {"surface": [], "solid": []}
        self._on_disk: dict[str, int] = {}  # entries of each series in its file

    @property
    def surface(self) -> list[tuple[float, str]]:
        return self.series["surface"]

    @property
    def solid(self) -> list[tuple[float, str]]:
        return self.series["solid"]

    def _rel(self, p: Path) -> str:
        p = Path(p)
        try:
            return Path(os.path.relpath(p.resolve(), self.out_dir.resolve())).as_posix()
        except ValueError:  # other drive (Windows)
            return p.resolve().as_posix()

    def add(self, step: int, load_factor: float, paths: dict[str, Path]) -> None:
        """Register the files of one step (``paths`` as returned by :func:`export_step`); every
        key becomes a series ``<key>.pvd``."""
        for key, p in paths.items():
            self.series.setdefault(key, []).append((float(load_factor), self._rel(p)))
        self.write()

    def write(self) -> None:
        """Bring every series file up to date: append what is new, rewrite what is not known."""
        self.out_dir.mkdir(parents=True, exist_ok=True)
        for key, entries in self.series.items():
            if not entries and key not in ("surface", "solid"):
                continue
            path = self.out_dir / f"{key}.pvd"
            n = self._on_disk.get(key)
            if n is not None and n < len(entries):
                try:
                    append_pvd(path, entries[n:])
                    self._on_disk[key] = len(entries)
                    continue
                except (OSError, ValueError):
                    pass
            elif n == len(entries):
                continue
            write_pvd(path, entries)
            self._on_disk[key] = len(entries)
