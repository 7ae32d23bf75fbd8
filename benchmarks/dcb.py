"""DCB (mode I, examples/dcb_cohesive.toml) opened under displacement control to δ = 10 mm on
several meshes: speed (steps, Newton iterations, CPU and wall time) and the mesh
convergence of the answer against corrected beam theory (Williams 1989). Uses the setup of
tests/test_dcb.py (``displacement_controlled``).

    PYTHONPATH=src python benchmarks/dcb.py                 # 150, 200, 300 elements
    PYTHONPATH=src python benchmarks/dcb.py 200             # one mesh
    PYTHONPATH=src python benchmarks/dcb.py 300 --viscosity 1e-6   # with viscous regularisation
    PYTHONPATH=src python benchmarks/dcb.py 100 --relax    # unstable jumps relaxed ([steps] unstable)
    PYTHONPATH=src python benchmarks/dcb.py 200 --relax --element mitc   # the MITC9 element
    PYTHONPATH=src python benchmarks/dcb.py 100 150 200 --arc-displacement  # the prescribed opening by arc length
    PYTHONPATH=src python benchmarks/dcb.py --arc 100 [600]  # force-loaded, arc length (max steps)
    PYTHONPATH=src python benchmarks/dcb.py --arc 200 2000 --target 16  # [steps] target_iterations = 16

Printed per mesh: node spacing h, DOFs, steps, iterations, CPU and wall seconds, the peak load,
the load at the opening δ = 8 mm (interpolated along the branch), the branch's range against
beam theory at the compliance-inferred crack length, the dissipated energy against G_Ic b Δa and
the largest energy balance error along the path. With three meshes the observed order of convergence of P(δ = 8 mm) and of
the peak, p = ln(|f₁ - f₂| / |f₂ - f₃|) / ln(h₁/h₂) for the spacing ratio of the first pair
(exact for equal ratios; with unequal ones the formula of Roache (1998) with the two ratios is
used), and the order at which the largest deviation of the branch from beam theory falls. The
last column counts the states the cohesive active-set loop accepted within its consistency
tolerance (solver/newton.py ActiveSetLoop) and their largest violation (fraction of the strength).
"""
from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
import test_dcb as T  # noqa: E402

LENGTH = 150.0
OPENING = 8.0


def displacement_controlled(nx: int, viscosity: float = 0.0, relax: bool = False, element: str = "full",
                            arc: bool = False):
    """tests/test_dcb.py ``displacement_controlled`` with an optional viscous regularisation, the
    relaxation of unstable jumps (``[steps] unstable = "relax"``), another element, or (``arc``)
    the prescribed opening traced by arc length (``control = "arc_length"``: through the
    snap-backs of the front's node-by-node growth, where the opening falls)."""
    if viscosity <= 0 and not relax and element == "full" and not arc:
        return T.displacement_controlled(nx)
    from helpers import run_example

    steps = ('control = "arc_length"\nn = 100\nmax_steps = 3000 #' if arc else
             ('unstable = "relax"\n' if relax else "") + "n = 100\nadaptive = true\nincrement_max = 0.02 #")
    repl = {**T.DISPLACEMENT_CONTROL, "nx = 150": f"nx = {nx}", "factors = [0.01, 0.02, 0.05,": steps}
    if viscosity > 0:
        repl["tau_max = 30.0"] = f"tau_max = 30.0\nviscosity = {viscosity!r}"
    if element != "full":
        repl['element = "full"'] = f'element = "{element}"'
    r = run_example("dcb_cohesive", repl)
    steps = r.summary["steps"]
    return (np.array([s["probes"]["P"] for s in steps]), np.array([T.opening(s) for s in steps]), r.summary)


def load_at_opening(P: np.ndarray, d: np.ndarray, at: float) -> float:
    """P at the opening ``at``, interpolated between the states of its last crossing by an opening
    increment (the path by arc length falls back through snap-backs, so δ is not monotonic)."""
    k = np.flatnonzero((d[:-1] <= at) & (d[1:] > at))
    if not k.size:
        return math.nan
    i = int(k[-1])
    return float(P[i] + (P[i + 1] - P[i]) * (at - d[i]) / (d[i + 1] - d[i]))


