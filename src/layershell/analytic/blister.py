"""The straight-sided blister: a thin film of thickness t, delaminated over a width 2a from a thick
substrate and compressed in plane strain, buckles away from it and drives the delamination
(Hutchinson & Suo 1992, Adv. Appl. Mech. 29, 63-191: the one-dimensional blister).

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

On a base of finite thickness H held flat (every point held across the interface, free in its
plane), the axial force is the same in every section: the base under the delamination carries
the film's relief ΔP as well, its strain ε_b = ε + ΔP/(E_b H) (E_b its axial modulus), and the
buckled film follows the base's shortening, δ = t sqrt(4/3 (E' ε_b/σ_c − 1)). Then (the layered
beam of Suo & Hutchinson 1990, the base arm rigid in bending)
G = (1/(2E')) (ΔP²/t + 12 M²/t³) + ΔP²/(2 E_b H) with the film's edge moment M = σ_c t δ/2, and
tan ψ = (m cos ω + p sin ω)/(p cos ω − m sin ω), p = ΔP/(σ_c t), m = 2√3 M/(σ_c t²); the thick
base (H → ∞, ε_b = ε) gives the thin-film forms above. ``base = (H, E_b)`` selects it; ω keeps
the thick substrate's value.

All functions take NumPy arrays (elementwise) where they say so.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from layershell.material import MaterialError

#: ω of Suo & Hutchinson (1990) for a thin film on a thick substrate of the same material (α = β = 0, h/H → 0)
OMEGA_THIN_FILM = np.radians(52.07)


def plane_strain_modulus(E: float, nu: float) -> float:
    """E' = E/(1 − ν²)."""
    return E / (1.0 - nu * nu)


def critical_stress(E: float, nu: float, t: float, a: float) -> float:
    """σ_c = π² E' t²/(12 a²): the film over a delamination of width 2a, clamped at its fronts."""
    for name, v in (("E", E), ("t", t), ("a", np.min(a))):
        if not v > 0:
            raise MaterialError(f"blister: {name} = {v} must be positive (the film's modulus, thickness "
                                "and half width)")
    if not -1.0 < nu < 0.5:
        raise MaterialError(f"blister: nu = {nu} must lie in (-1, 0.5)")
    return np.pi**2 * plane_strain_modulus(E, nu) * t * t / (12.0 * a * a)


def _edge_loads(strain, E: float, nu: float, t: float, a, base):
    """p = ΔP/(σ_c t) and m = 2√3 M/(σ_c t²) at the front, σ_c, and whether the film has buckled."""
    Ep = plane_strain_modulus(E, nu)
    sc = critical_stress(E, nu, t, np.asarray(a, float))
    sig = Ep * np.asarray(strain, float)
    dP = t * np.maximum(sig - sc, 0.0)
    sig_b = sig if base is None else sig + Ep * dP / (base[1] * base[0])  # the base's strain times E'
    m = np.sqrt(3.0) * np.sqrt(4.0 / 3.0 * np.maximum(sig_b / sc - 1.0, 0.0))  # √3 δ/t
    return dP / (sc * t), m, sc, sig > sc


def energy_release_rate(strain, E: float, nu: float, t: float, a, base: tuple[float, float] | None = None):
    """G at each front for the film's compressive strain ``strain`` (positive, plane strain:
    σ = E' ε) where it is bonded: with a thick base (``base`` None) G0 (1 − σ_c/σ)(1 + 3 σ_c/σ),
    on a base (H, E_b) held flat the layered-beam form of the module docstring; 0 below σ_c."""
    p, m, sc, buckled = _edge_loads(strain, E, nu, t, a, base)
    G = sc * sc * t / (2.0 * plane_strain_modulus(E, nu)) * (p * p + m * m)
    if base is not None:
        G = G + (p * sc * t) ** 2 / (2.0 * base[1] * base[0])
    return np.where(buckled, G, 0.0)


def buckle_height(strain, E: float, nu: float, t: float, a, base: tuple[float, float] | None = None):
    """δ = t sqrt(4/3 (σ_b/σ_c − 1)): the height of the buckled film at the middle (0 below σ_c),
    σ_b = E' ε_b (= σ on a thick base)."""
    return t * _edge_loads(strain, E, nu, t, a, base)[1] / np.sqrt(3.0)


def mode_angle(strain, E: float, nu: float, t: float, a, omega: float = OMEGA_THIN_FILM,
               base: tuple[float, float] | None = None):
    """ψ (radians, in (−π, 0)) of the front beyond buckling: tan ψ = K_II/K_I as in the module
    docstring; −π/2 is pure mode II."""
    p, m, _, _ = _edge_loads(strain, E, nu, t, a, base)
    return np.arctan2(-(m * np.cos(omega) + p * np.sin(omega)), m * np.sin(omega) - p * np.cos(omega))


def mode_ii_share(strain, E: float, nu: float, t: float, a, omega: float = OMEGA_THIN_FILM,
                  base: tuple[float, float] | None = None):
    """B = G_II/G = sin² ψ (of the film's share of G: the base's term ΔP²/(2 E_b H) is left out
    of the mix)."""
    return np.sin(mode_angle(strain, E, nu, t, a, omega, base)) ** 2


def bk_toughness(B, G_Ic: float, G_IIc: float, eta: float):
    """G_c = G_Ic + (G_IIc − G_Ic) B^η (Benzeggagh & Kenane 1996), the cohesive law's criterion."""
    return G_Ic + (G_IIc - G_Ic) * np.asarray(B, float) ** eta


def growth_strain(E: float, nu: float, t: float, a: float, G_Ic: float, G_IIc: float | None = None,
                  eta: float = 2.0, omega: float = OMEGA_THIN_FILM, base: tuple[float, float] | None = None) -> float:
    """The film's compressive strain at which the delamination of width 2a starts to grow:
    G = G_c(B) with the mode mix B of the front (:func:`mode_ii_share`); with ``G_IIc`` None the
    toughness G_Ic regardless of the mode. Raises ValueError where growth would need a state
    past pure mode II (on a thick base σ/σ_c > 7.55: the front closes and the formula does not
    hold)."""
    eps_c = critical_stress(E, nu, t, a) / plane_strain_modulus(E, nu)

    def opening(e: float) -> float:  # ∝ K_I: zero at pure mode II
        p, m, _, _ = _edge_loads(e, E, nu, t, a, base)
        return float(m * np.sin(omega) - p * np.cos(omega))

    eps_ii = brentq(opening, eps_c * (1.0 + 1e-9), 1e3 * eps_c, xtol=1e-14 * eps_c, rtol=1e-12)

    def excess(e: float) -> float:
        Gc = G_Ic if G_IIc is None else bk_toughness(mode_ii_share(e, E, nu, t, a, omega, base), G_Ic, G_IIc, eta)
        return float(energy_release_rate(e, E, nu, t, a, base)) - float(Gc)

    if excess(eps_ii) < 0.0:
        raise ValueError(f"the film of t = {t} over 2a = {2 * a} reaches pure mode II (strain {eps_ii:.4g}) "
                         "before G reaches the toughness: the blister formula does not hold there")
    return float(brentq(excess, eps_c * (1.0 + 1e-9), eps_ii, xtol=1e-14 * eps_ii, rtol=1e-12))
