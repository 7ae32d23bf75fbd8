"""Fit model-file parameters to a measured curve (``layershell calibrate``).

The measured curve is a CSV file with a header; ``x`` and ``y`` name one column each. The model's
curve is the same pair of quantities over its converged load steps: ``load_factor``, ``step``,
any probe name, ``debonded_area`` (summed over the interfaces) or ``debonded_area:<interface>``
(e.g. ``debonded_area:base/strap``). The objective is the RMS difference of the model's ``y``,
interpolated linearly at the data's ``x``, and the data's ``y``:

    RMS(p) = sqrt( mean_i ( y_model(x_i; p) - y_i )² ).

Where the data reach beyond the model's last converged step, the model's last value is used
(a run that stops early therefore scores badly instead of failing the fit), and the first
step's value below its x. The parameters
are dotted model-file paths (as in ``layershell sweep``) with bounds; the optimiser works on
the parameters scaled to [0, 1] by their bounds: SciPy's bounded Brent search
(``minimize_scalar``) for one parameter, a bounded trust-region least-squares fit
(``least_squares``, method ``trf``) of the residuals for several (or when asked).
"""
from __future__ import annotations

import copy
import csv
import math
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .io.build import InputError
from .sweep import build_spec, describe, get_path, read_model, set_path, with_values

METHODS = ("auto", "bounded", "least_squares")


@dataclass
class Param:
    """A fitted parameter: dotted model-file path, bounds and start value."""

    key: str
    lower: float
    upper: float
    start: float | None = None

    def to_unit(self, v: float) -> float:
        return (v - self.lower) / (self.upper - self.lower)

    def from_unit(self, t: float) -> float:
        return self.lower + float(np.clip(t, 0.0, 1.0)) * (self.upper - self.lower)


def parse_param(arg: str) -> Param:
    """``"interfaces.0.tau_max=1.0:3.0"`` or ``"...=1.0:3.0:2.4"`` (lower:upper[:start])."""
    key, eq, rng = arg.partition("=")
    key = key.strip()
    parts = rng.split(":")
    hint = ("write --param KEY=LOWER:UPPER or KEY=LOWER:UPPER:START with a dotted model-file path, "
            "e.g. --param interfaces.0.tau_max=1.0:3.0")
    if not eq or not key or len(parts) not in (2, 3):
        raise InputError(f"--param '{arg}': {hint}")
    try:
        nums = [float(p) for p in parts]
    except ValueError:
        raise InputError(f"--param '{arg}': the bounds and start must be numbers; {hint}") from None
    if not all(math.isfinite(v) for v in nums) or not nums[0] < nums[1]:
        raise InputError(f"--param '{arg}': need finite bounds with LOWER < UPPER (got {nums[0]} and {nums[1]})")
    start = nums[2] if len(nums) == 3 else None
    if start is not None and not nums[0] <= start <= nums[1]:
        raise InputError(f"--param '{arg}': the start value {start} lies outside [{nums[0]}, {nums[1]}]")
    return Param(key, nums[0], nums[1], start)


def read_curve(path: str | Path, x: str, y: str) -> tuple[np.ndarray, np.ndarray]:
    """Columns ``x`` and ``y`` of a CSV file with a header (rows with an empty cell are skipped),
    sorted by x."""
    path = Path(path)
    if not path.is_file():
        raise InputError(f"--data '{path}' does not exist; give a CSV file with a header row")
    try:
        with path.open(newline="", encoding="utf-8-sig") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError, csv.Error) as exc:
        raise InputError(f"--data '{path}' cannot be read as CSV ({exc}); save it as UTF-8 CSV") from None
    if not rows:
        raise InputError(f"--data '{path}' is empty; it needs a header row and data rows")
    header = [h.strip() for h in rows[0]]
    for opt, name in (("--x", x), ("--y", y)):
        if name not in header:
            raise InputError(f"{opt} '{name}': no such column in '{path}'; its columns are {header}")
    ix, iy = header.index(x), header.index(y)
    xs, ys = [], []
    for n, r in enumerate(rows[1:], start=2):
        if len(r) <= max(ix, iy) or not r[ix].strip() or not r[iy].strip():
            continue
        try:
            xs.append(float(r[ix]))
            ys.append(float(r[iy]))
        except ValueError:
            raise InputError(f"--data '{path}', line {n}: '{r[ix]}', '{r[iy]}' are not numbers; the columns "
                             f"'{x}' and '{y}' must hold numbers") from None
    xa, ya = np.asarray(xs), np.asarray(ys)
    ok = np.isfinite(xa) & np.isfinite(ya)
    if not ok.any():
        raise InputError(f"--data '{path}': no row with numbers in both '{x}' and '{y}'")
    o = np.argsort(xa[ok], kind="stable")
    return xa[ok][o], ya[ok][o]


