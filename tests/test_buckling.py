"""Linear eigenvalue buckling (src/layershell/buckling.py, `layershell buckle`) and geometric
imperfections ([imperfection], src/layershell/io/imperfection.py).

References: Euler's buckling loads of the cantilever column with Engesser's shear correction
(examples/column_buckling.toml, as in tests/test_stability.py), the sway column clamped at both
ends (effective length L) under a prescribed end shortening, the simply supported specially
orthotropic plate under uniaxial compression (N_cr = π²/b² (D11 m²/φ² + 2(D12 + 2 D66) +
D22 φ²/m²), φ = a/b, minimised over m; Timoshenko & Gere, Theory of Elastic Stability, §9.2 and
Lekhnitskii) and the isotropic square plate (k = 4), the linear axial shortening P L/(E A), the
amplification 1/(1 − P/P_cr) of an initial deflection affine to the first mode, and a
finite-difference derivative of the tangent."""
from __future__ import annotations

import json
import math
import warnings
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from helpers import EXAMPLES
from layershell.buckling import linear_buckling, reduced_tangent, stress_stiffness
from layershell.cli import app
from layershell.io.build import InputError, build, parse
from layershell.runner import run

E, L, B, T = 1000.0, 100.0, 10.0, 1.0  # N, mm: examples/column_buckling.toml
P_EULER = math.pi**2 * E * B * T**3 / 12 / (4 * L**2)
KAPPA_GA = 5 / 6 * E / 2 * B * T  # ν = 0


# the load of examples/column_buckling.toml
LOADS = ('[[loads]]               # λ = 1: Euler\'s load P_E, uniform through the thickness (N/mm²)\ntype = "edge"\n'
         'where = "near(x, 100)"\ndirection = [-1, 0, 0]\ndistribution = 0.02056167583560283\n')


def engesser(p_euler: float) -> float:
    """A buckling load with shear deformation (Engesser): P_E / (1 + P_E / (κ G A))."""
    return p_euler / (1 + p_euler / KAPPA_GA)


def column_text(nx: int = 8, steps: str = "[steps]\nn = 10\nlambda_end = 10.0\n") -> str:
    text = (EXAMPLES / "column_buckling.toml").read_text()
    for a, b in (("nx = 8\n", f"nx = {nx}\n"), ("[steps]\nn = 10\nlambda_end = 10.0\n", steps)):
        assert a in text
        text = text.replace(a, b)
    return text


def rel(a: float, b: float) -> float:
    return abs(a / b - 1)


def test_column_buckling_loads_against_engesser_on_three_meshes():
    """The cantilever column's first two buckling loads (λ = 1: Euler's first) against Euler's
    (2k − 1)² P_E with Engesser's shear correction: within 1 % on 4, 8 and 16 elements, the error
    of the second not growing with refinement, and within 2·10⁻⁴ on 8 elements."""
    errors = []
    for nx in (4, 8, 16):
        lam = linear_buckling(build(parse(column_text(nx))).model, 2).load_factors
        ref = [engesser((2 * k - 1) ** 2 * P_EULER) / P_EULER for k in (1, 2)]
        errors.append([rel(a, b) for a, b in zip(lam, ref)])
        assert max(errors[-1]) < 0.01, (nx, lam, ref)
    assert errors[1][0] < 2e-4 and errors[1][1] < 2e-4, errors
    assert errors[2][1] <= errors[0][1] + 1e-6, errors


def test_prestress_is_the_linear_state_and_the_stress_stiffness_is_the_tangent_derivative():
    """u₀ at the loaded end is the linear shortening −P L / (E A) (λ = 1: P = P_E); the stress
    stiffness K₁ (central difference over ±u₀) equals the one-sided finite-difference derivative
    (K_T(h u₀) − K_T(0)) / h of the nonlinear tangent for small h, to O(h)."""
    res = linear_buckling(build(parse(column_text(4))).model, 1)
    pb, u0 = res.problem, res.prestress
    tip = np.flatnonzero(np.isclose(pb.model.mesh.nodes[:, 0], L))
    ux = u0[pb.dm.layer_dofs[0][tip, 0, 0]]
    assert np.allclose(ux, -P_EULER * L / (E * B * T), rtol=1e-6), ux
    K1 = stress_stiffness(pb, u0).toarray()
    K0 = reduced_tangent(pb, np.zeros_like(u0)).toarray()
    errs = []
    for h in (1e-2, 1e-3):
        fd = (reduced_tangent(pb, h * u0).toarray() - K0) / h
        errs.append(np.abs(fd - K1).max() / np.abs(K1).max())
    assert errs[1] < 1e-3 and errs[1] < 0.2 * errs[0], errs


