"""Standard thin-shell locking benchmarks (MacNeal & Harder 1985; Belytschko et al. 1985):

* Scordelis-Lo roof, quarter model: R = 25, L = 50, t = 0.25, 80° arc, E = 4.32e8, ν = 0,
  self-weight 90 per area, rigid end diaphragms; vertical displacement at the free-edge
  midpoint, reference 0.3024. The self-weight is a body force (90/t per volume, the default
  ``load="volume"``; 3D solid 0.30148, ``SCORDELIS_3D``). ``load="outer"`` applies the 90 per
  middle-surface area on the outer (reference) face instead: 1.66 % more flexible (3D 0.30648),
  since the load's tangential component then acts t/2 off the middle surface.
* Pinched cylinder with end diaphragms, octant: R = 300, L = 600, t = 3, E = 3e6, ν = 0.3,
  P = 1 (P/4 on the octant); radial displacement under the load, reference 1.8248e-5.

    python examples/shell_benchmarks.py [--element mitc|full] [--d 2] [--n 4 8 16] [--load volume|outer]

Both are geometrically linear, one layer; the reference face is the outer face (``normal =
"inward"``), the displacement is evaluated on the middle surface (Θ³ = t/2). Rigid diaphragm:
x and z of every director fixed (u_x = u_z = 0 and no rotation about the cylinder axis).
"""
from __future__ import annotations

import argparse

import numpy as np

from layershell.element.shape import NODE_XI
from layershell.io.build import build, parse
from layershell.results import evaluate_points
from layershell.runner import run

SCORDELIS_REF = 0.3024
PINCHED_REF = 1.8248e-5
# The Scordelis-Lo roof as a 3D linear-elastic solid (benchmarks/scordelis_solid.py, docs/vs_solid.md
# §3: quadratic hexahedra graded towards the free edge, Richardson-extrapolated, ± 0.00002): the
# self-weight as a body force (load="volume"), and the same 90 per middle-surface area applied on
# the outer face (load="outer"). layershell's MITC9 element with
# d = 3 on the graded mesh gives both to 1e-6.
SCORDELIS_3D = {"volume": 0.30148, "outer": 0.30648}


def _model(n: int, element: str, d: int, R: float, t: float, a0: float, a1: float, width: float, E: float,
           nu: float, supports: str, loads: str) -> str:
    return f"""
[model]
nonlinear = false
element = "{element}"
[mesh]
type = "cylinder"
radius = {R + t / 2}
angle_start = {a0}
angle_end = {a1}
width = {width}
n_arc = {n}
n_width = {n}
normal = "inward"
axis = "y"
[materials.m]
type = "isotropic"
E = {E}
nu = {nu}
[[layers]]
name = "shell"
material = "m"
thickness = {t}
directors = {d}
{supports}
{loads}
[steps]
n = 1
"""


def _mid_displacement(res, point, t: float) -> np.ndarray:
    """Displacement of the middle surface (Θ³ = t/2) at the mesh node nearest to ``point``."""
    model = res.problem.model
    mesh = model.mesh
    node = int(np.argmin(np.linalg.norm(mesh.nodes - np.asarray(point), axis=1)))
    el, loc = np.argwhere(mesh.elements == node)[0]
    ps = evaluate_points(model, res.problem.dm, res.u, np.array([el]), NODE_XI[loc, 0], NODE_XI[loc, 1],
                         np.array([t / 2]))
    return ps.u[0]


SCORDELIS_R, SCORDELIS_T, SCORDELIS_L = 25.0, 0.25, 50.0