def curve_quantities(summary: dict) -> list[str]:
    """The names that ``model_curve`` accepts for a run summary."""
    steps = summary.get("steps") or []
    names = ["load_factor", "step"] + list(summary.get("probes") or {})
    areas = list(dict.fromkeys(k for st in steps for k in (st.get("debonded_area") or {})))
    if areas or "debonded_area" in summary:
        names += ["debonded_area"] + [f"debonded_area:{a}" for a in areas]
    return names


def _step_value(st: dict, name: str) -> float:
    if name in ("load_factor", "step"):
        return float(st[name])
    if name == "debonded_area":
        return float(sum((st.get("debonded_area") or {}).values()))
    if name.startswith("debonded_area:"):
        return float((st.get("debonded_area") or {}).get(name.split(":", 1)[1], math.nan))
    return float((st.get("probes") or {}).get(name, math.nan))


def model_curve(summary: dict, x: str, y: str) -> tuple[np.ndarray, np.ndarray]:
    """The model's (x, y) over its converged steps, sorted by x (the unloaded state is not
    included: give data from the first load step on, or start the steps at a small factor)."""
    steps = summary.get("steps") or []
    xs = np.array([_step_value(st, x) for st in steps])
    ys = np.array([_step_value(st, y) for st in steps])
    ok = np.isfinite(xs) & np.isfinite(ys)
    xs, ys = xs[ok], ys[ok]
    o = np.argsort(xs, kind="stable")
    return xs[o], ys[o]


def objective(model_xy: tuple[np.ndarray, np.ndarray], data_xy: tuple[np.ndarray, np.ndarray]) -> np.ndarray:
    """Residuals y_model(x_i) - y_i (linear interpolation; constant beyond the model's range)."""
    mx, my = model_xy
    dx, dy = data_xy
    if mx.size == 0:
        return np.full(dx.shape, np.nan)
    return np.interp(dx, mx, my) - dy


def rms(r: np.ndarray) -> float:
    return float(np.sqrt(np.mean(np.square(r)))) if np.all(np.isfinite(r)) else math.inf


class _Budget(Exception):
    """The maximum number of model runs is reached."""


@dataclass
class CalibrationResult:
    best: dict[str, float]
    objective: float
    objective_start: float
    evaluations: int
    method: str
    message: str
    history: list[dict] = field(default_factory=list)
    out: Path | None = None


