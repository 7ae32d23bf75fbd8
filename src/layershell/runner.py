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
from .recorder import Recorder, read_history
from .solver.arclength import ENERGY_WARN, probe_scales
from .solver.newton import ConvergenceError, DebondCut, load_steps, start_inertia
from .solver.path_state import End
from .solver.problem import Problem
from .threads import openblas_single_thread


def through_thickness(spec_profile, model, dm, u, load_factor: float = 1.0):
    """Stress component along the thickness at a point: {layer name: (Θ³, values)}; the profile's
    ``sampling`` (recovered transverse stresses by default) and ``frame``."""
    from .io.probes import STRESS_COMPONENTS
    from .recovery import stress_points
    from .results import locate

    pr = spec_profile
    e, x, y, _ = locate(model, pr.point)
    conn = model.mesh.elements[e]
    out = {}
    from .element.quadrature import ply_samples
    from .element.shape import quad9

    N, _, _ = quad9(np.array([x]), np.array([y]))
    for k in model.stacks[model.element_stack[e]]:
        H = float(N[0] @ model.layers[k].thickness[conn])
        off = float(N[0] @ model.offset(k)[conn])
        # points_per_layer samples in each ply (in the layer itself without plies)
        thL = H * ply_samples([f for _, _, f in model.layers[k].ply_table()], pr.points_per_layer).ravel()
        ps = stress_points(model, dm, u, np.full(thL.size, e), x, y, thL, np.full(thL.size, k), local_theta=True,
                           sampling=getattr(pr, "sampling", "recovered"), load_factor=load_factor)
        T = ps.stress(pr.measure, getattr(pr, "frame", "material"))
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


def write_profiles(spec, problem, u, rec: Recorder, load_factor: float = 1.0) -> dict:
    """profile_<name>.csv (Θ³ and one column per layer) and profile_<name>.png."""
    files = {}
    for pr in spec.profiles:
        cols = through_thickness(pr, spec.model, problem.dm, u, load_factor)
        names = list(cols)
        rows = []
        for i, n in enumerate(names):
            th, v = cols[n]
            for t, val in zip(th, v):
                rows.append([float(t)] + [float(val) if j == i else "" for j in range(len(names))])
        rec.write_csv(f"profile_{pr.name}.csv", ["theta3"] + names, rows)
        files[pr.name] = f"profile_{pr.name}.csv"
        if spec.output.plots:
            from .plots import height_axis, plot_through_thickness
            from .units import Units, axis_label

            plot_through_thickness(rec.path(f"profile_{pr.name}.png"), {k: (v, t) for k, (t, v) in cols.items()},
                                   axis_label(f"{pr.measure} σ{pr.component}", Units.parse(spec.model.units).stress),
                                   height=height_axis(spec.model, pr.point))
    return files


class Terminated(KeyboardInterrupt):
    """SIGTERM turned into an exception (by the CLI): the run ends like Ctrl-C (exit code 143)."""


def raise_terminated(signum, frame) -> None:
    """SIGTERM handler: stop like Ctrl-C (the converged steps are kept)."""
    raise Terminated()


@contextmanager
def _sigint_deferred(reraise: bool = True):
    """Hold Ctrl-C (SIGINT) and SIGTERM back while result files and the checkpoint of a step are
    written, so that they stay consistent; the interrupt is raised afterwards (``reraise``) or
    dropped (when the run is stopping anyway). Only in the main thread (elsewhere signals cannot
    be caught). SIGTERM is only held when a handler of its own is installed (the CLI's)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    hits: list[int] = []
    sigs = [signal.SIGINT]
    if hasattr(signal, "SIGTERM") and signal.getsignal(signal.SIGTERM) not in (signal.SIG_DFL, signal.SIG_IGN, None):
        sigs.append(signal.SIGTERM)
    old = {}
    try:
        for sg in sigs:
            old[sg] = signal.signal(sg, lambda signum, frame: hits.append(signum))
    except ValueError:  # not the main interpreter
        yield
        return
    try:
        yield
    finally:
        for sg, h in old.items():
            signal.signal(sg, h if h is not None else signal.SIG_DFL)
    if hits and reraise:
        raise (Terminated if signal.SIGTERM in hits and hasattr(signal, "SIGTERM") else KeyboardInterrupt)


def _version() -> str:
    from . import __version__

    return __version__


def _zone_arrays(zones) -> dict[str, np.ndarray]:
    """The recorded zone-map history as arrays for the checkpoint."""
    if not zones.steps:
        return {}
    out = {"zones.step": np.asarray(zones.steps), "zones.load_factor": np.asarray(zones.load_factors)}
    for i in range(len(zones.released[0])):
        out[f"zones.released.{i}"] = np.stack([rec[i] for rec in zones.released])
    return out


#: the first converged step at which an event of the inelastic layers is seen (summary.json keys)
MATERIAL_EVENTS = {"cracking": "first_cracking_load_factor", "yielding": "first_yield_load_factor",
                   "crushing": "first_crushing_load_factor", "rupture": "first_rupture_load_factor"}


def _material_record(problem, summary: dict, rec: dict, st, log) -> None:
    """The dissipated energy of the inelastic layers in the step record, and the first cracking,
    yielding, crushing and rupture (load factor, step) in the summary and the log."""
    asm = problem.assembler
    rec["dissipated_material"] = asm.material_dissipation()
    for name, seen in asm.material_events().items():
        key = MATERIAL_EVENTS.get(name)
        if key is not None and seen and summary.get(key) is None:
            summary[key] = st.load_factor
            summary[key.replace("load_factor", "step")] = st.step
            log(f"step {st.step} λ = {st.load_factor:.6g}: first {name}")


def _restore_zones(zones, extra: dict[str, np.ndarray]) -> None:
    """Inverse of :func:`_zone_arrays` (the steps before a restart stay in the zone maps)."""
    if "zones.step" not in extra:
        return
    n_itf = sum(1 for k in extra if k.startswith("zones.released."))
    zones.steps = [int(s) for s in extra["zones.step"]]
    zones.load_factors = [float(x) for x in extra["zones.load_factor"]]
    zones.released = [[extra[f"zones.released.{i}"][j].copy() for i in range(n_itf)] for j in range(len(zones.steps))]


def _path_steps(spec: RunSpec, problem: Problem, u, lam0: float, step0: int, ck, on_step_end,
                floors: "_ProbeFloors"):
    """The converged increments of arc-length or adaptive load control, continued from the
    checkpoint's path state (:class:`~layershell.solver.path_state.PathState`, whole) after a restart."""
    from .solver.arclength import path_steps
    from .solver.path_state import PathState

    ctl = problem.interfaces
    state = PathState.from_arrays(ck.extra) if ck is not None else None

    def watch(uu, lam):
        return {p.name: p.value(spec.model, problem.dm, uu, lam, ctl, problem=problem) for p in spec.probes}

    return path_steps(problem, spec.newton, spec.path_following, u0=u, lam0=lam0, step0=step0, state=state,
                      on_step_end=on_step_end, measure=(lambda pb: pb.interfaces.debonded_fraction())
                      if ctl is not None else None, watch=watch if spec.probes else None,
                      floors=floors)


