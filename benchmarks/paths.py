"""The softening-path benchmark set: a fixed list of path-following cases (delamination under
force, displacement and arc-length control), each run in its own subprocess on one thread, and
one table of how each got along and how close it came to its reference.

    PYTHONPATH=src python benchmarks/paths.py --quick                 # the small cases (< 10 minutes)
    PYTHONPATH=src python benchmarks/paths.py                         # the whole set (hours)
    PYTHONPATH=src python benchmarks/paths.py --case dcb_disp_200 --case enf_100
    PYTHONPATH=src python benchmarks/paths.py --max-seconds 600 --out paths.md   # also paths.csv, paths.json
    PYTHONPATH=src python benchmarks/paths.py --list                  # the cases and their models

Columns: the case and its mesh (elements, DOFs); whether the run reached its end, and where it
stopped (the last load factor, the stop's reason); increments (converged steps), Newton
iterations (summed over the converged steps, as steps.jsonl records them) and cuts (bisections);
linear solves (right-hand sides handed to ``solver.linear.LinearSolver.solve``, counted by a
wrapper that changes nothing) and factorisations among them; CPU and wall seconds of the run
(set-up included, Numba caches warm); the largest energy balance error over the steps
(summary.json 'energy'); the peak against its reference and the branch: the range of the
deviations of the states past the peak from the reference the tests use (tests/test_dcb.py,
test_enf.py, test_mmb.py, test_lapshear.py, test_cohesive_plate.py, test_slab_trc_soffit.py,
test_circular_delamination.py). A case capped by ``--max-seconds`` is stopped after its first
step past that many CPU seconds (as by Ctrl-C; one thread, so on an idle machine CPU and wall
seconds agree) and reports how far it got and its rate (increments per CPU minute); a case still
running after eight times the cap plus two minutes of wall time is killed and reported so.
"""
from __future__ import annotations

import argparse
import csv
import dataclasses
import io
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))

