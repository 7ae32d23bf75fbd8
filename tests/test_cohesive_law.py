"""Cohesive material point (issue 13): energies against the Benzeggagh–Kenane fracture energy,
the consistent tangent against finite differences, irreversibility and compression."""
import numpy as np
import pytest

from layershell.cohesive import CohesiveLaw, damage_trial, dissipated, onset, point_response

N3 = np.array([0.0, 0.0, 1.0])
K = 1.0e6  # N/mm³-like penalty
LAWS = {
    "thesis": CohesiveLaw(G_Ic=0.3, G_IIc=1.2, sigma_max=2.0, tau_max=6.0, eta=2.2, p=2.0),
    "thesis_p3": CohesiveLaw(G_Ic=0.3, G_IIc=1.2, sigma_max=2.0, tau_max=6.0, eta=1.45, p=3.0),
    "thesis_p1": CohesiveLaw(G_Ic=0.3, G_IIc=1.2, sigma_max=2.0, tau_max=6.0, eta=2.2, p=1.0),
    "quadratic": CohesiveLaw(G_Ic=0.3, G_IIc=1.2, sigma_max=2.0, tau_max=6.0, eta=2.2, onset="quadratic"),
    "exponential": CohesiveLaw(G_Ic=0.3, G_IIc=1.2, sigma_max=2.0, tau_max=6.0, eta=2.2, softening="exponential"),
}


def work_along(direction, law, lam_end, n=20000, K=K):
    """∫ t·dδ along δ = s·direction, s from 0 to lam_end (trapezoid). Along a monotonic path the
    converged damage of step k is the largest trial damage so far (the history variable)."""
    e = np.asarray(direction, float) / np.linalg.norm(direction)
    s = np.linspace(0.0, lam_end, n + 1)
    delta = s[:, None] * e
    normals = np.broadcast_to(N3, delta.shape)
    _, d_trial, _ = point_response(delta, normals, np.zeros(n + 1), K, law, tangent=False)
    d_hist = np.concatenate([[0.0], np.maximum.accumulate(d_trial)[:-1]])
    t, d, _ = point_response(delta, normals, d_hist, K, law, tangent=False)
    W = float(np.sum(0.5 * (t[1:] + t[:-1]) * np.diff(delta, axis=0)))
    return W, d[-1], t[-1]


@pytest.mark.parametrize("name", list(LAWS))
@pytest.mark.parametrize("angle", [0.0, 30.0, 55.0, 90.0])
def test_proportional_path_dissipates_bk_energy(name, angle):
    """The work of separating a point along a proportional path to complete failure equals the
    BK fracture energy G_Ic + (G_IIc - G_Ic) B^η at that mode ratio (within 1 %); pure mode I
    and II give G_Ic and G_IIc."""
    law = LAWS[name]
    a = np.radians(angle)
    direction = [np.sin(a) * np.cos(0.3), np.sin(a) * np.sin(0.3), np.cos(a)]
    B = np.sin(a) ** 2
    Gc = law.G_Ic + (law.G_IIc - law.G_Ic) * B**law.eta
    l0, _ = onset(np.array(B), K, law)
    lam_end = 2 * Gc / (K * l0) * (1.0001 if law.softening == "bilinear" else 30.0)
    W, d, t = work_along(direction, law, lam_end)
    if law.softening == "bilinear":
        assert d == 1.0 and np.linalg.norm(t) == 0.0
    assert W == pytest.approx(Gc, rel=1e-2)
    if angle in (0.0, 90.0):
        assert W == pytest.approx(law.G_Ic if angle == 0 else law.G_IIc, rel=1e-2)
    # the closed-form dissipation at complete damage is the same energy
    assert float(dissipated(np.array(1.0), np.array(B), K, law)) == pytest.approx(Gc, rel=1e-2)


@pytest.mark.parametrize("name", ["thesis", "thesis_p3", "thesis_p1", "quadratic"])
def test_onset_meets_strength_criterion(name):
    """The undamaged traction at λ0(B) lies on the strength criterion; pure modes give σ_max, τ_max.
    (p = 1 and 2 are solved in closed form, other p by a safeguarded Newton iteration.)"""
    law = LAWS[name]
    B = np.linspace(0.0, 1.0, 11)
    l0, dl0 = onset(B, K, law)
    sig, tau = K * l0 * np.sqrt(1 - B), K * l0 * np.sqrt(B)
    if law.onset == "quadratic":
        np.testing.assert_allclose((sig / law.sigma_max) ** 2 + (tau / law.tau_max) ** 2, 1.0, rtol=1e-12)
    else:
        # (B = 0 sits on the tensile cut-off σ = σ_max, checked below)
        np.testing.assert_allclose(tau[1:], law.tau_max * np.clip(1 - sig[1:] / law.sigma_max, 0, None) ** (1 / law.p),
                                   rtol=1e-9)
    assert sig[0] == pytest.approx(law.sigma_max) and tau[-1] == pytest.approx(law.tau_max)
    # dλ0/dB by central differences inside (0, 1)
    Bi = np.linspace(0.05, 0.95, 10)
    h = 1e-6
    fd = (onset(Bi + h, K, law)[0] - onset(Bi - h, K, law)[0]) / (2 * h)
    np.testing.assert_allclose(onset(Bi, K, law)[1], fd, rtol=1e-5)


