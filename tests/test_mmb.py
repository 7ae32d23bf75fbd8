"""Mixed-mode bending (MMB, examples/mmb_cohesive.toml) traced by arc length against the beam
theory of Reeder & Crews (1990) with the crack-length corrections of Williams (1989) and Wang &
Williams (1992), and the Benzeggagh–Kenane fracture energy at its mode ratio (issue 13).

The two forces of the MMB lever in a fixed ratio, F_end = 300 λ (upper arm's end pulled up) and
F_mid = 660 λ (upper arm pushed down at mid-span), on a specimen resting on supports at both ends
of the lower arm, are the DCB's opening pair P_I = F_end − F_mid/4 plus the ENF's load
P_II = F_mid. By beam theory the two are energy-orthogonal (equal arms: one antisymmetric, one
symmetric about the crack plane), so the work of the two forces is λ D with

    D = F_end w_end − F_mid w_mid (per λ = 1 forces),   D / λ = C(a) = p_I² C_DCB(a) + p_II² C_ENF(a),
    G_T / λ² = g_I(a) + g_II(a),  g_I = 12 p_I² (a + χh)² / (E11 b² h³),
    g_II = 9 p_II² (a + 0.42 χh)² / (16 E11 b² h³),

p_I = 300 − 660/4 = 135 N, p_II = 660 N. The crack grows where G_T = G_c(B), B = g_II/(g_I + g_II)
(0.497-0.505 for a = 35-50 mm)."""
import numpy as np
import pytest
from scipy.optimize import brentq

from helpers import run_example
from test_dcb import cbt_compliance as dcb_compliance
from test_enf import B_W, E11, H, bk, chi, enf_compliance

A0, L_HALF = 35.0, 50.0
F_END, F_MID = 300.0, 660.0  # forces at λ = 1 (examples/mmb_cohesive.toml)
P_I, P_II = F_END - F_MID / 4, F_MID


def mmb_compliance(a):
    """D / λ of the MMB forces at crack length ``a`` (< L); the DCB pair's opening per force by
    corrected beam theory (Williams 1989; the DCB's arms and material are the MMB's)."""
    return P_I**2 * dcb_compliance(a) + P_II**2 * enf_compliance(a)


def mmb_split(a):
    """(G_I, G_II) per λ² at crack length ``a``."""
    gI = 12 * P_I**2 * (a + chi() * H) ** 2 / (B_W**2 * H**3 * E11)
    gII = 9 * P_II**2 * (a + 0.42 * chi() * H) ** 2 / (16 * B_W**2 * H**3 * E11)
    return gI, gII


def mmb_load_factor(a):
    """λ at which G_T reaches the Benzeggagh–Kenane G_c of the mode ratio at ``a``."""
    gI, gII = mmb_split(a)
    return float(np.sqrt(bk(gII / (gI + gII)) / (gI + gII)))


def crack_from_compliance(C):
    """The crack length whose beam-theory compliance is C (NaN beyond the load point)."""
    if C >= mmb_compliance(L_HALF - 1e-6):
        return float("nan")
    return brentq(lambda a: mmb_compliance(a) - C, 1.0, L_HALF - 1e-6)


def test_mode_ratio_of_the_example_is_one_half():
    """The force ratio of the example gives G_II/G_T = 0.50 ± 0.01 over the crack lengths the
    branch covers (the beam theory above, independent of the FE model)."""
    for a in (35.0, 40.0, 45.0, 49.0):
        gI, gII = mmb_split(a)
        assert gII / (gI + gII) == pytest.approx(0.5, abs=0.01)


def mmb_path(replace=None):
    r = run_example("mmb_cohesive", replace)
    steps = r.summary["steps"]
    lam = np.array([s["load_factor"] for s in steps])
    D = np.array([F_END * s["probes"]["w_end"] - F_MID * s["probes"]["w_mid"] for s in steps])
    e = [s["energy"] for s in steps]
    dissipated = np.array([x["external_work"] - x["strain_energy"] - x["interface_elastic_energy"] for x in e])
    a = np.array([crack_from_compliance(Dk / lk) for Dk, lk in zip(D, lam)])
    return r.summary, lam, D, a, dissipated


@pytest.fixture(scope="module")
def mmb_100():
    return mmb_path()


