"""Length of the cohesive process zone (issue 13 item 4): from the onset of damage to complete
separation, along the crack, in steady propagation; the mesh should put at least 3 node
spacings into it (Turon, Dávila, Camanho & Costa 2007).

Two limits, per mode (I: strength σ_max, G_Ic; II: τ_max, G_IIc):

* a thick body (the zone is short against the layers): Hillerborg et al. (1976), with the
  modulus across the interface as Turon et al. (2007) use it, M = 1:
  ``l_inf = E3 G_c / τ0²``;
* slender layers (the zone is long against them): the layers bend and stretch as beams
  along the crack and the interface is a softening foundation. Yang & Cox (2005) and Harper &
  Hallett (2008, Eng. Fract. Mech. 75, 4774-4792) give the scalings
  ``l_I ~ (E G_Ic/σ0²)^(1/4) h^(3/4)``, ``l_II ~ (E G_IIc/τ0²)^(1/2) h^(1/2)`` with E the
  in-plane (bending) modulus along the crack. Here the prefactors are not fitted: the beam
  problems are solved for the bilinear law (below), which also brings in the elastic
  (penalty) branch.

The estimate of a mode is the smaller of the two (the slender result where the layers are
slender, Harper & Hallett 2008). With δ0 = τ0 f the separation at the onset (f: the elastic
compliance per area of the interface and of the half-thickness of each layer next to it, the
foundation of Kanninen's (1973) augmented DCB model; in shear the same with G_x3), δf = 2 G_c/τ0,
r = (δf − δ0)/δ0:

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

References: Hillerborg, Modéer & Petersson (1976), Cem. Concr. Res. 6, 773-782; Kanninen (1973),
Int. J. Fract. 9, 83-92 (augmented DCB: arms on an elastic foundation of the half thickness);
Yang & Cox (2005), Int. J. Fract. 133, 107-137; Harper & Hallett (2008), Eng. Fract. Mech. 75,
4774-4792; Yuan, Teng, Seracino, Wu & Yao (2004), Eng. Struct. 26, 553-565; Turon, Dávila,
Camanho & Costa (2007), Eng. Fract. Mech. 74, 1665-1682. Soto et al. (2016, "Cohesive zone length
of orthotropic materials undergoing delamination", Eng. Fract. Mech.) fit empirical prefactors
for orthotropic arms; the prefactors here are not fitted.

Where the effective law has no softening branch (r ≤ 0: the layers' own compliance stores
more than G_c before the onset) the slender estimate does not apply and l_inf is used.
The FE check (tests/test_process_zone.py) measures the zone along the crack in the DCB and ENF
examples and in the lap-shear example.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Arm:
    """One layer next to the interface: thickness h, in-plane modulus E along the crack,
    modulus E3 across the interface, transverse shear modulus G (x-3) along the crack."""

    h: float
    E: float
    E3: float
    G: float


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
                 arms: tuple[Arm, Arm]) -> dict[str, dict[str, float]]:
    """Per mode ("I", "II"): ``thick`` (l_inf), ``slender`` (beam estimate, inf where it does
    not apply) and ``length`` = the smaller (module docstring). ``K``: the interface's
    penalty stiffness per area; ``arms``: the layers on both sides."""
    E3 = min(a.E3 for a in arms)
    out = {}
    for mode, G, s in (("I", G_Ic, sigma_max), ("II", G_IIc, tau_max)):
        thick = E3 * G / s**2
        if mode == "I":
            f = 1.0 / K + sum(a.h / (2 * a.E3) for a in arms)
        else:
            f = 1.0 / K + sum(a.h / (2 * a.G) for a in arms)
        d0, df = s * f, 2 * G / s
        r = (df - d0) / d0
        slender = float("inf")
        if r > 1e-6:
            if mode == "I":
                c = sum(12.0 / (a.E * a.h**3) for a in arms)
                x = _x_mode_i(r)
                if np.isfinite(x):
                    slender = float(x / (c * s / (df - d0)) ** 0.25)
            else:
                c = (sum(1.0 / (a.E * a.h) for a in arms)
                     + 3 * sum(a.h for a in arms) ** 2 / sum(a.E * a.h**3 for a in arms))
                slender = float(np.arctan(np.sqrt(r)) / np.sqrt(c * s / (df - d0)))
        out[mode] = {"thick": thick, "slender": slender, "length": min(thick, slender)}
    return out


def in_plane_modulus(mat, angle: float) -> tuple[float, float]:
    """In-plane modulus E(θ) and transverse shear modulus G_θ3 of an orthotropic layer along a
    direction at ``angle`` from its material axis 1 (rotation in the 1-2 plane)."""
    c, s = np.cos(angle), np.sin(angle)
    inv = c**4 / mat.E1 + s**4 / mat.E2 + c * c * s * s * (1.0 / mat.G12 - 2 * mat.nu12 / mat.E1)
    G = 1.0 / (c * c / mat.G31 + s * s / mat.G23)
    return 1.0 / inv, G
