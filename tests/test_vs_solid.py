"""The solid reference model of benchmarks/vs_solid.py (scikit-fem, optional extra ``bench``)."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("skfem")
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import vs_solid as vs  # noqa: E402


def test_girkmann_reference_matches_model_md():
    ref = vs.girkmann_reference()
    assert round(ref["sigma_phi_inner"], 3) == 1.241 and round(ref["sigma_r_max"], 3) == 0.171


def test_solid_curved_beam_converges_to_girkmann():
    """Quadratic hexahedra: the errors against (3.94)-(3.95) fall under refinement, and the fine
    mesh is within 1.1 % (arc and radial refinement both matter)."""
    ref = vs.girkmann_reference()
    coarse = vs.with_errors([vs.solid_curved(2, 9)], ref)[0]
    fine = vs.with_errors([vs.solid_curved(8, 17)], ref)[0]
    assert fine.errors["sigma_phi_inner"] < coarse.errors["sigma_phi_inner"]
    assert fine.errors["sigma_r_max"] < coarse.errors["sigma_r_max"] / 5
    assert max(fine.errors.values()) < 0.011


def test_solid_face_load_integrates_the_traction():
    """Consistent nodal loads of the plate pressure sum to p × area (half plate)."""
    z = np.array([0.0, vs.PL_H1, vs.PL_H1 + vs.PL_H2])
    s = vs.Solid(np.linspace(0, vs.PL_L, 5), np.linspace(0, vs.PL_L / 2, 3), z, lambda p: p.copy(),
                 lambda c: (np.full(c.shape[1], 1.0), np.full(c.shape[1], 0.2)))
    f = s.face_load(2, vs.PL_H1 + vs.PL_H2, lambda p: np.stack([0 * p[0], 0 * p[0], 1.0 + p[0]]))
    # ∫∫ (1 + x) dx dy over [0, 1] × [0, 0.5] = 0.75
    assert np.isclose(f[2::3].sum(), 0.75) and np.isclose(f[0::3].sum(), 0.0)


def test_richardson_recovers_a_known_limit():
    q = [1.0 + 0.4 * h**2 for h in (1.0, 0.5, 0.25)]
    val, order = vs.richardson(q)
    assert abs(val - 1.0) < 1e-12 and abs(order - 2.0) < 1e-9


def test_plate_model_file_builds_and_matches_the_solid_shear_roughly():
    """layershell and the solid agree on the interface shear of the plate within a few % on
    moderately fine meshes (the benchmark's full study refines to 1 %)."""
    sh = vs.shell_plate(8, 1, 3).values["tau_xz_interface"]
    so = vs.solid_plate(8, 2, 2).values["tau_xz_interface"]
    assert sh < 0 and so < 0 and abs(sh / so - 1) < 0.03
