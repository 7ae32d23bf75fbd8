"""Scordelis-Lo roof as a 3D linear-elastic solid (scikit-fem quadratic hexahedra): the converged
deflection of the 3D problem, against which layershell's converged value is checked
(docs/vs_solid.md §3).

    pip install -e ".[bench]"            # scikit-fem, only for this benchmark
    python benchmarks/scordelis_solid.py [--n 8 16 32 64] [--m 1 2 4] [--loads body outer middle]
                                         [--grade 2 1] [--variants] [--shell 8 16 32]

Quarter model exactly as ``examples/shell_benchmarks.py::scordelis_lo``: cylinder axis y, radius of
the middle surface R = 25, thickness t = 0.25 (r ∈ [R - t/2, R + t/2]), x = r cos θ, z = r sin θ
with θ ∈ [50°, 90°] (crown θ = 90°, x = 0; free edge θ = 50°, 40° from the crown),
0 ≤ y ≤ L/2 = 25. E = 4.32e8, ν = 0. Self-weight 90 per unit middle-surface area in -z, as a body
force 90/t per unit volume (∫(r/R) dr over the thickness = t; ``body``), as a traction on the
outer face (``outer``, as the example applies it by default) or on the middle surface inside the
solid (``middle``). Supports: rigid diaphragm u_x = u_z = 0 on the whole end face y = 0; symmetry
u_y = 0 on y = L/2 and u_x = 0 on the crown x = 0. Quantity: -u_z at the free-edge midpoint
(r = R, θ = 50°, y = L/2), a node of every mesh (also printed on the inner and outer face).

Mesh: n elements along the arc and n along y (as the shell's n × n), m through the thickness; the
27 nodes of every element lie on the exact cylinder (isoparametric quadratic geometry).
``--grade 2 1`` grades the elements towards the free edge (θ = 50° + 40° (i/n)²): its boundary
layer makes uniform meshes converge slowly (observed order 1.8 from n = 16 to 64, against 3.9
graded). The element matrices, the solver (layershell's ``LinearSolver``, PARDISO) and the
Richardson extrapolation come from ``benchmarks/vs_solid.py``; all loads of a mesh share one
factorisation.

``--variants`` also solves the solid with the diaphragm only on the middle-surface line of the end
section. ``--shell`` runs layershell's MITC9 element (d = 2, 3; the example's outer-face load and a
volume load) on the same (graded) meshes.

Result (docs/vs_solid.md §3): 0.30148 with the body force (-0.30 % of the conventional 0.3024),
0.30648 with the load on the outer face, ± 0.00002; layershell MITC9 with d = 3 on graded meshes
0.301475 and 0.306483.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import vs_solid as vs  # noqa: E402  (exits with a message without scikit-fem)
from skfem import LinearForm, asm  # noqa: E402

import layershell.mesh as meshmod  # noqa: E402

sys.path.insert(0, str(vs.ROOT / "examples"))
import shell_benchmarks as sb  # noqa: E402

R, T, L = 25.0, 0.25, 50.0
E, NU = 4.32e8, 0.0
Q = 90.0  # self-weight per unit middle-surface area
THETA_EDGE, THETA_CROWN = np.deg2rad(50.0), np.deg2rad(90.0)
SCORDELIS_REF = 0.3024  # MacNeal & Harder (1985)
DEEP_SHELL = 0.3086  # Scordelis & Lo (1964), deep-shell theory


def _roof(p: np.ndarray) -> np.ndarray:
    """(r, θ, y) → (x, y, z) = (r cos θ, y, r sin θ), as layershell's cylinder mesh with axis y."""
    return np.vstack([p[0] * np.cos(p[1]), p[2], p[0] * np.sin(p[1])])


LOADS = ("body", "outer", "middle")


@dataclass
class SolidRun:
    n: int
    m: int
    load: str
    dofs: int
    seconds: float  # mesh, stiffness, loads and one solve for all the loads of the call
    w: float  # -u_z at the free-edge midpoint, middle surface r = R
    w_inner: float  # ... on the inner face r = R - t/2
    w_outer: float  # ... on the outer face r = R + t/2