def test_prescribed_shortening_buckles_the_sway_column():
    """The column clamped at both ends, the loaded end free to sway and shortened by the
    prescribed δ = P_E L / (E A) per unit λ (no force): the buckling factor is that of the
    effective length L, 4 P_E with Engesser's correction, within 1 %; the prestress state is the
    bar's linear shortening u = −δ x / L."""
    delta = P_EULER * L / (E * B * T)
    text = column_text(8).replace(
        '[[loads]]               # λ = 1: Euler\'s load P_E, uniform through the thickness (N/mm²)\ntype = "edge"\n'
        'where = "near(x, 100)"\ndirection = [-1, 0, 0]\ndistribution = 0.02056167583560283\n',
        f'[[supports]]\ntype = "fix"\nwhere = "near(x, 100)"\ndirectors = "all"\ncomponents = ["x"]\n'
        f'value = [{-delta!r}]\n')
    assert LOADS not in text and "value = [" in text
    res = linear_buckling(build(parse(text)).model, 1)
    pb = res.problem
    x = pb.model.mesh.nodes[:, 0]
    ux = res.prestress[pb.dm.layer_dofs[0][:, 0, 0]]  # the linear state: u = −δ x / L along the bar
    assert np.allclose(ux, -delta * x / L, rtol=0, atol=1e-9 * delta), ux
    lam = res.load_factors[0]
    assert rel(lam, engesser(4 * P_EULER) / P_EULER) < 0.01, lam


# ---------------------------------------------------------------- plates
ORTHO = dict(E1=140000.0, E2=10000.0, G12=5000.0, nu12=0.3)  # N/mm², a carbon/epoxy ply
ISO = dict(E=70000.0, nu=0.3)


def plate_text(a: float, b: float, t: float, nx: int, ny: int, material: str) -> str:
    """A plate a × b × t, simply supported at mid-thickness on all edges, held along x at x = 0,
    compressed by a unit edge force per length at x = a (λ = 1: N = 1 N/mm)."""
    return f"""
[model]
nonlinear = false
[mesh]
type = "rectangle"
lx = {a}
ly = {b}
nx = {nx}
ny = {ny}
[materials.m]
{material}
[[layers]]
name = "plate"
material = "m"
thickness = {t}
directors = 2
[[supports]]
type = "fix"
where = "near(x, 0) or near(x, {a}) or near(y, 0) or near(y, {b})"
components = ["z"]
height = {t / 2}
[[supports]]
type = "fix"
where = "near(x, 0)"
components = ["x"]
height = {t / 2}
[[supports]]
type = "fix"
point = [0, 0, 0]
components = ["y"]
height = {t / 2}
[[loads]]
type = "edge"
where = "near(x, {a})"
direction = [-1, 0, 0]
distribution = {1.0 / t}
"""


def orthotropic_plate_loads(a: float, b: float, t: float) -> list[float]:
    """N_cr of the simply supported specially orthotropic plate for m = 1, 2, ... half-waves."""
    E1, E2, G12, n12 = ORTHO["E1"], ORTHO["E2"], ORTHO["G12"], ORTHO["nu12"]
    den = 12 * (1 - n12 * n12 * E2 / E1)
    D11, D22, D12, D66 = E1 * t**3 / den, E2 * t**3 / den, n12 * E2 * t**3 / den, G12 * t**3 / 12
    phi = a / b
    return [math.pi**2 / b**2 * (D11 * m**2 / phi**2 + 2 * (D12 + 2 * D66) + D22 * phi**2 / m**2) for m in range(1, 6)]


