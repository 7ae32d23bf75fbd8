"""Thesis Fig. 3.13 (MODEL.md V3): tip deflection of the thick and thin cantilevers for every
combination of 1-3 layers × 1-3 directors, geometrically nonlinear and linear, with the MITC9
element (default) and the fully integrated element of the thesis (``element = "full"``).

    python examples/locking_study.py [--out results/locking_study] [--quick]

Writes locking_study.csv and locking_study.md (a table) and prints the table. Layers have equal
thicknesses h/n (MODEL.md V3 gap). The reference values are the thesis's 3 × 3 results
(3.899 cm thick, 8.790 cm thin) and the exact elastica of an inextensible Euler-Bernoulli
cantilever under a conservative end load, computed here by shooting (:func:`elastica_tip`):
P l²/EI = 1.2 → 3.490 cm (thick), 0.27 → 8.926 cm (thin).
"""
from __future__ import annotations

import argparse
import csv
from pathlib import Path

import numpy as np

from layershell.io.build import build, parse
from layershell.io.schema import LayerDef
from layershell.runner import run

HERE = Path(__file__).resolve().parent
# file, thesis 3 × 3 value, length l, end load P, EI = E b h³/12 (units N, cm)
CASES = {"thick": ("cantilever_thick_load_bottom.toml", 3.899, 10.0, 100.0, 1e5 / 12),
         "thin": ("cantilever_thin_load_bottom.toml", 8.790, 100.0, 0.00830844, 1e5 * 0.333**3 / 12)}


def elastica_tip(alpha: float) -> float:
    """Tip deflection / l of the elastica θ'' = −α cos θ (s ∈ [0, 1], θ(0) = 0, θ'(1) = 0,
    α = P l²/EI; inextensible Euler-Bernoulli cantilever, conservative transverse end load),
    by shooting on the root curvature (scipy solve_ivp + brentq)."""
    from scipy.integrate import solve_ivp
    from scipy.optimize import brentq

    def end(k0):
        sol = solve_ivp(lambda s, y: [y[1], -alpha * np.cos(y[0]), np.sin(y[0])], [0.0, 1.0], [0.0, k0, 0.0],
                        rtol=1e-12, atol=1e-14)
        return sol.y[:, -1]

    return float(end(brentq(lambda k: end(k)[1], 0.0, 2.0 * alpha))[2])


def elastica(case: str) -> float:
    """Exact elastica tip deflection of ``case`` (cm)."""
    _, _, l, P, EI = CASES[case]
    return l * elastica_tip(P * l * l / EI)


def variant(case: str, n_layers: int, directors: int, nonlinear: bool = True, element: str = "mitc"):
    """The example file of ``case`` with ``n_layers`` equal layers of ``directors`` directors."""
    fname = CASES[case][0]
    mf = parse((HERE / fname).read_text(), fname)
    h = sum(float(ly.thickness) for ly in mf.layers)
    layers = [LayerDef(name=f"l{k + 1}", material=mf.layers[0].material, thickness=h / n_layers,
                       directors=directors) for k in range(n_layers)]
    settings = mf.model.model_copy(update={"nonlinear": nonlinear, "element": element})
    steps = mf.steps if nonlinear else mf.steps.model_copy(update={"n": 1})
    return mf.model_copy(update={"layers": layers, "model": settings, "steps": steps})


def w_tip(case: str, n_layers: int, directors: int, nonlinear: bool = True, element: str = "mitc") -> float:
    res = run(build(variant(case, n_layers, directors, nonlinear, element), HERE), None, write_vtu=False)
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
    for case, (_, thesis, *_) in CASES.items():
        ref = elastica(case)
        for nl in (1, 2, 3):
            for d in (1, 2, 3):
                w = {}
                for el in ("mitc", "full"):
                    w[el, False] = w_tip(case, nl, d, nonlinear=False, element=el)
                    w[el, True] = float("nan") if a.quick else w_tip(case, nl, d, nonlinear=True, element=el)
                rows.append([case, nl, d, 3 * (d + 1) + 3 * d * (nl - 1), w["mitc", False], w["mitc", True],
                             w["full", False], w["full", True], thesis, round(ref, 4)])
                print(f"{case:5s} {nl} layer(s) x d={d}: MITC9 linear {w['mitc', False]:.4f} nonlinear "
                      f"{w['mitc', True]:.4f} | full linear {w['full', False]:.4f} nonlinear {w['full', True]:.4f}",
                      flush=True)
    head = ["case", "layers", "directors", "dofs_per_node", "w_linear_mitc", "w_nonlinear_mitc", "w_linear_full",
            "w_nonlinear_full", "w_thesis_3x3", "w_elastica"]
    with open(out / "locking_study.csv", "w", newline="") as fh:
        csv.writer(fh).writerows([head] + rows)
    md = ["| case | layers | d | DOF/node | MITC9 linear | MITC9 nonlinear | full linear | full nonlinear "
          "| thesis 3×3 | elastica |", "|" + "---|" * 10]
    md += [f"| {r[0]} | {r[1]} | {r[2]} | {r[3]} | {r[4]:.4f} | {r[5]:.4f} | {r[6]:.4f} | {r[7]:.4f} | {r[8]} "
           f"| {r[9]} |" for r in rows]
    (out / "locking_study.md").write_text("\n".join(md) + "\n")
    print("\n".join(md))


if __name__ == "__main__":
    main()