@pytest.mark.slow
def test_mmb_by_arc_length_follows_beam_theory(mmb_100):
    """The force-loaded MMB on 100 elements (189 increments, 103 s on 2 cores; on 29 Nov 2026
    214 on one thread, 179 on two: the route past the load point follows round-off) by arc length, through the peak along the
    propagation branch (force control ends at the peak; under displacement control at both load
    points the earlier runs stopped after 3-5 mm of growth):

    * initial compliance (λ = 0.05, elastic) within 1 % of beam theory (measured −0.06 %);
    * every state past the peak with the crack (from its compliance) short of 48.5 mm - where
      the load point's neighbourhood begins - lies within −2 … +4 % of the beam-theory load at
      its crack length (measured +0.4 … +3.3 %; the DCB and ENF branches of the same arms lie
      +0.4 … +3.0 % and +0.6 … +2.1 % above their beam theory on comparable meshes), and the
      crack grows by more than 10 mm;
    * the energy the structure loses from the peak on, external work − stored energy (independent
      of the interface ledger), per compliance crack growth is 1.00-1.08 × G_c(0.5) b (measured
      1.031-1.051; 1.054-1.060 without the energy step control, 1.036-1.054 with 23 times as many
      increments as that): the front
      dissipates about 5 % more than the Benzeggagh–Kenane energy of the mode ratio beam theory
      assigns - consistent with the load 2-3 % above beam theory (G ∝ P²). Each point of the
      front turns from nearly pure shear at its onset (B ≈ 0.95) to nearly pure opening as it
      fails (B ≈ 0.2), a path along which the law's dissipation is not G_c of one mode ratio."""
    s, lam, D, a, dissipated = mmb_100
    assert s["converged"]
    assert D[0] / lam[0] == pytest.approx(mmb_compliance(A0), rel=0.01)
    peak = int(np.argmax(np.where(np.isfinite(a), lam, -np.inf)))  # the peak before the crack nears the load point
    branch = (np.arange(lam.size) > peak) & np.isfinite(a) & (a < 48.5)
    assert branch.sum() >= 10 and a[branch].max() - A0 > 10.0
    ratio = lam[branch] / np.array([mmb_load_factor(x) for x in a[branch]])
    assert np.all((ratio > 0.98) & (ratio < 1.04)), ratio
    per_area = (dissipated[branch] - dissipated[peak]) / (bk(0.5) * B_W * (a[branch] - a[peak]))
    assert np.all((per_area > 1.0) & (per_area < 1.08)), per_area
    # the arc length's energy-error step control keeps the balance within 1 % (measured 0.64 %)
    assert max(abs(st["energy"]["balance_error"]) for st in s["steps"]) < 0.01
    assert not any("energy balance is off" in w for w in s["warnings"]) and "energy_balance_warned" not in s


@pytest.mark.slow
def test_without_the_energy_step_control_the_mmb_ledger_misses_more_than_one_percent(mmb_100):
    """The same run with [steps] energy_tolerance = 0 (the step control off; 54 increments instead
    of 189, 27 s): the interface ledger, which follows each front point along the straight
    separation path between converged states, books too little where the points turn from shear
    to opening within an increment - the balance error reaches 3.3 % and the run warns once.
    The loads along the branch stay within the same bounds: the control changes the sampling of
    the path and the ledger's accuracy, not the answer."""
    s, lam, D, a, dissipated = mmb_path({"max_steps = 400": "max_steps = 400\nenergy_tolerance = 0"})
    assert s["converged"] and len(s["steps"]) < len(mmb_100[0]["steps"]) / 2
    assert max(abs(st["energy"]["balance_error"]) for st in s["steps"]) > 0.02
    assert sum("energy balance is off" in w for w in s["warnings"]) == 1 and s["energy_balance_warned"] > 1
    peak = int(np.argmax(np.where(np.isfinite(a), lam, -np.inf)))
    branch = (np.arange(lam.size) > peak) & np.isfinite(a) & (a < 48.5)
    ratio = lam[branch] / np.array([mmb_load_factor(x) for x in a[branch]])
    assert np.all((ratio > 0.98) & (ratio < 1.04)), ratio


