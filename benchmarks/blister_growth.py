"""Delamination growth after local buckling: the mesh study of the straight-sided blister
(examples/laminate_blister_growth.toml) against the thin-film closed form, and the front of the
circular blister (examples/laminate_circular_growth.toml) at several strains.

    PYTHONPATH=src python benchmarks/blister_growth.py strip 60 120 240 [--out DIR]
    PYTHONPATH=src python benchmarks/blister_growth.py strip-results DIR60 DIR120 ... [--out DIR]
    PYTHONPATH=src python benchmarks/blister_growth.py circle RESULTS_FOLDER [--out DIR]

``strip``: runs the strip on the element counts given (0.5, 0.25, 0.125 mm elements for 60, 120,
240), prints the film strain ε' at the onset of growth and at the front positions 10.5 ... 12 mm,
the closed form's growth strain (layershell.analytic.blister), and writes blister_front.png: the
front against ε' on each mesh with the closed form's front (G = G_c(B) solved for a at each ε').
``strip-results``: the same from results folders of `layershell run` on the strip (the front
from delamination.csv's x_max, the film strain from the probes).
``circle``: reads the interface files of a results folder of the circular example (run with
`layershell run examples/laminate_circular_growth.toml --out RESULTS_FOLDER`) and writes
circle_front.png: the debonded zone's radius against the angle at the strains of several steps,
and prints the radius range per step.
"""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

E, NU, T, A, G_IC, G_IIC, ETA = 50000.0, 0.3, 0.5, 10.0, 0.352, 1.002, 2.284  # the strip example
BASE = (2.5, E * (1 - NU) / ((1 + NU) * (1 - 2 * NU)))  # its base: 2.5 mm in uniaxial strain


def closed_form_front(eps: np.ndarray) -> np.ndarray:
    """The front a(ε') where G(ε', a) = G_c(B(ε', a)) on the strip's base (nan before growth)."""
    from scipy.optimize import brentq

    from layershell.analytic import blister

    def excess(a: float, e: float) -> float:
        B = blister.mode_ii_share(e, E, NU, T, a, base=BASE)
        return float(blister.energy_release_rate(e, E, NU, T, a, BASE) - blister.bk_toughness(B, G_IC, G_IIC, ETA))

    out = np.full(len(eps), np.nan)
    for i, e in enumerate(eps):
        grid = np.linspace(A, 3 * A, 401)
        v = np.array([excess(a, e) for a in grid])
        ok = np.flatnonzero((v[:-1] > 0) & (v[1:] <= 0))  # growth stops where G falls below G_c
        if v[0] > 0 and ok.size:
            out[i] = brentq(excess, grid[ok[0]], grid[ok[0] + 1], args=(e,))
    return out


