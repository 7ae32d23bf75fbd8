"""Delamination criterion and post-fracture friction laws, MODEL.md §9-§10 / thesis ch. 4.

Pure functions over arrays; tractions are the physical Cauchy components of the upper layer's
surface traction (σ13, σ23 shear, σ33 normal, tension positive), thesis (3.33).
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class InterfaceLaw:
    """Parameters of one interface (between a layer and the one below it).

    sigma_max, tau_max, p: failure surface (4.15)-(4.21); mu0, mu, gT_mu: adhesive slip-
    softening friction (4.70)-(4.78) (``gT_mu = inf``: constant μ0 τ_Delam); mu_coulomb: Coulomb
    fallback (4.84); alpha_N: normal contact penalty (None: 100 E_3,max / H_min); alpha_T: stick
    penalty of the regularised friction (None: G_13/H of the thinner layer); open_gap: a gap larger than this counts as open
    (no friction; None: 0.1 × the upper layer's thickness); rule: the face points of the contact
    and friction between debonded layers, "gauss" (the thesis's (3.48)) or "lobatto" (the nodes:
    no traction oscillation of the stiff penalty, whose contact set can cycle at the Gauss points
    of refined meshes); the criterion (4.15) is evaluated at the Gauss points either way;
    rule_auto: the rule was not given in the model file - the contact starts at the Gauss points
    and moves to the nodes where their contact set finds no equilibrium
    (:meth:`~layershell.solver.interface_state.InterfaceController.contact_to_nodes`).
    """

    sigma_max: float
    tau_max: float
    p: float = 2.0
    mu0: float = 0.95
    mu: float = 0.2
    gT_mu: float = float("inf")
    mu_coulomb: float = 0.0
    alpha_N: float | None = None
    alpha_T: float | None = None
    open_gap: float | None = None
    rule: str = "gauss"
    rule_auto: bool = False

    def check(self, name: str = "interface") -> None:
        bad = []
        if not self.sigma_max > 0:
            bad.append(f"sigma_max = {self.sigma_max} must be positive")
        if not self.tau_max > 0:
            bad.append(f"tau_max = {self.tau_max} must be positive")
        if not self.p >= 1:
            bad.append(f"p = {self.p} must be >= 1 (p = 1 is the cone, (4.19))")
        if not 0 <= self.mu0 <= 1:
            bad.append(f"mu0 = {self.mu0} must lie in [0, 1] (4.70)")
        if not 0 < self.mu <= 1:
            bad.append(f"mu = {self.mu} must lie in (0, 1] (4.77)")
        if not self.gT_mu > 0:
            bad.append(f"gT_mu = {self.gT_mu} must be positive (use inf for constant friction)")
        if not self.mu_coulomb >= 0:
            bad.append(f"mu_coulomb = {self.mu_coulomb} must not be negative")
        if self.rule not in ("gauss", "lobatto"):
            bad.append(f"rule = {self.rule!r}: use \"gauss\" (the thesis's face points) or \"lobatto\" (the nodes)")
        if self.open_gap is not None and not self.open_gap > 0:
            bad.append(f"open_gap = {self.open_gap} must be positive (leave it out for 0.1 × the layer thickness)")
        if bad:
            raise ValueError(f"{name}: " + "; ".join(bad))


def tau_delam(sigma33, law: InterfaceLaw):
    """Admissible bond shear τ_Delam(σ33) = τ_max (1 - σ33/σ_max)^(1/p) (4.21); 0 beyond σ_max."""
    s = np.asarray(sigma33, float)
    base = np.clip(1.0 - s / law.sigma_max, 0.0, None)
    return law.tau_max * base ** (1.0 / law.p)


def failure_function(traction, law: InterfaceLaw):
    """V = |τ| - τ_Delam(σ33) (4.15); ``traction (..., 3)`` = [σ13, σ23, σ33].

    Returns (V, failed) with failed = V >= 0 or σ33 >= σ_max (4.16), (4.20)."""
    t = np.asarray(traction, float)
    shear = np.hypot(t[..., 0], t[..., 1])
    V = shear - tau_delam(t[..., 2], law)
    return V, (V >= 0) | (t[..., 2] >= law.sigma_max)


def tau_slide_start(sigma33, law: InterfaceLaw):
    """Friction limit right after fracture τ^Gleit_Delam = μ0 τ_Delam(min(σ33, 0)) (4.70)."""
    return law.mu0 * tau_delam(np.minimum(np.asarray(sigma33, float), 0.0), law)


def tau_slide(sigma33, gmax, law: InterfaceLaw):
    """Slip-softening limit τ^Gleit_max (4.76): τ^Gleit_Delam / (1 + (1/μ - 1)(g_max/g_T^μ)²),
    with the Coulomb law μ_C |σ33| (4.84)-(4.85, erratum E11) as a lower bound."""
    t0 = tau_slide_start(sigma33, law)
    ratio = np.asarray(gmax, float) / law.gT_mu if np.isfinite(law.gT_mu) else 0.0 * np.asarray(gmax, float)
    soft = t0 / (1.0 + (1.0 / law.mu - 1.0) * ratio**2)
    coulomb = law.mu_coulomb * np.abs(np.minimum(np.asarray(sigma33, float), 0.0))
    return np.maximum(soft, coulomb)


def return_map_at_fracture(traction, law: InterfaceLaw):
    """Return mapping right after fracture (4.71)-(4.73): tensile σ33 is set to zero, the trial
    shear is scaled radially onto τ^Gleit_Delam(σ'33). Returns the mapped traction (..., 3)."""
    t = np.array(traction, float, copy=True)
    t[..., 2] = np.minimum(t[..., 2], 0.0)
    shear = np.hypot(t[..., 0], t[..., 1])
    lim = tau_slide_start(t[..., 2], law)
    pos = shear > 1e-12 * law.tau_max  # a vanishing trial shear maps to zero
    unit = t[..., :2] / np.where(pos, shear, 1.0)[..., None]
    t[..., :2] = np.where(pos[..., None], unit * lim[..., None], 0.0)
    return t