def _graded(a: float, b: float, n: int, power: float) -> np.ndarray:
    """n + 1 points from a to b, a + (b - a) s^power for s uniform: refined towards a for power > 1.
    The map is fixed, so that meshes of n and 2n are nested (Richardson)."""
    return a + (b - a) * np.linspace(0.0, 1.0, n + 1) ** power


def _mesh(n: int, m: int, grade: tuple[float, float] = (1.0, 1.0)) -> vs.Solid:
    """grade: powers of the grading towards the free edge θ = 50° and towards the diaphragm y = 0."""
    return vs.Solid(np.linspace(R - T / 2, R + T / 2, m + 1), _graded(THETA_EDGE, THETA_CROWN, n, grade[0]),
                    _graded(0.0, L / 2, n, grade[1]), _roof,
                    lambda c: (np.full(c.shape[1], E), np.full(c.shape[1], NU)))


def load_vector(s: vs.Solid, load: str) -> np.ndarray:
    """Consistent nodal loads of the self-weight, 90 per unit middle-surface area in -z.

    ``"body"``: 90/t per unit volume (the 3D self-weight; ∫ (r/R) dr over the thickness = t).
    ``"outer"``: a traction 90 R/R_o per unit area of the outer face r = R_o = R + t/2, as
    examples/shell_benchmarks.py applies it by default (layershell's reference face).
    ``"middle"``: a traction 90 per unit area of the middle surface r = R inside the solid (the load
    of shell theory); r = R is a plane of nodes for any m (element faces or mid-nodes).
    """
    if load == "body":
        f = np.zeros(s.ndof)
        f[2::3] = -(Q / T) * asm(LinearForm(lambda v, w: v), s.basis)  # ∫ N_a dV on the curved mesh
        return f
    if load in ("outer", "middle"):
        # 90 R/r_f per physical area of r = r_f, which maps (θ, y) with dA = r_f dθ dy: 90 R per dθ dy
        r_f = R + T / 2 if load == "outer" else R
        return s.face_load(0, r_f, lambda p: np.stack([0 * p[0], 0 * p[0], np.full(p.shape[1], -Q * R)]))
    raise ValueError(f"load: one of {LOADS}, not {load!r}")


def solid_scordelis(n: int, m: int, loads=("body",), diaphragm: str = "face",
                    grade: tuple[float, float] = (1.0, 1.0)) -> dict[str, SolidRun]:
    """The quarter roof with n × n elements in plan and m through the thickness, one factorisation
    for all ``loads`` (see :func:`load_vector`).

    diaphragm: ``"face"`` (u_x = u_z = 0 on the whole end face y = 0: the rigid diaphragm, and what
    layershell's support of every director in x and z amounts to) or ``"mid"`` (only on the
    middle-surface line r = R of the end face: the section may rotate about the cylinder axis).
    grade: powers of the element grading towards the free edge and towards the diaphragm
    (:func:`_graded`; (1, 1): uniform).
    """
    t0 = time.perf_counter()
    s = _mesh(n, m, grade)
    K = s.stiffness()
    F = np.column_stack([load_vector(s, ld) for ld in loads])
    par = s.param  # node parameter coordinates (r, θ, y), in the scalar DOF order
    end = np.isclose(par[2], 0.0)
    if diaphragm == "mid":
        end &= np.isclose(par[0], R)
    elif diaphragm != "face":
        raise ValueError(diaphragm)
    end = np.flatnonzero(end)
    sym_y = np.flatnonzero(np.isclose(par[2], L / 2))
    crown = np.flatnonzero(np.isclose(par[1], THETA_CROWN))
    fixed = np.unique(np.concatenate([3 * end, 3 * end + 2, 3 * sym_y + 1, 3 * crown]))
    free = np.setdiff1d(np.arange(s.ndof), fixed)
    U = np.zeros_like(F)
    U[free] = np.asarray(vs.LinearSolver("auto").solve(K[free][:, free], F[free])).reshape(free.size, -1)
    seconds = time.perf_counter() - t0
    out = {}
    for k, ld in enumerate(loads):
        w = []
        for r in (R, R - T / 2, R + T / 2):
            a = np.flatnonzero(np.isclose(par[0], r) & np.isclose(par[1], THETA_EDGE) & np.isclose(par[2], L / 2))
            assert a.size == 1
            w.append(-float(U[3 * a[0] + 2, k]))
        out[ld] = SolidRun(n, m, ld, free.size, seconds, *w)
    return out


