"""`layershell sweep`: dotted-path variants of a model file, run in parallel processes.

References: each sweep row must equal a separate run of the model file edited as text (a second,
independent path through the code), a linear model's deflection must scale exactly with 1/E,
and the thick cantilever's deflection must match Timoshenko's beam theory (MODEL.md V2:
w = 4.0336 cm, layershell within 1 %).
"""
from __future__ import annotations

import csv
from pathlib import Path

import pytest
from typer.testing import CliRunner

from layershell.cli import app
from layershell.io.build import InputError, build, parse
from layershell.report import render
from layershell.runner import run
from layershell.sweep import (get_path, parse_assignment, parse_value, read_model, set_path, split_top_level,
                              sweep, variants)

ROOT = Path(__file__).resolve().parents[1]
CANTILEVER = ROOT / "examples" / "cantilever_thick.toml"
W_TIMOSHENKO = 4.0336  # cm, thesis §3.5.1 / MODEL.md V2 (E = 1e5 N/cm², ν = 0.4)


def test_values_and_paths():
    assert split_top_level("[1, 2],3,'a,b'") == ["[1, 2]", "3", "'a,b'"]
    assert parse_value("1e5") == 1e5 and parse_value("10") == 10 and parse_value("true") is True
    assert parse_value("explicit") == "explicit" and parse_value("[1, 0, 0]") == [1, 0, 0]
    assert parse_value("inf") == float("inf")
    assert parse_assignment("interfaces.0.tau_max=1.0,1.2") == ("interfaces.0.tau_max", [1.0, 1.2])
    doc = read_model(CANTILEVER)
    assert get_path(doc, "layers.0.thickness") == 1.0
    set_path(doc, "layers.0.thickness", 2.0)
    set_path(doc, "steps.max_iterations", 7)  # a key left at its default is created
    set_path(doc, "delamination.max_release", 3)  # so is a missing top-level section
    assert doc["layers"][0]["thickness"] == 2.0 and doc["steps"]["max_iterations"] == 7
    assert doc["delamination"] == {"max_release": 3}
    assert len(variants(doc, [("steps.n", [1, 2]), ("materials.mat.E", [1.0, 2.0, 3.0])])) == 6


@pytest.mark.parametrize("arg, words", [
    ("layers.3.thickness=1", ["layers.3.thickness", "index 3 does not exist"]),
    ("material.mat.E=1", ["material.mat.E", "did you mean 'materials'"]),
    ("layers.first.thickness=1", ["layers.first.thickness", "index"]),
    ("steps.n.x=1", ["steps.n.x", "not a table"]),
])
def test_bad_paths_name_the_key(arg, words):
    doc = read_model(CANTILEVER)
    with pytest.raises(InputError) as exc:
        variants(doc, [parse_assignment(arg)])
    assert all(w in str(exc.value) for w in words), str(exc.value)


@pytest.mark.parametrize("args, words", [
    (["--set", "steps.nn=3"], ["steps.nn", "did you mean 'n'"]),
    (["--set", "steps.n=abc"], ["steps.n", "integer"]),
    (["--set", "materials.mat.E=1e5,-2"], ["materials.mat", "variant 1", "must be positive"]),
    (["--set", "layers.3.thickness=1"], ["layers.3.thickness"]),
    (["--set", "steps.n"], ["KEY=VALUE"]),
    (["--set", "steps.n=1,,2"], ["empty value"]),
])
def test_cli_bad_input_exit_2(args, words, tmp_path):
    r = CliRunner().invoke(app, ["sweep", str(CANTILEVER), "--out", str(tmp_path / "s"), *args])
    text = " ".join(r.output.split())
    assert r.exit_code == 2, r.output
    assert "Traceback" not in r.output and all(w in text for w in words), text
    assert not (tmp_path / "s" / "sweep.csv").exists()  # validated before anything runs


def _direct(E: float, n: int) -> float:
    """w_tip of the cantilever file edited as text (no dotted paths involved)."""
    text = CANTILEVER.read_text()
    assert "E = 100000.0" in text and "n = 1\n" in text
    text = text.replace("E = 100000.0", f"E = {E!r}").replace("n = 1\n", f"n = {n}\n", 1)
    res = run(build(parse(text, str(CANTILEVER)), CANTILEVER.parent))
    assert res.converged
    return res.summary["probes"]["w_tip"]


def test_sweep_parallel_matches_direct_runs(tmp_path):
    res = sweep(CANTILEVER, [parse_assignment("materials.mat.E=1e5,2e5"), parse_assignment("steps.n=1,2")],
                tmp_path, jobs=2)
    with (tmp_path / "sweep.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["variant"] for r in rows] == ["v000", "v001", "v002", "v003"]
    assert [(float(r["materials.mat.E"]), int(r["steps.n"])) for r in rows] == [(1e5, 1), (1e5, 2), (2e5, 1), (2e5, 2)]
    assert all(r["converged"] == "True" and r["error"] == "" for r in rows) and res.failed == 0
    w = {(float(r["materials.mat.E"]), int(r["steps.n"])): float(r["w_tip"]) for r in rows}
    assert [int(r["steps"]) for r in rows] == [1, 2, 1, 2]
    # each variant wrote its own results
    assert all((tmp_path / r["folder"] / "summary.json").is_file() for r in rows)
    # the reports name the variant and tabulate the sweep
    named = "cantilever_thick.toml (sweep variant 3: materials.mat.E = 200000.0, steps.n = 2)"
    assert named in render(tmp_path / "v003")
    assert '<table id="sweep">' in render(tmp_path)
    # an independent run of the text-edited file gives the same number (CSV keeps 10 digits)
    assert w[(2e5, 2)] == pytest.approx(_direct(2e5, 2), rel=1e-9)
    # linear elasticity: w ∝ 1/E exactly; the step count does not matter for a linear model
    assert w[(1e5, 1)] == pytest.approx(2 * w[(2e5, 1)], rel=1e-8)
    assert w[(1e5, 1)] == pytest.approx(w[(1e5, 2)], rel=1e-8)
    # Timoshenko beam theory (independent reference)
    assert w[(1e5, 1)] == pytest.approx(W_TIMOSHENKO, rel=0.01)


def test_failed_variant_is_a_row(tmp_path):
    """A variant that does not converge (1 Newton iteration for a nonlinear solve, no bisection)
    is a row with converged = False and the solver's message; the CLI exits with 1, not a crash."""
    r = CliRunner().invoke(app, ["sweep", str(CANTILEVER), "--out", str(tmp_path), "-j", "1",
                                 "--set", "model.nonlinear=true,false", "--set", "steps.max_iterations=1",
                                 "--set", "steps.max_bisections=0"])
    assert r.exit_code == 1, r.output
    assert "1 of 2 variant(s) did not converge" in " ".join(r.output.split())
    with (tmp_path / "sweep.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert [r["converged"] for r in rows] == ["False", "True"]
    assert "no convergence" in rows[0]["error"] and rows[0]["w_tip"] == ""
    assert float(rows[1]["w_tip"]) == pytest.approx(4.0205, rel=1e-3)  # the linear solve (MITC9): one iteration