def measure(nx: int, viscosity: float = 0.0, relax: bool = False, element: str = "full", arc: bool = False) -> dict:
    t0, c0 = time.perf_counter(), time.process_time()
    P, d, summary = displacement_controlled(nx, viscosity, relax, element, arc)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    pk = int(np.argmax(P))
    ratio = P[pk + 1:] / T.cbt_load_at(P[pk + 1:], d[pk + 1:])
    a_end = (d[-1] / P[-1] * T.E11 * T.B * T.H**3 / 8) ** (1 / 3) - T.chi() * T.H
    e = summary["energy"]
    return {"nx": nx, "h": LENGTH / (2 * nx), "steps": len(P),
            "iterations": sum(s["iterations"] for s in summary["steps"]), "cpu": cpu, "wall": wall,
            "P_max": float(P.max()), "P_8": load_at_opening(P, d, OPENING),
            "branch": (float(ratio.min() - 1), float(ratio.max() - 1)) if ratio.size else (math.nan, math.nan),
            "dissipated": e["dissipated_fracture"] / (T.GIC * T.B * (a_end - T.A0)) - 1,
            "balance": max((abs(s["energy"]["balance_error"]) for s in summary["steps"] if s.get("energy")),
                           default=abs(e["balance_error"])), "converged": summary["converged"],
            "falling": int(np.sum(np.diff([s["load_factor"] for s in summary["steps"]]) < 0)),
            "median": float(np.median(ratio) - 1) if ratio.size else math.nan,
            "viscous": e.get("dissipated_viscous", 0.0) / max(e["dissipated_fracture"], 1e-300),
            "relaxed": len([e for e in summary.get("relaxations", [])
                            if e["debonded_fraction_after"] > e["debonded_fraction_before"]]),
            "accepted": summary.get("active_set", {}).get("accepted_within_tolerance", 0),
            "violation": summary.get("active_set", {}).get("largest_violation", 0.0)}


def order(h: list[float], f: list[float]) -> float:
    """Observed order of convergence from three solutions on spacings h[0] > h[1] > h[2]
    (Roache 1998 / Celik et al. 2008: fixed-point iteration for unequal refinement ratios)."""
    r21, r32 = h[1] / h[2], h[0] / h[1]  # 1 = finest
    e21, e32 = f[1] - f[2], f[0] - f[1]
    if e21 == 0 or e32 == 0 or e21 * e32 < 0:
        return math.nan  # not monotone: no asymptotic order
    p = abs(math.log(abs(e32 / e21))) / math.log(r21)
    for _ in range(100):
        q = math.log((r21**p - 1) / (r32**p - 1))
        p = abs(math.log(abs(e32 / e21)) + q) / math.log(r21)
    return p


def arc_length(nx: int, max_steps: int, target: int | None = None) -> dict:
    """The force-loaded DCB (the example's edge loads) traced by arc length with the dissipation
    constraint, from the start through the peak and the propagation branch, at most
    ``max_steps`` increments: steps, Newton iterations (all attempts), the iterations of the
    attempts that failed and were cut (the step's total minus the accepted attempt's cannot be
    separated from summary.json, so the count of cut increments is printed), CPU and wall time,
    the peak and the last load and why the path ended. ``target``: ``[steps] target_iterations``
    (the step-size control's iterations per increment; None: the default, 8)."""
    from helpers import run_example

    t0, c0 = time.perf_counter(), time.process_time()
    extra = f"target_iterations = {target}\n" if target is not None else ""
    r = run_example("dcb_cohesive", {"nx = 150": f"nx = {nx}",
                                     "factors = [0.01, 0.02, 0.05,": f'control = "arc_length"\nn = 50\nmax_steps = {max_steps}\n{extra}#'})
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    st = r.summary["steps"]
    P = np.array([s["probes"]["P"] for s in st])
    e = r.summary["energy"]
    return {"nx": nx, "steps": len(st), "iterations": sum(s["iterations"] for s in st),
            "cut": sum(1 for s in st if s["bisections"]), "cpu": cpu, "wall": wall, "P_max": float(P.max()),
            "P_end": float(P[-1]), "opening_end": float(T.opening(st[-1])), "converged": r.summary["converged"],
            "balance": e["balance_error"], "message": (r.message or "")[:160]}