ONE_THREAD = {k: "1" for k in ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")}
#: the per-case cap of --quick unless --max-seconds is given: the quick set stays under 10 minutes
QUICK_CAP = 90.0

COLUMNS = ("case", "mesh", "reached_end", "stopped_at", "increments", "newton_iterations", "cuts",
           "linear_solves", "factorisations", "cpu_s", "wall_s", "increments_per_min", "energy_balance",
           "peak", "peak_reference", "peak_deviation", "branch_deviation", "reference", "capped")


# ------------------------------------------------------------------------------------ references
@dataclass(frozen=True)
class Beam:
    """A DCB's arms and interface for corrected beam theory (Williams 1989)."""
    E11: float = 150000.0
    E22: float = 11000.0
    G13: float = 6000.0
    b: float = 20.0
    h: float = 1.98
    G_Ic: float = 0.352
    a0: float = 55.0

    def chi(self) -> float:
        gamma = 1.18 * math.sqrt(self.E11 * self.E22) / self.G13
        return math.sqrt(self.E11 / (11 * self.G13) * (3 - 2 * (gamma / (1 + gamma)) ** 2))

    def load_at(self, P, d):
        """The beam-theory load at the crack length the secant compliance d/P infers."""
        import numpy as np

        a_plus = (np.asarray(d) / np.asarray(P) * self.E11 * self.b * self.h**3 / 8) ** (1 / 3)
        return self.b / a_plus * np.sqrt(self.G_Ic * self.E11 * self.h**3 / 12)


EXAMPLE_DCB = Beam()
STIFF_DCB_BEAM = Beam(E11=130000.0, E22=9000.0, h=1.5, G_Ic=0.28)


def _series(s: dict, key: Callable[[dict], float]):
    import numpy as np

    return np.array([key(st) for st in s["steps"]], dtype=float)


def _deviation(values, refs) -> tuple[float, float]:
    import numpy as np

    r = np.asarray(values) / np.asarray(refs) - 1
    r = r[np.isfinite(r)]
    return (float(r.min()), float(r.max())) if r.size else (math.nan, math.nan)


def _peak_and_branch(P, ref, grow) -> dict:
    """The peak of P against ``ref`` there (none where no later state lies below it: a run capped
    or stopped on its way up), and the range of P/ref - 1 over the states ``grow``."""
    import numpy as np

    k = int(np.argmax(P))
    if not np.any(P[k + 1:] < P[k]):
        return {"peak": math.nan, "peak_reference": float(ref[k]), "branch_deviation": (math.nan, math.nan)}
    return {"peak": float(P[k]), "peak_reference": float(ref[k]), "branch_deviation": _deviation(P[grow], ref[grow])}


def dcb_reference(beam: Beam) -> Callable[[dict], dict]:
    def ref(s: dict) -> dict:
        import numpy as np

        P = _series(s, lambda st: st["probes"]["P"])
        d = _series(s, lambda st: st["probes"]["w_upper"] - st["probes"]["w_lower"])
        k = int(np.argmax(P))
        grow = (np.arange(P.size) > k) & (P > 0.3 * P.max()) & np.r_[True, np.diff(d) > 0]
        out = _peak_and_branch(P, beam.load_at(P, d), grow)
        return {**out, "reference": "corrected beam theory (Williams 1989) at the compliance crack length"}
    return ref


def enf_reference(s: dict) -> dict:
    import numpy as np
    import test_enf as T

    P = _series(s, lambda st: st["probes"]["P"])
    w = _series(s, lambda st: st["probes"]["w_load"])
    ref = T.enf_load(T.enf_crack_from_compliance(w / P))
    out = _peak_and_branch(P, ref, np.arange(P.size) > int(np.argmax(P)))
    return {**out, "reference": "beam theory (Wang & Williams 1992) at the compliance crack length"}


def mmb_reference(s: dict) -> dict:
    import numpy as np
    import test_mmb as T

    lam = _series(s, lambda st: st["load_factor"])
    D = _series(s, lambda st: T.F_END * st["probes"]["w_end"] - T.F_MID * st["probes"]["w_mid"])
    a = np.array([T.crack_from_compliance(x / l) if l > 0 else math.nan for x, l in zip(D, lam)])
    ref = np.array([T.mmb_load_factor(x) if np.isfinite(x) else math.nan for x in a])
    k = int(np.argmax(np.where(np.isfinite(a), lam, -np.inf)))
    grow = (np.arange(lam.size) > k) & np.isfinite(a) & (a < 48.5)
    passed = bool(np.any(lam[k + 1:] < lam[k]))
    return {"peak": float(lam[k]) if passed else math.nan, "peak_reference": float(ref[k]),
            "branch_deviation": _deviation(lam[grow], ref[grow]),
            "reference": "Reeder & Crews beam theory, Benzeggagh-Kenane G_c (load factor)"}


def lapshear_reference(s: dict) -> dict:
    import test_lapshear as T

    return {"peak": s["peak_load_factor"] * 25000.0, "peak_reference": float(T.JOINT.peak_load(T.L0)),
            "branch_deviation": (math.nan, math.nan),
            "reference": "bond-slip closed form on a rigid substrate (peak, N; friction adds 0.3 %)"}


def plate_reference(s: dict) -> dict:
    """w_front_max at λ = 1 (none where the run did not get there)."""
    at_end = s.get("probes") and s["steps"][-1]["load_factor"] == 1.0
    w = s["probes"]["w_front_max"] if at_end else math.nan
    return {"peak": w, "peak_reference": 0.0596738, "branch_deviation": (math.nan, math.nan),
            "reference": "w_front_max at lambda = 1 of the 24 x 24 run (m, docs/performance.md)"}


def slab_reference(first: float, second: float) -> Callable[[dict], dict]:
    """The end-debonding peak (largest λ before a tenth of the 3 m² interface debonds) against the
    load-controlled limit, the second peak (largest λ with more than 1 m² debonded) against the
    measured one; 'peak' is the second where the run got there."""
    def ref(s: dict) -> dict:
        import numpy as np

        lam = _series(s, lambda st: st["load_factor"])
        area = _series(s, lambda st: sum(st.get("debonded_area", {}).values()))
        intact = [i for i, a in enumerate(area) if a < 0.3]
        top = max(intact, key=lambda i: lam[i], default=None)
        passed = top is not None and bool(np.any(lam[top + 1:] < lam[top]))  # the end-debonding peak passed
        first_fe = lam[top] if passed else math.nan
        later = [l for l, a in zip(lam, area) if a > 1.0]
        second_fe = max(later) if later else math.nan
        return {"peak": second_fe, "peak_reference": second,
                "branch_deviation": (first_fe / first - 1, first_fe / first - 1),
                "reference": f"second peak {second:g} kN/m2 (docs/performance.md); branch: the end-debonding "
                             f"peak against load control's {first:g}"}
    return ref


def circular_reference(thesis: float) -> Callable[[dict], dict]:
    def ref(s: dict) -> dict:
        lam1 = s.get("first_delamination_load_factor")
        return {"peak": lam1 if lam1 is not None else math.nan, "peak_reference": thesis,
                "branch_deviation": (math.nan, math.nan),
                "reference": "first delamination load factor against the thesis (Matheas 2006, factor 1.5 accepted)"}
    return ref


# ----------------------------------------------------------------------------------------- cases
@dataclass(frozen=True)
class Case:
    name: str
    example: str  # examples/<example>.toml
    replace: dict = field(default_factory=dict)  # text replacements, as tests/helpers.example_spec
    reference: Callable[[dict], dict] = lambda s: {}
    ends: tuple = ("lambda_end", "complete failure")  # summary 'path_end' values that count as the end
    reached: Callable[[dict], bool] | None = None  # overrides 'ends' (the slab's second peak)
    quick: bool = False


def _dcb_force(nx: int) -> dict:
    return {"nx = 150": f"nx = {nx}",
            "factors = [0.01, 0.02, 0.05,": f'control = "arc_length"\nn = 50\nmax_steps = {20 * nx}\n#'}


STIFF_DCB = {"thickness = 1.98": "thickness = 1.5", "E1 = 150000.0": "E1 = 130000.0", "E2 = 11000.0": "E2 = 9000.0",
             "E3 = 11000.0": "E3 = 9000.0", "sigma_max = 30.0": "sigma_max = 57.0", "G_Ic = 0.352": "G_Ic = 0.28",
             "theta3 = 2.97": "theta3 = 2.25", "theta3 = 0.99": "theta3 = 0.75"}
#: examples/slab_trc_soffit.toml with the cohesive interface of tests/test_slab_trc_soffit.py, by arc length
SLAB = {"sigma_max = 1980.0": 'law = "cohesive"\nsigma_max = 1980.0',
        "mu0 = 0.95": "G_Ic = 0.14\nG_IIc = 0.50\neta = 2.0\nmu0 = 0.95",
        "n = 20\n": 'n = 80\ncontrol = "arc_length"\nmax_steps = 6000\n', "lambda_end = 100.0": "lambda_end = 400.0"}
#: the second peak and the end-debonding peak of load control per mesh (docs/performance.md)
SLAB_PEAKS = {(8, 6): (327.13, 376.60), (12, 9): (325.58, 374.04), (16, 12): (325.45, 374.0)}


def _slab_case(nx: int, ny: int) -> Case:
    first, second = SLAB_PEAKS[(nx, ny)]
    return Case(f"slab_{nx}x{ny}", "slab_trc_soffit", {**SLAB, "nx = 8\nny = 6": f"nx = {nx}\nny = {ny}"},
                slab_reference(first, second),
                reached=lambda s, second=second: slab_reference(first, second)(s)["peak"] >= 0.99 * second)


def _cases() -> list[Case]:
    cases = []
    for nx in (100, 200, 400):
        cases.append(Case(f"dcb_force_{nx}", "dcb_cohesive", _dcb_force(nx), dcb_reference(EXAMPLE_DCB),
                          ends=("complete failure",), quick=nx == 100))
        cases.append(Case(f"dcb_disp_{nx}", "dcb_displacement", {"nx = 150": f"nx = {nx}"},
                          dcb_reference(EXAMPLE_DCB), ends=("lambda_end",), quick=nx == 100))
    cases += [
        Case("dcb_stiff_200", "dcb_displacement", {**STIFF_DCB, "nx = 150": "nx = 200"},
             dcb_reference(STIFF_DCB_BEAM), ends=("lambda_end",), quick=True),
        Case("enf_100", "enf_cohesive", {}, enf_reference, quick=True),
        Case("mmb_100", "mmb_cohesive", {}, mmb_reference, quick=True),
        Case("lapshear_friction", "lapshear_cohesive", {"mu0 = 0.0": "mu0 = 0.95"}, lapshear_reference,
             ends=("complete failure",), quick=True),
    ]
    for n in (12, 24):
        cases.append(Case(f"plate_{n}x{n}", "cantilever_plate_cohesive", {"nx = 6": f"nx = {n}", "ny = 6": f"ny = {n}"},
                          plate_reference))
    cases += [_slab_case(8, 6), _slab_case(12, 9), _slab_case(16, 12)]
    cases += [Case("cfrp_circular", "cfrp_circular", {}, circular_reference(30.0)),
              Case("trc_circular", "trc_circular", {}, circular_reference(10.0))]
    return cases


CASES: dict[str, Case] = {c.name: c for c in _cases()}


def case_spec(case: Case):
    """The RunSpec of a case (its example with the replacements; each must occur)."""
    from helpers import example_spec

    return example_spec(case.example, case.replace)


# ---------------------------------------------------------------------------------------- worker
class SolveCounter:
    """Counts the right-hand sides handed to every LinearSolver (a wrapper around its ``solve``
    that returns what the original returns), and its factorisations (its own counts)."""

    def __init__(self) -> None:
        from layershell.solver import linear

        self.rhs = 0
        self.solvers: list = []
        self._original = original = linear.LinearSolver.solve
        counter = self

        def counted(solver, K, r):
            counter.rhs += 1 if getattr(r, "ndim", 1) == 1 else int(r.shape[1])
            if not any(s is solver for s in counter.solvers):
                counter.solvers.append(solver)
            return original(solver, K, r)

        linear.LinearSolver.solve = counted

    def factorisations(self) -> int:
        return sum(s.counts.factorisations for s in self.solvers)

    def close(self) -> None:
        """Put the original ``solve`` back."""
        from layershell.solver import linear

        linear.LinearSolver.solve = self._original


def _stopped_at(s: dict, result, interrupted: bool) -> str:
    lam = s["steps"][-1]["load_factor"] if s.get("steps") else 0.0
    if interrupted:
        return f"lambda = {lam:.6g} (capped)"
    if s.get("converged"):
        return f"lambda = {lam:.6g} ({s.get('path_end') or 'last step'})"
    reason = (result.message or "stopped").splitlines()[0]
    return f"lambda = {lam:.6g}: " + (reason if len(reason) <= 100 else reason[:99] + "…")


def measure(name: str, max_seconds: float | None) -> dict:
    """Run one case in this process: the table's row (without formatting)."""
    from layershell.runner import run

    case = CASES[name]
    counter = SolveCounter()
    spec = case_spec(case)
    t0, c0 = time.perf_counter(), time.process_time()

    def cap(i, n, lam):  # CPU seconds: what a case got done does not depend on the machine's other load
        if max_seconds is not None and time.process_time() - c0 > max_seconds:
            raise KeyboardInterrupt

    with tempfile.TemporaryDirectory() as tmp:
        r = run(spec, Path(tmp) / "out", progress=cap, write_vtu=False)
    wall, cpu = time.perf_counter() - t0, time.process_time() - c0
    s = r.summary
    steps = s.get("steps", [])
    capped = bool(r.interrupted)
    reached = (case.reached(s) if case.reached else
               bool(s.get("converged")) and s.get("path_end", "lambda_end") in case.ends) and not capped
    if case.reached is None and s.get("converged") and "path_end" not in s and not capped:
        reached = "lambda_end" in case.ends  # load-controlled runs end at their last factor
    balance = max((abs(st["energy"]["balance_error"]) for st in steps if st.get("energy")), default=math.nan)
    try:
        ref = case.reference(s) if steps else {}
    except Exception as exc:  # a reference that cannot be evaluated on a short path: say so in the row
        ref = {"reference": f"not evaluated ({type(exc).__name__}: {exc})"}
    return {"case": name, "mesh": f"{s.get('n_elements')} elements, {s.get('n_dofs')} DOFs",
            "reached_end": reached, "stopped_at": _stopped_at(s, r, capped), "increments": len(steps),
            "newton_iterations": sum(st.get("iterations", 0) for st in steps),
            "cuts": sum(st.get("bisections", 0) for st in steps), "linear_solves": counter.rhs,
            "factorisations": counter.factorisations(), "cpu_s": cpu, "wall_s": wall,
            "increments_per_min": 60.0 * len(steps) / cpu if cpu > 0 else math.nan,
            "energy_balance": balance, "capped": capped, **ref}


def run_in_subprocess(name: str, max_seconds: float | None) -> dict:
    """One case in a fresh interpreter on one thread; a case that does not stop at its cap (a step
    longer than the cap) is killed after eight times the cap plus two minutes of wall time."""
    env = {**os.environ, **ONE_THREAD, "PYTHONPATH": os.pathsep.join(
        [str(ROOT / "src")] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p])}
    cmd = [sys.executable, str(Path(__file__).resolve()), "--worker", name]
    if max_seconds is not None:
        cmd += ["--max-seconds", str(max_seconds)]
    limit = None if max_seconds is None else 8 * max_seconds + 120
    t0 = time.perf_counter()
    try:
        p = subprocess.run(cmd, env=env, capture_output=True, text=True, timeout=limit)
    except subprocess.TimeoutExpired:
        return {"case": name, "reached_end": False, "stopped_at": f"killed after {limit:g} s (one step past the cap)",
                "wall_s": time.perf_counter() - t0, "capped": True}
    for line in reversed(p.stdout.splitlines()):
        if line.startswith("paths_row "):
            return json.loads(line[len("paths_row "):])
    tail = (p.stderr.strip().splitlines() or ["no output"])[-1][:160]
    return {"case": name, "reached_end": False, "stopped_at": f"worker failed (exit {p.returncode}): {tail}",
            "wall_s": time.perf_counter() - t0}