def strip(counts: list[int], out: Path) -> None:
    from helpers import run_example
    from test_delamination_growth import growth_history

    from layershell.analytic import blister
    from layershell.plots import _figure

    eg = blister.growth_strain(E, NU, T, A, G_IC, G_IIC, ETA, base=BASE)
    print(f"closed form: growth strain {100 * eg:.4f} % (BK at the LEFM mode mix), "
          f"{100 * blister.growth_strain(E, NU, T, A, G_IC, base=BASE):.4f} % (G_Ic), "
          f"{100 * blister.growth_strain(E, NU, T, A, G_IIC, base=BASE):.4f} % (G_IIc)")
    fig = _figure((6.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for nx in counts:
        t0 = time.perf_counter()
        r = run_example("laminate_blister_growth", {"nx = 60": f"nx = {nx}"})
        wall = time.perf_counter() - t0
        h = growth_history(r)
        at = [h["eps"][np.argmax(h["front"] >= xf - 1e-6)] if h["front"].max() >= xf - 1e-6 else np.nan
              for xf in (10.5, 11.0, 11.5, 12.0)]
        print(f"{30.0 / nx:.3f} mm elements: onset between ε' = {100 * h['onset'][0]:.4f} and "
              f"{100 * h['onset'][1]:.4f} %; ε' at the front 10.5/11/11.5/12 mm: "
              + " / ".join(f"{100 * v:.4f}" for v in at) + f" %; {len(h['eps'])} steps, {wall:.0f} s")
        ax.step(100 * h["eps"], h["front"], where="post", label=f"{30.0 / nx:g} mm elements")
    _finish_front_figure(fig, ax, np.linspace(eg, h["eps"].max(), 40), out)


def _finish_front_figure(fig, ax, e: np.ndarray, out: Path) -> None:
    """The closed form's front over the film strains ``e``, axes and legend; saved as blister_front.png."""
    from layershell.plots import _save

    ax.plot(100 * e, closed_form_front(e), "k--", label="closed form (BK at the LEFM mode mix)")
    ax.set_xlim(left=0.5)  # the buckling branch before the growth is flat
    ax.set_xlabel("film strain ε' where bonded (%)")
    ax.set_ylabel("front x_f (mm)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    print(_save(fig, out / "blister_front.png"))


def strip_results(folders: list[Path], out: Path) -> None:
    import csv

    from layershell.plots import _figure

    fig = _figure((6.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for folder in folders:
        probes = list(csv.DictReader(open(folder / "probes.csv")))
        zone = list(csv.DictReader(open(folder / "delamination.csv")))
        eps = np.array([(0.3 * float(r["load_factor"]) + float(r["u_20"])) / 10.0 for r in probes])
        grown = np.array([float(r["grown"]) for r in probes])
        front = np.where(grown > 0, [float(z["base/film:x_max"]) for z in zone], A)
        first = int(np.argmax(grown > 0))
        at = [eps[np.argmax(front >= xf - 1e-6)] if front.max() >= xf - 1e-6 else np.nan
              for xf in (10.5, 11.0, 11.5, 12.0)]
        print(f"{folder}: onset between ε' = {100 * eps[first - 1]:.4f} and {100 * eps[first]:.4f} %; "
              "ε' at the front "
              "10.5/11/11.5/12 mm: " + " / ".join(f"{100 * v:.4f}" for v in at) + f" %; {len(eps)} steps")
        ax.step(100 * eps, front, where="post", label=folder.name)
    _finish_front_figure(fig, ax, np.linspace(0.00638, 0.0072, 30), out)


def circle(folder: Path, out: Path, n_curves: int = 5) -> None:
    import csv

    import meshio

    from layershell.plots import _figure, _save

    rows = list(csv.DictReader(open(folder / "probes.csv")))
    grown = np.array([float(r["grown"]) for r in rows])
    first = int(np.argmax(grown > 0))
    if grown[first] <= 0:
        print("no growth in", folder)
        return
    picks = np.unique(np.linspace(first, len(rows) - 1, n_curves).round().astype(int))
    fig = _figure((6.0, 4.2))
    ax = fig.add_subplot(1, 1, 1)
    for k in picks:
        m = meshio.read(folder / f"interface_base_film_{k + 1:04d}.vtu")
        xy = m.points[:, :2] - 20.0
        deb = m.point_data["debonded"] > 0
        r, th = np.hypot(*xy.T), np.degrees(np.arctan2(xy[:, 1], xy[:, 0]))
        bins = np.linspace(-180, 180, 33)
        idx = np.digitize(th, bins) - 1
        front = np.array([r[deb & (idx == b)].max() if (deb & (idx == b)).any() else np.nan for b in range(32)])
        eps = float(rows[k]["eps"])
        ax.plot(0.5 * (bins[1:] + bins[:-1]), front, marker="o", ms=3, label=f"ε = {100 * eps:.3f} %")
        print(f"step {k + 1}: ε = {100 * eps:.4f} %, front radius {np.nanmin(front):.2f} ... "
              f"{np.nanmax(front):.2f} mm")
    ax.set_xlabel("angle from x (degrees)")
    ax.set_ylabel("front radius (mm)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    print(_save(fig, out / "circle_front.png"))


if __name__ == "__main__":
    args = sys.argv[1:]
    dest = Path(args[args.index("--out") + 1]) if "--out" in args else Path(".")
    args = [a for i, a in enumerate(args) if a != "--out" and (i == 0 or args[i - 1] != "--out")]
    if args[0] == "strip":
        strip([int(a) for a in args[1:]] or [60, 120, 240], dest)
    elif args[0] == "strip-results":
        strip_results([Path(a) for a in args[1:]], dest)
    elif args[0] == "circle":
        circle(Path(args[1]), dest)
    else:
        raise SystemExit(__doc__)
