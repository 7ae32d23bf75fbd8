"""Buckling loads of a perfect cantilever column from the tangent's inertia (stability.py;
docs/user-guide.md "Stability"): the column of tests/test_stability.py loaded by load control
in 10 steps to ten times Euler's first load, on the meshes given (elements along the column);
prints the bifurcations the run located by bisection, as multiples of Euler's first load,
against Euler's and Engesser's (with shear) values, and the wall time.

    PYTHONPATH=src python benchmarks/column_buckling.py 2 4 8 16
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_stability import column, timoshenko  # noqa: E402


def main(argv: list[str]) -> None:
    meshes = [int(a) for a in argv] or [2, 4, 8, 16]
    print("| elements | first bifurcation | second bifurcation | wall s |")
    print("|---|---|---|---|")
    for nx in meshes:
        t0 = time.perf_counter()
        s = column(nx, "n = 10\nlambda_end = 10.0")
        located = [0.5 * sum(e["located"]) for e in s.get("stability", []) if e.get("located")]
        cells = [f"{v:.6g}" for v in located] + ["-"] * (2 - len(located))
        print(f"| {nx} | {cells[0]} | {cells[1]} | {time.perf_counter() - t0:.2f} |")
    print(f"| Euler / Engesser | 1 / {timoshenko(1):.6g} | 9 / {timoshenko(2):.6g} | |")


if __name__ == "__main__":
    main(sys.argv[1:])