# ----------------------------------------------------------------------------------------- table
def _fmt(key: str, v) -> str:
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    if key == "reached_end":
        return "yes" if v else "no"
    if key == "capped":
        return "capped" if v else ""
    if key in ("cpu_s", "wall_s"):
        return f"{v:.1f}"
    if key == "increments_per_min":
        return f"{v:.1f}"
    if key in ("energy_balance", "peak_deviation"):
        return f"{100 * v:+.2f} %" if key == "peak_deviation" else f"{100 * v:.2f} %"
    if key == "branch_deviation":
        lo, hi = v
        return "-" if lo is None or math.isnan(lo) else f"{100 * lo:+.1f} ... {100 * hi:+.1f} %"
    if key in ("peak", "peak_reference"):
        return f"{v:.6g}"
    return str(v)


def complete_row(row: dict) -> dict:
    """Every column present (missing ones None) and the peak's deviation from its reference."""
    out = {k: row.get(k) for k in COLUMNS}
    if out["branch_deviation"] is not None:
        out["branch_deviation"] = tuple(out["branch_deviation"])
    p, ref = out["peak"], out["peak_reference"]
    out["peak_deviation"] = p / ref - 1 if isinstance(p, (int, float)) and ref and not math.isnan(p) else None
    return out


MARKDOWN_HEADER = ("case", "mesh", "reached end", "stopped at", "increments", "Newton iterations", "cuts",
                   "linear solves (factorisations)", "CPU s", "wall s", "increments/CPU min", "energy balance",
                   "peak (reference)", "peak dev.", "branch dev.")


