"""benchmarks/paths.py, the softening-path benchmark set: its case list is the one the
performance targets name, every case's model builds as `layershell check` builds it (no
solving), its references agree with the closed forms of the tests, its solve counter counts
without changing a solution, and its table writer gives every column."""
import csv
import io
import json
import math
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "benchmarks"))
import paths  # noqa: E402

#: the cases of the benchmark set: the DCB on 100, 200 and 400 elements force- and
#: displacement-controlled, the stiff, strong DCB, ENF, MMB, the lap shear with friction, the
#: cohesive plate on 12 x 12 and 24 x 24, the slab on 8 x 6, 12 x 9, 16 x 12, the circular delaminations
EXPECTED = {"dcb_force_100": 100, "dcb_force_200": 200, "dcb_force_400": 400,
            "dcb_disp_100": 100, "dcb_disp_200": 200, "dcb_disp_400": 400, "dcb_stiff_200": 200,
            "enf_100": 100, "mmb_100": 100, "lapshear_friction": None,
            "plate_12x12": 144, "plate_24x24": 576, "slab_8x6": 48, "slab_12x9": 108, "slab_16x12": 192,
            "cfrp_circular": None, "trc_circular": None}


def test_case_list_is_complete():
    assert set(paths.CASES) == set(EXPECTED)
    quick = {c.name for c in paths.CASES.values() if c.quick}
    assert {"dcb_force_100", "dcb_disp_100", "lapshear_friction"} <= quick
    assert not quick & {"dcb_force_400", "dcb_disp_400", "plate_24x24", "slab_12x9", "slab_16x12"}


def test_every_case_model_builds():
    """Each case's example with its replacements (each must occur) builds its problem, with the
    mesh, control and interface the case names."""
    from layershell.solver.problem import Problem

    for name, n in EXPECTED.items():
        spec = paths.case_spec(paths.CASES[name])
        Problem.build(spec.model)
        if n is not None:
            assert spec.model.mesh.n_elements == n, name
        if name.startswith(("dcb", "mmb", "lapshear", "slab")):
            assert spec.path_following.control == "arc_length", name
    stiff = paths.case_spec(paths.CASES["dcb_stiff_200"]).model
    law = stiff.interface_laws[0] if isinstance(stiff.interface_laws, (list, tuple)) else next(iter(stiff.interface_laws.values()))
    assert (law.sigma_max, law.G_Ic) == (57.0, 0.28)
    assert all(np.allclose(lay.thickness, 1.5) for lay in stiff.layers)


def test_beam_theory_of_the_script_is_that_of_the_dcb_tests():
    """The script's corrected beam theory (its own Beam) is tests/test_dcb.py's for the example,
    and a path that lies on it has no deviation: the reference of a fake DCB path built from
    P(a) and C(a) is zero, and 5 % above it is +5 %."""
    import test_dcb as T

    beam = paths.EXAMPLE_DCB
    assert beam.chi() == pytest.approx(T.chi(), rel=1e-12)
    a = np.linspace(55.0, 90.0, 30)
    P_peak = T.cbt_load(55.0)
    P = np.r_[np.linspace(0.1, 0.99, 10) * P_peak, [T.cbt_load(x) for x in a]]
    d = np.r_[np.linspace(0.1, 0.99, 10) * P_peak * T.cbt_compliance(55.0), [T.cbt_load(x) * T.cbt_compliance(x) for x in a]]

    def summary(scale):
        return {"steps": [{"probes": {"P": scale * p, "w_upper": dd / 2, "w_lower": -dd / 2}} for p, dd in zip(P, d)]}

    ref = paths.dcb_reference(beam)(summary(1.0))
    assert ref["peak"] == pytest.approx(ref["peak_reference"], rel=1e-9)
    assert max(map(abs, ref["branch_deviation"])) < 1e-9
    # 5 % more load at the same openings: the compliance crack (a + χh ∝ C^(1/3)) is shorter, the
    # beam-theory load 1.05^(1/3) higher, the deviation 1.05^(2/3) - 1
    lo, hi = paths.dcb_reference(beam)(summary(1.05))["branch_deviation"]
    assert lo == pytest.approx(1.05 ** (2 / 3) - 1, rel=1e-6) and hi == pytest.approx(lo, rel=1e-9)


