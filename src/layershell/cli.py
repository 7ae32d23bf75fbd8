"""Command line: ``layershell run | check``. Bad input ends with one paragraph and exit code 2."""
from __future__ import annotations

import sys
from pathlib import Path

import typer
from rich.console import Console

app = typer.Typer(add_completion=False, no_args_is_help=True,
                  help="layershell: layered shells that delaminate (multi-director shell FE).")
err = Console(stderr=True)
out = Console()


def _load(model: Path):
    from .io.build import InputError, load

    try:
        return load(model)
    except InputError as exc:
        err.print(f"[bold red]error:[/] {exc}", markup=True, highlight=False, soft_wrap=True)
        raise typer.Exit(2)
    except (ValueError, KeyError, IndexError) as exc:  # last line of defence: never a traceback
        err.print(f"[bold red]error:[/] {model}: {type(exc).__name__}: {exc}", highlight=False, soft_wrap=True)
        raise typer.Exit(2)


@app.command()
def check(model: Path = typer.Argument(..., help="model file (TOML)")):
    """Validate a model file without solving."""
    spec = _load(model)
    from .dofs import number_dofs
    from .constraints import ConstraintError, constraint_operator

    try:
        dm = number_dofs(spec.model)
        op = constraint_operator(spec.model, dm)
    except ConstraintError as exc:
        err.print(f"[bold red]error:[/] {model}: {exc}", highlight=False, soft_wrap=True)
        raise typer.Exit(2)
    m = spec.model
    out.print(f"{model}: OK — {m.mesh.n_elements} elements, {m.mesh.n_nodes} nodes, {len(m.layers)} layer(s), "
              f"{op.n_red} DOFs, {len(spec.load_factors)} load step(s), {len(spec.probes)} probe(s)")


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
    from .runner import run as run_model

    out_dir = out_dir or Path("results") / model.stem
    from rich.progress import BarColumn, Progress, TextColumn, TimeElapsedColumn

    with Progress(TextColumn("[bold]{task.description}"), BarColumn(), TextColumn("λ = {task.fields[lam]:.4g}"),
                  TimeElapsedColumn(), console=err, disable=quiet, transient=False) as prog:
        task = prog.add_task(model.stem, total=len(spec.load_factors), lam=0.0)
        try:
            res = run_model(spec, out_dir, lambda i, n, lam: prog.update(task, completed=i, lam=lam),
                            write_vtu=False if no_vtu else None)
        except ConstraintError as exc:
            err.print(f"[bold red]error:[/] {model}: {exc}", highlight=False, soft_wrap=True)
            raise typer.Exit(2)
    s = res.summary
    if not quiet:
        for k, v in s["probes"].items():
            out.print(f"  {k:24s} = {v: .6g}")
        out.print(f"{s['n_elements']} elements, {s['n_dofs']} DOFs, {len(s['steps'])} step(s), "
                  f"{s['wall_seconds']:.2f} s — results in {out_dir}/ (summary.json, probes.csv, *.vtu, *.pvd)")
    if not res.converged:
        err.print(f"[bold red]error:[/] {res.message}", highlight=False, soft_wrap=True)
        raise typer.Exit(1)


def main() -> None:  # console-script entry point
    app()


if __name__ == "__main__":
    sys.exit(main())
