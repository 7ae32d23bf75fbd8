"""Thesis §5.3 (MODEL.md V7, V8): plates with a circular initial delamination whose debonded zone
grows with the load factor, examples/cfrp_circular.toml and examples/trc_circular.toml.

The example runs take minutes (nonlinear, contact, re-solutions after every release), so they
are marked slow; the homogenisation check is fast. Both examples model a quarter plate (symmetry
planes x1 = 0 and x2 = 0, origin at the plate centre), so the extent of the debonded zone along
x_i is the largest x_i of a released interface point.
"""
from __future__ import annotations

import importlib.util

import numpy as np
import pytest
from helpers import EXAMPLES, run_example

from layershell.element.geometry import surface_points
from layershell.element.quadrature import gauss_2d
from layershell.io.build import load


def _laminate_script():
    spec = importlib.util.spec_from_file_location("make_cfrp_laminate", EXAMPLES / "make_cfrp_laminate.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def released_points(res, k: int = 0) -> np.ndarray:
    """(n, 2) in-plane positions of the released face Gauss points of interface ``k``."""
    blk = res.problem.interfaces.runs[k].block
    pts, _ = gauss_2d(3)
    X = surface_points(res.problem.model.mesh.nodes[blk.conn], pts[:, 0], pts[:, 1]).X0
    return X[blk.released][:, :2]


def areas(res) -> np.ndarray:
    return np.array([sum(v for k, v in a.items() if k not in ("step", "load_factor"))
                     for a in res.summary["debonded_area"]])


# ------------------------------------------------------------------ homogenisation (fast)
def test_cfrp_example_uses_the_homogenised_constants_of_the_script():
    """The material blocks and the edge traction of cfrp_circular.toml are those printed by
    examples/make_cfrp_laminate.py (thickness average of the rotated ply stiffnesses)."""
    mod = _laminate_script()
    consts = mod.homogenise(verbose=False)
    spec = load(EXAMPLES / "cfrp_circular.toml")
    model = spec.model
    assert [ly.name for ly in model.layers] == ["I", "II", "III"]
    for ly in model.layers:
        ec, H = consts[ly.name]
        assert np.allclose(ly.thickness, H)
        for key, val in ec.items():
            assert getattr(ly.material, key) == pytest.approx(val, rel=2e-5), (ly.name, key)
    # outer regions are the 0° ply itself; region II is stiffer across (90°, ±45°) and softer along
    assert consts["I"][0]["E1"] == pytest.approx(135000.0) and consts["III"][0]["E2"] == pytest.approx(8500.0)
    assert 70000 < consts["II"][0]["E1"] < 90000 and consts["II"][0]["G12"] > 2 * 5150.0
    # balanced ±45° plies: no normal/shear coupling in region II (only round-off to drop)
    C, _ = mod.layer_stiffness(mod.REGIONS["II"])
    for i, j in mod.COUPLING.values():
        assert abs(C[i, j]) < 1e-12 * np.abs(C).max()
    # edge traction: layer forces ∝ E1 H, summing to F = 30 N/mm; the example's formula matches
    t = mod.edge_tractions(consts)
    assert sum(t[k] * consts[k][1] for k in t) == pytest.approx(30.0)
    (load_,) = model.edge_loads
    off = np.cumsum([0.0] + [consts[k][1] for k in ("I", "II", "III")])
    mid = 0.5 * (off[:-1] + off[1:])
    z = np.zeros(3)
    assert np.allclose(load_.distribution(theta3=mid, x=z, y=z, z=z), [t["I"], t["II"], t["III"]], rtol=1e-5)


# ------------------------------------------------------------------ CFRP plate (§5.3.1)
@pytest.fixture(scope="module")
def cfrp():
    return run_example("cfrp_circular")


@pytest.mark.slow
def test_cfrp_debonded_zone_grows_with_the_load(cfrp):
    """Nothing fails while layer III buckles out; from λ ≈ 30 the zone grows beyond the initial
    circle (r = 5 mm) and never shrinks."""
    assert cfrp.converged, cfrp.message
    a = areas(cfrp)
    assert np.all(np.diff(a) >= 0)
    assert a[-1] > 1.5 * a[0]
    lam1 = cfrp.summary["first_delamination_load_factor"]
    assert lam1 is not None and 20.0 < lam1 <= 32.0
    # the blister is open at the centre: layer III lies above layer II
    p = cfrp.summary["probes"]
    assert p["w_III_bottom_centre"] - p["w_II_top_centre"] > 0.1


@pytest.mark.slow
def test_cfrp_debonded_zone_is_longer_along_x2(cfrp):
    """Thesis: the zone grows into an oval with the larger extent along x2. At the last step
    (λ = 34) the released points reach x2 = 9.3 mm against x1 = 7.5 mm, both beyond the initial
    radius of 5 mm.

    Caveat (reported with the example): the x2 extent comes from a pair of nodes near the x2 axis
    at x2 = 9 mm that fails separately, ahead of the main zone; the zone connected to the initial
    circle reaches x1 = 7.5 and x2 = 6.3 mm, so the oval along x2 is reproduced only in this
    weaker sense. This test checks the extents of all released points."""
    P = released_points(cfrp)
    ext1, ext2 = P[:, 0].max(), P[:, 1].max()
    assert ext2 > ext1 > 5.0
    assert ext2 > 1.15 * ext1


@pytest.mark.slow
@pytest.mark.parametrize("name", ["cfrp_circular", "cfrp_circular_plies"])
def test_cfrp_examples_keep_the_full_element_because_mitc9_does_not_grow_the_zone(name):
    """Why the CFRP examples set element = "full" (the thesis's element): with MITC9 the blister
    opens alike (layer III 0.49 mm above the centre at λ = 32, homogenised), but the tractions at
    its front stay below the criterion: up to λ = 34 only points of the elements that hold the
    initial circle (r = 5 mm) release (debonded area 20.5 -> 22.7 mm², the released points' x1
    and x2 at most 4.5 mm), so the
    thesis's oval is not reached; the homogenised plate shows no growth up to λ = 38 either (full
    element: x1 = 7.5, x2 = 9.3 mm at λ = 32 and the global buckling at λ ≈ 35 that opens most of
    the quarter)."""
    r = run_example(name, {'element = "full"': 'element = "mitc"'})
    assert r.converged, r.message
    P = released_points(r)
    a = areas(r)
    assert P[:, 0].max() < 5.0 and P[:, 1].max() < 5.0  # the initial zone's points reach 4.5 mm on both axes
    assert a[-1] < 1.15 * a[0]


# ------------------------------------------------------------------ TRC plate (§5.3.2)
@pytest.fixture(scope="module")
def trc():
    return run_example("trc_circular")


@pytest.mark.slow
def test_trc_onset_near_lambda_10_and_growth(trc):
    """Thesis: the zone starts to grow at about λ = 10. The first failure is reported; with the
    supports, the mesh and the face of f unknown (MODEL.md V8 gaps), a factor of 1.5 either way
    is accepted. Here it comes at λ = 10, but at the supported corner (x1, x2) ≈ (180, 120) mm,
    not at the initial zone (see the next test)."""
    assert trc.converged, trc.message
    a = areas(trc)
    assert np.all(np.diff(a) >= 0)
    assert a[-1] > a[0]
    lam1 = trc.summary["first_delamination_load_factor"]
    assert lam1 is not None and 10.0 / 1.5 <= lam1 <= 10.0 * 1.5


@pytest.mark.slow
def test_trc_initial_zone_grows_next_to_x2_axis(trc):
    """Thesis: the growth of the initial zone (r = 50 mm) starts near (x1 = 0, x2 = 5 cm). At the
    last step (λ = 15, where it starts here) points just outside the initial circle are released,
    all on the x2 side."""
    P = released_points(trc)
    r = np.hypot(P[:, 0], P[:, 1])
    near = P[(r > 50.0) & (r < 80.0)]
    assert len(near) > 0
    assert np.all(near[:, 1] > near[:, 0])