class _ProbeFloors:
    """Noise floors of the probes for the jump check (:func:`~layershell.solver.arclength.jump_warnings`):
    a reaction probe ρ·(f_int − F_ext) is computed from a state whose residual the Newton loop
    only brought below ``tol_residual`` × the force scale of the run (``Problem.force_scale``,
    solver/newton.py), so by Cauchy–Schwarz it is resolved only beyond
    |scale| · ‖ρ‖ · tol_residual · force_scale. Below that it is round-off - e.g. the sum of the
    reactions that equilibrium makes zero (the DCB's P_all: ~1e-8 N against 60 N loads) - and
    its ratio between two steps means nothing.

    A debonded-area probe grows by whole nodal areas, so its ratio between two steps measures the
    mesh, not a jump: the TRC slab on 16 × 12, on its snap-back, had increments refused as jumps
    because the debonded area went from one node's share to five (0.0004 to 0.002 m², 5×, of the
    3 m² interface). The debonded area is judged by its share of the interface instead
    (``jump_area``, :func:`~layershell.solver.arclength.jump_warnings`), so its floor is that share
    of the area the probe watches: below it the ratio is not checked. Other probes get no floor.

    The floor is at least ``RELATIVE`` (10⁻⁶) of the force scale: a reaction that small is not
    resolved either where it is not one that equilibrium makes zero - the DCB opened by
    prescribed displacements on 100 elements: the sum of the two arms' reactions, 2.7e-6 ->
    -9.0e-6 N against P = 60 N (1.5e-7 of it), the clamp's share that the residual, spread over
    all free DOFs, does not bound - and no engineer reads a jump in it."""

    RELATIVE = 1e-6
    # a displacement probe below this share of the state's largest face translation is round-off
    # (the lateral deflection of a perfect column compressed along its axis: 1e-16 against a
    # shortening of 1e-3 is no jump however its noise changes; stability.py)
    DISPLACEMENT = 1e-9

    def __init__(self, spec: RunSpec, problem: Problem):
        self.spec, self.problem = spec, problem
        self.norms: dict[str, float] = {}  # ‖ρ‖ of each reaction probe
        self.areas: dict[str, float] = {}  # the interface area each debonded-area probe watches
        self.translations = problem.dm.translations()

    def __call__(self, u: np.ndarray | None = None) -> dict[str, float]:
        pb, spec = self.problem, self.spec
        scale = float(getattr(pb, "force_scale", 0.0)) * spec.newton.tol_residual
        out = {}
        largest = float(np.abs(u[self.translations]).max(initial=0.0)) if u is not None else 0.0
        jump_area = spec.source.steps.jump_area
        for p in spec.probes:
            if p.quantity == "debonded_area" and jump_area is not None:
                if p.name not in self.areas:
                    self.areas[p.name] = p.debonded_area(pb.interfaces, whole=True)
                out[p.name] = abs(p.scale) * jump_area * self.areas[p.name]
            if p.quantity == "displacement" and u is not None:
                out[p.name] = abs(p.scale) * self.DISPLACEMENT * largest
            if p.quantity == "interface_damage":  # bounded by 1: its jumps are a point's state, not the path's
                out[p.name] = abs(p.scale)
            if p.quantity != "reaction":
                continue
            if p.name not in self.norms:
                self.norms[p.name] = float(np.linalg.norm(p.rigid_mode(spec.model, pb.dm)))
            out[p.name] = abs(p.scale) * max(self.norms[p.name] * scale,
                                             self.RELATIVE * float(getattr(pb, "force_scale", 0.0)))
        return out


def _warn(summary: dict, m: str, category: type, log) -> None:
    """One warning of a run: summary.json 'warnings', Python's warnings (the console) and run.log."""
    import warnings as _w

    summary.setdefault("warnings", []).append(m)
    _w.warn(m, category, stacklevel=3)
    log(f"warning: {m}")


