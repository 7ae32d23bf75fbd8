"""Thesis §5.4 (MODEL.md V9): the Krümmel water-tower dome, examples/kruemmel_dome_*.toml.

The thesis gives no dimensions of the rings and the haunch (its figures are missing); the model
files document every assumption. The thesis's absolute numbers are therefore checked as strict
xfails (known gaps, reported in the example files), the rest against independent references:
the applied load against the analytic area of the spherical zone, axisymmetry, the
strengthened/unstrengthened ratio against the thesis, and the nonlinear onset of delamination
against a separate linear solve scaled to the failure criterion (4.15).
"""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from helpers import EXAMPLES, run_example
from layershell.delamination import failure_function
from layershell.interfaces import interface_state, interfaces
from layershell.io.build import build, parse
from layershell.runner import run

R, R_OPEN = 6.64, 1.5
Z_OPEN = float(np.sqrt(R**2 - R_OPEN**2))
THESIS_W = {"kruemmel_dome_linear": 0.0353e-3, "kruemmel_dome_unstrengthened": 0.0409e-3}  # m


@pytest.fixture(scope="module")
def linear_runs():
    return {name: run_example(name) for name in THESIS_W}


def test_load_on_the_dome_only_and_axisymmetric(linear_runs):
    for name, res in linear_runs.items():
        pb = res.problem
        d0 = pb.dm.layer_dofs[0][:, 0, :]  # u0 of the concrete layer (the reference face) at every node
        # 1 kN/m² vertical on the spherical zone only: total = 2 π R (z_open - 0) (analytic zone area)
        assert -pb.F_scaled[d0[:, 2]].sum() == pytest.approx(2 * np.pi * R * Z_OPEN, rel=5e-4), name
        assert abs(pb.F_scaled[d0[:, 0]].sum()) < 1e-9 and abs(pb.F_scaled[d0[:, 1]].sum()) < 1e-9
        # axisymmetric response: the whole top edge moves down alike
        spec_probe = next(p for p in _spec(name).probes if p.name == "w_top")
        w = spec_probe.samples(pb.model, pb.dm, res.u)
        # (the edge's nodes alternate corner / mid-side; MITC9 moves the two apart by 4e-4 of w, the
        # curved edge's discretisation, while each set stays uniform around the ring to 1e-12)
        assert w.size == 40 and w.min() > 0, name
        assert np.ptp(w[0::2]) < 1e-8 * w.max() and np.ptp(w[1::2]) < 1e-8 * w.max(), name
        assert np.ptp(w) < 1e-3 * w.max(), name


def _spec(name: str):
    path = EXAMPLES / f"{name}.toml"
    return build(parse(path.read_text(), str(path)), path.parent)


def test_strengthening_ratio_matches_the_thesis(linear_runs):
    """Thesis: 0.0353 / 0.0409 = 0.863; the TRC layer stiffens the dome by about 14 %."""
    w_s = linear_runs["kruemmel_dome_linear"].summary["probes"]["w_top"]
    w_u = linear_runs["kruemmel_dome_unstrengthened"].summary["probes"]["w_top"]
    assert w_s < w_u
    assert w_s / w_u == pytest.approx(0.0353 / 0.0409, rel=0.05)


SUPPORT = """[[supports]]             # lower edge of the lower ring beam, pinned in the reference face
type = "fix"
set = "first"
layer = "concrete"
directors = [0]
components = ["x", "y", "z"]"""
RIGID = """
[[supports]]             # x-y rigid-body motion only: radial motion stays free
type = "fix"
where = "near(z, -0.6) and near(y, 0)"
components = ["y"]
[[supports]]
type = "fix"
where = "near(z, -0.6) and near(x, 0) and y > 0"
components = ["x"]"""


def test_support_variants_vs_thesis(linear_runs):
    """Thesis (unstrengthened): pinned 0.0409 mm, sliding hinged ring 0.0411 mm, sliding hinges at 8 points
    0.0571 mm: the ratios to the pinned ring (1.005, 1.396) are compared, not the absolute values."""
    w_pinned = linear_runs["kruemmel_dome_unstrengthened"].summary["probes"]["w_top"]
    ring = 'type = "fix"\nset = "first"\ncomponents = ["z"]' + RIGID
    points = ('type = "fix"\nwhere = "near(z, -0.6) and (near(x, 0) or near(y, 0) or near(abs(x), abs(y)))"\n'
              'components = ["z"]' + RIGID)
    w_ring = run_example("kruemmel_dome_unstrengthened", {SUPPORT: "[[supports]]\n" + ring}).summary["probes"]["w_top"]
    w_points = run_example("kruemmel_dome_unstrengthened",
                           {SUPPORT: "[[supports]]\n" + points}).summary["probes"]["w_top"]
    assert w_ring / w_pinned == pytest.approx(0.0411 / 0.0409, rel=0.03)
    assert w_points / w_pinned == pytest.approx(0.0571 / 0.0409, rel=0.08)


