"""Issue 15, item 7: input that used to be accepted silently, misreported or slow now gets one
paragraph naming the cause and the fix (exit code 2), or a warning.

Each case mutates an example (the helpers of tests/test_cli.py) and calls the command line in
process (typer's CliRunner), with the same checks as tests/test_cli.py: exit code, no traceback,
one paragraph, the field and the fix named.
"""
from __future__ import annotations

import time
from pathlib import Path

import numpy as np
import pytest
from test_cli import EXAMPLES, Case, Outcome, _all, _delete, _describe, _prepare, _run_inprocess, _set

# a stress probe at mid-span (its height is set per case)
_STRESS_PROBE = {"name": "s11", "quantity": "stress", "point": [5.0, 0.5, 0.0], "component": "11", "theta3": 0.5}


def _append(path: str, item: dict):
    def mutate(d):
        d.setdefault(path, []).append(dict(item))
    return mutate


def _outcome(tmp_path: Path, name: str, case: Case, extra: list[str] | None = None) -> Outcome:
    args = _prepare(name, case, tmp_path)
    return _run_inprocess(args + (extra or []), tmp_path)


def _assert_error(o: Outcome, fields: tuple[str, ...], codes=(2,)) -> str:
    info = _describe(o)
    assert o.returncode in codes, info
    assert "Traceback" not in o.stderr + o.stdout, info
    msg = o.stderr.strip()
    assert msg.startswith("error:") and msg.count("error:") == 1, info
    assert all(line.strip() for line in msg.splitlines()), f"not one paragraph\n{info}"
    for f in fields:
        assert f in msg, f"{f!r} is not named\n{info}"
    return msg


# ------------------------------------------------------------------ byte-order mark
def test_utf8_byte_order_mark_is_accepted(tmp_path):
    """Windows editors write a BOM; it is not part of the TOML (it used to be 'Invalid statement line 1')."""
    o = _outcome(tmp_path, "bom", Case("cantilever_thick.toml", text=lambda t: "\ufeff" + t))
    assert o.returncode == 0 and "OK" in o.stdout and o.stderr.strip() == "", _describe(o)


def test_byte_order_mark_in_a_sweep(tmp_path):
    from layershell.sweep import read_model

    p = tmp_path / "m.toml"
    p.write_text("\ufeff" + (EXAMPLES / "ring.toml").read_text(encoding="utf-8"), encoding="utf-8")
    assert read_model(p)["mesh"]["type"] == "cylinder"


# ------------------------------------------------------------------ overlapping stacks
def test_overlapping_stacks_are_an_error(tmp_path):
    stacks = [{"layers": ["beam"], "where": "x < 6"}, {"layers": ["beam"], "where": "x > 4"}]
    o = _outcome(tmp_path, "overlap", Case("cantilever_thick.toml", _set("stacks", stacks)))
    _assert_error(o, ("stacks[1]", "stacks[0]", "x > 4", "x < 6", "disjoint"))


def test_two_stacks_without_selection_are_an_error(tmp_path):
    o = _outcome(tmp_path, "two_rest", Case("cantilever_thick.toml", _set("stacks", [{"layers": ["beam"]}] * 2)))
    _assert_error(o, ("stacks", "neither 'where' nor 'set'"))


@pytest.mark.parametrize("rest_first", [True, False])
def test_a_stack_without_selection_takes_the_remaining_elements(rest_first):
    """Independent of the order: the selected elements carry their stack, the others the rest stack."""
    import tomllib

    from layershell.io.build import build
    from layershell.io.schema import ModelFile

    d = tomllib.loads((EXAMPLES / "pulloff.toml").read_text(encoding="utf-8"))
    under, beside = d["stacks"]
    d["stacks"] = [{"layers": beside["layers"]}, under] if rest_first else [under, {"layers": beside["layers"]}]
    m = build(ModelFile.model_validate(d), EXAMPLES).model
    centres_y = m.mesh.nodes[m.mesh.elements[:, 8], 1]
    two = np.array([len(m.stacks[s]) == 2 for s in m.element_stack])
    assert np.array_equal(two, centres_y < 50) and 0 < two.sum() < two.size