def main(argv: list[str]) -> None:
    if "--arc" in argv:  # python benchmarks/dcb.py --arc 100 [max_steps] [--target N]
        target = None
        if "--target" in argv:
            i = argv.index("--target")
            target = int(argv[i + 1])
            argv = argv[:i] + argv[i + 2:]
        i = argv.index("--arc")
        nx = int(argv[i + 1])
        max_steps = int(argv[i + 2]) if len(argv) > i + 2 else 600
        os.environ.setdefault("LAYERSHELL_THREADS", "1")
        m = arc_length(nx, max_steps, target)
        print("| elements | steps | iterations | increments cut | CPU (s) | wall (s) | P_max (N) | last P (N) | "
              "last opening (mm) | energy balance | end |")
        print("|---|---|---|---|---|---|---|---|---|---|---|")
        print(f"| {nx} | {m['steps']} | {m['iterations']} | {m['cut']} | {m['cpu']:.0f} | {m['wall']:.0f} | "
              f"{m['P_max']:.2f} | {m['P_end']:.3g} | {m['opening_end']:.2f} | {100 * m['balance']:.2f} % | "
              + ("complete" if m["converged"] else f"stopped: {m['message']}") + " |")
        return
    relax = "--relax" in argv
    arc = "--arc-displacement" in argv
    element = "full"
    if "--element" in argv:
        i = argv.index("--element")
        element = argv[i + 1]
        argv = argv[:i] + argv[i + 2:]
    argv = [a for a in argv if a not in ("--relax", "--arc-displacement")]
    viscosity = 0.0
    if "--viscosity" in argv:
        i = argv.index("--viscosity")
        viscosity = float(argv[i + 1])
        argv = argv[:i] + argv[i + 2:]
    meshes = [int(a) for a in argv] or [150, 200, 300]
    os.environ.setdefault("LAYERSHELL_THREADS", "1")
    print("| elements | h (mm) | steps | iterations | CPU (s) | wall (s) | P_max (N) | P(δ = 8 mm) (N) | "
          "branch vs beam theory | dissipated vs G_Ic b Δa | energy balance (largest) | sets accepted (largest violation) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for nx in meshes:
        m = measure(nx, viscosity, relax, element, arc)
        rows.append(m)
        lo, hi = m["branch"]
        print(f"| {nx} | {m['h']:.3g} | {m['steps']} | {m['iterations']} | {m['cpu']:.0f} | {m['wall']:.0f} | "
              f"{m['P_max']:.2f} | {m['P_8']:.2f} | {100 * lo:+.1f} … {100 * hi:+.1f} % | "
              f"{100 * m['dissipated']:+.1f} % | {100 * m['balance']:.1f} %"
              + ("" if m["converged"] else " (stopped)")
              + (f", viscous {100 * m['viscous']:.2f} % of fracture" if viscosity > 0 or relax else "")
              + (f", {m['relaxed']} jumps relaxed" if relax else "")
              + (f", λ falls in {m['falling']} increments, branch median {100 * m['median']:+.1f} %" if arc else "")
              + f" | {m['accepted']} ({m['violation']:.1e}) |", flush=True)
    if len(rows) == 3:
        h = [m["h"] for m in rows]
        for key in ("P_max", "P_8"):
            f = [m[key] for m in rows]
            print(f"{key}: successive differences {f[1] - f[0]:+.3f}, {f[2] - f[1]:+.3f} N; "
                  f"observed order {order(h, f):.2f}")
        dev = [max(abs(v) for v in m["branch"]) for m in rows]  # against beam theory (the reference)
        print("largest branch deviation from beam theory: " + ", ".join(f"{100 * v:.2f} %" for v in dev)
              + "; orders " + ", ".join(f"{math.log(dev[i] / dev[i + 1]) / math.log(h[i] / h[i + 1]):.2f}"
                                        for i in range(2)))


if __name__ == "__main__":
    main(sys.argv[1:])
