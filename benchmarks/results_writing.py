"""Cost of recording a load step against the length of the history.

    PYTHONPATH=src python benchmarks/results_writing.py [--steps 1500] [--out DIR]

Runs the thick cantilever (examples/cantilever_thick.toml, 5 elements, linear, so a load step is a
few milliseconds of solving) with ``--steps`` load steps into a results folder (no ParaView files,
no figures) and times every step from the progress callback (solve + probes + everything written
for the step). Reported: the mean time per step in the first and the last 100 steps, the total,
and the part of it that is not solving (total minus the steps' own solve times). Without the recorder
every step rewrote summary.json, probes.csv and the checkpoint with the whole history, so the
time per step grew linearly with the step number (quadratic total); with the recorder the
per-step files are appended and the checkpoint holds the state only, so it stays flat.

Run it once with the sources of each version on PYTHONPATH to compare. Last line:
``results_writing {json}``. Measured (1500 steps, a shared 2-core machine, so ±30 % noise):

=====================  ========  ==============  ==================  =================
version                total s   not solving s   ms/step first 100   ms/step last 100
=====================  ========  ==============  ==================  =================
before (db602f8)       83.7      71.3            35.7                78.1
recorder               19.3      10.7            18.0                12.2
=====================  ========  ==============  ==================  =================

(an earlier, more loaded pair: 122.5 s with 44 → 152 ms/step before, 40.0 s with 35 → 33 ms/step
after, the checkpoint then still fsynced at every step).
"""
from __future__ import annotations

import argparse
import json
import shutil
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=1500)
    ap.add_argument("--out", type=Path, default=None)
    a = ap.parse_args()

    import layershell
    from layershell.io.build import load
    from layershell.runner import run

    text = (ROOT / "examples" / "cantilever_thick.toml").read_text(encoding="utf-8")
    text = text.replace("[steps]\nn = 1", f"[steps]\nn = {a.steps}") + "\n[output]\nvtu = false\nplots = false\n"
    tmp = Path(tempfile.mkdtemp(prefix="ls_bench_"))
    model = tmp / "bench.toml"
    model.write_text(text, encoding="utf-8")
    out = a.out or tmp / "out"
    spec = load(model)
    stamps: list[float] = []
    t0 = time.perf_counter()
    res = run(spec, out, lambda i, n, lam: stamps.append(time.perf_counter()), write_vtu=False)
    total = time.perf_counter() - t0
    assert res.converged and len(stamps) == a.steps
    dt = np.diff(np.r_[t0, stamps])
    solve = sum(s["wall_seconds"] for s in res.summary["steps"])
    k = min(100, a.steps // 2)
    rec = {"layershell": layershell.__file__, "steps": a.steps, "total_s": round(total, 3),
           "solve_s": round(solve, 3), "not_solving_s": round(total - solve, 3),
           "first_ms_per_step": round(1e3 * dt[:k].mean(), 3), "last_ms_per_step": round(1e3 * dt[-k:].mean(), 3),
           "growth_last_over_first": round(float(dt[-k:].mean() / dt[:k].mean()), 3)}
    for key, v in rec.items():
        print(f"{key:26s} {v}")
    print("results_writing " + json.dumps(rec))
    if a.out is None:
        shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
