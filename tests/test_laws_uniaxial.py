"""Uniaxial laws (layershell.laws.uniaxial): reinforcing steel with kinematic hardening and rupture,
textile rovings; analytic curves, energies, consistent tangents against finite differences."""
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from layershell.laws import SteelLaw, SteelState, TextileLaw
from layershell.material import MaterialError


def drive(law, path, state=None):
    """Commit a strain path (steps, n); stresses (steps, n), tangents (steps, n), final state."""
    state = law.state(path.shape[1]) if state is None else state
    out, tan = [], []
    for eps in path:
        s, Et, state = law.response(eps, state)
        out.append(s)
        tan.append(Et)
    return np.array(out), np.array(tan), state


def trapezoid(y, x):
    return np.sum(0.5 * (y[1:] + y[:-1]) * np.diff(x, axis=0), axis=0)


# -- steel ------------------------------------------------------------------------------------------

def test_b500b_characteristic_curve():
    """EN 1992-1-1 Annex C, B500B: f_yk = 500 MPa, E = 200 GPa, f_t = k f_yk = 540 MPa at eps_uk = 5 %."""
    law = SteelLaw.from_grade("B500B")
    e = np.array([0.001, 0.0025, 0.02, 0.05])[None, :]
    path = np.linspace(0, 1, 400)[:, None] * e
    s, _, _ = drive(law, path)
    hand = np.array([200.0, 500.0, 500.0 + 40.0 * (0.02 - 0.0025) / 0.0475, 540.0])
    np.testing.assert_allclose(s[-1], hand, rtol=1e-9)
    m = SteelLaw.from_grade("B500B", stress_unit=1e-3)  # kN/m²
    assert (m.E, m.f_y) == pytest.approx((2e8, 5e5))


def test_kinematic_hardening_bauschinger_and_closed_loop_energy():
    law = SteelLaw(E=200e3, f_y=500.0, E_h=2000.0)
    H = law.E * law.E_h / (law.E - law.E_h)
    e1 = 0.01
    up = np.linspace(0, e1, 200)
    down = np.linspace(e1, -e1, 400)
    back = np.linspace(-e1, e1, 400)
    path = np.concatenate([up, down[1:], back[1:]])[:, None]
    s, _, state = drive(law, path)
    # back stress after the first loading: α = H ε_p; reverse yield at σ = α - f_y (Bauschinger)
    eps_p1 = (e1 - 500.0 / 200e3) * 200e3 / (200e3 + H)
    alpha1 = H * eps_p1
    i_down = len(up) - 1 + np.arange(len(down))
    sd = s[i_down, 0]
    elastic = sd >= alpha1 - law.f_y + 1e-9
    np.testing.assert_allclose(np.diff(sd[elastic]) / np.diff(path[i_down, 0][elastic]), law.E, rtol=1e-9)
    assert np.min(sd) < alpha1 - law.f_y
    # a closed stabilised cycle: the work ∮σ dε equals the energy dissipated during it
    k0 = len(up) - 1
    _, _, st0 = drive(law, path[:k0 + 1])
    loop = trapezoid(s[k0:, 0], path[k0:, 0])
    assert loop > 0
    assert law.dissipation(state)[0] - law.dissipation(st0)[0] == pytest.approx(loop, rel=2e-3)
    # dissipation = f_y × accumulated plastic strain (hand: three plastic branches)
    assert law.dissipation(state)[0] == pytest.approx(law.f_y * np.sum(np.abs(np.diff(
        np.array([drive(law, path[:k + 1])[2].eps_p[0] for k in (0, k0, k0 + 399, len(path) - 1)])))), rel=1e-9)


def test_rupture_is_continuous_and_permanent():
    law = SteelLaw(E=200e3, f_y=500.0, E_h=1000.0, eps_u=0.05)
    path = np.concatenate([np.linspace(0, 0.06, 1201), np.linspace(0.06, 0.0, 50), np.linspace(0, 0.07, 50)])
    s, _, state = drive(law, path[:, None])
    e = path
    assert np.max(np.abs(np.diff(s[:1201, 0]))) < 0.06 * 540  # no jump (the drop spans 60 steps)
    assert np.all(s[(e > 0.0525 + 1e-12) & (np.arange(len(e)) < 1201), 0] == 0)
    assert np.all(s[1201:, 0] == 0.0)  # broken for good
    f_u = law.f_y + law.E_h * (0.05 - law.f_y / law.E)
    assert s[1000, 0] == pytest.approx(f_u, rel=1e-9)  # intact up to eps_u


