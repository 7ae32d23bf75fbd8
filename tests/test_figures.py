"""The PNG figures of a run (plots.write_figures, called by runner.run): which files, valid PNGs,
and that the plotted data are the run's results (against independent references where possible)."""
from __future__ import annotations

import numpy as np
import pytest
from helpers import EXAMPLES

from layershell.export import reference_displacement
from layershell.io.build import InputError, build, parse
from layershell.plots import ZoneHistory, write_figures
from layershell.runner import run, through_thickness
from layershell.solver.newton import load_steps

#: a 2 × 1 m block of two layers; the top layer is sucked off (σ33 = 1.1 λ) and debonds when σ33
#: passes σ_max = 1 (MODEL.md §9): not at λ = 0.5, at λ = 1 (cf. tests/test_delamination.py)
SUCTION = """
[model]
units = "kN, m"
[mesh]
type = "rectangle"
lx = 2.0
ly = 1.0
nx = 2
ny = 1
[materials.a]
type = "isotropic"
E = 1e4
nu = 0.0
[materials.b]
type = "isotropic"
E = 2e4
nu = 0.0
[[layers]]
name = "base"
material = "a"
thickness = 0.2
directors = 2
[[layers]]
name = "top"
material = "b"
thickness = 0.05
directors = 2
[[supports]]
type = "fix"
where = "x > -1"
components = ["z"]
[[supports]]
type = "fix"
point = [0, 0, 0]
components = ["x", "y"]
[[supports]]
type = "fix"
point = [2, 0, 0]
components = ["y"]
[[supports]]
type = "fix"
where = "x > -1"
layer = "top"
components = ["z"]
[[supports]]
type = "fix"
point = [0, 0, 0]
layer = "top"
components = ["x", "y"]
[[supports]]
type = "fix"
point = [2, 0, 0]
layer = "top"
components = ["y"]
[[loads]]
type = "surface"
face = "top"
direction = [0, 0, 1]
magnitude = 1.1
[[interfaces]]
layer = "top"
sigma_max = 1.0
tau_max = 1.0
mu0 = 0.5
[steps]
factors = [0.5, 1.0]
[[probes]]
name = "t33"
quantity = "traction"
point = [1, 0.5, 0]
layer = "top"
component = "33"
[[probes]]
name = "s33_base"
quantity = "stress"
point = [1, 0.5, 0]
theta3 = 0.1
component = "33"
[output]
vtu = false
"""


def _is_png(p) -> bool:
    return p.is_file() and p.stat().st_size > 1000 and p.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def _png_size(p) -> tuple[int, int]:
    b = p.read_bytes()
    assert b[12:16] == b"IHDR"
    return int.from_bytes(b[16:20], "big"), int.from_bytes(b[20:24], "big")


def _spec(text: str, replace: dict[str, str] | None = None, base=EXAMPLES):
    for a, b in (replace or {}).items():
        assert a in text, a
        text = text.replace(a, b)
    return build(parse(text, "model.toml"), base)


def test_run_writes_the_figures(tmp_path):
    """Cantilever (§3.5.1): load–displacement per probe and overall, deformed shape; the colour
    range of the deformed shape is the range of |u| (max = the largest nodal |u|, which a
    'magnitude, absmax' probe evaluates independently)."""
    text = (EXAMPLES / "cantilever_thick.toml").read_text() + (
        '\n[[probes]]\nname = "u_max"\nquantity = "displacement"\nwhere = "x > -1"\ncomponent = "magnitude"\n'
        'reduce = "max"\n')
    spec = _spec(text, {"[steps]\nn = 1": "[steps]\nn = 2"} if "[steps]\nn = 1" in text else None)
    res = run(spec, tmp_path, write_vtu=False)
    assert res.converged
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    assert names == ["deformed.png", "load_displacement.png", "load_displacement_u_max.png",
                     "load_displacement_w_tip.png"]
    assert all(_is_png(tmp_path / n) for n in names)
    assert _png_size(tmp_path / "load_displacement.png")[0] > _png_size(tmp_path / "load_displacement_w_tip.png")[0]
    info = write_figures(tmp_path / "again", spec, res.problem, res.u, res.summary)
    d = info["deformed.png"]
    umax = float(np.linalg.norm(reference_displacement(spec.model, res.problem.dm, res.u), axis=1).max())
    assert umax == pytest.approx(res.summary["probes"]["u_max"], rel=1e-12)
    assert d["max_u"] == pytest.approx(umax, rel=1e-12)
    assert d["color_range"][0] == pytest.approx(0.0, abs=1e-12)  # the clamped end does not move
    assert umax <= d["color_range"][1] <= umax * (1 + 1e-3)  # sampled surface: nodes included
    assert abs(res.summary["probes"]["w_tip"] - 4.0205) < 1e-3  # the validated result (README; MITC9)
    lw = info["load_displacement_w_tip.png"]["range"]
    assert lw[1] == pytest.approx(res.summary["probes"]["w_tip"])


