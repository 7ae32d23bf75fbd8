"""Homogenised orthotropic constants of the three element layers of thesis §5.3.1 (MODEL.md V7).

    python examples/make_cfrp_laminate.py

The CFRP plate has 16 AS/3501 plies of 0.12 mm with the ply data (5.1)

    E11 = 135000, E22 = E33 = 8500, G12 = G13 = G23 = 5150 N/mm², ν12 = ν23 = ν13 = 0.317

(axis 1 = fibre), stacked 0/0/45/0/0/-45/0/90 (plies 1-8, angle to x1) and mirrored (plies 16-9).
The thesis lumps them into three element layers, I = plies 1-2 (0.24 mm), II = plies 3-14
(1.44 mm), III = plies 15-16 (0.24 mm), each "homogenised orthotropic" without saying how. As
MODEL.md V7 proposes, every layer gets the thickness average of the rotated 6×6 ply stiffness
matrices (a Voigt average: exact for the in-plane stiffness of a layer under uniform in-plane
strain, an approximation for the through-thickness constants E3, G23, G31), inverted to the nine
engineering constants in the x1/x2/x3 frame.

Region II holds ±45° plies in balanced pairs, so the couplings C16, C26, C36 (normal/in-plane
shear) cancel, and C45 (23/13 shear coupling) vanishes because G13 = G23 for the ply. The script
prints them (they are zero up to round-off) and then drops them explicitly. Output: the TOML
``[materials.*]`` blocks used in examples/cfrp_circular.toml, and the through-thickness edge
traction of F = 30 N/mm split over the layers by E1 × thickness (the thesis: "entsprechend der
Längssteifigkeiten der Bereiche ... in x1-Richtung und der Schichtdicken").
"""
from __future__ import annotations

import numpy as np

from layershell.material import Orthotropic, rotate_stiffness

PLY = Orthotropic.from_nu13(135000.0, 8500.0, 8500.0, 5150.0, 5150.0, 5150.0, 0.317, 0.317, 0.317, name="AS/3501")
T_PLY = 0.12  # mm
HALF = [0.0, 0.0, 45.0, 0.0, 0.0, -45.0, 0.0, 90.0]  # plies 1..8; plies 16..9 repeat these
ANGLES = HALF + HALF[::-1]  # plies 1..16 from the reference (bottom) face up
REGIONS = {"I": (1, 2), "II": (3, 14), "III": (15, 16)}  # ply ranges (inclusive)
F_EDGE = 30.0  # N/mm, thesis (5.1)

# Voigt order [11, 22, 33, 23, 13, 12]: the entries that couple normal and in-plane shear (16, 26,
# 36) and the two transverse shears (45) must vanish for an orthotropic layer in the x1/x2/x3 frame
COUPLING = {"C16": (0, 5), "C26": (1, 5), "C36": (2, 5), "C45": (3, 4),
            "C14": (0, 3), "C24": (1, 3), "C34": (2, 3), "C15": (0, 4), "C25": (1, 4), "C35": (2, 4),
            "C46": (3, 5), "C56": (4, 5)}


def frame(angle_deg: float) -> np.ndarray:
    """Rows M_1, M_2, M_3 of a ply rotated by ``angle_deg`` about x3."""
    a = np.deg2rad(angle_deg)
    c, s = np.cos(a), np.sin(a)
    return np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])


def layer_stiffness(plies: tuple[int, int]) -> tuple[np.ndarray, float]:
    """Thickness average of the rotated ply stiffnesses of plies ``plies[0]..plies[1]`` and the thickness."""
    c0 = PLY.stiffness()
    angles = ANGLES[plies[0] - 1: plies[1]]
    C = sum(rotate_stiffness(c0, frame(a)) for a in angles) / len(angles)
    return C, len(angles) * T_PLY


