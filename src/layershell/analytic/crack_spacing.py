"""Crack spacing of reinforced concrete after EN 1992-1-1 §7.3.4: the reference length below which
elements of a smeared-crack layer with perfectly bonded bars stop being objective.

s_r,max = k3 c + k1 k2 k4 φ / ρ_p,eff (eq. 7.11) with k1 = 0.8 (high-bond bars), k2 = 0.5
(bending; 1.0 in pure tension), k3 = 3.4, k4 = 0.425 (the recommended values), c the cover to
the bars, ρ_p,eff = A_s / A_c,eff with the effective tension depth h_c,ef = min(2.5 (h − d), h/2)
(the third limit, (h − x)/3, needs the neutral axis and is left out: it matters only for thin
members with deep compression zones). The mean spacing is s_r,max / 1.7 (the ratio of the
characteristic to the mean crack width in EN 1992-1-1 and fib MC2010, 7.6.4).
"""
from __future__ import annotations

import numpy as np

from layershell.material import MaterialError

K1_HIGH_BOND = 0.8
K2_BENDING = 0.5
K3 = 3.4
K4 = 0.425
#: s_r,max over the mean crack spacing s_rm
MAX_OVER_MEAN = 1.7


def max_crack_spacing(cover, bar_diameter, area_per_width, thickness, k2: float = K2_BENDING) -> float:
    """s_r,max (eq. 7.11) of bars of ``bar_diameter`` with ``area_per_width`` (A_s per unit width)
    at ``cover`` (to the bar's surface) from the nearer face of a member ``thickness`` deep."""
    for name, v in (("cover", cover), ("bar_diameter", bar_diameter), ("area_per_width", area_per_width),
                    ("thickness", thickness)):
        if not (np.isfinite(v) and v > 0):
            raise MaterialError(f"crack spacing: '{name}' must be a positive number (got {v!r})")
    axis_depth = cover + 0.5 * bar_diameter
    h_eff = min(2.5 * axis_depth, 0.5 * thickness)
    rho = area_per_width / h_eff
    return K3 * cover + K1_HIGH_BOND * k2 * K4 * bar_diameter / rho


def mean_crack_spacing(cover, bar_diameter, area_per_width, thickness, k2: float = K2_BENDING) -> float:
    """s_rm = s_r,max / 1.7."""
    return max_crack_spacing(cover, bar_diameter, area_per_width, thickness, k2) / MAX_OVER_MEAN
