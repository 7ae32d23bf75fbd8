"""ParaView export (meshio .vtu / .pvd) and matplotlib quick-look plots."""
from __future__ import annotations

import xml.etree.ElementTree as ET

import meshio
import numpy as np
import pytest

from layershell.export import PvdWriter, export_step, reference_displacement, von_mises, write_pvd
from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import Fix, Layer, Model, SurfaceLoad
from layershell.plots import plot_deformed, plot_load_displacement, plot_through_thickness
from layershell.solver.newton import load_steps
from layershell.solver.problem import Problem


def _model(normal: str = "+z") -> Model:
    mesh = rectangle(2.0, 1.0, 2, 1, normal=normal)
    th = np.full(mesh.n_nodes, 0.1)
    layers = [
        Layer("base", Orthotropic.isotropic(1000.0, 0.2), 2, th),
        Layer("top", Orthotropic.isotropic(2000.0, 0.2), 1, th * 0.5),
    ]
    return Model(
        mesh, layers, [(0, 1)], np.zeros(mesh.n_elements, int),
        fixes=[Fix(np.flatnonzero(np.isclose(mesh.nodes[:, 0], 0)), 0, (0, 1, 2), (0, 1, 2))],
        surface_loads=[SurfaceLoad(np.arange(mesh.n_elements), "reference", np.array([0, 0, -1.0]),
                                   lambda x, y, z: 0 * x + 1.0)],
    )


@pytest.fixture(scope="module")
def solved():
    model = _model()
    pb = Problem.build(model)
    st = list(load_steps(pb, np.array([1.0])))[-1]
    return model, pb.dm, st.u


def _hex_volumes(points: np.ndarray, hexes: np.ndarray) -> np.ndarray:
    """Signed volumes of trilinear VTK hexahedra (2×2×2 Gauss integration of det J)."""
    ref = np.array([[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1],
                    [-1, -1, 1], [1, -1, 1], [1, 1, 1], [-1, 1, 1]], float)
    g = 1.0 / np.sqrt(3.0)
    vol = np.zeros(len(hexes))
    X = points[hexes]  # (c, 8, 3)
    for a in (-g, g):
        for b in (-g, g):
            for c in (-g, g):
                p = np.array([a, b, c])
                dN = np.empty((8, 3))
                for i in range(3):
                    others = [j for j in range(3) if j != i]
                    dN[:, i] = ref[:, i] / 8.0 * np.prod(1 + ref[:, others] * p[others], axis=1)
                J = np.einsum("cni,nj->cij", X, dN)
                vol += np.linalg.det(J)
    return vol


