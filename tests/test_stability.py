"""Stability of the equilibrium path from the inertia of the tangent (src/layershell/stability.py).

References: the buckling loads of a cantilever column, Euler's P_k = (2k − 1)² π² EI / (4 L²)
with Engesser's shear correction, and
the analytic path of the softening strip of tests/test_path_following.py (a limit point at
λ = 1, one negative eigenvalue beyond it)."""
from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from helpers import EXAMPLES
from layershell.io.build import build, parse
from layershell.runner import StabilityWarning, run
from layershell.stability import StabilityWatch
from test_path_following import _strip

E, L, B, T = 1000.0, 100.0, 10.0, 1.0  # N, mm: examples/column_buckling.toml
P_EULER = math.pi**2 * E * B * T**3 / 12 / (4 * L**2)  # first buckling load of the cantilever (λ = 1)


def column_text(nx: int, steps: str) -> str:
    """examples/column_buckling.toml (the perfect column: the axial edge load uniform through the
    thickness, so that no moment acts and it stays straight) with ``nx`` elements and the
    [steps] given (λ = 1: Euler's first load)."""
    text = (EXAMPLES / "column_buckling.toml").read_text()
    for a, b in (("nx = 8\n", f"nx = {nx}\n"), ("[steps]\nn = 10\nlambda_end = 10.0\n", f"[steps]\n{steps}\n")):
        assert a in text
        text = text.replace(a, b)
    return text


