"""The rectangle generator's node lines (lines_x/lines_y) and its grading towards chosen lines
(refine_x/refine_y with refine_ratio_x/refine_ratio_y), and the check that every [[stacks]]
'where' boundary on a rectangle mesh lies on element edges.

References: the coordinates asked for (exact), the geometric progression of the one-edge grading
(closed form, :func:`layershell.mesh.graded`), the rectangle's area, the pure-bending patch test
(exact quadratic field) and Timoshenko's cantilever deflection.
"""
from __future__ import annotations

import numpy as np
import pytest
from helpers import run_example
from test_bad_input import _assert_error, _outcome
from test_cli import Case, _all, _set

from layershell.mesh import graded, node_lines, rectangle


def _corners(m, axis: int) -> np.ndarray:
    """The distinct corner coordinates along ``axis`` (0: x, 1: y) of a rectangle mesh."""
    return np.unique(m.nodes[m.elements[:, :4], axis])


def _lengths(m, axis: int) -> np.ndarray:
    return np.diff(_corners(m, axis))


# ------------------------------------------------------------------ node lines
def test_node_lines_lie_exactly_at_the_given_coordinates():
    """Element edges at every given x and y (to the last bit, origin included), mid-side and
    centre nodes at the mid-points of straight edges, and a valid mesh."""
    m = rectangle(3.0, 1.0, 17, 5, origin=(1.0, -2.0, 0.0), lines_x=[1.1, 2.5, 3.9], lines_y=[-1.75],
                  refine_x=[1.1, 3.9], refine_ratio_x=4.0)
    m.check()
    cx, cy = _corners(m, 0), _corners(m, 1)
    for v in (1.0, 1.1, 2.5, 3.9, 4.0):
        assert np.any(cx == v), (v, cx)
    for v in (-2.0, -1.75, -1.0):
        assert np.any(cy == v), (v, cy)
    assert cx.size == 18 and cy.size == 6
    X = m.nodes[m.elements]
    mids = 0.5 * (X[:, [0, 1, 2, 3]] + X[:, [1, 2, 3, 0]])  # quad9: nodes 4..7 on the edges 0-1, 1-2, 2-3, 3-0
    assert np.allclose(X[:, 4:8], mids, rtol=0, atol=1e-14)
    assert np.allclose(X[:, 8], X[:, :4].mean(1), rtol=0, atol=1e-14)


def test_lines_alone_share_the_elements_by_length():
    """Without refine the pieces between lines hold elements in proportion to their length,
    equal within each piece: lines at 0.1, 1.5 and 2.9 on 3.0 with 30 elements give 30 equal ones."""
    x = node_lines(3.0, 30, [0.1, 1.5, 2.9])
    assert np.allclose(np.diff(x[::2]), 0.1, rtol=0, atol=1e-14)


@pytest.mark.parametrize("n, lines, refine, ratio", [
    (30, [], [0.0, 3.0], 3.0),           # both ends
    (31, [], [1.5], 4.0),                # an interior line
    (30, [0.1, 1.5, 2.9], [0.1, 2.9], 10.0),  # plate ends, a load line in between
    (12, [1.0], [0.0, 3.0], 2.0),
])
def test_grading_towards_lines_reaches_the_ratio(n, lines, refine, ratio):
    """Longest over shortest element = refine_ratio (to 10⁻³ here); the shortest element touches a
    refine line, the longest contains the point farthest from them."""
    c = node_lines(3.0, n, lines, refine, ratio)[::2]
    el = np.diff(c)
    assert abs(el.max() / el.min() / ratio - 1) < 1e-3
    short = np.argmin(el)
    assert np.min(np.abs(np.array(refine)[:, None] - c[[short, short + 1]][None])) < 1e-12
    grid = np.linspace(0.0, 3.0, 30001)
    far = grid[np.argmax(np.abs(grid[:, None] - np.array(refine)[None]).min(1))]
    long = np.argmax(el)
    assert c[long] - 1e-12 <= far <= c[long + 1] + 1e-12 or np.isclose(el[long], el[np.searchsorted(c, far) - 1])


def test_grading_towards_one_edge_is_the_geometric_progression():
    """Refined towards x = 0 alone, the element lengths are the geometric progression with last /
    first = ratio (closed form, the one-edge grading_x)."""
    for n, ratio in ((5, 3.0), (20, 0.25 ** -1), (7, 50.0)):
        assert np.allclose(node_lines(10.0, n, refine=[0.0], ratio=ratio), 10.0 * graded(n, ratio), rtol=0, atol=1e-9)


