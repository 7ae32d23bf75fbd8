"""Delamination growth after local buckling: the straight-sided blister of
examples/laminate_blister_growth.toml (a 0.5 mm film over a 20 mm delamination on a base held
flat, plane strain, the end shortening prescribed, a cohesive interface ahead of the front).

References: the thin-film closed forms of Hutchinson & Suo (1992) in layershell.analytic.blister
(the critical stress of the clamped film, its energy release rate and mode mix), checked here
against hand numbers and against the film's potential energy differentiated by finite
differences; the runs against them: the buckle's height, the energy release rate at the growing
front against the fracture energy the cohesive law dissipated at the points that debond, and the
onset strain against the closed form with the Benzeggagh–Kenane toughness at the front's mode mix."""
from __future__ import annotations

import numpy as np
import pytest
from helpers import run_example

from layershell.analytic import blister
from layershell.element.shape import quad9
from layershell.interfaces import face_points, interfaces

E, NU, T, A = 50000.0, 0.3, 0.5, 10.0  # the example's laminate, film thickness, half width
G_IC, G_IIC, ETA = 0.352, 1.002, 2.284  # its interface (Turon et al. 2007, T300/977-2)
L_BONDED_PROBE = 10.0  # the probe u_20 lies 10 mm from the loaded end x = 30
END_SHORTENING = 0.3  # mm at λ = 1 (the example's xmax support)
FAST_STEPS = {"nx = 60": "nx = 30", "n = 32\nlambda_end = 0.8\nadaptive = true\nincrement_max = 0.02":
              "factors = [0.2, 0.4, 0.5, 0.6, 0.64, 0.67, 0.70]"}


def film_strain(step: dict) -> float:
    """The film's compressive strain where it is bonded, between x = 20 and the loaded end."""
    return (END_SHORTENING * step["load_factor"] + step["probes"]["u_20"]) / L_BONDED_PROBE


def test_critical_stress_and_energy_release_rate_against_hand_numbers():
    """σ_c = π² E' t²/(12 a²) = π² · 54 945 · 0.25 / 1200 = 112.98 N/mm² for the example's film;
    at σ = 2 σ_c, G/G0 = (1/2)(5/2) = 1.25 with G0 = t σ²/(2E'); below σ_c, G = 0."""
    sc = blister.critical_stress(E, NU, T, A)
    assert sc == pytest.approx(112.98, abs=0.01)
    Ep = E / (1 - NU**2)
    eps2 = 2 * sc / Ep
    assert blister.energy_release_rate(eps2, E, NU, T, A) == pytest.approx(1.25 * T * (2 * sc) ** 2 / (2 * Ep), rel=1e-12)
    assert blister.energy_release_rate(0.9 * sc / Ep, E, NU, T, A) == 0.0


def film_energy(eps: float, a: float, half_length: float = 30.0) -> float:
    """Potential energy per width of the half film at the fixed strain ε where it is bonded, the
    delamination's half width a: bonded film t σ²/(2E') per length, the buckled part at σ_c plus
    the bending energy of w = δ/2 (1 + cos(πx/a)) with δ from the film's length, δ² = 16 a² (ε −
    ε_c)/π² (a rigid substrate)."""
    Ep = E / (1 - NU**2)
    ec = np.pi**2 * T**2 / (12 * a * a)
    d2 = 16 * a * a * (eps - ec) / np.pi**2
    return (T * Ep * ec**2 * a / 2 + Ep * T**3 * d2 * np.pi**4 / (192 * a**3)
            + T * Ep * eps**2 * (half_length - a) / 2)


@pytest.mark.parametrize("ratio", [1.5, 3.0, 6.0])
def test_energy_release_rate_is_the_films_energy_derivative(ratio):
    """G = −dΠ/da at fixed strain, Π the film's potential energy (film_energy), by central
    differences, at σ/σ_c = 1.5, 3, 6; the buckle height against the same δ."""
    ec = np.pi**2 * T**2 / (12 * A * A)
    eps, h = ratio * ec, 1e-4
    G_fd = -(film_energy(eps, A + h) - film_energy(eps, A - h)) / (2 * h)
    assert blister.energy_release_rate(eps, E, NU, T, A) == pytest.approx(G_fd, rel=1e-6)
    assert blister.buckle_height(eps, E, NU, T, A) == pytest.approx(4 * A * np.sqrt(eps - ec) / np.pi, rel=1e-12)


