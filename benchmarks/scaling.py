"""Scaling of one Newton iteration with the mesh: two-layer plate under pressure.

    python benchmarks/scaling.py [--directors 2] [--sizes 12 17 24 34 48] [--max-dofs 300000]

A square plate (side = n elements, 9-node elements) of two bonded layers with ``--directors``
directors each, clamped at x = 0 (every director of the base layer), under a uniform pressure on
the top face. Each mesh runs in its own subprocess (so that the peak memory is its own) and
measures one full Newton iteration from u = 0 exactly as ``newton.py`` does it:

* ``build_s``: Problem.build (DOF map, constraint operator T, full pattern + scatter, geometry);
* ``map_s``: the reduced pattern and scatter map of K_r = Tᵀ K T (once per bond state);
* ``assembly_s``: element kernels + scatter into K_r (``Assembler.evaluate_reduced``) + Tᵀ f;
* ``convert_s``: the symmetry check and the upper triangle handed to PARDISO (linear.py);
* ``analysis_s``, ``factor_s``, ``solve_s``: PARDISO phases 11 / 22 / 33 (SuperLU: analysis 0);
* ``iteration_s`` = assembly + convert + analysis + factor + solve (wall clock);
  ``iteration_cpu_s``, ``total_cpu_s``: the process's CPU time (all threads) for the same, less
  sensitive to other processes on a shared machine; ``peak_rss_gib``: peak
  resident memory of the process (ru_maxrss, includes MKL's factor); ``factor_mem_gib``:
  PARDISO's own report of its peak memory.

The exponent of iteration time (and of the total including build/map) against reduced DOFs is
fitted by least squares in log-log. Last line: ``scaling {json}``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import subprocess
import sys
import time

import numpy as np


def plate(n: int, directors: int):
    from layershell.material import Orthotropic
    from layershell.mesh import rectangle
    from layershell.model import Fix, Layer, Model, SurfaceLoad

    mesh = rectangle(float(n), float(n), n, n)
    th = np.full(mesh.n_nodes, 0.1)
    layers = [Layer("base", Orthotropic.isotropic(3e4, 0.2), directors, 2 * th),
              Layer("top", Orthotropic(3.4e4, 3.6e4, 3.4e4, 1.5e4, 1.45e4, 1.45e4, 0.17, 0.17, 0.17),
                    directors, th)]
    edge = np.flatnonzero(np.isclose(mesh.nodes[:, 0], 0))
    return Model(mesh, layers, [(0, 1)], np.zeros(mesh.n_elements, int),
                 fixes=[Fix(edge, 0, tuple(range(directors + 1)), (0, 1, 2))],
                 surface_loads=[SurfaceLoad(np.arange(mesh.n_elements), "top", np.array([0, 0, -1.0]),
                                            lambda x, y, z: 1e-3 + 0 * x)])


def reduced_dofs(n: int, directors: int) -> int:
    """Reduced DOFs of the plate without building it: 2 layers, u_0 of the top layer bonded."""
    nodes = (2 * n + 1) ** 2
    return nodes * 3 * (2 * directors + 1) - (2 * n + 1) * 3 * (directors + 1)


def one(n: int, directors: int, backend: str) -> dict:
    """Measure one mesh (in this process)."""
    from layershell.solver import linear
    from layershell.solver.problem import Problem

    c0 = time.process_time()
    t0 = time.perf_counter()
    pb = Problem.build(plate(n, directors))
    t_build = time.perf_counter() - t0
    t0 = time.perf_counter()
    rs = pb.assembler.reduced_scatter(pb.op)
    t_map = time.perf_counter() - t0
    u = np.zeros(pb.dm.n_full)
    c1 = time.process_time()
    t0 = time.perf_counter()
    f, Kr = pb.assembler.evaluate_reduced(u, pb.op)
    r = pb.op.reduce(pb.external(1.0) - f)
    t_asm = time.perf_counter() - t0
    name = linear.backend_name(backend)
    out = {"n": n, "directors": directors, "elements": n * n, "dofs_full": pb.dm.n_full, "dofs": pb.op.n_red,
           "nnz_full": pb.assembler.nnz, "nnz": Kr.nnz, "map_nnz": rs.P.nnz,
           "map_gib": round(rs.memory_bytes() / 2**30, 3), "backend": name}
    if name == "pardiso":
        t0 = time.perf_counter()
        sym = linear.is_symmetric(Kr)
        solver = linear.PardisoSymmetric() if sym else linear.PardisoGeneral()
        A = solver.matrix(Kr)
        b = np.asfortranarray(r)
        A = solver._check(A)
        t_conv = time.perf_counter() - t0
        times = []
        for phase in (11, 22, 33):
            t0 = time.perf_counter()
            x = solver._call(A, phase, b)
            times.append(time.perf_counter() - t0)
        ip = solver._s.iparm
        out["factor_nnz"] = int(ip[17])
        out["factor_mem_gib"] = round(max(int(ip[14]), int(ip[15]) + int(ip[16])) / 2**20, 3)
        solver.release()
    else:
        import scipy.sparse as sp
        import scipy.sparse.linalg as spla

        t0 = time.perf_counter()
        A = sp.csc_matrix(Kr)
        t_conv = time.perf_counter() - t0
        t0 = time.perf_counter()
        lu = spla.splu(A, permc_spec="COLAMD")
        t_fac = time.perf_counter() - t0
        t0 = time.perf_counter()
        x = lu.solve(r)
        times = [0.0, t_fac, time.perf_counter() - t0]
        out["factor_nnz"] = int(lu.L.nnz + lu.U.nnz)
    c2 = time.process_time()
    res = float(np.linalg.norm(Kr @ x - r) / np.linalg.norm(r))
    it = t_asm + t_conv + sum(times)
    out.update({"build_s": t_build, "map_s": t_map, "assembly_s": t_asm, "convert_s": t_conv,
                "analysis_s": times[0], "factor_s": times[1], "solve_s": times[2], "iteration_s": it,
                "total_s": t_build + t_map + it, "iteration_cpu_s": c2 - c1, "total_cpu_s": c2 - c0,
                "rel_residual": res,
                "peak_rss_gib": round(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20, 3)})
    return {k: (round(v, 3) if isinstance(v, float) and k != "rel_residual" else v) for k, v in out.items()}


def fit_exponent(x, y) -> float:
    """Least-squares slope of log y against log x."""
    return float(np.polyfit(np.log(x), np.log(y), 1)[0]) if len(x) > 1 else float("nan")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--directors", type=int, default=2)
    ap.add_argument("--sizes", type=int, nargs="*", default=[12, 17, 24, 34, 48],
                    help="elements per side (one mesh each)")
    ap.add_argument("--max-dofs", type=int, default=300_000, help="skip meshes with more reduced DOFs")
    ap.add_argument("--backend", default="auto", choices=["auto", "pardiso", "superlu"])
    ap.add_argument("--timeout", type=float, default=600.0, help="seconds per mesh")
    ap.add_argument("--one", type=int, help=argparse.SUPPRESS)  # internal: measure one mesh
    a = ap.parse_args()
    if a.one is not None:
        print(json.dumps(one(a.one, a.directors, a.backend)))
        return
    load = os.getloadavg()
    print(f"# {os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}; "
          f"two-layer plate, d = {a.directors}")
    hdr = ("n", "dofs", "nnz", "build_s", "map_s", "assembly_s", "convert_s", "analysis_s", "factor_s",
           "solve_s", "iteration_s", "iteration_cpu_s", "peak_rss_gib")
    print(" ".join(f"{h:>12}" for h in hdr))
    rows = []
    for n in a.sizes:
        if reduced_dofs(n, a.directors) > a.max_dofs:
            print(f"# n = {n}: {reduced_dofs(n, a.directors)} DOFs > --max-dofs, skipped")
            continue
        cmd = [sys.executable, __file__, "--one", str(n), "--directors", str(a.directors), "--backend", a.backend]
        try:
            p = subprocess.run(cmd, capture_output=True, text=True, timeout=a.timeout)
        except subprocess.TimeoutExpired:
            print(f"# n = {n}: longer than {a.timeout:.0f} s, stopped")
            break
        if p.returncode != 0:
            print(f"# n = {n}: failed (exit {p.returncode}): {p.stderr.strip().splitlines()[-1:]}")
            break
        row = json.loads(p.stdout.strip().splitlines()[-1])
        rows.append(row)
        print(" ".join(f"{row[h]:>12}" for h in hdr), flush=True)
    dofs = [r["dofs"] for r in rows]
    summary = {"directors": a.directors, "load_average": round(load[0], 2), "cpus": os.cpu_count(),
               "exponent_iteration": round(fit_exponent(dofs, [r["iteration_s"] for r in rows]), 3),
               "exponent_total": round(fit_exponent(dofs, [r["total_s"] for r in rows]), 3),
               "exponent_iteration_cpu": round(fit_exponent(dofs, [r["iteration_cpu_s"] for r in rows]), 3),
               "exponent_memory": round(fit_exponent(dofs, [r["peak_rss_gib"] for r in rows]), 3),
               "meshes": rows}
    print(f"# growth exponents vs DOFs: iteration {summary['exponent_iteration']}, total {summary['exponent_total']}, "
          f"peak memory {summary['exponent_memory']}, iteration CPU time {summary['exponent_iteration_cpu']}")
    print("scaling " + json.dumps(summary))


if __name__ == "__main__":
    main()