def test_graded_mesh_keeps_the_area():
    """The sum of the element areas (signed Jacobians at 3 × 3 Gauss points) is lx × ly."""
    from layershell.element.quadrature import gauss_2d

    m = rectangle(3.0, 1.2, 13, 6, lines_x=[0.1, 2.9], lines_y=[0.3], refine_x=[0.1, 2.9], refine_ratio_x=8.0,
                  refine_y=[0.0, 1.2], refine_ratio_y=3.0)
    _, w = gauss_2d(3)
    jg, _ = m.jacobians()
    assert np.isclose((jg * w).sum(), 3.0 * 1.2, rtol=1e-13)


def test_pure_bending_patch_is_exact_on_a_graded_mesh():
    """Pure bending of a strip 10 × 1 × 1 (linear end traction, moment M per width) on a mesh
    graded towards both ends with a node line at 3.3: the tip deflection is M l²/(2EI) to
    round-off (the quadratic field is exact on any straight-edged mesh)."""
    from test_patch import _edges

    from layershell.element.shape import NODE_XI
    from layershell.material import Orthotropic
    from layershell.model import EdgeLoad, Fix, Layer, Model, Symmetry
    from layershell.results import evaluate_points
    from layershell.solver.newton import load_steps
    from layershell.solver.problem import Problem

    E, M = 1e5, 100.0
    m = rectangle(10.0, 1.0, 6, 2, lines_x=[3.3], refine_x=[0.0, 10.0], refine_ratio_x=3.0)
    assert abs(_lengths(m, 0).max() / _lengths(m, 0).min() / 3.0 - 1) < 1e-3
    x = m.nodes
    ly = Layer("b", Orthotropic.isotropic(E, 0.3), 2, np.ones(m.n_nodes))
    x0 = np.flatnonzero(np.isclose(x[:, 0], 0))
    n0 = np.flatnonzero(np.isclose(x[:, 0], 0) & np.isclose(x[:, 1], 0))
    model = Model(m, [ly], [(0,)], np.zeros(m.n_elements, int), fixes=[Fix(n0, 0, (0,), (1, 2))],
                  symmetries=[Symmetry(x0, np.array([1.0, 0, 0]))],
                  edge_loads=[EdgeLoad(_edges(m, np.isclose(x[:, 0], 10.0)), np.array([1.0, 0, 0]),
                                       lambda theta3, **kw: 12 * M * (theta3 - 0.5))],
                  nonlinear=False)
    pb = Problem.build(model)
    st = list(load_steps(pb, np.array([1.0])))[-1]
    w = []
    for corner in ([10.0, 0.0], [0.0, 0.0]):
        node = int(np.argmin(np.linalg.norm(x[:, :2] - corner, axis=1)))
        el, loc = np.argwhere(m.elements == node)[0]
        w.append(evaluate_points(model, pb.dm, st.u, [el], NODE_XI[loc, 0], NODE_XI[loc, 1], [0.5]).u[0, 2])
    assert np.isclose(abs(w[0] - w[1]), M * 10.0 ** 2 / (2 * E / 12), rtol=1e-9)


def test_cantilever_on_a_graded_mesh_matches_beam_theory():
    """The thick cantilever (examples/cantilever_thick.toml) on 6 elements refined towards the
    clamp (ratio 3) with a node line at x = 3.3: w_tip within 0.6 % of Timoshenko's 4.0336 cm,
    as on the uniform mesh."""
    res = run_example("cantilever_thick", {"nx = 5": "nx = 6\nlines_x = [3.3]\nrefine_x = [0]\nrefine_ratio_x = 3"})
    assert res.converged
    x = res.problem.model.mesh.nodes[:, 0]
    assert np.any(x == 3.3)
    assert abs(res.summary["probes"]["w_tip"] / 4.0336 - 1) < 0.006


# ------------------------------------------------------------------ bad input (CLI, exit 2)
def _mesh(**keys):
    return _all(*(_set(f"mesh.{k}", v) for k, v in keys.items()))


