"""Cohesive (energy-based) interface law: damage onset by a strength criterion,
propagation by the fracture energies G_Ic, G_IIc with the Benzeggagh–Kenane mixed-mode law.

Material point (pure functions over arrays of points). Separation δ = Δu (upper layer's bottom
face relative to the lower layer's top face, :mod:`layershell.contact`), split along the
undeformed normal A3 into δ_n = δ·A3 and the tangential vector δ_s = (I - A3⊗A3) δ. One initial
(penalty) stiffness K per area in both directions (Turon, Dávila, Camanho & Costa 2007:
K = α E3 / t, α ≈ 50). With the damage d ∈ [0, 1] (Camanho & Dávila 2002; Turon et al. 2006):

    t = K δ - d K (<δ_n> A3 + δ_s)                 (compression δ_n < 0 never damages)
    λ = sqrt(<δ_n>² + |δ_s|²)                       equivalent separation
    B = |δ_s|² / λ²                                 mode ratio G_shear / G_T (equal stiffness)
    G_c(B) = G_Ic + (G_IIc - G_Ic) B^η              Benzeggagh & Kenane 1996
    λ0(B): onset, where the undamaged traction K λ meets the strength criterion
      * "thesis":    |τ| = τ_max (1 - σ/σ_max)^(1/p)  (thesis (4.15), (4.21)), σ = K <δ_n>, |τ| = K |δ_s|
      * "quadratic": (<σ>/σ_max)² + (|τ|/τ_max)² = 1
    λf(B) = 2 G_c(B) / (K λ0(B))                    bilinear: the area under t(λ) is G_c(B)
    d_trial = λf (λ - λ0) / (λ (λf - λ0)) clipped to [0, 1]    (bilinear)
    d_trial = 1 - (λ0/λ) exp(-(λ - λ0)/λc), λc = (G_c - K λ0²/2) / (K λ0)    (exponential)
    d = max(d_old, d_trial)                         irreversible, d_old the last converged value

With d itself as the history variable the damage never decreases when the mode ratio changes
(the concern of Turon et al. 2010), and a proportional path dissipates exactly G_c(B). The
consistent tangent includes ∂d/∂λ and ∂d/∂B (through λ0(B), λf(B)) where the damage grows.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: damage counted as "fully debonded" (first_delamination_load_factor, debonded area)
FULL_DAMAGE = 1.0 - 1e-9


@dataclass(frozen=True)
class CohesiveLaw:
    """Parameters of a cohesive interface.

    G_Ic, G_IIc: fracture energies (energy per area); eta: Benzeggagh–Kenane exponent;
    sigma_max, tau_max, p: strengths and exponent of the onset criterion; onset: "thesis" (4.15)
    or "quadratic"; softening: "bilinear" or "exponential"; K0: penalty stiffness per area
    (None: alpha E3/t of the adjacent layers); alpha: the factor of that default (Turon 2007);
    viscosity: Gao & Bower (2004) regularisation time in load-factor units (0: off);
    mu0, mu, gT_mu, mu_coulomb: the thesis's adhesive slip-softening friction (4.70)-(4.84),
    which acts on the damaged share of a point under compression; alpha_T: its stick penalty
    (None: K0), reduced per point where the slip limit is below tau_max (:func:`stick_penalty`);
    rule: "lobatto" (nodal, default) or "gauss" integration of the interface.
    """

    G_Ic: float
    G_IIc: float
    sigma_max: float
    tau_max: float
    eta: float = 2.0
    p: float = 2.0
    onset: str = "thesis"
    softening: str = "bilinear"
    K0: float | None = None
    alpha: float = 50.0
    viscosity: float = 0.0
    mu0: float = 0.95
    mu: float = 0.2
    gT_mu: float = float("inf")
    mu_coulomb: float = 0.0
    alpha_T: float | None = None
    rule: str = "lobatto"

    def check(self, name: str = "interface") -> None:
        """Raise ValueError with one message naming every bad field and its fix."""
        bad = []
        for key in ("G_Ic", "G_IIc"):
            v = getattr(self, key)
            if v is None or not v > 0:
                bad.append(f"'{name}.{key}' = {v}: the fracture energy must be a positive energy per area "
                           f"(e.g. N/mm = kN/m for a bond); take it from a fracture test or the literature")
        for key in ("sigma_max", "tau_max"):
            v = getattr(self, key)
            if v is None or not v > 0:
                bad.append(f"'{name}.{key}' = {v}: the strength of the onset criterion must be positive")
        if not self.eta > 0:
            bad.append(f"'{name}.eta' = {self.eta}: the Benzeggagh–Kenane exponent must be positive (1-3 typical)")
        if not self.p >= 1:
            bad.append(f"'{name}.p' = {self.p}: must be >= 1 (4.19)")
        if self.onset not in ("thesis", "quadratic"):
            bad.append(f"'{name}.onset' = {self.onset!r}: use \"thesis\" or \"quadratic\"")
        if self.softening not in ("bilinear", "exponential"):
            bad.append(f"'{name}.softening' = {self.softening!r}: use \"bilinear\" or \"exponential\"")
        if self.K0 is not None and not self.K0 > 0:
            bad.append(f"'{name}.K0' = {self.K0}: the penalty stiffness must be positive (or left out)")
        if not self.alpha > 0:
            bad.append(f"'{name}.alpha' = {self.alpha}: must be positive (about 50, Turon et al. 2007)")
        if not self.viscosity >= 0:
            bad.append(f"'{name}.viscosity' = {self.viscosity}: must not be negative (0 switches it off)")
        if self.rule not in ("lobatto", "gauss"):
            bad.append(f"'{name}.rule' = {self.rule!r}: use \"lobatto\" (nodal) or \"gauss\"")
        if bad:
            raise ValueError("; ".join(bad))

    def G_c(self, B):
        """Benzeggagh–Kenane mixed-mode fracture energy G_c(B) (BK 1996)."""
        return self.G_Ic + (self.G_IIc - self.G_Ic) * np.asarray(B, float) ** self.eta

    def process_zone_length(self, E: float) -> float:
        """l_cz = E G_c / τ0² with the smaller of the two modes' ratios (Turon et al. 2007, M = 1):
        the process zone in a thick body. Slender layers have other lengths (mode I much shorter
        in a DCB): the process-zone warning uses :mod:`layershell.process_zone`."""
        return E * min(self.G_Ic / self.sigma_max**2, self.G_IIc / self.tau_max**2)


# ---------------------------------------------------------------------- friction
def stick_penalty(alpha_T: float, cap: np.ndarray, tau_max: float) -> np.ndarray:
    """Stick penalty (e, q) of the friction on the damaged share: α_T min(1, cap/τ_max) at a point
    with the slip limit ``cap`` > 0 (α_T where there is no friction).

    With one α_T for all points a point sticks only while its slip from the anchor stays below
    cap/α_T, which vanishes with the contact pressure: with α_T = K0 = 50 E3/H the points of low
    pressure at the TRC slab's end-debonding peak stuck over 10⁻¹¹-10⁻¹⁰ m (rigid-plastic
    friction), and where their slip had to reverse the return mapping threw their friction force
    from +cap to -cap between Newton iterates, so the residual stalled (docs/performance.md).
    Scaled so, every point sticks elastically over at least τ_max/α_T - with the default α_T =
    K0 the slip at which the intact bond reaches its shear strength - a fixed elastic slip rather
    than a fixed stiffness, as in the penalty friction of commercial codes (Abaqus's maximum
    elastic slip). It regularises: with a stiff K0 (50 E3/H) the answer does not depend on it
    (the §5.1 plate: to 10⁻¹¹, tests/test_cohesive_interface.py); where K0 is a bond-slip law's
    own (the lap shear, τ_max/K0 = 0.064 mm) the friction mobilises over that slip and its share
    of the peak is smaller than the rigid-plastic one (+0.31 % against +0.35 % of P_u,
    tests/test_lapshear.py); a larger ``alpha_T`` shortens the range."""
    ratio = np.minimum(np.asarray(cap, float) / tau_max, 1.0)
    return alpha_T * np.where(ratio > 0.0, ratio, 1.0)


# ---------------------------------------------------------------------- onset
def onset(B: np.ndarray, K: float, law: CohesiveLaw) -> tuple[np.ndarray, np.ndarray]:
    """λ0(B) and dλ0/dB: the equivalent separation at which the undamaged traction K λ (normal
    share sqrt(1-B), shear share sqrt(B)) meets the onset criterion."""
    B = np.clip(np.asarray(B, float), 0.0, 1.0)
    cn, cs = np.sqrt(1.0 - B), np.sqrt(B)
    N, S = law.sigma_max, law.tau_max
    if law.onset == "quadratic":
        q = (1.0 - B) / N**2 + B / S**2
        lam0 = 1.0 / (K * np.sqrt(q))
        dq = -1.0 / N**2 + 1.0 / S**2
        return lam0, -0.5 * lam0 * dq / q
    # thesis (4.15): g(λ, B) = K λ cs - S (1 - K λ cn / N)^(1/p) = 0, increasing in λ; root in
    # [0, N/(K cn)] (the tensile cut-off (4.20))
    p = law.p
    if p in (1.0, 2.0):
        return _onset_thesis_closed(B, K, law, cn, cs)
    # other exponents: Newton from the bracket's side, safeguarded
    hi = np.where(cn > 0, N / (K * np.maximum(cn, 1e-300)), S / K * 1.0)
    hi = np.where(cs > 0, np.minimum(hi, S / (K * np.maximum(cs, 1e-300))), hi)  # g(S/(K cs)) >= 0
    lo = np.zeros_like(B)
    lam = 0.5 * (lo + hi)
    with np.errstate(all="ignore"):
        return _onset_thesis(B, K, law, cn, cs, lo, hi, lam)


def _onset_thesis_closed(B, K, law, cn, cs):
    """The thesis's onset for p = 1 or 2 in closed form (x = K λ0):
    p = 2: cs² x² + (S² cn/N) x - S² = 0, taken as x = 2S² / (S² cn/N + sqrt((S² cn/N)² + 4 cs² S²))
    (no cancellation; x = N/cn, the tensile cut-off, in pure mode I);
    p = 1: cs x = S (1 - x cn/N), x = S / (cs + S cn/N)."""
    N, S = law.sigma_max, law.tau_max
    a = S * cn / N
    if law.p == 2.0:
        x = 2.0 * S**2 / (S * a + np.sqrt((S * a) ** 2 + 4.0 * cs**2 * S**2))
    else:
        x = S / (cs + a)
    return _onset_derivative(B, K, law, cn, cs, x / K)


def _onset_thesis(B, K, law, cn, cs, lo, hi, lam):
    """Safeguarded Newton for the thesis's onset (see :func:`onset`)."""
    N, S, p = law.sigma_max, law.tau_max, law.p
    for _ in range(60):
        base = np.clip(1.0 - K * lam * cn / N, 0.0, None)
        g = K * lam * cs - S * base ** (1.0 / p)
        gl = K * cs + S / p * base ** (1.0 / p - 1.0) * K * cn / N if p != 1 else K * cs + S * K * cn / N
        lo = np.where(g < 0, lam, lo)
        hi = np.where(g >= 0, lam, hi)
        with np.errstate(all="ignore"):
            nxt = lam - g / gl
        ok = np.isfinite(nxt) & (nxt > lo) & (nxt < hi)
        new = np.where(ok, nxt, 0.5 * (lo + hi))
        if np.all(np.abs(new - lam) <= 1e-15 * np.maximum(hi, 1e-300)):
            lam = new
            break
        lam = new
    return _onset_derivative(B, K, law, cn, cs, lam)