def _relaxed(summary: dict, events: list[dict], energy: dict | None, step: int, log) -> None:
    """summary['relaxations'] gets the unstable jumps that the load stepping relaxed in this step
    ([steps] unstable = 'relax', solver/newton.py relax), each a warning; ``events`` is emptied."""
    fracture = (energy or {}).get("dissipated_fracture", 0.0)
    for ev in events:
        rec = {"step": step, **ev}
        summary.setdefault("relaxations", []).append(rec)
        if ev["debonded_fraction_after"] == ev["debonded_fraction_before"] and ev["energy_released"] <= 1e-3 * fracture:
            continue  # no jump: an equilibrium that the cut steps missed (recorded, not a warning)
        m = (f"step {step}: no equilibrium of the rate-independent cohesive law beyond load factor "
             f"{ev['from_load_factor']:.6g} (the crack front jumps: a snap-back of the path under this control); "
             f"the damage relaxed at load factor {ev['load_factor']:.6g} to the next equilibrium in "
             f"{ev['increments']} pseudo-time increments: debonded fraction {ev['debonded_fraction_before']:.4g} -> "
             f"{ev['debonded_fraction_after']:.4g}, energy released in the jump {ev['energy_released']:.4g}"
             + (f" ({ev['energy_released'] / fracture:.2%} of the fracture energy so far)" if fracture > 0 else "")
             + " - booked as viscous dissipation; summary.json 'relaxations'. Between the two states the path "
             "is not followed: use control = 'arc_length' (forces or prescribed displacements) or refine along the "
             "front to trace it")
        _warn(summary, m, JumpWarning, log)
    events.clear()


def _contact_moved(summary: dict, moves: list[dict], step: int, log) -> None:
    """summary['contact_moved_to_nodes'] gets the moves of the thesis-law contact from the face
    Gauss points to the nodes (InterfaceController.contact_to_nodes) made in this step, each a
    warning; ``moves`` is emptied."""
    from .solver.interface_state import contact_move_message

    for mv in moves:
        summary.setdefault("contact_moved_to_nodes", []).append({"step": step, **mv})
        m = f"step {step}: " + contact_move_message(mv)
        _warn(summary, m, ContactRuleWarning, log)
    moves.clear()


def _settled(summary: dict, events: list[dict], step: int, log) -> None:
    """summary['settlements'] gets the re-solutions at a fixed load that only pseudo-transient
    settling solved in this step (solver/newton.py settle), each a warning; ``events`` is
    emptied."""
    for ev in events:
        summary.setdefault("settlements", []).append({"step": step, **ev})
        fraction = ev.get("debonded_fraction")
        m = (f"step {step}: the re-solution at load factor {ev['load_factor']:.6g} after new releases found no "
             f"equilibrium by Newton's method from the last state ({ev['reason']}); with every DOF damped it "
             f"settled to one in {ev['increments']} pseudo-time increments ({ev['iterations']} iterations), the "
             f"displacements moving by up to {ev['largest_displacement_change']:.4g}"
             + (f", debonded fraction {fraction:.4g}" if fraction is not None else "")
             + f". That state is an equilibrium without the damping. Between the two states the structure snaps at "
             f"a fixed load (a dynamic jump whose path is not followed), releasing {ev['energy_released']:.4g} (the "
             "work of the out-of-balance forces along the damped path). summary.json 'settlements'")
        _warn(summary, m, JumpWarning, log)
    events.clear()


def _ended_early(summary: dict, st, steps, log) -> None:
    """A path (arc length or adaptive steps) that ended at [steps] max_steps before lambda_end:
    its run is converged - every increment is an equilibrium - but it did not reach the load it
    was asked for; warn (console, run.log, summary.json 'warnings'). The Gmsh plate with
    adaptive steps crawled for 1000 increments at λ ≈ 0.4998 of 1 (each tiny increment still took
    7-9 Newton iterations, so the step-size control never grew them) and said only 'converged'."""
    m = (f"step {st.step}: the path ended after [steps] max_steps = {steps.max_steps} increments at load factor "
         f"{st.load_factor:.6g}, before lambda_end = {steps.lambda_end:g} (summary.json 'path_end'): every "
         "increment is an equilibrium, but the load asked for was not reached. Raise max_steps; where the "
         "increments stay small (steps.jsonl 'path' sizes: each still takes about target_iterations Newton "
         "iterations), raise target_iterations or use fixed steps")
    _warn(summary, m, JumpWarning, log)


def _balance(summary: dict, energy: dict, step: int, log) -> None:
    """Warn once (console, run.log, summary.json 'warnings') at the first step whose energy
    balance error exceeds ENERGY_WARN after energy has been dissipated: the ledger's
    dissipation and the work no longer agree, most often because the increments are long where
    the crack front moves (the ledger integrates each point's damage along the straight
    separation path between converged states; examples/mmb_cohesive.toml: 3.3 % without the arc
    length's energy-error step control, 0.64 % with it; the DCB on 150 elements under
    displacement control, whose node rows release within one Newton solve: 1.8 %; 0.24 % with its
    prescribed opening traced by arc length)."""
    err = energy.get("balance_error", 0.0)
    lost = sum(energy.get(k, 0.0) for k in ("dissipated_fracture", "dissipated_friction", "dissipated_viscous"))
    if not (abs(err) > ENERGY_WARN and lost > 0) or summary.get("energy_balance_warned"):
        return
    summary["energy_balance_warned"] = step
    m = (f"step {step}: the energy balance is off by {err:.2%} of the external work (external work - stored energy "
         f"- dissipated, summary.json 'energy'; more than {ENERGY_WARN:.0%}): the dissipation the interfaces "
         "book and the work done disagree. The increments are likely too long where the crack front moves: the "
         "ledger follows each interface point along a straight separation path between converged states, which a "
         "mixed-mode front point does not take, nor a node row that releases within one Newton solve. Shorten them "
         "([steps] arc_length_max and target_iterations, increment_max, or more steps; by arc length a smaller "
         "energy_tolerance does it where the error arises) until the error is small; otherwise check the model. "
         "Under load or displacement control, steps in which a node row releases at once jump across a snap-back "
         "of the path (the load drops at a fixed load factor), and shorter steps do not close that error: "
         "trace the path by control = 'arc_length' (prescribed displacements too)")
    _warn(summary, m, CohesiveWarning, log)


