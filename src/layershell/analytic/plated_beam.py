"""Closed-form interfacial stresses in a simply supported beam with a bonded soffit plate that
stops short of the supports: the independent reference of the peel and shear stress at a plate end.

Smith & Teng (2001), *Interfacial stresses in plated beams*, Eng. Struct. 23:857-871. The beam
(1, above: E_1, I_1, A_1, y_1 = distance of its soffit from its centroid) and the plate (2, below:
E_2, I_2, A_2, y_2 = distance of its top face from its centroid, width b_2) are Euler-Bernoulli
beams joined by an adhesive layer of thickness t_a whose shear τ = G_a/t_a (u_2 - u_1) and peel
σ = E_a/t_a (w_2 - w_1) are constant through its thickness (w downward). With x measured from the
plate end into the plate, equal curvature of beam and plate in the shear equation, and the
total moment M_T and shear V_T of the section (statics of the simply supported span L with a
uniform load q per length, the plate end at a from the support):

    τ'' - λ² τ + m₂ V_T = 0,   λ² = G_a b_2/t_a [(y_1 + y_2)(y_1 + y_2 + t_a)/(E_1I_1 + E_2I_2)
                                                  + 1/(E_1A_1) + 1/(E_2A_2)],
    m₂ = G_a/t_a (y_1 + y_2)/(E_1I_1 + E_2I_2),   m₁ = m₂/λ²,   N_2(0) = 0:
    τ(x) = (m₂ M_T(0) - m₁ q)/λ e^{-λx} + m₁ V_T(x)

    σ'''' + 4β⁴ σ + E_a b_2/t_a (y_1/(E_1I_1) - y_2/(E_2I_2)) τ' + E_a q/(t_a E_1I_1) = 0,
    4β⁴ = E_a b_2/t_a (1/(E_1I_1) + 1/(E_2I_2)),
    σ(x) = e^{-βx} (C₁ cos βx + C₂ sin βx) - n₁ τ'(x) - n₂ q,
    n₁ = (y_1 E_2I_2 - y_2 E_1I_1)/(E_1I_1 + E_2I_2),   n₂ = E_2I_2/(b_2 (E_1I_1 + E_2I_2)),

with C₁, C₂ from the free plate end (M_2(0) = V_2(0) = 0): σ''(0) = E_a M_T(0)/(t_a E_1I_1),
σ'''(0) = E_a/t_a [V_T(0)/(E_1I_1) - b_2 τ(0) (y_1/(E_1I_1) - y_2/(E_2I_2))] (Smith & Teng's
eqs. for C₁, C₂). Peel σ > 0 is tension (the plate pulled off the beam).

The closed form neglects the shear deformation of beam and plate, the stress-free end face of
the continuum (τ(0) ≠ 0 here) and the variation of the stresses through the adhesive.
tests/test_recovery_layer_end.py checks it against the two-beam equations solved numerically and
uses it as the reference of the peel stress at a plate end.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class PlatedBeam:
    """A simply supported beam of span ``L`` under a uniform load ``q`` (force per length),
    strengthened by a plate bonded to its soffit from ``a`` to L - a (consistent units).
    Beam 1: modulus E1, rectangular b1 × h1; plate 2: E2, b2 × t2; adhesive: E_a, G_a, t_a."""

    E1: float
    b1: float
    h1: float
    E2: float
    b2: float
    t2: float
    E_a: float
    G_a: float
    t_a: float
    L: float
    a: float
    q: float

    def _sections(self):
        EI1 = self.E1 * self.b1 * self.h1**3 / 12
        EI2 = self.E2 * self.b2 * self.t2**3 / 12
        EA1 = self.E1 * self.b1 * self.h1
        EA2 = self.E2 * self.b2 * self.t2
        return EI1, EI2, EA1, EA2, self.h1 / 2, self.t2 / 2

    def _statics(self):
        """M_T(0), V_T(0) at the plate end."""
        a, L, q = self.a, self.L, self.q
        return q * a * (L - a) / 2, q * (L / 2 - a)

    def _shear_constants(self):
        EI1, EI2, EA1, EA2, y1, y2 = self._sections()
        ks = self.G_a / self.t_a
        lam2 = ks * self.b2 * ((y1 + y2) * (y1 + y2 + self.t_a) / (EI1 + EI2) + 1 / EA1 + 1 / EA2)
        m2 = ks * (y1 + y2) / (EI1 + EI2)
        lam = np.sqrt(lam2)
        M0, _ = self._statics()
        B = (m2 * M0 - m2 / lam2 * self.q) / lam
        return lam, m2 / lam2, B

    def shear(self, x) -> np.ndarray:
        """Interfacial shear stress τ(x), x from the plate end (τ > 0 drives the plate towards midspan)."""
        lam, m1, B = self._shear_constants()
        x = np.asarray(x, float)
        return B * np.exp(-lam * x) + m1 * self.q * (self.L / 2 - self.a - x)

    def peel(self, x) -> np.ndarray:
        """Interfacial normal (peel) stress σ(x), x from the plate end; tension positive."""
        EI1, EI2, _, _, y1, y2 = self._sections()
        lam, m1, B = self._shear_constants()
        kn = self.E_a / self.t_a
        beta = (kn * self.b2 / 4 * (1 / EI1 + 1 / EI2)) ** 0.25
        n1 = (y1 * EI2 - y2 * EI1) / (EI1 + EI2)
        n2 = EI2 / (self.b2 * (EI1 + EI2))
        M0, V0 = self._statics()
        tau0 = B + m1 * V0
        # second and third derivatives at x = 0 of the free plate end and of the particular part
        d2 = kn * M0 / EI1
        d3 = kn * (V0 / EI1 - self.b2 * tau0 * (y1 / EI1 - y2 / EI2))
        p2 = n1 * lam**3 * B  # (-n1 τ')'' at 0
        p3 = -n1 * lam**4 * B  # (-n1 τ')''' at 0
        C2 = (p2 - d2) / (2 * beta**2)
        C1 = (d3 - p3) / (2 * beta**3) - C2
        x = np.asarray(x, float)
        dtau = -lam * B * np.exp(-lam * x) - m1 * self.q
        return np.exp(-beta * x) * (C1 * np.cos(beta * x) + C2 * np.sin(beta * x)) - n1 * dtau - n2 * self.q
