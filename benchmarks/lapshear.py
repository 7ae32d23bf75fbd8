"""Single-lap shear test with the cohesive law (issue 13, examples/lapshear_cohesive.toml): the
peak load against the bond length and the path against the closed form (Yuan et al. 2004), as
the table in docs/user-guide.md. Uses the path tracer of tests/test_lapshear.py.

    PYTHONPATH=src python benchmarks/lapshear.py            # bond lengths, 10 mm elements
    PYTHONPATH=src python benchmarks/lapshear.py --mesh     # L = 100 mm on 20, 10, 5, 2.5 mm
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_lapshear import JOINT, P_U, trace  # noqa: E402


def row(L: float, h: float) -> str:
    t0 = time.perf_counter()
    o = trace(L, h, until="end" if L <= 250 else "peak")
    P_a, s_a = JOINT.state(np.minimum(o["s_free"], JOINT.delta_f), L)
    ref = JOINT.peak_load(L)
    bal = max(abs(e["balance_error"]) for e in o["energy"])
    return (f"| {L:g} | {h:g} | {o['peak'] / 1e3:.3f} | {ref / 1e3:.3f} | {100 * (o['peak'] / ref - 1):+.2f} % | "
            f"{100 * np.abs(o['P'] - P_a).max() / P_U:.2f} % | {100 * bal:.2f} % | {len(o['P'])} | "
            f"{time.perf_counter() - t0:.1f} s |")


def main(argv: list[str]) -> None:
    print("| L (mm) | element (mm) | P_max FE (kN) | closed form (kN) | difference | max |P - P_closed(δ0)| / P_u "
          "| energy balance | steps | wall |")
    print("|---|---|---|---|---|---|---|---|---|")
    cases = ([(100.0, h) for h in (20.0, 10.0, 5.0, 2.5)] if "--mesh" in argv else
             [(50.0, 5.0), (100.0, 10.0), (150.0, 10.0), (200.0, 10.0), (250.0, 10.0), (400.0, 10.0), (600.0, 10.0)])
    for L, h in cases:
        print(row(L, h), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