# -- textile ----------------------------------------------------------------------------------------

def test_textile_envelope_secant_and_compression():
    law = TextileLaw(E=240e3, f_t=2500.0, softening=0.05)
    e_t = law.f_t / law.E
    s, _, state = drive(law, np.array([[e_t, 1.025 * e_t, 1.05 * e_t, 1.2 * e_t]]) * np.linspace(0, 1, 101)[:, None])
    np.testing.assert_allclose(s[-1], [law.f_t, 0.5 * law.f_t, 0.0, 0.0], atol=1e-9 * law.f_t)
    # unloading/reloading on the secant, nothing in compression
    mid = np.array([1.025 * e_t])
    _, _, st_mid = drive(law, mid[None, :])
    for e in (0.5 * e_t, -e_t):
        sig, Et, _ = law.response(np.array([e]), st_mid)
        secant = 0.5 * law.f_t / mid[0]
        assert sig[0] == pytest.approx(secant * e if e > 0 else 0.0)
        assert Et[0] == pytest.approx(secant if e > 0 else 0.0)
    # total energy: the area under the envelope, ½ f_t e_t (1 + softening)
    path = np.linspace(0, 1.2 * e_t, 4001)[:, None]
    s, _, st_end = drive(law, path)
    assert trapezoid(s[:, 0], path[:, 0]) == pytest.approx(0.5 * law.f_t * e_t * 1.05, rel=1e-5)
    assert law.dissipation(st_end)[0] == pytest.approx(0.5 * law.f_t * e_t * 1.05, rel=1e-12)
    to_mid = np.linspace(0, mid[0], 2001)[:, None]
    s_mid, _, _ = drive(law, to_mid)
    spent = trapezoid(s_mid[:, 0], to_mid[:, 0]) - 0.5 * s_mid[-1, 0] * mid[0]
    assert law.dissipation(st_mid)[0] == pytest.approx(spent, rel=1e-5)


def test_fibre_defaults_and_bad_input():
    c, g = TextileLaw.from_fibre("carbon"), TextileLaw.from_fibre("AR-glass", stress_unit=1e-3)
    assert c.E > 3 * g.E * 1e-3 and g.f_t == pytest.approx(1000.0 / 1e-3)
    with pytest.raises(MaterialError, match="basalt.*carbon, AR-glass"):
        TextileLaw.from_fibre("basalt")
    for field, msg in (("E", "E=0.0 must be positive"), ("f_t", "f_t=0.0 must be positive"),
                       ("softening", "softening=0.0 must be positive")):
        kw = dict(E=1.0, f_t=1.0, softening=0.05)
        kw[field] = 0.0
        with pytest.raises(MaterialError, match=msg):
            TextileLaw(**kw).check()
    with pytest.raises(MaterialError, match="B600.*B500A, B500B, B500C"):
        SteelLaw.from_grade("B600")
    cases = [(dict(E=0.0, f_y=1.0), "E=0.0 must be positive"), (dict(E=1.0, f_y=-1.0), "f_y=-1.0 must be positive"),
             (dict(E=1.0, f_y=0.1, E_h=1.0), "E_h=1.0 must satisfy 0 <= E_h < E"),
             (dict(E=1.0, f_y=0.1, eps_u=0.05), "eps_u=0.05 must exceed the yield strain")]
    for kw, msg in cases:
        with pytest.raises(MaterialError, match=msg):
            SteelLaw(**kw).check()