def scordelis_lo_spec(n: int, element: str = "mitc", d: int = 2, load: str = "volume"):
    """The built (not yet run) n × n quarter model of the Scordelis-Lo roof: the mesh's nodes may
    still be moved (benchmarks/distortion.py) before ``run``.

    load: ``"volume"`` (default) the self-weight as a body force 90/t per volume (90 per
    middle-surface area); ``"outer"`` 90 R/R_o per area of the outer (reference) face. They differ by
    1.6 % (benchmarks/scordelis_solid.py, docs/vs_solid.md §3): the vertical load's tangential
    component acting t/2 off the middle surface."""
    R, t, L = SCORDELIS_R, SCORDELIS_T, SCORDELIS_L
    Ro = R + t / 2
    supports = """
[[supports]]
type = "fix"
where = "near(y, 0)"
directors = "all"
components = ["x", "z"]
[[supports]]
type = "symmetry"
where = "near(y, 25)"
normal = [0, 1, 0]
[[supports]]
type = "symmetry"
where = "near(x, 0)"
normal = [1, 0, 0]
"""
    if load == "outer":  # self-weight 90 per middle-surface area, applied on the outer (reference) face: × R / Ro
        loads = f"""
[[loads]]
type = "surface"
direction = [0, 0, -1]
magnitude = {90.0 * R / Ro!r}
"""
    elif load == "volume":  # 90 / t per volume: 90 per middle-surface area (∫ μ dΘ³ over the thickness)
        loads = f"""
[[loads]]
type = "volume"
layer = "shell"
value = [0, 0, {-90.0 / t!r}]
"""
    else:
        raise ValueError(f"load: 'outer' or 'volume', not {load!r}")
    return build(parse(_model(n, element, d, R, t, 50.0, 90.0, L / 2, 4.32e8, 0.0, supports, loads), "scordelis.toml"))


def scordelis_lo_deflection(res) -> float:
    """Vertical deflection (positive down) of a run of ``scordelis_lo_spec`` at the free-edge
    midpoint (the node nearest to it, on the middle surface)."""
    t, Ro, a = SCORDELIS_T, SCORDELIS_R + SCORDELIS_T / 2, np.deg2rad(50.0)
    return -float(_mid_displacement(res, [Ro * np.cos(a), SCORDELIS_L / 2, Ro * np.sin(a)], t)[2])


def scordelis_lo(n: int, element: str = "mitc", d: int = 2, load: str = "volume") -> float:
    """Vertical deflection (positive down) at the free-edge midpoint of the n × n quarter model
    (``load``: see :func:`scordelis_lo_spec`)."""
    res = run(scordelis_lo_spec(n, element, d, load), None, write_vtu=False)
    assert res.converged, res.message
    return scordelis_lo_deflection(res)


def pinched_cylinder(n: int, element: str = "mitc", d: int = 2) -> float:
    """Radial inward displacement under the load of the n × n octant model."""
    R, t, L = 300.0, 3.0, 600.0
    Ro = R + t / 2
    supports = """
[[supports]]
type = "fix"
where = "near(y, 0)"
directors = "all"
components = ["x", "z"]
[[supports]]
type = "symmetry"
where = "near(y, 300)"
normal = [0, 1, 0]
[[supports]]
type = "symmetry"
where = "near(x, 0)"
normal = [1, 0, 0]
[[supports]]
type = "symmetry"
where = "near(z, 0)"
normal = [0, 0, 1]
"""
    loads = f"""
[[loads]]
type = "nodal"
point = [0, 300, {Ro}]
value = [0, 0, -0.25]
"""
    spec = build(parse(_model(n, element, d, R, t, 0.0, 90.0, L / 2, 3e6, 0.3, supports, loads), "pinched.toml"))
    res = run(spec, None, write_vtu=False)
    assert res.converged, res.message
    return -float(_mid_displacement(res, [0.0, L / 2, Ro], t)[2])


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--element", default="mitc")
    ap.add_argument("--d", type=int, default=2)
    ap.add_argument("--n", type=int, nargs="+", default=[4, 8, 16])
    ap.add_argument("--load", choices=("volume", "outer"), default="volume",
                    help="Scordelis-Lo: the self-weight as a body force (default) or 90 per area on the outer face")
    a = ap.parse_args()
    for n in a.n:
        w = scordelis_lo(n, a.element, a.d, a.load)
        print(f"Scordelis-Lo {n}x{n} {a.element} d={a.d} load={a.load}: {w:.5f} "
              f"({100 * (w / SCORDELIS_REF - 1):+.2f} % of {SCORDELIS_REF}, "
              f"{100 * (w / SCORDELIS_3D[a.load] - 1):+.2f} % of the 3D value {SCORDELIS_3D[a.load]})", flush=True)
    for n in a.n:
        w = pinched_cylinder(n, a.element, a.d)
        print(f"pinched cylinder {n}x{n} {a.element} d={a.d}: {w:.5e} ({100 * (w / PINCHED_REF - 1):+.2f} %)",
              flush=True)


if __name__ == "__main__":
    main()
