"""Linear buckling of laminates with an initial delamination (src/layershell/buckling.py,
`layershell buckle` on a model with [[interfaces]]): the initial bond state of a run, tied where
bonded, open (no contact) where initially debonded.

References: the circular plate clamped at its edge under equal biaxial compression, N_cr R²/D =
j₁₁² = 14.682 (axisymmetric mode) and j₂₁² = 26.374 (one nodal diameter), j_n1 the first zero of
the Bessel function J_n (Timoshenko & Gere, Theory of Elastic Stability, ch. 9, circular plates),
with the sub-laminate's membrane force taken from the prestate's strains; the same plate with
every ply its own layer (the layerwise model that the ply stacks of two layers replace)."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from typer.testing import CliRunner

from helpers import EXAMPLES
from layershell.buckling import _nonlinear_problem, linear_buckling
from layershell.buckling_output import moving_face
from layershell.cli import app
from layershell.io.build import InputError, build, parse
from layershell.solver.problem import Problem

J11_SQ = 3.831705970207512**2  # first zero of J1, squared: the clamped plate's axisymmetric mode
J21_SQ = 5.135622301840683**2  # first zero of J2, squared: the mode with one nodal diameter
E, NU, T_TOP, R = 50000.0, 0.3, 0.25, 20.0  # examples/laminate_delamination_buckling.toml
D = E * T_TOP**3 / (12 * (1 - NU**2))
ISO = EXAMPLES / "laminate_delamination_buckling.toml"
PLIES = EXAMPLES / "laminate_delamination_plies.toml"
COHESIVE = 'law = "cohesive"\nsigma_max = 30.0\ntau_max = 60.0\nG_Ic = 0.3\nG_IIc = 1.0\n'


def iso_text(front: float = 4.0, ring_layers: int = 1, law: str | None = None) -> str:
    """The isotropic example on another front mesh, optionally with another interface law."""
    text = ISO.read_text()
    for a, b in ((r"front_size = 2\.0", f"front_size = {front}"), (r"ring_layers = 2", f"ring_layers = {ring_layers}")):
        assert re.search(a, text), a
        text = re.sub(a, b, text)
    if law is not None:
        old = "sigma_max = 30.0\ntau_max = 60.0\n"
        assert old in text
        text = text.replace(old, law)
    return text


def membrane_strain(res, layer: int) -> np.ndarray:
    """ε_x, ε_y, γ_xy of ``layer``'s bottom face over the delamination's interior nodes: a linear
    fit of the prestate's in-plane displacements, and the largest residual of the fit."""
    pb, u0 = res.problem, res.prestress
    nodes = pb.model.mesh.node_sets["interior"]
    X = pb.model.mesh.nodes[nodes]
    A = np.column_stack([np.ones(len(X)), X[:, 0], X[:, 1]])
    ux, uy = (u0[pb.dm.layer_dofs[layer][nodes, 0, i]] for i in (0, 1))
    cx, cy = (np.linalg.lstsq(A, v, rcond=None)[0] for v in (ux, uy))
    misfit = max(np.abs(A @ cx - ux).max(), np.abs(A @ cy - uy).max())
    return np.array([cx[1], cy[2], cx[2] + cy[1], misfit])


def test_initial_bond_state_is_the_runs_and_a_cohesive_interface_is_tied():
    """The buckling problem's bond flags are those a run starts from (Problem.build with its
    interface controller): the top layer free of the base exactly at the initially debonded
    ('interior') nodes, tied elsewhere; no contact or cohesive block is left. A cohesive
    interface with the same initial zone gives the same flags (its intact points tied) and the
    same load factors to round-off."""
    spec = build(parse(iso_text()))
    pb = _nonlinear_problem(spec.model)
    run_flags = Problem.build(spec.model).bonded[1]
    interior = np.zeros(spec.model.mesh.n_nodes, bool)
    interior[spec.model.mesh.node_sets["interior"]] = True
    assert np.array_equal(pb.bonded[1], run_flags) and np.array_equal(pb.bonded[1], ~interior)
    assert pb.interfaces is None and not pb.extra_blocks and not pb.assembler.extra
    coh = build(parse(iso_text(law=COHESIVE)))
    assert not Problem.build(coh.model).bonded[1].any()  # the run itself holds it by the penalty
    pb_c = _nonlinear_problem(coh.model)
    assert np.array_equal(pb_c.bonded[1], pb.bonded[1]) and not pb_c.assembler.extra
    lam, lam_c = linear_buckling(spec.model, 2).load_factors, linear_buckling(coh.model, 2).load_factors
    assert np.allclose(lam_c, lam, rtol=1e-8), (lam, lam_c)


