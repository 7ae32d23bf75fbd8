"""Thesis Fig. 3.13 (MODEL.md V3): tip deflection of the thick and thin cantilevers for every
combination of 1-3 layers × 1-3 directors, geometrically nonlinear and linear.

    python examples/locking_study.py [--out results/locking_study] [--quick]

Writes locking_study.csv and locking_study.md (a table) and prints the table. Layers have equal
thicknesses h/n (MODEL.md V3 gap). The reference values are the thesis's 3 × 3 results
(3.899 cm thick, 8.790 cm thin) and the exact elastica (3.490 / 8.926 cm).
"""
from __future__ import annotations

import argparse
import csv
from pathlib import Path

from layershell.io.build import build, parse
from layershell.io.schema import LayerDef
from layershell.runner import run

HERE = Path(__file__).resolve().parent
CASES = {"thick": ("cantilever_thick_load_bottom.toml", 3.899, 3.490),
         "thin": ("cantilever_thin_load_bottom.toml", 8.790, 8.926)}


def variant(case: str, n_layers: int, directors: int, nonlinear: bool = True):
    """The example file of ``case`` with ``n_layers`` equal layers of ``directors`` directors."""
    fname = CASES[case][0]
    mf = parse((HERE / fname).read_text(), fname)
    h = sum(float(ly.thickness) for ly in mf.layers)
    layers = [LayerDef(name=f"l{k + 1}", material=mf.layers[0].material, thickness=h / n_layers,
                       directors=directors) for k in range(n_layers)]
    settings = mf.model.model_copy(update={"nonlinear": nonlinear})
    steps = mf.steps if nonlinear else mf.steps.model_copy(update={"n": 1})
    return mf.model_copy(update={"layers": layers, "model": settings, "steps": steps})


def w_tip(case: str, n_layers: int, directors: int, nonlinear: bool = True) -> float:
    res = run(build(variant(case, n_layers, directors, nonlinear), HERE), None, write_vtu=False)
    if not res.converged:
        raise RuntimeError(f"{case} {n_layers}x{directors}: {res.message}")
    return res.summary["probes"]["w_tip"]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="results/locking_study")
    ap.add_argument("--quick", action="store_true", help="linear runs only")
    a = ap.parse_args()
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for case, (_, thesis, elastica) in CASES.items():
        for nl in (1, 2, 3):
            for d in (1, 2, 3):
                lin = w_tip(case, nl, d, nonlinear=False)
                non = float("nan") if a.quick else w_tip(case, nl, d, nonlinear=True)
                rows.append([case, nl, d, 3 * (d + 1) + 3 * d * (nl - 1), lin, non, thesis, elastica])
                print(f"{case:5s} {nl} layer(s) x d={d}: linear {lin:.4f}  nonlinear {non:.4f}", flush=True)
    head = ["case", "layers", "directors", "dofs_per_node", "w_linear", "w_nonlinear", "w_thesis_3x3", "w_elastica"]
    with open(out / "locking_study.csv", "w", newline="") as fh:
        csv.writer(fh).writerows([head] + rows)
    md = ["| case | layers | d | DOF/node | w linear | w nonlinear | thesis 3×3 | elastica |", "|" + "---|" * 8]
    md += [f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]:.4f} | {r[5]:.4f} | {r[6]} | {r[7]} |" for r in rows]
    (out / "locking_study.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