def test_thickness_figure_at_stress_probes(tmp_path):
    """Ring (§2.10): every stress probe at a point gets thickness_<probe>.png; its profile runs
    from σ_φ(b) to σ_φ(a), close to Lamé's −1.667 / −2.667 kN/m² (README table)."""
    spec = _spec((EXAMPLES / "ring.toml").read_text())
    res = run(spec, None)
    info = write_figures(tmp_path, spec, res.problem, res.u, res.summary, through_thickness=through_thickness)
    for n in ("sigma_phi_inner", "sigma_phi_outer", "sigma_r_outer"):
        assert _is_png(tmp_path / f"thickness_{n}.png")
    lo, hi = info["thickness_sigma_phi_inner.png"]["range"]
    assert lo == pytest.approx(-2.667, rel=0.02) and hi == pytest.approx(-1.667, rel=0.02)
    p = res.summary["probes"]
    assert lo <= p["sigma_phi_inner"] <= hi and lo <= p["sigma_phi_outer"] <= hi


def test_debonded_zone_maps_at_chosen_steps(tmp_path):
    res = run(_spec(SUCTION), tmp_path / "default")
    assert res.converged and res.summary["first_delamination_load_factor"] == 1.0
    out = tmp_path / "default"
    for n in ("debonded_zone_base_top.png", "load_debonded_area.png", "deformed.png",
              "load_displacement_t33.png", "thickness_s33_base.png"):
        assert _is_png(out / n), n
    assert not (out / "debonded_zone.png").exists()
    w1 = _png_size(out / "debonded_zone_base_top.png")[0]  # default: first debonding (= last) step, one panel
    res2 = run(_spec(SUCTION, {"vtu = false": "vtu = false\nzone_steps = [1, 2]"}), tmp_path / "both")
    w2 = _png_size(tmp_path / "both" / "debonded_zone_base_top.png")[0]
    assert w2 > 1.8 * w1  # two panels
    assert res2.summary["probes"] == res.summary["probes"]


def test_zone_history_records_the_debonded_flags():
    """The flags recorded per step give the debonded areas the controller reports at that step,
    and the default steps are the first debonding and the last step."""
    spec = _spec(SUCTION, {"factors = [0.5, 1.0]": "factors = [0.5, 1.0, 0.5]"})
    from layershell.solver.problem import Problem

    pb = Problem.build(spec.model)  # driven like runner.run does
    zones = ZoneHistory(pb.interfaces, keep=[1, 2, 3])
    bounded = ZoneHistory(pb.interfaces)  # no zone_steps: keeps the first debonding and the latest step only
    areas = []
    for st in load_steps(pb, spec.load_factors, spec.newton, on_step_end=pb.interfaces.update):
        zones.record(st.step, st.load_factor)
        bounded.record(st.step, st.load_factor)
        areas.append(pb.interfaces.debonded_area()["base/top"])
    assert bounded.steps == [2, 3] and bounded.default_steps() == [2, 3]
    blk = pb.interfaces.runs[0].block
    rec = [float((blk.w0 * r[0]).sum()) for r in zones.released]
    assert rec == pytest.approx(areas)
    assert rec[0] == 0.0 and rec[1] == pytest.approx(2.0)  # the whole 2 × 1 m interface lets go at λ = 1
    assert zones.default_steps() == [2, 3]
    assert ZoneHistory(None).default_steps() == []


def test_zone_steps_are_validated():
    with pytest.raises(InputError, match=r"zone_steps.*step 5 does not exist.*2 load step"):
        _spec(SUCTION, {"vtu = false": "vtu = false\nzone_steps = [1, 5]"})
    with pytest.raises(InputError, match="zone_steps"):
        _spec(SUCTION, {"vtu = false": "vtu = false\nzone_steps = [0]"})
    with pytest.raises(InputError, match="zone_steps"):
        _spec(SUCTION, {"vtu = false": "vtu = false\nzone_steps = [2, 2]"})
