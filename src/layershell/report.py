"""A self-contained HTML report of a results folder (``layershell report DIR``).

Reads what ``layershell run`` wrote (summary.json, probes.csv, PNG figures, profile CSVs, the
names of the ParaView files) and, when present, ``sweep.csv`` (``layershell sweep``) and
``calibration.json`` (``layershell calibrate``). Figures are embedded as base64 data URIs, so the
single HTML file opens anywhere; every text taken from the files is escaped. Missing pieces are
left out (with a note), never an error, as long as the folder holds at least one known file.
"""
from __future__ import annotations

import base64
import csv
import datetime as dt
import html
import json
from pathlib import Path
from typing import Any, Iterable

KNOWN = ("summary.json", "probes.csv", "sweep.csv", "calibration.json")
RUN_KEYS = (("converged", "converged"), ("error", "error"), ("n_elements", "elements"), ("n_nodes", "nodes"),
            ("n_dofs", "DOFs (after constraints)"), ("n_dofs_full", "DOFs (before constraints)"),
            ("nonlinear", "geometrically nonlinear"), ("solver", "linear solver"),
            ("wall_seconds", "wall time (s)"), ("first_delamination_load_factor", "first delamination at λ"))

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",sans-serif;margin:2em auto;max-width:70em;padding:0 1em;color:#222}
h1{font-size:1.6em}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:.2em;margin-top:1.6em}
table{border-collapse:collapse;margin:.5em 0 1em;font-size:.92em}
th,td{border:1px solid #ccc;padding:.25em .6em;text-align:right}th{background:#f2f2f2}
td.t,th.t{text-align:left}.bad{color:#b00020;font-weight:bold}.ok{color:#1b7f1b;font-weight:bold}
figure{display:inline-block;margin:.5em;vertical-align:top;max-width:100%}
figure img{max-width:100%;border:1px solid #ddd}figcaption{font-size:.85em;color:#555}
.note{color:#666;font-size:.9em}details{margin:.5em 0}
"""


def _esc(v: Any) -> str:
    return html.escape(str(v), quote=True)


def fmt(v: Any) -> str:
    """Cell text: numbers with 6 significant digits, None as an empty cell."""
    if v is None:
        return ""
    if isinstance(v, bool):
        return "yes" if v else "no"
    if isinstance(v, float):
        return f"{v:.6g}"
    return str(v)


def _table(table_id: str, header: list[str] | None, rows: Iterable[list], text_cols: int = 1) -> str:
    """An HTML table (no header row if ``header`` is None); the first ``text_cols`` columns are
    left-aligned labels."""
    cls = lambda j: ' class="t"' if j < text_cols else ""  # noqa: E731
    out = [f'<table id="{_esc(table_id)}">']
    if header is not None:
        out += ["<thead><tr>"] + [f"<th{cls(j)}>{_esc(h)}</th>" for j, h in enumerate(header)] + ["</tr></thead>"]
    out.append("<tbody>")
    for r in rows:
        out.append("<tr>" + "".join(f"<td{cls(j)}>{_esc(fmt(v))}</td>" for j, v in enumerate(r)) + "</tr>")
    out.append("</tbody></table>")
    return "".join(out)


def _read_csv(path: Path) -> tuple[list[str], list[list[str]]] | None:
    try:
        with path.open(newline="", encoding="utf-8") as f:
            rows = list(csv.reader(f))
    except (OSError, UnicodeDecodeError, csv.Error):
        return None
    return (rows[0], rows[1:]) if rows else None


def _num(s: str) -> Any:
    try:
        return float(s)
    except (TypeError, ValueError):
        return s


def _read_json(path: Path) -> dict | None:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError, UnicodeDecodeError):
        return None
    return data if isinstance(data, dict) else None


def _read_steps(path: Path) -> list[dict]:
    """The step records of steps.jsonl (written by the recorder, one line per converged step)."""
    out: list[dict] = []
    try:
        with path.open(encoding="utf-8") as f:
            for ln in f:
                rec = json.loads(ln)
                if not isinstance(rec, dict):
                    break
                rec.pop("files", None)
                out.append(rec)
    except (OSError, ValueError, UnicodeDecodeError):
        pass  # missing, or a line cut short by a kill: what was read
    return out


def _json_problem(path: Path) -> str:
    """Why ``path`` is not a JSON object (for the error message)."""
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except UnicodeDecodeError:
        return "not UTF-8 text"
    except ValueError as exc:
        return f"not JSON: {exc}"
    except OSError as exc:
        return exc.strerror or str(exc)
    return f"a JSON {type(data).__name__}, not an object" if not isinstance(data, dict) else "empty"


def _model_file(folder: Path, summary: dict, model: str | Path | None) -> str:
    if model is not None:
        return str(model)
    for k in ("model_file", "model", "source"):
        if isinstance(summary.get(k), str):
            return summary[k]
    variant = _read_json(folder / "variant.json") if (folder / "variant.json").is_file() else None
    if variant and variant.get("model_file"):
        vals = ", ".join(f"{k} = {v}" for k, v in (variant.get("values") or {}).items())
        return f"{variant['model_file']} (sweep variant {variant.get('variant')}: {vals})"
    tomls = sorted(folder.glob("*.toml"))
    return str(tomls[0]) if tomls else "not recorded in the results folder (give --model)"


def _section_model_text(folder: Path, summary: dict, model: str | Path | None) -> str:
    """The model file's text: as run (``model_text`` in summary.json), else the file named by
    ``--model`` or summary.json as it is now (noted when it is newer than the results)."""
    text, note = summary.get("model_text"), ""
    if not isinstance(text, str):
        name = model if model is not None else summary.get("model_file")
        path = Path(name) if isinstance(name, (str, Path)) else None
        if path is None or not path.is_file():
            return ""
        try:
            text = path.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError):
            return ""
        res = folder / "summary.json"
        if res.is_file() and path.stat().st_mtime > res.stat().st_mtime:
            note = f'<p class="note">read from {_esc(path)} now; it was changed after the results were written</p>'
    return (f'<h2>Model file</h2>{note}<details><summary>model file text</summary>'
            f'<pre id="model-text">{_esc(text)}</pre></details>')


def _utc(ts: float) -> str:
    return dt.datetime.fromtimestamp(ts, dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")


def render(folder: str | Path, model: str | Path | None = None) -> str:
    """The report of ``folder`` as one HTML document (str)."""
    from . import __version__
    from .io.build import InputError

    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(f"results folder '{folder}' does not exist or is not a folder; give the folder that "
                         "`layershell run MODEL --out DIR` (or sweep/calibrate) wrote")
    if not any((folder / k).is_file() for k in KNOWN):
        raise InputError(f"'{folder}' holds none of {', '.join(KNOWN)}; give the folder that `layershell run "
                         "MODEL --out DIR` (or sweep/calibrate) wrote")
    if model is not None and not Path(model).is_file():
        raise InputError(f"--model '{model}': no such file; give the model file of the run (it is named in the "
                         "report), or leave --model out to take the name recorded in summary.json")
    summary = _read_json(folder / "summary.json") or {}
    notes: list[str] = []
    if (folder / "summary.json").is_file() and not summary:
        raise InputError(f"'{folder / 'summary.json'}' cannot be read ({_json_problem(folder / 'summary.json')}), so "
                         "the report would lack the run's results; the file is damaged (cut short or edited): rerun "
                         "the model into this folder (layershell run MODEL --out DIR) or restore the file")
    recorded = _read_steps(folder / "steps.jsonl")
    if summary and len(recorded) > len(summary.get("steps") or []):  # summary.json lags (run killed)
        notes.append(f"summary.json lists {len(summary.get('steps') or [])} step(s) but steps.jsonl records "
                     f"{len(recorded)} converged step(s) (summary.json is rewritten at a bounded rate and the run "
                     "was stopped before its last rewrite); the step tables show steps.jsonl.")
        summary = dict(summary, steps=recorded)
    title = summary.get("title") or folder.name
    now = dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC")
    run_time = _utc((folder / "summary.json").stat().st_mtime) if (folder / "summary.json").is_file() else ""
    parts: list[str] = [f"<h1>{_esc(title)}</h1>"]
    meta = [["model file", _model_file(folder, summary, model)], ["results folder", str(folder.resolve())],
            ["results written", run_time or "—"], ["units", summary.get("units") or "not given"],
            ["written by layershell", summary.get("version") or "not recorded"],
            ["report generated", f"{now} by layershell {__version__}"]]
    parts.append(_table("meta", None, meta, text_cols=2))

    if summary:
        parts.append(_section_run(summary))
    probes_csv = _read_csv(folder / "probes.csv") if (folder / "probes.csv").is_file() else None
    if summary.get("steps") or probes_csv:
        parts.append(_section_steps(summary, probes_csv))
    parts.append(_section_figures(folder))
    for extra in (_section_model_text(folder, summary, model), _section_profiles(folder), _section_sweep(folder), _section_calibration(folder),
                  _section_files(folder)):
        if extra:
            parts.append(extra)
    if notes:
        parts.append("".join(f'<p class="note">{_esc(n)}</p>' for n in notes))
    body = "\n".join(parts)
    return (f'<!DOCTYPE html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{_esc(title)} — layershell report</title><style>{CSS}</style></head>\n"
            f"<body>\n{body}\n</body></html>\n")


def _section_run(s: dict) -> str:
    rows = []
    for k, label in RUN_KEYS:
        if k in s and not (k == "error" and not s[k]):
            rows.append([label, s[k]])
    rows.insert(1 if rows and rows[0][0] == "converged" else 0, ["converged steps", len(s.get("steps", []))])
    if s.get("steps"):
        rows.append(["final load factor λ", s["steps"][-1].get("load_factor")])
    out = ["<h2>Model and run</h2>"]
    if s.get("converged") is False:
        out.append(f'<p class="bad">The solution did not converge: {_esc(s.get("error", ""))}</p>')
    elif s.get("converged"):
        out.append('<p class="ok">Converged to the last load step.</p>')
    out.append(_table("run", ["quantity", "value"], rows))
    probes = s.get("probes") or {}
    out.append("<h2>Final probe values</h2>")
    if probes:
        out.append(_table("probes", ["probe", "value"], [[k, v] for k, v in probes.items()]))
    else:
        out.append('<p class="note">No probes (add [[probes]] to the model file).</p>')
    return "\n".join(out)


def _section_steps(s: dict, probes_csv) -> str:
    out = ["<h2>Convergence history</h2>"]
    steps = s.get("steps") or []
    if steps:
        areas = list(dict.fromkeys(k for st in steps for k in (st.get("debonded_area") or {})))
        header = ["step", "load factor λ", "Newton iterations", "bisections"]
        has_res = any("resolves" in st for st in steps)
        header += ["re-solutions"] if has_res else []
        header += ["wall time (s)"] + [f"debonded area {a}" for a in areas]
        rows = []
        for st in steps:
            r = [st.get("step"), st.get("load_factor"), st.get("iterations"), st.get("bisections")]
            r += [st.get("resolves")] if has_res else []
            r += [st.get("wall_seconds")] + [(st.get("debonded_area") or {}).get(a) for a in areas]
            rows.append(r)
        out.append(_table("convergence", header, rows, text_cols=0))
        itf = list(dict.fromkeys(k for st in steps for k in (st.get("interfaces") or {})))
        for name in itf:
            cols = list(dict.fromkeys(c for st in steps for c in (st.get("interfaces") or {}).get(name, {})))
            out.append(f"<h3>Interface {_esc(name)}: tractions of the upper layer</h3>")
            out.append(_table(f"interface-{name}", ["step", "load factor λ"] + cols,
                              [[st.get("step"), st.get("load_factor")]
                               + [(st.get("interfaces") or {}).get(name, {}).get(c) for c in cols] for st in steps],
                              text_cols=0))
    else:
        out.append('<p class="note">summary.json has no converged steps.</p>')
    out.append("<h2>Probes per step</h2>")
    if probes_csv:
        header, rows = probes_csv
        out.append('<p class="note">From probes.csv.</p>')
        out.append(_table("probes-per-step", header, [[_num(v) for v in r] for r in rows], text_cols=0))
    elif steps:
        names = list(dict.fromkeys(k for st in steps for k in (st.get("probes") or {})))
        out.append('<p class="note">probes.csv is missing; the values from summary.json.</p>')
        out.append(_table("probes-per-step", ["step", "load_factor", "iterations"] + names,
                          [[st.get("step"), st.get("load_factor"), st.get("iterations")]
                           + [(st.get("probes") or {}).get(n) for n in names] for st in steps], text_cols=0))
    return "\n".join(out)


def _png_uri(path: Path) -> str | None:
    try:
        data = path.read_bytes()
    except OSError:
        return None
    if not data.startswith(b"\x89PNG"):
        return None
    return "data:image/png;base64," + base64.b64encode(data).decode("ascii")


def _section_figures(folder: Path) -> str:
    pngs = sorted(folder.glob("*.png"))
    out = ["<h2>Figures</h2>"]
    figs = []
    for p in pngs:
        uri = _png_uri(p)
        if uri is None:
            continue
        figs.append(f'<figure><img src="{uri}" alt="{_esc(p.name)}"><figcaption>{_esc(p.name)}</figcaption></figure>')
    out += figs or ['<p class="note">No figures in the folder (plots = false, or matplotlib missing).</p>']
    return "\n".join(out)


def _section_profiles(folder: Path) -> str:
    out = []
    for p in sorted(folder.glob("profile_*.csv")):
        t = _read_csv(p)
        if not t:
            continue
        header, rows = t
        out.append(f"<details><summary>{_esc(p.name)} ({len(rows)} rows)</summary>"
                   + _table(p.stem, header, [[_num(v) for v in r] for r in rows], text_cols=0) + "</details>")
    return ("<h2>Through-thickness profiles</h2>\n" + "\n".join(out)) if out else ""


def _section_sweep(folder: Path) -> str:
    t = _read_csv(folder / "sweep.csv") if (folder / "sweep.csv").is_file() else None
    if not t:
        return ""
    header, rows = t
    return ("<h2>Parameter study (sweep.csv)</h2>\n"
            + _table("sweep", header, [[r[0]] + [_num(v) for v in r[1:]] for r in rows]))


def _section_calibration(folder: Path) -> str:
    c = _read_json(folder / "calibration.json") if (folder / "calibration.json").is_file() else None
    if not c:
        return ""
    out = ["<h2>Calibration (calibration.json)</h2>"]
    rows = [["data", c.get("data")], ["x / y", f"{c.get('x')} / {c.get('y')}"], ["method", c.get("method")],
            ["objective (RMS) at start", c.get("objective_start")], ["objective (RMS) at best", c.get("objective")],
            ["model runs", c.get("evaluations")], ["optimiser message", c.get("message")]]
    out.append(_table("calibration", ["quantity", "value"], rows))
    params = c.get("parameters") or {}
    if params:
        out.append(_table("calibration-parameters", ["parameter", "lower", "upper", "start", "best"],
                          [[k, p.get("lower"), p.get("upper"), p.get("start"), p.get("best")]
                           for k, p in params.items()]))
    hist = c.get("history") or []
    if hist:
        keys = list(params)
        out.append("<details><summary>history of the model runs</summary>"
                   + _table("calibration-history", ["run"] + keys + ["objective (RMS)", "converged"],
                            [[i + 1] + [h.get("values", {}).get(k) for k in keys] + [h.get("objective"),
                                                                                    h.get("converged")]
                             for i, h in enumerate(hist)], text_cols=0) + "</details>")
    return "\n".join(out)


def _section_files(folder: Path) -> str:
    files = sorted(p for p in folder.iterdir() if p.is_file() and p.suffix in (".vtu", ".pvd"))
    if not files:
        return ""
    rows = [[p.name, f"{p.stat().st_size / 1024:.1f}"] for p in files]
    return ("<h2>ParaView files</h2>\n<p class=\"note\">Open the .pvd files in ParaView (not embedded).</p>\n"
            + _table("files", ["file", "size (KiB)"], rows))


def write_report(folder: str | Path, out: str | Path | None = None, model: str | Path | None = None) -> Path:
    """Write the report of ``folder`` to ``out`` (default ``folder/report.html``); return its path."""
    from .io.output import atomic_write_text

    path = Path(out) if out is not None else Path(folder) / "report.html"
    atomic_write_text(path, render(folder, model))
    return path
