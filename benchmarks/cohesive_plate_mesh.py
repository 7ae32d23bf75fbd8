"""Mesh study of the §5.1 plate with a cohesive interface (issue 13): runs
examples/cantilever_plate_cohesive.toml (and, with --thesis, cantilever_plate_strong.toml, the
thesis's law) on the meshes given and prints first damage / first full debonding / w_front_max.

    PYTHONPATH=src python benchmarks/cohesive_plate_mesh.py 6 12 24 [--thesis]
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

from layershell.io.build import build, parse
from layershell.runner import run

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def study(name: str, n: int) -> dict:
    path = EXAMPLES / f"{name}.toml"
    text = path.read_text()
    for key in ("nx", "ny"):
        for old in (3, 6):
            text = text.replace(f"{key} = {old}\n", f"{key} = {n}\n")
    t0 = time.perf_counter()
    s = run(build(parse(text, str(path)), path.parent), None, write_vtu=False).summary
    return {"mesh": f"{n}x{n}", "lambda_end": s["steps"][-1]["load_factor"] if s["steps"] else 0.0,
            "first_damage": s.get("first_damage_load_factor"),
            "first_delamination": s.get("first_delamination_load_factor"),
            "w_front_max": s["probes"].get("w_front_max"), "wall_s": round(time.perf_counter() - t0, 1),
            "iterations": sum(st["iterations"] for st in s["steps"]), "error": s.get("error")}


def main(argv: list[str]) -> None:
    meshes = [int(a) for a in argv if a.isdigit()] or [6, 12]
    names = ["cantilever_plate_cohesive"] + (["cantilever_plate_strong"] if "--thesis" in argv else [])
    for name in names:
        print(name)
        for n in meshes:
            print("  ", study(name, n), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