def test_grade_and_fibre_defaults_take_any_overridden_constant():
    """A grade or fibre gives the defaults; any constant given beside it replaces its default, in
    the model's units. A mean yield strength moves the hardening slope with it: the grade's
    characteristic ratio k = f_t/f_y is kept, E_h = (k - 1) f_y / (eps_u - f_y/E) (EN 1992-1-1 C.1)."""
    s = SteelLaw.from_grade("B500B", stress_unit=1.0, f_y=550.0)
    k, eps_uk = 1.08, 0.05
    assert (s.E, s.f_y, s.eps_u) == (200e3, 550.0, eps_uk)
    assert s.f_y + s.E_h * (s.eps_u - s.f_y / s.E) == pytest.approx(k * 550.0, rel=1e-12)
    assert SteelLaw.from_grade("B500B", E_h=0.0).E_h == 0.0
    t = TextileLaw.from_fibre("AR-glass", stress_unit=1.0, E=76000.0)
    assert (t.E, t.f_t) == (76000.0, 1000.0)
    # the same through a model file's table, in kN and mm
    from layershell.io.build import _law  # noqa: PLC0415
    from layershell.io.schema import SteelMat, TextileMat  # noqa: PLC0415
    law = _law("b", SteelMat(type="steel", grade="B500B", f_y=0.55), "kN, mm")
    glass = _law("g", TextileMat(type="textile", fibre="AR-glass", E=76.0), "kN, mm")
    assert glass.E == 76.0 and glass.f_t == pytest.approx(1.0)
    assert law.f_y == 0.55 and law.E == pytest.approx(200.0)

# -- consistent tangents ----------------------------------------------------------------------------

def _fd_check(law, eps, committed, branch):
    """Relative tangent error where the central-difference stencil stays on one branch (both laws
    are piecewise linear or quadratic in the strain: central differences are exact up to roundoff)."""
    step = 1e-8
    _, Et, _ = law.response(eps, committed)
    fd = (law.response(eps + step, committed)[0] - law.response(eps - step, committed)[0]) / (2 * step)
    same = (branch(eps + step, committed) == branch(eps, committed)) & (branch(eps - step, committed) == branch(eps, committed))
    assert same.mean() > 0.98
    scale = np.maximum(np.abs(fd), 1e-3 * law.E)
    err = np.abs(Et - fd) / scale
    assert np.all(err[same] < 1e-5), np.max(err[same])
    return same


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2 ** 31 - 1))
def test_steel_tangent_against_central_differences(seed):
    rng = np.random.default_rng(seed)
    law, n = SteelLaw(E=200e3, f_y=500.0, E_h=1500.0, eps_u=0.05), 400
    pre = rng.uniform(-0.06, 0.06, n) * rng.choice([0.02, 0.2, 1.0], n)
    _, _, committed = law.response(pre, law.state(n))
    _, _, committed = law.response(-0.3 * pre, committed)
    eps = pre * rng.uniform(-1.5, 1.5, n)

    def branch(e, c):
        s_tr = law.E * (e - c.eps_p) - c.alpha
        return (np.abs(s_tr) > law.f_y) * 1 + (np.abs(e) > c.eps_max) * 2 + (np.abs(e) > law.eps_u) * 4 \
            + (np.abs(e) > 1.05 * law.eps_u) * 8

    _fd_check(law, eps, committed, branch)


@settings(max_examples=30, deadline=None, derandomize=True)
@given(seed=st.integers(0, 2 ** 31 - 1))
def test_textile_tangent_against_central_differences(seed):
    rng = np.random.default_rng(seed)
    law, n = TextileLaw(E=72e3, f_t=1000.0, softening=0.1), 400
    e_t = law.f_t / law.E
    pre = rng.uniform(0, 1.2 * e_t, n)
    _, _, committed = law.response(pre, law.state(n))
    eps = pre * rng.uniform(-0.5, 1.5, n)

    def branch(e, c):
        return (e > 0) * 1 + (e >= c.kappa) * 2 + (e > e_t) * 4 + (e > 1.1 * e_t) * 8

    _fd_check(law, eps, committed, branch)


def test_committed_state_untouched_and_round_trip():
    law = SteelLaw.from_grade("B500C")
    c = law.state(3)
    before = c.to_dict("s.")
    law.response(np.array([0.01, -0.02, 0.1]), c)
    for k, v in c.to_dict("s.").items():
        np.testing.assert_array_equal(v, before[k])
    _, _, t = law.response(np.array([0.01, -0.02, 0.1]), c)
    back = SteelState.from_dict(t.to_dict("s."), "s.")
    np.testing.assert_array_equal(back.eps_p, t.eps_p)
    assert t.take([0, 2]).n == 2
