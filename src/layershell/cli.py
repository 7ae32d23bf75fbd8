"""Command line: ``layershell run | check | buckle | report | sweep | calibrate``. Bad input ends with one
paragraph and exit code 2.

Exit codes: 0 success; 1 the solution failed (no convergence) or an internal error; 2 bad input
(model file, supports, command-line arguments, a restart folder of another model, a results
folder in use or holding another model's results); 130 stopped by Ctrl-C, 143 by SIGTERM (the
converged steps are written; continue with ``--restart``). Output to a console that cannot show
a character (e.g. ``PYTHONIOENCODING=ascii``) replaces it, never fails. Set
``LAYERSHELL_TRACEBACK=1`` to see the Python traceback of an unexpected error instead of the
one-paragraph message.
"""
from __future__ import annotations

import os
import sys
import warnings
from pathlib import Path
from typing import NoReturn

import typer
from rich.console import Console
from rich.markup import escape

app = typer.Typer(add_completion=False, no_args_is_help=True, rich_markup_mode=None,
                  help="layershell: layered shells that delaminate (multi-director shell FE).")
err = Console(stderr=True)
out = Console()


def _safe_streams() -> None:
    """Characters the console cannot encode (λ, —, Θ on an ASCII console) are replaced instead of
    raising UnicodeEncodeError after the results are written."""
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.reconfigure(errors="replace")
        except (AttributeError, ValueError, OSError):
            pass


def _version_option(value: bool) -> None:
    if value:
        from . import __version__

        _safe_streams()
        out.print(f"layershell {__version__}", highlight=False)
        raise typer.Exit()


@app.callback()
def _main(version: bool = typer.Option(False, "--version", callback=_version_option, is_eager=True,
                                       help="print the version of layershell and exit")) -> None:
    """layershell: layered shells that delaminate (multi-director shell FE)."""
    _safe_streams()


