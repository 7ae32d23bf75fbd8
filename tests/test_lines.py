"""[[lines]]: a field along a polyline, line_<name>.csv and line_<name>.png. The thick cantilever
of examples/cantilever_thick.toml (parabolic end shear P = 100 N, L = 10 cm, E = 10⁵ N/cm², ν = 0.4,
b = h = 1 cm): its deflection along the span against Timoshenko beam theory and against displacement
probes at the same nodes, its bending stress against M y / I; the soffit strip of
tests/test_probe_layers.py: the interface tractions along the span against traction probes at the
same points, empty where the soffit layer is absent. The command line runs in-process."""
from __future__ import annotations

import csv
import json
import os
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from layershell.cli import app

ROOT = Path(__file__).resolve().parents[1]
P, L, E, NU, B, H = 100.0, 10.0, 1.0e5, 0.4, 1.0, 1.0
I = B * H**3 / 12


def _cli(folder: Path, args: list[str]):
    cwd = os.getcwd()
    os.chdir(folder)
    try:
        return CliRunner().invoke(app, args, env={"LAYERSHELL_TRACEBACK": None, "NO_COLOR": "1", "COLUMNS": "400"})
    finally:
        os.chdir(cwd)


def _read(path: Path) -> dict[str, np.ndarray]:
    with path.open(newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    cols = list(zip(*rows[1:]))
    return {name: np.array([float(v) if v != "" else np.nan for v in col]) for name, col in zip(rows[0], cols)}


def _timoshenko(x):
    """Deflection of a cantilever under an end load P: bending and shear (κ = 5/6)."""
    G = E / (2 * (1 + NU))
    return P * x**2 * (3 * L - x) / (6 * E * I) + P * x / (5 / 6 * G * B * H)


CANTILEVER_LINES = """
[[lines]]
name = "deflection"
points = [[0, 0.5, 0], [10, 0.5, 0]]
samples = 11
quantity = "displacement"
components = ["z"]
scale = -1.0

[[lines]]
name = "bending"
points = [[0, 0.5, 0], [5, 0.5, 0], [10, 0.5, 0]]
samples = 11
quantity = "stress"
components = ["11"]
theta3 = 0.25
""" + "".join(f"""
[[probes]]
name = "w{i}"
quantity = "displacement"
point = [{i}, 0.5, 0]
component = "z"
scale = -1.0
""" for i in range(11))


def test_cantilever_lines_against_beam_theory_and_probes(tmp_path):
    """Deflection along the span within 0.5 % of the tip deflection of Timoshenko's w(x) and equal
    to displacement probes at the same nodes; σ11 at Θ³ = 0.25 (a
    quarter of the depth above the mid-plane; the reference face is the top face) within 1 % of
    M y / I = P (L - x) · 0.25 / I at the element mid-points x = 5, 7, 9. The samples of the
    second line: 11 per segment, the shared vertex x = 5 once (21 in all)."""
    text = (ROOT / "examples" / "cantilever_thick.toml").read_text(encoding="utf-8")
    (tmp_path / "cantilever.toml").write_text(text + CANTILEVER_LINES + "\n[output]\nvtu = false\n", encoding="utf-8")
    res = _cli(tmp_path, ["run", "cantilever.toml", "-o", "out", "-q"])
    assert res.exit_code == 0, res.output
    out = tmp_path / "out"
    w = _read(out / "line_deflection.csv")
    assert np.allclose(w["s"], np.arange(11.0)) and np.allclose(w["x"], w["s"]) and np.allclose(w["y"], 0.5)
    wt = _timoshenko(w["x"])
    assert np.abs(w["displacement_z"] - wt).max() < 5e-3 * wt[-1]  # measured 3.3e-3 (at the tip)

    probes = json.loads((out / "summary.json").read_text())["probes"]
    at_nodes = [probes[f"w{i}"] for i in range(11)]
    assert np.allclose(w["displacement_z"], at_nodes, rtol=1e-8, atol=1e-12)  # the CSV holds 10 digits
    s = _read(out / "line_bending.csv")
    assert np.allclose(s["x"], np.linspace(0, 10, 21)) and np.allclose(s["s"], s["x"])
    for x in (5.0, 7.0, 9.0):
        j = int(np.argmin(np.abs(s["x"] - x)))
        assert abs(s["x"][j] - x) < 1e-9
        assert s["stress_11"][j] == pytest.approx(P * (L - x) * 0.25 / I, rel=1e-2)
    for name in ("deflection", "bending"):
        assert (out / f"line_{name}.png").stat().st_size > 1000


SOFFIT_LINE = """
[[lines]]
name = "interface"
points = [[0, 0.1, 0], [1, 0.1, 0]]
samples = 21
quantity = "traction"
components = ["13", "33"]
layer = "trc"
""" + "".join(f"""
[[probes]]
name = "t13_{i}"
quantity = "traction"
point = [{x}, 0.1, 0]
layer = "trc"
component = "13"
""" for i, x in enumerate((0.1, 0.35, 0.7)))


def test_soffit_tractions_along_the_span(tmp_path):
    """The interface tractions below the soffit layer along the span: empty cells where the
    layer is absent (x < 0.1), τ equal to traction probes at x = 0.1 (the layer's end), 0.35 and
    0.7."""
    from test_probe_layers import STRIP

    (tmp_path / "strip.toml").write_text(STRIP.format(nx=10, grading=1.0, x_end=0.1) + SOFFIT_LINE,
                                         encoding="utf-8")
    res = _cli(tmp_path, ["run", "strip.toml", "-o", "out", "-q"])
    assert res.exit_code == 0, res.output
    t = _read(tmp_path / "out" / "line_interface.csv")
    assert np.allclose(t["x"], np.linspace(0, 1, 21))
    absent = t["x"] < 0.1 - 1e-9
    assert absent.sum() == 2 and np.isnan(t["traction_13"][absent]).all() and np.isnan(t["traction_33"][absent]).all()
    assert np.isfinite(t["traction_13"][~absent]).all()
    probes = json.loads((tmp_path / "out" / "summary.json").read_text())["probes"]
    for i, x in enumerate((0.1, 0.35, 0.7)):
        j = int(np.argmin(np.abs(t["x"] - x)))
        assert t["traction_13"][j] == pytest.approx(probes[f"t13_{i}"], rel=1e-8, abs=1e-9)
    assert abs(probes["t13_0"]) > 1.0


def _line(points="[[0, 0.1, 0], [1, 0.1, 0]]", components='["13", "33"]', layer='layer = "trc"') -> str:
    return (f'\n[[lines]]\nname = "interface"\npoints = {points}\nquantity = "traction"\ncomponents = {components}\n'
            f"{layer}\n")


@pytest.mark.parametrize("line, field", [
    (_line(points="[[0, 0.1, 0], [1, 0.1, 0.5]]"), "lines[0].points[1]"),
    (_line(components='["13", "xx"]'), "lines[0].components"),
    (_line(layer=""), "lines[0].layer"),
    (_line(points="[[0, 0.1, 0], [0.05, 0.1, 0]]"), "lines[0].layer"),
    (_line() + _line(), "lines"),
])
def test_bad_lines_are_input_errors(tmp_path, line, field):
    """A vertex off the reference surface, an unknown component, a traction line without a layer,
    a line only where the layer is absent, two lines of one name: `check` exits 2 and names the
    field."""
    from test_probe_layers import STRIP

    (tmp_path / "strip.toml").write_text(STRIP.format(nx=10, grading=1.0, x_end=0.1) + line, encoding="utf-8")
    res = _cli(tmp_path, ["check", "strip.toml"])
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert f"'{field}'" in text and "Traceback" not in text


def test_line_across_a_curved_shell_is_an_input_error(tmp_path):
    """On the half cylinder of examples/ring.toml (radius 5) a straight segment between two points
    of the surface at 0° and 180° runs through the axis, far from the shell: exit 2 naming
    'lines[0].points' and asking for vertices in between; with vertices every 15° the samples lie
    within 5 % of the segment length of the surface and the line is accepted."""
    text = (ROOT / "examples" / "ring.toml").read_text(encoding="utf-8")
    bad = '\n[[lines]]\nname = "arc"\npoints = [[5, 0, 1.5], [-5, 0, 1.5]]\nquantity = "displacement"\n' \
          'components = ["magnitude"]\n'
    (tmp_path / "ring.toml").write_text(text + bad, encoding="utf-8")
    res = _cli(tmp_path, ["check", "ring.toml"])
    assert res.exit_code == 2, res.output
    out = " ".join(res.output.split())
    assert "'lines[0].points'" in out and "leaves the shell" in out and "add vertices" in out
    many = bad.replace("[[5, 0, 1.5], [-5, 0, 1.5]]", "[" + ", ".join(
        f"[{5 * np.cos(a):.12g}, {5 * np.sin(a):.12g}, 1.5]" for a in np.linspace(0, np.pi, 13)) + "]")
    (tmp_path / "ring.toml").write_text(text + many, encoding="utf-8")
    res = _cli(tmp_path, ["check", "ring.toml"])
    assert res.exit_code == 0, res.output