@pytest.mark.xfail(strict=True, reason="known gap: with the assumed 0.86 m lower ring beam and the haunch over the "
                   "lowest dome row (thesis figures missing) w_top is about 30 % below the thesis; see "
                   "examples/kruemmel_dome_linear.toml")
def test_top_displacement_magnitude_vs_thesis(linear_runs):
    for name, res in linear_runs.items():
        assert res.summary["probes"]["w_top"] == pytest.approx(THESIS_W[name], rel=0.15), name


# ------------------------------------------------------------------ nonlinear: delamination onset
def linear_onset(name: str) -> float:
    """Load factor at which the failure criterion (4.15) is first met at an interface Gauss point,
    from ONE geometrically linear solve scaled by λ (independent of the incremental controller)."""
    path = EXAMPLES / f"{name}.toml"
    text = path.read_text().replace("nonlinear = true", "nonlinear = false")
    text = re.sub(r"factors = \[[^\]]*\]", "factors = [1.0]", text)
    spec = build(parse(text, str(path)), path.parent)
    res = run(spec, None, write_vtu=False)
    model = spec.model
    (law,) = model.interface_laws.values()
    (itf,) = interfaces(model)
    t = interface_state(model, res.problem.dm, res.u, itf).traction()
    lo, hi = 1.0, 1e5
    for _ in range(60):
        mid = np.sqrt(lo * hi)
        if failure_function(mid * t, law)[1].any():
            hi = mid
        else:
            lo = mid
    return hi


NONLINEAR = {
    # name: (thesis onset, load steps used here: coarse before the onset, 40 kN/m² after)
    "kruemmel_dome_half_load": (557.0, [400.0, 500.0, 520.0, 540.0, 560.0, 580.0]),
    "kruemmel_dome_pressure_suction": (624.0, [400.0, 770.0, 800.0, 830.0, 860.0, 890.0]),
}


def _nonlinear_run(name: str):
    text = (EXAMPLES / f"{name}.toml").read_text()
    old = re.search(r"factors = \[[^\]]*\]", text).group(0)
    return run_example(name, {old: f"factors = {NONLINEAR[name][1]}"})


@pytest.mark.slow
@pytest.mark.parametrize("name", list(NONLINEAR))
def test_delamination_onset_matches_the_linear_prediction(name):
    lam_lin = linear_onset(name)
    res = _nonlinear_run(name)
    s = res.summary
    assert s["converged"]
    lam = [st["load_factor"] for st in s["steps"]]
    area = [a["concrete/trc"] for a in s["debonded_area"]]
    onset = s["first_delamination_load_factor"]
    assert onset is not None, f"no delamination up to {lam[-1]} (linear prediction {lam_lin:.0f})"
    k = lam.index(onset)
    # the onset is the first step at or above the prediction, ±5 % for the geometric nonlinearity
    # (measured with these steps: nonlinear onset 520-540 vs 538 half-sided, 800-830 vs 859 pressure/suction)
    assert lam[k] >= 0.95 * lam_lin and (k == 0 or lam[k - 1] < 1.05 * lam_lin), (lam_lin, lam)
    assert all(a == 0 for a in area[:k]) and area[k] > 0
    assert all(b >= a for a, b in zip(area, area[1:]))  # debonding is irreversible


@pytest.mark.slow
@pytest.mark.parametrize("name", [
    "kruemmel_dome_half_load",  # linear prediction 538 kN/m², thesis 557
    pytest.param("kruemmel_dome_pressure_suction", marks=pytest.mark.xfail(
        strict=True, reason="known gap: this model's onset (linear prediction 859 kN/m²) lies 38 % above the "
        "thesis's 624 kN/m²; see examples/kruemmel_dome_pressure_suction.toml")),
])
def test_delamination_onset_vs_thesis(name):
    assert linear_onset(name) == pytest.approx(NONLINEAR[name][0], rel=0.15)
