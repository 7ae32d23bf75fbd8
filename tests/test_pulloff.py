"""Thesis §5.2 pull-off test (MODEL.md V6): examples/pulloff.toml.

Runs the example once (module fixture), writes results/pulloff/ (summary.json, probes.csv,
debonded_zone_*.png, delamination.csv, ...) and the force - debonded-length table
results/pulloff/force_debonded_length.csv, then checks convergence, the onset load, the
monotonic growth of the debonded zone and where debonding starts (the 4/5 element edge).

The table can also be made from any summary.json of the example:
``force_debonded_length_rows(json.load(open("summary.json")))``.
"""
from __future__ import annotations

import csv
import json
import re
from pathlib import Path

import numpy as np
import pytest

from layershell.element.geometry import surface_points
from layershell.element.quadrature import gauss_2d
from layershell.io.build import build, load, parse
from layershell.runner import run
from layershell.solver.problem import Problem

ROOT = Path(__file__).resolve().parents[1]
EXAMPLE = ROOT / "examples" / "pulloff.toml"
OUT = ROOT / "results" / "pulloff"

# geometry of examples/pulloff.toml (assumptions documented there)
F_FULL_KN = 30.0  # F = λ × 30 kN on the full strap
HALF_WIDTH = 50.0  # strap width on the half model (mm)
X_EDGE45 = 120.0  # the 4/5 element edge: end of the unbonded zone (mm)
ELEMENT_LENGTH = 30.0  # element length along the load (mm)
BOND_END = 270.0  # end of the bond zone (mm)
INTERFACE = "prism/strap"
# thesis §5.2: first debonding between 10.7 and 15.9 kN
ONSET_BAND = (10.7 / F_FULL_KN, 15.9 / F_FULL_KN)


def force_debonded_length_rows(summary: dict, interface: str = INTERFACE) -> list[dict]:
    """One row per converged step: load factor, pull force F (kN, full specimen), debonded area
    of the half model (mm², released interface regions, initially unbonded zone included),
    mean debonded length = area / half strap width (mm), the front: the largest x of the
    released interface points (mm; the bond zone starts at x = 120), and the thesis's d
    (Fig. 5.8a: the bond zone's debonded length over the inner two strap elements; the
    example's probe ``d_bond_zone``)."""
    rows = []
    for st in summary["steps"]:
        ext = st["debonded_extent"][interface]
        rows.append({"load_factor": st["load_factor"], "force_kN": st["load_factor"] * F_FULL_KN,
                     "debonded_area_mm2": ext["area"], "debonded_length_mm": ext["area"] / HALF_WIDTH,
                     "front_x_mm": ext["x_max"], "d_bond_zone_mm": st["probes"]["d_bond_zone"]})
    return rows


def write_force_debonded_length(summary: dict, path: Path) -> list[dict]:
    rows = force_debonded_length_rows(summary)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["load_factor", "force_kN", "debonded_area_mm2", "debonded_length_mm", "front_x_mm",
                    "d_bond_zone_mm"])
        for r in rows:
            w.writerow([f"{r['load_factor']:.4g}", f"{r['force_kN']:.4g}", f"{r['debonded_area_mm2']:.6g}",
                        f"{r['debonded_length_mm']:.5g}", f"{r['front_x_mm']:.5g}", f"{r['d_bond_zone_mm']:.5g}"])
    return rows


def _interface_points(problem) -> tuple[np.ndarray, object]:
    blk = problem.interfaces.runs[0].block
    xi, eta = gauss_2d(3)[0].T
    X = surface_points(problem.model.mesh.nodes[blk.conn], xi, eta).X0  # (e, 9, 3)
    return X, blk


def run_with_released_points(spec, out) -> tuple:
    """Run ``spec``; return the result and, per converged step, the released interface points
    (a boolean array (e, q), a copy)."""
    captured: list = []
    released: list[np.ndarray] = []
    original = Problem.build.__func__

    def spy(cls, model):
        pb = original(cls, model)
        captured.append(pb)
        return pb

    def progress(step, n, lam):
        released.append(captured[-1].interfaces.runs[0].block.released.copy())

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(Problem, "build", classmethod(spy))
        res = run(spec, out, progress=progress, write_vtu=False)
    return res, released


@pytest.fixture(scope="module")
def pulloff():
    """Run the example once; keep the released interface points of every converged step."""
    res, released = run_with_released_points(load(EXAMPLE), OUT)
    rows = write_force_debonded_length(res.summary, OUT / "force_debonded_length.csv")
    return res, released, rows


@pytest.mark.slow
def test_pulloff_converges(pulloff):
    res, released, rows = pulloff
    assert res.converged, res.message
    assert len(rows) == len(res.summary["steps"]) == len(released)
    assert (OUT / "force_debonded_length.csv").is_file()
    # the runner's own table: debonded area and the front (largest x of the released points)
    table = list(csv.DictReader(open(OUT / "delamination.csv")))
    assert len(table) == len(rows)
    for row, r in zip(table, rows):
        assert float(row[f"{INTERFACE}:area"]) == pytest.approx(r["debonded_area_mm2"], rel=1e-9)
        assert float(row[f"{INTERFACE}:x_max"]) == pytest.approx(r["front_x_mm"], rel=1e-9)
    assert json.loads((OUT / "summary.json").read_text())["converged"]


