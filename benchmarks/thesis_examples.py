"""Wall time of the thesis examples under examples/ (target: each under 60 s).

    python benchmarks/thesis_examples.py [NAME ...] [--skip NAME ...] [--timeout 900] [--vtu]

Runs every ``examples/*.toml`` (or the named ones, e.g. ``pulloff cantilever_thick``) through the
command line ``layershell run FILE --out TMP`` in a fresh process, as a user would, into a
temporary folder (deleted afterwards). Reported per example: wall seconds of the whole command
(start-up, imports, model build, solution, output files), the solver time the runner writes to
summary.json (``wall_seconds``), the CPU seconds of the command (all threads; on a shared,
loaded machine the wall time can be several times larger), reduced DOFs, load steps, Newton iterations, whether it
converged, and whether it met the 60 s target. VTU output is skipped unless ``--vtu``.
Last line: ``thesis_examples {json}``.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TARGET_S = 60.0


def cli() -> list[str]:
    exe = Path(sys.executable).with_name("layershell")
    return [str(exe)] if exe.exists() else [sys.executable, "-m", "layershell.cli"]


def run_one(path: Path, timeout: float, vtu: bool) -> dict:
    out = Path(tempfile.mkdtemp(prefix=f"ls_bench_{path.stem}_"))
    cmd = [*cli(), "run", str(path), "--out", str(out), "--quiet"] + ([] if vtu else ["--no-vtu"])
    t0 = time.perf_counter()
    c0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, cwd=ROOT)
        code, err = p.returncode, (p.stderr.strip().splitlines() or [""])[-1]
    except subprocess.TimeoutExpired:
        code, err = None, f"stopped after {timeout:.0f} s"
    wall = time.perf_counter() - t0
    c1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (c1.ru_utime + c1.ru_stime) - (c0.ru_utime + c0.ru_stime)
    row = {"example": path.stem, "wall_s": round(wall, 2), "cpu_s": round(cpu, 2), "exit": code, "converged": False, "dofs": None,
           "steps": None, "iterations": None, "solve_s": None}
    summary = out / "summary.json"
    if summary.exists():
        s = json.loads(summary.read_text())
        steps = s.get("steps", [])
        row.update(converged=bool(s.get("converged")), dofs=s.get("n_dofs"), steps=len(steps),
                   iterations=sum(int(st.get("iterations", 0)) for st in steps),
                   solve_s=round(float(s.get("wall_seconds", 0.0)), 2))
    if code != 0:
        row["error"] = err[:200]
    row["under_target"] = code == 0 and wall < TARGET_S
    shutil.rmtree(out, ignore_errors=True)
    return row


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("names", nargs="*", help="example names (file stems); default: all examples/*.toml")
    ap.add_argument("--skip", nargs="*", default=[], help="example names to leave out")
    ap.add_argument("--timeout", type=float, default=900.0, help="seconds per example before it is stopped")
    ap.add_argument("--vtu", action="store_true", help="also write the ParaView files")
    a = ap.parse_args()
    files = sorted((ROOT / "examples").glob("*.toml"))
    if a.names:
        known = {f.stem: f for f in files}
        unknown = [n for n in a.names if n not in known]
        if unknown:
            ap.error(f"unknown example(s) {', '.join(unknown)}; choose from {', '.join(known)}")
        files = [known[n] for n in a.names]
    files = [f for f in files if f.stem not in a.skip]
    load = os.getloadavg()
    print(f"# {os.cpu_count()} CPUs, load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f} at start")
    print(f"{'example':<32} {'dofs':>7} {'steps':>5} {'iter':>5} {'solve_s':>8} {'cpu_s':>8} {'wall_s':>8} {'conv':>5} {'<60s':>5}")
    rows = []
    for f in files:
        row = run_one(f, a.timeout, a.vtu)
        row["load_average"] = round(os.getloadavg()[0], 2)
        rows.append(row)
        print(f"{row['example']:<32} {row['dofs'] or '-':>7} {row['steps'] if row['steps'] is not None else '-':>5} "
              f"{row['iterations'] if row['iterations'] is not None else '-':>5} "
              f"{row['solve_s'] if row['solve_s'] is not None else '-':>8} {row['cpu_s']:>8.1f} {row['wall_s']:>8.1f} "
              f"{'yes' if row['converged'] else 'no':>5} {'yes' if row['under_target'] else 'NO':>5}"
              + (f"  ({row['error']})" if row.get("error") else ""), flush=True)
    print("thesis_examples " + json.dumps({"cpus": os.cpu_count(), "load_average_start": round(load[0], 2),
                                           "target_s": TARGET_S, "all_under_target": all(r["under_target"] for r in rows),
                                           "examples": rows}))


if __name__ == "__main__":
    main()
