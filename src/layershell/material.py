"""Linear elastic orthotropic 3D material, MODEL.md §4 / thesis (2.143)-(2.150).

Voigt order used throughout layershell: ``[11, 22, 33, 23, 13, 12]`` with engineering shear
strains ``2 E_23, 2 E_13, 2 E_12``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

VOIGT = ((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))


class MaterialError(ValueError):
    """Raised for physically inadmissible material constants."""


@dataclass(frozen=True)
class Orthotropic:
    """Nine engineering constants in the material frame M_1, M_2, M_3 (M_3 = shell normal).

    ``nu_ij`` is the contraction in j under uniaxial stress in i; reciprocity (2.147) gives
    ``nu_ji = nu_ij E_j / E_i``.
    """

    E1: float
    E2: float
    E3: float
    G12: float
    G23: float
    G31: float
    nu12: float
    nu23: float
    nu31: float
    density: float = 0.0
    name: str = "material"

    @classmethod
    def isotropic(cls, E: float, nu: float, density: float = 0.0, name: str = "material") -> "Orthotropic":
        if not -1.0 < nu < 0.5:
            raise MaterialError(f"material '{name}': the Poisson ratio nu={nu} must lie in (-1, 0.5) for a "
                                "positive definite isotropic law")
        G = E / (2.0 * (1.0 + nu))
        return cls(E, E, E, G, G, G, nu, nu, nu, density, name)

    @classmethod
    def from_nu13(cls, E1, E2, E3, G12, G23, G31, nu12, nu23, nu13, density=0.0, name="material"):
        """Constants with nu13 given instead of nu31 (thesis examples 5.1, 5.3.1)."""
        return cls(E1, E2, E3, G12, G23, G31, nu12, nu23, nu13 * E3 / E1, density, name)

    # -- laws ------------------------------------------------------------------------------
    def compliance(self) -> np.ndarray:
        """6x6 compliance matrix (Voigt, engineering shear)."""
        E1, E2, E3 = self.E1, self.E2, self.E3
        s = np.zeros((6, 6))
        s[0, 0], s[1, 1], s[2, 2] = 1 / E1, 1 / E2, 1 / E3
        s[0, 1] = s[1, 0] = -self.nu12 / E1
        s[1, 2] = s[2, 1] = -self.nu23 / E2
        s[0, 2] = s[2, 0] = -self.nu31 / E3
        s[3, 3], s[4, 4], s[5, 5] = 1 / self.G23, 1 / self.G31, 1 / self.G12
        return s

    def stiffness(self) -> np.ndarray:
        """6x6 stiffness matrix in the material frame, closed form (2.148)-(2.149)."""
        E1, E2, E3 = self.E1, self.E2, self.E3
        n12, n23, n31 = self.nu12, self.nu23, self.nu31
        n21, n32, n13 = n12 * E2 / E1, n23 * E3 / E2, n31 * E1 / E3
        D = 1 - n12 * n21 - n23 * n32 - n31 * n13 - 2 * n21 * n13 * n32
        c = np.zeros((6, 6))
        c[0, 0] = (1 - n23 * n32) * E1 / D
        c[1, 1] = (1 - n31 * n13) * E2 / D
        c[2, 2] = (1 - n12 * n21) * E3 / D
        c[0, 1] = c[1, 0] = (n12 + n32 * n13) * E2 / D
        c[1, 2] = c[2, 1] = (n23 + n21 * n13) * E3 / D
        c[2, 0] = c[0, 2] = (n13 + n12 * n23) * E3 / D
        c[3, 3], c[4, 4], c[5, 5] = self.G23, self.G31, self.G12
        return c

    def check(self) -> None:
        """Raise :class:`MaterialError` naming the constants if the law is not positive definite."""
        bad = [k for k in ("E1", "E2", "E3", "G12", "G23", "G31") if not getattr(self, k) > 0]
        if bad:
            raise MaterialError(
                f"material '{self.name}': {', '.join(bad)} must be positive "
                f"(got {', '.join(f'{k}={getattr(self, k)}' for k in bad)})"
            )
        ev = np.linalg.eigvalsh(self.compliance())
        if not np.all(ev > 0):
            raise MaterialError(
                f"material '{self.name}': the Poisson ratios nu12={self.nu12}, nu23={self.nu23}, "
                f"nu31={self.nu31} with E1={self.E1}, E2={self.E2}, E3={self.E3} give a stiffness "
                "tensor that is not positive definite (smallest compliance eigenvalue "
                f"{ev.min():.3g}); reduce the Poisson ratios (isotropic: -1 < nu < 0.5; "
                "orthotropic: nu_ij^2 < E_i/E_j and 1 - nu12 nu21 - nu23 nu32 - nu31 nu13 "
                "- 2 nu21 nu32 nu13 > 0)"
            )


def voigt_to_tensor(c: np.ndarray) -> np.ndarray:
    """(..., 6, 6) Voigt stiffness -> (..., 3, 3, 3, 3) tensor."""
    t = np.zeros(c.shape[:-2] + (3, 3, 3, 3))
    for a, (i, j) in enumerate(VOIGT):
        for b, (k, l) in enumerate(VOIGT):
            v = c[..., a, b]
            t[..., i, j, k, l] = t[..., j, i, k, l] = t[..., i, j, l, k] = t[..., j, i, l, k] = v
    return t


def tensor_to_voigt(t: np.ndarray) -> np.ndarray:
    """(..., 3, 3, 3, 3) stiffness tensor -> (..., 6, 6) Voigt."""
    idx = np.array(VOIGT)
    return t[..., idx[:, 0][:, None], idx[:, 1][:, None], idx[:, 0][None, :], idx[:, 1][None, :]]


def rotate_stiffness(c_material: np.ndarray, frame: np.ndarray) -> np.ndarray:
    """Cartesian Voigt stiffness from the material-frame one, (2.150).

    ``frame[..., i, :]`` is the unit vector M_i in Cartesian components; returns ``(..., 6, 6)``.
    """
    # C' = K C Kᵀ with the 6 × 6 transformation of the Voigt pairs: K_(IJ),(ij) = R_iI R_jJ
    # (+ R_jI R_iJ for i ≠ j, the two entries a Voigt pair stands for), R = frame - the same sums
    # as the tensor rotation Σ R_iI R_jJ R_kK R_lL c_ijkl, without the 3⁴ tensors per point
    v = np.array(VOIGT)
    i, j = v[:, 0][None, :], v[:, 1][None, :]  # material pair (columns)
    I, J = v[:, 0][:, None], v[:, 1][:, None]  # Cartesian pair (rows)
    R = np.asarray(frame, float)
    K = R[..., i, I] * R[..., j, J] + np.where(i != j, R[..., j, I] * R[..., i, J], 0.0)
    return np.matmul(np.matmul(K, c_material), np.swapaxes(K, -1, -2))


def laminate_equivalent(plies, name: str = "ply stack") -> Orthotropic:
    """A homogenised orthotropic stand-in for a ply stack (``plies``: (material, angle in degrees,
    thickness fraction) each), in the frame of the stack's angle 0: in-plane constants from the
    thickness average of the plane-stress stiffness Q̄ (the membrane stiffness A/h; E1 = 1/a11,
    E2 = 1/a22, ν12 = -a12/a11, G12 = 1/a66 with a = (A/h)⁻¹, the 16/26 coupling dropped),
    E3 and the transverse shear moduli in series (the compliances averaged), ν23, ν31 and the
    density averaged. For estimates only (penalties, process zones, mass), never for stresses."""
    f = np.array([p[2] for p in plies], float)
    f = f / f.sum()
    Qbar = np.zeros((3, 3))
    s33 = g13 = g23 = nu23 = nu31 = rho = 0.0
    for (mat, ang, _), fr in zip(plies, f):
        c, s = np.cos(np.deg2rad(ang)), np.sin(np.deg2rad(ang))
        R = np.array([[c, s, 0.0], [-s, c, 0.0], [0.0, 0.0, 1.0]])  # rows M_i in the stack frame
        Cg = rotate_stiffness(mat.stiffness(), R)
        Cip, Cn = Cg[np.ix_([0, 1, 5], [0, 1, 5])], Cg[np.ix_([0, 1, 5], [2])]
        Qbar += fr * (Cip - Cn @ Cn.T / Cg[2, 2])
        s33 += fr / mat.E3
        g13 += fr * (c * c / mat.G31 + s * s / mat.G23)
        g23 += fr * (s * s / mat.G31 + c * c / mat.G23)
        nu23, nu31, rho = nu23 + fr * mat.nu23, nu31 + fr * mat.nu31, rho + fr * mat.density
    a = np.linalg.inv(Qbar)
    return Orthotropic(1 / a[0, 0], 1 / a[1, 1], 1 / s33, 1 / a[2, 2], 1 / g23, 1 / g13, -a[0, 1] / a[0, 0],
                       nu23, nu31, rho, name)