@pytest.mark.parametrize("name, keys, fields", [
    ("outside", {"lines_x": [3.0, 12.0]}, ("lines_x[1] = 12.0", "outside", "x from 0 to 10")),
    ("refine_outside", {"refine_y": [-0.5], "refine_ratio_y": 2.0}, ("refine_y[0]", "outside", "y from 0 to 1")),
    ("ratio_zero", {"refine_x": [0.0], "refine_ratio_x": 0.0}, ("mesh.refine_ratio_x", "greater than or equal to 1")),
    ("ratio_negative", {"refine_x": [0.0], "refine_ratio_x": -2.0}, ("mesh.refine_ratio_x", "greater than or equal")),
    ("not_a_number", {"lines_x": ["a"]}, ("mesh.lines_x[0]", "valid number")),
    ("not_a_list", {"lines_x": 3.0}, ("mesh.lines_x", "valid list")),
    ("ratio_without_lines", {"refine_ratio_x": 3.0}, ("refine_ratio_x = 3.0 needs refine_x", "refine_x = [0, 10]")),
    ("lines_without_ratio", {"refine_x": [0.0]}, ("refine_x needs refine_ratio_x > 1",)),
    ("with_grading", {"refine_x": [0.0], "refine_ratio_x": 3.0, "grading_x": 2.0},
     ("grading_x", "refine_x = [0]")),
    ("too_few_elements", {"lines_x": [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]}, ("lines_x", "nx", "at least 7 elements")),
    ("unreachable_ratio", {"lines_x": [1.0, 2.0, 3.0], "refine_x": [1.0], "refine_ratio_x": 1.5},
     ("refine_ratio_x", "cannot be reached", "more elements")),
])
def test_bad_node_lines_are_one_clear_paragraph(tmp_path, name, keys, fields):
    o = _outcome(tmp_path, name, Case("cantilever_thick.toml", _mesh(**keys), inprocess=True))
    _assert_error(o, fields)


# ------------------------------------------------------------------ stack boundaries
_TRC = [{"name": "beam", "material": "mat", "thickness": 1.0, "directors": 3},
        {"name": "trc", "material": "mat", "thickness": 0.1, "directors": 1}]


def _stacks(where: str):
    return _all(_set("layers", _TRC),
                _set("stacks", [{"layers": ["beam", "trc"], "where": where}, {"layers": ["beam"]}]))


def test_stack_boundary_through_elements_names_the_node_lines(tmp_path):
    """A TRC layer on 1 < x < 9 over elements of 2 cm: the stack would take the elements whose
    centre lies inside (x from 0 to 10 or 2 to 8, not 1 to 9); an error names lines_x = [1, 9]."""
    o = _outcome(tmp_path, "cut", Case("cantilever_thick.toml", _stacks("x > 1 and x < 9"), inprocess=True))
    msg = _assert_error(o, ("stacks[0].where", "element edges", "lines_x = [1, 9]"))
    assert "lines_y" not in msg


def test_stack_boundary_in_both_directions(tmp_path):
    o = _outcome(tmp_path, "cut_xy", Case("cantilever_thick.toml", _all(_stacks("x > 1 and y < 0.3"),
                                                                          _set("mesh.ny", 2)), inprocess=True))
    _assert_error(o, ("stacks[0].where", "lines_x = [1]", "lines_y = [0.3]"))


def test_stack_boundary_on_the_named_node_lines_is_accepted(tmp_path):
    """With the node lines the error asks for (and the boundary on element edges already), the
    model is accepted and each element carries the stack its centre selects."""
    from layershell.io.build import load

    fixed = Case("cantilever_thick.toml", _all(_stacks("x > 1 and y < 0.3"), _mesh(ny=2, lines_x=[1.0],
                                                                                 lines_y=[0.3])), inprocess=True)
    o = _outcome(tmp_path, "fixed", fixed)
    assert o.returncode == 0 and "OK" in o.stdout, o.stderr
    spec = load(tmp_path / "fixed" / "model.toml")
    c = spec.model.mesh.nodes[spec.model.mesh.elements[:, 8]]
    assert np.array_equal(spec.model.element_stack == 0, (c[:, 0] > 1) & (c[:, 1] < 0.3))
    on_edges = Case("cantilever_thick.toml", _stacks("x > 2 and x < 8"), inprocess=True)
    assert _outcome(tmp_path, "on_edges", on_edges).returncode == 0


def test_the_user_guide_example_builds_the_mesh_it_describes():
    """The [mesh] example of docs/user-guide.md: node lines at 0.1, 1.5 and 2.9, elements at the
    plate ends 10 times shorter than the longest."""
    import re
    import tomllib
    from pathlib import Path

    from layershell.io.build import _mesh
    from layershell.io.schema import RectangleMesh

    guide = (Path(__file__).resolve().parents[1] / "docs" / "user-guide.md").read_text(encoding="utf-8")
    block = next(b for b in re.findall(r"```toml\n(.*?)```", guide, re.S) if "refine_ratio_x" in b)
    block = "\n".join(line.strip() for line in block.splitlines())
    m = _mesh(RectangleMesh.model_validate(tomllib.loads(block)["mesh"]), Path("."))
    el, cx = _lengths(m, 0), _corners(m, 0)
    assert all(np.any(cx == v) for v in (0.1, 1.5, 2.9))
    assert abs(el.max() / el.min() / 10.0 - 1) < 1e-3
    k = np.flatnonzero(cx == 0.1)[0]
    assert el.min() == min(el[k - 1], el[k])  # the shortest element touches a plate end