def calibrate(model: str | Path, data: str | Path, x: str, y: str, params: list[Param], out: str | Path,
              method: str = "auto", max_runs: int = 40, xtol: float = 1e-3, best_run: bool = True,
              progress: Callable[[dict], None] | None = None) -> CalibrationResult:
    """Fit ``params`` of ``model`` so that its (x, y) curve matches the CSV ``data``.

    Writes ``out/calibration.json`` (bounds, start, best values, objective, history of every
    model run), ``out/calibration.csv`` (data with the start and best model curves at the data's
    x) and ``out/calibration.png``; with ``best_run`` the best parameters are run once more
    into ``out/best/`` (summary.json, probes.csv, plots). ``xtol`` is the tolerance on the
    parameters as a fraction of their bound ranges."""
    from .io.output import write_csv, write_json
    from .runner import run

    model = Path(model)
    doc = read_model(model)
    if method not in METHODS:
        raise InputError(f"--method '{method}': choose one of {', '.join(METHODS)}")
    if not params:
        raise InputError("give at least one --param KEY=LOWER:UPPER (a dotted model-file path and its bounds)")
    keys = [p.key for p in params]
    if len(set(keys)) != len(keys):
        raise InputError(f"--param: a key is given twice in {keys}; give each parameter once")
    if max_runs < 2:
        raise InputError(f"--max-runs {max_runs}: need at least 2 model runs")
    for p in params:
        try:
            cur = get_path(doc, p.key)
        except InputError:  # a key left at its default: its parents must exist, the schema checks the key
            set_path(copy.deepcopy(doc), p.key, 0.0)
            cur = None
        if cur is None:
            p.start = 0.5 * (p.lower + p.upper) if p.start is None else p.start
        elif isinstance(cur, bool) or not isinstance(cur, (int, float)):
            raise InputError(f"--param '{p.key}': the model file has {cur!r} there, not a number; only numeric "
                             "values can be calibrated")
        elif p.start is None:
            p.start = float(cur) if p.lower <= float(cur) <= p.upper else 0.5 * (p.lower + p.upper)
    dxy = read_curve(data, x, y)
    # every corner of the box and the start must give a valid model (bad values fail fast)
    for label, vals in (("start", {p.key: p.start for p in params}), ("lower bounds", {p.key: p.lower for p in params}),
                        ("upper bounds", {p.key: p.upper for p in params})):
        build_spec(with_values(doc, vals), model.parent, f"{model} with the {label} ({describe(vals)})")
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    history: list[dict] = []
    cache: dict[tuple, dict] = {}

    def evaluate(vals: dict[str, float]) -> dict:
        ck = tuple(round(vals[k], 12) for k in keys)
        if ck in cache:
            return cache[ck]
        if len(history) >= max_runs:
            raise _Budget
        t0 = time.perf_counter()
        rec: dict[str, Any] = {"values": dict(vals), "objective": math.inf, "converged": False, "error": ""}
        try:
            spec = build_spec(with_values(doc, vals), model.parent, f"{model} ({describe(vals)})")
            res = run(spec, None, write_vtu=False)
            mxy = model_curve(res.summary, x, y)
            if len(history) == 0 and mxy[0].size == 0 and (x not in curve_quantities(res.summary)
                                                           or y not in curve_quantities(res.summary)):
                raise InputError(f"--x '{x}' / --y '{y}': the model has no such quantity; it has "
                                 f"{curve_quantities(res.summary)}")
            r = objective(mxy, dxy)
            rec.update(objective=rms(r), converged=bool(res.converged), error=res.message,
                       reached=float(mxy[0][-1]) if mxy[0].size else None,
                       curve={"x": mxy[0].tolist(), "y": mxy[1].tolist()}, residuals=r.tolist())
        except InputError:
            raise
        except Exception as exc:  # a failed run scores infinitely badly, the fit goes on
            rec["error"] = f"{type(exc).__name__}: {exc}"
        rec["seconds"] = round(time.perf_counter() - t0, 3)
        history.append(rec)
        cache[ck] = rec
        if progress:
            progress(rec)
        return rec

    def unit_to_vals(t) -> dict[str, float]:
        return {p.key: p.from_unit(ti) for p, ti in zip(params, np.atleast_1d(t))}

    start_vals = {p.key: float(p.start) for p in params}
    start = evaluate(start_vals)
    chosen = method if method != "auto" else ("bounded" if len(params) == 1 else "least_squares")
    message = ""
    try:
        from scipy import optimize

        if chosen == "bounded":
            if len(params) != 1:
                raise InputError("--method bounded fits exactly one --param; use least_squares for several")
            sol = optimize.minimize_scalar(lambda t: _finite(evaluate(unit_to_vals(t))["objective"]),
                                           bounds=(0.0, 1.0), method="bounded",
                                           options={"xatol": xtol, "maxiter": max_runs})
            message = str(sol.message)
        else:
            n_data = dxy[0].size
            scale = max(float(np.max(np.abs(dxy[1]))), 1e-300)

            def residuals(t):
                rec = evaluate(unit_to_vals(t))
                r = np.asarray(rec.get("residuals", [np.nan] * n_data), float)
                return np.where(np.isfinite(r), r, 10.0 * scale)  # failed runs: large, finite residuals

            t0 = np.array([p.to_unit(p.start) for p in params])
            sol = optimize.least_squares(residuals, t0, bounds=(0.0, 1.0), method="trf", diff_step=1e-3,
                                         x_scale=1.0, xtol=xtol, ftol=1e-10, gtol=1e-10, max_nfev=max_runs)
            message = str(sol.message)
    except _Budget:
        message = f"stopped after the maximum of {max_runs} model runs (--max-runs)"
    ok = [h for h in history if math.isfinite(h["objective"])]
    if not ok:
        raise InputError(f"{model}: no model run succeeded during the calibration (first error: "
                         f"{history[0]['error'] or 'no converged step'}); check the bounds and the model")
    best = min(ok, key=lambda h: h["objective"])
    result = CalibrationResult(dict(best["values"]), best["objective"], start["objective"], len(history), chosen,
                               message, history, out)
    write_json(out / "calibration.json", {
        "model": str(model), "data": str(data), "x": x, "y": y, "method": chosen, "message": message,
        "parameters": {p.key: {"lower": p.lower, "upper": p.upper, "start": p.start, "best": best["values"][p.key]}
                       for p in params},
        "objective": best["objective"], "objective_start": start["objective"], "evaluations": len(history),
        "history": [{k: v for k, v in h.items() if k not in ("curve", "residuals")} for h in history]})
    bx = np.interp(dxy[0], *best["curve"].values()) if best.get("curve") else np.full(dxy[0].shape, np.nan)
    sx = (np.interp(dxy[0], *start["curve"].values()) if start.get("curve") and start["curve"]["x"]
          else np.full(dxy[0].shape, np.nan))
    write_csv(out / "calibration.csv", [x, y, f"{y}_start", f"{y}_best"],
              [[float(a), float(b), float(c), float(d)] for a, b, c, d in zip(dxy[0], dxy[1], sx, bx)])
    try:
        plot_calibration(out / "calibration.png", dxy, start, best,
                         *_axis_labels(build_spec(with_values(doc, best["values"]), model.parent, str(model)), x, y))
    except ImportError:  # matplotlib missing: the JSON and CSV are the result
        pass
    if best_run:
        spec = build_spec(with_values(doc, best["values"]), model.parent, f"{model} (best)")
        run(spec, out / "best", write_vtu=False, overwrite=True)
    return result


