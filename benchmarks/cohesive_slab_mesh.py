"""Mesh study of the slab with a cohesive soffit layer (docs/user-guide.md "A slab with
a cohesive soffit layer"): examples/slab_trc_soffit.toml with the cohesive law of
tests/test_slab_trc_soffit.py (G_Ic = 0.14, G_IIc = 0.50 kN/m, η = 2) on the meshes given
(nx × ny, the example's 8 × 6 grading), printing first damage, w_mid and the fracture energy at
100 kN/m² - or, with ``--to 400``, loaded on until the end debonding: the load factor where load
control stops (or, with ``--relax``, the relaxed jumps).

    PYTHONPATH=src python benchmarks/cohesive_slab_mesh.py 8x6 16x12 32x24        # to 100 kN/m²
    PYTHONPATH=src python benchmarks/cohesive_slab_mesh.py 8x6 16x12 --to 400        # the snap-back
    PYTHONPATH=src python benchmarks/cohesive_slab_mesh.py 8x6 --to 400 --relax      # passed, relaxed
    PYTHONPATH=src python benchmarks/cohesive_slab_mesh.py 8x6 --to 400 --arc        # by arc length

The last line is one JSON record (``cohesive_slab {...}``).
"""
from __future__ import annotations

import json
import re
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from helpers import example_spec  # noqa: E402
from test_slab_trc_soffit import COHESIVE  # noqa: E402

from layershell.runner import run  # noqa: E402


def study(mesh: str, to: float = 100.0, relax: bool = False, arc: bool = False) -> dict:
    nx, ny = (int(v) for v in mesh.split("x"))
    steps = f"n = {round(to / 5)}\n" + ('unstable = "relax"\n' if relax else "")
    if arc:
        steps += 'control = "arc_length"\nmax_steps = 3000\n'
    repl = {**COHESIVE, "n = 20\n": steps, "lambda_end = 100.0": f"lambda_end = {to!r}",
            "nx = 8\nny = 6": f"nx = {nx}\nny = {ny}"}
    t0 = time.perf_counter()
    r = run(example_spec("slab_trc_soffit", repl), None, write_vtu=False)
    s = r.summary
    last = s["steps"][-1] if s["steps"] else {"load_factor": 0.0, "probes": {}}
    at100 = next((st for st in s["steps"] if abs(st["load_factor"] - 100.0) < 1e-9), None)
    return {"mesh": mesh, "dofs": s.get("n_dofs"), "converged": r.converged, "last_load_factor": last["load_factor"],
            "peak_load_factor": s.get("peak_load_factor"), "first_damage": s.get("first_damage_load_factor"),
            "first_delamination": s.get("first_delamination_load_factor"),
            "w_mid_100": at100["probes"]["w_mid"] if at100 else None,
            "fracture_100": at100["energy"]["dissipated_fracture"] if at100 and "energy" in at100 else None,
            "debonded_end": last["probes"].get("debonded"),
            "relaxations": [{k: v.get(k) for k in ("load_factor", "debonded_fraction_before", "debonded_fraction_after",
                                                   "energy_released")} for v in s.get("relaxations", [])],
            # where load control stops: the load factor of the last converged (bisected) increment
            "limit": (float(m.group(1)) if (m := re.search(r"the last converged load factor is ([0-9.]+)", r.message))
                      else None),
            "increments": len(s["steps"]),
            "balance": max((abs(st["energy"]["balance_error"]) for st in s["steps"] if "energy" in st), default=None),
            "message": r.message[:160], "wall_s": round(time.perf_counter() - t0, 1)}


def main(argv: list[str]) -> None:
    to = float(argv[argv.index("--to") + 1]) if "--to" in argv else 100.0
    meshes = [a for a in argv if "x" in a and a[0].isdigit()]
    rows = [study(m, to, "--relax" in argv, "--arc" in argv) for m in meshes or ["8x6"]]
    print("| mesh | DOFs | first damage | w_mid(100) mm | fracture(100) | last λ | peak λ | first full debonding | "
          "debonded at end | increments | largest balance error | wall s |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mesh']} | {r['dofs']} | {r['first_damage']} | {r['w_mid_100']} | {r['fracture_100']} | "
              f"{r['last_load_factor']:.6g} | {r['peak_load_factor']} | {r['first_delamination']} | {r['debonded_end']} | "
              f"{r['increments']} | {'-' if r['balance'] is None else format(r['balance'], '.2g')} | {r['wall_s']} |")
        if not r["converged"]:
            print(f"  stopped: {r['message']}" + (f" - last converged load factor {r['limit']}" if r["limit"] else ""))
        for x in r["relaxations"]:
            print(f"  relaxed at λ = {x['load_factor']:.6g}: debonded {x['debonded_fraction_before']:.3f} -> "
                  f"{x['debonded_fraction_after']:.3f}, released {x['energy_released']:.4g}")
    print("cohesive_slab " + json.dumps(rows))


if __name__ == "__main__":
    main(sys.argv[1:])
