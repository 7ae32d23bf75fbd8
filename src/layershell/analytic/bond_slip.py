"""Closed-form full-range response of a bonded plate in a single-lap shear (pull) test with a
bilinear bond-slip law: the independent reference of the cohesive interface in shear.

Yuan, Teng, Seracino, Wu & Yao (2004), *Full-range behavior of FRP-to-concrete bonded joints*,
Eng. Struct. 26:553-565. A plate (modulus E_p, thickness t_p, width b_p) is bonded over the length
L to a substrate (E_c, t_c, b_c); the plate is pulled at x = L, the substrate pushed at the same
end (pull-push) or held along its length (``rigid`` substrate). With the slip δ(x) (plate minus
substrate displacement) and the bond stress τ(δ), equilibrium of the plate and the substrate gives

    δ'' = β τ(δ),   β = (1 + b_p E_p t_p / (b_c E_c t_c)) / (E_p t_p),   P = b_p δ'(L) / β,

with δ'(0) = 0 at the free end. The bilinear law: τ = τ_f δ/δ₁ (0 ≤ δ ≤ δ₁), τ_f (δ_f − δ)/(δ_f − δ₁)
(δ₁ < δ ≤ δ_f), 0 beyond; G_f = τ_f δ_f / 2. Each state of the debonding process is fixed by the
free-end slip δ₀ (it grows monotonically through the whole process), and on each branch the
equation is linear with constant coefficients, so the state follows in closed form:

* elastic zone from the free end: δ = δ₀ cosh(λ₁ x), λ₁² = β τ_f/δ₁, up to x₁ where δ = δ₁;
* softening zone: δ = δ_f + (δ₁ − δ_f) cos(λ₂ s) + δ'(x₁)/λ₂ sin(λ₂ s), s = x − x₁,
  λ₂² = β τ_f/(δ_f − δ₁), up to x₂ where δ = δ_f;
* a debonded zone (τ = 0) from x₂ to L: the plate carries P with constant δ' = δ'(x₂).

If L is reached first, P = b_p δ'(L)/β and the loaded-end slip is δ(L); otherwise the load is
P = b_p δ'(x₂)/β and the loaded-end slip δ_f + (L − x₂) δ'(x₂). For long bonds the peak load is
P_u = b_p √(2 G_f / β) (= b_p √(2 G_f E_p t_p) on a rigid substrate), reached from the
effective bond length on; beyond the peak the load-slip curve snaps back.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class BondedJoint:
    """Plate, substrate and bilinear bond-slip law of a single-lap shear test (consistent units:
    E force/area, t and b length, tau_f stress, delta_1 and delta_f length)."""

    E_p: float
    t_p: float
    b_p: float
    tau_f: float
    delta_1: float
    delta_f: float
    E_c: float = np.inf  # inf: rigid substrate
    t_c: float = 1.0
    b_c: float = 1.0

    def __post_init__(self) -> None:
        if not 0.0 < self.delta_1 < self.delta_f:
            raise ValueError("the bilinear law needs 0 < delta_1 < delta_f")
        if min(self.E_p, self.t_p, self.b_p, self.tau_f, self.E_c, self.t_c, self.b_c) <= 0:
            raise ValueError("moduli, thicknesses, widths and tau_f must be positive")

    @property
    def G_f(self) -> float:
        """Interfacial fracture energy (area under the bond-slip curve)."""
        return 0.5 * self.tau_f * self.delta_f

    @property
    def beta(self) -> float:
        return (1.0 + self.b_p * self.E_p * self.t_p / (self.b_c * self.E_c * self.t_c)) / (self.E_p * self.t_p)

    @property
    def lambda_1(self) -> float:
        return float(np.sqrt(self.beta * self.tau_f / self.delta_1))

    @property
    def lambda_2(self) -> float:
        return float(np.sqrt(self.beta * self.tau_f / (self.delta_f - self.delta_1)))

    def peak_load_long(self) -> float:
        """P_u of an infinitely long bond, b_p √(2 G_f / β)."""
        return self.b_p * float(np.sqrt(2.0 * self.G_f / self.beta))

    def state(self, delta_0: np.ndarray, L: float) -> tuple[np.ndarray, np.ndarray]:
        """Load P and loaded-end slip for free-end slips ``delta_0`` (0 < δ₀ ≤ δ_f) on a bond of
        length ``L``: the whole equilibrium path, snap-back included."""
        d0 = np.atleast_1d(np.asarray(delta_0, dtype=float))
        if np.any(d0 <= 0) or np.any(d0 > self.delta_f):
            raise ValueError("free-end slips must lie in (0, delta_f]")
        l1, l2, d1, df = self.lambda_1, self.lambda_2, self.delta_1, self.delta_f
        P = np.empty_like(d0)
        s_end = np.empty_like(d0)
        # elastic zone: δ = δ₀ cosh(λ₁ x) reaches δ₁ at x₁ (if δ₀ < δ₁)
        x1 = np.where(d0 < d1, np.arccosh(np.maximum(d1 / d0, 1.0)) / l1, 0.0)
        el = x1 >= L  # the whole bond is elastic
        P[el] = self.b_p * d0[el] * l1 * np.sinh(l1 * L) / self.beta
        s_end[el] = d0[el] * np.cosh(l1 * L)
        # softening zone: from x₁ with δ(x₁) = max(δ₀, δ₁) and δ'(x₁) = δ₀ λ₁ sinh(λ₁ x₁)
        # (a free end already softening has δ'(0) = 0 and δ(0) = δ₀ > δ₁)
        so = ~el
        a = np.where(d0 < d1, d1, d0)[so] - df  # δ - δ_f = a cos(λ₂ s) + b sin(λ₂ s)
        b = (d0[so] * l1 * np.sinh(l1 * x1[so])) / l2
        # a cos θ + b sin θ = R cos(θ - φ), φ = atan2(b, a) in [π/2, π] (a ≤ 0 ≤ b): rising from
        # below, it reaches zero (δ = δ_f) first at θ = φ - π/2
        s2 = (np.arctan2(b, a) - np.pi / 2) / l2
        x2 = x1[so] + s2
        slope_at = lambda s: l2 * (-a * np.sin(l2 * s) + b * np.cos(l2 * s))  # noqa: E731
        value_at = lambda s: df + a * np.cos(l2 * s) + b * np.sin(l2 * s)  # noqa: E731
        inside = x2 >= L  # L reached inside the softening zone
        sL = L - x1[so]
        slope = np.where(inside, slope_at(sL), slope_at(s2))
        P[so] = self.b_p * slope / self.beta
        s_end[so] = np.where(inside, value_at(sL), df + (L - x2) * slope)
        return P, s_end

    def peak_load(self, L: float, samples: int = 4001) -> float:
        """Largest load on the path of a bond of length ``L`` (dense sampling of δ₀ on a
        logarithmic grid, refined around the maximum)."""
        d = np.geomspace(self.delta_f * 1e-9, self.delta_f, samples)
        P, _ = self.state(d, L)
        i = int(np.argmax(P))
        lo, hi = d[max(i - 1, 0)], d[min(i + 1, samples - 1)]
        d = np.linspace(lo, hi, samples)
        return float(self.state(d, L)[0].max())