def _onset_derivative(B, K, law, cn, cs, lam):
    """(λ0, dλ0/dB) of the thesis's onset at its root ``lam``."""
    N, S, p = law.sigma_max, law.tau_max, law.p
    base = np.clip(1.0 - K * lam * cn / N, 0.0, None)
    # implicit derivative dλ/dB = -g_B / g_λ, with dcn/dB = -1/(2 cn), dcs/dB = 1/(2 cs)
    with np.errstate(all="ignore"):
        dpow = S / p * base ** (1.0 / p - 1.0) * K / N
        g_l = K * cs + dpow * cn
        g_B = K * lam * 0.5 / np.where(cs > 0, cs, np.inf) + dpow * lam * (-0.5 / np.where(cn > 0, cn, np.inf))
        dlam = -g_B / g_l
    # at the ends (pure modes) the one-sided derivative is unbounded or undefined: the tangent
    # uses 0 there (B is stationary in the pure modes anyway: ∂B/∂δ = 0 at B = 0 and B = 1)
    dlam = np.where(np.isfinite(dlam) & (B > 0) & (B < 1), dlam, 0.0)
    return lam, dlam


# ---------------------------------------------------------------------- damage
def damage_trial(lam: np.ndarray, B: np.ndarray, K: float, law: CohesiveLaw, extend: bool = False):
    """d_trial(λ, B) and its partial derivatives ∂d/∂λ, ∂d/∂B (softening law of ``law``).
    ``extend``: the softening formula also below the onset λ0 (d < 0 there), the
    smooth continuation that an active-set iteration with a frozen loading set uses (the traction
    stays on the softening line: no kink at λ0; a point that ends below its onset leaves the
    loading set)."""
    lam = np.asarray(lam, float)
    l0, dl0 = onset(B, K, law)
    Gc = law.G_c(B)
    dGc = (law.G_IIc - law.G_Ic) * law.eta * np.clip(B, 1e-300, 1.0) ** (law.eta - 1.0)
    dGc = np.where(B > 0, dGc, 0.0) if law.eta < 1 else dGc
    lsafe = np.maximum(lam, 1e-12 * l0)  # d = 0 below λ0 anyway
    if law.softening == "bilinear":
        lf = 2.0 * Gc / (K * l0)
        dlf = 2.0 * dGc / (K * l0) - lf / l0 * dl0
        lf = np.maximum(lf, l0 * (1.0 + 1e-9))  # brittle: immediate loss (guarded in build)
        span = lf - l0
        d = lf * (lam - l0) / (lsafe * span)
        soft = (lam > l0) & (lam < lf)
        dd_l = lf * l0 / (lsafe**2 * span)
        # ∂d/∂l0 = lf (lam - lf) / (lam span²), ∂d/∂lf = -l0 (lam - l0)/(lam span²)
        dd_l0 = lf * (lam - lf) / (lsafe * span**2)
        dd_lf = -l0 * (lam - l0) / (lsafe * span**2)
        dd_B = dd_l0 * dl0 + dd_lf * dlf
    else:
        lc = (Gc - 0.5 * K * l0**2) / (K * l0)
        dlc = dGc / (K * l0) - Gc / (K * l0**2) * dl0 - 0.5 * dl0
        lc = np.maximum(lc, 1e-12 * l0)
        ex = np.exp(-np.clip(lam - l0, -50.0 * lc if extend else 0.0, None) / lc)
        d = 1.0 - l0 / lsafe * ex
        soft = lam > l0
        # d = 1 - (l0/λ) e, e = exp(-(λ-l0)/lc)
        dd_l = l0 / lsafe * ex * (1.0 / lsafe + 1.0 / lc)
        dd_l0 = -ex / lsafe - l0 / lsafe * ex / lc
        dd_lc = -l0 / lsafe * ex * (lam - l0) / lc**2
        dd_B = dd_l0 * dl0 + dd_lc * dlc
    if extend:  # below λ0 the softening formula itself: the traction (1 - d) K λ stays on the
        # softening line (affine in λ, no kink at λ0), d < 0; bounded where λ → 0
        soft = (d < 1.0) & (d > -1e3)
        return np.clip(d, -1e3, 1.0), np.where(soft, dd_l, 0.0), np.where(soft, dd_B, 0.0)
    d = np.where(lam >= l0, np.clip(d, 0.0, 1.0), 0.0)
    return d, np.where(soft, dd_l, 0.0), np.where(soft, dd_B, 0.0)


