"""The PNG figures of a run (plots.write_figures, called by runner.run): which files, valid PNGs,
and that the plotted data are the run's results (against independent references where possible)."""
from __future__ import annotations

from pathlib import Path

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


# ----------------------------------------------------------------------------- what the axes say


class _Figures:
    """The figures that plots writes, as seen just before they are saved (artists, not pixels)."""

    def __init__(self, monkeypatch):
        from layershell import plots

        self.saved: dict[str, object] = {}
        save = plots._save

        def keep(fig, path):
            savefig = fig.savefig

            def snapshot_and_save(*args, **kwargs):  # after the layout of the tick labels
                fig.canvas.draw()
                self.saved[Path(path).name] = self._snapshot(fig)
                return savefig(*args, **kwargs)

            fig.savefig = snapshot_and_save
            return save(fig, path)

        monkeypatch.setattr(plots, "_save", keep)

    @staticmethod
    def _snapshot(fig) -> list[dict]:
        renderer = fig.canvas.get_renderer()
        axes = []
        for ax in fig.axes:
            if not ax.get_visible() or ax.name != "rectilinear" or not ax.get_xlabel():
                continue  # colour bars have no x label
            ticks = {}
            for axis in (ax.xaxis, ax.yaxis):
                lo, hi = sorted(axis.get_view_interval())
                boxes = [t.label1.get_window_extent(renderer) for t in axis.get_major_ticks()
                         if lo - 1e-9 * (hi - lo) <= t.get_loc() <= hi + 1e-9 * (hi - lo) and t.label1.get_text()]
                ticks[axis.axis_name] = boxes
            axes.append({
                "title": ax.get_title(), "xlabel": ax.get_xlabel(), "ylabel": ax.get_ylabel(), "ticks": ticks,
                "lines": {ln.get_label(): np.asarray(ln.get_xydata(), float) for ln in ax.get_lines()},
                "polys": [[np.asarray(p.vertices, float) for p in c.get_paths()] for c in ax.collections
                          if type(c).__name__ == "PolyCollection"],
            })
        return axes


def _overlapping(boxes, axis_name: str) -> bool:
    if axis_name == "x":
        spans = sorted((b.x0, b.x1) for b in boxes)
    else:
        spans = sorted((b.y0, b.y1) for b in boxes)
    return any(a[1] > b[0] for a, b in zip(spans[:-1], spans[1:]))


def test_tick_labels_do_not_overlap(monkeypatch, tmp_path):
    """Long negative tick labels (−0.0123 …, −98765 …) in three panels side by side: no two tick
    labels of an axis overlap."""
    from layershell.plots import plot_load_displacement

    figs = _Figures(monkeypatch)
    lam = np.linspace(0.0, 1.0, 11)
    plot_load_displacement(tmp_path / "ld.png", lam, {"a": -0.0123456 * lam, "b": -98765.4321 * lam,
                                                        "c": 1e-7 * lam - 3e-6}, units="mm")
    axes = figs.saved["ld.png"]
    assert len(axes) == 3
    for ax in axes:
        for name, boxes in ax["ticks"].items():
            assert len(boxes) >= 2, (ax["title"], name)
            assert not _overlapping(boxes, name), (ax["title"], name)


def test_units_derived_from_the_unit_system():
    from layershell.units import Units

    u = Units.parse("N, mm")
    assert (u.force, u.length, u.stress, u.per_length, u.area) == ("N", "mm", "N/mm²", "N/mm", "mm²")
    assert Units.parse("m, kN") == Units.parse("kN, m") == Units.parse("kN m") == Units("kN", "m")
    assert Units.parse("kN, m").of_probe("stress", "11") == "kN/m²"
    assert Units.parse("kN, m").of_probe("traction", "33") == "kN/m²"
    assert Units.parse("kN, m").of_probe("debonded_area") == "m²"
    assert Units.parse("kN, m").of_probe("reaction", "z") == "kN"
    assert Units.parse("kN, m").of_probe("reaction", "mx") == "kN·m"
    assert Units.parse("kN, m").of_probe("resultant", "n") == "kN/m"
    assert Units.parse("kN, m").of_probe("resultant", "m") == "kN·m/m"
    assert Units.parse("kN, m").of_probe("displacement", "z") == "m"
    assert Units.parse("kN, m").of_probe("load_factor") == ""
    assert Units.parse("").stress == "" and Units.parse("SI").of_probe("stress") == ""


