"""The concrete law's increment stiffness (layershell.laws.concrete.INCREMENT_STIFFNESS): the stress
k d_n C0 (ε − ε_n) on the strain change since the commit; its tangent against finite differences,
its energy error on a softening path against the step count, and that it leaves undamaged points
and the fracture energy alone."""
import numpy as np
import pytest
from test_laws_concrete import C30, NZ, _strains, trapezoid

from layershell.laws import concrete


def test_tangent_of_the_increment_stiffness_against_central_differences():
    """The tangent's added part k d_n C0 against central differences of the added stress, with and
    without IMPL-EX; where the committed state is damaged the factor is k max(d⁺, d⁻) > 0."""
    law, n = C30, 200
    rng = np.random.default_rng(7)
    eps = _strains(rng, n, "none")
    eps_n = eps * rng.uniform(0.3, 1.6, (n, 1))
    _, _, committed = law.response(eps_n, law.state(n), 80.0, 20.0, NZ, False)
    _, k = law.increment_stress(np.zeros((n, 6)), committed)
    assert np.sum(k > 0) > n // 4 and np.all(k <= concrete.INCREMENT_STIFFNESS)
    for implex in (None, committed):
        s0, D0, _ = law.response(eps, committed, 80.0, 20.0, NZ, implex=implex)
        s1, D1, _ = law.response(eps, committed, 80.0, 20.0, NZ, implex=implex, strain_n=eps_n)
        added, _ = law.increment_stress(eps - eps_n, committed)
        np.testing.assert_array_equal(s1, s0 + added)
        fd = np.empty((n, 6, 6))
        for b in range(6):
            ep, em = eps.copy(), eps.copy()
            ep[:, b] += 1e-7
            em[:, b] -= 1e-7
            fd[:, :, b] = (law.increment_stress(ep - eps_n, committed)[0]
                           - law.increment_stress(em - eps_n, committed)[0]) / 2e-7
        err = np.linalg.norm((D1 - D0) - fd, axis=(1, 2)) / np.maximum(np.linalg.norm(fd, axis=(1, 2)), 1e-300)
        assert np.all(err[k > 0] < 1e-6), err.max()
        np.testing.assert_array_equal((D1 - D0)[k == 0], 0.0)


def test_undamaged_points_keep_their_stress_exactly():
    law = C30
    eps = np.array([[0.5, -0.1, -0.1, 0.2, 0.0, 0.1]]) * law.f_ct / law.E
    st = law.state(1)
    s0, D0, _ = law.response(eps, st, 50.0, 10.0, NZ)
    s1, D1, _ = law.response(eps, st, 50.0, 10.0, NZ, strain_n=np.zeros((1, 6)))
    np.testing.assert_array_equal(s0, s1)
    np.testing.assert_array_equal(D0, D1)


def softening_work(law, h, steps, increment=True):
    """Work per volume of a uniaxial stress path along x through complete softening (to 40 times
    the cracking strain over the band h) in ``steps`` equal increments, each with the increment
    stiffness on its strain change (``increment``); and the law's dissipation at the end."""
    e0 = law.f_ct / law.E
    ex = np.linspace(0.0, e0 * (1 + 40 * law.G_F * law.E / (h * law.f_ct ** 2)), steps + 1)
    eps = np.stack([ex, -law.nu * ex, -law.nu * ex, 0 * ex, 0 * ex, 0 * ex], -1)
    st, sig = law.state(1), [0.0]
    for a, b in zip(eps[:-1], eps[1:]):
        s, _, st = law.response(b[None], st, h, h, NZ, False, strain_n=a[None] if increment else None)
        sig.append(s[0, 0])
    return trapezoid(np.array(sig), ex), law.dissipation(st)[0]


@pytest.mark.parametrize("h", [10.0, 50.0, 150.0])
def test_fracture_energy_with_the_increment_stiffness_and_its_error_against_the_steps(h):
    """Uniaxial tension with the increment stiffness on every step: the work it adds, k d E Δε per
    step, halves as the steps halve (first order), and the work extrapolated to vanishing steps,
    2 W(2m) − W(m), is G_F per crack area within 1 % for three bands."""
    law = C30
    work = {m: softening_work(law, h, m) for m in (1000, 2000, 4000)}
    np.testing.assert_allclose(work[4000][1] * h, law.G_F, rtol=0.01)  # the law's own dissipation
    extra = {m: (w[0] - softening_work(law, h, m, False)[0]) * h / law.G_F for m, w in work.items()}
    assert 0 < extra[1000] < 100 * concrete.INCREMENT_STIFFNESS
    assert extra[2000] / extra[1000] == pytest.approx(0.5, rel=0.02)
    assert extra[4000] / extra[2000] == pytest.approx(0.5, rel=0.02)
    np.testing.assert_allclose((2 * work[4000][0] - work[2000][0]) * h, law.G_F, rtol=0.01)
