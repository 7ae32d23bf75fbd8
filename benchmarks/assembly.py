"""Global assembly of the reduced tangent for a square two-layer d = 3 plate.

    python benchmarks/assembly.py [--n 20]

Measures: building the problem (DOF map, constraint operator T, sparsity pattern and scatter
map, reference geometry), one full assembly of element values into the full-space CSR matrix,
the reduction K_r = Tᵀ K T by sparse products (``product_s``, the former path) and by the
reduced scatter map (``map_s`` once per bond state, ``reduction_s`` = ``P @ K.data`` per
iteration; both give the same K_r). Last line: ``seconds_per_million_nnz=<assembly + reduction
per million nonzeros of K_r>``.
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np

from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.model import Fix, Layer, Model
from layershell.solver.problem import Problem


def plate(n: int) -> Model:
    mesh = rectangle(float(n), float(n), n, n)
    th = np.full(mesh.n_nodes, 0.1)
    layers = [Layer("base", Orthotropic.isotropic(3e4, 0.2), 3, 2 * th),
              Layer("top", Orthotropic(3.4e4, 3.6e4, 3.4e4, 1.5e4, 1.45e4, 1.45e4, 0.17, 0.17, 0.17), 3, th)]
    edge = np.flatnonzero(np.isclose(mesh.nodes[:, 0], 0))
    return Model(mesh, layers, [(0, 1)], np.zeros(mesh.n_elements, int),
                 fixes=[Fix(edge, 0, (0, 1, 2, 3), (0, 1, 2))])


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--n", type=int, default=20, help="elements per side")
    a = ap.parse_args()
    t0 = time.perf_counter()
    pb = Problem.build(plate(a.n))
    t_build = time.perf_counter() - t0
    u = np.zeros(pb.dm.n_full)
    t0 = time.perf_counter()
    f, K = pb.assembler.evaluate(u)
    t_asm = time.perf_counter() - t0
    t0 = time.perf_counter()
    Kp = (pb.op.T.T @ K @ pb.op.T).tocsr()
    t_prod = time.perf_counter() - t0
    t0 = time.perf_counter()
    rs = pb.assembler.reduced_scatter(pb.op)
    t_map = time.perf_counter() - t0
    t0 = time.perf_counter()
    Kr = rs.matrix(K.data)
    t_red = time.perf_counter() - t0
    diff = abs(Kr - Kp).max() / abs(Kp).max()
    print(json.dumps({"elements": a.n * a.n, "dofs_reduced": pb.op.n_red, "nnz_full": K.nnz, "nnz_reduced": Kr.nnz,
                      "build_s": round(t_build, 3), "assembly_s": round(t_asm, 3), "product_s": round(t_prod, 3),
                      "map_s": round(t_map, 3), "reduction_s": round(t_red, 3), "max_rel_difference": float(diff)}))
    print(f"seconds_per_million_nnz={(t_asm + t_red) / (Kr.nnz / 1e6):.4f}")


if __name__ == "__main__":
    main()
