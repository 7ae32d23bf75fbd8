"""The results folder has one owner (issue 15): lock, earlier results, atomic files, modes,
appended per-step files; run.log, --verbose, --version, live progress; and the CLI's answers to
faults around the folder (a checkpoint holding NaN, a damaged summary.json, a missing --model,
a 300-character name, an ASCII console).

The references are independent of the code under test: file modes against ``0666 & ~umask``
(what ``open()`` gives), appended CSV/PVD files against a rewrite of all rows at once, PNG files
against the PNG format (signature and final IEND chunk), the holder of a lock by its PID.
"""
from __future__ import annotations

import ast
import json
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from layershell import __version__, checkpoint
from layershell.export import PvdWriter, write_pvd
from layershell.io.build import load
from layershell.io.output import FILE_MODE, AppendCsv, csv_text, write_csv
from layershell.recorder import LOCK, MANIFEST, Recorder, ResultsFolderError
from layershell.runner import run

ROOT = Path(__file__).resolve().parents[1]
SRC = ROOT / "src" / "layershell"
EXAMPLES = ROOT / "examples"


def _command() -> list[str]:
    return [sys.executable, "-m", "layershell"]


def _env(**extra) -> dict:
    env = dict(os.environ, NO_COLOR="1", COLUMNS="200", PYTHONIOENCODING="utf-8",
               PYTHONPATH=str(ROOT / "src") + os.pathsep + os.environ.get("PYTHONPATH", ""))
    env.update(extra)
    env.pop("LAYERSHELL_TRACEBACK", None)
    return env


def _cli(args: list, cwd: Path, timeout: float = 300, preexec=None, **env) -> subprocess.CompletedProcess:
    return subprocess.run(_command() + [str(a) for a in args], cwd=cwd, capture_output=True, text=True,
                          encoding="utf-8", errors="replace", env=_env(**env), timeout=timeout, preexec_fn=preexec)


def _model(d: Path, name: str = "beam.toml", steps: int = 1, extra: str = "") -> Path:
    """The thick cantilever (5 elements, linear) with ``steps`` load steps."""
    text = (EXAMPLES / "cantilever_thick.toml").read_text(encoding="utf-8")
    text = text.replace("[steps]\nn = 1", f"[steps]\nn = {steps}") + extra
    p = d / name
    p.write_text(text, encoding="utf-8")
    return p


def _delam_model(d: Path, name: str = "delam.toml") -> Path:
    """A tiny plate that debonds (cantilever_plate_slip, 1 × 2 elements, d = 1, 6 steps)."""
    text = (EXAMPLES / "cantilever_plate_slip.toml").read_text(encoding="utf-8")
    for a, b in {"nx = 3": "nx = 1", "ny = 3": "ny = 2", "n = 24": "n = 6\nlambda_end = 1.5",
                 "directors = 3": "directors = 1", "every = 6": "every = 2\nplots = false"}.items():
        assert a in text, a
        text = text.replace(a, b)
    p = d / name
    p.write_text(text, encoding="utf-8")
    return p


def _png_complete(p: Path) -> bool:
    b = p.read_bytes()
    return b.startswith(b"\x89PNG\r\n\x1a\n") and b[-12:] == b"\x00\x00\x00\x00IEND\xaeB`\x82"


# ------------------------------------------------------------------ file modes


@pytest.mark.parametrize("umask", [0o022, 0o027])
def test_every_file_gets_the_mode_of_the_umask(tmp_path, umask):
    """All files of a run (JSON, CSV, VTU, PVD, checkpoint, PNG, run.log) get 0666 & ~umask (0644
    with the usual umask 022; mkstemp alone would give 0600)."""
    model = _model(tmp_path, steps=2)
    r = _cli(["run", model, "--out", tmp_path / "out", "-q"], tmp_path, preexec=lambda: os.umask(umask))
    assert r.returncode == 0, r.stderr
    files = [p for p in (tmp_path / "out").iterdir() if p.is_file()]
    assert {"summary.json", "probes.csv", "checkpoint.npz", "surface.pvd", "solid_0002.vtu", "deformed.png",
            "run.log", "steps.jsonl"} <= {p.name for p in files}
    modes = {p.name: stat.S_IMODE(p.stat().st_mode) for p in files}
    assert set(modes.values()) == {0o666 & ~umask}, modes
    mask = os.umask(0o022)
    os.umask(mask)
    assert FILE_MODE == 0o666 & ~mask  # this process: the same rule


