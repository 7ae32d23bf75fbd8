"""Debonding strains and anchorage strengths of FRP (or the textile of a TRC layer) bonded to
concrete: the references of intermediate-crack (IC) and plate-end debonding.

The formulas are empirical and fixed in units: f_c (cylinder compressive strength) and E_f in
MPa, thicknesses, widths and lengths in mm, forces in N. t_f is the plate thickness, or the
equivalent thickness (fibre area per width) of a sheet or textile; b_f its width, b_c the width
of the concrete member.

- Chen & Teng (2001), *Anchorage strength models for FRP and steel plates bonded to concrete*,
  J. Struct. Eng. 127(7):784-791 — the pull-test (plate-end) strength
  P_u = α β_w β_L √f_c b_f L_e,  L_e = √(E_f t_f/√f_c),
  β_w = √((2 − b_f/b_c)/(1 + b_f/b_c)),  β_L = 1 for L ≥ L_e, sin(πL/(2L_e)) otherwise,
  α = 0.427 (the mean fit; 0.315 their 95 % characteristic value).
- Teng, Smith, Yao & Chen (2003), *Intermediate crack-induced debonding in RC beams and slabs*,
  Constr. Build. Mater. 17:447-462 — the same bond model with α refitted to IC debonding
  tests, written as a strain: ε_db = 0.48 β_w √(√f_c/(E_f t_f)) (β_L = 1: the bond lengths
  between flexural cracks and a plate end exceed L_e). Dividing Chen & Teng's P_u by
  b_f t_f E_f gives exactly this form with α = 0.427. The short form 0.48 √(f_c/(E_f t_f)),
  with f_c to the first power, gives strains larger by f_c^(1/4) (2.5 at f_c = 38 MPa); it has
  the shape of the ACI form below, not of the bond model it derives from.
- ACI 440.2R-08, eq. (10-2) (SI): ε_fd = 0.41 √(f_c/(n E_f t_f)) ≤ 0.9 ε_fu, n plies of
  thickness t_f (the US form 0.083 √(f'_c/(n E_f t_f)) in psi and in); the committee's
  recalibration of the Teng et al. model to measured IC debonding strains.
- Said & Wu (2008), *Evaluating and proposing models of predicting IC debonding failure*,
  J. Compos. Constr. 12(3):284-299: ε_db = 0.23 f_c^0.2/(E_f t_f)^0.35.

``ic_debonding_moment`` combines a debonding strain with layershell.analytic.rc_section: the
section moment at which the strengthening layer's strain reaches it.
"""
from __future__ import annotations

import numpy as np

from layershell.analytic.rc_section import RCSection, moment_at_strengthening_strain
from layershell.material import MaterialError

#: Chen & Teng (2001): mean-fit coefficient of the anchorage strength (characteristic: 0.315)
ALPHA_CHEN_TENG = 0.427
#: Teng et al. (2003): the coefficient refitted to IC debonding tests
ALPHA_TENG_IC = 0.48
#: ACI 440.2R-08 eq. (10-2), SI units (MPa, mm)
ALPHA_ACI = 0.41
#: ACI 440.2R-08: the debonding strain is capped at this fraction of the rupture strain
ACI_RUPTURE_CAP = 0.9
#: Said & Wu (2008): coefficient and exponents of their regression (MPa, mm)
SAID_WU = (0.23, 0.2, 0.35)


def _check_positive(**values) -> None:
    for name, v in values.items():
        if not np.all(np.isfinite(v)) or np.any(np.asarray(v) <= 0):
            raise MaterialError(f"'{name}' must be positive (got {v!r}); give it in MPa or mm "
                                "as the IC debonding formulas expect")


def width_factor(b_f, b_c) -> np.ndarray:
    """β_w = √((2 − b_f/b_c)/(1 + b_f/b_c)) for 0 < b_f ≤ b_c (1 at b_f = b_c/2, 1/√2 for a
    full-width layer)."""
    _check_positive(b_f=b_f, b_c=b_c)
    r = np.asarray(b_f, dtype=float) / np.asarray(b_c, dtype=float)
    if np.any(r > 1.0):
        raise MaterialError("the strengthening width 'b_f' exceeds the concrete width 'b_c'; "
                            "give b_f ≤ b_c")
    return np.sqrt((2.0 - r) / (1.0 + r))


