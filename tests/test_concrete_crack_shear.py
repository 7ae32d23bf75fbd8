"""Shear retention across an open crack (``ConcreteLaw.shear_retention`` = β, or with
``aggregate_size`` = d_agg the crack's shear stiffness of Walraven's aggregate interlock at its width w
over the band h, β = K(w) h/μ):
a pure shear across a fully opened crack keeps the fraction β of the elastic shear stiffness (none
beyond the damaged split's with the default 0), a closed crack its full stiffness, the tangent of
the retained shear against central differences, the projector Q_n against its definition, and bad
values refused."""
import dataclasses

import numpy as np
import pytest
from test_laws_concrete import NZ, _branches, _rotation
from test_laws_concrete import C30 as PLAIN

from layershell.laws.concrete import crack_shear_projector
from layershell.material import MaterialError

C30 = dataclasses.replace(PLAIN, shear_retention=0.2)
AGG = dataclasses.replace(PLAIN, aggregate_size=16.0, crack_spacing=40.0)  # N, mm; bars hold the cracks


def walraven_beta(width, band, f_c, mu):
    """β = K h/μ in [0, 1], K = 1.8 w^−0.8 + (0.234 w^−0.707 − 0.20) f_c (MPa/mm, w in mm; Walraven &
    Reinhardt 1981, d_max = 16 mm, so k_dg = 1)."""
    K = 1.8 * width ** -0.8 + (0.234 * width ** -0.707 - 0.2) * f_c
    return min(1.0, max(0.0, K * band / mu))


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


def _width_branches(law, eps, committed, normal, implex):
    """Per point: whether the crack strain n·ε·n is positive and whether 0 < β(w) < 1 (the kinks of
    the aggregate-size retention), w with the damage the response acts with."""
    _, _, tr = law.response(eps, committed, 80.0, 20.0, normal, tangent=False)
    d, _, _ = law.damage_tension((committed if implex else tr).r_t, committed.h_t)
    nv = np.stack([committed.n1, committed.n2, committed.n3], -1)
    e_nn = np.einsum("na,na->n", np.einsum("ni,nj->nij", nv, nv).reshape(-1, 9)[:, [0, 4, 8, 5, 2, 1]], eps)
    beta, _ = law.retention_factor(d * np.maximum(e_nn, 0.0) * committed.h_t, committed.h_t)
    return np.column_stack([e_nn > 0, beta > 0, beta < 1])


@pytest.mark.parametrize("implex", [False, True])
@pytest.mark.parametrize("law", [C30, AGG], ids=["beta=0.2", "d_agg=16"])
def test_tangent_with_retained_shear_against_central_differences(implex, law):
    """Points cracked along random normals (loaded past cracking), then random strains with shear:
    the tangent against central differences within 10⁻⁶ where the stencil stays on one branch
    (with d_agg = 16 mm the crack widths, up to about 0.3 mm over bands of 20 to 80 mm, give β
    between 0 and 1, and the variation of β with the width is in the tangent)."""
    n = 300
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
    k0 = _width_branches(law, eps, committed, normal, implex)
    for b in range(6):
        ep, em = eps.copy(), eps.copy()
        ep[:, b:b + 1] += step
        em[:, b:b + 1] -= step
        same &= np.all(_branches(law, ep, committed, 80.0, 20.0, normal) == b0, axis=1)
        same &= np.all(_branches(law, em, committed, 80.0, 20.0, normal) == b0, axis=1)
        for e in (ep, em):
            same &= np.all(_width_branches(law, e, committed, normal, implex) == k0, axis=1)
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