def separation_measures(delta: np.ndarray, n: np.ndarray):
    """δ_n, δ_s (vector), λ, B and their derivatives ∂λ/∂δ, ∂B/∂δ (..., 3) for separations
    ``delta (..., 3)`` with unit normals ``n (..., 3)``."""
    dn = np.einsum("...i,...i->...", delta, n)
    ds = delta - dn[..., None] * n
    dnp = np.maximum(dn, 0.0)
    s2 = np.einsum("...i,...i->...", ds, ds)
    lam2 = dnp**2 + s2
    lam = np.sqrt(lam2)
    pos = lam > 0
    ls = np.where(pos, lam, 1.0)
    B = np.where(pos, s2 / np.where(pos, lam2, 1.0), 0.0)
    g = dnp[..., None] * n + ds  # ∂(λ²/2)/∂δ
    dlam = g / ls[..., None] * pos[..., None]
    dB = (2.0 * ds - 2.0 * B[..., None] * g) / np.where(pos, lam2, 1.0)[..., None] * pos[..., None]
    return dn, ds, lam, B, dlam, dB


def point_response(delta: np.ndarray, n: np.ndarray, d_old: np.ndarray, K: float, law: CohesiveLaw,
                   tangent: bool = True, with_dd: bool = False, frozen: tuple | None = None):
    """Traction t (..., 3), damage d (...) and the consistent tangent dt/dδ (..., 3, 3) of the
    cohesive law at separations ``delta`` (normals ``n``), from the converged damage ``d_old``.
    ``with_dd``: also ∂d/∂δ (..., 3) (zero where the damage does not grow). ``frozen``:
    (tension, loading) masks that replace δ_n > 0 and d_trial > d_old (an active-set iteration:
    the response is then smooth; the caller checks the sets after convergence)."""
    dn, ds, lam, B, dlam, dB = separation_measures(delta, n)
    if frozen is not None:  # λ, B and their derivatives with the frozen tension state
        tension, loading_f = frozen
        dnp = np.where(tension, dn, 0.0)
        lam2 = dnp**2 + np.einsum("...i,...i->...", ds, ds)
        lam = np.sqrt(lam2)
        pos = lam > 0
        ls = np.where(pos, lam, 1.0)
        B = np.where(pos, (lam2 - dnp**2) / np.where(pos, lam2, 1.0), 0.0)
        gv = dnp[..., None] * n + ds
        dlam = gv / ls[..., None] * pos[..., None]
        dB = (2.0 * ds - 2.0 * B[..., None] * gv) / np.where(pos, lam2, 1.0)[..., None] * pos[..., None]
    if frozen is not None and loading_f is not None:  # frozen loading set: the smooth continuation
        dt, dd_l, dd_B = damage_trial(lam, B, K, law, extend=True)
        loading = loading_f
    else:
        dt, dd_l, dd_B = damage_trial(lam, B, K, law)
        loading = dt > d_old
    d = np.where(loading, dt, d_old)
    # δ_n = 0 counts as tension (the same traction; the tangent of an opening point - a damaged
    # point that starts at δ_n = 0, e.g. an initial crack at u = 0, then opens in one iteration)
    tens = dn >= 0 if frozen is None else tension
    g = np.where(tens, dn, 0.0)[..., None] * n + ds  # the damageable part of δ
    t = K * delta - (K * d)[..., None] * g
    if not tangent:
        return t, d, None
    eye = np.eye(3)
    nn = n[..., :, None] * n[..., None, :]
    dg = np.where(tens[..., None, None], eye, eye - nn)  # ∂g/∂δ
    D = K * eye - (K * d)[..., None, None] * dg
    dd = (dd_l[..., None] * dlam + dd_B[..., None] * dB) * loading[..., None]
    D = D - K * g[..., :, None] * dd[..., None, :]
    return (t, d, D, dd) if with_dd else (t, d, D)


