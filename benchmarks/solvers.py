"""Sparse direct solvers on the reduced tangents of this project's models.

    python benchmarks/solvers.py [--plate 16] [--mmd-max-dofs 40000] [--repeat 3]

Tangents K_r = Tᵀ K T at u = 0 (λ = 0) of examples/pulloff.toml, examples/cantilever_plate_bonded.toml
and of the two-layer d = 3 plate of benchmarks/scaling.py with ``--plate`` elements per side.
For each: SciPy SuperLU with COLAMD and with MMD_AT_PLUS_A ordering, MKL PARDISO in the real
symmetric indefinite mode (mtype -2, upper triangle, as used by linear.py) and in the general
mode (mtype 11, used where a tangent is not symmetric); the symmetric mode with both orderings
(METIS nested dissection and minimum degree: ``linear.PardisoSymmetric(ordering="auto")``
analyses a solver's first pattern with both and keeps the one with fewer flops). Reported: factorisation
seconds (PARDISO: symbolic analysis and numerical factorisation separately; the analysis is done
once per bond state and reused), factor nonzeros, fill = factor nonzeros / nnz(K_r) (a symmetric
factor stores one triangle), PARDISO's factorisation MFLOP, and the relative residual of one solve. Best of ``--repeat`` runs.
Last line: ``solvers {json}``.
"""
from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

ROOT = Path(__file__).resolve().parents[1]


def tangent_of_example(name: str):
    from layershell.io.build import load
    from layershell.solver.problem import Problem

    pb = Problem.build(load(ROOT / "examples" / f"{name}.toml").model)
    return tangent(pb)


def tangent(pb):
    u = np.zeros(pb.dm.n_full)
    f, Kr = pb.assembler.evaluate_reduced(u, pb.op)
    r = pb.op.reduce(pb.external(1.0) - f)
    if not np.any(r):
        r = np.ones(Kr.shape[0])
    return Kr, r


def best(fn, repeat: int):
    """(min seconds, last result) of ``repeat`` calls of ``fn``."""
    ts, out = [], None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        ts.append(time.perf_counter() - t0)
    return min(ts), out


def superlu(K, r, spec: str, repeat: int) -> dict:
    A = sp.csc_matrix(K)
    t, lu = best(lambda: spla.splu(A, permc_spec=spec), repeat)
    x = lu.solve(r)
    fnnz = lu.L.nnz + lu.U.nnz
    return {"factor_s": t, "factor_nnz": int(fnnz), "fill": fnnz / K.nnz,
            "residual": float(np.linalg.norm(K @ x - r) / np.linalg.norm(r))}


def pardiso(K, r, general: bool, repeat: int, ordering: str = "metis") -> dict:
    from layershell.solver import linear

    s = linear.PardisoGeneral(ordering) if general else linear.PardisoSymmetric(ordering)
    A = s.matrix(K)
    b = np.asfortranarray(r)
    A = s._check(A)
    ta, _ = best(lambda: s._call(A, 11, b), 1)
    tf, _ = best(lambda: s._call(A, 22, b), repeat)
    x = s._call(A, 33, b)
    fnnz, mflop = int(s._s.iparm[17]), int(s._s.iparm[18])
    s.release()
    return {"analysis_s": ta, "factor_s": tf, "factor_nnz": fnnz, "fill": fnnz / K.nnz, "mflop": mflop,
            "residual": float(np.linalg.norm(K @ x - r) / np.linalg.norm(r))}


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--plate", type=int, default=16, help="elements per side of the d = 3 plate (0: none)")
    ap.add_argument("--mmd-max-dofs", type=int, default=40_000, help="skip SuperLU/MMD above this size (slow)")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    sys.path.insert(0, str(Path(__file__).parent))
    from scaling import plate

    from layershell.solver import linear
    from layershell.solver.problem import Problem

    cases = {"pulloff (λ = 0)": lambda: tangent_of_example("pulloff"),
             "cantilever_plate_bonded": lambda: tangent_of_example("cantilever_plate_bonded")}
    if a.plate:
        cases[f"plate {a.plate}x{a.plate}, 2 layers d = 3"] = lambda: tangent(Problem.build(plate(a.plate, 3)))
    have_pardiso = linear.backend_name("auto") == "pardiso"
    load = os.getloadavg()
    print(f"# {os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; best of {a.repeat}")
    print(f"{'case':<34} {'dofs':>8} {'nnz':>10} {'solver':<30} {'analysis_s':>10} {'factor_s':>9} "
          f"{'factor_nnz':>11} {'fill':>6} {'residual':>9}")
    results = []
    for case, make in cases.items():
        K, r = make()
        runs = {"superlu COLAMD": lambda: superlu(K, r, "COLAMD", a.repeat)}
        if K.shape[0] <= a.mmd_max_dofs:
            runs["superlu MMD_AT_PLUS_A"] = lambda: superlu(K, r, "MMD_AT_PLUS_A", a.repeat)
        if have_pardiso:
            runs["pardiso symmetric (-2) metis"] = lambda: pardiso(K, r, False, a.repeat, "metis")
            runs["pardiso symmetric (-2) mmd"] = lambda: pardiso(K, r, False, a.repeat, "mmd")
            runs["pardiso general (11)"] = lambda: pardiso(K, r, True, a.repeat)
        for solver, fn in runs.items():
            res = fn()
            row = {"case": case, "dofs": K.shape[0], "nnz": K.nnz, "solver": solver, **res}
            results.append(row)
            print(f"{case:<34} {K.shape[0]:>8} {K.nnz:>10} {solver:<30} {res.get('analysis_s', 0.0):>10.3f} "
                  f"{res['factor_s']:>9.3f} {res['factor_nnz']:>11} {res['fill']:>6.2f} {res['residual']:>9.1e}",
                  flush=True)
    print("solvers " + json.dumps({"load_average": round(load[0], 2), "cpus": os.cpu_count(),
                                   "results": [{k: (round(v, 4) if isinstance(v, float) and k != "residual" else v)
                                                for k, v in row.items()} for row in results]}))


if __name__ == "__main__":
    main()