def test_an_energy_balance_off_by_more_than_one_percent_is_warned_once():
    """runner._balance: no warning before energy is dissipated or within 1 %; the first step
    beyond 1 % warns (console, summary.json 'warnings', 'energy_balance_warned'), later ones not."""
    from layershell.runner import CohesiveWarning, _balance

    summary, lines = {}, []
    quiet = {"balance_error": 0.5, "dissipated_fracture": 0.0, "dissipated_friction": 0.0, "dissipated_viscous": 0.0}
    _balance(summary, quiet, 1, lines.append)  # nothing dissipated yet: the work is too small to judge
    _balance(summary, {**quiet, "balance_error": 0.009, "dissipated_fracture": 1.0}, 2, lines.append)
    assert "warnings" not in summary and not lines
    with pytest.warns(CohesiveWarning, match="step 3: the energy balance is off by -2.00%"):
        _balance(summary, {**quiet, "balance_error": -0.02, "dissipated_fracture": 1.0}, 3, lines.append)
    _balance(summary, {**quiet, "balance_error": 0.05, "dissipated_fracture": 2.0}, 4, lines.append)
    assert len(summary["warnings"]) == 1 and summary["energy_balance_warned"] == 3 and len(lines) == 1


@pytest.mark.slow
def test_mmb_on_three_meshes(mmb_100):
    """The MMB on 100, 150 and 200 elements (node spacings 0.5, 0.33, 0.25 mm; 189 / 160 / 128
    increments): every run passes the peak and reaches its end (λ = 1, the crack past the load
    point), each branch lies within −2 … +4 % of beam theory (measured +0.4 … +3.3, +0.9 … +3.2,
    +1.9 … +2.8 %) and their medians agree within 0.5 % (measured 1.0254, 1.0272, 1.0233), the
    energy lost per crack growth is 1.00-1.08 G_c(0.5) b on each (1.031-1.051, 1.046-1.054,
    1.047-1.053), and the energy balance stays within 1 % on each (0.64, 0.71, 0.71 %; without
    the energy step control 3.3, 2.2, 1.7 %)."""
    medians, balances = [], []
    for nx, run in ((100, mmb_100), (150, None), (200, None)):
        s, lam, D, a, dissipated = run if run is not None else mmb_path({"nx = 100": f"nx = {nx}"})
        assert s["converged"] and s["path_end"] == "lambda_end"
        peak = int(np.argmax(np.where(np.isfinite(a), lam, -np.inf)))
        branch = (np.arange(lam.size) > peak) & np.isfinite(a) & (a < 48.5)
        assert branch.sum() >= 10 and a[branch].max() - A0 > 10.0
        ratio = lam[branch] / np.array([mmb_load_factor(x) for x in a[branch]])
        assert np.all((ratio > 0.98) & (ratio < 1.04)), (nx, ratio)
        per_area = (dissipated[branch] - dissipated[peak]) / (bk(0.5) * B_W * (a[branch] - a[peak]))
        assert np.all((per_area > 1.0) & (per_area < 1.08)), (nx, per_area)
        medians.append(float(np.median(ratio)))
        balances.append(max(abs(st["energy"]["balance_error"]) for st in s["steps"]))
    assert max(medians) - min(medians) < 0.005, medians
    assert max(balances) < 0.01, balances


def _branch_ratio(lam, a):
    """Load factor over beam theory's at the compliance crack length, past the peak, a < 48.5 mm."""
    peak = int(np.argmax(np.where(np.isfinite(a), lam, -np.inf)))
    branch = (np.arange(lam.size) > peak) & np.isfinite(a) & (a < 48.5)
    return lam[branch] / np.array([mmb_load_factor(x) for x in a[branch]])


@pytest.mark.slow
def test_mmb_keeps_the_full_element_because_mitc9_lies_further_above_beam_theory(mmb_100):
    """Why examples/mmb_cohesive.toml sets element = "full": with MITC9 (100 elements) the run
    passes the peak and reaches its end as well, but its branch lies up to +4.1 % above beam
    theory (full element +0.4 ... +3.3 %), past the +4 % the example is checked to, and its
    median further above than the full element's. About 2 CPU minutes more than the fixture."""
    s, lam, D, a, dissipated = mmb_path({'element = "full"': 'element = "mitc"'})
    assert s["converged"] and s["path_end"] == "lambda_end"
    ratio = _branch_ratio(lam, a)
    assert ratio.size >= 10 and np.all((ratio > 0.98) & (ratio < 1.05)), ratio
    full = _branch_ratio(mmb_100[1], mmb_100[3])
    assert np.median(ratio) > np.median(full)