@pytest.mark.parametrize("implex", [False, True])
def test_shear_across_an_opening_crack_follows_walravens_interlock(implex):
    """Crack normal x opened to 60, 120, 200, 300 and 400 times the cracking strain (d⁺ > 0.9999)
    over the 50 mm band: a small shear γ_xy or γ_xz is carried with [β + (1 − β)(1 − d⁺)] μ,
    β = K(w) h/μ of Walraven's interlock stiffness (:func:`walraven_beta`) at the crack width
    w = d⁺ ε_xx h = 0.26, 0.53, 0.88, 1.32 and 1.76 mm: 0.075 falling to 0 (K = 0 from about
    1.6 mm at f_c = 38 MPa); the tangent's diagonal likewise."""
    law = AGG
    mu = law.lame()[1]
    kept = []
    for factor in (60.0, 120.0, 200.0, 300.0, 400.0):
        st, eps = opened(law, np.array([1.0, 0.0, 0.0]), factor)
        d, _, _ = law.damage_tension(st.r_t, st.h_t)
        assert d[0] > 0.9999 and st.h_t[0] == pytest.approx(H)
        beta = walraven_beta(d[0] * eps[0, 0] * H, H, law.f_c, mu)
        extra = {"implex": st} if implex else {}
        s0, D, _ = law.response(eps, st, H, H, NZ, **extra)
        for k in (5, 4):
            e = eps.copy()
            e[0, k] += 1e-3 * law.f_ct / law.E
            s1, _, _ = law.response(e, st, H, H, NZ, **extra)
            secant = (s1 - s0)[0, k] / (mu * (e - eps)[0, k])
            assert secant == pytest.approx(beta + (1 - beta) * (1 - d[0]), abs=1e-5)
            assert D[0, k, k] / mu == pytest.approx(beta + (1 - beta) * (1 - d[0]), abs=1e-5)
        kept.append(beta)
    assert 0.07 < kept[0] < 0.08 and kept[-1] == 0.0
    assert np.all(np.diff(kept) <= 0)


def test_interlock_scales_with_the_aggregate_size_and_the_units():
    """k_dg = 32/(16 + d_agg): with d_agg = 32 mm a width w keeps the β of w·2/3 at 16 mm; the same
    concrete in kN and m gives the same β."""
    law32 = dataclasses.replace(AGG, aggregate_size=32.0)
    w, h = np.array([0.3, 0.6, 0.9]), np.full(3, 50.0)
    np.testing.assert_allclose(law32.retention_factor(w, h)[0], AGG.retention_factor(w * 2 / 3, h)[0], rtol=1e-12)
    from layershell.laws import ConcreteLaw
    si = ConcreteLaw.from_class(30.0, 1e-3, 1.0, aggregate_size=0.016)  # kN, m
    np.testing.assert_allclose(si.retention_factor(w * 1e-3, h * 1e-3)[0], AGG.retention_factor(w, h)[0], rtol=1e-9)


def test_interlock_needs_a_crack_spacing():
    """Without bars holding its cracks (crack_spacing = 0) a crack keeps no interlock: a shear across
    it is carried with (1 − d⁺) μ only, as without retention."""
    law = dataclasses.replace(AGG, crack_spacing=0.0)
    st, eps = opened(law, np.array([1.0, 0.0, 0.0]), 60.0)
    d, _, _ = law.damage_tension(st.r_t, st.h_t)
    _, D, _ = law.response(eps, st, H, H, NZ)
    assert D[0, 5, 5] / law.lame()[1] == pytest.approx(1 - d[0], abs=1e-6)
    assert AGG.response(eps, st, H, H, NZ)[1][0, 5, 5] / law.lame()[1] > 0.07


@pytest.mark.parametrize("fields, match", [
    ({"aggregate_size": -16.0}, "aggregate_size=-16.0 must be a positive length"),
    ({"aggregate_size": float("nan")}, "aggregate_size=nan must be a positive length"),
    ({"aggregate_size": 16.0, "shear_retention": 0.2}, "not both"),
    ({"aggregate_size": 16.0, "stress_unit": 0.0}, "needs the model's units"),
])
def test_bad_aggregate_size_is_refused(fields, match):
    with pytest.raises(MaterialError, match=match):
        dataclasses.replace(PLAIN, **fields).check()
