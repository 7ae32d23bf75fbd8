"""The exact 3D solution of a simply supported cross-ply laminate under a double-sine load
(layershell.analytic.pagano) against independent references: the 3D field equations checked
by finite differences (equilibrium, Hooke's law, face tractions, interface continuity: together
they determine the solution uniquely), the Kirchhoff limit of a thin isotropic plate, and
Pagano's published normalised values for [0/90/0]."""
import numpy as np
import pytest

from layershell.analytic import pagano as pg
from layershell.material import Orthotropic

# Pagano (1970) ply: E_L/E_T = 25, G_LT = G_LZ = 0.5 E_T, G_TT = 0.2 E_T, ν = 0.25
PLY = Orthotropic.from_nu13(25.0, 1.0, 1.0, 0.5, 0.2, 0.5, 0.25, 0.25, 0.25)


def cross_ply(s: float, a: float = 1.0, b: float = 1.0) -> pg.PaganoPlate:
    h = a / s
    C = [pg.ply_stiffness(PLY.stiffness(), ang) for ang in (0, 90, 0)]
    return pg.solve(C, [h / 3] * 3, a, b)


@pytest.mark.parametrize("case", ["cross_ply", "isotropic", "unsymmetric"])
def test_fields_satisfy_3d_elasticity(case):
    """Strains from central differences of u, v, w times C equal the returned stresses; the
    divergence of the returned stresses (central differences) vanishes; σzz = -q0 sin sin,
    τxz = τyz = 0 on the top, zero tractions on the bottom; u, v, w, σzz, τxz, τyz continuous at
    the interfaces; σxx = 0 and w = v = 0 on the edge x = 0."""
    a, b = 1.0, 1.5
    if case == "cross_ply":
        C, t = [pg.ply_stiffness(PLY.stiffness(), ang) for ang in (0, 90, 0)], [0.1, 0.1, 0.1]
    elif case == "isotropic":
        C, t = [Orthotropic.isotropic(2.0, 0.3).stiffness()], [0.25]
    else:
        C = [pg.ply_stiffness(PLY.stiffness(), 90), Orthotropic.isotropic(3.0, 0.2).stiffness()]
        t = [0.05, 0.15]
    sol = pg.solve(C, t, a, b, q0=1.3)
    h = sol.h
    rng = np.random.default_rng(1)
    zs = np.concatenate([(sol.z0[:, None] + sol.t[:, None] * rng.uniform(0.1, 0.9, (len(t), 3))).ravel()])
    X = np.stack([rng.uniform(0.05, 0.95, zs.size) * a, rng.uniform(0.05, 0.95, zs.size) * b, zs], 1)
    eps = 1e-5 * h
    ply = np.searchsorted(sol.z0, zs, side="right") - 1

    def F(x, key):
        return sol.fields(x[:, 0], x[:, 1], x[:, 2])[key]

    def d(key, i, x=X):
        e = np.zeros(3)
        e[i] = eps
        return (F(x + e, key) - F(x - e, key)) / (2 * eps)

    H = np.stack([np.stack([d(k, i) for i in range(3)], -1) for k in ("u", "v", "w")], 1)  # (p, 3, 3)
    strain = np.stack([H[:, 0, 0], H[:, 1, 1], H[:, 2, 2], H[:, 1, 2] + H[:, 2, 1], H[:, 0, 2] + H[:, 2, 0],
                       H[:, 0, 1] + H[:, 1, 0]], 1)
    stress = np.einsum("pij,pj->pi", np.asarray(sol.C)[ply], strain)
    f = sol.fields(X[:, 0], X[:, 1], X[:, 2])
    ref = np.stack([f[k] for k in ("sxx", "syy", "szz", "tyz", "txz", "txy")], 1)
    scale = np.abs(ref).max()
    assert np.abs(stress - ref).max() < 1e-6 * scale
    div = np.stack([d("sxx", 0) + d("txy", 1) + d("txz", 2), d("txy", 0) + d("syy", 1) + d("tyz", 2),
                    d("txz", 0) + d("tyz", 1) + d("szz", 2)], 1)
    assert np.abs(div).max() < 1e-6 * scale / h
    x, y = 0.3 * a, 0.6 * b
    top, bot = sol.fields(x, y, h), sol.fields(x, y, 0.0)
    assert np.isclose(top["szz"], -1.3 * np.sin(np.pi * x / a) * np.sin(np.pi * y / b), rtol=1e-10)
    for k in ("txz", "tyz"):
        assert abs(top[k]) < 1e-10 * scale and abs(bot[k]) < 1e-10 * scale
    assert abs(bot["szz"]) < 1e-10 * scale
    for zi in sol.z0[1:]:
        lo, up = sol.fields(x, y, zi * (1 - 1e-12)), sol.fields(x, y, zi * (1 + 1e-12))
        for k in ("u", "v", "w", "szz", "txz", "tyz"):
            assert np.isclose(lo[k], up[k], rtol=1e-8, atol=1e-12 * scale)
    edge = sol.fields(0.0, y, np.linspace(0, h, 5))
    assert np.abs(edge["sxx"]).max() < 1e-12 and np.abs(edge["w"]).max() < 1e-12 and np.abs(edge["v"]).max() < 1e-12