def cohesive_traction_energy(delta: np.ndarray, n: np.ndarray, d: np.ndarray, K: float):
    """Traction t = Kδ - dK(<δ_n>n + δ_s) (..., 3) and stored energy ψ = ½K|δ|² - ½dKλ² (...) at
    separations ``delta`` with the damage ``d`` held fixed (tension where δ_n >= 0)."""
    dn, ds, lam, _, _, _ = separation_measures(delta, n)
    g = np.where(dn >= 0, dn, 0.0)[..., None] * n + ds
    t = K * delta - (K * d)[..., None] * g
    psi = 0.5 * K * np.einsum("...i,...i->...", delta, delta) - 0.5 * d * K * lam**2
    return t, psi


def dissipated(d: np.ndarray, B: np.ndarray, K: float, law: CohesiveLaw) -> np.ndarray:
    """Energy per area dissipated by monotonic damage growth from 0 to ``d`` at the mode ratio B
    (bilinear law, closed form ∫ ½Kλ² dd = ½ K λ0² λf d / (λf - d (λf - λ0)); it reaches G_c(B)
    at d = 1). For the exponential law the same integral is evaluated numerically."""
    l0, _ = onset(B, K, law)
    d = np.clip(np.asarray(d, float), 0.0, 1.0)
    if law.softening == "bilinear":
        lf = np.maximum(2.0 * law.G_c(B) / (K * l0), l0 * (1 + 1e-9))
        return 0.5 * K * l0**2 * lf * d / (lf - d * (lf - l0))
    # exponential: the work up to λ(d) minus the stored energy, W(λ) = ½Kλ0² + Kλ0λc(1 - e^(-(λ-λ0)/λc)),
    # with λ(d) by bisection on [λ0, λ0 + 60 λc]
    Gc = law.G_c(B)
    lc = np.maximum((Gc - 0.5 * K * l0**2) / (K * l0), 1e-12 * l0)
    lo, hi = l0 * np.ones_like(d), l0 + 60.0 * lc
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        dm = 1.0 - l0 / mid * np.exp(-(mid - l0) / lc)
        lo, hi = np.where(dm < d, mid, lo), np.where(dm < d, hi, mid)
    lam = 0.5 * (lo + hi)
    W = 0.5 * K * l0**2 + K * l0 * lc * (1.0 - np.exp(-(lam - l0) / lc))
    return np.where(d > 0, W - 0.5 * (1.0 - d) * K * lam**2, 0.0)


#: sub-steps of :func:`path_dissipation`
LEDGER_SUBSTEPS = 16


