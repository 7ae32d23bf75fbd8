"""The round-off floor of the residual's entries (solver.newton.above_round_off): an internal-force
entry cannot be resolved below ε Σ_j |K_gj u_j|, the round-off of the sum of its terms. A thick
layer with quadratic directors in mm has entries in N·mm² whose terms are ~10¹¹ at a few mm of
deflection; Newton stalls there (examples of the strengthened strip, docs/concrete.md) unless
those entries count as converged."""
from __future__ import annotations

import numpy as np
import pytest
import scipy.sparse as sp

from layershell.io.build import build, parse
from layershell.solver.newton import ROUND_OFF_TERMS, NewtonSettings, above_round_off, newton_fixed_set
from layershell.solver.problem import Problem

THICK = """
[model]
units = "N, mm"
nonlinear = false
[mesh]
type = "rectangle"
lx = 1500.0
ly = 250.0
nx = 4
ny = 1
[materials.c]
type = "isotropic"
E = 33550.0
nu = 0.2
[[layers]]
name = "slab"
material = "c"
thickness = 160.0
directors = 2
[[supports]]
type = "fix"
where = "near(x, 0)"
directors = "all"
[[loads]]
type = "surface"
face = "reference"
direction = [0, 0, -1]
magnitude = 0.05
"""


def test_entries_within_their_round_off_count_as_zero():
    K = sp.csr_matrix(np.array([[4.0e18, -1.0e18], [-1.0e18, 2.0]]))
    u = np.array([1.0e-7, 2.0])
    terms = np.abs(K.toarray()) @ np.abs(u)  # 2.4e12 and 1.0e11 + 4
    floor = ROUND_OFF_TERMS * np.finfo(float).eps * terms
    r = np.array([0.5 * floor[0], 3.0 * floor[1]])
    assert above_round_off(r, K, u) == pytest.approx(2.0 * floor[1], rel=1e-12)
    assert above_round_off(-r, K, u) == pytest.approx(2.0 * floor[1], rel=1e-12)
    assert above_round_off(np.zeros(2), K, u) == 0.0


def _solved_thick_plate():
    pb = Problem.build(build(parse(THICK)).model)
    u, res = newton_fixed_set(pb, np.zeros(pb.dm.n_full), 1.0, NewtonSettings(tol_residual=1e-12))
    assert res.converged
    f, _ = pb.assembler.evaluate(u, tangent=False)
    _, Kr = pb.assembler.evaluate_reduced(u, pb.op, forces=False)
    r = pb.op.reduce(pb.external(1.0) - f)
    return pb, u, r, Kr


def test_a_solved_thick_layer_is_within_the_floor_and_a_real_error_is_not():
    pb, u, r, Kr = _solved_thick_plate()
    ur = u[pb.op.independent]
    load = np.linalg.norm(pb.op.reduce(pb.external(1.0)))
    assert np.linalg.norm(r) > 1e-9 * load  # the raw residual stalls far above a tolerance of 10⁻¹²
    assert above_round_off(r, Kr, ur) <= 1e-12 * load  # what remains is round-off
    # a displacement error of 10⁻⁹ of the deflection leaves a residual well above the floor
    du = 1e-9 * np.abs(ur).max() * np.random.default_rng(1).normal(size=ur.size)
    r_err = r - Kr @ du
    assert above_round_off(r_err, Kr, ur + du) > 1e-6 * np.linalg.norm(Kr @ du)