def test_mode_mix_limits_and_the_growth_strain():
    """ψ = ω − 90° = −37.93° at σ_c (the moment alone), −90° at σ/σ_c = 1 + 4 tan² ω = 7.55;
    the growth strain makes G equal to the BK toughness at its mode mix, lies between the strains
    for G_Ic and G_IIc, and a film that would need a state past pure mode II is refused."""
    ec = blister.critical_stress(E, NU, T, A) / (E / (1 - NU**2))
    assert np.degrees(blister.mode_angle(ec * (1 + 1e-12), E, NU, T, A)) == pytest.approx(52.07 - 90.0, abs=1e-4)
    w = blister.OMEGA_THIN_FILM
    assert np.degrees(blister.mode_angle(ec * (1 + 4 * np.tan(w) ** 2), E, NU, T, A)) == pytest.approx(-90.0, abs=1e-9)
    eg = blister.growth_strain(E, NU, T, A, G_IC, G_IIC, ETA)
    Gc = blister.bk_toughness(blister.mode_ii_share(eg, E, NU, T, A), G_IC, G_IIC, ETA)
    assert blister.energy_release_rate(eg, E, NU, T, A) == pytest.approx(Gc, rel=1e-9)
    assert blister.growth_strain(E, NU, T, A, G_IC) < eg < blister.growth_strain(E, NU, T, A, G_IIC)
    with pytest.raises(ValueError, match="pure mode II"):
        blister.growth_strain(E, NU, 0.25, A, G_IC, G_IIC, ETA)


def point_x(problem) -> np.ndarray:
    """x of the cohesive interface's points (element × 9 nodes)."""
    model = problem.model
    itf = interfaces(model)[0]
    N = quad9(*face_points("nodes"))[0]  # (9 points, 9 nodes)
    return np.einsum("qn,en->eq", N, model.mesh.nodes[model.mesh.elements[itf.elements], 0])


def test_coarse_blister_buckles_and_then_grows():
    """The example on 1 mm elements (about 3 node spacings in the process zone) in 7 load steps:
    the film buckles (at λ = 0.5 the middle has risen more than the film's thickness, 100 times
    the imperfection, within 20 % of the clamped film's δ at the measured film strain: the film
    rotates at the cohesive front, which the clamp does not), stays above the base (the gap of
    the delaminated zone is not negative beyond the contact penalty's 10⁻⁴ mm), and the
    delamination grows by λ = 0.70 at a film strain between the closed form's for G_Ic and for
    G_IIc, after the film has buckled: over twice its buckling strain."""
    r = run_example("laminate_blister_growth", FAST_STEPS)
    assert r.converged, r.message
    steps = {round(s["load_factor"], 6): s for s in r.summary["steps"]}
    s5 = steps[0.5]
    delta = blister.buckle_height(film_strain(s5), E, NU, T, A)
    assert s5["probes"]["w_mid"] > T and abs(s5["probes"]["w_mid"] / delta - 1) < 0.2, (s5["probes"], delta)
    grown = [s for s in r.summary["steps"] if s["probes"]["grown"] > 0]
    assert grown, "no growth by λ = 0.70"
    e_on = film_strain(grown[0])
    ec = blister.critical_stress(E, NU, T, A) / (E / (1 - NU**2))
    assert 2 * ec < e_on and blister.growth_strain(E, NU, T, A, G_IC) < e_on < blister.growth_strain(E, NU, T, A, G_IIC)
    run = r.problem.interfaces.runs[0]
    assert run.delta[run.initial][:, 2].min() > -1e-4, run.delta[run.initial][:, 2].min()