def markdown(rows: list[dict]) -> str:
    lines = ["| " + " | ".join(MARKDOWN_HEADER) + " |", "|" + "---|" * len(MARKDOWN_HEADER)]
    for row in map(complete_row, rows):
        f = {k: _fmt(k, row[k]) for k in COLUMNS}
        cells = [f["case"] + (" (capped)" if row["capped"] else ""), f["mesh"], f["reached_end"], f["stopped_at"],
                 f["increments"], f["newton_iterations"], f["cuts"], f"{f['linear_solves']} ({f['factorisations']})",
                 f["cpu_s"], f["wall_s"], f["increments_per_min"], f["energy_balance"],
                 f"{f['peak']} ({f['peak_reference']})", f["peak_deviation"], f["branch_deviation"]]
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def csv_text(rows: list[dict]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf)
    w.writerow(COLUMNS)
    for row in map(complete_row, rows):
        w.writerow([_fmt(k, row[k]) for k in COLUMNS])
    return buf.getvalue()


def json_text(rows: list[dict]) -> str:
    def clean(v):
        if isinstance(v, float) and not math.isfinite(v):
            return None
        if isinstance(v, tuple):
            return [clean(x) for x in v]
        return v

    return json.dumps([{k: clean(v) for k, v in complete_row(r).items()} for r in rows], indent=1) + "\n"


