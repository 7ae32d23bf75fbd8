"""Mesh files with inverted or badly distorted elements are rejected with the element ids and
Jacobians (exit code 2); 4- and 8-node quadrilaterals are converted to 9-node ones with a note."""
from __future__ import annotations

import re

import meshio
import numpy as np
import pytest
from helpers import EXAMPLES
from typer.testing import CliRunner

from layershell.cli import app
from layershell.io.meshfile import read_mesh
from layershell.mesh import Mesh, MeshError, rectangle, revolution

GMSH = EXAMPLES / "plate_gmsh.msh"


def _model_file(tmp_path, mesh_name: str) -> str:
    """examples/plate_gmsh.toml reading ``mesh_name`` in tmp_path (with the groups 'strengthened',
    'plain' and 'clamp'; the load and the initial zone selected by formulas)."""
    text = (EXAMPLES / "plate_gmsh.toml").read_text()
    for a, b in {'path = "plate_gmsh.msh"': f'path = "{mesh_name}"', 'set = "plate"\n': "",
                 '{set = "debonded"}': '{where = "x > 0.99 and x < 2.01 and y > 0.99 and y < 2.01"}'}.items():
        assert a in text
        text = text.replace(a, b)
    p = tmp_path / "model.toml"
    p.write_text(text)
    return str(p)


def _write(path, mesh: Mesh, kind: str = "quad9") -> None:
    """Write ``mesh`` as a Gmsh 2.2 file (meshio) with the physical groups 'strengthened' and
    'plain' (elements) and 'clamp' (the edge y = 0 as line3 cells); ``kind`` 'quad'/'quad8' keeps
    only the first 4/8 nodes of every element."""
    from layershell.io.build import boundary_edges

    n = {"quad": 4, "quad8": 8, "quad9": 9}[kind]
    be = boundary_edges(mesh)
    clamp = be[np.isclose(mesh.nodes[be][..., 1], 0).all(1)]
    cells = mesh.elements[:, :n]
    used = np.unique(np.concatenate([cells.ravel(), clamp.ravel()]))
    remap = -np.ones(mesh.n_nodes, int)
    remap[used] = np.arange(used.size)
    tag = np.where(np.isin(np.arange(mesh.n_elements), mesh.element_sets["strengthened"]), 1, 2)
    mm = meshio.Mesh(mesh.nodes[used], [(kind, remap[cells]), ("line3", remap[clamp])],
                     cell_data={"gmsh:physical": [tag, np.full(len(clamp), 3)],
                                "gmsh:geometrical": [tag, np.full(len(clamp), 3)]},
                     field_data={"strengthened": np.array([1, 2]), "plain": np.array([2, 2]),
                                 "clamp": np.array([3, 1])})
    meshio.write(path, mm, file_format="gmsh22", binary=False)


def _cli(*args):
    return CliRunner().invoke(app, list(args))


def _jacobians(text: str) -> list[float]:
    return [float(v) for v in re.findall(r"Jacobian (?:min )?(-?[0-9.eE+-]+)", text)]


def test_example_mesh_written_back_passes(tmp_path):
    m = read_mesh(GMSH)
    _write(tmp_path / "ok.msh", m)
    r = _cli("check", _model_file(tmp_path, "ok.msh"))
    assert r.exit_code == 0, r.output
    assert "9 elements" in r.output


def test_inverted_element_exit_2_with_id_and_jacobian(tmp_path):
    m = read_mesh(GMSH)
    m.flip(np.arange(m.n_elements) == 4)  # reversed node order: its normal points down
    _write(tmp_path / "inverted.msh", m)
    r = _cli("check", _model_file(tmp_path, "inverted.msh"))
    assert r.exit_code == 2
    text = " ".join(r.output.split())
    assert "'mesh'" in text and "inverted" in text and "ids [4]" in text
    # a unit square: area Jacobian 1/4 everywhere, negative relative to its neighbours
    jac = _jacobians(text)
    assert jac and np.allclose(jac, -0.25)
    assert "Traceback" not in r.output


def test_distorted_element_exit_2_with_id_and_jacobian(tmp_path):
    m = read_mesh(GMSH)
    c = m.nodes[m.elements[:, 8]]
    e = int(np.flatnonzero(np.isclose(c[:, 0], 1.5) & np.isclose(c[:, 1], 0.5))[0])  # the middle clamp element
    # its mid-side node on the clamped edge y = 0 slides 0.24 towards the corner at x = 2: the map
    # x(ξ) along that edge has dx/dξ = 0.5 - 2·0.24 = 0.02 at the corner (exactly, quadratic map),
    # so the area Jacobian there is 0.02 × 0.5 = 0.01 against up to 0.5: folded-over almost, not yet inverted
    m.nodes[m.elements[e, 4]] += [0.24, 0.0, 0.0]
    _write(tmp_path / "distorted.msh", m)
    r = _cli("check", _model_file(tmp_path, "distorted.msh"))
    assert r.exit_code == 2
    text = " ".join(r.output.split())
    assert "badly distorted" in text and f"ids [{e}]" in text
    jmin, jmax = _jacobians(text)[0], float(re.search(r"max ([0-9.eE+-]+)", text).group(1))
    assert jmin == pytest.approx(0.01, rel=1e-6) and 0.25 < jmax < 1.0
    # one step further the element folds over: a negative Jacobian
    m.nodes[m.elements[e, 4]] += [0.06, 0.0, 0.0]
    with pytest.raises(MeshError, match=rf"ids \[{e}\].*Jacobian min -0\.05"):
        m.check()


def test_valid_meshes_pass():
    """Generated meshes, including the collapsed elements at the pole of a dome, pass the check."""
    rectangle(3.0, 1.0, 4, 2, normal="-z").check()
    revolution([1.0, 0.0], [0.0, 1.0], 3, 8, normal="outward").check()
    m = read_mesh(GMSH)
    m.nodes[m.elements[1, 4]] += [0.2, 0.0, 0.0]  # a moderately distorted element is fine
    m.check()


def test_orientation_check_takes_the_majority():
    m = rectangle(3.0, 3.0, 3, 3)
    flip = np.zeros(9, bool)
    flip[[0, 1, 2, 3, 5]] = True  # 5 of 9 flipped: the other 4 are reported
    m.flip(flip)
    assert m.inconsistent_orientation().tolist() == [4, 6, 7, 8]
    m.flip(np.ones(9, bool) & ~flip)
    assert m.inconsistent_orientation().size == 0  # consistently -z: fine


@pytest.mark.parametrize("kind, n", [("quad", 4), ("quad8", 8)])
def test_lower_order_quads_note_on_the_command_line(tmp_path, kind, n):
    _write(tmp_path / "low.msh", read_mesh(GMSH), kind)
    r = _cli("check", _model_file(tmp_path, "low.msh"))
    assert r.exit_code == 0, r.output
    text = " ".join(r.output.split())
    assert f"note: mesh file 'low.msh': 9 {n}-node quadrilaterals ('{kind}') converted to 9-node elements" in text
    assert "9 elements, 49 nodes" in text  # the same 49 nodes as the quad9 file