def test_stress_and_zone_axes_in_physical_units(monkeypatch, tmp_path):
    """The suction block (units kN, m): stress and traction axes in kN/m², not the unit system;
    the debonded-zone map in m with the area in m² (the whole 2 × 1 m interface: 2 m²)."""
    figs = _Figures(monkeypatch)
    res = run(_spec(SUCTION), tmp_path)
    assert res.converged
    t33 = figs.saved["load_displacement_t33.png"][0]
    assert t33["xlabel"] == "t33 [kN/m²]" and t33["ylabel"] == "load factor λ"
    thick = figs.saved["thickness_s33_base.png"][0]
    assert thick["xlabel"].endswith("[kN/m²]"), thick["xlabel"]
    zone = figs.saved["debonded_zone_base_top.png"][0]
    assert (zone["xlabel"], zone["ylabel"]) == ("x [m]", "y [m]")
    assert zone["title"].endswith("debonded area 2 m²"), zone["title"]
    assert figs.saved["load_debonded_area.png"][0]["xlabel"] == "debonded area [m²]"
    assert not any("kN, m" in ax["xlabel"] + ax["ylabel"] for axes in figs.saved.values() for ax in axes)


#: a 100 × 10 mm strip (one layer 1 mm thick), clamped at x = 0 and pulled at x = 100 by a
#: prescribed displacement λ × 0.5 mm
STRIP = """
[model]
units = "N, mm"
nonlinear = false
[mesh]
type = "rectangle"
lx = 100.0
ly = 10.0
nx = 2
ny = 1
[materials.m]
type = "isotropic"
E = 1000.0
nu = 0.0
[[layers]]
name = "strip"
material = "m"
thickness = 1.0
directors = 1
[[supports]]
type = "fix"
where = "near(x, 0)"
components = ["x", "y", "z"]
[[supports]]
type = "fix"
where = "near(x, 100)"
components = ["x"]
value = [0.5]
[steps]
factors = [0.5, 1.0]
[[probes]]
name = "u_end"
quantity = "displacement"
point = [100, 5, 0]
component = "x"
[[probes]]
name = "N"
quantity = "reaction"
where = "near(x, 100)"
component = "x"
[output]
vtu = false
"""


def test_load_axis_under_displacement_control(monkeypatch, tmp_path):
    """Pulled by a prescribed displacement, the y axis is that displacement (λ × 0.5 mm), not
    'load factor': the end's own displacement (x) equals it (y) at every step; the reaction axis
    is in N."""
    figs = _Figures(monkeypatch)
    res = run(_spec(STRIP), tmp_path)
    assert res.converged
    ax = figs.saved["load_displacement_u_end.png"][0]
    assert ax["ylabel"] == "prescribed displacement λ × 0.5 [mm]"
    assert ax["xlabel"] == "u_end [mm]"
    (xy,) = [v for v in ax["lines"].values() if len(v) == 2]
    assert xy[:, 1] == pytest.approx([0.25, 0.5], rel=1e-12)
    assert xy[:, 0] == pytest.approx(xy[:, 1], rel=1e-9)
    n = figs.saved["load_displacement_N.png"][0]
    assert n["xlabel"] == "N [N]"


def test_load_axis_names_what_the_load_factor_scales():
    from layershell.plots import load_axis

    pulled_two_ways = STRIP + '[[supports]]\ntype = "fix"\nwhere = "near(x, 50)"\ncomponents = ["y"]\nvalue = [-0.25]\n'
    assert load_axis(_spec(pulled_two_ways).model) == ("largest prescribed displacement λ × 0.5 [mm]", 0.5)
    loaded = STRIP + '[[loads]]\ntype = "surface"\nface = "top"\ndirection = [0, 0, 1]\nmagnitude = 1.0\n'
    assert load_axis(_spec(loaded).model)[0] == "load factor λ (scales the loads and prescribed displacements)"
    assert load_axis(_spec(SUCTION).model) == ("load factor λ", 1.0)


def test_deformed_shape_shows_a_lifted_layer(monkeypatch, tmp_path):
    """Two layers, the upper one lifted off by δ everywhere (a hand-made displacement: its
    director 0 moved by δ along z, the lower layer at rest): the reference face does not move,
    but the section of deformed.png shows the gap δ × the stated magnification between the lower
    layer's top face (z = 0.2) and the upper layer's bottom face."""
    from layershell.dofs import number_dofs
    from layershell.plots import plot_deformed

    spec = _spec(SUCTION)
    model = spec.model
    dm = number_dofs(model)
    delta = 0.01
    u = np.zeros(int(dm.layer_dofs[1].max()) + 1)
    top = model.layers.index(next(ly for ly in model.layers if ly.name == "top"))
    u[dm.layer_dofs[top][:, 0, 2]] = delta
    figs = _Figures(monkeypatch)
    _, info = plot_deformed(tmp_path / "deformed.png", model, dm, u, info=True)
    assert info["separation"] == pytest.approx(delta, rel=1e-12)
    assert info["max_u"] == 0.0  # the reference face (the lower layer's bottom) is at rest
    (section,) = figs.saved["deformed.png"]
    scale = info["scale"]
    assert f"× {scale:.3g}" in section["title"] and section["ylabel"] == "z [m]"
    lower, upper = (np.concatenate(p) for p in section["polys"])
    assert lower[:, 1].max() == pytest.approx(0.2, abs=1e-12)
    assert upper[:, 1].min() - lower[:, 1].max() == pytest.approx(scale * delta, rel=1e-9)
    assert upper[:, 1].max() == pytest.approx(0.25 + scale * delta, rel=1e-9)