@pytest.mark.slow
def test_sublaminate_buckles_as_the_clamped_circular_plate_on_three_meshes():
    """The isotropic example on 4, 3 and 2 mm front elements: the prestate of the sub-laminate is
    the equal biaxial strain (ε_x = ε_y within 10⁻⁶, no shear), its membrane force N = E t ε / (1 −
    ν); λ₁ N R² / D against j₁₁² and the pair λ₂ = λ₃ against j₂₁² within 5 % on each mesh (they
    come out within 0.7 %), and the first converges (its change from the second to the third mesh
    is less than a fifth of that from the first to the second)."""
    k1 = []
    for front, ring_layers in ((4.0, 1), (3.0, 2), (2.0, 2)):
        res = linear_buckling(build(parse(iso_text(front, ring_layers))).model, 3)
        ex, ey, gxy, misfit = membrane_strain(res, 1)
        assert ex < 0 and abs(ey / ex - 1) < 1e-6 and abs(gxy) < 1e-6 * abs(ex), (ex, ey, gxy)
        assert misfit < 1e-6 * abs(ex) * R, misfit
        N = -E * T_TOP * ex / (1 - NU)  # the compressive membrane force at λ = 1 (plane stress)
        k = res.load_factors * N * R**2 / D
        assert abs(k[0] / J11_SQ - 1) < 0.05 and abs(k[1] / J21_SQ - 1) < 0.05, (front, k)
        assert abs(k[2] / k[1] - 1) < 1e-6, k
        k1.append(k[0])
    assert abs(k1[2] - k1[1]) < 0.2 * abs(k1[1] - k1[0]), k1


def test_uniaxial_compression_lies_between_the_rayleigh_bounds():
    """The isotropic example compressed in x only (y edges free, one point held in y; 4 mm front
    elements): the sub-laminate's prestate is N_x < 0 with a small tension N_y (the base, held flat
    through its thickness, contracts with ν/(1 − ν)). Rayleigh's quotient bounds the first
    buckling factor: the load term λ(|N_x| w_x² − N_y w_y²) is at most λ|N_x| |∇w|², so λ|N_x| R²/D
    ≥ j₁₁² (the equal biaxial value); the clamped axisymmetric mode J₀ (∫w_x² = ∫w_y² = ½∫|∇w|²)
    gives λ (|N_x| − N_y)/2 R²/D ≤ j₁₁². The computed value, 29.9, lies between."""
    text = iso_text()
    y_edges = text[text.index("[[supports]]           # ... and in y"):text.index("[[interfaces]]")]
    text = text.replace(y_edges, '[[supports]]\ntype = "fix"\npoint = [75.0, 0.0, 0.0]\nlayer = "all"\n'
                        'directors = "all"\ncomponents = ["y"]\n\n')
    res = linear_buckling(build(parse(text)).model, 1)
    ex, ey, gxy, _ = membrane_strain(res, 1)
    Nx, Ny = (E * T_TOP / (1 - NU**2) * (a + NU * b) for a, b in ((ex, ey), (ey, ex)))
    assert Nx < 0 < Ny < 0.2 * -Nx and abs(gxy) < 1e-6 * abs(ex), (Nx, Ny, gxy)
    assert abs(ey / ex + NU / (1 - NU)) < 0.05 * NU / (1 - NU), ey / ex
    k = res.load_factors[0] * -Nx * R**2 / D
    assert J11_SQ < k < 2 * J11_SQ / (1 - Ny / -Nx), (k, Ny / Nx)