def engineering_constants(C: np.ndarray) -> dict[str, float]:
    """E1 E2 E3 G12 G23 G31 nu12 nu23 nu31 of an orthotropic Voigt stiffness (couplings already dropped)."""
    S = np.linalg.inv(C)
    E1, E2, E3 = 1 / S[0, 0], 1 / S[1, 1], 1 / S[2, 2]
    return {"E1": E1, "E2": E2, "E3": E3, "G12": 1 / S[5, 5], "G23": 1 / S[3, 3], "G31": 1 / S[4, 4],
            "nu12": -S[0, 1] * E1, "nu23": -S[1, 2] * E2, "nu31": -S[2, 0] * E3}


def homogenise(verbose: bool = True) -> dict[str, tuple[dict[str, float], float]]:
    """{region: (engineering constants, thickness)} with the off-orthotropic terms dropped."""
    out = {}
    for name, plies in REGIONS.items():
        C, H = layer_stiffness(plies)
        scale = np.abs(C).max()
        coup = {k: C[i, j] for k, (i, j) in COUPLING.items()}
        worst = max(abs(v) for v in coup.values()) / scale
        if verbose:
            print(f"# region {name}: plies {plies[0]}-{plies[1]}, angles {ANGLES[plies[0] - 1: plies[1]]}, H = {H:.2f} mm")
            print(f"#   largest off-orthotropic term |C_ij|/max|C| = {worst:.2e} "
                  f"(C16 = {coup['C16']:.3e}, C26 = {coup['C26']:.3e}, C36 = {coup['C36']:.3e}, "
                  f"C45 = {coup['C45']:.3e} N/mm²)")
            why = ("the ±45° plies are balanced, so C16/C26/C36 cancel; G13 = G23 makes C45 zero"
                   if any(abs(a) == 45.0 for a in ANGLES[plies[0] - 1: plies[1]]) else "only 0° plies")
            print(f"#   NOTE: these terms are dropped explicitly (set to 0) before inverting: {why}")
        Co = C.copy()
        for i, j in COUPLING.values():
            Co[i, j] = Co[j, i] = 0.0
        ec = engineering_constants(Co)
        mat = Orthotropic(**ec, name=name)
        mat.check()
        assert np.allclose(mat.stiffness(), Co, rtol=1e-9, atol=1e-9 * scale)
        out[name] = (ec, H)
    return out


def edge_tractions(consts: dict[str, tuple[dict[str, float], float]], F: float = F_EDGE) -> dict[str, float]:
    """Through-thickness traction per layer (N/mm²) with layer force ∝ E1 × H and Σ t H = F."""
    EH = {k: ec["E1"] * H for k, (ec, H) in consts.items()}
    tot = sum(EH.values())
    return {k: F * EH[k] / tot / consts[k][1] for k in consts}


def main() -> None:
    consts = homogenise()
    print()
    for name, (ec, H) in consts.items():
        a, b = REGIONS[name]
        angles = "/".join(f"{x:g}" for x in ANGLES[a - 1: b])
        print(f"[materials.cfrp_{name}]   # element layer {name}, plies {a}-{b} ({angles}), H = {H:.2f} mm")
        print('type = "orthotropic"')
        for k in ("E1", "E2", "E3", "G12", "G23", "G31"):
            print(f"{k} = {ec[k]:.1f}")
        for k in ("nu12", "nu23", "nu31"):
            print(f"{k} = {ec[k]:.6g}")
        print()
    t = edge_tractions(consts)
    H = {k: consts[k][1] for k in consts}
    print(f"# edge traction of F = {F_EDGE} N/mm split by E1 x H (N/mm² per unit load factor):")
    for k in t:
        print(f"#   layer {k}: t = {t[k]:.4f} N/mm²  (force {t[k] * H[k]:.4f} N/mm, "
              f"{100 * t[k] * H[k] / F_EDGE:.2f} %)")
    b1, b2 = H["I"], H["I"] + H["II"]
    print(f'distribution = "where(t < {b1:.2f}, {t["I"]:.4f}, where(t < {b2:.2f}, {t["II"]:.4f}, {t["III"]:.4f}))"')


if __name__ == "__main__":
    main()
