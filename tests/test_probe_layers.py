"""Probes on a layer that [[stacks]] leave out in part of the model: a clear error where the layer
is absent at the probe point, and the element that holds the layer at the point where the layer
ends (whatever the mesh numbering). The command line runs in-process (typer's CliRunner) on a
small strip written into a temporary folder: a concrete strip with a soffit layer that starts at
x = 0.1."""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from typer.testing import CliRunner

from layershell.cli import app

STRIP = """
[model]
title = "strip with a soffit layer that stops short of the support"
units = "kN, m"
nonlinear = false

[mesh]
type = "rectangle"
lx = 1.0
ly = 0.2
nx = {nx}
ny = 1
normal = "-z"
grading_x = {grading}

[materials.concrete]
type = "isotropic"
E = 3.0e7
nu = 0.2

[materials.trc]
type = "isotropic"
E = 1.0e7
nu = 0.2

[[layers]]
name = "concrete"
material = "concrete"
thickness = 0.16

[[layers]]
name = "trc"
material = "trc"
thickness = 0.01

[[stacks]]
layers = ["concrete", "trc"]
where = "x > {x_end}"

[[stacks]]
layers = ["concrete"]
where = "x < {x_end}"

[[supports]]
type = "fix"
where = "near(x, 0)"
layer = "concrete"
directors = "all"

[[loads]]
type = "surface"
direction = [0, 0, -1]
magnitude = 10.0

[steps]
n = 1

[output]
vtu = false
plots = false
"""


def _cli(folder: Path, args: list[str]):
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        return CliRunner().invoke(app, args, env={"LAYERSHELL_TRACEBACK": None, "NO_COLOR": "1", "COLUMNS": "400"})
    finally:
        os.chdir(cwd)


def _write(folder: Path, probes: str, nx: int = 10, grading: float = 1.0, x_end: float = 0.1) -> Path:
    path = folder / "strip.toml"
    path.write_text(STRIP.format(nx=nx, grading=grading, x_end=x_end) + probes, encoding="utf-8")
    return path


def _probe(name: str, quantity: str, point, component: str, layer: str = "trc", extra: str = "") -> str:
    return (f'\n[[probes]]\nname = "{name}"\nquantity = "{quantity}"\npoint = {list(point)}\nlayer = "{layer}"\n'
            f'component = "{component}"\n{extra}')


@pytest.mark.parametrize("probe, field", [
    (_probe("tau", "traction", [0.05, 0.1, 0], "13"), "probes[0].point"),
    (_probe("s11", "stress", [0.05, 0.1, 0], "11", extra="theta3 = 0.165\n"), "probes[0].point"),
    (_probe("w", "displacement", [0.0, 0.1, 0], "z"), "probes[0].point"),
])
def test_probe_on_absent_layer_is_an_input_error(tmp_path, probe, field):
    """A traction, stress or displacement probe on the soffit layer where [[stacks]] leave it out
    (x < 0.1): exit 2 naming the probe's layer, the point field to move and the layers present
    there (before: the traction probe read τ = 0, σ33 = -10, the applied load, and the others
    read numbers of a layer that is not there)."""
    _write(tmp_path, probe)
    res = _cli(tmp_path, ["check", "strip.toml"])
    assert res.exit_code == 2, res.output
    assert "Traceback" not in res.output
    text = " ".join(res.output.split())
    assert "'probes[0].layer'" in text and "'trc' is absent" in text
    assert f"'{field}'" in text and "['concrete']" in text


def test_probe_at_layer_end_reads_the_layer(tmp_path):
    """A traction probe exactly at the layer's end reads the element that holds the layer: the
    same τ and σ33 as 10⁻⁷ inside it, on a uniform mesh (the two elements at the end are equally
    near and the unplated one has the lower number) and on a mesh graded towards the support (the
    unplated element's centre is the nearer one). Before, the probe read the unplated element:
    τ = 0 and σ33 = -10 (the applied load)."""
    from layershell.mesh import graded

    for nx, grading in ((10, 1.0), (12, 3.0)):
        x_end = 0.1 if grading == 1.0 else float(graded(nx, grading)[4])  # the end of the second element
        probes = "".join(_probe(f"t{c}_{tag}", "traction", [x, 0.1, 0], c)
                         for c in ("13", "33") for tag, x in (("end", x_end), ("in", x_end + 1e-7)))
        folder = tmp_path / f"m{nx}"
        folder.mkdir()
        _write(folder, probes, nx, grading, x_end)
        res = _cli(folder, ["run", "strip.toml", "-o", "out", "-q"])
        assert res.exit_code == 0, res.output
        p = json.loads((folder / "out" / "summary.json").read_text())["probes"]
        assert abs(p["t13_in"]) > 1.0  # the bond shear at the end
        assert p["t13_end"] == pytest.approx(p["t13_in"], rel=1e-4)
        assert p["t33_end"] == pytest.approx(p["t33_in"], rel=1e-4)


def test_load_on_absent_layer_fails_check(tmp_path):
    """`check` builds the loads as `run` does: a nodal load on the soffit layer at x = 0, where
    [[stacks]] leave it out, is exit 2 naming 'loads' in both (before: check said OK and run
    stopped with an internal error)."""
    load = '\n[[loads]]\ntype = "nodal"\nwhere = "near(x, 0)"\nlayer = "trc"\nvalue = [0, 0, 1]\n'
    _write(tmp_path, load)
    for command in (["check", "strip.toml"], ["run", "strip.toml", "-o", "out", "-q"]):
        res = _cli(tmp_path, command)
        assert res.exit_code == 2, res.output
        text = " ".join(res.output.split())
        assert "'loads'" in text and "'trc' does not exist" in text and "Traceback" not in text
