"""Single-lap shear test with the cohesive law (examples/lapshear_cohesive.toml): the
peak load against the bond length and the path against the closed form (Yuan et al. 2004), as
the table in docs/user-guide.md. Uses the path tracer of tests/test_lapshear.py.

    PYTHONPATH=src python benchmarks/lapshear.py            # bond lengths, 10 mm elements
    PYTHONPATH=src python benchmarks/lapshear.py --mesh     # L = 100 mm on 20, 10, 5, 2.5 mm
    PYTHONPATH=src python benchmarks/lapshear.py --friction # stiff stick penalties, short arc lengths

``--friction``: the example's bond with friction (μ0 = 0.95) and a stick penalty alpha_T of 1e5 or
1e6 N/mm³, at the example's arc length and at a half, a quarter and a tenth of it (the
``arc_fraction`` of the test's trace), run to 3 % below the peak: increments, the peak above
P_u (the friction's share, 0.35 % rigid-plastic) and the time (docs/performance.md, "The
cohesive slab").
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_lapshear import JOINT, L0, P_U, trace, trace_with_friction  # noqa: E402


def row(L: float, h: float) -> str:
    t0 = time.perf_counter()
    o = trace(L, h, until="end" if L <= 250 else "peak")
    P_a, s_a = JOINT.state(np.minimum(o["s_free"], JOINT.delta_f), L)
    ref = JOINT.peak_load(L)
    bal = max(abs(e["balance_error"]) for e in o["energy"])
    return (f"| {L:g} | {h:g} | {o['peak'] / 1e3:.3f} | {ref / 1e3:.3f} | {100 * (o['peak'] / ref - 1):+.2f} % | "
            f"{100 * np.abs(o['P'] - P_a).max() / P_U:.2f} % | {100 * bal:.2f} % | {len(o['P'])} | "
            f"{time.perf_counter() - t0:.1f} s |")


def friction_row(alpha_T: float, fraction: float) -> str:
    t0 = time.perf_counter()
    o = trace_with_friction(alpha_T, 3000, fraction)
    end = f"{o['P'][-1] / o['peak']:.3f} of the peak" + (" (stopped)" if "stopped" in o else "")
    return (f"| {alpha_T:g} | {fraction:g} | {len(o['P'])} | {100 * (o['peak'] / JOINT.peak_load(L0) - 1):+.3f} % | "
            f"{end} | {time.perf_counter() - t0:.1f} s |")


def main(argv: list[str]) -> None:
    if "--friction" in argv:
        print("| alpha_T (N/mm³) | share of the arc length | increments | peak above P_u | end | wall |")
        print("|---|---|---|---|---|---|")
        for alpha_T, fraction in ((1e5, 1.0), (1e6, 1.0), (1e5, 0.25), (1e6, 0.25), (1e6, 0.5), (1e5, 0.1), (1e6, 0.1)):
            print(friction_row(alpha_T, fraction), flush=True)
        return
    print("| L (mm) | element (mm) | P_max FE (kN) | closed form (kN) | difference | max |P - P_closed(δ0)| / P_u "
          "| energy balance | steps | wall |")
    print("|---|---|---|---|---|---|---|---|---|")
    cases = ([(100.0, h) for h in (20.0, 10.0, 5.0, 2.5)] if "--mesh" in argv else
             [(50.0, 5.0), (100.0, 10.0), (150.0, 10.0), (200.0, 10.0), (250.0, 10.0), (400.0, 10.0), (600.0, 10.0)])
    for L, h in cases:
        print(row(L, h), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