def path_dissipation(delta0: np.ndarray, delta1: np.ndarray, n: np.ndarray, d0: np.ndarray, d1: np.ndarray,
                     K: float, law: CohesiveLaw, m: int = LEDGER_SUBSTEPS) -> np.ndarray:
    """Energy per area dissipated in a step in which the separation goes from ``delta0`` (the last
    converged state, damage ``d0``) to ``delta1`` (damage ``d1``): ∫ ½Kλ² dd along the straight
    separation path between them (the path the trapezoidal external work assumes), in ``m``
    sub-steps. In each the damage follows the law from the one before (:func:`point_response`;
    the last sub-step ends at ``d1``) and the sub-step's dissipation is the closed form
    :func:`dissipated` at the mode ratio of its midpoint - exact on a proportional path, whatever
    the step. Zero where the damage does not grow.

    The closed form at the end-of-step mode ratio alone (the earlier ledger) is of first order
    where the mode ratio turns within a step, and it books a point that fails within the step
    at the mode ratio of the step's end instead of that of its failure. On a single point whose
    separation turns from opening to shear, 50 steps: 0.5 % against 0.009 % of the dissipation
    (tests/test_enf.py); on the force-loaded MMB with increments a tenth of the default: energy
    balance 0.97 % against 0.12 % (tests/test_mmb.py). Where a front point passes from onset to
    failure within one or two long increments its path between them is not straight either: the
    default MMB still books about 11 % too little (13 % before; the run warns)."""
    d0, d1 = np.asarray(d0, float), np.asarray(d1, float)
    grow = d1 > d0
    out = np.zeros(d1.shape)
    if not np.any(grow):
        return out
    x0, x1, nn = delta0[grow], delta1[grow], np.broadcast_to(n, delta1.shape)[grow]
    dmax, d = d1[grow], d0[grow]
    total = np.zeros_like(d)
    for k in range(1, m + 1):
        if k < m:
            _, dk, _ = point_response(x0 + (k / m) * (x1 - x0), nn, d, K, law, tangent=False)
            dk = np.minimum(dk, dmax)
        else:
            dk = dmax
        B = separation_measures(x0 + ((k - 0.5) / m) * (x1 - x0), nn)[3]
        total += dissipated(dk, B, K, law) - dissipated(d, B, K, law)
        d = dk
    out[grow] = total
    return out