# ------------------------------------------------------------------ one run per folder


def test_a_second_run_into_a_folder_in_use_is_refused(tmp_path):
    """While a run holds the folder, a second `layershell run` there exits 2 naming the holder's
    PID and --out, and leaves the folder alone; afterwards the folder can be used again."""
    model = _model(tmp_path)
    out = tmp_path / "out"
    with Recorder(out, model_file=str(model)) as rec:
        rec.write_json("summary.json", {"title": "the first run", "model_file": str(model)})
        before = (out / "summary.json").read_bytes()
        r = _cli(["run", model, "--out", out, "-q"], tmp_path)
        assert r.returncode == 2, r.stderr
        msg = " ".join(r.stderr.split())
        assert "in use by another layershell run" in msg and f"PID {os.getpid()}" in msg and "--out" in msg, msg
        assert "Traceback" not in r.stderr
        assert (out / "summary.json").read_bytes() == before
        with pytest.raises(ResultsFolderError, match=f"PID {os.getpid()}"):  # also within one process
            Recorder(out, model_file=str(model)).open()
    r = _cli(["run", model, "--out", out, "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "summary.json").read_text())["converged"]


def test_two_runs_started_together_never_mix(tmp_path):
    """Two runs of a 6-step model started at the same moment into one folder: one of them is
    refused with exit code 2 (or they ran one after the other); the folder then holds one
    complete, consistent run (summary.json, probes.csv and steps.jsonl with all 6 steps)."""
    model = _model(tmp_path, steps=6)
    out = tmp_path / "out"
    procs = [subprocess.Popen(_command() + ["run", str(model), "--out", str(out), "-q"], cwd=tmp_path, env=_env(),
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    results = [(p.wait(timeout=300), p.communicate()[1]) for p in procs]
    codes = sorted(c for c, _ in results)
    assert codes in ([0, 0], [0, 2]), results
    for c, e in results:
        if c == 2:
            assert "in use by another layershell run" in " ".join(e.split())
    s = json.loads((out / "summary.json").read_text())
    assert s["converged"] and [st["step"] for st in s["steps"]] == list(range(1, 7))
    assert len((out / "probes.csv").read_text().splitlines()) == 7
    assert len((out / "steps.jsonl").read_text().splitlines()) == 6


# ------------------------------------------------------------------ earlier results


def test_another_models_results_are_refused_then_replaced_with_overwrite(tmp_path):
    """A run of another model file into a folder holding results is refused (exit 2, naming the
    earlier model and --overwrite) and changes nothing; with --overwrite the earlier model's files
    are gone (no delamination.csv, interface series or figures of it), files that layershell did
    not write stay, and the report shows the new model only."""
    a, b = _delam_model(tmp_path), _model(tmp_path, "other.toml")
    out = tmp_path / "out"
    r = _cli(["run", a, "--out", out, "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    (out / "notes.txt").write_text("mine", encoding="utf-8")
    earlier = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != LOCK}
    assert {"delamination.csv", "interface_concrete_trc.pvd", "solid_0006.vtu"} <= set(earlier)
    r = _cli(["run", b, "--out", out, "-q"], tmp_path)
    assert r.returncode == 2
    msg = " ".join(r.stderr.split())
    assert "holds the results of the model file" in msg and "delam.toml" in msg and "--overwrite" in msg, msg
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file() and p.name != LOCK} == earlier
    r = _cli(["run", b, "--out", out, "-q", "--overwrite"], tmp_path)
    assert r.returncode == 0, r.stderr
    names = {p.name for p in out.iterdir()}
    assert "delamination.csv" not in names and not any(n.startswith("interface_") for n in names)
    assert "solid_0006.vtu" not in names and "solid_0001.vtu" in names and "notes.txt" in names
    assert (out / "probes.csv").read_text().splitlines()[0] == "step,load_factor,iterations,w_tip"
    r = _cli(["report", out], tmp_path)
    assert r.returncode == 0, r.stderr
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "other.toml" in html and "delam" not in html


def test_a_rerun_of_the_same_model_file_replaces_its_results(tmp_path):
    """Rerunning an edited model file into its folder needs no --overwrite and leaves no file of
    the earlier run (its step 4 files are gone after a rerun with 2 steps)."""
    model = _model(tmp_path, steps=4)
    out = tmp_path / "out"
    assert _cli(["run", model, "--out", out, "-q"], tmp_path).returncode == 0
    assert (out / "surface_0004.vtu").is_file()
    (out / ".summary.json.x.tmp").write_text("{", encoding="utf-8")  # a leftover of a killed write
    _model(tmp_path, steps=2)
    r = _cli(["run", model, "--out", out, "-q"], tmp_path)
    assert r.returncode == 0, r.stderr
    names = {p.name for p in out.iterdir()}
    assert "surface_0004.vtu" not in names and "surface_0002.vtu" in names
    assert not [n for n in names if n.endswith(".tmp")]
    assert "surface_0004.vtu" not in (out / "surface.pvd").read_text()
    assert len(json.loads((out / "summary.json").read_text())["steps"]) == 2
    assert MANIFEST in names


def test_a_model_that_fails_to_build_leaves_the_earlier_results(tmp_path, monkeypatch):
    """The earlier run's files are removed only once the new run is set up: a rerun whose model
    cannot be built (here: the problem set-up raises) leaves them as they were."""
    from layershell.solver.problem import Problem

    model = _model(tmp_path, steps=2)
    out = tmp_path / "out"
    assert run(load(model), out, write_vtu=False).converged
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}

    def broken(cls, m):
        raise ValueError("supports cannot be set up")

    monkeypatch.setattr(Problem, "build", classmethod(broken))
    with pytest.raises(ValueError, match="supports"):
        run(load(model), out, write_vtu=False)
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


# ------------------------------------------------------------------ atomic files


_WRITER = """
import io, sys, time
from pathlib import Path
import matplotlib.figure
from layershell.io.build import load
from layershell.plots import write_figures
from layershell.runner import run, through_thickness

save = matplotlib.figure.Figure.savefig


def slow_disk(self, fname, *args, **kw):  # write the PNG in two halves with a pause between
    buf = io.BytesIO()
    save(self, buf, *args, **dict(kw, format="png"))
    data = buf.getvalue()
    with open(fname, "wb") as f:
        f.write(data[: len(data) // 2])
        f.flush()
        print("half written", flush=True)
        time.sleep(60)
        f.write(data[len(data) // 2:])


matplotlib.figure.Figure.savefig = slow_disk
spec = load(sys.argv[2])
res = run(spec, None)
print("drawing", flush=True)
write_figures(Path(sys.argv[1]), spec, res.problem, res.u, res.summary, through_thickness=through_thickness)
"""


def test_a_kill_during_figure_writing_leaves_no_broken_png(tmp_path):
    """SIGKILL a process in the middle of writing a figure over the run's PNG (a slow disk: half of
    the bytes written, then a pause): the PNG in the folder is still the complete earlier one,
    never 0 bytes or cut short (written in place, as before issue 15, it would be half a PNG); the
    temporary leftover is removed by the next run into the folder."""
    model = _model(tmp_path)
    out = tmp_path / "out"
    assert _cli(["run", model, "--out", out, "-q"], tmp_path).returncode == 0
    before = {q.name: q.read_bytes() for q in out.glob("*.png")}
    assert before and all(_png_complete(out / n) for n in before)
    p = subprocess.Popen([sys.executable, "-c", _WRITER, str(out), str(model)], cwd=tmp_path, env=_env(),
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        lines = []
        while not lines or lines[-1] != "half written":
            line = p.stdout.readline()
            assert line, p.stderr.read()
            lines.append(line.strip())
    finally:
        p.send_signal(signal.SIGKILL)
        p.communicate()
    assert {q.name: q.read_bytes() for q in out.glob("*.png")} == before  # unchanged, complete
    assert list(out.glob(".*.tmp"))  # the killed write's half file is a hidden temporary
    assert _cli(["run", model, "--out", out, "-q"], tmp_path).returncode == 0
    assert not list(out.glob(".*.tmp")) and all(_png_complete(q) for q in out.glob("*.png"))


# ------------------------------------------------------------------ appended files


def test_appended_csv_equals_a_rewrite(tmp_path):
    """Row by row appended CSV has the bytes of one write of all rows (floats, NaN, ints, empty
    cells, text with commas and quotes)."""
    rng = np.random.default_rng(7)
    header = ["step", "x", "note", "y"]
    rows = [[i, float(v), "" if i % 3 else 'a, "b"', float("nan") if i == 4 else float(w)]
            for i, (v, w) in enumerate(rng.standard_normal((40, 2)) * 10.0 ** rng.integers(-12, 12, (40, 2)))]
    f = AppendCsv(tmp_path / "a.csv", header, rows[:5])
    for r in rows[5:]:
        f.append(r)
    f.close()
    write_csv(tmp_path / "b.csv", header, rows)
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()


def test_a_runs_appended_files_equal_a_rewrite_from_the_summary(tmp_path):
    """probes.csv, delamination.csv, steps.jsonl and the .pvd files of a 6-step delamination run,
    written step by step, equal what one write of the final summary's steps gives."""
    model = _delam_model(tmp_path)
    spec = load(model)
    out = tmp_path / "out"
    res = run(spec, out, write_vtu=True)
    assert res.converged
    steps = res.summary["steps"]
    log = (out / "run.log").read_text(encoding="utf-8")  # bond and contact changes are logged
    first = next(s["step"] for s in steps if sum(s["debonded_area"].values()) > 0)
    assert f"step {first} λ = " in log and "bond/contact update, debonded area 0 → " in log
    assert "contact points" in log and "changed)" in log
    names = [p.name for p in spec.probes]
    rows = [[s["step"], s["load_factor"], s["iterations"]] + [s["probes"][n] for n in names] for s in steps]
    assert (out / "probes.csv").read_text() == csv_text(["step", "load_factor", "iterations"] + names, rows)
    itf = list(steps[0]["debonded_extent"])
    keys = ["area", "x_min", "x_max", "y_min", "y_max"]
    drows = [[s["step"], s["load_factor"]] + ["" if s["debonded_extent"][n][k] is None
                                               else float(s["debonded_extent"][n][k]) for n in itf for k in keys]
             for s in steps]
    assert (out / "delamination.csv").read_text() == csv_text(
        ["step", "load_factor"] + [f"{n}:{k}" for n in itf for k in keys], drows)
    lines = [json.loads(x) for x in (out / "steps.jsonl").read_text().splitlines()]
    assert [{k: v for k, v in x.items() if k != "files"} for x in lines] == json.loads(
        (out / "summary.json").read_text())["steps"]
    for key in ("surface", "solid", "interface_concrete_trc"):
        entries = [(s["load_factor"], f"{key}_{s['step']:04d}.vtu") for s in steps if s["step"] % 2 == 0]
        write_pvd(tmp_path / "ref.pvd", entries)
        assert (out / f"{key}.pvd").read_text() == (tmp_path / "ref.pvd").read_text(), key
    w = PvdWriter(tmp_path / "pvd")  # appending to a .pvd = writing it whole
    for i in range(5):
        w.add(i, 0.1 * i, {"surface": tmp_path / "pvd" / f"s{i}.vtu"})
    write_pvd(tmp_path / "ref.pvd", [(0.1 * i, f"s{i}.vtu") for i in range(5)])
    assert (tmp_path / "pvd" / "surface.pvd").read_text() == (tmp_path / "ref.pvd").read_text()


def test_the_checkpoint_does_not_grow_with_the_steps(tmp_path):
    """The history lives in steps.jsonl (appended); checkpoint.npz holds the state only, so its
    size after 2 and after 8 steps is the same to a few bytes of JSON numbers."""
    sizes = {}
    for n in (2, 8):
        model = _model(tmp_path, f"m{n}.toml", steps=n)
        spec = load(model)
        run(spec, tmp_path / f"o{n}", write_vtu=False)
        sizes[n] = (tmp_path / f"o{n}" / "checkpoint.npz").stat().st_size
        assert len((tmp_path / f"o{n}" / "steps.jsonl").read_text().splitlines()) == n
    assert abs(sizes[8] - sizes[2]) < 64, sizes


# ------------------------------------------------------------------ no import circles


def _imports(path: Path, package: str) -> set[str]:
    """Modules of layershell that ``path`` imports anywhere (also inside functions)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    here = package.split(".")
    out = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                base = here[: len(here) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out.add(mod)
            out |= {f"{mod}.{a.name}" for a in node.names}
        elif isinstance(node, ast.Import):
            out |= {a.name for a in node.names}
    return {m for m in out if m.startswith("layershell")}


@pytest.mark.parametrize("a, b", [("plots", "runner"), ("io.build", "io.probes"), ("recorder", "runner"),
                                  ("recorder", "plots")])
def test_no_import_circle(a, b):
    """plots ↔ runner and io/build ↔ io/probes: only one direction is imported (also lazily);
    the recorder imports neither the runner nor the figures."""
    def uses(x, y):
        return f"layershell.{y}" in _imports(SRC / (x.replace(".", "/") + ".py"), f"layershell.{x}")

    assert not (uses(a, b) and uses(b, a)), (a, b)
    if a == "recorder":
        assert not uses(a, b)


def test_every_module_imports_alone():
    """Each module of the package imports first in a fresh interpreter (no circle at import)."""
    mods = sorted("layershell." + str(p.relative_to(SRC).with_suffix("")).replace(os.sep, ".")
                  for p in SRC.rglob("*.py") if p.name not in ("__main__.py",) and "parallel" not in p.parts)
    mods = [m[: -len(".__init__")] if m.endswith(".__init__") else m for m in mods]
    code = ("import importlib, sys\nbad = []\nfor m in sys.argv[1:]:\n"
            "    for k in [k for k in sys.modules if k.startswith('layershell')]: del sys.modules[k]\n"
            "    try: importlib.import_module(m)\n"
            "    except Exception as e: bad.append((m, repr(e)))\nprint(bad)\n")
    r = subprocess.run([sys.executable, "-c", code, *mods], capture_output=True, text=True, env=_env(), timeout=300)
    assert r.returncode == 0 and r.stdout.strip() == "[]", (r.stdout, r.stderr)


# ------------------------------------------------------------------ feedback


def test_run_log_verbose_and_live_progress(tmp_path):
    """run.log holds every Newton iteration (residual, energy norm) and every converged step;
    --verbose prints the same lines; the progress callback sees every iteration live."""
    model = _model(tmp_path, steps=2, extra="")
    text = model.read_text().replace("nonlinear = false", "nonlinear = true")
    model.write_text(text)
    r = _cli(["run", model, "--out", tmp_path / "out", "--verbose"], tmp_path)
    assert r.returncode == 0, r.stderr
    log = (tmp_path / "out" / "run.log").read_text(encoding="utf-8").splitlines()
    its = [ln for ln in log if " iteration " in ln]
    assert any("energy norm" in ln for ln in its) and any("iteration 0: residual" in ln for ln in its)
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert [ln for ln in log if "converged:" in ln] == [ln for ln in log if ln.startswith("step ") and "converged" in ln]
    assert len([ln for ln in log if "converged:" in ln]) == 2
    for st in s["steps"]:  # iterations 0..n of each step (a step may need more with bisections)
        assert len([ln for ln in its if ln.startswith(f"step {st['step']} ")]) >= st["iterations"] + 1
    assert all(ln in r.stderr for ln in log)  # --verbose: every line of run.log on the console
    seen = []
    res = run(load(model), None, monitor=seen.append)
    assert [i["iteration"] for i in seen if i["step"] == 1][:2] == [0, 1]
    last = [i for i in seen if i["step"] == 2][-1]
    assert last["relative_residual"] <= 1e-8 and res.converged


def test_version(tmp_path):
    r = _cli(["--version"], tmp_path)
    assert r.returncode == 0 and r.stdout.strip() == f"layershell {__version__}"


def test_run_help_has_no_raw_markup(tmp_path):
    r = _cli(["run", "--help"], tmp_path)
    assert r.returncode == 0
    for raw in ("``", "[bold", "[/", ":func:", "--restart DIR``"):
        assert raw not in r.stdout, raw
    assert "--overwrite" in r.stdout and "--verbose" in r.stdout


# ------------------------------------------------------------------ item 7: faults


def test_an_ascii_console_never_gives_a_traceback(tmp_path):
    """PYTHONIOENCODING=ascii: the run succeeds, λ and — are replaced, no traceback (also for an
    error message with non-ASCII characters)."""
    model = _model(tmp_path)
    r = _cli(["run", model, "--out", tmp_path / "out"], tmp_path, PYTHONIOENCODING="ascii")
    assert r.returncode == 0 and "Traceback" not in r.stderr + r.stdout, r.stderr
    assert "w_tip" in r.stdout and "results in" in r.stdout
    bad = tmp_path / "bäd—λ.toml"
    bad.write_text("[model]\ntitle = 'Θ'\n", encoding="utf-8")
    r = _cli(["check", bad], tmp_path, PYTHONIOENCODING="ascii")
    assert r.returncode == 2 and "Traceback" not in r.stderr and r.stderr.startswith("error:"), r.stderr


def test_a_checkpoint_holding_nan_is_refused(tmp_path):
    """--restart from a checkpoint with NaN displacements: exit 2 naming the cause and the fix
    (before: an internal error from the figures, 'Axis limits cannot be NaN')."""
    model = _model(tmp_path, steps=3)
    out = tmp_path / "out"
    assert _cli(["run", model, "--out", out, "-q"], tmp_path).returncode == 0
    ck = checkpoint.load(out)
    ck.u[5] = np.nan
    checkpoint.save(out / checkpoint.FILENAME, ck)
    r = _cli(["run", model, "--restart", out, "-q"], tmp_path)
    assert r.returncode == 2, r.stderr
    msg = " ".join(r.stderr.split())
    assert "NaN or infinite" in msg and "without --restart" in msg and "Traceback" not in r.stderr, msg


def test_figures_that_cannot_be_drawn_are_a_warning_not_an_error(tmp_path, monkeypatch):
    """A converged run whose figures fail (as matplotlib does on NaN axis limits) keeps its
    numbers and says so in one warning (summary.json, run.log, the CLI) instead of an internal
    error."""
    import layershell.plots as plots

    def broken(*a, **k):
        raise ValueError("Axis limits cannot be NaN or Inf")

    monkeypatch.setattr(plots, "plot_deformed", broken)
    res = run(load(_model(tmp_path)), tmp_path / "out", write_vtu=False)
    assert res.converged
    s = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert len(s["warnings"]) == 1 and "figures could not be drawn" in s["warnings"][0]
    assert "Axis limits" in s["warnings"][0] and s["probes"]["w_tip"] == pytest.approx(4.02045, rel=1e-5)  # MITC9 (full element: 4.01246)
    assert "warning: the figures could not be drawn" in (tmp_path / "out" / "run.log").read_text()


def test_report_of_a_damaged_summary_and_a_missing_model_file(tmp_path):
    model = _model(tmp_path)
    out = tmp_path / "out"
    assert _cli(["run", model, "--out", out, "-q"], tmp_path).returncode == 0
    r = _cli(["report", out, "--model", tmp_path / "missing.toml"], tmp_path)
    assert r.returncode == 2 and "--model" in r.stderr and "no such file" in r.stderr, r.stderr
    r = _cli(["report", out, "--model", model], tmp_path)
    assert r.returncode == 0, r.stderr
    s = json.loads((out / "summary.json").read_text())  # as after a kill between two summary rewrites
    with (out / "steps.jsonl").open("a") as f:
        f.write(json.dumps(dict(s["steps"][0], step=2, load_factor=2.0)) + "\n")
    r = _cli(["report", out], tmp_path)
    assert r.returncode == 0, r.stderr
    html = (out / "report.html").read_text(encoding="utf-8")
    assert "steps.jsonl records 2 converged step(s)" in html
    text = (out / "summary.json").read_text()
    (out / "summary.json").write_text(text[: len(text) // 2])
    r = _cli(["report", out], tmp_path)
    msg = " ".join(r.stderr.split())
    assert r.returncode == 2 and "summary.json" in msg and "not JSON" in msg and "rerun" in msg, msg


def test_a_300_character_name(tmp_path):
    """A 300-character results folder or model file name: exit 2 saying the name is too long."""
    model = _model(tmp_path)
    r = _cli(["run", model, "--out", tmp_path / ("r" * 300), "-q"], tmp_path)
    msg = " ".join(r.stderr.split())
    assert r.returncode == 2 and "too long" in msg and "--out" in msg and "Traceback" not in r.stderr, msg
    r = _cli(["run", tmp_path / ("m" * 300 + ".toml"), "-q"], tmp_path)
    msg = " ".join(r.stderr.split())
    assert r.returncode == 2 and "too long" in msg and "rename" in msg and "Traceback" not in r.stderr, msg
