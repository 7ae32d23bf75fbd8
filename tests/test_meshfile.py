"""Meshes from files (meshio): Gmsh physical groups as sets, quad4/quad8 → quad9 conversion."""
import meshio
import numpy as np
import pytest
from helpers import EXAMPLES

from layershell.io.build import InputError, boundary_edges, build, parse
from layershell.io.meshfile import read_mesh
from layershell.mesh import MeshError, rectangle
from layershell.runner import run


def _write_gmsh(path, m):
    x = m.nodes
    be = boundary_edges(m)
    clamp = be[np.isclose(x[be][..., 0], 0).all(1)]
    mm = meshio.Mesh(x, [("quad9", m.elements), ("line3", clamp)],
                     cell_data={"gmsh:physical": [np.full(m.n_elements, 1), np.full(len(clamp), 2)],
                                "gmsh:geometrical": [np.full(m.n_elements, 1), np.full(len(clamp), 2)]},
                     field_data={"beam": np.array([1, 2]), "clamp": np.array([2, 1])})
    meshio.write(path, mm, file_format="gmsh22", binary=False)


def test_gmsh_round_trip_with_physical_groups(tmp_path):
    m = rectangle(10.0, 1.0, 5, 1, normal="-z")
    _write_gmsh(tmp_path / "beam.msh", m)
    r = read_mesh(tmp_path / "beam.msh")
    assert r.n_elements == 5 and r.n_nodes == m.n_nodes
    assert np.allclose(r.nodes[r.node_sets["clamp"]][:, 0], 0.0) and len(r.node_sets["clamp"]) == 3
    assert len(r.element_sets["beam"]) == 5
    r.check()


@pytest.mark.parametrize("kind", ["quad", "quad8"])
def test_lower_order_quads_are_converted(tmp_path, kind):
    m = rectangle(2.0, 1.0, 2, 2)
    cells = m.elements[:, :4] if kind == "quad" else m.elements[:, :8]
    used = np.unique(cells)
    remap = -np.ones(m.n_nodes, int)
    remap[used] = np.arange(used.size)
    meshio.write(tmp_path / "m.vtu", meshio.Mesh(m.nodes[used], [(kind, remap[cells])]))
    r = read_mesh(tmp_path / "m.vtu")
    assert r.n_elements == 4 and r.n_nodes == m.n_nodes
    assert r.notes and kind in r.notes[0]
    r.check()
    # the converted 9-node elements reproduce the flat geometry: total area 2
    from layershell.element.geometry import surface_points
    from layershell.element.quadrature import gauss_2d

    pts, w = gauss_2d(3)
    sp = surface_points(r.nodes[r.elements], pts[:, 0], pts[:, 1])
    assert np.isclose((sp.sqrtA * w).sum(), 2.0)


def test_model_with_a_mesh_file_and_named_sets(tmp_path):
    """The thick cantilever read from a Gmsh file, clamped through the physical group 'clamp',
    gives the same tip deflection as with the generated mesh."""
    m = rectangle(10.0, 1.0, 5, 1, normal="-z")
    _write_gmsh(tmp_path / "beam.msh", m)
    text = (EXAMPLES / "cantilever_thick.toml").read_text()
    text = text.replace('type = "rectangle"\nlx = 10.0\nly = 1.0\nnx = 5\nny = 1\nnormal = "-z"',
                        'type = "file"\npath = "beam.msh"')
    text = text.replace('type = "symmetry"\nwhere = "near(x, 0)"', 'type = "symmetry"\nset = "clamp"')
    spec = build(parse(text), tmp_path)
    assert abs(run(spec).summary["probes"]["w_tip"] - 4.0205) < 1e-3  # the example (MITC9 default)


def test_generated_meshes_name_their_edges():
    m = rectangle(2.0, 1.0, 2, 1)
    assert np.allclose(m.nodes[m.node_sets["xmax"]][:, 0], 2.0)
    assert np.allclose(m.nodes[m.node_sets["ymin"]][:, 1], 0.0)


def test_bad_mesh_files(tmp_path):
    with pytest.raises(MeshError, match="does not exist"):
        read_mesh(tmp_path / "nope.msh")
    meshio.write(tmp_path / "tri.vtu", meshio.Mesh(np.eye(3), [("triangle", np.array([[0, 1, 2]]))]))
    with pytest.raises(MeshError, match="no quadrilateral"):
        read_mesh(tmp_path / "tri.vtu")
    text = (EXAMPLES / "cantilever_thick.toml").read_text().replace(
        'type = "rectangle"\nlx = 10.0\nly = 1.0\nnx = 5\nny = 1\nnormal = "-z"', 'type = "file"\npath = "tri.vtu"')
    with pytest.raises(InputError, match="mesh"):
        build(parse(text), tmp_path)