@pytest.mark.slow
def test_force_and_debonded_length_probes(pulloff):
    """The example's probes are the thesis's Fig. 5.8a table: force_kN = λ × 30 and d_bond_zone =
    the released area of the bond zone (x > 120) under the inner two strap elements (y < 25),
    divided by their 25 mm width, recomputed here from the released Gauss points and the Gauss
    weights of the 30 × 12.5 mm elements. d grows from 0 to the whole bond length (150 mm)."""
    res, released, _ = pulloff
    X, _ = _interface_points(res.problem)
    w = gauss_2d(3)[1] * (ELEMENT_LENGTH / 2) * (HALF_WIDTH / 4 / 2)
    inner_bond = (X[..., 0] > X_EDGE45) & (X[..., 1] < HALF_WIDTH / 2)
    d = [float((w * (rel & inner_bond)).sum()) / (HALF_WIDTH / 2) for rel in released]
    steps = res.summary["steps"]
    assert [s["probes"]["force_kN"] for s in steps] == pytest.approx([s["load_factor"] * F_FULL_KN for s in steps])
    assert [s["probes"]["d_bond_zone"] for s in steps] == pytest.approx(d, rel=1e-12, abs=1e-12)
    assert d[0] == 0 and d[-1] == pytest.approx(BOND_END - X_EDGE45) and np.all(np.diff(d) >= 0)
    table = list(csv.DictReader(open(OUT / "probes.csv")))
    assert [float(r["d_bond_zone"]) for r in table] == pytest.approx(d, rel=1e-9, abs=1e-9)


def predicted_onset(lam0: float = 0.05) -> float:
    """Independent estimate of the first debonding: solve the example at the small load factor
    ``lam0`` (no interface update), take the interface tractions at the bonded points and scale
    them until the failure function (4.15)-(4.16) reaches zero at the first point (bisection per
    point). Exact where the response before debonding is linear in λ."""
    from layershell.delamination import failure_function
    from layershell.interfaces import interface_state
    from layershell.solver.newton import load_steps

    spec = load(EXAMPLE)
    pb = Problem.build(spec.model)
    st = list(load_steps(pb, np.array([lam0]), spec.newton))[-1]
    r = pb.interfaces.runs[0]
    blk = r.block
    t = interface_state(spec.model, pb.dm, st.u, blk.itf, "gauss").traction().reshape(*blk.w.shape, 3)
    t = t[~blk.released]
    lo, hi = np.zeros(len(t)), np.full(len(t), 1e3)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        failed = failure_function(mid[:, None] * t, r.law)[1]
        hi, lo = np.where(failed, mid, hi), np.where(failed, lo, mid)
    return lam0 * float(hi.min())


@pytest.mark.slow
def test_pulloff_onset_load(pulloff):
    """The independent prediction lies between the last step without and the first step with
    debonding (3 % allowance for the slight nonlinearity before debonding)."""
    res, _, _ = pulloff
    lam = res.summary["first_delamination_load_factor"]
    assert lam is not None
    pred = predicted_onset()
    factors = [s["load_factor"] for s in res.summary["steps"]]
    before = factors[factors.index(lam) - 1]
    print(f"first debonding at λ = {lam} (F = {lam * F_FULL_KN:.1f} kN); predicted {pred:.4f}; "
          f"thesis 0.357-0.530")
    assert before < 1.03 * pred and 0.97 * pred <= lam


@pytest.mark.slow
@pytest.mark.xfail(strict=True, reason="onset λ = 0.30 (9 kN) with the assumed dimensions, 16 % below the "
                   "thesis's 10.7-15.9 kN; the specimen's dimensions (thesis Figs. 5.6-5.7) are not available "
                   "and nothing was tuned")
def test_pulloff_onset_in_thesis_band(pulloff):
    res, _, _ = pulloff
    lam = res.summary["first_delamination_load_factor"]
    assert ONSET_BAND[0] <= lam <= ONSET_BAND[1]


@pytest.mark.slow
def test_pulloff_debonded_area_grows(pulloff):
    res, released, rows = pulloff
    area = np.array([r["debonded_area_mm2"] for r in rows])
    assert np.all(np.diff(area) >= -1e-9)
    # initially unbonded zone: elements 1-4 less the region of the (bonded) 4/5 edge nodes, i.e.
    # element 4's last Gauss column (weight 5/18 of the element length)
    assert area[0] == pytest.approx(HALF_WIDTH * (X_EDGE45 - ELEMENT_LENGTH * 5 / 18), rel=1e-9)
    assert area[-1] > area[0]  # the bond zone debonds
    # at the last converged load (λ = 0.75, see the example's header) the whole strap is off
    assert area[-1] == pytest.approx(HALF_WIDTH * BOND_END, rel=1e-9)
    # release is irreversible, step by step
    for a, b in zip(released, released[1:]):
        assert np.all(b[a])


