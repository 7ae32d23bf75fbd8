"""Mesh study of the §5.1 plate with a cohesive interface: runs
examples/cantilever_plate_cohesive.toml (and, with --thesis, cantilever_plate_strong.toml, the
thesis's law) on the meshes given and prints first damage / first full debonding / w_front_max.

    PYTHONPATH=src python benchmarks/cohesive_plate_mesh.py 6 12 24 [--thesis] [--beyond]
    PYTHONPATH=src python benchmarks/cohesive_plate_mesh.py 24 --element mitc --reuse never
    PYTHONPATH=src python benchmarks/cohesive_plate_mesh.py 6 12 --only-thesis strong,weak,slip --rule lobatto
    PYTHONPATH=src python benchmarks/cohesive_plate_mesh.py 3 6 12 --element mitc --arc

``--beyond``: load past the design load to λ = 1.2 (steps of 0.1 to 0.9, then 0.01), where the
interface debonds completely at a first point (first_delamination_load_factor).
``--arc``: traced by arc length (``[steps] control = "arc_length"``) instead of load steps.
``--element mitc|full``: that element instead of the example's (the cohesive plate: MITC9); ``--reuse never|always``: the
linear solver's ``[steps] reuse_factorization`` (default auto: GMRES on kept factorisations;
the printed ``linear_solves`` count them). ``--only-thesis CASES``: the thesis-law plates
cantilever_plate_<case>.toml alone (strong, weak, slip); ``--rule lobatto|gauss``: their
``[[interfaces]] rule`` (the contact between debonded layers at the nodes or at the face Gauss
points, the default; docs/user-guide.md "Refined meshes with the thesis's law").
"""
from __future__ import annotations

import re
import sys
import time
from pathlib import Path

from layershell.io.build import build, parse
from layershell.runner import run

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


def study(name: str, n: int, beyond: bool = False, element: str | None = None, reuse: str | None = None,
          rule: str | None = None, arc: bool = False) -> dict:
    path = EXAMPLES / f"{name}.toml"
    text = path.read_text()
    if rule is not None:
        text = text.replace("[[interfaces]]", f'[[interfaces]]\nrule = "{rule}"', 1)
    if element is not None:  # the example's [model] element, or one added after its nonlinear switch
        if 'element = "' in text:
            text = re.sub(r'element = "\w+"', f'element = "{element}"', text)
        else:
            text = text.replace("nonlinear = true", f'nonlinear = true\nelement = "{element}"', 1)
    for key in ("nx", "ny"):
        for old in (3, 6):
            text = text.replace(f"{key} = {old}\n", f"{key} = {n}\n")
    if beyond:
        factors = [round(0.1 * i, 4) for i in range(1, 10)] + [round(0.9 + 0.01 * i, 4) for i in range(1, 31)]
        text = text.replace("[steps]\nn = 24", f"[steps]\nfactors = {factors}")
    if arc:
        text = text.replace("[steps]\n", '[steps]\ncontrol = "arc_length"\n', 1)
    if reuse is not None:
        text = text.replace("[steps]\n", f'[steps]\nreuse_factorization = "{reuse}"\n', 1)
    t0, c0 = time.perf_counter(), time.process_time()
    s = run(build(parse(text, str(path)), path.parent), None, write_vtu=False).summary
    return {"mesh": f"{n}x{n}", "lambda_end": s["steps"][-1]["load_factor"] if s["steps"] else 0.0,
            "increments": len(s["steps"]), "path_end": s.get("path_end"),
            "first_damage": s.get("first_damage_load_factor"),
            "first_delamination": s.get("first_delamination_load_factor"),
            "w_front_max": s["probes"].get("w_front_max"), "wall_s": round(time.perf_counter() - t0, 1),
            "cpu_s": round(time.process_time() - c0, 1),
            "iterations": sum(st["iterations"] for st in s["steps"]), "error": s.get("error"),
            "stabilized": s.get("stabilized"), "balance": (s.get("energy") or {}).get("balance_error"),
            "debonded_area": (s.get("debonded_area") or [{}])[-1].get("concrete/trc"),
            "linear_solves": s.get("linear_solves")}


def main(argv: list[str]) -> None:
    opts = {}
    for flag in ("--element", "--reuse", "--rule", "--only-thesis"):
        if flag in argv:
            i = argv.index(flag)
            opts[flag[2:]] = argv[i + 1]
            argv = argv[:i] + argv[i + 2:]
    meshes = [int(a) for a in argv if a.isdigit()] or [6, 12]
    names = ["cantilever_plate_cohesive"] + (["cantilever_plate_strong"] if "--thesis" in argv else [])
    only = opts.pop("only-thesis", None)
    if only is not None:
        names = [f"cantilever_plate_{c}" for c in only.split(",")]
    for name in names:
        print(name)
        for n in meshes:
            print("  ", study(name, n, "--beyond" in argv, arc="--arc" in argv, **opts), flush=True)


if __name__ == "__main__":
    main(sys.argv[1:])