def write_tables(rows: list[dict], out: Path) -> list[Path]:
    """``out`` (Markdown) with ``out``.csv and ``out``.json beside it."""
    paths = [out, out.with_suffix(".csv"), out.with_suffix(".json")]
    for p, text in zip(paths, (markdown(rows), csv_text(rows), json_text(rows))):
        p.write_text(text)
    return paths


# ------------------------------------------------------------------------------------------ main
def select(args) -> list[str]:
    if args.case:
        unknown = [c for c in args.case if c not in CASES]
        if unknown:
            raise SystemExit(f"unknown case(s) {', '.join(unknown)}; the cases: {', '.join(CASES)}")
        return list(args.case)
    return [c.name for c in CASES.values() if c.quick or not args.quick]


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help=f"the small cases, each capped at {QUICK_CAP:g} CPU s")
    ap.add_argument("--case", action="append", help="run this case (repeatable); --list names them")
    ap.add_argument("--max-seconds", type=float, help="stop each case after its first step past this many CPU seconds")
    ap.add_argument("--out", type=Path, help="write the table here (Markdown) and as .csv and .json beside it")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args(argv)
    if args.worker:
        print("paths_row " + json.dumps(measure(args.worker, args.max_seconds)), flush=True)
        return 0
    if args.list:
        for c in CASES.values():
            print(f"{c.name:20s} examples/{c.example}.toml {'quick' if c.quick else ''}")
        return 0
    cap = args.max_seconds if args.max_seconds is not None else (QUICK_CAP if args.quick else None)
    rows = []
    for name in select(args):
        print(f"running {name} ...", file=sys.stderr, flush=True)
        rows.append(run_in_subprocess(name, cap))
        print(markdown(rows[-1:]).splitlines()[-1], file=sys.stderr, flush=True)
    print(markdown(rows), end="")
    if args.out:
        for p in write_tables(rows, args.out):
            print(f"written {p}", file=sys.stderr)
    print("paths " + json.dumps({"cap_s": cap, "cases": [r["case"] for r in rows],
                                 "reached": sum(bool(r.get("reached_end")) for r in rows)}))
    return 0


if __name__ == "__main__":
    sys.exit(main())