def ply_by_ply(text: str) -> str:
    """The plies example with every ply its own layer (d = 2, the same material axis), the floor
    under the lowest ply and the delamination below ply 7 of 8."""
    angles = [0, 45, -45, 90, 90, -45, 45, 0]
    start, end = text.index("[[layers]]"), text.index("[[supports]]")
    layers = "".join(f'[[layers]]\nname = "p{k}"\nmaterial = "cfrp"\nthickness = 0.125\nangle = {a}\n'
                     f'direction = [1, 0, 0]\ndirectors = 2\n\n' for k, a in enumerate(angles, 1))
    text = text[:start] + layers + text[end:]
    for a, b in (('layer = "base"', 'layer = "p1"'), ('layer = "top"', 'layer = "p7"')):
        assert text.count(a) == 1, a
        text = text.replace(a, b)
    return text


@pytest.mark.slow
def test_ply_stacks_in_two_layers_buckle_as_the_ply_by_ply_model_with_under_a_third_of_the_dofs():
    """The quasi-isotropic [0/45/−45/90]s plate with a 40 mm delamination below ply 2: two
    layers with ply stacks and eight single-ply layers (both d = 2) give the same first two
    buckling strains within 1 % (they agree within 0.2 %), with at most a third of the unknowns
    (21 442 against 72 898)."""
    text = PLIES.read_text()
    two = linear_buckling(build(parse(text)).model, 2)
    eight = linear_buckling(build(parse(ply_by_ply(text))).model, 2)
    assert len(eight.problem.model.layers) == 8 and len(two.problem.model.layers) == 2
    assert np.all(np.abs(two.load_factors / eight.load_factors - 1) < 0.01), (two.load_factors, eight.load_factors)
    assert two.problem.op.n_red <= eight.problem.op.n_red / 3, (two.problem.op.n_red, eight.problem.op.n_red)
    assert two.load_factors[0] > 1.0  # above the λ = 1 of the prestate: ε_cr beyond 100 µε


def test_buckle_command_on_the_delaminated_ply_stack_plate(tmp_path: Path):
    """`layershell buckle` on examples/laminate_delamination_plies.toml: exit code 0, the files
    and load factors of the API; the first mode is the sub-laminate's bulge: the top layer's
    lateral displacement is largest inside the circle; where it is tied to the base it moves only
    with the base's top face, whose bottom face the floor holds (under 10⁻⁴ of the bulge: the
    base's thickness change). The mode figure draws the top layer's face; the mode cannot serve as
    an [imperfection] of the mesh (the reference face does not move), which is refused by name."""
    out = tmp_path / "modes"
    r = CliRunner().invoke(app, ["buckle", str(PLIES), "--modes", "2", "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert "initial delaminations open" in r.output, r.output
    s = json.loads((out / "buckling.json").read_text())
    res = linear_buckling(build(parse(PLIES.read_text())).model, 2)
    assert np.allclose(s["load_factors"], res.load_factors, rtol=1e-8)
    for f in ("buckling_mode_1.vtu", "buckling_mode_2.vtu", "buckling_modes.npz", "buckling.csv"):
        assert (out / f).stat().st_size > 0
    pb, phi = res.problem, res.modes[0]
    X = pb.model.mesh.nodes
    w = phi[pb.dm.layer_dofs[1][:, 0, 2]]
    r_c = np.hypot(X[:, 0] - 75.0, X[:, 1] - 75.0)
    assert r_c[np.argmax(np.abs(w))] < R
    assert np.abs(w[r_c > R + 1e-6]).max() < 1e-4 * np.abs(w).max()
    assert moving_face(pb, phi)[0] == "bottom face of layer 'top'"  # what buckling_modes.png draws
    text = PLIES.read_text() + f'\n[imperfection]\nmode = 1\nfolder = "{out}"\namplitude = 0.01\n'
    with pytest.raises(InputError, match="a mode local to a layer above a held reference face"):
        build(parse(text))