def check_geometry(n: int = 4, m: int = 1) -> None:
    """The DOF locations are the mapped parameter nodes and lie on the exact cylinder."""
    s = _mesh(n, m)
    assert np.allclose(s.basis.doflocs, _roof(s.param))
    assert np.allclose(np.hypot(s.basis.doflocs[0], s.basis.doflocs[2]), s.param[0])


def _graded_nodes(u: np.ndarray, n: int, power: float) -> np.ndarray:
    """The node parameters u = j / (2n) of a uniform quad9 grid moved as the solid's grid: element
    ends to (i/n)^power, mid-side nodes to the middle of their element (as :func:`_graded` and
    MeshHex2's mid-nodes)."""
    j = np.rint(u * 2 * n).astype(int)
    ends = np.linspace(0.0, 1.0, n + 1) ** power
    return np.where(j % 2 == 0, ends[j // 2], 0.5 * (ends[(j - 1) // 2] + ends[(j + 1) // 2]))


@contextlib.contextmanager
def _graded_cylinder(n: int, grade: tuple[float, float]):
    """layershell's ``cylinder`` mesh (axis y, arc from 50° to 90°) graded like the solid: the nodes
    are moved along the arc and the axis; the library is unchanged."""
    orig = meshmod.cylinder

    def cylinder(radius, angle_start, angle_end, width, n_arc, n_width, normal="inward", axis="z"):
        mesh = orig(radius, angle_start, angle_end, width, n_arc, n_width, normal, axis)
        assert axis == "y" and n_arc == n_width == n
        x, y, z = mesh.nodes.T
        a0, a1 = np.deg2rad(angle_start), np.deg2rad(angle_end)
        phi = a0 + (a1 - a0) * _graded_nodes((np.arctan2(z, x) - a0) / (a1 - a0), n, grade[0])
        r = np.hypot(x, z)
        mesh.nodes[:] = np.column_stack([r * np.cos(phi), width * _graded_nodes(y / width, n, grade[1]),
                                         r * np.sin(phi)])
        return mesh

    meshmod.cylinder = cylinder
    try:
        yield
    finally:
        meshmod.cylinder = orig


def shell_scordelis(n: int, element: str = "mitc", d: int = 2, load: str = "outer",
                    grade: tuple[float, float] = (1.0, 1.0)) -> float:
    """layershell's deflection (examples/shell_benchmarks.py) on the n × n mesh graded like the
    solid's (``grade`` = (1, 1): the example's uniform mesh)."""
    with _graded_cylinder(n, grade):
        return sb.scordelis_lo(n, element, d, load)


def extrapolate(values: dict[tuple[int, int], float], ns: list[int], ms: list[int]) -> dict:
    """Richardson in n (for each m) and in m (for each n), and the two-way limit.

    Errors are taken additive, w(n, m) ≈ w* + a n^-p + b m^-q: the in-plane limit w(∞, m) from the
    three finest n at each m, then Richardson of those limits in m (three m values) or, with two,
    with the order observed on the finest n.
    """
    out: dict = {"in_plane": {}, "thickness": {}}
    for m in ms:
        q = [values[(n, m)] for n in ns[-3:] if (n, m) in values]
        if len(q) == 3:
            out["in_plane"][m] = vs.richardson(q)
    for n in ns:
        q = [values[(n, m)] for m in ms[-3:] if (n, m) in values]
        if len(q) == 3:
            out["thickness"][n] = vs.richardson(q)
    lim = [out["in_plane"][m][0] for m in ms[-3:] if m in out["in_plane"]]
    if len(lim) == 3:
        out["limit"] = vs.richardson(lim)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--n", type=int, nargs="+", default=[8, 16, 32], help="elements along the arc and along y")
    ap.add_argument("--m", type=int, nargs="+", default=[1, 2, 4], help="elements through the thickness")
    ap.add_argument("--loads", nargs="+", default=["body", "outer"], choices=LOADS,
                    help="body force (self-weight), load on the outer face (layershell's example), on the middle "
                         "surface")
    ap.add_argument("--grade", type=float, nargs=2, default=[1.0, 1.0], metavar=("ARC", "Y"),
                    help="grading powers towards the free edge and towards the diaphragm (1 1: uniform)")
    ap.add_argument("--max-dofs", type=int, default=300_000, help="skip larger solids")
    ap.add_argument("--shell", type=int, nargs="*", default=[],
                    help="also layershell MITC9 on these n × n meshes, d = 2 and 3, both loads")
    ap.add_argument("--variants", action="store_true",
                    help="diaphragm only on the middle-surface line (finest n ≤ 32, m = 2)")
    a = ap.parse_args()
    check_geometry()
    print(f"Scordelis-Lo roof, 3D solid (quadratic hexahedra), grading powers {a.grade}; "
          f"load average {os.getloadavg()[0]:.1f}")
    vals: dict[str, dict[tuple[int, int], float]] = {ld: {} for ld in a.loads}
    for m in a.m:
        for n in a.n:
            if 3 * (2 * n + 1) ** 2 * (2 * m + 1) > a.max_dofs:
                continue
            for ld, r in solid_scordelis(n, m, a.loads, grade=tuple(a.grade)).items():
                vals[ld][(n, m)] = r.w
                print(f"  solid n={n:3d} m={m} load={ld:6s}: dofs={r.dofs:7d} t={r.seconds:6.1f} s  w={r.w:.6f} "
                      f"(inner face {r.w_inner:.6f}, outer face {r.w_outer:.6f})", flush=True)
    for ld in a.loads:
        ex = extrapolate(vals[ld], sorted(a.n), sorted(a.m))
        for m, (v, p) in ex["in_plane"].items():
            print(f"  load={ld}: Richardson in n at m={m}: {v:.6f} (observed order {p:.2f})")
        for n, (v, p) in ex["thickness"].items():
            print(f"  load={ld}: Richardson in m at n={n}: {v:.6f} (observed order {p:.2f})")
        if "limit" in ex:
            v, p = ex["limit"]
            print(f"  load={ld}: two-way limit {v:.6f} (order in m {p:.2f}); vs 0.3024 "
                  f"{100 * (v / SCORDELIS_REF - 1):+.2f} %, vs 0.3086 {100 * (v / DEEP_SHELL - 1):+.2f} %", flush=True)
    if a.variants:
        n = max(k for k in a.n if k <= 32)
        for dia in ("face", "mid"):
            for ld, r in solid_scordelis(n, 2, a.loads, dia, tuple(a.grade)).items():
                print(f"  variant n={n} m=2 load={ld:6s} diaphragm={dia:4s}: w={r.w:.6f} "
                      f"(inner face {r.w_inner:.6f}, outer face {r.w_outer:.6f})", flush=True)
    if a.shell:
        for load in ("volume", "outer"):
            for d in (2, 3):
                for n in a.shell:
                    t0 = time.perf_counter()
                    w = shell_scordelis(n, "mitc", d, load, tuple(a.grade))
                    print(f"  layershell MITC9 load={load:6s} n={n:3d} d={d}: w={w:.6f} "
                          f"({time.perf_counter() - t0:.1f} s)", flush=True)


if __name__ == "__main__":
    main()
