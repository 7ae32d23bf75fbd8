"""The straight-sided blister: a thin film of thickness t, delaminated over a width 2a from a thick
substrate and compressed in plane strain, buckles away from it and drives the delamination
(Hutchinson & Suo 1992, Adv. Appl. Mech. 29, 63-191, section 6.2: the one-dimensional blister).

With the film clamped at the delamination front and E' = E/(1 − ν²):

- the film buckles at the compressive stress σ_c = π² E' t² / (12 a²) (Euler, clamped-clamped
  over the length 2a);
- beyond it, with σ the film's compressive stress where it is bonded (σ = E' ε in plane strain),
  the energy release rate at each front is G = G0 (1 − σ_c/σ)(1 + 3 σ_c/σ), G0 = t σ²/(2 E') the
  elastic energy per area of the bonded film;
- the mode mix at the front, from the film's edge force ΔP = t (σ − σ_c) and moment M (Suo &
  Hutchinson 1990, a thin film on a thick substrate of the same material: ω = 52.07°):
  tan ψ = (4 cos ω + √3 ξ sin ω)/(−4 sin ω + √3 ξ cos ω), ξ = sqrt(4/3 (σ/σ_c − 1)) the
  buckle's height over t; ψ = ω − 90° = −37.9° at σ = σ_c, pure mode II (ψ = −90°) at
  σ/σ_c = 1 + 4 tan² ω = 7.55, beyond which the crack faces would touch at the front;
- the share of mode II in G is B = sin² ψ, and with the Benzeggagh–Kenane criterion of the
  cohesive law (G_c = G_Ic + (G_IIc − G_Ic) B^η) the delamination grows where G = G_c(B).

All functions take NumPy arrays (elementwise) where they say so.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

#: ω of Suo & Hutchinson (1990) for a thin film on a thick substrate of the same material (α = β = 0, h/H → 0)
OMEGA_THIN_FILM = np.radians(52.07)


def plane_strain_modulus(E: float, nu: float) -> float:
    """E' = E/(1 − ν²)."""
    return E / (1.0 - nu * nu)


def critical_stress(E: float, nu: float, t: float, a: float) -> float:
    """σ_c = π² E' t²/(12 a²): the film over a delamination of width 2a, clamped at its fronts."""
    return np.pi**2 * plane_strain_modulus(E, nu) * t * t / (12.0 * a * a)


def energy_release_rate(strain, E: float, nu: float, t: float, a):
    """G at each front for the film's compressive strain ``strain`` (positive, plane strain:
    σ = E' ε) where it is bonded: G0 (1 − σ_c/σ)(1 + 3 σ_c/σ) beyond buckling, 0 below it."""
    Ep = plane_strain_modulus(E, nu)
    sig = Ep * np.asarray(strain, float)
    r = critical_stress(E, nu, t, np.asarray(a, float)) / np.maximum(sig, 1e-300)
    G = t * sig**2 / (2.0 * Ep) * (1.0 - r) * (1.0 + 3.0 * r)
    return np.where(r < 1.0, G, 0.0)


def buckle_height(strain, E: float, nu: float, t: float, a):
    """δ = t sqrt(4/3 (σ/σ_c − 1)): the height of the buckled film at the middle (0 below σ_c)."""
    ratio = plane_strain_modulus(E, nu) * np.asarray(strain, float) / critical_stress(E, nu, t, np.asarray(a, float))
    return t * np.sqrt(4.0 / 3.0 * np.maximum(ratio - 1.0, 0.0))


def mode_angle(strain, E: float, nu: float, t: float, a, omega: float = OMEGA_THIN_FILM):
    """ψ (radians, in (−π, 0)) of the front beyond buckling: tan ψ = K_II/K_I as in the module
    docstring; −π/2 is pure mode II."""
    xi = buckle_height(strain, E, nu, t, a) / t
    num = 4.0 * np.cos(omega) + np.sqrt(3.0) * xi * np.sin(omega)
    den = -4.0 * np.sin(omega) + np.sqrt(3.0) * xi * np.cos(omega)
    return np.arctan2(-num, -den)  # K_I ∝ −den > 0 below pure mode II, K_II ∝ −num < 0


def mode_ii_share(strain, E: float, nu: float, t: float, a, omega: float = OMEGA_THIN_FILM):
    """B = G_II/G = sin² ψ."""
    return np.sin(mode_angle(strain, E, nu, t, a, omega)) ** 2


def bk_toughness(B, G_Ic: float, G_IIc: float, eta: float):
    """G_c = G_Ic + (G_IIc − G_Ic) B^η (Benzeggagh & Kenane 1996), the cohesive law's criterion."""
    return G_Ic + (G_IIc - G_Ic) * np.asarray(B, float) ** eta


def growth_strain(E: float, nu: float, t: float, a: float, G_Ic: float, G_IIc: float | None = None,
                  eta: float = 2.0, omega: float = OMEGA_THIN_FILM) -> float:
    """The film's compressive strain at which the delamination of width 2a starts to grow:
    G = G_c(B) with the mode mix B of the front (:func:`mode_ii_share`); with ``G_IIc`` None the
    toughness G_Ic regardless of the mode. Raises ValueError where growth would need a state
    past pure mode II (σ/σ_c > 7.55: the front closes and the formula does not hold)."""
    eps_c = critical_stress(E, nu, t, a) / plane_strain_modulus(E, nu)
    eps_ii = eps_c * (1.0 + 4.0 * np.tan(omega) ** 2)  # pure mode II

    def excess(e: float) -> float:
        Gc = G_Ic if G_IIc is None else bk_toughness(mode_ii_share(e, E, nu, t, a, omega), G_Ic, G_IIc, eta)
        return float(energy_release_rate(e, E, nu, t, a)) - float(Gc)

    if excess(eps_ii) < 0.0:
        raise ValueError(f"the film of t = {t} over 2a = {2 * a} reaches pure mode II (strain {eps_ii:.4g}) "
                         "before G reaches the toughness: the blister formula does not hold there")
    return float(brentq(excess, eps_c * (1.0 + 1e-9), eps_ii, xtol=1e-14 * eps_ii, rtol=1e-12))