@pytest.mark.parametrize("s, tol", [(100, 2e-3), (1000, 2e-5)])
def test_isotropic_thin_plate_limit(s, tol):
    """A thin homogeneous isotropic plate: the mid-plane deflection tends to Kirchhoff's
    q0 / (D (p² + q²)²) with the 3D correction O((h/a)²) (shear + thickness stretch), and σxx on
    the faces to ± 6 M / h² with M = D (p² + ν q²) w."""
    E, nu, a, b = 7.0, 0.3, 1.0, 2.0
    h = a / s
    sol = pg.solve([Orthotropic.isotropic(E, nu).stiffness()], [h], a, b)
    D = E * h**3 / (12 * (1 - nu**2))
    w_k = pg.classical_plate_deflection(np.array([D, nu * D, D, (1 - nu) * D / 2]), a, b)
    w = -sol.fields(a / 2, b / 2, h / 2)["w"]
    assert w > w_k and (w - w_k) / w_k < tol
    p, q = np.pi / a, np.pi / b
    sx = sol.fields(a / 2, b / 2, h)["sxx"]
    assert np.isclose(-sx, 6 * D * (p**2 + nu * q**2) * w_k / h**2, rtol=5 * tol)


# Pagano (1970), Table 3 (also Reddy, "Mechanics of laminated composite plates and shells",
# 2nd ed. 2004, Table 8.3.1 "exact"): square [0/90/0] plate, equal plies, normalised
# w̄ = 100 E_T h³ w(a/2, b/2, 0) / (q0 a⁴), σ̄ = σ h² / (q0 a²), τ̄ = τ h / (q0 a), z from mid-plane.
PAGANO_0_90_0 = {  # s = a/h: w̄, σ̄xx(a/2,b/2,h/2), σ̄yy(a/2,b/2,h/6), τ̄xz(0,b/2,0), τ̄yz(a/2,0,0), τ̄xy(0,0,h/2)
    4: (2.0059, 0.801, 0.534, 0.256, 0.2172, 0.0511),
    10: (0.7530, 0.590, 0.285, 0.357, 0.1228, 0.0289),
    20: (0.5164, 0.552, 0.210, 0.385, 0.0938, 0.0234),
    100: (0.4347, 0.539, 0.181, 0.395, 0.0828, 0.0213),
}


@pytest.mark.parametrize("s", sorted(PAGANO_0_90_0))
def test_cross_ply_matches_pagano_table(s):
    """The normalised values of Pagano's table to the digits printed (half a unit of the last
    digit, 0.5 % for the three-digit σ̄yy which Pagano rounded up)."""
    a = 1.0
    h = a / s
    sol = cross_ply(s, a, a)
    f = sol.fields
    got = (-100 * h**3 * f(a / 2, a / 2, h / 2)["w"] / a**4, -f(a / 2, a / 2, h)["sxx"] / s**2,
           -f(a / 2, a / 2, h / 2 + h / 6)["syy"] / s**2, -f(0, a / 2, h / 2)["txz"] / s,
           -f(a / 2, 0, h / 2)["tyz"] / s, f(0, 0, h)["txy"] / s**2)
    for g, ref in zip(got, PAGANO_0_90_0[s]):
        digits = len(f"{ref}".split(".")[1])
        assert abs(g - ref) <= max(0.5 * 10**-digits, 0.005 * ref) * (1 + 1e-9), (g, ref)
