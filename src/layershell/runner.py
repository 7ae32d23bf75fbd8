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
    try:
        for st in load_steps(problem, spec.load_factors, spec.newton):
            u = st.u
            vals = {p.name: p.value(model, problem.dm, u) for p in spec.probes}
            rec = {"step": st.step, "load_factor": st.load_factor, "iterations": st.iterations,
                   "bisections": st.bisections, "wall_seconds": round(st.wall_seconds, 4), "probes": vals}
            summary["steps"].append(rec)
            summary["probes"] = vals
            rows.append([st.step, st.load_factor, st.iterations] + [vals[n] for n in names])
            if out is not None:
                if pvd is not None and (st.step % spec.output.every == 0 or st.step == n_steps):
                    from .export import export_step

                    paths = export_step(out, st.step, model, problem.dm, u, st.load_factor)
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
    return RunResult(summary["converged"], summary, problem, u, message)