def _finite(v: float) -> float:
    return v if math.isfinite(v) else 1e300


def _axis_labels(spec, *names: str) -> list[str]:
    """``names`` (curve quantities) with their units from the model's ``[model] units``."""
    from .plots import probe_units
    from .units import Units, axis_label

    units = probe_units(spec)
    area = Units.parse(spec.model.units).area
    return [axis_label(n, area if n.split(":", 1)[0] == "debonded_area" and n not in units else units.get(n, ""))
            for n in names]


def plot_calibration(path: Path, data_xy, start: dict, best: dict, x: str, y: str) -> Path:
    """Data points with the model curves at the start and at the best parameters."""
    from .plots import _figure, _save

    fig = _figure((6.4, 4.4))
    ax = fig.add_subplot(111)
    ax.plot(data_xy[0], data_xy[1], "ko", ms=4, label="data")
    for rec, style, label in ((start, "--", "start"), (best, "-", "best")):
        c = rec.get("curve")
        if c and c["x"]:
            vals = ", ".join(f"{k} = {v:.6g}" for k, v in rec["values"].items())
            ax.plot(c["x"], c["y"], style, marker=".", label=f"{label}: {vals} (RMS {rec['objective']:.3g})")
    ax.set_xlabel(x)
    ax.set_ylabel(y)
    ax.grid(True, alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    return _save(fig, path)