# ---------------------------------------------------------------------- interface block
@dataclass
class CohesiveBlock:
    """Element-like block of one cohesive interface: the layers on both sides keep their own
    DOFs (no bond constraint) and are coupled by the cohesive tractions at the face points.

    Kinematics, DOFs and weights are those of :class:`~layershell.contact.ContactBlock` (its
    relative displacement Δu = C U (4.43)-(4.44), its normal A3 and its friction return
    mapping), built on the chosen face rule. The sparsity pattern is fixed (every element's
    full matrix, or on the nodal rule every face point's block over its node's DOFs:
    ``assembly_dofs``), so the block is element-like. The tangent is not symmetric where the damage
    grows (K g ⊗ ∂d/∂δ)."""

    contact: object  # ContactBlock (kinematics, friction state: cap, g_p, alpha_T)
    law: CohesiveLaw
    K: float
    d_old: np.ndarray  # (e, q) converged damage (history variable)
    frozen: tuple | None = None  # (tension, loading) during an active-set solve
    # viscous regularisation (Gao & Bower 2004), law.viscosity = η > 0: the acting damage d_v
    # follows the rate-independent d with ḋ_v = (d - d_v)/η in load-factor time, backward Euler
    # d_v = (d_v,old + r d)/(1 + r), r = Δλ/η (never decreasing)
    dv_old: np.ndarray | None = None  # (e, q) converged acting damage (= d_old without viscosity)
    lam_old: float = 0.0  # load factor of the last commit
    lam_trial: float = 0.0  # load factor of the current solve (Problem.external)
    last_inviscid: np.ndarray | None = None  # rate-independent damage of the last point_state
    # pseudo-time added to the load-factor time of the viscous law, so that the damage can relax
    # at a fixed load (solver/newton.py relax: a load step past a snap-back)
    relax_time: float = 0.0
    symmetric = False
    #: the last tangent was exactly symmetric at every point (M_q = M_qᵀ: no growing damage in a
    #: mixed mode, e.g. a pure mode I DCB), so K is symmetric to round-off and the assembler can
    #: skip the solver's O(nnz) symmetry check (``Assembler.symmetric``); False before a tangent
    symmetric_now = False
    compact_tangent = False
    smooth_when_frozen = True  # newton(): no residual line search in the active-set loop

    # ------------------------------------------------------------------ active set (solver/newton.py)
    def gap(self, u_full: np.ndarray) -> np.ndarray:
        """Normal separation δ_n (e, q)."""
        return np.einsum("eqi,eqi->eq", self.separation(u_full), self.contact.A3)

    #: damage tolerance of the loading-set check (a point whose trial damage exceeds its history
    #: by less counts as not loading; one below its history by less as still loading)
    LOADING_TOL = 1e-9
    #: consistency tolerance of a cycling active set: a converged state whose sets violate the
    #: damage law by less than this fraction of the strength at every point (:meth:`set_violation`)
    #: is accepted where the loop cycles - a crack front passing a node can have no exactly
    #: consistent set (its loading and unloading states each imply the other), and the two states
    #: differ there by traction changes of 10⁻⁵-10⁻⁴ of the strength (DCB, 300 elements)
    CONSISTENCY_TOL = 1e-3

    def _trial(self, u_full: np.ndarray):
        """Normal gap, trial damage (smooth continuation below the onset), equivalent separation
        λ and mode ratio B at ``u_full``."""
        delta = self.separation(u_full)
        n = self.contact.A3
        _, _, lam, B, _, _ = separation_measures(delta, n)
        dt, _, _ = damage_trial(lam, B, self.K, self.law, extend=True)
        return np.einsum("eqi,eqi->eq", delta, n), dt, lam, B

    def actual_sets(self, u_full: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(tension, loading) of every point at ``u_full``: δ_n >= 0, and the points whose damage
        grows (trial damage, continued below the onset, above the history)."""
        return self._sets(*self._trial(u_full)[:2])

    def _sets(self, g: np.ndarray, dt: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        loading = (dt > self.d_old - self.LOADING_TOL) & (dt > 0.0) & (self.d_old < FULL_DAMAGE)
        return g >= 0, loading

    def freeze(self, u_full: np.ndarray, limited: bool = False) -> None:
        """Fix the tension/compression state and the loading set (points whose damage grows) of
        every point for the next Newton iterations: within them the response is smooth (the
        damage of a loading point follows the softening formula continued below its onset, the
        others keep their history). The kinks - the onset of damage at λ0, where the normal
        stiffness drops from K to the softening slope, and the normal stiffness of a damaged
        point at δ_n = 0 - are then handled by the active-set loop (:func:`~layershell.solver.
        newton.newton`): semi-smooth Newton across the onset kink can cycle between the states
        of a few points at the crack tip (DCB). Where friction acts on the damaged
        share, its stick state is frozen too (``contact.stick_frozen``: a point frozen sticking
        keeps the stick law beyond its slip limit; :meth:`set_violation` checks it).

        ``limited``: change the frozen loading set only at the points that violate it most
        (those within 1e-6 of the largest |d_trial - d_old| among the points whose state
        changed; symmetric points flip together). Flipping every violated point at once can
        cycle between two sets neither of which is consistent - near a crack front passing a
        node, all points of the front loading unloads two of them, and without those they load
        again - while a set in between is (the standard remedy for a cycling primal-dual active
        set, cf. Hintermüller, Ito & Kunisch 2002)."""
        g, dt, _, _ = self._trial(u_full)
        tension, loading = self._sets(g, dt)
        if limited and self.frozen is not None and self.frozen[1] is not None:
            prev = self.frozen[1]
            viol = np.where(loading != prev, np.abs(dt - self.d_old), 0.0)
            worst = float(viol.max())
            if worst > 0.0:
                loading = np.where(viol >= (1.0 - 1e-6) * worst, loading, prev)
        self.frozen = (tension, loading)
        cb = self.contact
        if cb.cap is not None and np.any(cb.cap > 0):
            # the friction's stick state too: within the frozen solve a sticking point keeps the
            # stick law, so that points that start at their limit (the committed sliding state)
            # do not switch between stick and slip from one iterate to the next
            cb.stick_frozen = cb.slip_ratio(u_full) < 1.0

    def frozen_key(self) -> bytes:
        """The frozen state as the active-set loop's cycle detection compares it: tension,
        loading and, where friction acts, the stick state - a loop whose stick state changes is
        not repeating itself (:func:`~layershell.solver.newton.freeze_sets`)."""
        arrays = list(self.frozen) if self.frozen is not None else []
        if self.contact.stick_frozen is not None:
            arrays.append(self.contact.stick_frozen)
        return b"".join(np.packbits(a).tobytes() for a in arrays)

    def release_closed(self, u_full: np.ndarray) -> int:
        """Take the points frozen as opening and loading whose normal separation is negative at
        ``u_full`` out of both sets (closed, damage held); returns how many.

        Within the frozen sets the traction of such a point is K (1 - d(λ)) δ with λ = |δ|
        and d on the softening line, t = K λ0 (λf - λ)/(λf - λ0) δ/λ: it reverses where δ
        passes through zero (in mode I at δ_n = 0), within about 10⁻³ λ0 where the continued
        damage is bounded at -10³ - practically a jump of twice the strength. A Newton iterate that
        pushes the point just behind a crack front across it - the first correction of an
        increment often does, the point opening only by about λ0 - is then thrown back, and
        the iterates alternate between the two sides for good (the force-loaded DCB on 200
        elements, arc length: 122 of 418 attempts failed so, their residual frozen at one
        point's jump). Closed, the point's law is continuous there (K δ_n across δ_n = 0), so
        the frozen problem is continuous again; where the point opens at the solution after
        all, the set check finds it (:meth:`set_violation`) and the active-set loop freezes it
        opening again. Only this direction changes, so the release cannot cycle within one
        solve."""
        if self.frozen is None or self.frozen[1] is None:
            return 0
        tension, loading = self.frozen
        if not np.any(tension & loading):
            return 0
        g = self.gap(u_full)
        crossed = tension & loading & (g < 0.0)
        n = int(crossed.sum())
        if n:
            self.frozen = (tension & ~crossed, loading & ~crossed)
        return n

    def set_changed(self, u_full: np.ndarray) -> bool:
        """Do the frozen sets still hold at the converged ``u_full``? Tension: where it matters
        (damaged points). Loading: a loading point whose damage fell below its history, or a
        point outside the set whose trial damage exceeds its history. Where a set changed, the
        next :meth:`freeze` (from ``u_full``) takes the actual sets."""
        return self.set_violation(u_full) > 0.0

    def set_violation(self, u_full: np.ndarray) -> float:
        """How far the frozen sets are from the damage law at the converged ``u_full``: the
        largest traction change, as a fraction of the point's strength K λ0(B), that taking the
        actual sets would make at one point - K λ |d_trial - d_held| for a loading point whose
        damage fell below its history or a point outside the set whose trial damage exceeds it,
        K d |δ_n| for a damaged point whose tension state changed, d (|t_tr| - cap) for a point
        frozen sticking beyond its friction limit (:meth:`_friction_violation`); 0 where the sets hold
        (:data:`LOADING_TOL` on the damage). The active-set loop accepts a cycling set whose
        violation is below :data:`CONSISTENCY_TOL` (:class:`~layershell.solver.newton.
        ActiveSetLoop`)."""
        if self.frozen is None:
            return 0.0
        tension_f, loading_f = self.frozen
        g, dt, lam, B = self._trial(u_full)
        tol = self.LOADING_TOL
        d_held = np.where(loading_f, dt, self.d_old)
        tension_changed = ((g >= 0) != tension_f) & (d_held > 0)
        loading_changed = np.where(loading_f, dt < self.d_old - tol,
                                   (dt > self.d_old + tol) & (self.d_old < FULL_DAMAGE))
        vf = self._friction_violation(u_full, d_held)
        if not np.any(tension_changed | loading_changed):
            return vf
        l0, _ = onset(B, self.K, self.law)
        v = np.where(loading_changed, np.abs(dt - self.d_old) * lam / l0, 0.0)
        v = np.maximum(v, np.where(tension_changed, np.clip(d_held, 0.0, 1.0) * np.abs(g) / l0, 0.0))
        return max(float(v.max()), np.finfo(float).tiny, vf)

    #: relative tolerance of the friction's frozen stick state: a point frozen sticking whose trial
    #: traction exceeds its slip limit by more violates it
    STICK_TOL = 1e-9

    def _friction_violation(self, u_full: np.ndarray, d: np.ndarray) -> float:
        """The largest traction by which a point frozen sticking exceeds its slip limit, d (|t_tr|
        - cap), as a fraction of τ_max (0 where the frozen stick state holds)."""
        cb = self.contact
        if cb.stick_frozen is None:
            return 0.0
        x = cb.slip_ratio(u_full)
        over = cb.stick_frozen & (cb.cap > 0) & (x > 1.0 + self.STICK_TOL)
        if not np.any(over):
            return 0.0
        v = (x - 1.0) * cb.cap * np.clip(d, 0.0, 1.0) / self.law.tau_max
        return max(float(v[over].max()), np.finfo(float).tiny)

    def reversal_step(self, u_full: np.ndarray, dU: np.ndarray) -> float:
        """The largest fraction (≤ 1) of the correction ``dU`` (full space) that takes no sliding
        friction point past its anchor, where its trial traction would reverse: a sliding point
        has no stiffness along its slip, so a Newton correction can carry it through the stick
        range at once and throw its friction from +cap to -cap (the TRC slab on its snap-back,
        where all friction points near the bearing slide)."""
        cb = self.contact
        if cb.cap is None or not np.any(cb.cap > 0):
            return 1.0
        t0 = cb.trial_traction(u_full)
        n0 = np.linalg.norm(t0, axis=-1)
        dt = cb.trial_traction(dU, anchored=False)
        along = np.einsum("eqi,eqi->eq", dt, t0) / np.where(n0 > 0, n0, 1.0)
        back = (cb.cap > 0) & (n0 >= cb.cap) & (along < -n0)
        return float((n0[back] / -along[back]).min()) if np.any(back) else 1.0

    def unfreeze(self) -> None:
        self.frozen = None
        self.contact.stick_frozen = None

    # the attributes that assembly / results read from a block
    @property
    def dofs(self) -> np.ndarray:
        return self.contact.dofs

    @property
    def w(self) -> np.ndarray:
        return self.contact.w

    @property
    def assembly_dofs(self) -> np.ndarray | None:
        """The point form's DOFs (nodal rule; ``ContactBlock._point_form``) or None."""
        return self.contact.assembly_dofs

    # read by results, probes, plots (as from a ContactBlock)
    itf = property(lambda self: self.contact.itf)
    conn = property(lambda self: self.contact.conn)
    region = property(lambda self: self.contact.region)
    w0 = property(lambda self: self.contact.w0)
    X0 = property(lambda self: self.contact.X0)

    @property
    def released(self) -> np.ndarray:
        """Fully damaged points (e, q)."""
        return self.d_old >= FULL_DAMAGE

    def separation(self, u_full: np.ndarray) -> np.ndarray:
        """Δu (e, q, 3) at the face points."""
        ne, nq, nk = self.contact.c.shape
        return np.matmul(self.contact.c, u_full[self.dofs].reshape(ne, nk, 3))

    def set_load_factor(self, lam: float) -> None:
        """The load factor of the coming solve (pseudo-time of the viscous regularisation)."""
        self.lam_trial = float(lam)

    def point_state(self, u_full: np.ndarray, with_dd: bool = False):
        """(δ, t, d, D[, ∂d/∂δ]) of the cohesive law at every face point; d is the acting damage
        (the viscous one where ``law.viscosity`` > 0; the rate-independent one is kept in
        ``last_inviscid``)."""
        delta = self.separation(u_full)
        n = self.contact.A3
        t, d, D, dd = point_response(delta, n, self.d_old, self.K, self.law, True, True, self.frozen)
        self.last_inviscid = d
        if self.law.viscosity > 0:
            r = (max(self.lam_trial - self.lam_old, 0.0) + self.relax_time) / self.law.viscosity
            dv_old = self.d_old if self.dv_old is None else self.dv_old
            dv = (dv_old + r * d) / (1.0 + r)
            grow = dv > dv_old
            dv = np.where(grow, dv, dv_old)
            ddv = np.where(grow[..., None], r / (1.0 + r) * dd, 0.0)
            # t = Kδ - K d g, D = K I - K d ∂g/∂δ - K g ⊗ ∂d/∂δ: swap d for d_v
            dn = np.einsum("eqi,eqi->eq", delta, n)
            tens = dn >= 0 if self.frozen is None else self.frozen[0]
            g = np.where(tens, dn, 0.0)[..., None] * n + (delta - dn[..., None] * n)
            nn = n[..., :, None] * n[..., None, :]
            dg = np.where(tens[..., None, None], np.eye(3), np.eye(3) - nn)
            t = t + (self.K * (d - dv))[..., None] * g
            D = (D + (self.K * (d - dv))[..., None, None] * dg
                 + self.K * g[..., :, None] * (dd - ddv)[..., None, :])
            d, dd = dv, ddv
        return (delta, t, d, D, dd) if with_dd else (delta, t, d, D)

    def tractions(self, u_full: np.ndarray):
        """Total traction (cohesive + friction on the damaged share) t (e, q, 3), the cohesive
        part, the friction part and the damage d (e, q)."""
        delta, t, d, _ = self.point_state(u_full)
        tf = np.zeros_like(t)
        if self.contact.cap is not None and np.any(self.contact.cap > 0):
            tf, _ = self.contact.friction_traction(u_full, delta)
        return t + d[..., None] * tf, t, tf, d

    def response(self, u_full: np.ndarray, tangent: bool = True, compact: bool = False, points: bool = False):
        """Internal force (e, m) and tangent (e, m, m): f_(k,i) = Σ_q c_qk w_q T_qi and
        K_(k,i)(l,j) = Σ_q c_qk c_ql w_q D_qij (C = c ⊗ I₃, as in ContactBlock.response);
        ``points``: both in the point form of the nodal rule (``assembly_dofs``, (e·q, 3 s) and
        (e·q, 3 s, 3 s), :meth:`ContactBlock.point_matrices`)."""
        cb = self.contact
        ne, nq, nk = cb.c.shape
        delta, t, d, D, dd = self.point_state(u_full, with_dd=True)
        T = t
        friction = cb.cap is not None and np.any(cb.cap > 0)
        if friction:
            tf, Df = cb.friction_traction(u_full, delta)
            T = t + d[..., None] * tf
        if points:
            if not tangent:
                return cb.point_matrices(cb.w[..., None] * T, None)[0], None
        else:
            f = np.matmul(cb.c.transpose(0, 2, 1), cb.w[..., None] * T).reshape(ne, 3 * nk)
            if not tangent:
                return f, None
        M = D
        if friction:
            M = M + d[..., None, None] * Df + tf[..., :, None] * dd[..., None, :]
        M = cb.w[..., None, None] * M
        self.symmetric_now = not np.any(M != M.swapaxes(-1, -2))
        if points:
            return cb.point_matrices(cb.w[..., None] * T, M)
        c = cb.c
        cM = (c[:, :, None, :, None] * M[:, :, :, None, :]).reshape(ne, nq, 9 * nk)
        K = np.matmul(c.transpose(0, 2, 1), cM).reshape(ne, 3 * nk, 3 * nk)
        return f, K

    def friction_excess(self, u_full: np.ndarray, gradient: bool = False) -> tuple[float, np.ndarray | None]:
        """c = ½ Σ_q w d t_f·(P δ − t_f/α_T): what the secant energy ½ f·u of the friction on the
        damaged share counts beyond its stored energy, and (``gradient``) ∂c/∂u per element
        (e, 3 k); (0, None) where no friction acts.

        The friction's stick spring holds t_f = α_T (P δ − g_p) from its anchor g_p (sliding: the
        return-mapped anchor P δ − t_f/α_T), so it stores ½ d |t_f|²/α_T, not the ½ d t_f·δ of the
        secant form that the dissipation constraint assumes (Gutiérrez 2004: stored energy ½ uᵀf).
        Their difference is c; the dissipation of an increment is the constraint's ΔG + Δc
        (solver/arclength.py, :func:`~layershell.solver.arclength.friction_excess`). Without it a
        sticking point that unloads towards its anchor counts the fall of its c as dissipated,
        and the constraint is met with no damage. With a = P δ − t_f/α_T and D_f = ∂t_f/∂δ:
        ∂c/∂δ = ½ [d (D_fᵀ a + (P − D_f/α_T)ᵀ t_f) + (t_f·a) ∂d/∂δ]."""
        cb = self.contact
        if cb.cap is None or not np.any(cb.cap > 0):
            return 0.0, None
        delta, _, d, _, dd = self.point_state(u_full, with_dd=True)
        tf, Df = cb.friction_traction(u_full, delta)
        P = cb.projector()
        aT = cb._penalty()  # a number or (e, q, 1)
        a = np.einsum("eqij,eqj->eqi", P, delta) - tf / aT
        ta = np.einsum("eqi,eqi->eq", tf, a)
        c = 0.5 * float((cb.w * d * ta).sum())
        if not gradient:
            return c, None
        aT4 = aT[..., None] if np.ndim(aT) else aT
        G = 0.5 * (d[..., None] * (np.einsum("eqji,eqj->eqi", Df, a) + np.einsum("eqji,eqj->eqi", P - Df / aT4, tf))
                   + ta[..., None] * dd)
        ne, _, nk = cb.c.shape
        return c, np.matmul(cb.c.transpose(0, 2, 1), cb.w[..., None] * G).reshape(ne, 3 * nk)

    def elastic_energy(self, u_full: np.ndarray) -> float:
        """Stored energy of the cohesive springs ½K|δ|² - ½dK|<δ_n>n + δ_s|² integrated."""
        delta, _, d, _ = self.point_state(u_full)
        _, psi = cohesive_traction_energy(delta, self.contact.A3, d, self.K)
        return float((self.contact.w * psi).sum())
