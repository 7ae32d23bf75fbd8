"""Transverse stresses next to a bearing on a face, checked by the statics of the end block.

The concrete strip of tests/test_recovery_layer_end.py without the plate (span 400 mm, 40 mm deep,
plane strain, 10 N/mm² on top) rests on a line bearing under its soffit at x = 0. The block
below mid-depth from x = 0 to X = 80 mm (two depths) carries the bearing's reaction R = q L/2,
the shear on its face x = X and the vertical stress on its top face z = mid-depth, so

    ∫_0^X σ_zz(x, mid-depth) dx + ∫_soffit^mid-depth σ_xz(X, z) dz + R = 0   (per unit width).

The recovery integrates the equilibrium from the applied face tractions, and the bearing's
reaction is none: near the bearing its σ_zz missed 5, 24, 34 and 39 % of R on end elements of 4, 2,
1 and 0.5 mm. Within one depth of such a support the outputs give the raw values instead, and the
balance closes.
"""
from __future__ import annotations

import numpy as np
import pytest
from test_recovery_layer_end import MODEL

from layershell.element.quadrature import gauss_1d
from layershell.io.build import build, parse
from layershell.recovery import RecoveryWarning, face_support_elements, stress_points
from layershell.results import locate
from layershell.runner import run

STRIP = MODEL[:MODEL.index("[[probes]]")]
for _cut in ('[[layers]]\nname = "adhesive"\nmaterial = "adhesive"\nthickness = 0.5\ndirectors = 1\n',
             '[[layers]]\nname = "cfrp"\nmaterial = "cfrp"\nthickness = 4.0\ndirectors = 1\n',
             '[[stacks]]\nlayers = ["concrete", "adhesive", "cfrp"]\nwhere = "x > 40"\n',
             '[[stacks]]\nlayers = ["concrete"]\n'):
    assert _cut in STRIP
    STRIP = STRIP.replace(_cut, "")
STRIP += """
[[probes]]
name = "s33_bearing"
quantity = "stress"
point = [0.0, 0.5, 0.0]
theta3 = 20.0
component = "33"
"""
DEPTH, X, R = 40.0, 80.0, 10.0 * 400.0 / 2


def stresses(spec, res, x, theta3):
    """Cauchy stress (global components) of the default (recovered) output at points x, Θ³."""
    m = spec.model
    x, theta3 = np.broadcast_arrays(np.asarray(x, float), np.asarray(theta3, float))
    loc = [locate(m, [xx, 0.5, 0.0]) for xx in x]
    e, xi, eta = (np.array([l_[i] for l_ in loc]) for i in range(3))
    return stress_points(m, res.problem.dm, res.u, e, xi, eta, theta3, np.zeros(x.size, int), local_theta=True).sigma


@pytest.mark.parametrize("h", [4.0, 2.0, 1.0, 0.5])
def test_end_block_statics_next_to_bearing(h):
    spec = build(parse(STRIP.format(nx=int(round(200 / h))), "strip.toml"))
    with pytest.warns(RecoveryWarning, match="supports held on a face"):
        res = run(spec, None, write_vtu=False)
    assert res.converged, res.message
    zone = face_support_elements(spec.model)
    centres = spec.model.mesh.nodes[spec.model.mesh.elements[zone]].mean(axis=1)[:, 0]
    assert centres.max() < DEPTH + h  # within one depth of the bearing
    xg, wg = gauss_1d(6)
    n = int(round(X / h))
    xs = ((np.arange(n)[:, None] + 0.5 * (xg + 1)) * h).ravel()
    top = stresses(spec, res, xs, DEPTH / 2)[:, 2, 2] @ np.tile(wg * h / 2, n)  # ∫ σ_zz dx at mid-depth
    zq = DEPTH / 2 * (1.5 + 0.5 * xg)  # Θ³ from mid-depth to the soffit
    side = stresses(spec, res, np.full(zq.size, X - 1e-7), zq)[:, 0, 2] @ (wg * DEPTH / 4)
    # measured: +0.19, +0.25, +0.29, +0.31 % of R (the raw values alone: -0.01 %)
    assert abs(top + side + R) < 0.01 * R, (top, side, R)


def test_the_warning_names_the_place_of_a_single_element():
    """The place of the raw zone is named for one element too (every coordinate equal)."""
    from layershell.recovery import _span_text

    assert _span_text(np.array([[1.0, 0.5, 0.0]])) == "x = 1, y = 0.5, z = 0"
    assert _span_text(np.array([[0.0, 0.5, 0.0], [2.0, 0.5, 0.0]])) == "x 0 to 2, y = 0.5, z = 0"
