"""Mesh-distortion sensitivity of the MITC9 (``element = "mitc"``) and the fully integrated
(``element = "full"``) element on thin plates and shells.

    python benchmarks/distortion.py [--cases plate roof] [--n 4 8 16 32] [--slenderness 100 1000]
        [--meshes regular straight curved] [--elements mitc full] [--amount 0.2] [--seed 5] [--d 2]

Cases (both linear, one layer, d = 2 directors):

* ``plate``: clamped square plate a × a (a = 1, a/t = 100 and 1000, E = 1e6, ν = 0.3) under a
  uniform load q on its reference face, full model n × n; every director of every boundary node
  fixed. Centre deflection on the middle surface (Θ³ = t/2) over the Kirchhoff value
  w_K = 0.00126532 q a⁴ / D (Timoshenko & Woinowsky-Krieger, D = E t³ / 12(1 − ν²)), column
  ``w/w_K``, and over the element's own regular-mesh value on the finest ``--n`` (``w/w_reg``,
  the reference that includes transverse shear: at a/t = 100 the Mindlin deflection is larger
  than w_K; only printed when the finest regular mesh is run).
* ``roof``: the Scordelis-Lo roof of examples/shell_benchmarks.py (quarter model, n × n),
  self-weight as a body force, vertical deflection at the free-edge midpoint over 0.30148, the
  converged 3D value (benchmarks/scordelis_solid.py; the conventional 0.3024 is 0.3 % above).

Meshes (fixed random seed ``--seed``, one generator per run, so a run does not depend on the
others; the plate's centre node and all boundary nodes stay in place):

* ``regular``: the generated mesh.
* ``straight``: the inner element corners moved in x and y by up to ± ``amount`` × the element
  size (uniform random), mid-side and centre nodes on each element's bilinear map (straight
  edges, mid-side nodes at the edge midpoints: a 4-node mesh converted to quad9).
* ``curved``: every inner node (corner, mid-side, centre) moved by up to ± ``amount`` × the
  node spacing (half the element size): curved element edges, mid-side nodes off the midpoints.
  For the roof the moves are in the angle and the axial coordinate, so nodes stay on the
  cylinder. The moves of the nodes of an element that ``Mesh.check`` would reject (signed area
  Jacobian min/max < 0.05, which 0.2 reaches now and then) are drawn again from the same
  generator.

Prints one line per run (case, mesh, element, n, ratio, seconds, elements redrawn) while running,
then the table of all ratios (a line per case, mesh and element, a column per n) and, for the
plate, the same over w_reg. The default run (72 solves) takes about 1 minute on a 2-core
machine with ``LAYERSHELL_THREADS=1`` (the 32 × 32 meshes most of it).

Measured 26 Nov 2026, default options (d = 2, amount 0.2, seed 5), 2-core Xeon shared with
other jobs, 52 s; w/w_K for the plate, w/0.30148 for the roof (self-weight as a body force,
re-measured after that default changed), MITC9 / full:

| case | mesh | 4 × 4 | 8 × 8 | 16 × 16 | 32 × 32 |
|---|---|---|---|---|---|
| plate a/t = 100 | regular | 0.970 / 0.770 | 0.980 / 0.937 | 0.990 / 0.982 | 0.996 / 0.995 |
| plate a/t = 100 | straight | 0.946 / 0.729 | 0.978 / 0.929 | 0.990 / 0.980 | 0.996 / 0.994 |
| plate a/t = 100 | curved | 0.560 / 0.222 | 0.787 / 0.532 | 0.931 / 0.764 | 0.978 / 0.894 |
| plate a/t = 1000 | regular | 0.968 / 0.762 | 0.978 / 0.930 | 0.988 / 0.977 | 0.994 / 0.991 |
| plate a/t = 1000 | straight | 0.686 / 0.187 | 0.934 / 0.778 | 0.982 / 0.956 | 0.993 / 0.989 |
| plate a/t = 1000 | curved | 0.027 / 0.004 | 0.129 / 0.025 | 0.291 / 0.094 | 0.532 / 0.274 |
| roof | regular | 0.995 / 0.816 | 0.998 / 0.983 | 0.998 / 0.997 | 0.999 / 0.999 |
| roof | straight | 0.993 / 0.795 | 0.998 / 0.982 | 0.998 / 0.997 | 0.999 / 0.999 |
| roof | curved | 0.727 / 0.476 | 0.862 / 0.695 | 0.942 / 0.829 | 0.981 / 0.923 |

Curved-edge elements redrawn: 5 at 16 × 16 and 10 at 32 × 32 (plate), 1 at 8 × 8 and 12 at
32 × 32 (roof). Over w_reg (the element's regular 32 × 32 value: MITC9 0.996 / 0.994 of w_K
at a/t = 100 / 1000, full 0.995 / 0.991) every plate ratio rises by at most 0.9 % (e.g. a/t =
1000, 4 × 4: MITC9 regular 0.974, straight 0.690, curved 0.027). On regular meshes both
elements approach w_K from below about linearly in the element size, also at a/t = 100 where
transverse shear makes the Mindlin value slightly larger than w_K. Most of that is the clamp:
it fixes every director, so also the thickness stretch at the edge (a 3D clamp), which
stiffens the first row of elements through the Poisson effect; with the highest director left
free at the edge MITC9 gives 0.9997 w_K at 16 × 16, a/t = 1000 (0.9884 clamped).

The draw matters on coarse meshes: over seeds 0-9 (a/t = 1000, MITC9 / full) straight 4 × 4
spans 0.59-0.77 / 0.08-0.32, straight 8 × 8 0.93-0.94 / 0.72-0.82, curved 4 × 4 0.022-0.055 /
0.003-0.009, curved 8 × 8 0.10-0.16 / 0.019-0.029; roof curved 4 × 4 0.64-0.78 / 0.41-0.52, 8 × 8
0.84-0.90 / 0.69-0.75. In none of them is seed 5 the best or the worst draw.

Reading: on regular meshes MITC9 is locking-free (a/t = 1000, 4 × 4: 3 % below w_K), the full
element locks (−24 %). Moving the element corners with straight edges costs MITC9 little at
a/t = 100 and on the roof, but on the thin plate 29 % of its regular-mesh value at 4 × 4 and
4.5 % at 8 × 8 (full element 75 % and 16 %). Curved edges (mid-side nodes off the edge
midpoints) bring the locking back for both elements, the worse the thinner the shell: at
a/t = 1000 MITC9 keeps 3 % (4 × 4), 13 % (8 × 8) and 53 % (32 × 32) of the deflection, the
full element 0.4 %, 2.5 % and 27 %. Regular meshes, or straight element edges with the mid-side
nodes at the edge midpoints, are the safe choice for thin shells; on a curved surface
"straight" means straight in the surface parameters with the mid-side nodes at the parameter
midpoints (the roof's ``straight`` mesh: MITC9 within 0.7 % of 0.30148 at 4 × 4).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from layershell.element.shape import NODE_XI
from layershell.material import Orthotropic
from layershell.mesh import Mesh, rectangle
from layershell.model import Fix, Layer, Model, SurfaceLoad
from layershell.results import evaluate_points
from layershell.runner import run
from layershell.solver.newton import load_steps
from layershell.solver.problem import Problem

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))
import shell_benchmarks as sb  # noqa: E402

KIRCHHOFF = 0.00126532  # clamped square plate, uniform load: w_centre = KIRCHHOFF q a⁴ / D
ROOF_CONVERGED = sb.SCORDELIS_3D["volume"]  # Scordelis-Lo, the 3D value (benchmarks/scordelis_solid.py)
ELEMENT_NAMES = {"mitc": "MITC9", "full": "full"}

# the four corner shape functions at the nine nodes: the bilinear map of an element
_XI, _ETA = NODE_XI[:, 0], NODE_XI[:, 1]
_N4 = 0.25 * np.stack([(1 - _XI) * (1 - _ETA), (1 + _XI) * (1 - _ETA), (1 + _XI) * (1 + _ETA),
                       (1 - _XI) * (1 + _ETA)], -1)


def _bad_elements(p: np.ndarray, elements: np.ndarray) -> np.ndarray:
    """Elements of the planar mesh ``p (n_nodes, 2)`` that ``Mesh.check`` rejects: signed area
    Jacobian min/max below ``Mesh.MIN_JACOBIAN_RATIO`` at the 3 × 3 Gauss points and the nodes."""
    jg, jn = Mesh(np.column_stack([p, np.zeros(len(p))]), elements).jacobians()
    jmin, jmax = np.minimum(jg.min(1), jn.min(1)), np.maximum(jg.max(1), jn.max(1))
    return np.flatnonzero(jmin < Mesh.MIN_JACOBIAN_RATIO * jmax)


def distort(p: np.ndarray, elements: np.ndarray, movable: np.ndarray, spacing: np.ndarray, mesh: str,
            amount: float, rng: np.random.Generator) -> tuple[np.ndarray, int]:
    """Distorted copy of the 2D nodal coordinates ``p (n_nodes, 2)`` (x, y of a plate; angle and
    axial coordinate of a cylinder) and the number of elements redrawn. ``movable``: nodes that
    may move; ``spacing (2,)``: the node spacing (half the element size) per coordinate. Module
    docstring: ``straight``, ``curved``; with ``curved`` the moves of the nodes of an element that
    ``Mesh.check`` would reject are drawn again (from the same generator) until none is left."""
    p = p.copy()
    redrawn = 0
    if mesh == "curved":
        move = np.zeros_like(p)
        nodes = np.flatnonzero(movable)
        for _ in range(1000):
            move[nodes] = amount * spacing * rng.uniform(-1, 1, (nodes.size, 2))
            bad = _bad_elements(p + move, elements)
            if not bad.size:
                break
            redrawn += bad.size
            nodes = np.intersect1d(elements[bad], np.flatnonzero(movable))
        else:
            raise RuntimeError("no valid curved-edge distortion found")
        p += move
    elif mesh == "straight":
        corners = np.unique(elements[:, :4])
        corners = corners[movable[corners]]
        p[corners] += 2 * amount * spacing * rng.uniform(-1, 1, (corners.size, 2))
        for el in elements:
            p[el[4:]] = _N4[4:] @ p[el[:4]]
    elif mesh != "regular":
        raise ValueError(mesh)
    return p, redrawn


def plate(n: int, slenderness: float, mesh: str, element: str, amount: float = 0.2, seed: int = 5,
          d: int = 2) -> tuple[float, int]:
    """Centre deflection of the clamped square plate (a = 1, t = a / slenderness, q = 1) over the
    Kirchhoff value, and the number of elements whose distortion was drawn again."""
    a, q, E, nu = 1.0, 1.0, 1e6, 0.3
    t = a / slenderness
    m = rectangle(a, a, n, n)
    x = m.nodes
    inner = (x[:, 0] > 1e-9) & (x[:, 0] < a - 1e-9) & (x[:, 1] > 1e-9) & (x[:, 1] < a - 1e-9)
    centre = np.isclose(x[:, 0], a / 2) & np.isclose(x[:, 1], a / 2)
    x[:, :2], redrawn = distort(x[:, :2], m.elements, inner & ~centre, np.full(2, a / (2 * n)), mesh,
                                amount, np.random.default_rng(seed))
    m.check()
    layer = Layer("plate", Orthotropic.isotropic(E, nu), d, np.full(m.n_nodes, t))
    model = Model(m, [layer], [(0,)], np.zeros(m.n_elements, int),
                  fixes=[Fix(np.flatnonzero(~inner), 0, tuple(range(d + 1)), (0, 1, 2))],
                  surface_loads=[SurfaceLoad(np.arange(m.n_elements), "reference", np.array([0, 0, -1.0]),
                                             lambda x, y, z: q + 0 * x)],
                  nonlinear=False, element=element)
    pb = Problem.build(model)
    st = list(load_steps(pb, np.array([1.0])))[-1]
    el, loc = np.argwhere(m.elements == int(np.flatnonzero(centre)[0]))[0]
    ps = evaluate_points(model, pb.dm, st.u, [el], NODE_XI[loc, 0], NODE_XI[loc, 1], [t / 2])
    D = E * t**3 / (12 * (1 - nu**2))
    return -float(ps.u[0, 2]) / (KIRCHHOFF * q * a**4 / D), redrawn


def roof(n: int, mesh: str, element: str, amount: float = 0.2, seed: int = 5, d: int = 2) -> tuple[float, int]:
    """Scordelis-Lo free-edge midpoint deflection over the 3D value 0.30148, and the number of
    elements whose distortion was drawn again."""
    spec = sb.scordelis_lo_spec(n, element, d)
    m: Mesh = spec.model.mesh
    X = m.nodes
    th, y, r = np.arctan2(X[:, 2], X[:, 0]), X[:, 1], np.hypot(X[:, 0], X[:, 2])
    a0, a1, half = np.deg2rad(50.0), np.deg2rad(90.0), sb.SCORDELIS_L / 2
    inner = (th > a0 + 1e-6) & (th < a1 - 1e-6) & (y > 1e-6) & (y < half - 1e-6)
    spacing = np.array([(a1 - a0) / (2 * n), half / (2 * n)])
    p, redrawn = distort(np.stack([th, y], -1), m.elements, inner, spacing, mesh, amount,
                         np.random.default_rng(seed))
    X[:] = np.stack([r * np.cos(p[:, 0]), p[:, 1], r * np.sin(p[:, 0])], -1)
    m.check()
    res = run(spec, None, write_vtu=False)
    assert res.converged, res.message
    return sb.scordelis_lo_deflection(res) / ROOF_CONVERGED, redrawn


def _table(rows: list[dict], scale: dict | None = None) -> list[str]:
    """Markdown table: a line per (case, mesh, element), a column per n; each ratio divided by
    ``scale[case, element]`` where given (rows of other cases left out)."""
    ns = sorted({r["n"] for r in rows})
    keys: list[tuple] = []
    val = {}
    for r in rows:
        k = (r["case"], r["mesh"], r["element"])
        if scale is not None and (r["case"], r["element"]) not in scale:
            continue
        if k not in keys:
            keys.append(k)
        val[k + (r["n"],)] = r["ratio"] / (scale[r["case"], r["element"]] if scale is not None else 1.0)
    out = ["| case | mesh | element | " + " | ".join(f"{n} × {n}" for n in ns) + " |",
           "|---|---|---|" + "---|" * len(ns)]
    for k in keys:
        cells = [f"{val[k + (n,)]:.3f}" if k + (n,) in val else "" for n in ns]
        out.append(f"| {k[0]} | {k[1]} | {ELEMENT_NAMES[k[2]]} | " + " | ".join(cells) + " |")
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cases", nargs="+", default=["plate", "roof"], choices=["plate", "roof"])
    ap.add_argument("--n", type=int, nargs="+", default=[4, 8, 16, 32], help="elements per side (even)")
    ap.add_argument("--slenderness", type=float, nargs="+", default=[100.0, 1000.0], help="plate a/t")
    ap.add_argument("--meshes", nargs="+", default=["regular", "straight", "curved"],
                    choices=["regular", "straight", "curved"])
    ap.add_argument("--elements", nargs="+", default=["mitc", "full"], choices=["mitc", "full"])
    ap.add_argument("--amount", type=float, default=0.2, help="node moves, in element sizes / node spacings")
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--d", type=int, default=2, help="directors")
    a = ap.parse_args()
    if "plate" in a.cases and any(n % 2 for n in a.n):
        ap.error("--n must be even (the plate's centre is a node)")
    runs = []
    for case in a.cases:
        for s in (a.slenderness if case == "plate" else [None]):
            name = f"plate a/t={s:g}" if case == "plate" else "roof"
            for mesh in a.meshes:
                for n in sorted(a.n):
                    for e in a.elements:
                        runs.append((name, s, mesh, n, e))
    rows, t_all = [], time.perf_counter()
    for name, s, mesh, n, e in runs:
        t0 = time.perf_counter()
        if s is not None:
            ratio, redrawn = plate(n, s, mesh, e, a.amount, a.seed, a.d)
        else:
            ratio, redrawn = roof(n, mesh, e, a.amount, a.seed, a.d)
        rows.append({"case": name, "mesh": mesh, "n": n, "element": e, "ratio": ratio})
        ref = "w/w_K" if s is not None else f"w/{ROOF_CONVERGED}"
        note = f", {redrawn} element(s) redrawn" if redrawn else ""
        print(f"{name} {mesh} {ELEMENT_NAMES[e]} {n}x{n}: {ref} = {ratio:.4f} ({time.perf_counter() - t0:.1f} s{note})",
              flush=True)
    # the element's own regular-mesh value on the finest mesh (plate: includes transverse shear)
    finest = max(a.n)
    reference = {(r["case"], r["element"]): r["ratio"] for r in rows
                 if r["case"].startswith("plate") and r["mesh"] == "regular" and r["n"] == finest}
    print(f"\ntotal {time.perf_counter() - t_all:.0f} s\n\nw/w_K (plate), w/{ROOF_CONVERGED} (roof):\n")
    print("\n".join(_table(rows)))
    if reference:
        print(f"\nplate, w/w_reg (w_reg: the element's own regular {finest} × {finest} value):\n")
        print("\n".join(_table(rows, reference)))

if __name__ == "__main__":
    main()
