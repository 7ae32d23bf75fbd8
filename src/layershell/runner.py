"""Run a model: load steps, probes, result files. Used by the CLI; knows nothing of argv."""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from .io.build import RunSpec
from .io.output import write_csv, write_json
from .solver.newton import ConvergenceError, load_steps
from .solver.problem import Problem


def through_thickness(spec_profile, model, dm, u):
    """Stress component along the thickness at a point: {layer name: (Θ³, values)}."""
    from .io.probes import STRESS_COMPONENTS
    from .results import evaluate_points, locate

    pr = spec_profile
    e, x, y, _ = locate(model, pr.point)
    conn = model.mesh.elements[e]
    out = {}
    from .element.shape import quad9

    N, _, _ = quad9(np.array([x]), np.array([y]))
    for k in model.stacks[model.element_stack[e]]:
        H = float(N[0] @ model.layers[k].thickness[conn])
        off = float(N[0] @ model.offset(k)[conn])
        thL = np.linspace(0.0, H, pr.points_per_layer)
        ps = evaluate_points(model, dm, u, np.full(thL.size, e), x, y, thL, np.full(thL.size, k), local_theta=True)
        T = ps.cauchy_physical if pr.measure == "cauchy" else ps.pk2_physical
        c = pr.component
        if c in STRESS_COMPONENTS:
            i, j = STRESS_COMPONENTS[c]
            v = T[:, i, j]
        elif c in ("p1", "p2", "p3"):
            v = np.linalg.eigvalsh(T)[:, ::-1][:, int(c[1]) - 1]
        else:
            dev = T - np.trace(T, axis1=1, axis2=2)[:, None, None] / 3 * np.eye(3)
            v = np.sqrt(1.5 * np.einsum("pij,pij->p", dev, dev))
        out[model.layers[k].name] = (off + thL, v)
    return out


def write_profiles(spec, problem, u, out: Path) -> dict:
    """profile_<name>.csv (Θ³ and one column per layer) and profile_<name>.png."""
    from .io.output import write_csv

    files = {}
    for pr in spec.profiles:
        cols = through_thickness(pr, spec.model, problem.dm, u)
        names = list(cols)
        rows = []
        for i, n in enumerate(names):
            th, v = cols[n]
            for t, val in zip(th, v):
                rows.append([float(t)] + [float(val) if j == i else "" for j in range(len(names))])
        write_csv(out / f"profile_{pr.name}.csv", ["theta3"] + names, rows)
        files[pr.name] = f"profile_{pr.name}.csv"
        if spec.output.plots:
            from .plots import plot_through_thickness

            plot_through_thickness(out / f"profile_{pr.name}.png", {k: (v, t) for k, (t, v) in cols.items()},
                                   f"{pr.measure} σ{pr.component}")
    return files


@dataclass
class RunResult:
    converged: bool
    summary: dict
    problem: Problem
    u: np.ndarray
    message: str = ""
    history: list[dict] = field(default_factory=list)


def run(spec: RunSpec, out: Path | None = None, progress: Callable[[int, int, float], None] | None = None,
        write_vtu: bool | None = None) -> RunResult:
    """Solve ``spec`` and (if ``out``) write summary.json, probes.csv and ParaView files."""
    t0 = time.perf_counter()
    model = spec.model
    problem = Problem.build(model)
    names = [p.name for p in spec.probes]
    summary = {
        "title": spec.source.model.title,
        "units": model.units,
        "converged": False,
        "n_elements": int(model.mesh.n_elements),
        "n_nodes": int(model.mesh.n_nodes),
        "n_dofs": int(problem.op.n_red),
        "n_dofs_full": int(problem.dm.n_full),
        "nonlinear": bool(model.nonlinear),
        "solver": spec.newton.backend,
        "wall_seconds": 0.0,
        "steps": [],
        "probes": {},
    }
    rows: list[list] = []
    vtu = spec.output.vtu if write_vtu is None else write_vtu
    pvd = None
    if out is not None:
        out = Path(out)
        out.mkdir(parents=True, exist_ok=True)
        if vtu:
            from .export import PvdWriter

            pvd = PvdWriter(out)
    u = np.zeros(problem.dm.n_full)
    message = ""
    n_steps = len(spec.load_factors)
    ctl = problem.interfaces
    if ctl is not None:
        summary["first_delamination_load_factor"] = None
        summary["debonded_area"] = []
    resolves = {"n": 0}

    def on_step_end(pb, uu, lam):
        again = ctl.update(pb, uu, lam)
        resolves["n"] += int(again)
        return again

    try:
        for st in load_steps(problem, spec.load_factors, spec.newton,
                             on_step_end=on_step_end if ctl is not None else None):
            u = st.u
            vals = {p.name: p.value(model, problem.dm, u) for p in spec.probes}
            rec = {"step": st.step, "load_factor": st.load_factor, "iterations": st.iterations,
                   "bisections": st.bisections, "wall_seconds": round(st.wall_seconds, 4), "probes": vals}
            from .interfaces import traction_summary

            itf = traction_summary(model, problem.dm, u)
            if itf:
                rec["interfaces"] = itf
            if ctl is not None:
                rec["resolves"] = resolves["n"]
                resolves["n"] = 0
                rec["debonded_area"] = ctl.debonded_area()
                summary["debonded_area"].append({"step": st.step, "load_factor": st.load_factor,
                                                 **rec["debonded_area"]})
                summary["first_delamination_load_factor"] = ctl.first_failure()
            summary["steps"].append(rec)
            summary["probes"] = vals
            rows.append([st.step, st.load_factor, st.iterations] + [vals[n] for n in names])
            if out is not None:
                if pvd is not None and (st.step % spec.output.every == 0 or st.step == n_steps):
                    from .export import export_step

                    paths = export_step(out, st.step, model, problem.dm, u, st.load_factor, ctl)
                    pvd.add(st.step, st.load_factor, paths)
                summary["wall_seconds"] = round(time.perf_counter() - t0, 4)
                write_json(out / "summary.json", summary)
                write_csv(out / "probes.csv", ["step", "load_factor", "iterations"] + names, rows)
            if progress is not None:
                progress(st.step, n_steps, st.load_factor)
        summary["converged"] = True
    except ConvergenceError as exc:
        message = str(exc)
        summary["error"] = message
    except KeyboardInterrupt:
        message = "interrupted by the user; the converged steps are kept"
        summary["error"] = message
    summary["wall_seconds"] = round(time.perf_counter() - t0, 4)
    if out is not None and spec.profiles and summary["steps"]:
        summary["profiles"] = write_profiles(spec, problem, u, out)
    if out is not None:
        write_json(out / "summary.json", summary)
        write_csv(out / "probes.csv", ["step", "load_factor", "iterations"] + names, rows)
        if spec.output.plots and rows and names:
            try:
                from .plots import plot_load_displacement

                lf = [r[1] for r in rows]
                plot_load_displacement(out / "load_displacement.png", lf,
                                       {n: [r[3 + i] for r in rows] for i, n in enumerate(names)}, model.units)
            except ImportError:
                pass
        if spec.output.plots and ctl is not None and summary["debonded_area"]:
            from .plots import plot_debonded_zone, plot_load_vs_area

            plot_debonded_zone(out / "debonded_zone.png", ctl, f"λ = {summary['steps'][-1]['load_factor']:.3g}")
            da = summary["debonded_area"]
            plot_load_vs_area(out / "load_debonded_area.png", [a["load_factor"] for a in da],
                              {k: [a[k] for a in da] for k in da[0] if k not in ("step", "load_factor")})
    return RunResult(summary["converged"], summary, problem, u, message)