def test_orthotropic_plate_against_the_closed_form_on_three_meshes():
    """The simply supported 200 × 100 × 1 mm carbon/epoxy plate (0° along the load): the first
    two buckling loads (m = 1 and 2 half-waves) against the closed form, within 1 % on 8 × 4 and
    12 × 6 elements (the 4 × 2 mesh is 1 % off); the first converges (its change from 8 × 4 to
    12 × 6 is under a fifth of that from 4 × 2 to 8 × 4)."""
    a, b, t = 200.0, 100.0, 1.0
    mat = ('type = "orthotropic"\nE1 = 140000.0\nE2 = 10000.0\nE3 = 10000.0\nG12 = 5000.0\nG23 = 3500.0\n'
           'G31 = 5000.0\nnu12 = 0.3\nnu23 = 0.4\nnu13 = 0.3')
    ref = sorted(orthotropic_plate_loads(a, b, t))
    got = [linear_buckling(build(parse(plate_text(a, b, t, 2 * n, n, mat))).model, 2).load_factors
           for n in (2, 4, 6)]
    for lam in got[1:]:
        assert rel(lam[0], ref[0]) < 0.01 and rel(lam[1], ref[1]) < 0.01, (lam, ref[:2])
    assert abs(got[2][0] - got[1][0]) < 0.2 * abs(got[1][0] - got[0][0]), got


def test_isotropic_square_plate_k4():
    """The simply supported square aluminium plate (b/t = 100): N_cr = 4 π² D / b² within 1 %."""
    a = b = 100.0
    t = 1.0
    D = ISO["E"] * t**3 / (12 * (1 - ISO["nu"] ** 2))
    lam = linear_buckling(build(parse(plate_text(a, b, t, 6, 6, 'type = "isotropic"\nE = 70000.0\nnu = 0.3'))).model,
                          1).load_factors[0]
    assert rel(lam, 4 * math.pi**2 * D / b**2) < 0.01, (lam, 4 * math.pi**2 * D / b**2)


# ---------------------------------------------------------------- CLI and imperfections
def buckle(tmp_path: Path, text: str, *args: str):
    model = tmp_path / "model.toml"
    model.write_text(text)
    return CliRunner().invoke(app, ["buckle", str(model), *args])


@pytest.fixture(scope="module")
def column_modes(tmp_path_factory) -> Path:
    """`layershell buckle` of the perfect column (8 elements), 2 modes."""
    folder = tmp_path_factory.mktemp("column")
    r = buckle(folder, column_text(8), "--modes", "2", "--out", str(folder / "modes"))
    assert r.exit_code == 0, r.output
    return folder / "modes"


def test_buckle_command_writes_the_modes(column_modes):
    """buckling.json/csv hold the load factors of the API, one VTU per mode, the figure and the
    mode file with the nodes of the mesh."""
    s = json.loads((column_modes / "buckling.json").read_text())
    assert [m["mode"] for m in s["modes"]] == [1, 2]
    assert np.allclose(s["load_factors"], linear_buckling(build(parse(column_text(8))).model, 2).load_factors,
                       rtol=1e-8)
    assert (column_modes / "buckling.csv").read_text().splitlines()[0] == "mode,load_factor"
    for f in ("buckling_mode_1.vtu", "buckling_mode_2.vtu", "buckling_modes.png", "buckling_modes.npz"):
        assert (column_modes / f).stat().st_size > 0
    with np.load(column_modes / "buckling_modes.npz") as d:
        assert d["displacement"].shape == (2, d["nodes"].shape[0], 3)
        assert np.abs(d["displacement"][0][:, 2]).max() == pytest.approx(1.0)  # scaled to the face translation


def imperfect_column(folder: Path, amplitude: str = "0.1", mode: str = "1", extra: str = "") -> str:
    steps = "[steps]\nfactors = [0.2, 0.4, 0.6, 0.8, 0.9]\n"
    return (column_text(8, steps) + f'\n[imperfection]\nmode = {mode}\nfolder = "{folder}"\n'
            f"amplitude = {amplitude}\n{extra}")


