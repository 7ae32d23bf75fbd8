"""Cost of the transverse-stress recovery against one Newton iteration of the same model.

    python benchmarks/recovery.py [--n 8 16 32] [--repeat 3]

Model: the simply supported [0/90/0] plate of tests/test_recovery.py (quarter, n × n elements,
three plies with d = 3, linear). One Newton iteration = internal force + tangent
(``assembler.evaluate``), the reduced matrix Tᵀ K T and the sparse solve, timed once the
factorisation pattern is known (second iteration). Recovery, per displacement state: the stresses at the
Gauss levels of every layer, the two patch-recovery products and the evaluation at every point
the solid ParaView file writes (all elements × layers × 27 lattice points); the patch operators
themselves (``Recovery(...)``) are built once per model and reported separately.
Last line, for the largest mesh: ``recovery/newton=<ratio>`` (the recovery of one state,
the target "recovery costs less than one Newton iteration": below 1) and
``with_solid_vtu/newton=<ratio>`` (plus the evaluation at every lattice point of the solid
ParaView file, an output step's whole stress export).
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))


def best(fn, repeat):
    ts = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return min(ts)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, nargs="+", default=[8, 16, 32])
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args()
    from test_recovery import cross_ply_plate

    from layershell.export import solid_mesh
    from layershell.recovery import Recovery
    from layershell.solver.linear import LinearSolver

    rows = []
    for n in args.n:
        m, pb, u, _ = cross_ply_plate(10, n=n)
        op = pb.op
        solver = LinearSolver()

        def newton_iteration():
            f, K = pb.assembler.evaluate(u)
            Kr = (op.T.T @ K @ op.T).tocsr()
            solver.solve(Kr, op.T.T @ f + 1e-3 * np.ones(Kr.shape[0]))

        newton_iteration()  # the solver's symbolic analysis, as after the first iteration of a run
        newton = best(newton_iteration, args.repeat)
        t0 = time.perf_counter()
        rec = Recovery(m, pb.dm)
        setup = time.perf_counter() - t0

        def fields():
            rec._cache = None
            rec.fields(u)

        t_fields = best(fields, args.repeat)
        import layershell.recovery as R

        R._INSTANCES[:] = [(lambda: m, lambda: pb.dm, rec)]

        def solid():
            rec._cache = None
            solid_mesh(m, pb.dm, u)

        t_solid = best(solid, args.repeat)
        rows.append({"n": n, "dofs": int(op.n_red), "newton_s": round(newton, 4), "setup_s": round(setup, 4),
                     "fields_s": round(t_fields, 4), "fields_plus_solid_vtu_s": round(t_solid, 4),
                     "ratio": round(t_fields / newton, 3), "ratio_with_solid_vtu": round(t_solid / newton, 3)})
        print(json.dumps(rows[-1]), flush=True)
    print(f"load={os.getloadavg()[0]:.2f}")
    print(f"recovery/newton={rows[-1]['ratio']} with_solid_vtu/newton={rows[-1]['ratio_with_solid_vtu']}")


if __name__ == "__main__":
    main()
