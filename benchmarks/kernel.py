"""Element kernel throughput against the machine's dense matrix-multiply roofline.

    python benchmarks/kernel.py [--elements 2000] [--repeat 3] [--element mitc|full] [--directors 3]

Internal force + tangent (nonlinear) of a 2-layer element over many elements, both kernels timed
interleaved. Thickness points as ``assembly.build_blocks`` chooses them with the default
``thickness_points = 3``: the full element max(3, d) (fewer than d points give spurious
zero-energy modes, tests/test_element_rank.py), MITC9 max(3, d + 1) (with d points it has six);
for d ≥ 3 the full element is timed a second time with the MITC9's points
(``time_ratio_mitc_over_full_equal_points``, the cost per integration point). For d = 3: 216
DOFs, 2 × 27 integration points (full) and 2 × 36 (MITC9). Flops counted for the mathematically
necessary work per point: the material part Bᵀ (C B) (2·6·6·m + 2·6·m² with m = 27(d+1) layer
DOFs), the geometric part gᵀ S g (2·a·9 + 2·a²·3, a = m/3 basis functions) and the force Bᵀ S
(2·6·m); no symmetry savings. The roofline is NumPy's float64 matmul of two 2000 × 2000 matrices
with all CPUs (``roofline_gflops``, the last line ``roofline_share=<achieved/roofline>``) and with
one CPU (``share_of_one_cpu_roofline``: a 1-thread kernel can reach at most 1/cores of the first).

The kernels do less work than counted where they can: the full element's material part is one
symmetric rank-k product per element (BLAS syrk, half the counted 2·6·m² per point, 6 rows per
point); MITC9's works in the tie space (37 tied strains per level instead of 6 × 9 rows, one BLAS
product with the Cholesky factor of the level's tied stiffness, block diagonal with the transverse
shear apart, then the syrk; see ``layershell.element.mitc._mitc_range``). Also printed: the
kernel's threads (``LAYERSHELL_THREADS``), the first call (Numba compile or cache load), the
deviation from the plain NumPy reference on a few elements, and the load average (timings on a
shared machine are noisy: compare runs at similar load).

Measured 24 Nov 2026, 1000 elements, 1 thread, 2-core machine shared with solver runs (load
average 1.8-2.3; s = both layers, min of 3, two runs; "before" = the kernel at the start of that
session, load 1.3-2.1):

| d | points MITC9 / full | MITC9 s (before → after) | full s | per element | equal points |
|---|---|---|---|---|---|
| 1 | 3 / 3 | 0.083 → 0.064 | 0.057 | 1.45 → 1.11-1.15 | the same |
| 2 | 3 / 3 | 0.128 → 0.105 | 0.095 | 1.36 → 1.09-1.12 | the same |
| 3 | 4 / 3 | 0.25 → 0.19 | 0.145 | 1.62-1.71 → 1.31-1.32 | 1.34 → 1.01 |
| 4 | 5 / 4 | 0.43-0.47 → 0.35 | 0.29 | 1.45-1.48 → 1.19-1.25 | 1.23 → 1.02 |

Roofline share with 1 thread: the all-CPU roofline is ~196 GFLOP/s when the other core is free
(share 0.17 at d = 1, 0.23 at d = 2; d = 3, 4 reach 59-63 GFLOP/s, i.e. 0.30-0.32 of it) and
87-91 GFLOP/s when it is busy (share 0.40-0.69); of one CPU (~98 GFLOP/s) 0.34 (d = 1), 0.47
(d = 2), 0.60 (d = 3), 0.62 (d = 4). With the other core busy ``LAYERSHELL_THREADS=2`` was no
faster than 1 thread, so the 2-thread share could not be measured cleanly here.

Measured again 24 Nov 2026 on another CPU (AMD EPYC, 2 cores, load average 0.8-0.9; 1000
elements, 1 thread; the all-CPU roofline 105 GFLOP/s, one CPU 53): the MITC9 kernel over the
full one per element 1.24 (d = 1), 1.13 (d = 2), 1.15-1.19 (d = 3; at equal points 0.85-0.90),
1.11 (d = 4; 0.96); MITC9 s 0.093 / 0.172 / 0.231-0.245 / 0.495; roofline share 0.24 / 0.28 /
0.45 / 0.43 (of one CPU 0.89 at d = 3). The ratio is within 1.3 for every d on this
CPU; the 1.31-1.32 at d = 3 above was measured on the earlier one.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from layershell.element.kernel import kernel_threads, layer_block, layer_response, layer_response_reference
from layershell.material import Orthotropic
from layershell.mesh import rectangle


def flops_per_point(m: int) -> float:
    a = m // 3
    return 2 * 36 * m + 2 * 6 * m * m + 2 * a * 9 + 2 * a * a * 3 + 2 * 6 * m


def roofline(n: int = 2000, repeat: int = 3, threads: int | None = None) -> float:
    """GFLOP/s of NumPy's float64 matmul of two n × n matrices with ``threads`` BLAS threads
    (default all CPUs of this process, whatever OMP_NUM_THREADS says)."""
    from layershell.threads import controller

    A = np.random.default_rng(0).standard_normal((n, n))
    B = A.T.copy()
    with controller().limit(limits=threads or _cpus(), user_api="blas"):
        A @ B
        t = min(_timed(lambda: A @ B) for _ in range(repeat))
    return 2 * n**3 / t / 1e9


def _cpus() -> int:
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def _timed(fn) -> float:
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--elements", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--chunk", type=int, default=256)
    ap.add_argument("--element", choices=["mitc", "full"], default="mitc",
                    help="kernel timed (default the MITC9 default element); the other one is timed too "
                         "and the ratio printed")
    ap.add_argument("--directors", type=int, default=3)
    a = ap.parse_args()
    d = a.directors
    na = 9 * (d + 1)
    side = int(np.ceil(np.sqrt(a.elements)))
    mesh = rectangle(float(side), float(side), side, side)
    X = mesh.nodes[mesh.elements][: a.elements]
    ne = len(X)
    th = np.full((ne, 9), 0.1)
    mat = Orthotropic(3.4e4, 3.6e4, 3.4e4, 1.5e4, 1.45e4, 1.45e4, 0.17, 0.17, 0.17)
    other = "full" if a.element == "mitc" else "mitc"
    # thickness points as assembly.build_blocks chooses them (thickness_points = 3): the full
    # element max(3, d) (fewer than d give spurious modes, tests/test_element_rank.py), MITC9
    # max(3, d + 1); the full element is also timed with the MITC9's points (equal-points ratio)
    nz = {"full": max(3, d), "mitc": max(3, d + 1)}

    def blocks_of(element, n_thickness):
        return [layer_block(X, th * k, th, d, mat, 15.0, n_thickness=n_thickness, element=element) for k in (0, 1)]

    blocks = blocks_of(a.element, nz[a.element])
    blocks_other = blocks_of(other, nz[other])
    blocks_equal = blocks_of("full", nz["mitc"]) if nz["full"] != nz["mitc"] else None
    rng = np.random.default_rng(1)
    U = [1e-3 * rng.standard_normal((ne, na, 3)) for _ in blocks]

    def run(bl=blocks):
        for b, u in zip(bl, U):
            for s in range(0, ne, a.chunk):
                sl = slice(s, s + a.chunk)
                layer_response(b, u[sl], True, True, sl)

    first = _timed(lambda: layer_response(blocks[0], U[0][:1], True, True, slice(0, 1)))
    n = min(ne, 8)
    f0, K0 = layer_response_reference(blocks[1], U[1][:n], True, True, slice(0, n))
    f1, K1 = layer_response(blocks[1], U[1][:n], True, True, slice(0, n))
    dev = max(np.abs(f1 - f0).max() / np.abs(f0).max(), np.abs(K1 - K0).max() / np.abs(K0).max())
    run()
    layer_response(blocks_other[0], U[0][:1], True, True, slice(0, 1))
    run(blocks_other)
    if blocks_equal is not None:
        run(blocks_equal)
    times, times_other, times_equal = [], [], []
    for _ in range(a.repeat):  # interleaved, so that load changes on a shared machine hit all alike
        times.append(_timed(run))
        times_other.append(_timed(lambda: run(blocks_other)))
        if blocks_equal is not None:
            times_equal.append(_timed(lambda: run(blocks_equal)))
    t, t_other = min(times), min(times_other)
    t_mitc, t_full = (t, t_other) if a.element == "mitc" else (t_other, t)
    t_equal = min(times_equal) if times_equal else t_full
    q = blocks[0].dV.shape[1]
    fl = 2 * q * flops_per_point(3 * na) * ne
    achieved = fl / t / 1e9
    peak = roofline()
    peak1 = roofline(threads=1)
    print(json.dumps({"elements": ne, "dofs_per_element": 6 * na, "directors": d, "seconds": round(t, 4),
                      "elements_per_second": round(ne / t, 1), "gflops": round(achieved, 3),
                      "roofline_gflops": round(peak, 3),
                      "roofline_cpus": _cpus(), "roofline_gflops_one_cpu": round(peak1, 3),
                      "share_of_one_cpu_roofline": round(achieved / peak1, 4),
                      "mflop_per_element": round(fl / ne / 1e6, 3),
                      "threads": kernel_threads(), "element": a.element,
                      f"seconds_{other}": round(t_other, 4),
                      "time_ratio_mitc_over_full": round(t_mitc / t_full, 3),
                      "thickness_points": nz,
                      "seconds_full_at_mitc_points": round(t_equal, 4),
                      "time_ratio_mitc_over_full_equal_points": round(t_mitc / t_equal, 3),
                      "integration_points_per_layer": q, "first_call_seconds": round(first, 3),
                      "max_rel_deviation_from_reference": float(f"{dev:.2e}"),
                      "load_average": [round(x, 2) for x in os.getloadavg()]}))
    print(f"roofline_share={achieved / peak:.4f}")


if __name__ == "__main__":
    main()
