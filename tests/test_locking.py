"""Issue 3 #2: the locking study of thesis Fig. 3.13 (MODEL.md V3); issue 14: the MITC9 element."""
import sys
from pathlib import Path

import pytest
from helpers import run_example

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import locking_study  # noqa: E402


def rel(a, b):
    return abs(a - b) / abs(b)


def test_elastica_shooting():
    """The elastica by shooting: small loads give the linear P l³/3EI (w/l → α/3), and the
    two cantilevers' values agree with the tabulated elastica (Mattiasson 1981: α = 1 →
    w/l = 0.30172)."""
    assert rel(locking_study.elastica_tip(1e-4), 1e-4 / 3) < 1e-4
    assert rel(locking_study.elastica_tip(1.0), 0.30172) < 1e-4
    assert rel(locking_study.elastica("thick"), 3.490) < 1e-3
    assert rel(locking_study.elastica("thin"), 8.926) < 1e-3


def test_thick_example_matches_the_elastica():
    """3 layers × 3 directors, geometrically nonlinear, MITC9 (default): within 2 % of the exact
    elastica (P l²/EI = 1.2). The thesis's 3.899 cm is 12 % above the elastica and cannot
    be the result of a conservative end load; it is close to the linear value (4.012)."""
    w = run_example("cantilever_thick_load_bottom").summary["probes"]["w_tip"]
    assert rel(w, locking_study.elastica("thick")) < 0.02
    assert rel(w, 3.899) > 0.1


def test_thin_linear_matches_the_thesis_value():
    """Thin beam, 3 × 3, the thesis's fully integrated element: the geometrically linear
    deflection (8.786) equals the thesis's 8.790 to 0.1 %; both are 2.4 % below Euler-Bernoulli
    (9.0) — the 9-node element's mild locking over 20 cm elements of 0.333 cm depth, as the
    thesis says."""
    w = locking_study.w_tip("thin", 3, 3, nonlinear=False, element="full")
    assert rel(w, 8.790) < 0.001


def test_thin_linear_mitc_removes_the_locking():
    """The same with the MITC9 element: within 1 % of Euler-Bernoulli P l³/3EI = 9.000 (the
    full element's −2.4 % is locking)."""
    w = locking_study.w_tip("thin", 3, 3, nonlinear=False)
    assert rel(w, 9.000088) < 0.01


@pytest.mark.parametrize("case", ["thick", "thin"])
def test_deflection_grows_towards_the_reference_with_layers_and_directors(case):
    """Fig. 3.13 trend (the thesis's fully integrated element, linear runs, fast): more layers at
    d = 1 and more directors in one layer both reduce the locking; d = 2 is the most effective
    step."""
    by_layers = [locking_study.w_tip(case, n, 1, nonlinear=False, element="full") for n in (1, 2, 3)]
    by_dirs = [locking_study.w_tip(case, 1, d, nonlinear=False, element="full") for d in (1, 2, 3)]
    assert by_layers[0] < by_layers[1] < by_layers[2]
    assert by_dirs[0] < by_dirs[1] <= by_dirs[2] * (1 + 1e-9)
    assert (by_dirs[1] - by_dirs[0]) > 10 * (by_dirs[2] - by_dirs[1])


@pytest.mark.slow
def test_thin_example_nonlinear_membrane_locking():
    """Thin beam, nonlinear, 3 × 3, the thesis's fully integrated element: 7.64 cm, 14 % below
    the elastica (8.926): five quadratic elements over l/h = 300 lock in large rotation ("larger
    loads or slenderness quickly ruin results", thesis 3.5.1). Documented, not hidden."""
    w = run_example("cantilever_thin_load_bottom", {"nonlinear = true": 'nonlinear = true\nelement = "full"'}
                    ).summary["probes"]["w_tip"]
    assert 7.5 < w < 7.8


@pytest.mark.slow
def test_thin_example_nonlinear_mitc_matches_the_elastica():
    """The thin example as shipped (MITC9 default): within 2 % of the exact elastica (8.926 cm).
    What remains (−0.9 %) is the same as in the linear run (−0.8 % against Euler-Bernoulli):
    the 3D clamp with ν = 0.4, not locking."""
    w = run_example("cantilever_thin_load_bottom").summary["probes"]["w_tip"]
    assert rel(w, locking_study.elastica("thin")) < 0.02


@pytest.mark.slow
def test_large_rotation_end_shear_matches_the_elastica():
    """Large rotation: the thin cantilever (l/h = 300, ν = 0, 5 elements, 20 steps) under a
    conservative end shear P l²/EI = 2 (tip deflection half the length, tip rotation ≈ 1 rad):
    MITC9 within 1 % of the elastica (measured −0.6 %; 10 elements −0.07 %)."""
    EI = 1e5 * 0.333**3 / 12
    P = 2.0 * EI / 100.0**2
    res = run_example("cantilever_thin_load_bottom", {"nu = 0.4": "nu = 0.0", "distribution = 0.00830844":
                                                      f"distribution = {P!r}", "n = 10": "n = 20"})
    assert res.converged
    assert rel(res.summary["probes"]["w_tip"], 100.0 * locking_study.elastica_tip(2.0)) < 0.01
