"""Mesh study of the §5.1 plate with a cohesive interface (issue 13): runs
examples/cantilever_plate_cohesive.toml (and, with --thesis, cantilever_plate_strong.toml, the
thesis's law) on the meshes given and prints first damage / first full debonding / w_front_max.

    PYTHONPATH=src python benchmarks/cohesive_plate_mesh.py 6 12 24 [--thesis] [--beyond]

``--beyond``: load past the design load to λ = 1.2 (steps of 0.1 to 0.9, then 0.01), where the
interface debonds completely at a first point (first_delamination_load_factor).
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from layershell.io.build import build, parse
from layershell.runner import run

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def study(name: str, n: int, beyond: bool = False) -> dict:
    path = EXAMPLES / f"{name}.toml"
    text = path.read_text()
    for key in ("nx", "ny"):
        for old in (3, 6):
            text = text.replace(f"{key} = {old}\n", f"{key} = {n}\n")
    if beyond:
        factors = [round(0.1 * i, 4) for i in range(1, 10)] + [round(0.9 + 0.01 * i, 4) for i in range(1, 31)]
        text = text.replace("[steps]\nn = 24", f"[steps]\nfactors = {factors}")
    t0, c0 = time.perf_counter(), time.process_time()
    s = run(build(parse(text, str(path)), path.parent), None, write_vtu=False).summary
    return {"mesh": f"{n}x{n}", "lambda_end": s["steps"][-1]["load_factor"] if s["steps"] else 0.0,
            "first_damage": s.get("first_damage_load_factor"),
            "first_delamination": s.get("first_delamination_load_factor"),
            "w_front_max": s["probes"].get("w_front_max"), "wall_s": round(time.perf_counter() - t0, 1),
            "cpu_s": round(time.process_time() - c0, 1),
            "iterations": sum(st["iterations"] for st in s["steps"]), "error": s.get("error"),
            "stabilized": s.get("stabilized"), "balance": (s.get("energy") or {}).get("balance_error")}


def main(argv: list[str]) -> None:
    meshes = [int(a) for a in argv if a.isdigit()] or [6, 12]
    names = ["cantilever_plate_cohesive"] + (["cantilever_plate_strong"] if "--thesis" in argv else [])
    for name in names:
        print(name)
        for n in meshes:
            print("  ", study(name, n, "--beyond" in argv), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
