"""examples/plate_gmsh.{geo,msh,toml}: a Gmsh mesh whose physical groups select the support, the
load, two layer stacks and an initially debonded region. Independent reference: the same plate
built with the rectangle generator and coordinate formulas instead of the mesh file's groups."""
import json

import numpy as np
import pytest
from helpers import EXAMPLES

from layershell.export import reference_displacement
from layershell.io.build import build, parse
from layershell.io.meshfile import read_mesh
from layershell.runner import run

TOML = EXAMPLES / "plate_gmsh.toml"

#: plate_gmsh.toml with the mesh file's groups replaced by the generator and formulas
TWIN = {
    'type = "file"\npath = "plate_gmsh.msh"': 'type = "rectangle"\nlx = 3.0\nly = 3.0\nnx = 3\nny = 3\nnormal = "+z"',
    'set = "strengthened"': 'where = "y < 2"',
    'set = "plain"': 'where = "y > 2"',
    'set = "clamp"': 'where = "near(y, 0)"',
    'set = "plate"\n': "",
    '{set = "debonded"}': '{where = "x > 0.99 and x < 2.01 and y > 0.99 and y < 2.01"}',
}


def _spec(twin: bool, extra: dict[str, str] | None = None):
    text = TOML.read_text()
    for a, b in {**(TWIN if twin else {}), **(extra or {})}.items():
        assert a in text, a
        text = text.replace(a, b)
    return build(parse(text, str(TOML)), EXAMPLES)


def _match(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Index into ``b`` of the point equal to each point of ``a`` (both (n, 3))."""
    d = np.linalg.norm(a[:, None] - b[None], axis=-1)
    idx = d.argmin(1)
    assert np.allclose(d[np.arange(len(a)), idx], 0.0, atol=1e-9)  # Gmsh writes 16 digits
    return idx


def test_geo_and_msh_belong_together():
    geo = (EXAMPLES / "plate_gmsh.geo").read_text()
    msh = (EXAMPLES / "plate_gmsh.msh").read_text()
    assert msh.startswith("$MeshFormat\n4.1 0 8")  # Gmsh 4.1 ASCII
    for name in ("clamp", "plate", "strengthened", "plain", "debonded"):
        assert f'Physical {"Curve" if name == "clamp" else "Surface"}("{name}")' in geo
        assert f'"{name}"' in msh


def test_physical_groups_arrive_as_sets():
    m = read_mesh(EXAMPLES / "plate_gmsh.msh")
    m.check()
    assert (m.n_elements, m.n_nodes) == (9, 49) and not m.notes  # quad9 as written: nothing converted
    x = m.nodes
    np.testing.assert_allclose(m.normals_at_centres(), np.tile([0, 0, 1.0], (9, 1)))
    assert sorted(m.node_sets["clamp"].tolist()) == np.flatnonzero(np.isclose(x[:, 1], 0)).tolist()
    c = x[m.elements[:, 8]]
    assert m.element_sets["strengthened"].tolist() == np.flatnonzero(c[:, 1] < 2).tolist()
    assert m.element_sets["plain"].tolist() == np.flatnonzero(c[:, 1] > 2).tolist()
    assert m.element_sets["plate"].tolist() == list(range(9))
    (e,) = m.element_sets["debonded"]
    np.testing.assert_allclose(c[e], [1.5, 1.5, 0])
    assert sorted(m.node_sets["debonded"].tolist()) == sorted(m.elements[e].tolist())
    assert "gmsh:bounding_entities" not in m.node_sets  # meshio's bookkeeping is not a group


def test_model_from_groups_equals_model_from_formulas():
    g, r = _spec(False).model, _spec(True).model
    node = _match(g.mesh.nodes, r.mesh.nodes)  # gmsh node -> generator node
    el = _match(g.mesh.nodes[g.mesh.elements[:, 8]], r.mesh.nodes[r.mesh.elements[:, 8]])
    assert [g.stacks[s] for s in g.element_stack] == [r.stacks[s] for s in r.element_stack[el]]
    assert {0: 2, 1: 1} == {k: len(g.stacks[k]) for k in range(2)}
    k = 1  # the TRC layer: initially debonded below it
    assert sorted(node[g.initially_debonded[k]].tolist()) == sorted(r.initially_debonded[k].tolist())
    assert len(g.initially_debonded[k]) == 9
    fg = sorted(node[np.concatenate([f.nodes for f in g.fixes])].tolist())
    fr = sorted(np.concatenate([f.nodes for f in r.fixes]).tolist())
    assert fg == fr and len(fg) == 7


@pytest.mark.slow  # the full example twice: about 35 s of CPU (longer on a busy machine)
def test_gmsh_plate_solves_like_the_generated_plate(tmp_path):
    """The whole example (8 nonlinear steps; the initial zone in contact from the start, new
    debonding at λ = 0.5 and 0.875) and its generator/formula twin: the same probes, debonded
    areas per step and nodal displacement field."""
    rg = run(_spec(False), tmp_path / "g", write_vtu=False)
    rr = run(_spec(True), None)
    assert rg.converged and rr.converged
    pg, pr = rg.summary["probes"], rr.summary["probes"]
    assert pg["w_front_max"] > 0.05 and pg["w_debonded"] > 0.01
    for n in pr:
        assert abs(pg[n] - pr[n]) <= 1e-7 * abs(pr[n]), n
    ag = [a["concrete/trc"] for a in rg.summary["debonded_area"]]
    ar = [a["concrete/trc"] for a in rr.summary["debonded_area"]]
    assert ag == pytest.approx(ar, rel=1e-9)
    assert ag[0] > 0 and ag[-1] > ag[0]  # open from the start, and it grows
    assert rg.summary["first_delamination_load_factor"] == rr.summary["first_delamination_load_factor"]
    ug = reference_displacement(rg.problem.model, rg.problem.dm, rg.u)
    ur = reference_displacement(rr.problem.model, rr.problem.dm, rr.u)
    node = _match(rg.problem.model.mesh.nodes, rr.problem.model.mesh.nodes)
    np.testing.assert_allclose(ug, ur[node], rtol=0, atol=1e-7 * np.abs(ur).max())
    s = json.loads((tmp_path / "g" / "summary.json").read_text())
    assert s["converged"] and len(s["steps"]) == 8
    assert (tmp_path / "g" / "debonded_zone_concrete_trc.png").is_file()