@pytest.mark.slow
def test_pulloff_debonding_starts_at_edge_4_5(pulloff):
    res, released, _ = pulloff
    X, blk = _interface_points(res.problem)
    lam = res.summary["first_delamination_load_factor"]
    k = [s["load_factor"] for s in res.summary["steps"]].index(lam)
    before = released[k - 1] if k > 0 else np.zeros_like(released[0])
    new = released[k] & ~before
    assert new.any()
    x = X[..., 0][new]
    # thesis: debonding starts in element 5 at the 4/5 edge. Released at the first failing load
    # level (including its re-solutions): the regions of the 4/5 edge nodes (element 4's last and
    # element 5's first Gauss column) and at most the rest of element 5
    assert np.any(np.abs(x - X_EDGE45) < ELEMENT_LENGTH / 3), np.unique(np.round(x, 3))
    assert np.all((x > X_EDGE45 - ELEMENT_LENGTH / 3) & (x < X_EDGE45 + ELEMENT_LENGTH)), np.unique(np.round(x, 3))
    assert np.any(x > X_EDGE45)  # bond-zone points (element 5) are among them


@pytest.mark.slow
def test_pulloff_with_the_thesis_procedure_front_lags_as_in_the_thesis(pulloff):
    """[delamination] reequilibrate = false (the thesis evaluates the criterion once per load step
    and does not re-solve): thesis §5.2 reports that at 23.2 kN (λ = 0.773) the debonding reaches
    element 6 (150-180 mm) at mid-width and runs further at the strap edge. With this procedure
    the strap edge leads at every step, the mid-width front lies in element 6 at loads below
    λ = 0.773 (from λ = 0.525, earlier, like this model's onset), and at λ = 0.75 the front has
    reached the 6/7 edge - not the whole strap, as with the default re-equilibration (see
    ``test_pulloff_debonded_area_grows``)."""
    text = EXAMPLE.read_text().replace("max_bisections = 8", "max_bisections = 8\n\n[delamination]\nreequilibrate = false")
    spec = build(parse(text, str(EXAMPLE)), EXAMPLE.parent)
    res, released = run_with_released_points(spec, None)
    X, _ = _interface_points(res.problem)

    def front(P, y0, y1):
        sel = (P[:, 1] >= y0) & (P[:, 1] < y1)
        return float(P[sel, 0].max()) if sel.any() else 0.0

    fronts = [(front(X[rel], 0.0, HALF_WIDTH / 4), front(X[rel], 3 * HALF_WIDTH / 4, HALF_WIDTH + 1e-9))
              for rel in released]
    assert res.converged, res.message
    assert all(s["resolves"] == 0 for s in res.summary["steps"])
    assert res.summary["first_delamination_load_factor"] == pulloff[0].summary["first_delamination_load_factor"]
    mid, edge = np.array(fronts).T
    lam = np.array([s["load_factor"] for s in res.summary["steps"]])
    assert np.all(edge >= mid) and np.any(edge > mid)  # the strap edge leads
    in6 = (mid >= 5 * ELEMENT_LENGTH) & (mid < 6 * ELEMENT_LENGTH)
    assert np.any(in6 & (lam <= 0.773)) and np.all(edge[in6] > mid[in6] - 1e-9)
    assert mid[-1] < 7 * ELEMENT_LENGTH  # λ = 0.75: not beyond the 6/7 edge's region
    area = res.summary["steps"][-1]["debonded_area"][INTERFACE]
    assert area < 0.8 * HALF_WIDTH * BOND_END  # far from the whole strap


@pytest.mark.slow
def test_pulloff_keeps_the_full_element_because_mitc9_moves_the_onset():
    """Why examples/pulloff.toml sets element = "full": with MITC9 the contact between the debonded
    layers at the face Gauss points finds no equilibrium in the first step (its set keeps
    changing), so it moves to the nodes, and the first release (λ = 0.25, 7.5 kN: 30 % below the
    thesis's 10.7 kN; predicted 0.241 from the tractions) lies in the middle of element 5
    (x = 135 mm), not at the 4/5 edge the thesis names. The whole run then debonds the strap at
    λ = 0.70 (21 kN) and has no equilibrium beyond. Run here to λ = 0.30."""
    text = EXAMPLE.read_text().replace('element = "full"', 'element = "mitc"')
    lams = [0.05, 0.10, 0.15, 0.20, 0.25, 0.30]
    text = re.sub(r"factors = \[[^\]]*\]", f"factors = {lams}", text)
    res, released = run_with_released_points(build(parse(text, str(EXAMPLE)), EXAMPLE.parent), None)
    assert res.converged
    assert [m["load_factor"] for m in res.summary["contact_moved_to_nodes"]] == [0.0]
    k = [s["load_factor"] for s in res.summary["steps"]].index(res.summary["first_delamination_load_factor"])
    assert lams[k] == 0.25 and lams[k] < ONSET_BAND[0]
    X, _ = _interface_points(res.problem)
    x = X[..., 0][released[k] & ~released[k - 1]]
    assert np.all(np.abs(x - X_EDGE45) > ELEMENT_LENGTH / 3), np.unique(np.round(x, 3))
