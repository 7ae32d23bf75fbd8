"""Length of the cohesive process zone: from the onset of damage to complete separation, along the
crack, in steady propagation; the mesh should put at least 3 node spacings into it (Turon, Dávila,
Camanho & Costa 2007).

Two limits, per mode (I: strength σ_max, G_Ic; II: τ_max, G_IIc); the estimate of a mode is the
smaller applicable one (Harper & Hallett 2008), and :func:`zone_lengths` says which it used:

* a thick body (the zone is short against the layers): ``l_thick = M E' G_c / τ0²``
  (Hillerborg et al. 1976 with M = 1; Harper & Hallett 2008 list M = 0.21 ... 1 from the
  cohesive-zone models of Hui, Irwin, Dugdale, Rice and Hillerborg). E' is the crack-tip modulus
  of the orthotropic layers, the factor between G and K² (Sih, Paris & Irwin 1965; Soto et al.
  2016 use it for the cohesive zone of orthotropic laminates): with the compliances of the plane
  of the crack (a11 = 1/E along the crack, a22 = 1/E3 across the interface, a12 = −ν/E,
  a66 = 1/G_x3) and ρ = sqrt(sqrt(a22/a11) + (2 a12 + a66)/(2 a11)),
  ``1/E'_I = sqrt(a11 a22 / 2) ρ``, ``1/E'_II = a11 ρ / sqrt 2`` (E for an isotropic layer);
  two layers: 2/E' = 1/E'_1 + 1/E'_2 (a rigid one counts 0). M = 1/π (Irwin): the prefactor
  that the zones measured in FE runs follow (tests/test_process_zone.py: DCBs of 1.5, 1.98 and
  8 mm arms and the ENF measure 0.8-1.2 times this estimate; M = 1 with E3 would be 2.2-3 times
  the DCBs' zones and 0.6 times the ENF's);
* slender layers (the zone is long against them): the layers bend and stretch as beams
  along the crack and the interface is a softening foundation. Yang & Cox (2005) and Harper &
  Hallett (2008) give the scalings ``l_I ~ (E G_Ic/σ0²)^(1/4) h^(3/4)``,
  ``l_II ~ (E G_IIc/τ0²)^(1/2) h^(1/2)`` with E the in-plane (bending) modulus along the crack.
  Here the prefactors are not fitted: the beam problems are solved for the bilinear law
  (below), which also brings in the elastic (penalty) branch. The half thickness of a layer acts
  as a local (Winkler) foundation only over lengths longer than the layer is thick: a slender
  estimate shorter than the thicker deformable layer does not apply. (Where the layers' own
  compliance across their thickness, the foundation's, stores nearly G_c before the onset,
  r → 0, the beam estimate tends to 0 while the zone does not: a DCB of 1.5 mm arms with
  E3 = 9 GPa, σ_max = 57 MPa, G_Ic = 0.28 N/mm has r = 0.013, a beam estimate of 0.013 mm
  and a zone of 0.35 mm.)

With δ0 = τ0 f the separation at the onset (f: the elastic compliance per area of the interface
and of the half-thickness of each layer next to it, the foundation of Kanninen's (1973)
augmented DCB model; in shear the same with G_x3), δf = 2 G_c/τ0, r = (δf − δ0)/δ0:

* mode II (shear lag of two layers that bend together, or the bond-slip problem of a strip
  on a rigid substrate): in the softening zone δ'' = c_II τ, so
  ``l_II = arctan(√r) / λ``, λ² = c_II τ0/(δf − δ0), c_II = Σ 1/(E_i h_i) + 3 (h_1 + h_2)²/Σ E_i h_i³
  (the closed form of the bilinear bond-slip law, Yuan, Teng, Seracino, Wu & Yao 2004, with
  c_II = 1/(E t) for a strip on a rigid substrate; π/(2λ) for a rigid-plastic onset);
* mode I (two arms as Euler-Bernoulli beams on the softening foundation, opening δ,
  δ'''' = −c_I σ, c_I = Σ 12/(E_i h_i³), the crack tip shear-free as for a long crack):
  ``l_I = x(r)/μ``, μ⁴ = c_I σ0/(δf − δ0), x(r) the root of the matching of the softening zone
  (y = δf − δ = A (cosh − cos) + B (sinh + sin) of μs) to the elastic foundation ahead
  (δ = δ0 e^(−βt)(cos βt + F sin βt), (β/μ)⁴ = r/4) in slope, moment and shear (:func:`_x_mode_i`).

Where the foundation has no softening branch (r ≤ 0: the layers' own compliance stores more
than G_c before the onset) there is no slender estimate.

References: Hillerborg, Modéer & Petersson (1976), Cem. Concr. Res. 6, 773-782; Sih, Paris &
Irwin (1965), Int. J. Fract. Mech. 1, 189-203; Kanninen (1973), Int. J. Fract. 9, 83-92
(augmented DCB: arms on an elastic foundation of the half thickness); Yang & Cox (2005),
Int. J. Fract. 133, 107-137; Harper & Hallett (2008), Eng. Fract. Mech. 75, 4774-4792; Yuan,
Teng, Seracino, Wu & Yao (2004), Eng. Struct. 26, 553-565; Turon, Dávila, Camanho & Costa
(2007), Eng. Fract. Mech. 74, 1665-1682; Soto, González, Lopes & Mayugo (2016), "Cohesive zone
length of orthotropic materials undergoing delamination", Eng. Fract. Mech. 159, 174-188.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


#: the prefactor M of the thick-body estimate M E' G_c/τ0² (Irwin's 1/π; module docstring)
THICK_FACTOR = 1.0 / np.pi


@dataclass(frozen=True)
class Arm:
    """One layer next to the interface: thickness h, in-plane modulus E along the crack,
    modulus E3 across the interface, transverse shear modulus G (x-3) along the crack and the
    Poisson ratio nu = −E S_x3 of the plane of the crack (strain across the interface under a
    stress along the crack)."""

    h: float
    E: float
    E3: float
    G: float
    nu: float = 0.0


def crack_tip_moduli(arm: Arm) -> tuple[float, float]:
    """E'_I and E'_II of one layer (Sih, Paris & Irwin 1965; module docstring): G = K²/E' for a
    crack along the layer; inf for a rigid layer, E for an isotropic one."""
    if not np.isfinite(arm.E):
        return float("inf"), float("inf")
    a11, a22, a12, a66 = 1.0 / arm.E, 1.0 / arm.E3, -arm.nu / arm.E, 1.0 / arm.G
    rho = np.sqrt(np.sqrt(a22 / a11) + (2 * a12 + a66) / (2 * a11))
    return float(1.0 / (np.sqrt(a11 * a22 / 2) * rho)), float(np.sqrt(2.0) / (a11 * rho))


def _x_mode_i(r: float) -> float:
    """Dimensionless mode-I softening length x = μ l (module docstring) for r = (δf − δ0)/δ0."""
    b = (r / 4.0) ** 0.25

    def resid(L: float) -> float:
        ch, sh, c, s = np.cosh(L), np.sinh(L), np.cos(L), np.sin(L)
        g0, g1, g2, g3 = (ch - c, sh + s), (sh + s, ch + c), (ch + c, sh - s), (sh - s, ch - c)
        M = np.array([[g0[0], g0[1], 0.0], [g1[0], g1[1], b], [g2[0], g2[1], -2 * b * b]])
        A, B, F = np.linalg.solve(M, [r, b, 0.0])
        return A * g3[0] + B * g3[1] + 2 * b**3 * (F + 1)

    Ls = np.linspace(1e-3, 8.0, 801)
    v = np.array([resid(L) for L in Ls])
    i = np.flatnonzero(np.sign(v[:-1]) != np.sign(v[1:]))
    if i.size == 0:
        return float("nan")
    from scipy.optimize import brentq

    return float(brentq(resid, Ls[i[0]], Ls[i[0] + 1], xtol=1e-10))


def zone_lengths(G_Ic: float, G_IIc: float, sigma_max: float, tau_max: float, K: float,
                 arms: tuple[Arm, Arm]) -> dict[str, dict]:
    """Per mode ("I", "II"): ``thick`` (M E' G_c/τ0²), ``slender`` (beam estimate, inf where
    it does not apply), ``length`` = the smaller applicable one and ``used`` ("thick" or
    "slender"; module docstring). ``K``: the interface's penalty stiffness per area; ``arms``:
    the layers on both sides."""
    moduli = np.array([crack_tip_moduli(a) for a in arms])  # (2, mode)
    E_tip = 2.0 / np.sum(1.0 / moduli, axis=0)
    h_max = max(a.h for a in arms if np.isfinite(a.E))  # a rigid layer is no foundation
    out = {}
    for m, (mode, G, s) in enumerate((("I", G_Ic, sigma_max), ("II", G_IIc, tau_max))):
        thick = THICK_FACTOR * E_tip[m] * G / s**2
        slender = _slender(mode, G, s, K, arms)
        if slender < h_max:  # a foundation of the half thickness only over lengths longer than it
            slender = float("inf")
        used = "slender" if slender < thick else "thick"
        out[mode] = {"thick": float(thick), "slender": slender, "length": float(min(thick, slender)), "used": used}
    return out


def _slender(mode: str, G: float, s: float, K: float, arms: tuple[Arm, Arm]) -> float:
    """The beam estimate of the mode (module docstring); inf without a softening branch."""
    if mode == "I":
        f = 1.0 / K + sum(a.h / (2 * a.E3) for a in arms)
    else:
        f = 1.0 / K + sum(a.h / (2 * a.G) for a in arms)
    d0, df = s * f, 2 * G / s
    r = (df - d0) / d0
    if r <= 1e-6:
        return float("inf")
    if mode == "I":
        c = sum(12.0 / (a.E * a.h**3) for a in arms)
        x = _x_mode_i(r)
        return float(x / (c * s / (df - d0)) ** 0.25) if np.isfinite(x) else float("inf")
    c = (sum(1.0 / (a.E * a.h) for a in arms)
         + 3 * sum(a.h for a in arms) ** 2 / sum(a.E * a.h**3 for a in arms))
    return float(np.arctan(np.sqrt(r)) / np.sqrt(c * s / (df - d0)))


def in_plane_modulus(mat, angle: float) -> tuple[float, float, float]:
    """In-plane modulus E(θ), transverse shear modulus G_θ3 and Poisson ratio ν = −E(θ) S_θ3 of
    an orthotropic layer along a direction at ``angle`` from its material axis 1 (rotation in
    the 1-2 plane; S_θ3 = c² S_13 + s² S_23, S_13 = −ν31/E3, S_23 = −ν23/E2)."""
    c, s = np.cos(angle), np.sin(angle)
    inv = c**4 / mat.E1 + s**4 / mat.E2 + c * c * s * s * (1.0 / mat.G12 - 2 * mat.nu12 / mat.E1)
    G = 1.0 / (c * c / mat.G31 + s * s / mat.G23)
    S3 = -(c * c * mat.nu31 / mat.E3 + s * s * mat.nu23 / mat.E2)
    return 1.0 / inv, G, -S3 / inv
