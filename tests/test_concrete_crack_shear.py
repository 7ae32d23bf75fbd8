"""Shear retention across an open crack (``ConcreteLaw.shear_retention`` = β): a pure shear across a
fully opened crack keeps the fraction β of the elastic shear stiffness (none beyond the damaged
split's with the default 0), a closed crack its full stiffness, the tangent of the retained shear
against central differences, the projector Q_n against its definition, and bad values refused."""
import dataclasses

import numpy as np
import pytest
from test_laws_concrete import NZ, _branches, _rotation
from test_laws_concrete import C30 as PLAIN

from layershell.laws.concrete import crack_shear_projector
from layershell.material import MaterialError

C30 = dataclasses.replace(PLAIN, shear_retention=0.2)

H = 50.0


def opened(law, normal, factor):
    """A point cracked along ``normal`` by a uniaxial stress path to ``factor`` times the cracking
    strain: its committed state and the last strain (n = 1)."""
    e0 = law.f_ct / law.E
    R = np.linalg.qr(np.column_stack([normal, np.eye(3)[:, :2]]))[0]
    st = law.state(1)
    for e in np.linspace(0.0, factor * e0, 400):
        local = np.diag([e, -law.nu * min(e, e0), -law.nu * min(e, e0)])
        T = R @ local @ R.T
        eps = np.array([[T[0, 0], T[1, 1], T[2, 2], 2 * T[1, 2], 2 * T[0, 2], 2 * T[0, 1]]])
        _, _, st = law.response(eps, st, H, H, NZ, tangent=False)
    return st, eps


def test_projector_keeps_the_shear_traction_on_the_crack_plane():
    rng = np.random.default_rng(5)
    n = rng.normal(size=(20, 3))
    n /= np.linalg.norm(n, axis=1)[:, None]
    A = rng.normal(size=(20, 6))
    T = np.zeros((20, 3, 3))
    for a, (i, j) in enumerate(((0, 0), (1, 1), (2, 2), (1, 2), (0, 2), (0, 1))):
        T[:, i, j] = T[:, j, i] = A[:, a]
    t = np.einsum("nij,nj->ni", T, n)
    tn = np.einsum("ni,ni->n", t, n)
    S = np.einsum("ni,nj->nij", t - tn[:, None] * n, n)
    S = S + S.transpose(0, 2, 1)
    ref = np.stack([S[:, 0, 0], S[:, 1, 1], S[:, 2, 2], S[:, 1, 2], S[:, 0, 2], S[:, 0, 1]], -1)
    np.testing.assert_allclose(np.einsum("nab,nb->na", crack_shear_projector(n), A), ref, atol=1e-12)


@pytest.mark.parametrize("implex", [False, True])
@pytest.mark.parametrize("law", [C30, PLAIN], ids=["beta=0.2", "default"])
def test_shear_across_an_open_crack_keeps_the_retained_fraction(implex, law):
    """Crack normal x, opened to 60 times the cracking strain (d⁺ > 0.9999): a small shear γ_xy or
    γ_xz is carried with β μ, a shear γ_yz in the crack's plane with (1 - d⁺) μ only."""
    st, eps = opened(law, np.array([1.0, 0.0, 0.0]), 60.0)
    d, _, _ = law.damage_tension(st.r_t, st.h_t)
    assert d[0] > 0.9999
    mu = law.lame()[1]
    extra = {"implex": st} if implex else {}
    s0, D, _ = law.response(eps, st, H, H, NZ, **extra)
    for k, keep in ((5, law.shear_retention), (4, law.shear_retention), (3, 0.0)):
        e = eps.copy()
        e[0, k] += 1e-3 * law.f_ct / law.E
        s1, _, _ = law.response(e, st, H, H, NZ, **extra)
        secant = (s1 - s0)[0, k] / (mu * (e - eps)[0, k])
        assert secant == pytest.approx(keep, abs=2e-4)
        assert D[0, k, k] / mu == pytest.approx(keep, abs=2e-4)


def test_a_closed_crack_has_the_full_stiffness_in_shear_too():
    law = C30
    st, _ = opened(law, np.array([1.0, 1.0, 0.0]) / np.sqrt(2), 20.0)
    comp = -1e-4 * np.array([[1.0, 1.0, 1.0, 0.2, 0.1, 0.3]])
    s, D, _ = law.response(comp, st, H, H, NZ)
    np.testing.assert_allclose(D[0], law.stiffness(), rtol=1e-9, atol=1e-9 * law.E)
    np.testing.assert_allclose(s[0], comp[0] @ law.stiffness(), rtol=1e-12)


@pytest.mark.parametrize("implex", [False, True])
def test_tangent_with_retained_shear_against_central_differences(implex):
    """Points cracked along random normals (loaded past cracking), then random strains with shear:
    the tangent against central differences within 10⁻⁶ where the stencil stays on one branch."""
    law, n = C30, 300
    rng = np.random.default_rng(21)
    e0 = law.f_ct / law.E
    normal = np.array([_rotation(*rng.uniform(0, 2 * np.pi, 3))[:, 2] for _ in range(n)])
    crack = rng.normal(size=(n, 3))
    crack /= np.linalg.norm(crack, axis=1)[:, None]
    N = np.einsum("ni,nj->nij", crack, crack)
    T = rng.uniform(1.5, 30.0, (n, 1, 1)) * e0 * N  # opening across a random plane
    first = np.stack([T[:, 0, 0], T[:, 1, 1], T[:, 2, 2], 2 * T[:, 1, 2], 2 * T[:, 0, 2], 2 * T[:, 0, 1]], -1)
    _, _, committed = law.response(first, law.state(n), 80.0, 20.0, normal, False)
    cracked = committed.h_t > 0
    assert cracked.sum() > n // 2
    eps = first * rng.uniform(0.5, 1.5, (n, 1)) + rng.normal(0.0, 2 * e0, (n, 6))
    extra = {"implex": committed} if implex else {}
    _, D, _ = law.response(eps, committed, 80.0, 20.0, normal, **extra)
    step = 1e-8 * np.abs(eps).max(axis=1, keepdims=True)
    fd = np.empty_like(D)
    same = np.ones(n, bool)
    b0 = _branches(law, eps, committed, 80.0, 20.0, normal)
    for b in range(6):
        ep, em = eps.copy(), eps.copy()
        ep[:, b:b + 1] += step
        em[:, b:b + 1] -= step
        same &= np.all(_branches(law, ep, committed, 80.0, 20.0, normal) == b0, axis=1)
        same &= np.all(_branches(law, em, committed, 80.0, 20.0, normal) == b0, axis=1)
        fd[:, :, b] = (law.response(ep, committed, 80.0, 20.0, normal, False, **extra)[0]
                       - law.response(em, committed, 80.0, 20.0, normal, False, **extra)[0]) / (2 * step)
    ok = same & cracked
    assert ok.sum() > n // 4
    err = np.linalg.norm(D - fd, axis=(1, 2)) / np.linalg.norm(fd, axis=(1, 2))
    assert np.all(err[ok] < 1e-6), (err[ok].max(), np.argmax(np.where(ok, err, 0)))


@pytest.mark.parametrize("value", [-0.1, 1.5])
def test_shear_retention_outside_0_1_is_refused(value):
    with pytest.raises(MaterialError, match="shear_retention.*must lie in"):
        dataclasses.replace(PLAIN, shear_retention=value).check()