def _stabilized(summary: dict, where: dict, energy: dict | None, step: int, log) -> None:
    """summary['stabilized'] of a run whose cohesive interfaces the load stepping regularised
    (NewtonSettings.stabilize): where, η, and the viscous share of the dissipation so far; warns
    once when it is switched on."""
    visc = (energy or {}).get("dissipated_viscous", 0.0)
    total = visc + (energy or {}).get("dissipated_fracture", 0.0)
    first = "stabilized" not in summary
    summary["stabilized"] = {**where, "dissipated_viscous": visc,
                             "viscous_share_of_dissipation": visc / total if total > 0 else 0.0}
    if first:
        m = (f"step {step}: no equilibrium of the rate-independent cohesive law near λ = {where['load_factor']:.6g} "
             f"(every cut of the step failed); the viscous regularisation was switched on from there with η = "
             f"{where['viscosity']:.3g} (load-factor units, [steps] stabilize) - the summary's 'stabilized' and "
             "energy.dissipated_viscous show its share of the dissipation; where it is not small, follow the "
             "path by control = 'arc_length' or smaller steps")
        _warn(summary, m, CohesiveWarning, log)


def _path_arrays(st) -> dict[str, np.ndarray]:
    state = getattr(st, "state", None)
    return state.to_arrays() if state is not None else {}


class _JumpWatch:
    """Jump warnings (issue 13): a step in which the debonded area grows by more than
    [steps] jump_area of the interface or a probe grows more than jump_ratio times as fast as λ
    gets a warning on the console (a UserWarning) and in summary.json 'warnings'."""

    def __init__(self, spec: RunSpec, summary: dict, ctl, floors: "_ProbeFloors | None" = None):
        st = spec.source.steps
        self.area, self.ratio = st.jump_area, st.jump_ratio
        self.floors = floors  # noise floors of reaction probes (round-off is no jump)
        self.summary = summary
        prev = summary["steps"][-1] if summary["steps"] else None
        self.lam = prev["load_factor"] if prev else 0.0
        self.probes = prev["probes"] if prev else None
        self.frac = ctl.debonded_fraction() if ctl is not None else None  # after a restart: the restored state
        self.scales: dict[str, float] = {}  # largest |value| of each probe (round-off is no jump)
        for s in summary["steps"]:
            probe_scales(self.scales, s.get("probes"))

    def check(self, st, probes: dict, area: dict | None, ctl) -> None:
        import warnings as _w

        from .solver.arclength import jump_warnings

        frac = ctl.debonded_fraction() if ctl is not None else None
        msgs = getattr(st, "warnings", None)
        probe_scales(self.scales, probes)
        if msgs is None:  # fixed steps: checked here (arc length and adaptive steps check, and cut, themselves)
            msgs = jump_warnings(st.step, st.load_factor, self.lam, frac, self.frac, probes, self.probes,
                                 self.area, self.ratio, self.scales,
                                 self.floors(st.u) if self.floors is not None else None)
        for m in msgs:
            _w.warn(m, JumpWarning, stacklevel=2)
        if msgs:
            self.summary.setdefault("warnings", []).extend(msgs)
        self.lam, self.probes, self.frac = st.load_factor, probes, frac


class CohesiveWarning(UserWarning):
    """A cohesive interface whose model is doubtful (e.g. an unresolved process zone)."""


class JumpWarning(UserWarning):
    """A step with a jump of the debonded area or of a probe."""


class StabilityWarning(UserWarning):
    """The tangent stiffness gained negative eigenvalues without a limit point (stability.py)."""


def _stability(summary: dict, events, log, locate: Callable | None = None) -> None:
    """summary['stability'] gets the changes of the tangent's negative eigenvalues (stability.py);
    bifurcations and an unstable start are warnings. An event of a step already recorded (a
    restarted run replays its history) is skipped. ``locate(event)``: a bisection of a
    bifurcation's load factors, (λ_lo, λ_hi) or None."""
    seen = {e["step"] for e in summary.get("stability", [])}
    for ev in events:
        if ev.step in seen:
            continue
        if ev.kind == "bifurcation" and locate is not None:
            ev.located, ev.mode_file = locate(ev)
        summary.setdefault("stability", []).append(ev.as_dict())
        if ev.warns:
            _warn(summary, ev.message(), StabilityWarning, log)


def _last_inertia(problem: Problem, u: np.ndarray, summary: dict, spec: RunSpec) -> int | None:
    """The negative eigenvalues of the tangent at the last converged state: from the first solve
    of the step that failed, else (a finished run) one factorisation at ``u`` - only without
    interface laws, whose tangent at a committed state depends on the loading sets that the
    path's solves freeze (None then, and where unknown)."""
    if summary.get("failure") is not None:
        return start_inertia(problem)
    if not summary["steps"] or problem.interfaces is not None or not spec.model.nonlinear:
        return None
    return problem.inertia_at(u, spec.newton.backend)


class ContactRuleWarning(UserWarning):
    """The thesis law's contact between debonded layers moved from the face Gauss points to the
    nodes, where its contact set had found no equilibrium."""


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
    signal: str | None = None  # "SIGINT" or "SIGTERM" when interrupted


def _rebase(entries: list, old: Path, new: Path) -> list[tuple[float, str]]:
    """ParaView series entries (paths relative to ``old``) relative to ``new``."""
    if old.resolve() == new.resolve():
        return [(float(t), str(p)) for t, p in entries]
    return [(float(t), Path(os.path.relpath((old / p).resolve(), new.resolve())).as_posix()) for t, p in entries]


