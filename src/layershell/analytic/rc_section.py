"""Plane-sections analysis of a rectangular reinforced concrete section with an optional bonded
strengthening layer (FRP plate, or the textile of a TRC layer) at its soffit: the independent
reference of cracking, yielding and ultimate moments, of the moment–curvature curve and of the
uncracked and fully cracked flexural stiffness.

Geometry: depth z measured down from the top face, the concrete occupies 0 ≤ z ≤ h with width b;
reinforcement layers are points at depth d_i with area A_i; the strengthening layer is a point at
its centroid depth (default h + t_f/2) with area b_f t_f. A TRC layer may add its cementitious
matrix: a second concrete of thickness t_m below the soffit (h ≤ z ≤ h + t_m, width b_f) with its
own law, integrated like the section's concrete; the textile then lies inside it (default
depth h + t_m/2). Plane sections, perfect bond: the strain is ε(z) = κ (z − x) with κ > 0
sagging (top in compression) and x the neutral axis depth; strains and stresses are positive in
tension. Any consistent units (N, mm, MPa in the tests).

Concrete in compression (f_c, the strain magnitudes ε_c1, ε_c2, ε_cu given as positive numbers):

- ``"parabola-rectangle"``: EN 1992-1-1 eq. (3.17), σ = −f_c [1 − (1 − |ε|/ε_c2)^n] up to ε_c2,
  −f_c from ε_c2 to ε_cu;
- ``"sargin"``: fib Model Code 2010 eq. (5.1-26), σ = −f_c (k η − η²)/(1 + (k − 2) η),
  η = |ε|/ε_c1, k = E_c ε_c1/f_c (E_c the initial tangent modulus E_ci);
- ``"linear"``: σ = E_c ε (the limiting case of the state-II formulas).

A fibre compressed beyond ε_cu has crushed and carries nothing. Concrete in tension: linear with
E_c up to f_ct, then ``"brittle"`` (zero), ``"softening"`` (linear to zero at ε_tu) or ``"none"``
(no tension at all: the bare cracked section). Reinforcement: bilinear, E_s to f_y then the
hardening modulus E_h, symmetric in compression; rupture at ε_su if given. Strengthening: linear
elastic E_f to its rupture stress f_fu.

The concrete is integrated with the midpoint rule over ``fibres`` equal slices (≥ 200); bar holes
are not deducted (the transformed-section formulas below do the same, so the limits agree
exactly). For each curvature the neutral axis is the root of the axial force N(x) = 0,
bracketed in [0, z_max] (all fibres in tension at x = 0, all in compression at the deepest
fibre) and found with Brent's method.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from layershell.material import MaterialError

#: fewest concrete fibres accepted: the brittle tension drop is resolved to f_ct b h / fibres
MIN_FIBRES = 200
#: fewest fibres across a TRC matrix (its thickness is a small fraction of h)
MIN_MATRIX_FIBRES = 20
#: relative tolerance of the neutral-axis root (to the section depth)
X_TOL = 1e-13
#: curvatures scanned (× 1/h) to bracket a limit state: from far below cracking to far past failure
KAPPA_SCAN = (1e-8, 1.0, 400)

CURVES = ("parabola-rectangle", "sargin", "linear")
TENSION = ("brittle", "softening", "exponential", "none")


def _positive(name: str, value, fix: str) -> None:
    if not (value is not None and np.isfinite(value) and value > 0):
        raise MaterialError(f"'{name}' must be a positive number (got {value!r}); {fix}")


@dataclass(frozen=True)
class Concrete:
    """Uniaxial concrete law; strengths and strain limits as positive magnitudes."""

    f_c: float
    f_ct: float
    E_c: float
    curve: str = "sargin"
    eps_c1: float = 0.0023
    eps_cu: float = 0.0035
    eps_c2: float = 0.002
    n: float = 2.0
    tension: str = "brittle"
    eps_tu: float | None = None
    G_F: float | None = None  # tension = "exponential": fracture energy (force/length) ...
    band: float | None = None  # ... over the crack band (length)

    def __post_init__(self):
        _positive("f_c", self.f_c, "give the compressive strength as a positive stress")
        _positive("E_c", self.E_c, "give the initial modulus of the concrete")
        for name in ("eps_c1", "eps_cu", "eps_c2", "n"):
            _positive(name, getattr(self, name), "strain limits are positive magnitudes")
        if self.curve not in CURVES:
            raise MaterialError(f"'curve' = {self.curve!r} is not known; use one of {CURVES}")
        if self.tension not in TENSION:
            raise MaterialError(f"'tension' = {self.tension!r} is not known; use one of {TENSION}")
        if self.tension != "none":
            _positive("f_ct", self.f_ct, "give the tensile strength, or tension = 'none'")
        if self.tension == "exponential" and not ((self.G_F or 0) > 0 and (self.band or 0) > 0
                                                  and self.band < 2 * self.G_F * self.E_c / self.f_ct ** 2):
            raise MaterialError("tension = 'exponential' needs a positive 'G_F' and a crack 'band' below the "
                                "snap-back limit 2 G_F E_c / f_ct²")
        if self.tension == "softening" and not (self.eps_tu or 0) > self.f_ct / self.E_c:
            raise MaterialError("'eps_tu' must exceed the cracking strain f_ct/E_c for "
                                "tension = 'softening'; give the strain at which tension ends")
        k = self.E_c * self.eps_c1 / self.f_c
        if self.curve == "sargin" and 1.0 + (k - 2.0) * self.eps_cu / self.eps_c1 <= 0.0:
            raise MaterialError(f"Sargin's law is singular before eps_cu: k = E_c eps_c1/f_c = "
                                f"{k:.3g} is too small; give the initial modulus E_ci as 'E_c' "
                                "or a smaller 'eps_cu'")
        if self.curve == "parabola-rectangle" and self.eps_c2 > self.eps_cu:
            raise MaterialError("'eps_c2' must not exceed 'eps_cu' (EN 1992-1-1 Table 3.1)")

    def stress(self, eps) -> np.ndarray:
        """σ(ε), vectorised over ε (tension positive)."""
        eps = np.asarray(eps, dtype=float)
        e = -np.minimum(eps, 0.0)  # compressive strain magnitude
        if self.curve == "parabola-rectangle":
            comp = self.f_c * (1.0 - (1.0 - np.minimum(e / self.eps_c2, 1.0)) ** self.n)
        elif self.curve == "sargin":
            k = self.E_c * self.eps_c1 / self.f_c
            eta = e / self.eps_c1
            comp = self.f_c * (k * eta - eta**2) / (1.0 + (k - 2.0) * eta)
        else:
            comp = self.E_c * e
        comp = np.where(e > self.eps_cu, 0.0, comp)
        return np.where(eps < 0.0, -comp, self._tension(np.maximum(eps, 0.0)))

    def _tension(self, eps: np.ndarray) -> np.ndarray:
        if self.tension == "none":
            return np.zeros_like(eps)
        eps_cr = self.f_ct / self.E_c
        rising = self.E_c * eps
        if self.tension == "brittle":
            return np.where(eps <= eps_cr, rising, 0.0)
        if self.tension == "exponential":  # Oliver (1989): G_F / band dissipated per volume
            A = 1.0 / (self.G_F * self.E_c / (self.band * self.f_ct ** 2) - 0.5)
            return np.where(eps <= eps_cr, rising, self.f_ct * np.exp(A * (1.0 - np.maximum(eps, eps_cr) / eps_cr)))
        soft = self.f_ct * np.clip((self.eps_tu - eps) / (self.eps_tu - eps_cr), 0.0, 1.0)
        return np.where(eps <= eps_cr, rising, soft)


@dataclass(frozen=True)
class Rebar:
    """A layer of bars at ``depth`` below the top face with total ``area`` (over the width b)."""

    depth: float
    area: float
    E_s: float = 200e3
    f_y: float = 500.0
    E_h: float = 0.0
    eps_su: float | None = None

    def __post_init__(self):
        _positive("rebar area", self.area, "give the bar area over the section width")
        _positive("rebar E_s", self.E_s, "give the steel modulus")
        _positive("rebar f_y", self.f_y, "give the yield stress")
        if not self.E_h >= 0:
            raise MaterialError(f"'rebar E_h' must be ≥ 0 (got {self.E_h!r})")
        if self.eps_su is not None and not self.eps_su > self.f_y / self.E_s:
            raise MaterialError("'rebar eps_su' must exceed the yield strain f_y/E_s, or be None")

    @property
    def eps_y(self) -> float:
        return self.f_y / self.E_s

    def stress(self, eps) -> np.ndarray:
        eps = np.asarray(eps, dtype=float)
        a = np.abs(eps)
        return np.sign(eps) * np.where(a <= self.eps_y, self.E_s * a,
                                       self.f_y + self.E_h * (a - self.eps_y))


@dataclass(frozen=True)
class Strengthening:
    """A bonded linear-elastic layer at the soffit: thickness t_f (for a textile, its fibre area
    per width), modulus E_f, rupture stress f_fu, width b_f (default: the section's), centroid
    ``depth`` (default h + t_f/2, or h + t_m/2 with a matrix); optionally the TRC ``matrix``
    concrete of thickness ``t_m`` that embeds it."""

    t_f: float
    E_f: float
    f_fu: float
    b_f: float | None = None
    depth: float | None = None
    matrix: Concrete | None = None
    t_m: float = 0.0

    def __post_init__(self):
        _positive("strengthening t_f", self.t_f, "give the layer (or equivalent) thickness")
        _positive("strengthening E_f", self.E_f, "give the layer modulus")
        _positive("strengthening f_fu", self.f_fu, "give the rupture stress")
        if self.matrix is not None:
            _positive("strengthening t_m", self.t_m, "give the thickness of the TRC matrix")
        elif self.t_m != 0.0:
            raise MaterialError("'t_m' is given without a 'matrix'; give the matrix concrete "
                                "or leave t_m at 0")

    @property
    def eps_fu(self) -> float:
        return self.f_fu / self.E_f


@dataclass(frozen=True)
class RCSection:
    """Rectangular section h × b with reinforcement layers and an optional soffit layer."""

    h: float
    b: float
    concrete: Concrete
    rebars: tuple[Rebar, ...] = ()
    strengthening: Strengthening | None = None
    fibres: int = 400
    _z: np.ndarray = field(init=False, repr=False, compare=False)
    _zm: np.ndarray = field(init=False, repr=False, compare=False)

    def __post_init__(self):
        _positive("h", self.h, "give the section depth")
        _positive("b", self.b, "give the section width")
        if int(self.fibres) < MIN_FIBRES:
            raise MaterialError(f"'fibres' = {self.fibres} is too few; use at least {MIN_FIBRES}")
        object.__setattr__(self, "rebars", tuple(self.rebars))
        for r in self.rebars:
            if not 0.0 <= r.depth <= self.h:
                raise MaterialError(f"rebar depth {r.depth} lies outside the section [0, {self.h}]"
                                    "; give the depth below the top face")
        s = self.strengthening
        if s is not None and s.depth is not None and not s.depth >= self.h:
            raise MaterialError(f"strengthening depth {s.depth} lies above the soffit h = {self.h}")
        bottom = self.h + self.t_m
        if self.t_m > 0.0 and not self.strengthening_depth <= bottom:
            raise MaterialError(f"strengthening depth {s.depth} lies below its matrix (h + t_m = "
                                f"{bottom}); give a depth inside the TRC layer")
        n = int(self.fibres)
        object.__setattr__(self, "_z", (np.arange(n) + 0.5) * self.h / n)
        n_m = max(MIN_MATRIX_FIBRES, int(np.ceil(n * self.t_m / self.h)))
        object.__setattr__(self, "_zm", self.h + (np.arange(n_m) + 0.5) * self.t_m / n_m)

    @property
    def t_m(self) -> float:
        """Thickness of the TRC matrix below the soffit (0 without one)."""
        s = self.strengthening
        return 0.0 if s is None or s.matrix is None else s.t_m

    @property
    def b_f(self) -> float:
        s = self.strengthening
        return self.b if s is None or s.b_f is None else s.b_f

    # --- the point-like components: reinforcement first, then the strengthening layer ---
    @property
    def point_depths(self) -> np.ndarray:
        d = [r.depth for r in self.rebars]
        if self.strengthening is not None:
            d.append(self.strengthening_depth)
        return np.array(d, dtype=float)

    @property
    def point_areas(self) -> np.ndarray:
        a = [r.area for r in self.rebars]
        if self.strengthening is not None:
            a.append(self.b_f * self.strengthening.t_f)
        return np.array(a, dtype=float)

    @property
    def point_moduli(self) -> np.ndarray:
        e = [r.E_s for r in self.rebars]
        if self.strengthening is not None:
            e.append(self.strengthening.E_f)
        return np.array(e, dtype=float)

    @property
    def strengthening_depth(self) -> float:
        s = self.strengthening
        if s.depth is not None:
            return s.depth
        return self.h + (s.t_m / 2 if s.matrix is not None else s.t_f / 2)

    @property
    def z_max(self) -> float:
        return float(max([self.h + self.t_m, *self.point_depths]))

    def point_stresses(self, eps: np.ndarray) -> np.ndarray:
        """Stresses of the point components for their strains (last axis: the components)."""
        out = np.empty_like(eps)
        for i, r in enumerate(self.rebars):
            out[..., i] = r.stress(eps[..., i])
        if self.strengthening is not None:
            out[..., -1] = self.strengthening.E_f * eps[..., -1]
        return out


@dataclass(frozen=True)
class SectionState:
    """Equilibrium states at the curvatures ``kappa``: moment, neutral axis depth, top strain,
    strains and stresses of the point components (columns: rebars in order, then the
    strengthening layer)."""

    kappa: np.ndarray
    M: np.ndarray
    x: np.ndarray
    eps_top: np.ndarray
    eps_points: np.ndarray
    sigma_points: np.ndarray


def _forces(sec: RCSection, kappa: float, x: float) -> tuple[float, float]:
    """Axial force and moment (sagging positive) of the state (κ, x)."""
    dz = sec.h / sec._z.size
    fc = sec.concrete.stress(kappa * (sec._z - x)) * sec.b * dz
    zp = sec.point_depths
    fp = sec.point_stresses(kappa * (zp - x)) * sec.point_areas
    N, M = fc.sum() + fp.sum(), fc @ sec._z + fp @ zp
    if sec.t_m > 0.0:
        fm = (sec.strengthening.matrix.stress(kappa * (sec._zm - x)) * sec.b_f
              * sec.t_m / sec._zm.size)
        N, M = N + fm.sum(), M + fm @ sec._zm
    return N, M


def neutral_axis(sec: RCSection, kappa: float) -> float:
    """Neutral axis depth x at curvature κ > 0 from N(x) = 0 (Brent, bracket [0, z_max])."""
    if not kappa > 0:
        raise MaterialError(f"curvature must be positive (sagging), got {kappa!r}")
    lo, hi = 0.0, sec.z_max
    n_lo, n_hi = _forces(sec, kappa, lo)[0], _forces(sec, kappa, hi)[0]
    if n_lo <= 0.0 or n_hi >= 0.0:
        raise MaterialError("no equilibrium: the section carries no tension at x = 0 or no "
                            "compression at x = z_max; add reinforcement or concrete tension")
    return brentq(lambda x: _forces(sec, kappa, x)[0], lo, hi, xtol=X_TOL * sec.h, rtol=1e-15,
                  maxiter=500)


def moment_curvature(sec: RCSection, kappas) -> SectionState:
    """Moment, neutral axis and component strains/stresses at each curvature (κ = 0: the
    unstrained section, x = NaN)."""
    k = np.atleast_1d(np.asarray(kappas, dtype=float))
    if np.any(k < 0):
        raise MaterialError("curvatures must be ≥ 0 (sagging); mirror the section for hogging")
    x = np.full(k.shape, np.nan)
    M = np.zeros(k.shape)
    for i, ki in enumerate(k):
        if ki > 0:
            x[i] = neutral_axis(sec, ki)
            M[i] = _forces(sec, ki, x[i])[1]
    eps = np.where(k[:, None] > 0, k[:, None] * (sec.point_depths[None, :] - x[:, None]), 0.0)
    eps_top = np.where(k > 0, -k * x, 0.0)
    return SectionState(k, M, x, eps_top, eps, sec.point_stresses(eps))


def _limit_ratio(sec: RCSection, kappa: float, limits: np.ndarray) -> tuple[np.ndarray, float]:
    """Strain of the top fibre and each point component over its limit; and x."""
    x = neutral_axis(sec, kappa)
    eps = np.concatenate([[-kappa * x], kappa * (sec.point_depths - x)])
    return eps / limits, x


def _first_crossing(sec: RCSection, limits: np.ndarray) -> tuple[float, int]:
    """Smallest curvature at which some strain reaches its limit (ratio 1; a limit of ±inf is
    never reached); returns it and the index of the governing entry (0 = top fibre)."""
    lo_f, hi_f, n = KAPPA_SCAN
    grid = np.geomspace(lo_f, hi_f, n) / sec.h
    prev = None
    for k in grid:
        g = _limit_ratio(sec, k, limits)[0].max() - 1.0
        if g >= 0.0:
            if prev is None:
                raise MaterialError("a strain limit is reached at the smallest curvature scanned")
            kc = brentq(lambda kk: _limit_ratio(sec, kk, limits)[0].max() - 1.0, prev, k,
                        xtol=1e-14 / sec.h, rtol=1e-13, maxiter=500)
            return kc, int(np.argmax(_limit_ratio(sec, kc, limits)[0]))
        prev = k
    raise MaterialError("no strain limit reached up to a curvature of 1/h; give eps_cu or a "
                        "rupture strain")


def _state_at(sec: RCSection, kappa: float) -> SectionState:
    return moment_curvature(sec, [kappa])


def cracking_moment(sec: RCSection) -> tuple[float, float]:
    """M_cr = f_ct I_I/(h − z̄) of the uncracked transformed section (every component with
    α = E/E_c, holes not deducted), f_ct reached at the concrete soffit; with a TRC matrix the
    smaller of that and f_ct,m I_I/(α_m (h + t_m − z̄)), its bottom face cracking. And
    EI_I = E_c I_I."""
    z_bar, I = transformed_uncracked(sec)
    M = sec.concrete.f_ct * I / (sec.h - z_bar)
    if sec.t_m > 0.0:
        m = sec.strengthening.matrix
        alpha_m = m.E_c / sec.concrete.E_c
        M = min(M, m.f_ct * I / (alpha_m * (sec.h + sec.t_m - z_bar)))
    return M, sec.concrete.E_c * I


def transformed_uncracked(sec: RCSection) -> tuple[float, float]:
    """Centroid depth z̄ and second moment I_I of the uncracked section in concrete units."""
    aA = sec.point_moduli / sec.concrete.E_c * sec.point_areas
    zp = sec.point_depths
    # rectangles (area, centroid, own second moment): the concrete and the TRC matrix
    rect = [(sec.b * sec.h, sec.h / 2, sec.b * sec.h**3 / 12)]
    if sec.t_m > 0.0:
        a_m = sec.strengthening.matrix.E_c / sec.concrete.E_c * sec.b_f
        rect.append((a_m * sec.t_m, sec.h + sec.t_m / 2, a_m * sec.t_m**3 / 12))
    A = sum(r[0] for r in rect) + aA.sum()
    z_bar = (sum(r[0] * r[1] for r in rect) + aA @ zp) / A
    I = sum(r[2] + r[0] * (r[1] - z_bar) ** 2 for r in rect) + aA @ (zp - z_bar) ** 2
    return z_bar, I


def cracked_stiffness(sec: RCSection) -> tuple[float, float]:
    """State II: neutral axis x_II from b x²/2 = Σ α_i A_i (d_i − x) (linear concrete without
    tension, every component linear with α_i = E_i/E_c; a TRC matrix, in tension, carries
    nothing), and EI_II = E_c [b x³/3 + Σ α_i A_i (d_i − x)²]."""
    aA = sec.point_moduli / sec.concrete.E_c * sec.point_areas
    zp = sec.point_depths
    # b/2 x² + (Σ αA) x − Σ αA d = 0
    p, q = aA.sum(), aA @ zp
    x = (-p + np.sqrt(p**2 + 2 * sec.b * q)) / sec.b
    return float(x), float(sec.concrete.E_c * (sec.b * x**3 / 3 + aA @ (zp - x) ** 2))


def yield_moment(sec: RCSection) -> tuple[float, float]:
    """Moment and curvature at first yield of the deepest bar layer."""
    if not sec.rebars:
        raise MaterialError("yield_moment needs at least one rebar layer")
    i = int(np.argmax([r.depth for r in sec.rebars]))
    limits = np.full(1 + len(sec.point_depths), np.inf)
    limits[1 + i] = sec.rebars[i].eps_y
    k, _ = _first_crossing(sec, limits)
    return float(_state_at(sec, k).M[0]), k


def ultimate_limits(sec: RCSection) -> np.ndarray:
    """Strain limits: −ε_cu at the top fibre, rupture strains of bars and strengthening."""
    lim = [-sec.concrete.eps_cu]
    lim += [np.inf if r.eps_su is None else r.eps_su for r in sec.rebars]
    if sec.strengthening is not None:
        lim.append(sec.strengthening.eps_fu)
    return np.array(lim, dtype=float)


def ultimate_moment(sec: RCSection) -> tuple[float, float, str]:
    """Moment and curvature when the top fibre reaches ε_cu or a bar or the strengthening
    ruptures, whichever comes first; and which one ("concrete crushing", "rebar rupture",
    "strengthening rupture")."""
    k, j = _first_crossing(sec, ultimate_limits(sec))
    mode = ("concrete crushing" if j == 0 else
            "rebar rupture" if j <= len(sec.rebars) else "strengthening rupture")
    return float(_state_at(sec, k).M[0]), k, mode


def moment_at_strengthening_strain(sec: RCSection, eps_f: float) -> tuple[float, float]:
    """Moment and curvature at which the strengthening layer's strain reaches ``eps_f`` (e.g.
    an IC debonding strain), on the monotonic moment–curvature path; MaterialError if the
    section reaches its ultimate state (crushing, rupture) first."""
    if sec.strengthening is None:
        raise MaterialError("the section has no strengthening layer")
    _positive("eps_f", eps_f, "give the strain of the strengthening layer")
    limits = np.full(1 + len(sec.point_depths), np.inf)
    limits[-1] = eps_f
    k, _ = _first_crossing(sec, limits)
    if _limit_ratio(sec, k, ultimate_limits(sec))[0].max() > 1.0 + 1e-9:
        Mu, _, mode = ultimate_moment(sec)
        raise MaterialError(f"the strengthening strain {eps_f:.4g} is not reached: the section "
                            f"fails first by {mode} at M_u = {Mu:.4g}")
    return float(_state_at(sec, k).M[0]), k
