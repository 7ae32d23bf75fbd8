"""``mpiexec -n N python -m layershell.parallel MODEL.toml [--mode linear|newton] [--out r.npz]``.

Solves a bonded model, or one with cohesive interfaces, distributed over N ranks and writes (rank 0)
an ``.npz`` with the reduced solution ``x_red`` (linear mode) or the final full displacement
``u_full`` (newton mode; with cohesive interfaces also every step's ``u_steps`` and committed
``damage_steps``), and the phase timings (maximum over the ranks). Prints one JSON line with the
timings.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

import numpy as np


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m layershell.parallel", description=__doc__.splitlines()[0])
    ap.add_argument("model", help="model file (TOML)")
    ap.add_argument("--mode", choices=("linear", "newton"), default="linear",
                    help="linear: one solve K_r x = Tᵀ(λF) at u = 0; newton: the [steps] (load factors, or "
                         "arc length / adaptive steps)")
    ap.add_argument("--lam", type=float, default=1.0, help="load factor of the linear solve (default 1)")
    ap.add_argument("--solver", choices=("mumps", "gamg"), default="mumps")
    ap.add_argument("--repeat", type=int, default=1, help="linear mode: assemble and solve this often (timing)")
    ap.add_argument("--out", default=None, help="write the result here (.npz, rank 0)")
    args, petsc_args = ap.parse_known_args(argv)

    from .petsc import PetscUnavailableError, find_petsc4py, import_petsc, unavailable_message

    try:
        find_petsc4py()
        import petsc4py

        petsc4py.init([sys.argv[0], *petsc_args])  # remaining options go to PETSc (-ls_ksp_view, ...)
        PETSc, _ = import_petsc()
    except PetscUnavailableError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    except (ImportError, ValueError) as exc:  # ValueError: petsc4py built for another NumPy
        print(f"error: {unavailable_message(exc)}", file=sys.stderr)
        return 2
    from ..io.build import InputError, load
    from ..solver.arclength import PathError
    from ..solver.newton import ConvergenceError
    from .petsc import DistributedProblem, SolveError, UnsupportedModelError

    t_start = time.perf_counter()
    try:
        spec = load(args.model)
        pb = DistributedProblem(spec.model, solver=args.solver)
    except (InputError, UnsupportedModelError) as exc:
        if PETSc.COMM_WORLD.getRank() == 0:
            print(f"error: {exc}", file=sys.stderr)
        return 2
    out: dict = {"ranks": pb.size, "n_red": pb.op.n_red, "n_full": pb.dm.n_full, "nnz": pb.nnz,
                 "n_elements": int(spec.model.mesh.elements.shape[0]),
                 "elements_per_rank": np.diff(pb.bounds).tolist()}
    steps: list = []
    damage: list = []
    rc = 0

    def step_arrays() -> dict:
        if not steps:
            return {}
        arrays = {"u_full": steps[-1][1], "load_factors": np.array([s[0] for s in steps]),
                  "iterations": np.array([s[2] for s in steps])}
        if pb.interfaces is not None or spec.path_following is not None:  # every step's u and damage
            arrays.update(u_steps=np.array([s[1] for s in steps]), damage_steps=np.array(damage))
        return arrays

    try:
        if args.mode == "linear":
            for _ in range(args.repeat):
                x = pb.solve_linear(args.lam)
            arrays = {"x_red": x, "u_full": pb.op.expand(x)}
        else:
            for st in pb.steps(spec.load_factors, spec.newton, spec.path_following):
                steps.append(st)
                damage.append(pb.damage())
            arrays = step_arrays()
    except (ConvergenceError, SolveError) as exc:  # collective: every rank stops here
        if pb.rank == 0:
            print(f"error: {exc}", file=sys.stderr)
        if not steps:
            return 1
        # the converged steps so far are written (a force-controlled run that stops at its peak)
        arrays, rc = step_arrays(), 1
        out["stopped"] = str(exc)
    except (PathError, UnsupportedModelError) as exc:  # bad [steps] settings for this model
        if pb.rank == 0:
            print(f"error: {exc}", file=sys.stderr)
        return 2
    t = pb.finish_timings()
    total = pb._max(time.perf_counter() - t_start)
    out.update(setup_s=t.setup, assemble_s=t.assemble, solve_s=t.solve, gather_s=t.gather,
               setup_cpu_s=t.setup_cpu, assemble_cpu_s=t.assemble_cpu, solve_cpu_s=t.solve_cpu,
               evaluations=t.evaluations, total_s=total, solver=args.solver, mode=args.mode)
    if pb.rank == 0:
        print(json.dumps(out))
        if args.out:
            np.savez(args.out, **arrays, info=json.dumps(out))
    pb.destroy()
    return rc


if __name__ == "__main__":
    sys.exit(main())