def test_imperfect_column_amplifies_its_initial_deflection(column_modes):
    """The column with the first mode as initial deflection w₀ = 0.1 mm at the tip: the nodes
    move by w₀ × the mode along the normal; the nonlinear run's tip deflection follows
    w₀ (λ/λ_cr) / (1 − λ/λ_cr) within 1 % up to 0.9 λ_cr, and Southwell's line through the last
    states (w/λ against w) gives λ_cr within 1 %."""
    lam_cr = json.loads((column_modes / "buckling.json").read_text())["load_factors"][0]
    spec = build(parse(imperfect_column(column_modes)))
    perfect = build(parse(column_text(8))).model.mesh.nodes
    moved = spec.model.mesh.nodes - perfect
    assert np.allclose(moved[:, :2], 0.0) and np.abs(moved[:, 2]).max() == pytest.approx(0.1)
    tip = np.isclose(perfect[:, 0], L)
    assert np.allclose(moved[tip, 2], 0.1)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = run(spec, None, write_vtu=False)
    assert r.converged, r.message
    lam = np.array([s["load_factor"] for s in r.summary["steps"]])
    w = np.array([s["probes"]["w_tip"] for s in r.summary["steps"]])
    amplified = 0.1 * (lam / lam_cr) / (1 - lam / lam_cr)
    assert np.all(np.abs(w / amplified - 1) < 0.01), (w, amplified)
    slope = np.polyfit(w[-3:], w[-3:] / lam[-3:], 1)[0]  # Southwell: w/λ = w/λ_cr + w₀/λ_cr
    assert rel(1 / slope, lam_cr) < 0.01, (1 / slope, lam_cr)


def test_formula_imperfection_moves_the_nodes_along_the_normal():
    """A formula imperfection: every node moves by amplitude × formula(x, y, z) along the normal
    (+z on the flat plate)."""
    text = column_text(4) + '\n[imperfection]\nformula = "x * (100 - x) / 2500"\namplitude = 0.5\n'
    nodes = build(parse(text)).model.mesh.nodes
    x = nodes[:, 0]
    assert np.allclose(nodes[:, 2], 0.5 * x * (100 - x) / 2500)


@pytest.mark.parametrize("case, field", [
    (dict(mode="3"), "imperfection.mode"),
    (dict(amplitude='"large"'), "imperfection.amplitude"),
    (dict(folder_missing=True), "imperfection.folder"),
    (dict(extra='formula = "x"\n'), "imperfection"),
])
def test_bad_imperfection_is_refused_by_name(column_modes, tmp_path, case, field):
    """A mode that the file does not hold, a non-number amplitude, a folder without modes, and
    both a mode and a formula: InputError naming the field and the fix."""
    folder = tmp_path / "nowhere" if case.get("folder_missing") else column_modes
    text = imperfect_column(folder, case.get("amplitude", "0.1"), case.get("mode", "1"), case.get("extra", ""))
    with pytest.raises(InputError) as exc:
        build(parse(text))
    msg = str(exc.value)
    assert f"'{field}" in msg or f"{field}:" in msg or field in msg, msg
    if case.get("mode"):
        assert "holds 2 mode(s)" in msg and "layershell buckle" in msg
    if case.get("folder_missing"):
        assert "layershell buckle" in msg


def test_modes_of_another_mesh_are_refused(column_modes):
    """Modes written for the 8-element column applied to the 4-element one: refused."""
    text = imperfect_column(column_modes).replace("nx = 8\n", "nx = 4\n")
    with pytest.raises(InputError, match="another mesh"):
        build(parse(text))


def test_buckle_refuses_bad_options(tmp_path):
    """A model without loads, --modes 0 and supports that leave a rigid-body motion: exit code 2
    with one paragraph, no traceback."""
    text = column_text(4).replace(LOADS, "")
    assert LOADS not in column_text(4).replace(LOADS, "") and LOADS in column_text(4)
    r = buckle(tmp_path, text, "--out", str(tmp_path / "o2"))
    assert r.exit_code == 2 and "no loads" in r.output, r.output
    r = buckle(tmp_path, column_text(4), "--modes", "0")
    assert r.exit_code == 2, r.output
    loose = column_text(4).replace('components = ["x", "y", "z"]', 'components = ["x", "z"]')  # free along y
    r = buckle(tmp_path, loose, "--out", str(tmp_path / "o3"))
    assert r.exit_code == 2 and "rigid-body motion" in r.output, r.output