def fd_tangent(delta, d_old, law, h=1e-9):
    D = np.zeros((3, 3))
    for j in range(3):
        e = np.zeros(3)
        e[j] = h
        tp, _, _ = point_response((delta + e)[None], N3[None], d_old, K, law, tangent=False)
        tm, _, _ = point_response((delta - e)[None], N3[None], d_old, K, law, tangent=False)
        D[:, j] = (tp[0] - tm[0]) / (2 * h)
    return D


@pytest.mark.parametrize("name", list(LAWS))
def test_tangent_against_finite_differences(name):
    """dt/dδ on loading (elastic), softening (pure I, pure II, mixed), unloading, reloading and
    under compression with shear, against central differences."""
    law = LAWS[name]
    l0_I = law.sigma_max / K
    l0_II = law.tau_max / K
    states = {
        "elastic": (np.array([0.1, -0.2, 0.4]) * l0_I, 0.0),
        "softening_I": (np.array([0.0, 0.0, 1.7]) * l0_I, 0.0),
        "softening_II": (np.array([1.5, -0.9, -0.02]) * l0_II, 0.0),  # (δ_n = 0 is a kink)
        "softening_mixed": (np.array([0.8, 0.5, 1.1]) * l0_I, 0.0),
        "softening_mixed_2": (np.array([2.1, 0.5, 0.7]) * l0_I, 0.0),
        "unloading": (np.array([0.3, 0.2, 0.9]) * l0_I, 0.6),
        "reloading": (np.array([0.9, 0.6, 2.0]) * l0_I, 0.3),
        "compression_shear": (np.array([1.6, 0.3, -0.5]) * l0_II, 0.0),
        "compression_damaged": (np.array([0.2, 0.1, -0.5]) * l0_II, 0.7),
    }
    for key, (delta, dold) in states.items():
        d_old = np.array([dold])
        t, d, D = point_response(delta[None], N3[None], d_old, K, law)
        if key.startswith("softening") or key == "reloading" or key == "compression_shear":
            assert d[0] > dold, key  # the state is really on the damage branch
        if key in ("unloading", "compression_damaged"):
            assert d[0] == dold, key
        fd = fd_tangent(delta, d_old, law, h=1e-7 * np.linalg.norm(delta))
        np.testing.assert_allclose(D[0], fd, rtol=2e-5, atol=2e-5 * np.abs(fd).max(), err_msg=f"{name} {key}")


def test_irreversible_and_compression():
    """Unloading keeps the damage (secant path to the origin), a changing mode ratio never
    reduces it, and compression neither damages nor softens the normal stiffness."""
    law = LAWS["thesis"]
    l0 = law.sigma_max / K
    t, d, _ = point_response(np.array([[0.0, 0.0, 2.0 * l0]]), N3[None], np.zeros(1), K, law)
    assert 0 < d[0] < 1
    t2, d2, _ = point_response(np.array([[0.0, 0.0, 1.0 * l0]]), N3[None], d, K, law)
    assert d2[0] == d[0] and t2[0, 2] == pytest.approx(0.5 * t[0, 2])
    # same λ, now shear dominated (B changes): the trial damage is lower, the damage stays
    t3, d3, _ = point_response(np.array([[1.99 * l0, 0.0, 0.2 * l0]]), N3[None], d, K, law)
    assert d3[0] >= d[0]
    # pure compression: no damage, full penalty, no interpenetration beyond the penalty
    t4, d4, D4 = point_response(np.array([[0.0, 0.0, -50 * l0]]), N3[None], np.zeros(1), K, law)
    assert d4[0] == 0 and t4[0, 2] == pytest.approx(-50 * l0 * K) and D4[0, 2, 2] == K
    # fully damaged point under compression still carries the normal penalty
    t5, _, _ = point_response(np.array([[3 * l0, 0.0, -l0]]), N3[None], np.ones(1), K, law)
    assert t5[0, 2] == pytest.approx(-K * l0) and t5[0, 0] == 0.0


def test_damage_trial_monotone_in_lambda():
    law = LAWS["thesis"]
    lam = np.linspace(0, 0.5, 2001)  # λf = 0.3 (mode I) and 0.4 (mode II)
    for B in (0.0, 0.3, 1.0):
        d, _, _ = damage_trial(lam, np.full_like(lam, B), K, law)
        assert np.all(np.diff(d) >= -1e-15) and d[0] == 0 and d[-1] == 1.0
