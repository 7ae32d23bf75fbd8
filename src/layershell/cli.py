"""Command line: ``layershell run | check``. Bad input ends with one paragraph and exit code 2.

Exit codes: 0 success; 1 the solution failed (no convergence) or an internal error; 2 bad input
(model file, supports, command-line arguments). Set ``LAYERSHELL_TRACEBACK=1`` to see the Python
traceback of an unexpected error instead of the one-paragraph message.
"""
from __future__ import annotations

import os
import sys
from pathlib import Path
from typing import NoReturn

import typer
from rich.console import Console
from rich.markup import escape

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="layershell: layered shells that delaminate (multi-director shell FE).")
err = Console(stderr=True)
out = Console()


def _fail(message: str, code: int = 2) -> NoReturn:
    """Print ``error: message`` as one paragraph (no markup interpretation) and exit with ``code``."""
    text = " ".join(str(message).split())  # one paragraph: no line breaks, no blank lines
    err.print(f"[bold red]error:[/] {escape(text)}", markup=True, highlight=False, soft_wrap=True)
    raise typer.Exit(code)


def _traceback_wanted() -> bool:
    return os.environ.get("LAYERSHELL_TRACEBACK", "") not in ("", "0")


def _load(model: Path):
    from .io.build import InputError, load

    try:
        return load(model)
    except InputError as exc:
        _fail(str(exc))
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
    from .constraints import ConstraintError, constraint_operator
    from .dofs import number_dofs

    try:
        dm = number_dofs(spec.model)
        op = constraint_operator(spec.model, dm)
    except ConstraintError as exc:
        _fail(f"{model}: 'supports': {exc}")
    except Exception as exc:
        if _traceback_wanted():
            raise
        _fail(f"{model}: the supports and layer bonds could not be set up ({type(exc).__name__}: {exc}); "
              "check 'supports' (set LAYERSHELL_TRACEBACK=1 to see where it failed)")
    m = spec.model
    out.print(f"{model}: OK — {m.mesh.n_elements} elements, {m.mesh.n_nodes} nodes, {len(m.layers)} layer(s), "
              f"{op.n_red} DOFs, {len(spec.load_factors)} load step(s), {len(spec.probes)} probe(s)",
              soft_wrap=True)


@app.command()
def run(
    model: Path = typer.Argument(..., help="model file (TOML)"),
    out_dir: Path = typer.Option(None, "--out", "-o", help="results folder (default results/<model name>)"),
    no_vtu: bool = typer.Option(False, "--no-vtu", help="skip the ParaView files"),
    quiet: bool = typer.Option(False, "--quiet", "-q"),
):
    """Solve a model and write summary.json, probes.csv, ParaView files and plots."""
    spec = _load(model)
    from .constraints import ConstraintError
    from .formula import FormulaError
    from .runner import run as run_model

    out_dir = out_dir or Path("results") / model.stem
    if out_dir.exists() and not out_dir.is_dir():
        _fail(f"--out '{out_dir}' is a file, not a folder; give a folder for the results")
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), TextColumn("λ = {task.fields[lam]:.4g}"),
                  TimeElapsedColumn(), console=err, disable=quiet, transient=False) as prog:
        task = prog.add_task(escape(model.stem), total=len(spec.load_factors), lam=0.0)
        failure: tuple[str, int] | None = None
        try:
            res = run_model(spec, out_dir, lambda i, n, lam: prog.update(task, completed=i, lam=lam),
                            write_vtu=False if no_vtu else None)
        except ConstraintError as exc:
            failure = (f"{model}: 'supports': {exc}", 2)
        except FormulaError as exc:
            failure = (f"{model}: a formula or value in the model file cannot be evaluated ({exc}); "
                       "check the load magnitudes and distributions", 2)
        except OSError as exc:
            failure = (f"cannot write the results to '{out_dir}': {exc.strerror or exc}; "
                       "choose another folder with --out", 2)
        except Exception as exc:
            if _traceback_wanted():
                raise
            failure = (f"{model}: the solution stopped with an internal error ({type(exc).__name__}: {exc}); "
                       "set LAYERSHELL_TRACEBACK=1 to see where, and report it with the model file", 1)
    if failure is not None:
        _fail(*failure)
    s = res.summary
    if not quiet:
        for k, v in s["probes"].items():
            out.print(f"  {k:24s} = {v: .6g}", highlight=False)
        out.print(f"{s['n_elements']} elements, {s['n_dofs']} DOFs, {len(s['steps'])} step(s), "
                  f"{s['wall_seconds']:.2f} s — results in {out_dir}/ (summary.json, probes.csv, *.vtu, *.pvd)",
                  soft_wrap=True, highlight=False)
    if not res.converged:
        _report_failure(model, res)


def _report_failure(model: Path, res) -> None:
    """One paragraph for a solve that did not converge: free rigid-body motions are bad input (2)."""
    msg = res.message.rstrip(".")
    if "interrupted" in msg:
        _fail(msg, 1)
    kept = ("the converged steps are in summary.json and probes.csv" if res.summary.get("steps")
            else "no load step converged")
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
    else:
        cause = ("check that the supports prevent every rigid-body motion (3 translations and 3 rotations); if "
                 "they do, the load may pass a limit point or be too large for one step: use more load steps "
                 "([steps] n), a smaller lambda_end, or larger max_iterations / max_bisections")
    _fail(f"{model}: the solution failed: {msg}; {cause}; {kept}", 1)


def main() -> None:  # console-script entry point
    app()


if __name__ == "__main__":
    sys.exit(main())