def test_superlu_gives_the_same_loads():
    """Both linear-solver backends factorise K₀: the same buckling loads to 10⁻⁸."""
    model = build(parse(column_text(4))).model
    assert np.allclose(linear_buckling(model, 2, "superlu").load_factors, linear_buckling(model, 2).load_factors,
                       rtol=1e-8)


def test_imperfect_plate_follows_the_amplification_towards_its_buckling_load(tmp_path):
    """The simply supported square plate (b/t = 100, 6 × 6): its first mode is sin(πx/a) sin(πy/b)
    (MAC > 0.999); with that mode as initial deflection w₀ = 0.01 t, the nonlinear run's centre
    deflection follows w₀ (λ/λ_cr)/(1 − λ/λ_cr) within 1 % up to 0.8 λ_cr and within 3 % at
    0.89 λ_cr, where the membrane stiffening of the deflected plate begins (w = 0.08 t)."""
    a = b = 100.0
    base = plate_text(a, b, 1.0, 6, 6, 'type = "isotropic"\nE = 70000.0\nnu = 0.3')
    r = buckle(tmp_path, base, "--modes", "1", "--out", str(tmp_path / "modes"))
    assert r.exit_code == 0, r.output
    lam_cr = json.loads((tmp_path / "modes" / "buckling.json").read_text())["load_factors"][0]
    with np.load(tmp_path / "modes" / "buckling_modes.npz") as d:
        X, w_mode = d["nodes"], d["displacement"][0][:, 2]
    shape = np.sin(np.pi * X[:, 0] / a) * np.sin(np.pi * X[:, 1] / b)
    assert (w_mode @ shape) ** 2 / ((w_mode @ w_mode) * (shape @ shape)) > 0.999
    text = base.replace("nonlinear = false", "nonlinear = true") + f"""
[steps]
factors = [5.0, 10.0, 15.0, 20.0, 22.5]
[[probes]]
name = "w"
quantity = "displacement"
point = [50, 50, 0]
component = "z"
[imperfection]
mode = 1
folder = "{tmp_path / 'modes'}"
amplitude = 0.01
"""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        res = run(build(parse(text)), None, write_vtu=False)
    assert res.converged, res.message
    lam = np.array([s["load_factor"] for s in res.summary["steps"]])
    w = np.array([s["probes"]["w"] for s in res.summary["steps"]])
    dev = w / (0.01 * (lam / lam_cr) / (1 - lam / lam_cr)) - 1
    assert np.all(np.abs(dev[lam <= 0.8 * lam_cr]) < 0.01) and abs(dev[-1]) < 0.03, (lam / lam_cr, dev)


def test_stress_stiffness_is_exact_on_a_curved_mitc_shell():
    """On the curved beam (examples/curved_beam.toml, MITC9 with tied strains, a curved
    reference surface) the tangent is quadratic in u, so the central difference over ±s u₀ does
    not depend on s: s = 1 and s = 10 agree to 10⁻⁷ of K₁ (s = 10⁻³ differs by round-off only,
    ~10⁻⁵)."""
    from layershell.buckling import _factorised, _nonlinear_problem, prestress
    from layershell.io.build import load

    pb = _nonlinear_problem(load(EXAMPLES / "curved_beam.toml").model)
    assert pb.model.element == "mitc"
    u0 = prestress(pb, _factorised(reduced_tangent(pb, np.zeros(pb.dm.n_full)), "auto"))
    k1 = stress_stiffness(pb, u0)
    k10 = stress_stiffness(pb, 10 * u0) / 10
    assert abs(k1 - k10).max() < 1e-7 * abs(k1).max()
    assert abs(k1).max() > 0