def _history(ck, where) -> tuple[list[dict], dict[str, list]]:
    """The step records before a restart (with their ParaView files) and, for checkpoints of
    format 1 written before steps.jsonl existed, the ParaView series stored in the checkpoint."""
    if "steps" in ck.summary:  # older checkpoint: the history is inside
        return [dict(r) for r in ck.summary.pop("steps")], {k: list(v) for k, v in ck.pvd.items()}
    hist = read_history(checkpoint.locate(where).parent, ck.step)
    if len(hist) != ck.step or [r.get("step") for r in hist] != list(range(1, ck.step + 1)):
        raise checkpoint.CheckpointError(
            f"--restart '{where}': steps.jsonl next to the checkpoint holds {len(hist)} of its {ck.step} step "
            "record(s) (deleted or damaged); rerun the model from the start")
    return hist, {}


_IN_SUMMARY_ONLY = ("files",)


def run(spec: RunSpec, out: Path | None = None, progress: Callable[[int, int, float], None] | None = None,
        write_vtu: bool | None = None, restart: str | Path | None = None, overwrite: bool = False,
        monitor: Callable[[dict], None] | None = None, echo: Callable[[str], None] | None = None) -> RunResult:
    """Solve ``spec`` and (if ``out``) record every converged step in the results folder through
    a :class:`~layershell.recorder.Recorder` (summary.json, probes.csv, steps.jsonl, run.log,
    ParaView files, the restart file checkpoint.npz; figures at the end).

    ``restart``: a results folder (or its checkpoint.npz) of an earlier run of the same model:
    the run continues after its last converged step with the full state (displacements, bond
    flags, interface histories) and gives the same results as an uninterrupted run.
    ``overwrite``: replace the results of another model in ``out`` (otherwise refused, see the
    recorder). ``monitor(info)``: called after every Newton iteration with step, iteration,
    load factor, residual, re-solutions and debonded area; ``echo(line)``: every run.log line.
    Non-convergence, Ctrl-C and SIGTERM (with the CLI's handler) end the run with ``converged =
    False`` and the converged steps written; other errors are re-raised after the converged steps
    are written.
    """
    ck = checkpoint.load(restart) if restart is not None else None  # a bad folder fails before the build
    with openblas_single_thread():  # vector BLAS on one thread (layershell/threads.py)
        if out is None:
            return _run(spec, None, progress, write_vtu, restart, ck, monitor)
        out = Path(out)
        resume = restart is not None and checkpoint.locate(restart).parent.resolve() == out.resolve()
        with Recorder(out, model_file=str(Path(spec.path).resolve()) if spec.path is not None else None,
                      model_hash=checkpoint.model_hash(spec), title=spec.source.model.title,
                      overwrite=overwrite, resume=resume, echo=echo) as rec:
            return _run(spec, rec, progress, write_vtu, restart, ck, monitor)