def test_profiles_against_the_physical_height(monkeypatch, tmp_path):
    """Lamé ring (reference face outside, normal A3 = −e_r): at the probes' point (0, 5) the
    height axis is y = 5 − Θ³, the radius, and every plotted point lies on Lamé's σ_φ(r) and
    σ_r(r) (p = 1, a = 2.5, b = 5) within 2 %. A plate with normal −z: height z = −Θ³."""
    figs = _Figures(monkeypatch)
    spec = _spec((EXAMPLES / "ring.toml").read_text())
    res = run(spec, None)
    write_figures(tmp_path, spec, res.problem, res.u, res.summary, through_thickness=through_thickness)
    a, b = 2.5, 5.0
    lame = {"11": lambda r: -b**2 / (b**2 - a**2) * (1 + a**2 / r**2),
            "33": lambda r: -b**2 / (b**2 - a**2) * (1 - a**2 / r**2)}
    for probe, comp in (("sigma_phi_inner", "11"), ("sigma_r_outer", "33")):
        (ax,) = figs.saved[f"thickness_{probe}.png"]
        assert ax["ylabel"] == "height y [m]" and ax["xlabel"].endswith("[kN/m²]")
        sr = ax["lines"]["ring"]
        assert sr[:, 1].min() == pytest.approx(a) and sr[:, 1].max() == pytest.approx(b)
        assert np.abs(sr[:, 0] - lame[comp](sr[:, 1])).max() < 0.02 * abs(lame["11"](a))
        probe_mark = ax["lines"]["probe"][0]
        assert probe_mark[0] == pytest.approx(lame[comp](probe_mark[1]), abs=0.02 * abs(lame["11"](a)))
    from layershell.plots import height_axis

    flipped = _spec(SUCTION.replace('ny = 1\n', 'ny = 1\nnormal = "-z"\n', 1)).model
    assert height_axis(flipped, [1.0, 0.5, 0.0]) == (0.0, -1.0, "height z [m]")


def test_units_that_name_no_force_and_length_are_refused(tmp_path):
    """`[model] units` gives the axes their units, so a string that names no force and length unit
    ("MPa, mm": a stress) is an input error (exit 2) naming the field and the units accepted."""
    from typer.testing import CliRunner

    from layershell.cli import app

    model = tmp_path / "strip.toml"
    model.write_text(STRIP.replace('units = "N, mm"', 'units = "MPa, mm"'), encoding="utf-8")
    res = CliRunner().invoke(app, ["check", str(model)], env={"NO_COLOR": "1"})
    assert res.exit_code == 2, res.output
    text = res.output + getattr(res, "stderr", "")
    assert "model.units" in text and "'MPa, mm'" in text and "'kN, m' or 'N, mm'" in text
    assert res.exception is None or isinstance(res.exception, SystemExit)  # no traceback
    model.write_text(STRIP.replace('units = "N, mm"', 'units = "mm, N"'), encoding="utf-8")
    assert CliRunner().invoke(app, ["check", str(model)], env={"NO_COLOR": "1"}).exit_code == 0


def test_calibration_axes_in_physical_units(monkeypatch, tmp_path):
    """calibration.png: the fitted curve's axes carry the probes' units (N, mm), as the run's figures."""
    from layershell.calibrate import Param, calibrate

    model = tmp_path / "strip.toml"
    model.write_text(STRIP, encoding="utf-8")
    data = tmp_path / "data.csv"
    data.write_text("u_end,N\n0.25,6\n0.5,12\n", encoding="utf-8")
    figs = _Figures(monkeypatch)
    calibrate(model, data, "u_end", "N", [Param("materials.m.E", 500.0, 2000.0, 1000.0)], tmp_path / "cal",
              max_runs=2, best_run=False)
    (ax,) = figs.saved["calibration.png"]
    assert (ax["xlabel"], ax["ylabel"]) == ("u_end [mm]", "N [N]")
