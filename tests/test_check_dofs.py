"""`layershell check` reports the DOF counts that `run` solves with: the unknowns after the
supports, bonds and ties at the start of the run (an initially debonded zone of the stress-criterion
law and a cohesive interface, whose layers keep their own DOFs, add unknowns), and all DOFs of the
layers. The command line runs in-process (typer's CliRunner) on a two-layer strip written into a
temporary folder; the interface is strong enough that nothing debonds in the one linear step."""
from __future__ import annotations

import json
import os
import re
from pathlib import Path

import pytest
from typer.testing import CliRunner

from layershell.cli import app

STRIP = """
[model]
units = "kN, m"
nonlinear = false

[mesh]
type = "rectangle"
lx = 1.0
ly = 0.2
nx = 10
ny = 1

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

[[interfaces]]
layer = "trc"
sigma_max = 1000.0
tau_max = 2000.0
initially_debonded = [{{ where = "x < 0.3" }}]
{law}
"""

COUNTS = re.compile(r"(\d+) unknowns after constraints \((\d+) DOFs in all\)")


def _cli(folder: Path, args: list[str]):
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        return CliRunner().invoke(app, args, env={"LAYERSHELL_TRACEBACK": None, "NO_COLOR": "1", "COLUMNS": "400"})
    finally:
        os.chdir(cwd)


@pytest.mark.parametrize("law", ['law = "thesis"', 'law = "cohesive"\nG_Ic = 0.5\nG_IIc = 1.0'])
def test_check_counts_the_dofs_of_run(tmp_path, law):
    """check and run print the same counts, and they are summary.json's n_dofs and n_dofs_full.
    Before, check counted the fully bonded stack, fewer unknowns than run solves."""
    (tmp_path / "strip.toml").write_text(STRIP.format(law=law), encoding="utf-8")
    checked = _cli(tmp_path, ["check", "strip.toml"])
    assert checked.exit_code == 0, checked.output
    ran = _cli(tmp_path, ["run", "strip.toml", "-o", "out"])
    assert ran.exit_code == 0, ran.output
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    in_check = COUNTS.search(" ".join(checked.output.split()))
    in_run = COUNTS.search(" ".join(ran.output.split()))
    assert in_check and in_run, (checked.output, ran.output)
    assert in_check.groups() == in_run.groups() == (str(summary["n_dofs"]), str(summary["n_dofs_full"]))
    from layershell.constraints import constraint_operator
    from layershell.dofs import number_dofs
    from layershell.io.build import load

    model = load(tmp_path / "strip.toml").model
    bonded = constraint_operator(model, number_dofs(model)).n_red  # the fully bonded stack
    assert summary["n_dofs"] > bonded  # the model tells the two counts apart