def _fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: message`` as one paragraph (no markup interpretation) and exit with ``code``."""
    text = " ".join(str(message).split())  # one paragraph: no line breaks, no blank lines
    err.print(f"[bold red]error:[/] {escape(text)}", markup=True, highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _traceback_wanted() -> bool:
    return os.environ.get("LAYERSHELL_TRACEBACK", "") not in ("", "0")


def _results_folder(out_dir: Path | None, model: Path, suffix: str) -> Path:
    """``--out`` or results/<model name><suffix>; a file there is bad input."""
    out_dir = out_dir or Path("results") / f"{model.stem}{suffix}"
    try:
        is_file = out_dir.exists() and not out_dir.is_dir()
    except OSError as exc:
        _fail(_os_error_message(exc, out_dir))
    if is_file:
        _fail(f"--out '{out_dir}' is a file, not a folder; give a folder for the results")
    return out_dir


def _load(model: Path):
    from .io.build import InputError, load

    try:
        spec = load(model)
        for note in spec.model.mesh.notes:  # e.g. quad4/quad8 converted to quad9
            err.print(f"note: {escape(note)}", highlight=False, soft_wrap=True)
        for text in spec.warnings:  # valid but almost surely not meant (e.g. no loads)
            err.print(f"warning: {escape(f'{spec.path}: {text}')}", highlight=False, soft_wrap=True)
        return spec
    except InputError as exc:
        _fail(str(exc))
    except OSError as exc:  # e.g. a name too long for the file system
        _fail(_os_error_message(exc, None, reading=model))
    except Exception as exc:  # last line of defence: never a traceback
        if _traceback_wanted():
            raise
        _fail(f"{model}: the model could not be built ({type(exc).__name__}: {exc}); check the values in the "
              "model file against examples/ (set LAYERSHELL_TRACEBACK=1 to see where it failed)")


def _rigid_body_modes(problem, max_dofs: int = 3000) -> list[str] | None:
    """Describe the rigid-body motions that the supports leave free (diagnosis after a failed solve).

    Zero eigenvalues of the diagonally scaled linear stiffness whose eigenvectors are rigid motions
    of the reference face (u0 = t + ω × X). Returns None when the model is too large for the dense
    eigenvalue test or the test itself fails; [] when no rigid-body motion is free.
    """
    import numpy as np

    try:
        op = problem.op
        n = op.n_red
        if n == 0 or n > max_dofs:
            return None
        _, K = problem.assembler.evaluate(np.zeros(problem.dm.n_full), tangent=True)
        Kr = (op.T.T @ K @ op.T).toarray()
        d = np.sqrt(np.abs(np.diag(Kr)))
        d[d == 0] = 1.0
        ev, vec = np.linalg.eigh(Kr / d[:, None] / d[None, :])
        free = ev <= 1e-13 * max(abs(ev[-1]), 1e-300)  # very thin shells: ~1e-12
        if not free.any():
            return []
        model = problem.model
        k = model.stacks[0][0]
        dofs = problem.dm.layer_dofs[k][:, 0, :]  # (n_nodes, 3) director 0 of the reference-face layer
        present = np.all(dofs >= 0, axis=1)
        X = model.mesh.nodes[present]
        Xc = X - X.mean(0)
        # u0 = t + ω × (X - Xc): columns for t (3) and ω (3)
        A = np.zeros((X.shape[0], 3, 6))
        A[:, :, :3] = np.eye(3)
        for j in range(3):
            e = np.zeros(3)
            e[j] = 1.0
            A[:, :, 3 + j] = np.cross(e, Xc)
        A = A.reshape(-1, 6)
        params, fits = [], []
        for v in vec[:, free].T:
            u = op.expand(v / d)[dofs[present]].reshape(-1)
            p, *_ = np.linalg.lstsq(A, u, rcond=None)
            params.append(p)
            fits.append(np.linalg.norm(A @ p - u) <= 1e-3 * max(np.linalg.norm(u), 1e-300))
        out: list[str] = []
        P = np.array([p for p, ok in zip(params, fits) if ok]).reshape(-1, 6)
        if P.size:
            P[:, 3:] *= max(float(np.linalg.norm(Xc, axis=1).max(initial=0.0)), 1e-300)  # comparable units
            P /= np.linalg.norm(P, axis=1, keepdims=True)
            U, s, Vt = np.linalg.svd(P[:, 3:], full_matrices=True)
            n_rot = int(np.sum(s > 1e-3))
            out += [f"rotation about {a}" for a in _directions(Vt[:n_rot])]
            out += [f"translation along {a}" for a in _directions(U[:, n_rot:].T @ P[:, :3])]
        return out
    except Exception:
        return None


def _directions(M) -> list[str]:
    """Names of an orthonormal basis of the row space of ``M (k, 3)``: axes x, y, z where possible."""
    import numpy as np

    M = np.asarray(M, float).reshape(-1, 3)
    if M.size == 0:
        return []
    _, s, Vt = np.linalg.svd(M, full_matrices=False)
    Q = Vt[s > 1e-3 * max(s.max(initial=0.0), 1e-300)]
    if Q.size == 0:
        return []
    axes = [n for j, n in enumerate("xyz") if np.linalg.norm(Q[:, j]) > 1 - 1e-3]
    if len(axes) == len(Q):
        return axes
    return ["(" + ", ".join(f"{c:.3g}" for c in q) + ")" for q in Q]


@app.command()
def check(model: Path = typer.Argument(..., help="model file (TOML)")):
    """Validate a model file without solving."""
    spec = _load(model)
    from .constraints import ConstraintError
    from .loads import LoadError
    from .solver.problem import Problem

    try:  # the problem as `run` builds it: bonds, initially debonded zones and cohesive interfaces included
        problem = Problem.build(spec.model)
    except ConstraintError as exc:
        _fail(f"{model}: 'supports': {exc}")
    except LoadError as exc:
        _fail(f"{model}: 'loads': {exc}")
    except Exception as exc:
        if _traceback_wanted():
            raise
        _fail(f"{model}: the supports, layer bonds, loads and interfaces could not be set up ({type(exc).__name__}: "
              f"{exc}); check 'supports', 'loads' and 'interfaces' (set LAYERSHELL_TRACEBACK=1 to see where it failed)")
    m = spec.model
    from .checks import pre_run_warnings

    for text in pre_run_warnings(spec):  # supports that do not hold a layer, a mesh coarser than the process zone
        err.print(f"warning: {escape(f'{model}: {text}')}", highlight=False, soft_wrap=True)
    pf = spec.path_following
    if pf is None:
        steps = f"{len(spec.load_factors)} load step(s)"
    else:  # the steps are sized as the run goes
        steps = (f"{'arc length' if pf.control == 'arc_length' else 'adaptive load steps'} to λ = {pf.lambda_end:g} "
                 f"(first increment {pf.increment:g}, at most {pf.max_steps} increments)")
    out.print(f"{model}: OK — {m.mesh.n_elements} elements, {m.mesh.n_nodes} nodes, {len(m.layers)} layer(s), "
              f"{_dof_counts(problem.op.n_red, problem.dm.n_full)}, {steps}, {len(spec.probes)} probe(s)",
              soft_wrap=True)


def _dof_counts(unknowns: int, all_dofs: int) -> str:
    """The DOF counts of `check` and `run`: the unknowns solved for (after the supports, bonds and
    ties) at the start, and all DOFs of the layers."""
    return f"{unknowns} unknowns after constraints ({all_dofs} DOFs in all)"


@app.command()
def run(
    model: Path = typer.Argument(..., help="model file (TOML)"),
    out_dir: Path = typer.Option(None, "--out", "-o", help="results folder (default results/<model name>, "
                                 "with --restart the folder restarted from)"),
    no_vtu: bool = typer.Option(False, "--no-vtu", help="skip the ParaView files"),
    quiet: bool = typer.Option(False, "--quiet", "-q", help="no progress line and no probe table"),
    verbose: bool = typer.Option(False, "--verbose", "-v", help="print every line of run.log (each Newton "
                                 "iteration: residual, energy norm; bond and contact changes) while solving"),
    restart: Path = typer.Option(None, "--restart", help="continue a stopped run from the last converged step "
                                 "saved in this results folder (checkpoint.npz)"),
    overwrite: bool = typer.Option(False, "--overwrite", help="delete the results of another model in the "
                                   "results folder (without it such a folder is refused; a rerun of the same "
                                   "model file replaces its own results anyway)"),
):
    """Solve a model and write summary.json, probes.csv, run.log, ParaView files and plots.

    Every converged step is recorded at once (with the restart file checkpoint.npz). Ctrl-C or
    SIGTERM stop cleanly after the converged steps (exit code 130 or 143); --restart DIR continues
    from there. One run at a time may write into a results folder.
    """
    spec = _load(model)
    from .checkpoint import CheckpointError
    from .constraints import ConstraintError
    from .formula import FormulaError
    from .loads import LoadError
    from .recorder import ResultsFolderError
    from .runner import raise_terminated
    from .runner import run as run_model

    if restart is not None and out_dir is None:
        out_dir = restart if restart.is_dir() else restart.parent
    out_dir = _results_folder(out_dir, model, "")
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    failure: tuple[str, int] | None = None
    old_term = _install_sigterm(raise_terminated)
    try:
        with Progress(TextColumn("[bold]{task.description}"), BarColumn(), TextColumn("{task.fields[state]}"),
                      TimeElapsedColumn(), console=err, disable=quiet, transient=False) as prog:
            task = prog.add_task(escape(model.stem), total=len(spec.load_factors), state="λ = 0")
            live = {"lam": 0.0}

            def on_step(i, n, lam):
                live["lam"] = lam
                prog.update(task, completed=i, state=f"λ = {lam:.4g}")

            def on_iteration(info):
                state = (f"λ = {live['lam']:.4g} | step {info['step']} → λ {info['load_factor']:.4g}: "
                         f"iteration {info['iteration']}, residual {info['relative_residual']:.2e}")
                if info["resolves"]:
                    state += f", re-solutions {info['resolves']}"
                if info["debonded_area"]:
                    state += f", debonded {info['debonded_area']:.4g}"
                prog.update(task, state=state)

            def echo(line):
                prog.console.print(escape(line), highlight=False, soft_wrap=True)

            try:
                with warnings.catch_warnings(record=True) as caught:  # numerical warnings: one note below
                    warnings.simplefilter("default")
                    res = run_model(spec, out_dir, on_step, write_vtu=False if no_vtu else None, restart=restart,
                                    overwrite=overwrite, monitor=None if quiet else on_iteration,
                                    echo=echo if verbose else None)
            except (CheckpointError, ResultsFolderError) as exc:
                failure = (f"{model}: {exc}", 2)
            except ConstraintError as exc:
                failure = (f"{model}: 'supports': {exc}", 2)
            except LoadError as exc:
                failure = (f"{model}: 'loads': {exc}", 2)
            except FormulaError as exc:
                failure = (f"{model}: a formula or value in the model file cannot be evaluated ({exc}); "
                           "check the load magnitudes and distributions", 2)
            except OSError as exc:
                failure = (_os_error_message(exc, out_dir), 2)
            except MemoryError:
                failure = (f"{model}: the model needs more memory than this computer has; use a coarser mesh, "
                           "fewer layers or fewer directors", 2)
            except KeyboardInterrupt:
                raise
            except Exception as exc:
                if _traceback_wanted():
                    raise
                failure = (f"{model}: the solution stopped with an internal error ({type(exc).__name__}: {exc}); "
                           "the converged steps are in summary.json; set LAYERSHELL_TRACEBACK=1 to see where, and "
                           "report it with the model file", 1)
    except KeyboardInterrupt as exc:  # before the first load step (building the problem)
        term = type(exc).__name__ == "Terminated"
        failure = (f"{model}: {'stopped by SIGTERM' if term else 'interrupted by the user'} before the first load "
                   "step; nothing was solved", 143 if term else 130)
    finally:
        _install_sigterm(old_term)
    if failure is not None:
        _fail(*failure)
    numeric = [w for w in caught if issubclass(w.category, RuntimeWarning)]
    notes = set(res.summary.get("warnings", []))  # the run's own warnings: printed once, below
    for w in caught:  # other warnings as usual
        if not issubclass(w.category, RuntimeWarning) and str(w.message) not in notes:
            warnings.showwarning(w.message, w.category, w.filename, w.lineno)
    if numeric and res.converged:  # a failed run explains itself; a converged one may hold NaN values
        first = " ".join(str(numeric[0].message).split())
        err.print(f"warning: {len(numeric)} numerical warning(s) during the solution (first: {escape(first)}); check "
                  "summary.json and probes.csv for NaN or infinite values", soft_wrap=True, highlight=False)
    s = res.summary
    for note in s.get("warnings", []):
        err.print(f"warning: {escape(note)}", soft_wrap=True, highlight=False)
    if not quiet:
        for k, v in s["probes"].items():
            out.print(f"  {k:24s} = {v: .6g}", highlight=False)
        out.print(f"{s['n_elements']} elements, {_dof_counts(s['n_dofs'], s['n_dofs_full'])}, "
                  f"{len(s['steps'])} step(s), "
                  f"{s['wall_seconds']:.2f} s — results in {out_dir}/ (summary.json, probes.csv, run.log, "
                  "*.vtu, *.pvd)", soft_wrap=True, highlight=False)
    if not res.converged:
        _report_failure(model, res, out_dir)


def _install_sigterm(handler):
    """Install ``handler`` for SIGTERM (main thread only); returns the previous one (or None)."""
    import signal
    import threading

    if not hasattr(signal, "SIGTERM") or threading.current_thread() is not threading.main_thread():
        return None
    try:
        return signal.signal(signal.SIGTERM, handler if handler is not None else signal.SIG_DFL)
    except (ValueError, OSError):
        return None


def _os_error_message(exc: OSError, out_dir: Path | None, reading: Path | None = None) -> str:
    """One paragraph for a file that cannot be written (name too long, no space, no permission),
    or, with ``reading``, for a model file that cannot be read."""
    import errno

    name = getattr(exc, "filename", None) or out_dir or reading
    if reading is not None:
        if exc.errno == errno.ENAMETOOLONG:
            return (f"cannot read the model file '{reading}': its name is too long for the file system "
                    f"({len(Path(reading).name)} characters; at most 255 bytes per file or folder name); rename "
                    "the file")
        return (f"cannot read '{name}' (needed by the model file '{reading}'): {exc.strerror or exc}; check the "
                "path and the permissions")
    if exc.errno == errno.ENAMETOOLONG:
        return (f"cannot write the results: the path '{name}' is too long for the file system (a file or folder "
                "name may have at most 255 bytes); choose a shorter folder with --out or a shorter model file name")
    if exc.errno == errno.ENOSPC:
        return f"cannot write the results to '{out_dir}': the disk is full; free space or choose another folder with --out"
    if exc.errno in (errno.EACCES, errno.EPERM, errno.EROFS):
        return (f"cannot write the results to '{out_dir}': no permission to write '{name}'; choose a folder you "
                "may write to with --out")
    return f"cannot write the results to '{out_dir}': {exc.strerror or exc}; choose another folder with --out"


def _report_failure(model: Path, res, out_dir: Path | None = None) -> None:
    """One paragraph for a run that stopped early: Ctrl-C (exit code 130) with the restart command;
    free rigid-body motions are bad input (2); other non-convergence names the step, the load
    factor and the last residual (1). The converged steps are kept in every case."""
    msg = res.message.rstrip(".")
    where = f"'{out_dir}'" if out_dir is not None else "the results folder"
    if getattr(res, "interrupted", False) or "interrupted" in msg:
        again = (f"; continue with: layershell run {model} --restart {out_dir}" if out_dir is not None
                 and res.summary.get("steps") else "")
        code = 143 if getattr(res, "signal", None) == "SIGTERM" else 130
        _fail(f"{model}: {msg}; summary.json and probes.csv in {where} hold them{again}", code)
    kept = (f"the {len(res.summary['steps'])} converged step(s) are kept in summary.json and probes.csv in {where}"
            if res.summary.get("steps") else "no load step converged")
    modes = _rigid_body_modes(res.problem)
    if modes:
        _fail(f"{model}: 'supports': the supports leave {len(modes)} rigid-body motion(s) free "
              f"({', '.join(modes)}), so the stiffness matrix is singular and the solution failed ({msg}); "
              "supports must prevent every rigid-body motion (3 translations and 3 rotations): add or extend "
              "[[supports]] entries, e.g. a 'fix' at a point with the missing components", 2)
    if "singular" in msg:
        cause = ("the stiffness matrix is singular, usually because the supports leave a rigid-body motion free: "
                 "supports must prevent every rigid-body motion (3 translations and 3 rotations), so check "
                 "'supports'")
    elif "the run has reached complete separation" in msg:  # solver/newton.py separated_hint
        cause = ("every interface point had debonded, so the layers part: that is the end of the debonding, not a "
                 "fault of the model or of the step size (where it comes earlier than expected, check the "
                 "interfaces' strengths and the loads on the loose layer)")
    elif "the regularisation, not the interface, carries the load" in msg:  # stabilised (solver/newton.py)
        cause = "the load factors beyond the limit point are not equilibrium states of the rate-independent law"
    else:
        cause = _post_peak_cause(res.summary) or (
            "check that the supports prevent every rigid-body motion (3 translations and 3 rotations); if "
            "they do, the load may pass a limit point or be too large for one step: use more load steps "
            "([steps] n), a smaller lambda_end, or larger max_iterations / max_bisections")
    _fail(f"{model}: the solution failed: {msg}; {cause}; {kept}", 1)


#: a run whose last converged load factor lies more than this share below the largest one before it
#: stopped on a branch after a peak (:func:`_post_peak_cause`)
POST_PEAK = 0.01


def _post_peak_cause(summary: dict) -> str | None:
    """The advice for a run that stopped after passing a peak of its load factor (a path followed by
    arc length: a force, or a prescribed displacement past a snap-back): the largest load factor,
    where it was reached, and that the path stopped on a falling branch - not the generic hint
    about supports and step sizes, which a structure that carried the peak does not need. None
    where the last converged load factor is within POST_PEAK of the largest one (or no step
    converged)."""
    steps = summary.get("steps") or []
    lams = [st.get("load_factor") for st in steps]
    if not lams or any(not isinstance(x, (int, float)) for x in lams):
        return None
    k = max(range(len(lams)), key=lambda i: lams[i])
    peak, last = lams[k], lams[-1]
    if not peak > 0.0 or not last < (1.0 - POST_PEAK) * peak:
        return None
    return (f"the path had passed a peak of the load factor, {peak:.6g} at step {steps[k].get('step', k + 1)}, "
            f"and stopped {1.0 - last / peak:.1%} below it on the branch after it: the steps up to here, the peak "
            "included, are equilibrium states; past a peak a quasi-static path can end where it branches "
            "or where the debonding or the friction jumps, and a later branch may rise again, so this peak "
            "is the largest load so far, not necessarily the capacity (a finer mesh along the debonding front "
            "may pass such a stop)")


def _guarded(what: str, fn, *args, **kwargs):
    """Call ``fn``: InputError → one paragraph, exit 2; other errors → exit 1 (no traceback)."""
    from .io.build import InputError

    try:
        return fn(*args, **kwargs)
    except InputError as exc:
        _fail(str(exc))
    except OSError as exc:
        _fail(f"{what}: cannot read or write '{getattr(exc, 'filename', '') or ''}': {exc.strerror or exc}; "
              "check the paths and choose another folder with --out", 2)
    except Exception as exc:
        if _traceback_wanted():
            raise
        _fail(f"{what} stopped with an internal error ({type(exc).__name__}: {exc}); set LAYERSHELL_TRACEBACK=1 "
              "to see where, and report it with the model file", 1)


@app.command()
def buckle(
    model: Path = typer.Argument(..., help="model file (TOML)"),
    modes: int = typer.Option(3, "--modes", "-n", min=1, help="number of buckling modes"),
    out_dir: Path = typer.Option(None, "--out", "-o", help="results folder (default results/<model name>_buckle)"),
):
    """Linear (eigenvalue) buckling of the model under its loads at λ = 1, the layers bonded except the
    initially debonded zones of [[interfaces]] (open, without contact): writes buckling.json, buckling.csv,
    buckling_mode_<k>.vtu, buckling_modes.npz (for [imperfection]) and buckling_modes.png."""
    spec = _load(model)
    from .buckling import BucklingError, linear_buckling
    from .buckling_output import write_buckling
    from .constraints import ConstraintError
    from .loads import LoadError

    out_dir = _results_folder(out_dir, model, "_buckle")
    from .io.build import InputError

    def analyse():
        try:
            return linear_buckling(spec.model, modes, spec.newton.backend)
        except BucklingError as exc:
            raise InputError(f"{model}: {exc}") from None
        except ConstraintError as exc:
            raise InputError(f"{model}: 'supports': {exc}") from None
        except LoadError as exc:
            raise InputError(f"{model}: 'loads': {exc}") from None

    res = _guarded(f"buckling analysis of {model}", analyse)
    info = {"title": spec.source.model.title, "model_file": str(model), "units": spec.model.units}
    _guarded(f"buckling files of {model}", write_buckling, out_dir, res, info)
    for k, lam in enumerate(res.load_factors, start=1):
        out.print(f"  mode {k}: load factor {lam:.6g}", highlight=False)
    if len(res.load_factors) < modes:
        err.print(f"warning: {len(res.load_factors)} of the {modes} modes asked for have a positive load factor "
                  "(the others would buckle under the reversed load)", soft_wrap=True, highlight=False)
    state = "with its initial delaminations open" if spec.model.interface_laws else "bonded"
    out.print(f"{len(res.load_factors)} buckling mode(s) of the model ({state}), {res.problem.op.n_red} unknowns — "
              f"results in {out_dir}/ (buckling.json, buckling.csv, buckling_mode_*.vtu, buckling_modes.npz, "
              "buckling_modes.png)", soft_wrap=True, highlight=False)


@app.command()
def report(
    results: Path = typer.Argument(..., help="results folder written by run, sweep or calibrate"),
    out_file: Path = typer.Option(None, "--out", "-o", help="HTML file to write (default DIR/report.html)"),
    model: Path = typer.Option(None, "--model", help="the model file, named in the report"),
):
    """Write a self-contained HTML report (tables and embedded figures) of a results folder."""
    from .report import write_report

    path = _guarded(f"report of '{results}'", write_report, results, out_file, model)
    out.print(f"report written to {path}", highlight=False, soft_wrap=True)


@app.command()
def sweep(
    model: Path = typer.Argument(..., help="model file (TOML)"),
    sets: list[str] = typer.Option(..., "--set", help="KEY=V1,V2,... with a dotted model-file path as KEY, e.g. "
                                   "interfaces.0.tau_max=1.0,1.2; several --set give the Cartesian product"),
    out_dir: Path = typer.Option(None, "--out", "-o", help="results folder (default results/<model name>_sweep)"),
    jobs: int = typer.Option(None, "--jobs", "-j", min=1, help="parallel processes (default: number of cores)"),
    vtu: bool = typer.Option(False, "--vtu", help="also write the ParaView files of every variant"),
    quiet: bool = typer.Option(False, "--quiet", "-q"),
):
    """Run variants of a model in parallel and tabulate their final probes (sweep.csv).

    Exit code 0 when every variant converged, 1 when some did not (they are rows with an error),
    2 for bad input (a path or value that does not fit the model file)."""
    from rich.table import Table

    from .sweep import parse_assignment
    from .sweep import sweep as run_sweep

    pairs = [_guarded("--set", parse_assignment, a) for a in sets]
    out_dir = _results_folder(out_dir, model, "_sweep")

    def progress(rec):
        if not quiet:
            state = "ok" if rec["converged"] else "FAILED"
            err.print(f"variant {rec['index']}: {escape(str(rec['values']))} {state} ({rec.get('wall_seconds')} s)",
                      highlight=False, soft_wrap=True)

    from rich.progress import Progress

    with Progress(console=err, disable=quiet, transient=True) as checks:  # validation of many variants
        task = checks.add_task("checking the variants", total=None)
        res = _guarded(f"sweep of {model}", run_sweep, model, pairs, out_dir, jobs, vtu, progress,
                       lambda i, n: checks.update(task, completed=i, total=n, visible=i < n))
    if not quiet:
        table = Table(title=f"{model.name}: {len(res.rows)} variant(s) — {res.out / 'sweep.csv'}")
        shown = [h for h in res.header if h not in ("folder", "error", "wall_seconds")]
        for h in shown:
            table.add_column(escape(h), justify="left" if h == "variant" else "right", overflow="fold")
        idx = [res.header.index(h) for h in shown]
        for r in res.rows:
            table.add_row(*[escape(f"{r[i]:.6g}" if isinstance(r[i], float) else str(r[i])) for i in idx])
        out.print(table)
        for r in res.rows:
            if r[-1]:
                err.print(f"{r[0]}: {escape(str(r[-1]))}", highlight=False, soft_wrap=True)
    if res.failed:
        _fail(f"{res.failed} of {len(res.rows)} variant(s) did not converge; see the 'error' column of "
              f"{res.out / 'sweep.csv'} and their folders", 1)


@app.command()
def calibrate(
    model: Path = typer.Argument(..., help="model file (TOML); its values are the start unless given"),
    data: Path = typer.Option(..., "--data", help="measured curve: CSV file with a header row"),
    x: str = typer.Option("load_factor", "--x", help="column of the data and model quantity on the x axis: "
                          "load_factor, a probe name, debonded_area[:interface]"),
    y: str = typer.Option(..., "--y", help="column of the data and model quantity on the y axis"),
    params: list[str] = typer.Option(..., "--param", help="KEY=LOWER:UPPER[:START], a dotted model-file path "
                                     "and its bounds, e.g. interfaces.0.tau_max=1.0:3.0"),
    out_dir: Path = typer.Option(None, "--out", "-o", help="results folder (default results/<model name>_calibration)"),
    method: str = typer.Option("auto", "--method", help="auto (bounded Brent for one parameter, least_squares "
                               "for several), bounded or least_squares"),
    max_runs: int = typer.Option(40, "--max-runs", help="most model runs"),
    xtol: float = typer.Option(1e-3, "--xtol", help="tolerance on the parameters, fraction of the bound range"),
    no_best_run: bool = typer.Option(False, "--no-best-run", help="do not re-run the best parameters into OUT/best"),
    quiet: bool = typer.Option(False, "--quiet", "-q"),
):
    """Fit model-file parameters to a measured curve (bounded SciPy optimisation of the RMS difference)."""
    from .calibrate import calibrate as run_calibration
    from .calibrate import parse_param

    plist = [_guarded("--param", parse_param, a) for a in params]
    out_dir = _results_folder(out_dir, model, "_calibration")

    def progress(rec):
        if not quiet:
            vals = ", ".join(f"{k}={v:.6g}" for k, v in rec["values"].items())
            err.print(f"run: {escape(vals)} → RMS {rec['objective']:.6g}"
                      + (f" ({escape(rec['error'])})" if rec["error"] else ""), highlight=False, soft_wrap=True)

    res = _guarded(f"calibration of {model}", run_calibration, model, data, x, y, plist, out_dir, method,
                   max_runs, xtol, not no_best_run, progress)
    if not quiet:
        for k, v in res.best.items():
            out.print(f"  {k:32s} = {v: .6g}", highlight=False)
        out.print(f"RMS {res.objective_start:.6g} at the start → {res.objective:.6g} after {res.evaluations} model "
                  f"run(s) ({res.method}: {res.message}) — {out_dir}/calibration.json, calibration.png",
                  highlight=False, soft_wrap=True)


def main() -> None:  # console-script entry point
    app()


if __name__ == "__main__":
    sys.exit(main())