def test_export_step_files(solved, tmp_path):
    model, dm, u = solved
    paths = export_step(tmp_path / "out", 3, model, dm, u, 1.0)
    assert paths["surface"].name == "surface_0003.vtu" and paths["solid"].name == "solid_0003.vtu"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == [
        "interface_base_top_0003.vtu", "solid_0003.vtu", "surface_0003.vtu"]
    import meshio

    itf = meshio.read(paths["interface_base_top"])
    n = model.mesh.n_elements
    assert itf.cells[0].type == "quad9" and itf.cells[0].data.shape == (n, 9)
    assert itf.point_data["traction"].shape == (9 * n, 3) and np.all(np.isfinite(itf.point_data["traction"]))
    # interface points lie at the top face of the base layer (offset 0.1 along +z)
    assert np.allclose(itf.points[:, 2], 0.1)

    surf = meshio.read(paths["surface"])
    assert [c.type for c in surf.cells] == ["quad9"]
    assert surf.cells[0].data.shape == (model.mesh.n_elements, 9)
    np.testing.assert_array_equal(surf.cells[0].data, model.mesh.elements)
    np.testing.assert_allclose(surf.points, model.mesh.nodes)
    nn = model.mesh.n_nodes
    expected = {"displacement", "u0_base", "u1_base", "u2_base", "u0_top", "u1_top"}
    assert set(surf.point_data) == expected
    for name in expected:
        assert surf.point_data[name].shape == (nn, 3)
        assert np.all(np.isfinite(surf.point_data[name]))
    # reference-face displacement = director 0 of the first layer
    np.testing.assert_allclose(surf.point_data["displacement"], u[dm.layer_dofs[0][:, 0, :]])
    assert np.abs(surf.point_data["displacement"]).max() > 0
    np.testing.assert_array_equal(surf.cell_data["element_id"][0], np.arange(model.mesh.n_elements))
    np.testing.assert_array_equal(surf.cell_data["stack"][0], model.element_stack)

    sol = meshio.read(paths["solid"])
    assert [c.type for c in sol.cells] == ["hexahedron"]
    ne, nl = model.mesh.n_elements, len(model.layers)
    hexes = sol.cells[0].data
    assert hexes.shape == (ne * nl * 8, 8)
    npts = ne * nl * 27
    assert sol.points.shape == (npts, 3)
    shapes = {"displacement": (npts, 3), "cauchy": (npts, 6), "pk2": (npts, 6),
              "von_mises": (npts,), "principal": (npts, 3)}
    for name, shape in shapes.items():
        arr = np.asarray(sol.point_data[name])
        assert arr.shape == shape, name
        assert np.all(np.isfinite(arr)), name
    assert np.all(np.diff(sol.point_data["principal"], axis=1) <= 1e-9)
    assert np.abs(sol.point_data["cauchy"]).max() > 0
    assert sorted(np.unique(sol.cell_data["layer"][0])) == [0, 1]
    assert sorted(np.unique(sol.cell_data["element_id"][0])) == list(range(ne))

    vol = _hex_volumes(sol.points, hexes)
    assert np.all(vol > 0)
    total = np.ptp(model.mesh.nodes[:, 0]) * np.ptp(model.mesh.nodes[:, 1]) * 0.15
    assert np.isclose(vol.sum(), total, rtol=1e-9)

    # the solid displacement at reference-face points equals the surface displacement
    lay0 = sol.cell_data["layer"][0] == 0
    X = sol.points
    Ud = sol.point_data["displacement"]
    bottom = np.unique(hexes[lay0][:, :4])
    bottom = bottom[np.isclose(X[bottom, 2], 0.0)]
    assert bottom.size > 0
    for p in bottom:
        node = np.flatnonzero(np.linalg.norm(model.mesh.nodes - X[p], axis=1) < 1e-12)
        assert node.size == 1
        np.testing.assert_allclose(Ud[p], surf.point_data["displacement"][node[0]], atol=1e-12)