# ------------------------------------------------------------------ a layer far too thick
def test_layer_thicker_than_the_model_is_a_unit_error(tmp_path):
    """It used to fail in the solver with 'the supports leave a rigid-body motion free'."""
    o = _outcome(tmp_path, "thick", Case("cantilever_thick.toml", _set("layers.0.thickness", 10000.0), command="run"),
                 ["--out", str(tmp_path / "out"), "--no-vtu", "--quiet"])
    msg = _assert_error(o, ("layers[0].thickness", "10000", "units"))
    assert "supports" not in msg and "rigid-body" not in msg
    assert not (tmp_path / "out").exists()  # refused before anything is solved


# ------------------------------------------------------------------ no load
def test_no_loads_is_warned(tmp_path):
    o = _outcome(tmp_path, "noload", Case("cantilever_thick.toml", _delete("loads")))
    assert o.returncode == 0 and "OK" in o.stdout, _describe(o)
    assert o.stderr.strip().startswith("warning:") and "no [[loads]]" in o.stderr and "zero" in o.stderr, _describe(o)


def test_no_loads_run_warns_and_runs(tmp_path):
    o = _outcome(tmp_path, "noload_run", Case("cantilever_thick.toml", _delete("loads"), command="run"),
                 ["--out", str(tmp_path / "out"), "--no-vtu", "--quiet"])
    assert o.returncode == 0, _describe(o)
    assert "warning:" in o.stderr and "no [[loads]]" in o.stderr, _describe(o)


def test_displacement_control_without_loads_is_not_warned(tmp_path):
    """A model loaded only by prescribed displacements (a fix with a 'value') is not 'unloaded'."""
    o = _outcome(tmp_path, "dcb", Case("dcb_cohesive.toml", lambda d: d))
    assert o.returncode == 0 and "OK" in o.stdout and "warning" not in o.stderr, _describe(o)


def test_zero_loads_are_warned(tmp_path):
    o = _outcome(tmp_path, "zeroload", Case("cantilever_thick.toml", _set("loads.0.distribution", 0.0)))
    assert o.returncode == 0 and "OK" in o.stdout, _describe(o)
    assert o.stderr.strip().startswith("warning:") and "every [[loads]] entry is zero" in o.stderr, _describe(o)


def test_gravity_without_density_is_an_error(tmp_path):
    o = _outcome(tmp_path, "gravity0", Case("cantilever_thick.toml", _set("loads", [{"type": "gravity"}])))
    _assert_error(o, ("loads[0]", "density", "[materials.mat]"))


def test_gravity_vector_zero_is_an_error(tmp_path):
    mutate = _all(_set("materials.mat.density", 1.0), _set("loads", [{"type": "gravity", "g": [0.0, 0.0, 0.0]}]))
    o = _outcome(tmp_path, "g0", Case("cantilever_thick.toml", mutate))
    _assert_error(o, ("loads[0].g", "9.81"))


def test_gravity_with_density_is_accepted(tmp_path):
    mutate = _all(_set("materials.mat.density", 1.0), _set("loads", [{"type": "gravity"}]))
    o = _outcome(tmp_path, "g_ok", Case("cantilever_thick.toml", mutate))
    assert o.returncode == 0 and o.stderr.strip() == "", _describe(o)


# ------------------------------------------------------------------ probes and profiles outside the shell
@pytest.mark.parametrize("theta3", [100.0, -0.5, [0.0, 1.5, 4]])
def test_stress_probe_outside_the_thickness_is_refused(tmp_path, theta3):
    """It used to extrapolate the director polynomials (σ11 ≈ -5e7 at Θ³ = 100 on a 1 cm beam)."""
    o = _outcome(tmp_path, "probe_out", Case("cantilever_thick.toml",
                                             _append("probes", {**_STRESS_PROBE, "theta3": theta3})))
    _assert_error(o, ("probes[1].theta3", "outside", "0 to 1"))


def test_displacement_probe_outside_the_layer_is_refused(tmp_path):
    o = _outcome(tmp_path, "probe_layer", Case("pulloff.toml", _set("probes.0.theta3", 120.0)))
    _assert_error(o, ("probes[0].theta3", "layer 'strap'"))


