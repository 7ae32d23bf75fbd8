"""Run a model: load steps, probes, result files. Used by the CLI; knows nothing of argv."""
from __future__ import annotations

import os
import signal
import threading
import time
from contextlib import contextmanager
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

import numpy as np

from . import checkpoint
from .io.build import RunSpec
from .io.output import write_csv, write_json
from .solver.newton import ConvergenceError, DebondCut, load_steps
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


@contextmanager
def _sigint_deferred(reraise: bool = True):
    """Hold Ctrl-C (SIGINT) back while result files and the checkpoint of a step are written, so
    that they stay consistent; the interrupt is raised afterwards (``reraise``) or dropped (when
    the run is stopping anyway). Only in the main thread (elsewhere signals cannot be caught)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    hits: list[int] = []
    try:
        old = signal.signal(signal.SIGINT, lambda signum, frame: hits.append(signum))
    except ValueError:  # not the main interpreter
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, old if old is not None else signal.SIG_DFL)
    if hits and reraise:
        raise KeyboardInterrupt


def _version() -> str:
    from . import __version__

    return __version__


def write_delamination_table(path: Path, steps: list[dict]) -> None:
    """delamination.csv: per converged step the load factor and, per interface, the debonded
    area and the bounding box of the debonded points (e.g. the front position of a pull-off
    test is the largest x)."""
    recs = [s for s in steps if "debonded_extent" in s]
    if not recs:
        return
    names = list(recs[0]["debonded_extent"])
    keys = ["area", "x_min", "x_max", "y_min", "y_max"]
    header = ["step", "load_factor"] + [f"{n}:{k}" for n in names for k in keys]
    rows = [[s["step"], float(s["load_factor"])]
            + [("" if s["debonded_extent"][n][k] is None else float(s["debonded_extent"][n][k]))
               for n in names for k in keys] for s in recs]
    write_csv(path, header, rows)


def _fresh_linear_solvers(problem: Problem) -> None:
    """Begin the next load step with new linear solvers, as a restarted run does. PARDISO's
    pivoting (matching, scaling) follows the matrix of its symbolic analysis, so a solver kept
    across steps would make a restarted run differ from an uninterrupted one in the last digits
    and in the iteration counts. Costs one symbolic analysis per load step."""
    for solver in getattr(problem, "solvers", {}).values():
        solver.release()
    getattr(problem, "solvers", {}).clear()


def _zone_arrays(zones) -> dict[str, np.ndarray]:
    """The recorded zone-map history as arrays for the checkpoint."""
    if not zones.steps:
        return {}
    out = {"zones.step": np.asarray(zones.steps), "zones.load_factor": np.asarray(zones.load_factors)}
    for i in range(len(zones.released[0])):
        out[f"zones.released.{i}"] = np.stack([rec[i] for rec in zones.released])
    return out


def _restore_zones(zones, extra: dict[str, np.ndarray]) -> None:
    """Inverse of :func:`_zone_arrays` (the steps before a restart stay in the zone maps)."""
    if "zones.step" not in extra:
        return
    n_itf = sum(1 for k in extra if k.startswith("zones.released."))
    zones.steps = [int(s) for s in extra["zones.step"]]
    zones.load_factors = [float(x) for x in extra["zones.load_factor"]]
    zones.released = [[extra[f"zones.released.{i}"][j].copy() for i in range(n_itf)] for j in range(len(zones.steps))]


@dataclass
class RunResult:
    converged: bool
    summary: dict
    problem: Problem
    u: np.ndarray
    message: str = ""
    history: list[dict] = field(default_factory=list)
    interrupted: bool = False
    failure: dict | None = None  # non-convergence: step, load_factor, residual


def _rebase(entries: list, old: Path, new: Path) -> list[tuple[float, str]]:
    """ParaView series entries (paths relative to ``old``) relative to ``new``."""
    if old.resolve() == new.resolve():
        return [(float(t), str(p)) for t, p in entries]
    return [(float(t), Path(os.path.relpath((old / p).resolve(), new.resolve())).as_posix()) for t, p in entries]


def run(spec: RunSpec, out: Path | None = None, progress: Callable[[int, int, float], None] | None = None,
        write_vtu: bool | None = None, restart: str | Path | None = None) -> RunResult:
    """Solve ``spec`` and (if ``out``) write summary.json, probes.csv, ParaView files and the
    restart file checkpoint.npz after every converged step (atomically).

    ``restart``: a results folder (or its checkpoint.npz) of an earlier run of the same model:
    the run continues after its last converged step with the full state (displacements, bond
    flags, interface histories) and gives the same results as an uninterrupted run.
    Non-convergence and Ctrl-C end the run with ``converged = False`` and the converged steps
    written; other errors are re-raised after the converged steps are written.
    """
    t0 = time.perf_counter()
    model = spec.model
    ck = checkpoint.load(restart) if restart is not None else None  # a bad folder fails before the build
    problem = Problem.build(model)
    if ck is not None:
        checkpoint.check_compatible(ck, spec, problem.dm.n_full, restart)
    names = [p.name for p in spec.probes]
    summary = {
        "title": spec.source.model.title,
        "model_file": str(spec.path) if spec.path is not None else None,
        "version": _version(),
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
    lam0, step0, wall0 = 0.0, 0, 0.0
    message = ""
    n_steps = len(spec.load_factors)
    ctl = problem.interfaces
    if ctl is not None:
        summary["first_delamination_load_factor"] = None
        summary["debonded_area"] = []
    # cohesive interfaces (issue 13): energy columns in probes.csv, onset/peak in summary.json
    energy_names = (["external_work", "strain_energy", "interface_elastic_energy", "dissipated_fracture",
                     "dissipated_friction", "dissipated_viscous"]
                    if ctl is not None and ctl.energies(problem, np.zeros(problem.dm.n_full)) is not None else [])
    if energy_names:
        summary.update(first_damage_load_factor=None, peak_load_factor=None, energy=None)
        if ctl.warnings:
            summary["warnings"] = list(ctl.warnings)
    hash_ = checkpoint.model_hash(spec) if out is not None else ""
    from .plots import ZoneHistory

    zones = ZoneHistory(ctl)  # debonded flags per step for the zone maps (records nothing without interfaces)
    if ck is not None:
        u, lam0, step0 = ck.u.copy(), ck.load_factor, ck.step
        _restore_zones(zones, ck.extra)
        if ctl is not None:
            try:
                ctl.restore(problem, ck.interface_state)
            except ValueError as exc:
                raise checkpoint.CheckpointError(f"--restart '{restart}': {exc}; rerun without --restart") from None
        elif ck.interface_state:
            raise checkpoint.CheckpointError(f"--restart '{restart}': the checkpoint has an interface state but the "
                                             "model has no [[interfaces]]; rerun without --restart")
        wall0 = float(ck.summary.pop("wall_seconds", 0.0))
        summary.update(ck.summary)
        summary["restarts"] = list(summary.get("restarts", [])) + [{"step": step0, "load_factor": lam0}]
        rows = [list(r) for r in ck.rows]
        if pvd is not None:
            base = checkpoint.locate(restart).parent
            for key, entries in ck.pvd.items():
                pvd.series[key] = _rebase(entries, base, out)
    resolves = {"n": 0}
    last = ck  # the state of the last converged step (written again when the run stops)
    interrupted = False
    failure: dict | None = None
    pending: BaseException | None = None

    def on_step_end(pb, uu, lam):
        again = ctl.update(pb, uu, lam)
        resolves["n"] += int(again)
        return again

    def write_files() -> None:
        summary["wall_seconds"] = round(wall0 + time.perf_counter() - t0, 4)
        write_json(out / "summary.json", summary)
        write_csv(out / "probes.csv", ["step", "load_factor", "iterations"] + names + energy_names, rows)
        if ctl is not None:
            write_delamination_table(out / "delamination.csv", summary["steps"])

    if progress is not None and step0:
        progress(step0, n_steps, lam0)
    try:
        cut = None
        if ctl is not None and ctl.settings.max_debond_fraction is not None:
            cut = DebondCut(ctl.settings.max_debond_fraction, ctl.settings.max_debond_cuts,
                            lambda pb: pb.interfaces.debonded_fraction())
        steps = (load_steps(problem, spec.load_factors[step0:], spec.newton, u0=u, lam0=lam0, step0=step0,
                            on_step_end=on_step_end if ctl is not None else None, cut=cut)
                 if step0 < n_steps else ())
        for st in steps:
            with _sigint_deferred():  # a step is recorded completely or not at all
                u = st.u
                vals = {p.name: p.value(model, problem.dm, u, st.load_factor, problem.interfaces)
                        for p in spec.probes}
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
                    rec["debonded_extent"] = ctl.debonded_extent()
                    summary["debonded_area"].append({"step": st.step, "load_factor": st.load_factor,
                                                     **rec["debonded_area"]})
                    summary["first_delamination_load_factor"] = ctl.first_failure()
                energy = ctl.energies(problem, u) if energy_names else None
                if energy is not None:
                    rec["energy"] = energy
                    summary["energy"] = energy
                    summary["first_damage_load_factor"] = ctl.first_damage()
                    summary["peak_load_factor"] = max(float(st.load_factor), summary["peak_load_factor"] or 0.0)
                summary["steps"].append(rec)
                zones.record(st.step, st.load_factor)
                summary["probes"] = vals
                rows.append([st.step, st.load_factor, st.iterations] + [vals[n] for n in names]
                            + ([energy[k] for k in energy_names] if energy_names else []))
                if out is not None:
                    if pvd is not None and (st.step % spec.output.every == 0 or st.step == n_steps):
                        from .export import export_step

                        paths = export_step(out, st.step, model, problem.dm, u, st.load_factor, ctl)
                        pvd.add(st.step, st.load_factor, paths)
                    summary["wall_seconds"] = round(wall0 + time.perf_counter() - t0, 4)
                    last = checkpoint.capture(st.step, st.load_factor, u, spec.load_factors, hash_,
                                              ctl.state(problem) if ctl is not None else None, summary, rows,
                                              pvd.series if pvd is not None else {}, _zone_arrays(zones))
                    checkpoint.save(out / checkpoint.FILENAME, last)
                    write_files()
            _fresh_linear_solvers(problem)
            if progress is not None:
                progress(st.step, n_steps, st.load_factor)
        summary["converged"] = True
    except ConvergenceError as exc:
        done = summary["steps"][-1]["step"] if summary["steps"] else 0
        failure = {"step": done + 1, "load_factor": float(exc.load_factor), "residual": float(exc.residual)}
        message = str(exc)
        if "residual" not in message:
            message += f" (last residual {exc.residual:.3e})"
        summary["error"] = message
        summary["failure"] = failure
    except KeyboardInterrupt:
        interrupted = True
        done = summary["steps"][-1] if summary["steps"] else None
        message = ("interrupted by the user " + (f"after step {done['step']} (load factor {done['load_factor']:.6g})"
                                                  if done else "before the first load step converged")
                   + "; the converged steps are kept")
        summary["error"] = message
        summary["interrupted"] = True
    except Exception as exc:  # write what is done, then let the caller report it
        pending = exc
        summary["error"] = f"{type(exc).__name__}: {exc}"
    with _sigint_deferred(reraise=False):  # the run stops anyway: finish writing
        if out is not None and last is not None and last is not ck:
            checkpoint.save(out / checkpoint.FILENAME, last)  # again: a Ctrl-C may have hit the step's writes
        if pending is not None:
            if out is not None:
                write_files()
            raise pending
        summary["wall_seconds"] = round(wall0 + time.perf_counter() - t0, 4)
        if out is not None and spec.profiles and summary["steps"]:
            summary["profiles"] = write_profiles(spec, problem, u, out)
        if out is not None:
            write_files()
            if spec.output.plots:
                from .plots import write_figures

                write_figures(out, spec, problem, u, summary, zones)
    res = RunResult(summary["converged"], summary, problem, u, message, interrupted=interrupted, failure=failure)
    return res