def test_solid_stress_fields_consistent(solved, tmp_path):
    model, dm, u = solved
    sol = meshio.read(export_step(tmp_path, 0, model, dm, u, 0.5)["solid"])
    c = np.asarray(sol.point_data["cauchy"])
    t = np.empty((len(c), 3, 3))
    for k, (r, s) in enumerate(((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))):
        t[:, r, s] = t[:, s, r] = c[:, k]
    np.testing.assert_allclose(sol.point_data["von_mises"], von_mises(t), rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(sol.point_data["principal"], np.linalg.eigvalsh(t)[:, ::-1], rtol=1e-8, atol=1e-10)
    # the in-plane lattice points on the bottom face of element 0's first layer are its 9 nodes
    hexes = sol.cells[0].data
    first = hexes[(sol.cell_data["layer"][0] == 0) & (sol.cell_data["element_id"][0] == 0)]
    pts = np.unique(sol.points[np.unique(first[:, :4])].round(12), axis=0)
    pts = pts[np.isclose(pts[:, 2], 0.0)]
    nodes = np.unique(model.mesh.nodes[model.mesh.elements[0]].round(12), axis=0)
    np.testing.assert_allclose(pts, nodes)


def test_hexes_positive_for_reference_face_on_top(tmp_path):
    model = _model(normal="-z")
    pb = Problem.build(model)
    u = np.zeros(pb.dm.n_full)
    sol = meshio.read(export_step(tmp_path, 1, model, pb.dm, u, 0.0)["solid"])
    vol = _hex_volumes(sol.points, sol.cells[0].data)
    assert np.all(vol > 0)
    assert sol.points[:, 2].max() <= 1e-12 and sol.points[:, 2].min() < -0.1


def test_pvd(tmp_path, solved):
    model, dm, u = solved
    out = tmp_path / "vtk"
    w = PvdWriter(out)
    for step, lam in enumerate((0.25, 0.5)):
        w.add(step, lam, export_step(out, step, model, dm, lam * u, lam))
    for kind in ("surface", "solid"):
        root = ET.parse(out / f"{kind}.pvd").getroot()
        assert root.tag == "VTKFile" and root.attrib["type"] == "Collection"
        ds = root.find("Collection").findall("DataSet")
        assert [d.attrib["file"] for d in ds] == [f"{kind}_0000.vtu", f"{kind}_0001.vtu"]
        assert [float(d.attrib["timestep"]) for d in ds] == [0.25, 0.5]
        assert all(d.attrib["part"] == "0" for d in ds)
        for d in ds:
            assert (out / d.attrib["file"]).is_file()
    assert not [p for p in out.iterdir() if p.name.endswith(".tmp")]

    write_pvd(tmp_path / "x.pvd", [(0.0, "a.vtu"), (1e-3, "b.vtu")])
    ds = ET.parse(tmp_path / "x.pvd").getroot().findall("./Collection/DataSet")
    assert [(float(d.attrib["timestep"]), d.attrib["file"]) for d in ds] == [(0.0, "a.vtu"), (1e-3, "b.vtu")]


def _is_png(p) -> bool:
    return p.is_file() and p.stat().st_size > 1000 and p.read_bytes()[:4] == b"\x89PNG"


def test_plot_load_displacement(tmp_path):
    p = tmp_path / "a" / "ld.png"
    plot_load_displacement(p, [0.0, 0.5, 1.0], {"tip w": [0.0, -0.1, -0.2], "tip u": [0.0, 0.01, 0.02]}, units="mm")
    assert _is_png(p)
    q = tmp_path / "none.png"
    plot_load_displacement(q, [0.0, 1.0], {})
    assert _is_png(q)


def test_plot_deformed(tmp_path, solved):
    model, dm, u = solved
    assert np.abs(reference_displacement(model, dm, u)).max() > 0
    p = tmp_path / "b" / "def.png"
    plot_deformed(p, model, dm, u)
    q = tmp_path / "c" / "uz.png"
    plot_deformed(q, model, dm, u, field="z", scale=2.0)
    assert _is_png(p) and _is_png(q)
    with pytest.raises(ValueError):
        plot_deformed(tmp_path / "x.png", model, dm, u, field="bogus")


def test_plot_through_thickness(tmp_path):
    p = tmp_path / "d" / "thick.png"
    plot_through_thickness(p, {"x=1": (np.array([1.0, 0.0, -1.0]), np.array([0.0, 0.05, 0.1]))}, "σ11")
    assert _is_png(p)


def test_every_written_paraview_file_reads_back_cleanly(tmp_path, capfd):
    """A run with delamination writes surface, solid and interface series; every .pvd lists
    existing files in load order, and every .vtu reads back with meshio without a warning (meshio
    prints its warnings to stderr), with finite data of the right length on the right cell type."""
    import warnings

    from test_figures import SUCTION

    from layershell.io.build import build, parse
    from layershell.runner import run

    spec = build(parse(SUCTION.replace("vtu = false", "vtu = true"), "suction.toml"), tmp_path)
    out = tmp_path / "out"
    res = run(spec, out)
    assert res.converged
    capfd.readouterr()
    pvds = sorted(p.name for p in out.glob("*.pvd"))
    assert pvds == ["interface_base_top.pvd", "solid.pvd", "surface.pvd"]
    cell_type = {"surface": "quad9", "solid": "hexahedron", "interface_base_top": "quad9"}
    listed = set()
    for name in pvds:
        root = ET.parse(out / name).getroot()
        assert root.tag == "VTKFile" and root.attrib["type"] == "Collection"
        ds = root.findall("./Collection/DataSet")
        assert [float(d.attrib["timestep"]) for d in ds] == [0.5, 1.0]
        for d in ds:
            f = out / d.attrib["file"]
            listed.add(f.name)
            with warnings.catch_warnings():
                warnings.simplefilter("error")
                m = meshio.read(f)
            assert capfd.readouterr().err == "", f.name
            n = len(m.points)
            assert n > 0 and np.all(np.isfinite(m.points))
            assert [c.type for c in m.cells] == [cell_type[name[:-4]]]
            for key, arr in m.point_data.items():
                assert len(arr) == n and np.all(np.isfinite(arr)), (f.name, key)
            for key, blocks in m.cell_data.items():
                assert [len(b) for b in blocks] == [len(c.data) for c in m.cells], (f.name, key)
            assert m.cells[0].data.max() < n
    assert listed == {p.name for p in out.glob("*.vtu")}  # no file outside a series
    # the interface state matches the run: intact at λ = 0.5, all debonded at λ = 1
    flags = [meshio.read(out / f"interface_base_top_{s:04d}.vtu").point_data["debonded"] for s in (1, 2)]
    assert flags[0].max() == 0 and flags[1].min() == 1
    assert [a["base/top"] for a in res.summary["debonded_area"]] == pytest.approx([0.0, 2.0])
