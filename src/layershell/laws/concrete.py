"""Concrete: bi-scalar tension/compression damage on the effective stress with a spectral split.

Formulation (Faria, Oliver & Cervera 1998; Wu, Li & Faria 2006; the damage part of OpenSees
ASDConcrete3D), without plastic strain, explicit in the strain (no local iteration):

* effective stress σ̄ = C0 : ε (isotropic E, ν), split into its positive and negative principal
  parts σ̄ = σ̄⁺ + σ̄⁻; nominal stress σ = (1 - d⁺) σ̄⁺ + (1 - d⁻) σ̄⁻ (a closing crack carries
  compression with the full stiffness: the unilateral effect);
* compression equivalent stress τ⁻ = (α Ī1⁻ + √(3 J̄2⁻)) / (1 - α), α = (k_b - 1)/(2 k_b - 1), from
  the invariants of σ̄⁻ (Lubliner's criterion without its tension term);
* tension equivalent stress τ⁺ = ⟨σ̄_max⟩ / (1 - κ q⁻/f_c), q⁻ = (1 - d⁻) τ⁻ the nominal
  compression equivalent stress, κ = ``KAPPA_TC``: the cracking threshold f_ct falls linearly with
  the compression acting across the crack. In plane stress this is Kupfer & Gerstle's (1973)
  tension-compression line σ_t = f_ct (1 - κ σ_c/f_c) through the data of Kupfer, Hilsdorf & Rüsch
  (1969); biaxial tension cracks at f_ct as measured. As a quotient (not a sum) the compression
  scales the whole tensile branch: after onset the tension softens at any compression, and τ⁺ is
  continuous (0 where σ̄_max ≤ 0; q⁻ ≤ f_c keeps the divisor ≥ 1 - κ > 0);
* histories r± = max(r±_committed, τ±); d⁺(r⁺) linear to f_ct, then exponential (Oliver 1989) with
  A = 1/(G_F E/(h f_ct²) - 1/2) so uniaxial tension dissipates G_F per crack area over the band h;
  d⁻(r⁻) the fib MC2010 (5.1-26) Sargin curve σ = f_c (kη - η²)/(1 + (k - 2)η), η = ε/ε_c1,
  k = E ε_c1/f_c, read as a secant damage, then σ = f_c exp(-(ε - ε_c1) h f_c/G_c) beyond the peak
  (area under the post-peak branch × h = G_c).

Crack band: fixed when a point first cracks, h = h_t sin θ + h_z |cos θ| with θ between the crack
normal (principal direction of σ̄_max at onset) and the shell normal, h_t = max(h_in,
``crack_spacing``): in a layer with bonded bars the cracks distribute at the bars' crack spacing
s, so an element shorter than s smears one crack's opening over s, not over itself (the crack
band model for reinforced concrete: Bažant & Oh 1983; Rots 1988); ``crack_spacing`` = 0 (plain
concrete) keeps the element band. Crushing uses h_in: it localises
across an in-plane element length (compression normal to the mid-surface is not a shell's
failure mode).

Optional shear retention: an open crack keeps β μ across the plane of its fixed normal n,
σ += β d⁺ Q_n(σ̄⁺) (:func:`crack_shear_projector`), β the constant ``shear_retention`` (default 0),
or with ``aggregate_size`` the aggregate interlock of Walraven & Reinhardt (1981) at the crack's
width w = d⁺ ⟨n·ε·n⟩ h (:meth:`ConcreteLaw.crack`): β = K(w) h/μ, K the crack's shear stiffness
per slip, which falls with the opening and vanishes at about 1.6 mm for C30/37
(:meth:`ConcreteLaw.retention_factor`). Increment stiffness
(``strain_n`` given, as by the layer elements): σ += k d_n C0 (ε − ε_n) with the committed strain
ε_n and damage d_n, k = :data:`INCREMENT_STIFFNESS`: an opened crack makes all three principal
effective stresses positive (the Poisson part of its strain), so d⁺ → 1 leaves no stiffness in
any strain mode; this term holds such modes within an increment.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from types import SimpleNamespace

import numpy as np

from layershell.laws import spectral
from layershell.laws.state import PointState
from layershell.material import MaterialError

KAPPA_TC = 0.8  # tension-compression slope of Kupfer & Gerstle (1973), J. Eng. Mech. Div. 99(4), 853-866
# fib Model Code 2010 Table 5.1-8: strain at peak stress ε_c1 (‰) per characteristic strength f_ck (MPa)
MC2010_EPS_C1 = ((12, 1.8), (16, 1.9), (20, 2.1), (25, 2.2), (30, 2.3), (35, 2.3), (40, 2.4), (45, 2.5),
                 (50, 2.6), (55, 2.6), (60, 2.7), (70, 2.7), (80, 2.8), (90, 2.8), (100, 3.0), (120, 3.0))
#: the largest damage an IMPL-EX step acts with: a residual stiffness of 10⁻⁶ E keeps the tangent of
#: a fully opened crack regular (the implicit state itself goes on to d = 1); a lasting 10⁻⁴ E would
#: leave a separated plain beam 5 % of its peak load (INCREMENT_STIFFNESS acts within an increment)
MAX_IMPLEX_DAMAGE = 1.0 - 1e-6
#: within an increment a damaged point keeps INCREMENT_STIFFNESS d_n C0 on the strain change since
#: the last commit (d_n its committed damage): it holds the strain modes that an opened crack leaves
#: without stiffness where the increment does not move them; its stress, INCREMENT_STIFFNESS E Δε, goes
#: with the increment Δε. 3·10⁻⁴: the TRC strip on 62.5 mm elements needs more than 10⁻⁴, and 10⁻³
#: leaves the separated plain beam on 12 mm elements 1.2 % of its peak load (docs/concrete.md)
INCREMENT_STIFFNESS = 3e-4
#: the smallest crack width (mm) at which Walraven's interlock stiffness is evaluated: K(w) grows
#: without bound as w → 0 (K = 9·10³ MPa/mm here, so β = K h/μ = 1 for any band above 2 mm)
WALRAVEN_MIN_WIDTH = 1e-4
NAKAMURA_HIGAI = 8.8  # G_c = 8.8 √f_c N/mm (f_c in MPa): Nakamura & Higai (2001), ASCE SP, 471-487


@dataclass(frozen=True)
class ConcreteState(PointState):
    """r_t, r_c: tension/compression histories; h_t: crack band (0 = uncracked); h_c: crushing band;
    n1, n2, n3: crack normal fixed at onset (zero while uncracked)."""

    r_t: np.ndarray
    r_c: np.ndarray
    h_t: np.ndarray
    h_c: np.ndarray
    n1: np.ndarray
    n2: np.ndarray
    n3: np.ndarray


def _x_minus_log1p_rest(x):
    """g(x) = (x - log(1 + x) - x²/2)/x³, a series near 0 where the difference cancels."""
    x = np.asarray(x, float)
    small = np.abs(x) < 0.1
    xs = np.where(small, 0.0, x)
    with np.errstate(divide="ignore", invalid="ignore"):
        exact = (xs - np.log1p(xs) - 0.5 * xs * xs) / xs ** 3
    series = sum((-1.0) ** (m + 1) * x ** m / (m + 3) for m in range(16))
    return np.where(small, series, exact)


def crack_shear_projector(normal) -> np.ndarray:
    """Q_n (n, 6, 6): stress-like Voigt A ↦ the Voigt form of (A n) ⊗ n + n ⊗ (A n) − 2 (n·A·n) n ⊗ n,
    the shear traction of A on the plane with the unit normal ``normal`` (n, 3), as a symmetric tensor."""
    nv = np.asarray(normal, float)
    m = nv.shape[0]
    t = np.einsum("bij,nj->nbi", spectral.to_tensor(np.eye(6)), nv)  # A n of each unit Voigt stress A
    a_nn = np.einsum("nbi,ni->nb", t, nv)
    An_n = spectral.dyad(t.reshape(-1, 3), np.repeat(nv, 6, axis=0)).reshape(m, 6, 6)  # sym((A n) ⊗ n)
    return (2.0 * An_n - 2.0 * a_nn[:, :, None] * spectral.dyad(nv, nv)[:, None, :]).transpose(0, 2, 1)


@dataclass(frozen=True)
class ConcreteLaw:
    """Damage law of plain concrete (module docstring); SI-consistent model units throughout."""

    E: float
    nu: float
    f_c: float
    f_ct: float
    G_F: float
    G_c: float
    eps_c1: float
    k_b: float = 1.16
    #: β, the fraction of the shear modulus an open crack keeps across its plane (aggregate
    #: interlock, as the constant shear retention of fixed smeared cracks); 0: none beyond the
    #: split's own, since 0.2 locks the stress of a separating plain beam (docs/concrete.md, limits)
    shear_retention: float = 0.0
    #: d_agg, the largest aggregate size (model length); > 0: β falls with the crack width as
    #: Walraven's aggregate interlock (:meth:`retention_factor`), in place of the constant; 0: the
    #: constant; acts where ``crack_spacing`` > 0 (bars hold the cracks)
    aggregate_size: float = 0.0
    #: MPa per model stress unit and m per model length unit (from_class sets them; 0: not known),
    #: for the dimensional interlock relation of ``aggregate_size``
    stress_unit: float = 0.0
    length_unit: float = 0.0
    #: s, the in-plane tension band's lower bound (model length): the mean crack spacing of bars
    #: bonded in the layer (the crack band theory's band of distributed cracking); 0: the element band
    crack_spacing: float = 0.0
    name: str = "concrete"

    # -- construction --------------------------------------------------------------------------
    @classmethod
    def from_class(cls, f_ck: float, stress_unit: float = 1.0, length_unit: float = 1.0, **overrides):
        """fib Model Code 2010 mean values from the characteristic strength ``f_ck`` (MPa).

        f_cm = f_ck + 8 (5.1-1); f_ctm = 0.3 f_ck^(2/3) up to C50, 2.12 ln(1 + 0.1 f_cm) above (5.1-3a/b);
        E_ci = 21.5e3 (f_cm/10)^(1/3) MPa, quartzite aggregate (5.1-21); G_F = 73 f_cm^0.18 N/m (5.1-9);
        ε_c1 from Table 5.1-8 (linear between classes); ν = 0.2 (5.1.7.3); G_c = 8.8 √f_cm N/mm
        (Nakamura & Higai 2001). ``stress_unit``: MPa per model stress unit (N, mm: 1; kN, m: 1e-3);
        ``length_unit``: m per model length unit (mm: 1e-3). Returned in model units; ``overrides``
        (model units) replace any field.
        """
        if not f_ck > 0:
            raise MaterialError(f"concrete class: f_ck={f_ck} MPa must be positive (e.g. 30 for C30/37)")
        f_cm = f_ck + 8.0
        f_ctm = 0.3 * f_ck ** (2 / 3) if f_ck <= 50 else 2.12 * np.log(1 + 0.1 * f_cm)
        E_ci = 21.5e3 * (f_cm / 10.0) ** (1 / 3)
        G_F = 73.0 * f_cm ** 0.18 * 1e-6  # N/m -> MPa m
        G_c = NAKAMURA_HIGAI * float(np.sqrt(f_cm)) * 1e-3  # N/mm -> MPa m
        cls_fck, cls_eps = np.array(MC2010_EPS_C1, float).T
        eps_c1 = float(np.interp(f_ck, cls_fck, cls_eps)) * 1e-3
        s, e = float(stress_unit), float(stress_unit) * float(length_unit)
        vals = dict(E=E_ci / s, nu=0.2, f_c=f_cm / s, f_ct=f_ctm / s, G_F=G_F / e, G_c=G_c / e, eps_c1=eps_c1,
                    stress_unit=float(stress_unit), length_unit=float(length_unit))
        vals.update(overrides)
        law = cls(**vals)
        law.check()
        return law

    def check(self) -> None:
        """Raise :class:`MaterialError` naming the field and the fix for inadmissible constants."""
        for k in ("E", "f_c", "f_ct", "G_F", "G_c", "eps_c1"):
            if not getattr(self, k) > 0:
                raise MaterialError(f"concrete '{self.name}': {k}={getattr(self, k)} must be positive; give "
                                    f"{k} in model units or use ConcreteLaw.from_class(f_ck)")
        if not 0.0 <= self.nu < 0.5:
            raise MaterialError(f"concrete '{self.name}': nu={self.nu} must lie in [0, 0.5); concrete has "
                                "nu = 0.2 (fib MC2010 5.1.7.3)")
        if not self.eps_c1 > self.f_c / self.E:
            raise MaterialError(f"concrete '{self.name}': eps_c1={self.eps_c1} must exceed f_c/E="
                                f"{self.f_c / self.E:.4g} (no hardening branch below the peak otherwise); "
                                "raise eps_c1 (about 0.002-0.003) or E")
        if not 0.0 <= self.shear_retention <= 1.0:
            raise MaterialError(f"concrete '{self.name}': shear_retention={self.shear_retention} must lie in "
                                "[0, 1] (the fraction of the shear modulus an open crack keeps); 0 keeps none")
        if not (np.isfinite(self.aggregate_size) and self.aggregate_size >= 0.0):
            raise MaterialError(f"concrete '{self.name}': aggregate_size={self.aggregate_size} must be a positive "
                                "length (the largest aggregate size d_agg, e.g. 16 mm); leave it out for none")
        if self.aggregate_size > 0 and self.shear_retention > 0:
            raise MaterialError(f"concrete '{self.name}': give shear_retention (a constant β) or aggregate_size "
                                "(β falling with the crack width), not both")
        if self.aggregate_size > 0 and not (self.stress_unit > 0 and self.length_unit > 0):
            raise MaterialError(f"concrete '{self.name}': aggregate_size needs the model's units (its interlock "
                                "relation is in MPa and mm): add units = 'N, mm' (or 'kN, m', ...) to [model]")
        if not (np.isfinite(self.crack_spacing) and self.crack_spacing >= 0.0):
            raise MaterialError(f"concrete '{self.name}': crack_spacing={self.crack_spacing} must be a length >= 0 "
                                "(the mean spacing of the cracks the bars distribute); 0 keeps the element band")
        if not self.crack_spacing < self.max_band():
            raise MaterialError(f"concrete '{self.name}': crack_spacing={self.crack_spacing:.4g} reaches the "
                                f"snap-back limit 2 G_F E / f_ct² = {self.max_band():.4g} of the softening over "
                                "that band; give a smaller crack_spacing, or 0 for the element band")
        if not self.k_b >= 1.0:
            raise MaterialError(f"concrete '{self.name}': k_b={self.k_b} (biaxial/uniaxial compressive "
                                "strength) must be at least 1; Kupfer's value is 1.16")

    def max_band(self) -> float:
        """Largest crack band without snap-back in tension: 2 G_F E / f_ct²."""
        return 2.0 * self.G_F * self.E / self.f_ct ** 2

    def tension_band(self, h_in):
        """The in-plane band of a crack across the layer: max(h_in, ``crack_spacing``)."""
        return np.maximum(np.asarray(h_in, float), self.crack_spacing)

    def check_band(self, h_in, h_z, name: str) -> None:
        """Raise :class:`MaterialError` if a crack band h = h_t sin θ + h_z |cos θ| ≤ √(h_t² + h_z²)
        (h_t = :meth:`tension_band` of h_in) can reach :meth:`max_band` (the exponential softening
        would need snap-back)."""
        h_t = self.tension_band(h_in)
        h = np.sqrt(h_t ** 2 + np.asarray(h_z, float) ** 2)
        if np.any(h >= self.max_band()):
            spacing = (f", or give the layer a smaller crack_spacing (its in-plane band is at least "
                       f"{self.crack_spacing:.4g})" if self.crack_spacing > 0 else "")
            raise MaterialError(
                f"layer '{name}' (concrete '{self.name}'): the in-plane band h_t={np.max(h_t):.4g} with "
                f"thickness-point spacing h_z={np.max(h_z):.4g} gives crack bands up to {np.max(h):.4g}, "
                f"beyond the snap-back limit 2 G_F E / f_ct² = {self.max_band():.4g}; refine the mesh "
                f"(smaller elements) or use more thickness points in this layer{spacing}")

    def state(self, n: int) -> ConcreteState:
        """Virgin committed state of ``n`` points."""
        z = np.zeros(n)
        return ConcreteState(np.full(n, self.f_ct), z, z, z, z, z, z)

    # -- elasticity and damage functions --------------------------------------------------------
    def lame(self) -> tuple[float, float]:
        """Lamé constants λ, μ of the undamaged elasticity."""
        return self.E * self.nu / ((1 + self.nu) * (1 - 2 * self.nu)), self.E / (2 * (1 + self.nu))

    def stiffness(self) -> np.ndarray:
        """Undamaged 6 × 6 Voigt stiffness C0 (engineering shear strains)."""
        lam, mu = self.lame()
        c = np.zeros((6, 6))
        c[:3, :3] = lam
        c[[0, 1, 2], [0, 1, 2]] += 2 * mu
        c[[3, 4, 5], [3, 4, 5]] = mu
        return c

    def _tension_A(self, h):
        """Oliver's softening parameter A(h) and dA/dh (h > 0)."""
        K = self.G_F * self.E / self.f_ct ** 2
        A = 1.0 / (K / h - 0.5)
        return A, A * A * K / (h * h)

    def damage_tension(self, r, h):
        """d⁺(r; h), ∂d⁺/∂r, ∂d⁺/∂h."""
        r0 = self.f_ct
        hs = np.where(h > 0, h, 1.0)
        A, dA = self._tension_A(hs)
        x = np.maximum(r / r0, 1.0)
        e = np.exp(A * (1.0 - x))
        on = r > r0
        d = np.where(on, 1.0 - e / x, 0.0)
        dr = np.where(on, e / (x * r0) * (1.0 / x + A), 0.0)
        dh = np.where(on & (h > 0), e / x * (x - 1.0) * dA, 0.0)
        return d, dr, dh

    def damage_compression(self, r, h):
        """d⁻(r; h) and ∂d⁻/∂r (Sargin secant to the peak E ε_c1, exponential beyond)."""
        rp, k = self.E * self.eps_c1, self.E * self.eps_c1 / self.f_c
        eta = np.clip(r / rp, 0.0, 1.0)
        den = 1.0 + (k - 2.0) * eta
        keep_pre = (k - eta) / (k * den)
        dpre = (k - 1.0) ** 2 / (k * den * den) / rp
        inv_es = np.where(h > 0, h, 1.0) * self.f_c / self.G_c  # 1/ε_s
        rs = np.maximum(r, rp)
        sig = self.f_c * np.exp(-(rs / self.E - self.eps_c1) * inv_es)
        keep_post = sig / rs
        dpost = sig / rs ** 2 + keep_post * inv_es / self.E
        post = r > rp
        return 1.0 - np.where(post, keep_post, keep_pre), np.where(post, dpost, dpre)

    # -- response -------------------------------------------------------------------------------
    def _histories(self, w, committed, h_c):
        """Per point from the effective principal stresses ``w``: r⁻, d⁻ and dd⁻/dw (n, 3) of the
        compression, r⁺, whether it loads and dτ⁺/dw (n, 3) of the tension (module docstring: τ⁻,
        τ⁺ = ⟨σ̄_max⟩/(1 − κ q⁻/f_c)); compiled, :func:`layershell.laws._concrete_jit.histories`."""
        from ._concrete_jit import histories

        n = w.shape[0]
        r_c, d_c, r_t = np.empty(n), np.empty(n), np.empty(n)
        ddc, dtau_t, load_t = np.empty((n, 3)), np.empty((n, 3)), np.empty(n, dtype=np.bool_)
        f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
        histories(f64(w), f64(committed.r_c), f64(committed.r_t), f64(h_c), self.E, self.f_c, self.eps_c1, self.G_c,
                  (self.k_b - 1.0) / (2.0 * self.k_b - 1.0), KAPPA_TC, r_c, d_c, ddc, r_t, load_t, dtau_t)
        return r_c, d_c, ddc, r_t, load_t, dtau_t

    def _band(self, V, w, normal, h_in, h_z):
        """Crack band from the principal direction of σ̄_max, and the row r with r @ dσ̄ = dh."""
        v = V[:, :, 2]
        c = np.einsum("ni,ni->n", normal, v)
        s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
        h = h_in * s + h_z * np.abs(c)
        dh_dc = -h_in * c / np.where(s > 0, s, 1.0) + h_z * np.sign(c)
        return h, v, dh_dc[:, None] * spectral.eigvec_derivative_row(V, w, 2, normal)

    def response(self, eps, committed: ConcreteState, h_in, h_z, normal, tangent: bool = True,
                 implex: ConcreteState | None = None, strain_n=None):
        """Stress (n, 6), consistent tangent dσ/dε (n, 6, 6) or None, and the trial state.

        ``eps`` (n, 6) Voigt strains with engineering shears; ``h_in``, ``h_z`` (n,) element size and
        thickness-point spacing; ``normal`` (n, 3) unit shell normal. ``committed`` is not modified.
        ``implex``: the histories extrapolated to this step (IMPL-EX, Oliver, Huespe & Cante 2008):
        stress and tangent take the damage of its r_t, r_c (bands of ``committed``) at frozen damage;
        the trial state is the implicit update as without it. ``strain_n`` (n, 6): the strains of
        ``committed``; with it the stress adds the increment stiffness k d_n C0 (ε − ε_n)
        (:data:`INCREMENT_STIFFNESS`, :meth:`increment_stress`).
        """
        u = self._update(eps, committed, h_in, h_z, normal)
        if implex is not None:
            out = self._implex(u, committed, tangent, implex)
        else:
            out = self._implicit(u, committed, tangent)
        if strain_n is None:
            return out
        ds, k = self.increment_stress(np.atleast_2d(np.asarray(eps, float)) - strain_n, committed)
        if not k.any():  # no damaged point: the term is zero
            return out
        return out[0] + ds, (None if out[1] is None else out[1] + k[:, None, None] * self.stiffness()), out[2]

    def increment_stress(self, deps, committed: ConcreteState):
        """The increment stiffness's stress k d_n C0 Δε (n, 6) of the strain change ``deps`` since the
        commit, and its factor k d_n (n,): d_n = max(d⁺, d⁻) of ``committed``, k =
        :data:`INCREMENT_STIFFNESS` (0 at undamaged points; constant within an increment)."""
        d_t, _, _ = self.damage_tension(committed.r_t, committed.h_t)
        d_c, _ = self.damage_compression(committed.r_c, committed.h_c)
        k = INCREMENT_STIFFNESS * np.maximum(np.where(committed.h_t > 0, d_t, 0.0), d_c)
        return k[:, None] * (np.asarray(deps, float) @ self.stiffness()), k

    def _implicit(self, u, committed, tangent: bool):
        """The implicit response at the update ``u`` (:meth:`_update`): stress, tangent with the
        damage's variation (or None) and the trial state."""
        s = (1.0 - u.d_t)[:, None] * np.maximum(u.w, 0.0) + (1.0 - u.d_c)[:, None] * np.minimum(u.w, 0.0)
        sigma = np.einsum("nk,nka->na", s, u.P)
        ret = self._retention(u, committed, u.d_t, tangent, variation=True)
        if ret is not None:
            sigma = sigma + ret[0]
        if not tangent:
            return sigma, None, u.trial
        e_t = np.zeros((u.w.shape[0], 6))
        e_t[u.on] = u.ddt_h[u.on, None] * u.dh_row
        D = self._tangent(u, u.d_t, u.d_c, True, u.g_t, u.g_c, e_t)
        return sigma, (D if ret is None else D + ret[1]), u.trial

    def retention_factor(self, width, band):
        """β and dβ/dw (n,) at the crack widths ``width`` over the bands ``band`` (model length)
        (dβ/dw = 0 where β is clipped).

        With ``aggregate_size`` d_agg > 0: β = K(w) h/μ clipped to [0, 1], K the crack's shear
        stiffness, the slope of Walraven & Reinhardt's (1981) aggregate interlock relation
        τ = −f_c/30 + [1.8 w^−0.8 + (0.234 w^−0.707 − 0.20) f_c] δ (MPa, mm; gravel concrete,
        d_max 16 mm) at the width w k_dg (k_dg = 32/(16 + d_agg), fib MC2010 7.3.3.2): the band's
        shear strain γ is the slip δ = γ h of its crack, so τ = K δ = (K h/μ) μ γ. Else the constant
        ``shear_retention`` (dβ/dw = 0). The interlock acts in layers with a crack spacing only
        (:meth:`_retention`)."""
        w = np.asarray(width, float)
        if not self.aggregate_size > 0:
            return np.full(w.shape, self.shear_retention), np.zeros(w.shape)
        mm, mpa = 1e-3 / self.length_unit, 1.0 / self.stress_unit  # model length per mm, stress per MPa
        k_dg = 32.0 / (16.0 + self.aggregate_size / mm)
        we = np.maximum(w / mm * k_dg, WALRAVEN_MIN_WIDTH)
        fc = self.f_c / mpa
        K = 1.8 * we ** -0.8 + (0.234 * we ** -0.707 - 0.2) * fc  # MPa/mm
        dK = (-1.8 * 0.8 * we ** -1.8 - 0.234 * 0.707 * we ** -1.707 * fc) * k_dg / mm  # MPa/mm per model length
        scale = np.asarray(band, float) * (mpa / mm) / self.lame()[1]  # h/μ in mm/MPa
        beta = K * scale
        inside = (beta > 0.0) & (beta < 1.0) & (w / mm * k_dg > WALRAVEN_MIN_WIDTH)
        return np.clip(beta, 0.0, 1.0), np.where(inside, dK * scale, 0.0)

    def _retention(self, u, committed, d_t, tangent: bool, variation: bool):
        """The shear an open crack retains, β(w) d⁺ Q_n(σ̄⁺) (n, 6), and its tangent (n, 6, 6) or None
        (tangent False); None where no point retains any (no retention or no committed crack). The
        interlock of ``aggregate_size`` needs the crack held by bonded bars (``crack_spacing`` > 0):
        Walraven's shear comes with a normal compression across the crack that a restraint supplies,
        and a free crack in plain concrete opens instead (its retention would lock the stress of a
        separating beam, docs/concrete.md):
        Q_n(A) = (A n) ⊗ n + n ⊗ (A n) − 2 (n·A·n) n ⊗ n, the shear traction of σ̄⁺ on the plane
        of the committed crack normal n (zero where the committed state is uncracked, and where the
        crack is closed: σ̄⁺ = 0); β from :meth:`retention_factor` of the crack width
        w = d⁺ ⟨n·ε·n⟩ h (:meth:`crack`, with the acting d⁺). ``variation``: the tangent adds the
        variation of d⁺ (β Q_n(σ̄⁺) ⊗ dd⁺/dε and its part of dβ/dε: the implicit update), else d⁺
        is frozen (IMPL-EX) and dβ/dε = β'(w) d⁺ h H(ε_nn) n ⊗ n."""
        retains = self.shear_retention > 0 or (self.aggregate_size > 0 and self.crack_spacing > 0)
        cracked = np.flatnonzero(committed.h_t > 0) if retains else np.zeros(0, int)
        if cracked.size == 0:
            return None
        n = u.w.shape[0]
        ds = np.zeros((n, 6))
        dD = np.zeros((n, 6, 6)) if tangent else None
        nv = np.stack([committed.n1, committed.n2, committed.n3], -1)[cracked]
        Q = crack_shear_projector(nv)
        sp = np.einsum("nk,nka->na", np.maximum(u.w[cracked], 0.0), u.P[cracked])
        qs = np.einsum("nab,nb->na", Q, sp)
        nn = spectral.dyad(nv, nv)  # d(n·ε·n)/dε for engineering shears
        e_nn = np.einsum("na,na->n", nn, u.eps[cracked])
        d, h = d_t[cracked], committed.h_t[cracked]
        beta, dbeta = self.retention_factor(d * np.maximum(e_nn, 0.0) * h, h)
        bd = beta * d
        ds[cracked] = bd[:, None] * qs
        if tangent:
            sub = SimpleNamespace(V=u.V[cracked], w=u.w[cracked], P=u.P[cracked], sbar=u.sbar[cracked])
            m = cracked.size
            dpos = self._tangent(sub, np.zeros(m), np.ones(m), False)  # dσ̄⁺/dε
            dD[cracked] = bd[:, None, None] * np.einsum("nab,nbc->nac", Q, dpos)
            dw = (d * h * (e_nn > 0))[:, None] * nn  # dw/dε at frozen d⁺
            dd = np.zeros((m, 6))
            if variation:
                dd = (np.einsum("nk,nka->na", u.g_t[cracked], u.P[cracked]) * spectral.WEIGHT) @ self.stiffness()
                dw = dw + (np.maximum(e_nn, 0.0) * h)[:, None] * dd
            dD[cracked] += qs[:, :, None] * (beta[:, None] * dd + (d * dbeta)[:, None] * dw)[:, None, :]
        return ds, dD

    def _update(self, eps, committed: ConcreteState, h_in, h_z, normal) -> SimpleNamespace:
        """The implicit update at the strains ``eps``: the trial state (``trial``), the effective
        stress σ̄ (``sbar``) with its eigenvalues ``w``, eigenvectors ``V`` and projections ``P``, the
        damage ``d_t``, ``d_c`` and the terms of their variation (``g_t``, ``g_c`` (n, 3): dd±/dw;
        ``on``: the points cracking now, ``ddt_h`` ∂d⁺/∂h and ``dh_row`` their band's row)."""
        eps = np.atleast_2d(np.asarray(eps, float))
        n = eps.shape[0]
        h_in, h_z = np.broadcast_to(np.asarray(h_in, float), (n,)), np.broadcast_to(np.asarray(h_z, float), (n,))
        normal = np.broadcast_to(np.asarray(normal, float), (n, 3))
        if not (np.all(h_in > 0) and np.all(h_z > 0)):
            raise ValueError(f"concrete '{self.name}': h_in and h_z (element size and thickness-point "
                             "spacing) must be positive at every point; pass the element's sizes")
        sbar = eps @ self.stiffness()
        w, V, P = spectral.principal(sbar)
        r_c, d_c, ddc, r_t, load_t, dtau_t = self._histories(w, committed, h_in)
        onset = (committed.h_t <= 0) & (r_t > self.f_ct)
        on = np.flatnonzero(onset)
        h_new, v_new, dh_row = self._band(V[on], w[on], normal[on], self.tension_band(h_in[on]), h_z[on])
        h_t = committed.h_t.copy()
        h_t[on] = h_new
        if np.any(h_t >= self.max_band()):
            i = int(np.argmax(h_t >= self.max_band()))
            raise MaterialError(
                f"concrete '{self.name}': a crack band h={h_t[i]:.4g} (in-plane band {self.tension_band(h_in[i]):.4g}, "
                f"thickness-point spacing h_z={h_z[i]:.4g}) exceeds the snap-back limit 2 G_F E / f_ct² = "
                f"{self.max_band():.4g}; refine the mesh or use more thickness points (check_band finds "
                "this before the analysis)")
        d_t, ddt_r, ddt_h = self.damage_tension(r_t, h_t)
        nvec = np.stack([committed.n1, committed.n2, committed.n3], -1)
        nvec[on] = v_new
        trial = ConcreteState(r_t, r_c, h_t, h_in.copy(), nvec[:, 0], nvec[:, 1], nvec[:, 2])
        return SimpleNamespace(trial=trial, eps=eps, sbar=sbar, w=w, V=V, P=P, d_t=d_t, d_c=d_c,
                               g_t=(ddt_r * load_t)[:, None] * dtau_t, g_c=ddc, on=on, ddt_h=ddt_h, dh_row=dh_row)

    def _tangent(self, u, d_t, d_c, rank2: bool, g_t=None, g_c=None, e_t=None) -> np.ndarray:
        """dσ/dε (n, 6, 6) at the update ``u`` (:meth:`_update`) with the damage ``d_t``, ``d_c``: the
        split's derivative at frozen damage and, with ``rank2``, minus σ̄⁺ ⊗ g⁺ + σ̄⁻ ⊗ g⁻ for the
        damage's variation (compiled: :func:`layershell.laws._concrete_jit.split_tangent`)."""
        from ._concrete_jit import split_tangent

        n = u.w.shape[0]
        lam, mu = self.lame()
        f64 = lambda a: np.ascontiguousarray(a, dtype=np.float64)  # noqa: E731
        none3 = np.zeros((0, 3))
        out = np.empty((n, 6, 6))
        split_tangent(f64(u.V), f64(u.w), f64(u.P), f64(d_t), f64(d_c), bool(rank2),
                      f64(g_t) if rank2 else none3, f64(g_c) if rank2 else none3,
                      f64(e_t) if rank2 else np.zeros((0, 6)), f64(u.sbar), lam, mu, out)
        return out

    def extrapolate(self, previous: ConcreteState, current: ConcreteState, ratio: float = 1.0) -> ConcreteState:
        """The histories of the next increment by IMPL-EX's linear extrapolation in pseudo-time:
        r̃ = r_n + ratio (r_n − r_(n−1)), ``ratio`` = the next increment over the last one."""
        return dataclasses.replace(current, r_t=current.r_t + ratio * (current.r_t - previous.r_t),
                                   r_c=current.r_c + ratio * (current.r_c - previous.r_c))

    def implex_error(self, trial: ConcreteState, implex: ConcreteState) -> np.ndarray:
        """Per point, how far the damage an IMPL-EX increment acted with is off the implicit update:
        max(|d⁺(r_t) − d̃⁺|, |d⁻(r_c) − d̃⁻|) (d̃ from the extrapolated histories; d̃⁺ = 0 where the
        increment started uncracked)."""
        d_t, _, _ = self.damage_tension(trial.r_t, trial.h_t)
        d_tx, _, _ = self.damage_tension(implex.r_t, implex.h_t)
        d_tx = np.where(implex.h_t > 0, d_tx, 0.0)
        d_c, _ = self.damage_compression(trial.r_c, trial.h_c)
        d_cx, _ = self.damage_compression(implex.r_c, trial.h_c)
        return np.maximum(np.abs(d_t - np.minimum(d_tx, 1.0)), np.abs(d_c - d_cx))

    def _implex(self, u, committed, tangent, implex):
        """The IMPL-EX response at the update ``u`` (:meth:`_update`): σ = (1 − d̃⁺) σ̄⁺ + (1 − d̃⁻) σ̄⁻
        with the damage of the extrapolated histories (d̃⁺ = 0 where the point has not cracked at the
        last commit), its tangent at that frozen damage, and the implicit trial state."""
        d_t, _, _ = self.damage_tension(implex.r_t, committed.h_t)
        d_t = np.where(committed.h_t > 0, d_t, 0.0)
        d_c, _ = self.damage_compression(implex.r_c, u.trial.h_c)
        d_t, d_c = np.minimum(d_t, MAX_IMPLEX_DAMAGE), np.minimum(d_c, MAX_IMPLEX_DAMAGE)
        s = (1.0 - d_t)[:, None] * np.maximum(u.w, 0.0) + (1.0 - d_c)[:, None] * np.minimum(u.w, 0.0)
        sigma = np.einsum("nk,nka->na", s, u.P)
        ret = self._retention(u, committed, d_t, tangent, variation=False)
        if ret is not None:
            sigma = sigma + ret[0]
        if not tangent:
            return sigma, None, u.trial
        D = self._tangent(u, d_t, d_c, False)
        return sigma, (D if ret is None else D + ret[1]), u.trial

    # -- post-processing ------------------------------------------------------------------------
    def events(self, state: ConcreteState) -> dict[str, np.ndarray]:
        """Per point: cracked (a crack band is set) and crushed (past the compressive peak)."""
        return {"cracking": state.h_t > 0, "crushing": state.r_c > self.E * self.eps_c1}

    def dissipation(self, state: ConcreteState) -> np.ndarray:
        """Energy dissipated per unit volume, per point: the uniaxial-path values of both histories
        (exact on uniaxial paths; on others the energy of the uniaxial path with the same damage)."""
        return self._dissipation_tension(state.r_t, state.h_t) + self._dissipation_compression(state.r_c, state.h_c)

    def _dissipation_tension(self, r, h):
        r0 = self.f_ct
        A, _ = self._tension_A(np.where(h > 0, h, 1.0))
        x = np.maximum(r / r0, 1.0)
        e = np.exp(A * (1.0 - x))
        return np.where(r > r0, r0 * r0 / self.E * (0.5 + (1.0 - e) / A - 0.5 * x * e), 0.0)

    def _dissipation_compression(self, r, h):
        rp, k = self.E * self.eps_c1, self.E * self.eps_c1 / self.f_c
        c = k - 2.0
        eta = np.clip(r / rp, 0.0, 1.0)
        work = self.f_c * self.eps_c1 * (0.5 * k * eta ** 2 + (k * c + 1.0) * eta ** 3 * _x_minus_log1p_rest(c * eta))
        es = self.G_c / (np.where(h > 0, h, 1.0) * self.f_c)
        beyond = np.maximum(r / self.E - self.eps_c1, 0.0)
        work = work + self.f_c * es * (1.0 - np.exp(-beyond / es))
        d, _ = self.damage_compression(r, h)
        return np.maximum(work - 0.5 * (1.0 - d) * r * r / self.E, 0.0)

    def crack(self, eps, state: ConcreteState):
        """Crack width (n,) = d⁺ ⟨n·ε·n⟩ × band (the inelastic normal strain over the band) and the
        crack normal (n, 3) fixed at onset (zeros where uncracked)."""
        eps = np.atleast_2d(np.asarray(eps, float))
        nv = np.stack([state.n1, state.n2, state.n3], -1)
        e_nn = np.einsum("na,na->n", spectral.dyad(nv, nv) * spectral.WEIGHT, eps * [1, 1, 1, 0.5, 0.5, 0.5])
        d, _, _ = self.damage_tension(state.r_t, state.h_t)
        return d * np.maximum(e_nn, 0.0) * state.h_t, nv