def test_stress_probe_on_the_faces_is_accepted(tmp_path):
    mutate = _all(_append("probes", {**_STRESS_PROBE, "theta3": 1.0}), _append("probes", {**_STRESS_PROBE,
                  "name": "s0", "theta3": [0.0, 1.0, 5], "reduce": "max"}))
    o = _outcome(tmp_path, "probe_ok", Case("cantilever_thick.toml", mutate))
    assert o.returncode == 0, _describe(o)


def test_profile_point_far_from_the_shell_is_refused(tmp_path):
    o = _outcome(tmp_path, "profile_out", Case("cantilever_thick.toml",
                                               _append("profiles", {"name": "p", "point": [500.0, 0.5, 0.0]})))
    _assert_error(o, ("profiles[0].point", "490", "reference surface"))


# ------------------------------------------------------------------ a selection that is a number
@pytest.mark.parametrize("path", ["supports.0.where", "loads.0.where"])
def test_numeric_selection_is_an_error(tmp_path, path):
    """where = "x" used to select the nodes with x != 0."""
    o = _outcome(tmp_path, "where_x", Case("cantilever_thick.toml", _set(path, "x")))
    _assert_error(o, (path.replace(".0.", "[0]."), "'x' is a number", "near(x, 0)"))


def test_numeric_stack_selection_is_an_error(tmp_path):
    o = _outcome(tmp_path, "stack_where", Case("cantilever_thick.toml", _set("stacks", [{"layers": ["beam"],
                                                                                       "where": "x - 1"}])))
    _assert_error(o, ("stacks[0].where", "not a condition"))


# ------------------------------------------------------------------ mesh files mixing quadrilaterals and triangles
def test_mesh_file_with_triangles_is_rejected(tmp_path):
    import meshio

    m = meshio.read(EXAMPLES / "plate_gmsh.msh")
    quads = np.concatenate([cb.data for cb in m.cells if cb.type == "quad9"])
    tri = quads[:3][:, [0, 1, 2, 4, 5, 8]]  # three 6-node triangles on existing nodes
    mutate = _set("mesh", {"type": "file", "path": "mixed.vtu"})
    args = _prepare("mixed", Case("plate_gmsh.toml", mutate), tmp_path)
    meshio.write(tmp_path / "mixed" / "mixed.vtu", meshio.Mesh(m.points, [("quad9", quads), ("triangle6", tri)]))
    o = _run_inprocess(args, tmp_path)
    _assert_error(o, ("mesh", "3 'triangle6'", f"{len(quads)} quadrilaterals", "RecombineAll"))


# ------------------------------------------------------------------ huge sweeps
def test_sweep_with_a_million_variants_is_refused_at_once(tmp_path):
    """It used to validate every variant silently (about 40 minutes) before solving any."""
    args = _prepare("sweep", Case("cantilever_thick.toml"), tmp_path)
    model = args[1]
    e_values = ",".join(str(1000.0 + i) for i in range(1000))
    n_values = ",".join(str(i) for i in range(1, 1001))
    t0 = time.perf_counter()
    o = _run_inprocess(["sweep", model, "--set", f"materials.mat.E={e_values}", "--set", f"steps.n={n_values}",
                        "--out", str(tmp_path / "out")], tmp_path)
    assert time.perf_counter() - t0 < 20
    _assert_error(o, ("1,000,000 variants", "1000 (materials.mat.E) × 1000 (steps.n)", "10,000"))
    assert not (tmp_path / "out").exists()


def test_sweep_reports_progress_while_checking_the_variants(tmp_path):
    """A long validation is not silent: ``checking(i, n)`` follows it (the CLI shows a progress bar)."""
    from layershell.io.build import InputError
    from layershell.sweep import sweep

    calls = []
    with pytest.raises(InputError, match="variant 2"):
        sweep(EXAMPLES / "cantilever_thick.toml", [("materials.mat.E", [1000.0, 2000.0, -1.0])], tmp_path / "out",
              checking=lambda i, n: calls.append((i, n)))
    assert calls == [(1, 3), (2, 3)]
    assert not (tmp_path / "out").exists()