def effective_bond_length(f_c, E_f, t_f) -> np.ndarray:
    """L_e = √(E_f t_f/√f_c) in mm (Chen & Teng 2001)."""
    _check_positive(f_c=f_c, E_f=E_f, t_f=t_f)
    return np.sqrt(np.asarray(E_f) * np.asarray(t_f) / np.sqrt(f_c))


def length_factor(L, L_e) -> np.ndarray:
    """β_L = 1 for L ≥ L_e, sin(πL/(2 L_e)) for shorter bonds."""
    _check_positive(L=L, L_e=L_e)
    ratio = np.asarray(L, dtype=float) / np.asarray(L_e, dtype=float)
    return np.where(ratio >= 1.0, 1.0, np.sin(np.pi / 2 * np.minimum(ratio, 1.0)))


def chen_teng_anchorage(f_c, E_f, t_f, b_f, b_c, L, alpha: float = ALPHA_CHEN_TENG):
    """Pull-test (plate-end anchorage) strength P_u in N of a bond of length L (mm)."""
    L_e = effective_bond_length(f_c, E_f, t_f)
    return (alpha * width_factor(b_f, b_c) * length_factor(L, L_e) * np.sqrt(f_c)
            * np.asarray(b_f) * L_e)


def teng_ic_strain(f_c, E_f, t_f, b_f, b_c, alpha: float = ALPHA_TENG_IC):
    """IC debonding strain of Teng et al. (2003): α β_w √(√f_c/(E_f t_f))."""
    _check_positive(f_c=f_c, E_f=E_f, t_f=t_f)
    return alpha * width_factor(b_f, b_c) * np.sqrt(np.sqrt(f_c) / (np.asarray(E_f) * t_f))


def aci440_strain(f_c, E_f, t_f, n_plies: int = 1, eps_fu=None):
    """ACI 440.2R-08 debonding strain 0.41 √(f_c/(n E_f t_f)), capped at 0.9 ε_fu if given."""
    _check_positive(f_c=f_c, E_f=E_f, t_f=t_f, n_plies=n_plies)
    eps = ALPHA_ACI * np.sqrt(np.asarray(f_c) / (n_plies * np.asarray(E_f) * t_f))
    return eps if eps_fu is None else np.minimum(eps, ACI_RUPTURE_CAP * np.asarray(eps_fu))


def said_wu_strain(f_c, E_f, t_f):
    """Said & Wu (2008) IC debonding strain 0.23 f_c^0.2/(E_f t_f)^0.35."""
    _check_positive(f_c=f_c, E_f=E_f, t_f=t_f)
    c, p, q = SAID_WU
    return c * np.asarray(f_c, dtype=float) ** p / (np.asarray(E_f) * t_f) ** q


def section_debonding_strain(sec: RCSection, model: str = "teng") -> float:
    """The IC debonding strain of a section's strengthening layer (the section in N, mm), with
    f_c the concrete strength of the section and b_c its width."""
    s = sec.strengthening
    if s is None:
        raise MaterialError("the section has no strengthening layer")
    b_f = sec.b if s.b_f is None else s.b_f
    f_c = sec.concrete.f_c
    if model == "teng":
        return float(teng_ic_strain(f_c, s.E_f, s.t_f, b_f, sec.b))
    if model == "aci440":
        return float(aci440_strain(f_c, s.E_f, s.t_f, eps_fu=s.eps_fu))
    if model == "said-wu":
        return float(said_wu_strain(f_c, s.E_f, s.t_f))
    raise MaterialError(f"IC debonding model {model!r} is not known; use 'teng', 'aci440' "
                        "or 'said-wu'")


def ic_debonding_moment(sec: RCSection, model: str = "teng") -> tuple[float, float, float]:
    """(M_db, κ_db, ε_db): the section moment and curvature at which the strengthening layer's
    strain reaches the IC debonding strain of ``model``."""
    eps_db = section_debonding_strain(sec, model)
    M, k = moment_at_strengthening_strain(sec, eps_db)
    return M, k, eps_db