def test_solve_counter_counts_right_hand_sides_and_changes_nothing():
    import scipy.sparse as sp

    from layershell.solver.linear import LinearSolver

    K = sp.csr_matrix(sp.diags([4.0, 5.0, 6.0]) + sp.diags([1.0, 1.0], 1) + sp.diags([1.0, 1.0], -1))
    b = np.column_stack([np.ones(3), np.arange(3.0)])
    plain = LinearSolver("superlu").solve(K, b)
    counter = paths.SolveCounter()
    try:
        s = LinearSolver("superlu")
        x = s.solve(K, b)
        s.solve(K, b[:, 0])
    finally:
        counter.close()
    assert np.array_equal(x, plain)
    assert counter.rhs == 3 and counter.factorisations() == 2
    LinearSolver("superlu").solve(K, b)
    assert counter.rhs == 3  # closed: no longer counted


FAKE = {"case": "dcb_disp_200", "mesh": "200 elements, 28830 DOFs", "reached_end": True,
        "stopped_at": "lambda = 1 (lambda_end)", "increments": 312, "newton_iterations": 2460, "cuts": 139,
        "linear_solves": 5000, "factorisations": 2600, "cpu_s": 300.25, "wall_s": 310.5,
        "increments_per_min": 60.3, "energy_balance": 0.0084, "peak": 63.0, "peak_reference": 60.0,
        "branch_deviation": (-0.008, 0.017), "reference": "beam theory", "capped": False}


def test_table_writer_produces_the_columns(tmp_path):
    md = paths.markdown([FAKE, {"case": "slab_16x12", "reached_end": False, "stopped_at": "killed", "capped": True}])
    header, rule, row, failed = md.splitlines()
    assert [c.strip() for c in header.strip("|").split("|")] == list(paths.MARKDOWN_HEADER)
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert len(cells) == len(paths.MARKDOWN_HEADER)
    assert cells[:9] == ["dcb_disp_200", "200 elements, 28830 DOFs", "yes", "lambda = 1 (lambda_end)", "312",
                         "2460", "139", "5000 (2600)", "300.2"]
    assert cells[11:] == ["0.84 %", "63 (60)", "+5.00 %", "-0.8 ... +1.7 %"]
    assert failed.startswith("| slab_16x12 (capped) |") and "| no |" in failed
    md_path, csv_path, json_path = paths.write_tables([FAKE], tmp_path / "t.md")
    assert md_path.read_text() == paths.markdown([FAKE])
    rows = list(csv.DictReader(io.StringIO(csv_path.read_text())))
    assert tuple(rows[0]) == paths.COLUMNS and rows[0]["newton_iterations"] == "2460"
    data = json.loads(json_path.read_text())[0]
    assert set(data) == set(paths.COLUMNS)
    assert data["peak_deviation"] == pytest.approx(0.05) and data["branch_deviation"] == [-0.008, 0.017]
    assert json.loads(paths.json_text([{**FAKE, "energy_balance": math.nan}]))[0]["energy_balance"] is None
    # the JSON rows give the same Markdown table again (no branch: NaN written as null)
    rows = [FAKE, {**FAKE, "case": "lapshear_friction", "branch_deviation": (math.nan, math.nan)}]
    assert paths.markdown(json.loads(paths.json_text(rows))) == paths.markdown(rows)


def test_unknown_case_is_named(capsys):
    with pytest.raises(SystemExit, match="unknown case.*enf_100"):
        paths.main(["--case", "nope"])


def test_a_path_that_has_not_passed_its_peak_reports_none():
    """A run capped on its way up reports no peak (its last state is no peak) and no branch; the
    slab's end-debonding peak counts once a later state lies below it, the plate's deflection
    only at λ = 1."""
    rising = {"steps": [{"load_factor": l, "probes": {"P": 10 * l, "w_upper": l, "w_lower": -l},
                         "debonded_area": {"i": 0.0}} for l in (0.1, 0.2, 0.3)]}
    ref = paths.dcb_reference(paths.EXAMPLE_DCB)(rising)
    assert math.isnan(ref["peak"]) and all(map(math.isnan, ref["branch_deviation"]))
    slab = paths.slab_reference(327.13, 376.6)
    assert all(map(math.isnan, slab(rising)["branch_deviation"]))
    passed = {"steps": rising["steps"] + [{"load_factor": 0.25, "debonded_area": {"i": 0.1}}]}
    assert slab(passed)["branch_deviation"][0] == pytest.approx(0.3 / 327.13 - 1)
    assert math.isnan(paths.plate_reference({**rising, "probes": {"w_front_max": 0.01}})["peak"])
    at_end = {"steps": [{"load_factor": 1.0}], "probes": {"w_front_max": 0.0597}}
    assert paths.plate_reference(at_end)["peak"] == 0.0597