def _run(spec: RunSpec, rcd: Recorder | None, progress, write_vtu, restart, ck, monitor) -> RunResult:
    t0 = time.perf_counter()
    model = spec.model
    out = rcd.folder if rcd is not None else None
    log = rcd.log if rcd is not None else (lambda line: None)
    problem = Problem.build(model)
    if ck is not None:
        checkpoint.check_compatible(ck, spec, problem.dm.n_full, restart)
    names = [p.name for p in spec.probes]
    hash_ = checkpoint.model_hash(spec) if out is not None else ""
    summary = {
        "title": spec.source.model.title,
        "model_file": str(spec.path) if spec.path is not None else None,
        "model_hash": hash_,
        "model_text": spec.model_text(),
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
    vtu = spec.output.vtu if write_vtu is None else write_vtu
    pvd = None
    if out is not None and vtu:
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
    from .plots import ZoneHistory

    zones = ZoneHistory(ctl, keep=spec.output.zone_steps)  # debonded flags of the steps the zone maps may show
    history: list[dict] = []
    if ck is not None:
        history, legacy_pvd = _history(ck, restart)
        u, lam0, step0 = ck.u.copy(), ck.load_factor, ck.step
        _restore_zones(zones, ck.extra)
        mat = {k[4:]: v for k, v in ck.extra.items() if k.startswith("mat/")}
        if problem.assembler.inelastic:
            try:
                problem.assembler.set_material_state(mat)
            except KeyError as exc:
                raise checkpoint.CheckpointError(f"--restart '{restart}': the checkpoint lacks the material state "
                                                 f"{exc} of the model's concrete/reinforcement; rerun without "
                                                 "--restart") from None
        if ctl is not None:
            try:
                ctl.restore(problem, ck.interface_state)
            except ValueError as exc:
                raise checkpoint.CheckpointError(f"--restart '{restart}': {exc}; rerun without --restart") from None
        elif ck.interface_state:
            raise checkpoint.CheckpointError(f"--restart '{restart}': the checkpoint has an interface state but the "
                                             "model has no [[interfaces]]; rerun without --restart")
        wall0 = float(ck.summary.pop("wall_seconds", 0.0))
        ck.summary.pop("debonded_area", None)
        summary.update(ck.summary)
        # the counters go on from the checkpoint's (summary.json counts the whole run)
        if hasattr(problem, "accepted_sets"):
            problem.accepted_sets = int(summary.get("active_set", {}).get("accepted_within_tolerance", 0))
            problem.accepted_violation = float(summary.get("active_set", {}).get("largest_violation", 0.0))
        if hasattr(problem, "solve_counts_before"):
            problem.solve_counts_before = dict(summary.get("linear_solves", {}))
        summary["steps"] = [{k: v for k, v in r.items() if k not in _IN_SUMMARY_ONLY} for r in history]
        if ctl is not None:
            summary["debonded_area"] = [{"step": r["step"], "load_factor": r["load_factor"], **r["debonded_area"]}
                                        for r in history if "debonded_area" in r]
        summary["restarts"] = list(summary.get("restarts", [])) + [{"step": step0, "load_factor": lam0}]
        if pvd is not None:
            base = checkpoint.locate(restart).parent
            series: dict[str, list] = {k: list(v) for k, v in legacy_pvd.items()}
            for r in history:
                for key, f in (r.get("files") or {}).items():
                    series.setdefault(key, []).append((r["load_factor"], f))
            for key, entries in series.items():
                pvd.series[key] = _rebase(entries, base, out)
            if base.resolve() != out.resolve():  # the history's files now live elsewhere: paths relative to out
                for r in history:
                    if r.get("files"):
                        r["files"] = {k: _rebase([(0.0, f)], base, out)[0][1] for k, f in r["files"].items()}
    if rcd is not None:
        rcd.begin(names, history, energy_names)
        if pvd is not None:
            pvd.write()
            rcd.register([f"{k}.pvd" for k in pvd.series])
        log(f"layershell {_version()} run of {spec.path} ({summary['n_elements']} elements, {summary['n_dofs']} "
            f"DOFs, {n_steps} load step(s))" + (f", restarted after step {step0}" if ck is not None else ""))
    from .recovery import RecoveryWarning, raw_fallback_warning

    raw_note = raw_fallback_warning(
        model, spec.probes, spec.profiles, vtu=pvd is not None and spec.output.sampling == "recovered",
        criterion=getattr(getattr(ctl, "settings", None), "stresses", "raw") == "recovered")
    if raw_note is not None:
        _warn(summary, raw_note, RecoveryWarning, log)
    resolves = {"n": 0}
    live = {"step": step0 + 1, "load_factor": lam0}
    last = ck  # the state of the last converged step (written again when the run stops)
    interrupted = False
    stop_signal: str | None = None
    failure: dict | None = None
    pending: BaseException | None = None

    def debonded_total() -> float:
        return float(sum(ctl.debonded_area().values())) if ctl is not None else 0.0

    def on_step_end(pb, uu, lam):
        before = debonded_total()
        again = ctl.update(pb, uu, lam)
        if ctl.new_warnings:  # a process zone covered by fewer than 3 node spacings (when damage starts)
            import warnings as _w

            summary.setdefault("warnings", []).extend(ctl.new_warnings)
            for m in ctl.new_warnings:
                _w.warn(m, CohesiveWarning, stacklevel=2)
                log(f"warning: {m}")
            ctl.new_warnings.clear()
        resolves["n"] += int(again)
        after = debonded_total()
        if again or after != before:
            log(f"step {live['step']} λ = {lam:.6g}: bond/contact update, debonded area {before:.6g} → {after:.6g}"
                + (", re-solving" if again else ""))
        return again

    contact = [b for b in problem.assembler.extra if hasattr(b, "gap") and hasattr(b, "released")]

    def on_iteration(it: int, lam: float, rn: float, scale: float, energy, uu=None) -> None:
        live["load_factor"] = lam
        info = {"step": live["step"], "iteration": it, "load_factor": lam, "residual": rn,
                "relative_residual": rn / scale if scale else float("nan"), "energy": energy,
                "resolves": resolves["n"], "debonded_area": debonded_total()}
        if rcd is not None:
            line = (f"step {info['step']} λ = {lam:.6g} iteration {it}: residual {rn:.3e} "
                    f"(relative {info['relative_residual']:.3e})"
                    + (f", energy norm {energy:.3e}" if energy is not None else ""))
            if contact and uu is not None:  # points in contact (released and closed), and how many changed
                now = [b.released & (b.gap(uu) <= 0.0) for b in contact]
                n = int(sum(int(a.sum()) for a in now))
                prev = live.get("contact")
                changed = (int(sum(int((a != b).sum()) for a, b in zip(now, prev)))
                           if prev is not None and all(a.shape == b.shape for a, b in zip(now, prev)) else None)
                live["contact"] = now
                line += f", contact points {n}" + (f" ({changed} changed)" if changed else "")
            log(line)
        if monitor is not None:
            monitor(info)

    problem.monitor = on_iteration  # called by the Newton loop (solver/newton.py)

    if progress is not None and step0:
        progress(step0, n_steps, lam0)
    from .stability import StabilityWatch

    # the load factor only grows under load control (fixed or adaptive steps)
    # not with cohesive interfaces: there the tangent's inertia depends on which points the
    # solves freeze as loading (every one at its threshold: Hill's comparison solid), and on the
    # ENF it separated neither branch (docs/user-guide.md, ENF); a warning from it would be wrong
    # on every softening run or never given
    # nor with inelastic layers: their softening makes the tangent indefinite without any buckling
    stab = (StabilityWatch(monotone=spec.path_following is None or spec.path_following.control != "arc_length")
            if (ctl is None or not ctl.cohesive()) and not problem.assembler.inelastic else None)
    prev_state = (0, 0.0)  # (step, λ) of the last converged state, whose inertia the next step brings
    # the states of the last steps, from which a bifurcation is located by bisection: only where a
    # state is a function of λ (no interface laws; geometrically nonlinear)
    recent: dict[int, np.ndarray] = {}
    bisect = stab is not None and ctl is None and model.nonlinear
    if bisect:
        recent[step0] = u.copy()

    def locate(ev):
        """(λ_lo, λ_hi) of a bifurcation by bisection, and the file of its buckling mode (the
        eigenvector of the tangent just below it, written with the results) - or None."""
        from .solver.newton import critical_mode, locate_inertia_change

        if ev.step_before not in recent:
            return None, None
        found = locate_inertia_change(problem, spec.newton, recent[ev.step_before], ev.load_factor_before,
                                      ev.negative_eigenvalues_before, ev.load_factor)
        if found is None:
            return None, None
        lo, hi, u_lo = found
        name = None
        if rcd is not None:
            phi = critical_mode(problem, u_lo)
            if phi is not None:
                from .export import _write_vtu, surface_mesh

                name = f"buckling_mode_{ev.step:04d}.vtu"
                _write_vtu(rcd.path(name), surface_mesh(model, problem.dm, phi))
                rcd.register([name])
        return (lo, hi), name
    try:
        cut = None
        if ctl is not None and ctl.settings.max_debond_fraction is not None:
            cut = DebondCut(ctl.settings.max_debond_fraction, ctl.settings.max_debond_cuts,
                            lambda pb: pb.interfaces.debonded_fraction())
        steps = (load_steps(problem, spec.load_factors[step0:], spec.newton, u0=u, lam0=lam0, step0=step0,
                            on_step_end=on_step_end if ctl is not None else None, cut=cut)
                 if step0 < n_steps else ())
        floors = _ProbeFloors(spec, problem)  # noise floors of the reaction probes (the jump check)
        if spec.path_following is not None:  # arc length / adaptive steps (solver/arclength.py)
            steps = _path_steps(spec, problem, u, lam0, step0, ck, on_step_end if ctl is not None else None, floors)
        jumps = _JumpWatch(spec, summary, ctl, floors)
        for r in summary["steps"] if stab is not None else ():  # a restart: the history's states (events recorded)
            stab.add(*prev_state, r.get("negative_eigenvalues_at_start"))
            prev_state = (r["step"], float(r["load_factor"]))
        for st in steps:
            with _sigint_deferred():  # a step is recorded completely or not at all
                u = st.u
                vals = {p.name: p.value(model, problem.dm, u, st.load_factor, problem.interfaces, problem=problem)
                        for p in spec.probes}
                rec = {"step": st.step, "load_factor": st.load_factor, "iterations": st.iterations,
                       "bisections": st.bisections, "wall_seconds": round(st.wall_seconds, 4), "probes": vals}
                if problem.assembler.inelastic:
                    _material_record(problem, summary, rec, st, log)
                if stab is not None:  # the inertia of the tangent at the previous converged state (stability.py)
                    if st.negative_eigenvalues_start is not None:
                        rec["negative_eigenvalues_at_start"] = int(st.negative_eigenvalues_start)
                    _stability(summary, stab.add(*prev_state, st.negative_eigenvalues_start), log,
                               locate if bisect else None)
                    prev_state = (st.step, float(st.load_factor))
                    if bisect:
                        recent[st.step] = u.copy()
                        for k in [k for k in recent if k < st.step - 3]:
                            del recent[k]
                from .interfaces import traction_summary

                itf = traction_summary(model, problem.dm, u)
                if itf:
                    rec["interfaces"] = itf
                if ctl is not None:
                    rec["resolves"] = resolves["n"]
                    resolves["n"] = 0
                    ctl.begin_step()  # [delamination] max_resolves counts per step
                    rec["debonded_area"] = ctl.debonded_area()
                    rec["debonded_extent"] = ctl.debonded_extent()
                    summary["debonded_area"].append({"step": st.step, "load_factor": st.load_factor,
                                                     **rec["debonded_area"]})
                    summary["first_delamination_load_factor"] = ctl.first_failure()
                if getattr(st, "state", None) is not None:  # arc length / adaptive: the constraint of the step
                    rec["path"] = {"constraint": st.state.mode, "size": float(st.state.size),
                                   "dissipation": float(st.dissipation)}
                    if getattr(st, "end", None):
                        summary["path_end"] = st.end.value  # lambda_end, complete failure or max_steps
                        if st.end is End.MAX_STEPS:
                            _ended_early(summary, st, spec.path_following, log)
                jumps.check(st, vals, rec.get("debonded_area"), ctl)
                energy = ctl.energies(problem, u) if energy_names else None
                if energy is not None:
                    rec["energy"] = energy
                    summary["energy"] = energy
                    summary["first_damage_load_factor"] = ctl.first_damage()
                    summary["peak_load_factor"] = max(float(st.load_factor), summary["peak_load_factor"] or 0.0)
                    _balance(summary, energy, st.step, log)
                if ctl is not None and ctl.stabilized is not None:  # automatic viscous stabilisation (solver/newton.py)
                    _stabilized(summary, ctl.stabilized, energy, st.step, log)
                if ctl is not None and getattr(ctl, "relaxations", None):  # unstable jumps relaxed (solver/newton.py relax)
                    _relaxed(summary, ctl.relaxations, energy, st.step, log)
                if ctl is not None and getattr(ctl, "contact_moves", None):  # thesis contact moved to the nodes (solver/newton.py)
                    _contact_moved(summary, ctl.contact_moves, st.step, log)
                if ctl is not None and getattr(ctl, "settlements", None):  # re-solutions settled (solver/newton.py settle)
                    _settled(summary, ctl.settlements, st.step, log)
                if getattr(problem, "accepted_sets", 0):  # cohesive active sets accepted within their tolerance (solver/newton.py)
                    summary["active_set"] = {"accepted_within_tolerance": problem.accepted_sets,
                                             "largest_violation": problem.accepted_violation}
                counts = problem.solve_counts() if hasattr(problem, "solve_counts") else {}
                if counts.get("krylov_solves") or counts.get("krylov_failures"):  # solver/linear.py reuse
                    summary["linear_solves"] = counts
                summary["steps"].append(rec)
                zones.record(st.step, st.load_factor)
                summary["probes"] = vals
                if rcd is not None:
                    files = None
                    if pvd is not None and (st.step % spec.output.every == 0 or st.step == n_steps
                                            or getattr(getattr(st, "state", None), "finished", False)):
                        from .export import export_step

                        paths = export_step(out, st.step, model, problem.dm, u, st.load_factor, ctl,
                                            spec.output.sampling, spec.output.frame)
                        rcd.register(paths.values())
                        rcd.register([f"{k}.pvd" for k in paths])
                        pvd.add(st.step, st.load_factor, paths)
                        files = {k: pvd._rel(p) for k, p in paths.items()}
                    rcd.step(rec, files)
                    summary["wall_seconds"] = round(wall0 + time.perf_counter() - t0, 4)
                    last = checkpoint.capture(st.step, st.load_factor, u, spec.load_factors, hash_,
                                              ctl.state(problem) if ctl is not None else None, summary,
                                              [], {}, {**_zone_arrays(zones), **_path_arrays(st),
                                                       **{f"mat/{k}": v for k, v in problem.assembler.material_state().items()}})
                    checkpoint.save(rcd.path(checkpoint.FILENAME), last, fsync=rcd.sync_due())
                    rcd.summary(summary)
                    log(f"step {st.step} converged: λ = {st.load_factor:.6g}, {st.iterations} iteration(s), "
                        f"{st.bisections} bisection(s), {st.wall_seconds:.3f} s"
                        + (f", debonded area {debonded_total():.6g}" if ctl is not None else ""))
                live["step"] = st.step + 1
            if progress is not None:
                progress(st.step, n_steps, st.load_factor)
        summary["converged"] = True
    except ConvergenceError as exc:
        done = summary["steps"][-1]["step"] if summary["steps"] else 0
        failure = {"step": done + 1, "load_factor": float(exc.load_factor),
                   "residual": float(exc.residual) if np.isfinite(exc.residual) else None}
        message = str(exc)
        if "residual" not in message and np.isfinite(exc.residual):
            message += f" (last residual {exc.residual:.3e})"
        negative = start_inertia(problem) if stab is not None else None
        if negative:  # the failed step's first solve factorised the tangent at the last converged state
            lam_last = summary["steps"][-1]["load_factor"] if summary["steps"] else lam0
            message += (f"; the tangent at the last converged state (load factor {lam_last:.6g}) has {negative} "
                        "negative eigenvalue(s): that equilibrium is unstable - the structure passed a buckling "
                        "(bifurcation) or limit point before it (summary.json 'stability')")
        summary["error"] = message
        summary["failure"] = failure
    except KeyboardInterrupt as exc:
        interrupted = True
        stop_signal = "SIGTERM" if isinstance(exc, Terminated) else "SIGINT"
        done = summary["steps"][-1] if summary["steps"] else None
        who = "stopped by SIGTERM " if stop_signal == "SIGTERM" else "interrupted by the user "
        message = (who + (f"after step {done['step']} (load factor {done['load_factor']:.6g})"
                          if done else "before the first load step converged")
                   + "; the converged steps are kept")
        summary["error"] = message
        summary["interrupted"] = True
        summary["signal"] = stop_signal
    except Exception as exc:  # write what is done, then let the caller report it
        pending = exc
        summary["error"] = f"{type(exc).__name__}: {exc}"
    finally:
        problem.monitor = None
    with _sigint_deferred(reraise=False):  # the run stops anyway: finish writing
        if stab is not None:
            if pending is None and not interrupted:
                _stability(summary, stab.add(*prev_state, _last_inertia(problem, u, summary, spec)), log,
                           locate if bisect else None)
            _stability(summary, stab.finish(), log, locate if bisect else None)
        if rcd is not None:
            if message or pending is not None:
                log(f"stopped: {summary.get('error')}")
            if last is not None and last is not ck:  # again (with fsync): a signal may have hit the step's writes
                checkpoint.save(rcd.path(checkpoint.FILENAME), last)
        summary["wall_seconds"] = round(wall0 + time.perf_counter() - t0, 4)
        if pending is not None:
            if rcd is not None:
                rcd.summary(summary, force=True)
            raise pending
        if rcd is not None and spec.profiles and summary["steps"]:
            summary["profiles"] = write_profiles(spec, problem, u, rcd, float(summary["steps"][-1]["load_factor"]))
        if rcd is not None and spec.lines and summary["steps"]:
            from .io.lines import write_lines

            summary["lines"] = write_lines(spec, problem, u, rcd, float(summary["steps"][-1]["load_factor"]))
        if rcd is not None:
            rcd.summary(summary, force=True)
            if spec.output.plots:
                from .plots import write_figures

                try:
                    figs = write_figures(out, spec, problem, u, summary, zones, through_thickness=through_thickness)
                    rcd.register(list(figs))
                except Exception as exc:  # NaN/inf results cannot be drawn: the numbers are written, say so
                    finite = np.isfinite(u).all() and all(np.isfinite(v) for v in summary["probes"].values()
                                                          if isinstance(v, (int, float)))
                    why = f"{type(exc).__name__}: {exc}" if finite else "the results hold NaN or infinite values"
                    note = (f"the figures could not be drawn ({why}); summary.json, probes.csv and the ParaView "
                            "files are written")
                    summary.setdefault("warnings", []).append(note)
                    log(f"warning: {note}")
                    rcd.summary(summary, force=True)
            log(f"finished: {'converged' if summary['converged'] else summary.get('error', 'stopped')}, "
                f"{len(summary['steps'])} step(s), {summary['wall_seconds']:.3f} s")
    return RunResult(summary["converged"], summary, problem, u, message, interrupted=interrupted, failure=failure,
                     signal=stop_signal)
