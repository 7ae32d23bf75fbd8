"""Uniaxial laws for bars and rovings: reinforcing steel and textile (strain (n,) -> stress (n,))."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from layershell.laws.state import PointState
from layershell.material import MaterialError

RUPTURE_SPAN = 0.05  # steel: the stress falls to 0 linearly over eps_u .. (1 + RUPTURE_SPAN) eps_u (a continuous curve)
# EN 1992-1-1 Annex C, Table C.1 (characteristic): ductility class -> (k = (f_t/f_y)_k, eps_uk)
STEEL_GRADES = {"B500A": (1.05, 0.025), "B500B": (1.08, 0.05), "B500C": (1.15, 0.075)}
# Typical fibre values (RILEM TC 201-TRC state-of-the-art report "Textile Reinforced Concrete",
# Brameshuber ed., 2006, ch. 2): filament modulus, and a roving tensile strength in the matrix (MPa)
FIBRES = {"carbon": (240e3, 2500.0), "AR-glass": (72e3, 1000.0)}


@dataclass(frozen=True)
class SteelState(PointState):
    """eps_p plastic strain, alpha back stress, eps_max largest |ε| so far, diss dissipated energy."""

    eps_p: np.ndarray
    alpha: np.ndarray
    eps_max: np.ndarray
    diss: np.ndarray


@dataclass(frozen=True)
class SteelLaw:
    """Elastic-plastic with linear kinematic hardening (``E_h``: slope of the σ-ε curve after yield),
    return mapping; optional rupture at the total strain ``eps_u``: the stress then falls linearly to 0
    at (1 + RUPTURE_SPAN) eps_u and stays 0 (a broken bar)."""

    E: float
    f_y: float
    E_h: float = 0.0
    eps_u: float | None = None
    name: str = "steel"

    @classmethod
    def from_grade(cls, grade: str = "B500B", stress_unit: float = 1.0, name: str | None = None,
                   **overrides) -> "SteelLaw":
        """EN 1992-1-1 Annex C grade: f_yk = 500 MPa, E = 200 GPa, hardening from the characteristic
        k and eps_uk (E_h = (k - 1) f_y / (eps_u - f_y/E), with the f_y, E and eps_u in use).
        Characteristic, not mean, values: a mean yield strength (about 1.1 f_yk) must be given
        explicitly. ``stress_unit``: MPa per model stress unit; ``overrides`` (model units) replace
        any field."""
        if grade not in STEEL_GRADES:
            raise MaterialError(f"steel grade '{grade}' is not known; use one of {', '.join(STEEL_GRADES)}")
        k, eps_uk = STEEL_GRADES[grade]
        E = overrides.pop("E", 200e3 / stress_unit)
        f_y = overrides.pop("f_y", 500.0 / stress_unit)
        eps_u = overrides.pop("eps_u", eps_uk)
        if "E_h" not in overrides and E > 0 and f_y > 0 and eps_u is not None and eps_u > f_y / E:
            overrides["E_h"] = (k - 1.0) * f_y / (eps_u - f_y / E)
        law = cls(E=E, f_y=f_y, eps_u=eps_u, name=name or grade, **overrides)
        law.check()
        return law

    def check(self) -> None:
        """Raise :class:`MaterialError` naming the field and the fix."""
        for k in ("E", "f_y"):
            if not getattr(self, k) > 0:
                raise MaterialError(f"steel '{self.name}': {k}={getattr(self, k)} must be positive "
                                    "(model units; e.g. SteelLaw.from_grade('B500B'))")
        if not 0.0 <= self.E_h < self.E:
            raise MaterialError(f"steel '{self.name}': E_h={self.E_h} must satisfy 0 <= E_h < E={self.E} "
                                "(the hardening slope after yield; 0 for perfect plasticity)")
        if self.eps_u is not None and not self.eps_u > self.f_y / self.E:
            raise MaterialError(f"steel '{self.name}': eps_u={self.eps_u} must exceed the yield strain "
                                f"f_y/E={self.f_y / self.E:.4g}; give the rupture strain (e.g. 0.05) or None")

    def state(self, n: int) -> SteelState:
        z = np.zeros(n)
        return SteelState(z, z, z, z)

    def _hardening(self) -> float:
        """Kinematic hardening modulus H with E H/(E + H) = E_h."""
        return self.E * self.E_h / (self.E - self.E_h)

    def response(self, eps, committed: SteelState, tangent: bool = True):
        """Stress (n,), tangent dσ/dε (n,) or None, trial state; ``committed`` is not modified."""
        eps = np.atleast_1d(np.asarray(eps, float))
        E, H = self.E, self._hardening()
        s_tr = E * (eps - committed.eps_p)
        xi = s_tr - committed.alpha
        sg = np.sign(xi)
        dgam = np.maximum(np.abs(xi) - self.f_y, 0.0) / (E + H)
        eps_p, alpha = committed.eps_p + dgam * sg, committed.alpha + H * dgam * sg
        s_p = s_tr - E * dgam * sg
        Et = np.where(dgam > 0, E * H / (E + H), E)
        e_max = np.maximum(committed.eps_max, np.abs(eps))
        om_c, _ = self._rupture(committed.eps_max)
        om, dom = self._rupture(e_max)
        dom = dom * (np.abs(eps) > committed.eps_max) * np.sign(eps)
        psi = 0.5 * E * (eps - eps_p) ** 2 + (0.5 * alpha ** 2 / H if H > 0 else 0.0)
        diss = committed.diss + (1.0 - om) * self.f_y * dgam + psi * (om - om_c)
        trial = SteelState(eps_p, alpha, e_max, diss)
        sigma = (1.0 - om) * s_p
        return sigma, ((1.0 - om) * Et - s_p * dom) if tangent else None, trial

    def _rupture(self, e_max):
        """Broken fraction ω(max |ε|) and dω/d|ε|."""
        if self.eps_u is None:
            z = np.zeros_like(e_max)
            return z, z
        span = RUPTURE_SPAN * self.eps_u
        om = np.clip((e_max - self.eps_u) / span, 0.0, 1.0)
        return om, ((e_max > self.eps_u) & (e_max < self.eps_u + span)) / span

    def events(self, state: SteelState) -> dict[str, np.ndarray]:
        """Per point: yielded (a plastic strain) and ruptured (past eps_u)."""
        out = {"yielding": state.eps_p != 0.0}
        if self.eps_u is not None:
            out["rupture"] = state.eps_max >= self.eps_u
        return out

    def dissipation(self, state: SteelState) -> np.ndarray:
        """Energy dissipated per unit volume: f_y |dε_p| summed (exact for linear kinematic hardening)
        plus the energy released by rupture (accumulated per step)."""
        return state.diss.copy()


@dataclass(frozen=True)
class TextileState(PointState):
    """kappa: the largest tensile strain so far."""

    kappa: np.ndarray


@dataclass(frozen=True)
class TextileLaw:
    """Textile roving: linear elastic to rupture at ``f_t``, then a linear drop to 0 over a strain
    ``softening`` f_t/E, irreversible (unloading and reloading on the secant to the origin).
    Compression carries nothing: the thin rovings buckle."""

    E: float
    f_t: float
    softening: float = 0.05
    name: str = "textile"

    @classmethod
    def from_fibre(cls, fibre: str = "carbon", stress_unit: float = 1.0, name: str | None = None,
                   **overrides) -> "TextileLaw":
        """Typical values (``FIBRES``; take the producer's data where known). ``stress_unit``: MPa per
        model stress unit; ``overrides`` (model units) replace any field."""
        if fibre not in FIBRES:
            raise MaterialError(f"textile fibre '{fibre}' is not known; use one of {', '.join(FIBRES)}")
        E, f_t = FIBRES[fibre]
        vals = {"E": E / stress_unit, "f_t": f_t / stress_unit, "name": name or fibre, **overrides}
        law = cls(**vals)
        law.check()
        return law

    def check(self) -> None:
        """Raise :class:`MaterialError` naming the field and the fix."""
        for k in ("E", "f_t", "softening"):
            if not getattr(self, k) > 0:
                raise MaterialError(f"textile '{self.name}': {k}={getattr(self, k)} must be positive "
                                    "(model units; e.g. TextileLaw.from_fibre('carbon'))")

    def state(self, n: int) -> TextileState:
        return TextileState(np.zeros(n))

    def _envelope(self, k):
        """Envelope stress at the strain k > 0 and its slope."""
        e_t = self.f_t / self.E
        drop = self.softening * e_t
        s = np.where(k <= e_t, self.E * k, self.f_t * np.clip(1.0 - (k - e_t) / drop, 0.0, 1.0))
        ds = np.where(k <= e_t, self.E, np.where(k < e_t + drop, -self.f_t / drop, 0.0))
        return s, ds

    def response(self, eps, committed: TextileState, tangent: bool = True):
        """Stress (n,), tangent (n,) or None, trial state; ``committed`` is not modified."""
        eps = np.atleast_1d(np.asarray(eps, float))
        kappa = np.maximum(committed.kappa, eps)
        load = eps >= committed.kappa
        s_env, ds_env = self._envelope(np.maximum(kappa, 1e-300))
        sec = s_env / np.maximum(kappa, 1e-300)
        pos = eps > 0
        sigma = np.where(pos, np.where(load, s_env, sec * eps), 0.0)
        Et = np.where(pos, np.where(load, ds_env, sec), 0.0)
        return sigma, Et if tangent else None, TextileState(kappa)

    def events(self, state: TextileState) -> dict[str, np.ndarray]:
        """Per point: ruptured (strained beyond f_t/E)."""
        return {"rupture": state.kappa > self.f_t / self.E}

    def dissipation(self, state: TextileState) -> np.ndarray:
        """Energy dissipated per unit volume: ∫ envelope - the energy stored at the secant."""
        e_t = self.f_t / self.E
        drop = self.softening * e_t
        x = np.clip(state.kappa - e_t, 0.0, drop)
        work = np.where(state.kappa <= e_t, 0.5 * self.E * np.maximum(state.kappa, 0) ** 2,
                        0.5 * self.f_t * e_t + self.f_t * x - 0.5 * self.f_t * x * x / drop)
        s, _ = self._envelope(np.maximum(state.kappa, 1e-300))
        return work - 0.5 * s * np.maximum(state.kappa, 0.0)