def column(nx: int, steps: str) -> dict:
    """The summary of the perfect column run to the load factors of ``steps``."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = run(build(parse(column_text(nx, steps))), None, write_vtu=False)
    assert r.converged, r.message
    return r.summary


def test_example_matches_its_data():
    """The example's load is Euler's P_E spread over the end section (λ = 1)."""
    assert f"distribution = {P_EULER / (B * T)!r}" in (EXAMPLES / "column_buckling.toml").read_text()


def test_watch_classifies_changes_of_the_count():
    """Pure logic: a growing count without a turn of λ is a bifurcation (at once under load
    control, one state later under arc length); with λ turning within one increment a limit
    point; a falling count without a turn restabilises; a change that the path's end leaves
    open is undecided; a negative eigenvalue at the first state is an unstable start."""
    w = StabilityWatch(monotone=True)
    assert w.add(0, 0.0, 0) == [] and w.add(1, 0.5, 0) == []
    ev = w.add(2, 1.0, 1)
    assert [e.kind for e in ev] == ["bifurcation"] and ev[0].warns
    assert (ev[0].load_factor_before, ev[0].load_factor, ev[0].negative_eigenvalues) == (0.5, 1.0, 1)
    assert w.finish() == []

    arc = StabilityWatch()
    lams, counts = [0.0, 0.4, 0.8, 0.9, 0.7, 0.5, 0.6, 0.9], [0, 0, 0, 1, 1, 1, 0, 0]
    kinds = [e.kind for i, (lam, n) in enumerate(zip(lams, counts)) for e in arc.add(i, lam, n)] + \
        [e.kind for e in arc.finish()]
    assert kinds == ["limit point", "limit point"]  # the maximum at 0.9, the minimum at 0.5

    arc = StabilityWatch()
    got = [e for i, (lam, n) in enumerate(zip([0.0, 0.5, 1.0, 1.5, 2.0, 2.5], [0, 0, 1, 1, 0, 0])) for e in arc.add(i, lam, n)]
    assert [e.kind for e in got] == ["bifurcation", "restabilised"]  # decided one state later
    assert not got[1].warns

    arc = StabilityWatch()
    assert [e.kind for i, (lam, n) in enumerate(zip([0.0, 0.5, 1.0], [0, 0, 1])) for e in arc.add(i, lam, n)] == []
    assert [e.kind for e in arc.finish()] == ["undecided"]

    assert [e.kind for e in StabilityWatch().add(1, 0.2, 2)] == ["unstable"]
    unknown = StabilityWatch(monotone=True)  # unknown counts (None) are skipped, their λ kept
    assert [e.kind for i, (lam, n) in enumerate(zip([0.0, 0.5, 1.0], [0, None, 1]))
            for e in unknown.add(i, lam, n)] == ["bifurcation"]


@pytest.mark.parametrize("df", [0.03, 0.006])
def test_softening_strip_has_one_negative_eigenvalue_past_its_limit_point(df):
    """The strip with a softening spring traced by arc length (without and with snap-back): the
    tangent at every converged state before the peak is positive definite, at every state past it
    has exactly one negative eigenvalue (the spring's softening slope), and the change is a limit
    point, not a bifurcation."""
    from layershell.solver.arclength import PathSettings, path_steps

    spec, pb, spring, _ = _strip(df)
    ps = PathSettings(control="arc_length", lambda_end=2.0, increment=0.1, max_steps=400, dissipation=df < 0.01)
    states = [(0, 0.0, 0.0)]  # (step, λ, spring separation) of the converged states
    counts = []  # the inertia of each state, from the next increment's first solve
    for st in path_steps(pb, spec.newton, ps, on_step_end=lambda p, u, lam: spring.commit(u)):
        counts.append(st.negative_eigenvalues_start)
        states.append((st.step, float(st.load_factor), float(spring.w @ st.u[spring.dofs[0]])))
    states = states[:len(counts)]
    D0 = 1e-3  # the separation at the peak (test_path_following.D0)
    assert all(n == (1 if d > D0 * (1 + 1e-9) else 0) for (_, _, d), n in zip(states, counts) if d < D0 * (1 - 1e-9)
               or d > D0 * (1 + 1e-9)), list(zip(states, counts))
    assert 0 in counts and 1 in counts
    w = StabilityWatch()
    events = [e for (step, lam, _), n in zip(states, counts) for e in w.add(step, lam, n)] + w.finish()
    assert [e.kind for e in events] == ["limit point"]
    assert events[0].load_factor_before <= 1.0 + 1e-9 and not events[0].warns


def timoshenko(k: int) -> float:
    """The k-th buckling load of the cantilever with shear deformation (Engesser), as a load factor
    on Euler's first: P_E,k / (1 + P_E,k / (κ G A)), κ = 5/6, G = E/2 (ν = 0)."""
    pe = (2 * k - 1) ** 2 * P_EULER
    return pe / (1 + pe / (5 / 6 * E / 2 * B * T)) / P_EULER


def test_perfect_column_under_load_control_locates_its_buckling_loads_on_three_meshes():
    """The perfect cantilever column loaded in 10 steps to 10 × Euler's load by load control
    stays straight (its lateral deflection is round-off), but the run reports two bifurcations,
    each a StabilityWarning, and bisects each between the states that bracket it to 10⁻⁴ of λ.
    Against Engesser's buckling loads with shear (Euler's: 1 and 9): the first within 2·10⁻⁴
    on 4, 8 and 16 elements (measured 0.99997, 0.99991, 0.99991 against 0.99995), the second
    converging with the mesh (9.0378, 8.9963, 8.9934: differences falling 14-fold, order 3.8)
    to within 10⁻³ of 8.9960."""
    second = []
    for nx in (4, 8, 16):
        s = column(nx, "n = 10\nlambda_end = 10.0")
        ev = s["stability"]
        assert [e["kind"] for e in ev] == ["bifurcation", "bifurcation"], ev
        assert [e["negative_eigenvalues"] for e in ev] == [1, 2]
        for e in ev:
            lo, hi = e["located"]
            assert e["load_factor_before"] <= lo < hi <= e["load_factor"]
            assert hi - lo <= 2e-4 * hi
        first = sum(ev[0]["located"]) / 2
        assert first == pytest.approx(timoshenko(1), rel=2e-4), (nx, first)
        second.append(sum(ev[1]["located"]) / 2)
        assert sum("bifurcation point" in m and "bisection locates" in m for m in s["warnings"]) == 2
        assert abs(s["probes"]["w_tip"]) < 1e-9 * L  # it stays straight
        assert all("negative_eigenvalues_at_start" in r for r in s["steps"])
    assert second[-1] == pytest.approx(timoshenko(2), rel=1e-3), second
    assert abs(second[2] - second[1]) < abs(second[1] - second[0]) / 5, second


def test_arc_length_through_a_bifurcation_warns_it():
    """Arc length follows the perfect column's straight path through its bifurcation (λ keeps
    growing): the count grows without a limit point, so it is a bifurcation (warned), decided
    one increment later."""
    s = column(8, 'control = "arc_length"\nlambda_end = 1.5\nn = 10\ndissipation = false')
    ev = s["stability"]
    assert [e["kind"] for e in ev] == ["bifurcation"], ev
    assert ev[0]["load_factor_before"] < 1.0 < ev[0]["load_factor"]
    assert any("bifurcation point" in m for m in s["warnings"])


def test_stable_run_reports_no_event():
    """Below the buckling load every state is stable: no event, no stability warning, and the
    final state's count (one factorisation at the end) is zero."""
    s = column(4, "n = 4\nlambda_end = 0.9")
    assert "stability" not in s
    assert not any("bifurcation" in m for m in s.get("warnings", []))
    assert [r["negative_eigenvalues_at_start"] for r in s["steps"]] == [0, 0, 0, 0]


def test_stability_warning_category():
    """The bifurcation is a StabilityWarning on the console (filterable by category)."""
    text = column_text(2, "factors = [0.5, 1.5]")
    with pytest.warns(StabilityWarning, match="bifurcation point"):
        run(build(parse(text)), None, write_vtu=False)


def test_restart_neither_repeats_nor_loses_an_event(tmp_path):
    """Interrupted after step 3 (its first bifurcation recorded) and restarted from the
    checkpoint: the same two located events as the uninterrupted run, none twice."""
    spec = build(parse(column_text(4, "n = 10\nlambda_end = 10.0")))

    def stop_after_3(step, n, lam):
        if step == 3:
            raise KeyboardInterrupt

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = run(spec, tmp_path / "whole", write_vtu=False).summary["stability"]
        part = run(spec, tmp_path / "part", progress=stop_after_3, write_vtu=False)
        assert part.interrupted and [e["step"] for e in part.summary["stability"]] == [1]
        again = run(spec, tmp_path / "part", restart=tmp_path / "part", write_vtu=False).summary["stability"]
    assert [(e["kind"], e["step"], e["located"]) for e in again] == [(e["kind"], e["step"], e["located"]) for e in whole]


def elastica_deflection(ratio: float) -> float:
    """The lateral tip deflection of the inextensible cantilever elastica at P = ratio × P_E
    (Timoshenko & Gere §2.7): P / P_E = (2 K(k) / π)², δ / L = 2 k / K(k), K the complete
    elliptic integral of the first kind of modulus k = sin(α/2), α the tip rotation."""
    from scipy.optimize import brentq
    from scipy.special import ellipk

    K = math.pi / 2 * math.sqrt(ratio)
    m = brentq(lambda m: ellipk(m) - K, 0.0, 1.0 - 1e-12)  # scipy's ellipk takes m = k²
    return 2 * math.sqrt(m) / K * L


def imperfect_column(nx: int, factors, eps: float = 1e-4, steps: str = "", converged: bool = True):
    """The column with a lateral tip load eps × P_E (the imperfection) at the load factors given
    (``steps``: more [steps] settings); its summary, or (with ``converged=False``) the RunResult."""
    text = column_text(nx, "factors = [" + ", ".join(f"{f:.4f}" for f in factors) + "]" + steps)
    text += f"""
[[loads]]
type = "edge"
where = "near(x, {L})"
direction = [0, 0, 1]
distribution = {eps * P_EULER / (B * T)!r}
"""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = run(build(parse(text)), None, write_vtu=False)
    if not converged:
        return r
    assert r.converged, r.message
    return r.summary


def test_imperfect_column_follows_the_stable_elastica_on_three_meshes():
    """With a lateral tip load of 10⁻⁴ P_E and load steps of 0.01 past the buckling load, the
    column takes the buckled branch: every state is stable (no negative eigenvalue, no
    stability event), and the tip deflection at 1.1, 1.2 and 1.5 P_E (where it is 79 % of the
    length) converges with the mesh to within 1 % of the elastica: measured −1.9 / −0.9 / +0.1 %
    on 4 elements, +0.4 / +0.5 / +0.7 % on 8 and +0.5 / +0.5 / +0.7 % on 16 (the imperfection,
    shear and the axis's shortening, which the inextensible elastica lacks)."""
    factors = np.r_[np.arange(0.1, 0.951, 0.05), np.arange(0.96, 1.2001, 0.01), 1.3, 1.4, 1.5]
    at = (1.1, 1.2, 1.5)
    ratios = []
    for nx in (4, 8, 16):
        s = imperfect_column(nx, factors)
        assert "stability" not in s, s["stability"]
        assert all(r["negative_eigenvalues_at_start"] == 0 for r in s["steps"])
        w = {round(r["load_factor"], 4): r["probes"]["w_tip"] for r in s["steps"]}
        ratios.append(np.array([w[lam] / elastica_deflection(lam) for lam in at]))
    assert np.all(np.abs(ratios[0] - 1) < 0.02), ratios
    assert np.all(np.abs(ratios[1] - 1) < 0.01) and np.all(np.abs(ratios[2] - 1) < 0.01), ratios
    assert np.all(np.abs(ratios[2] - ratios[1]) < np.abs(ratios[1] - ratios[0])), ratios


def test_load_step_across_the_buckling_load_of_an_imperfect_column_is_warned():
    """The column with a smaller imperfection (10⁻⁵ P_E) and one load step from 0.99 to 1.01 P_E
    (with 10⁻⁴ P_E the same steps find the buckled branch): Newton converges on
    the unstable branch that deflects against the imperfection (w_tip −0.08 mm, against +18 mm
    on the elastica) and stays there to 1.5 P_E. Each of these states has one negative eigenvalue:
    the run warns that the equilibria are unstable (the located bracket is missing where the
    bisection's first midpoint, near the buckling load, does not converge)."""
    s = imperfect_column(8, [0.5, 0.9, 0.99, 1.01, 1.1, 1.5], eps=1e-5)
    ev = s["stability"]
    assert [e["kind"] for e in ev] == ["bifurcation"], ev
    assert (ev[0]["load_factor_before"], ev[0]["load_factor"]) == (0.99, 1.01)
    assert [r["negative_eigenvalues_at_start"] for r in s["steps"]] == [0, 0, 0, 0, 1, 1]
    assert all(r["probes"]["w_tip"] < 0 for r in s["steps"][3:])
    assert "located" not in ev[0]
    assert any("unstable" in m and "jumped onto an unstable branch" in m for m in s["warnings"])


def test_a_run_that_stops_on_an_unstable_state_says_so():
    """Load control that fails from an unstable equilibrium (the imperfect column on its unstable
    branch at 1.01 P_E, the next step to 5 P_E given 8 iterations and no bisection): the stop's
    message names the negative eigenvalue of the tangent at the last converged state."""
    r = imperfect_column(8, [0.5, 0.9, 0.99, 1.01, 5.0], eps=1e-5,
                         steps="\nmax_iterations = 8\nmax_bisections = 0", converged=False)
    assert not r.converged and r.summary["steps"][-1]["load_factor"] == pytest.approx(1.01)
    assert "the tangent at the last converged state (load factor 1.01) has 1 negative eigenvalue(s)" in r.message
    assert [e["kind"] for e in r.summary["stability"]] == ["bifurcation"]


def test_buckling_modes_are_written_and_match_the_euler_shapes(tmp_path):
    """With a results folder each located bifurcation's mode (the tangent's eigenvector nearest
    zero just below it) is written as buckling_mode_<step>.vtu and named in the event and the
    warning. On 8 elements the lateral deflection along the column matches the cantilever's
    Euler modes 1 − cos((2k − 1) π x / 2L) (shear does not change the shape of a uniform column):
    MAC above 0.9999 for both."""
    import meshio

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        s = run(build(parse(column_text(8, "n = 10\nlambda_end = 10.0"))), tmp_path, write_vtu=False).summary
    files = [e["mode_file"] for e in s["stability"]]
    assert files == ["buckling_mode_0001.vtu", "buckling_mode_0009.vtu"]
    assert sum(f"its mode: {f}" in m for f in files for m in s["warnings"]) == 2
    for k, f in enumerate(files, start=1):
        m = meshio.read(tmp_path / f)
        x = m.points[:, 0]
        w = m.point_data["displacement"][:, 2]
        exact = 1 - np.cos((2 * k - 1) * np.pi * x / (2 * L))
        mac = (w @ exact) ** 2 / ((w @ w) * (exact @ exact))
        assert mac > 0.9999, (k, mac)
        assert np.abs(m.point_data["displacement"]).max() == pytest.approx(1.0)
    assert set(files) <= set((tmp_path / ".layershell-files").read_text().split())
