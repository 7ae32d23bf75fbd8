"""The command line on bad input: one paragraph naming the field and the fix, exit code 2, no traceback.

Every case copies an example from ``examples/``, mutates it (through :mod:`tomllib` and the small
TOML writer below, or as text) and runs the installed ``layershell`` console script in a
subprocess. The subprocesses are started together (one module fixture), because each one spends
most of its ~1 s importing NumPy/SciPy; the tests then only inspect the results. To keep the file
fast, the extra cases beyond the issue's list (``inprocess=True``) call ``layershell.cli.app``
through typer's CliRunner instead, with the same checks.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import pytest

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
GOOD = ("cantilever_thick.toml", "ring.toml", "curved_beam_1layer.toml")


def _command() -> list[str]:
    exe = Path(sys.executable).parent / ("layershell.exe" if os.name == "nt" else "layershell")
    if exe.is_file():
        return [str(exe)]
    found = shutil.which("layershell")
    if found:
        return [found]
    return [sys.executable, "-m", "layershell.cli"]


# ------------------------------------------------------------------ a tiny TOML writer
_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def _key(k: str) -> str:
    return k if _BARE.match(k) else json.dumps(k)


def _value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # JSON string escapes are valid TOML basic-string escapes
    if isinstance(v, list):
        return "[" + ", ".join(_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{_key(k)} = {_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(f"cannot write {type(v).__name__} to TOML")


def _is_tables(v) -> bool:
    return isinstance(v, list) and bool(v) and all(isinstance(x, dict) for x in v)


def _emit(lines: list[str], path: list[str], table: dict) -> None:
    for k, v in table.items():
        if not isinstance(v, dict) and not _is_tables(v):
            lines.append(f"{_key(k)} = {_value(v)}")
    for k, v in table.items():
        sub = path + [_key(k)]
        if isinstance(v, dict):
            lines += ["", f"[{'.'.join(sub)}]"]
            _emit(lines, sub, v)
        elif _is_tables(v):
            for item in v:
                lines += ["", f"[[{'.'.join(sub)}]]"]
                _emit(lines, sub, item)


def dumps(data: dict) -> str:
    lines: list[str] = []
    _emit(lines, [], data)
    return "\n".join(lines).lstrip("\n") + "\n"


def test_toml_writer_round_trips_the_examples():
    for name in GOOD:
        data = tomllib.loads((EXAMPLES / name).read_text(encoding="utf-8"))
        assert tomllib.loads(dumps(data)) == data


# ------------------------------------------------------------------ the cases
@dataclass
class Case:
    example: str | None  # None: no model file is written (the path does not exist)
    mutate: Callable[[dict], None] | None = None
    text: Callable[[str], str] | None = None  # textual edit instead of ``mutate``
    command: str = "check"
    fields: tuple[str, ...] = ()  # must all appear in the message
    codes: tuple[int, ...] = (2,)
    inprocess: bool = False  # CliRunner instead of a subprocess (same checks, much faster)


def _set(path: str, value):
    """Mutation that sets a dotted path such as ``layers.0.thickness`` (integers index lists)."""
    def mutate(d):
        *head, last = path.split(".")
        for p in head:
            d = d[int(p)] if isinstance(d, list) else d[p]
        if isinstance(d, list):
            d[int(last)] = value
        else:
            d[last] = value
    return mutate


def _delete(path: str):
    def mutate(d):
        *head, last = path.split(".")
        for p in head:
            d = d[int(p)] if isinstance(d, list) else d[p]
        del d[int(last) if isinstance(d, list) else last]
    return mutate


def _all(*mutations):
    def mutate(d):
        for m in mutations:
            m(d)
    return mutate


_BAD_ORTHOTROPIC = {"type": "orthotropic", "E1": 100.0, "E2": 10.0, "E3": 10.0, "G12": 5.0, "G23": 4.0,
                    "G31": 5.0, "nu12": 3.5, "nu23": 0.3, "nu13": 0.3}

# The cantilever without its vertical support: free to translate in z (and to rotate), loaded in z.
# Few iterations and no bisections keep the failing solve short.
_FREE_IN_Z = _all(_delete("supports.1"), _set("steps.max_iterations", 3), _set("steps.max_bisections", 0))

CASES: dict[str, Case] = {
    # the four cases of the issue
    "negative_thickness": Case("cantilever_thick.toml", _set("layers.0.thickness", -1.0),
                               fields=("layers[0].thickness", "positive")),
    "unknown_key": Case("cantilever_thick.toml", _set("layers.0.thicknes", 1.0),
                        fields=("layers[0].thicknes", "thickness")),
    "unknown_key_in_mesh": Case("cantilever_thick.toml", _set("mesh.n_x", 5), fields=("mesh.n_x", "nx"), inprocess=True),
    "unknown_section": Case("cantilever_thick.toml", _set("solver", {"tolerance": 1e-8}), fields=("solver",), inprocess=True),
    "not_positive_definite": Case("cantilever_thick.toml", _set("materials.mat", dict(_BAD_ORTHOTROPIC)),
                                  fields=("materials.mat", "positive definite")),
    "support_selects_no_node": Case("cantilever_thick.toml", _set("supports.1.where", "near(x, 99)"),
                                    fields=("supports[1]", "near(x, 99)", "selects no node")),
    # thickness
    "thickness_formula_negative": Case("cantilever_thick.toml", _set("layers.0.thickness", "x - 5"),
                                       fields=("layers[0].thickness", "positive")),
    "thickness_formula_bad_variable": Case("cantilever_thick.toml", _set("layers.0.thickness", "1 + t"),
                                           fields=("layers[0].thickness", "'t'"), inprocess=True),
    # names
    "unknown_material": Case("cantilever_thick.toml", _set("layers.0.material", "steel"),
                             fields=("layers[0].material", "steel", "mat")),
    "unknown_layer_in_support": Case("cantilever_thick.toml", _set("supports.1.layer", "core"),
                                     fields=("supports[1].layer", "core", "beam")),
    "unknown_layer_in_probe": Case("cantilever_thick.toml", _set("probes.0.layer", "core"),
                                   fields=("probes[0].layer", "core", "beam"), inprocess=True),
    # formulas
    "formula_import": Case("cantilever_thick.toml", _set("supports.0.where", "__import__('os')"),
                           fields=("supports[0].where", "__import__")),
    "formula_attribute": Case("cantilever_thick.toml", _set("supports.0.where", "x.__class__"),
                              fields=("supports[0].where", "not allowed"), inprocess=True),
    "formula_syntax": Case("cantilever_thick.toml", _set("supports.0.where", "near(x, 0"),
                           fields=("supports[0].where", "syntax")),
    "formula_in_load": Case("ring.toml", _set("loads.0.magnitude", "1 +* x"), fields=("loads[0].magnitude",), inprocess=True),
    "load_not_finite": Case("ring.toml", _set("loads.0.magnitude", "log(x - 100)"),
                            fields=("loads[0].magnitude", "finite"), inprocess=True),
    # types and structure
    "wrong_type_number": Case("cantilever_thick.toml", _set("mesh.lx", "ten"), fields=("mesh.lx", "number")),
    "wrong_type_material": Case("cantilever_thick.toml", _set("materials.mat.E", "big"),
                                fields=("materials.mat.E",), inprocess=True),
    "wrong_type_list": Case("cantilever_thick.toml", _set("layers.0.thickness", [1.0, 2.0]),
                            fields=("layers[0].thickness",), inprocess=True),
    "missing_mesh": Case("cantilever_thick.toml", _delete("mesh"), fields=("mesh", "missing")),
    "missing_key": Case("cantilever_thick.toml", _delete("mesh.lx"), fields=("mesh.lx", "missing"), inprocess=True),
    "missing_mesh_type": Case("cantilever_thick.toml", _delete("mesh.type"), fields=("mesh.type", "rectangle"), inprocess=True),
    "unknown_mesh_type": Case("cantilever_thick.toml", _set("mesh.type", "square"),
                              fields=("mesh.type", "square", "rectangle"), inprocess=True),
    "unknown_support_type": Case("cantilever_thick.toml", _set("supports.1.type", "clamp"),
                                 fields=("supports[1].type", "clamp", "fix"), inprocess=True),
    "toml_syntax": Case("cantilever_thick.toml", text=lambda t: t.replace("nx = 5", "nx = = 5"),
                        fields=("TOML", "line")),
    "nonexistent_file": Case(None, fields=("does not exist",)),
    "nonexistent_file_run": Case(None, command="run", fields=("does not exist",), inprocess=True),
    "mesh_file_missing": Case("cantilever_thick.toml", _set("mesh", {"type": "file", "path": "nowhere.msh"}),
                              fields=("mesh.path", "nowhere.msh"), inprocess=True),
    # ranges
    "directors_out_of_range": Case("cantilever_thick.toml", _set("layers.0.directors", 5),
                                   fields=("layers[0].directors", "4")),
    "support_director_out_of_range": Case("cantilever_thick.toml", _set("supports.1.directors", [4]),
                                          fields=("supports[1].directors",), inprocess=True),
    "poisson_half": Case("cantilever_thick.toml", _set("materials.mat.nu", 0.5), fields=("materials.mat", "nu")),
    "negative_modulus": Case("cantilever_thick.toml", _set("materials.mat.E", -1.0),
                             fields=("materials.mat", "E"), inprocess=True),
    "probe_component": Case("cantilever_thick.toml", _set("probes.0.component", "w"),
                            fields=("probes[0].component", "'w'", "magnitude")),
    "probe_point_off_surface": Case("ring.toml", _set("probes.0.point", [0.0, 9.0, 1.5]),
                                    fields=("probes[0].point",), inprocess=True),
    "edge_load_no_edge": Case("cantilever_thick.toml", _set("loads.0.where", "near(x, 10) and near(y, 0)"),
                              fields=("loads[0]", "edge")),
    "edge_load_no_node": Case("cantilever_thick.toml", _set("loads.0.where", "x > 100"),
                              fields=("loads[0]", "selects no node"), inprocess=True),
    # supports that leave rigid-body motion free
    "no_supports": Case("cantilever_thick.toml", _delete("supports"), fields=("supports", "rigid-body")),
    "no_supports_run": Case("cantilever_thick.toml", _delete("supports"), command="run",
                            fields=("supports", "rigid-body"), inprocess=True),
    "rigid_body_mode_run": Case("cantilever_thick.toml", _FREE_IN_Z, command="run",
                                fields=("supports", "rigid-body"), codes=(1, 2)),
    # bad input also stops `run` before anything is solved
    "negative_thickness_run": Case("cantilever_thick.toml", _set("layers.0.thickness", -1.0), command="run",
                                   fields=("layers[0].thickness",)),
}


@dataclass
class Outcome:
    args: list[str]
    returncode: int
    stdout: str
    stderr: str
    out_dir: Path


def _prepare(name: str, case: Case, base: Path) -> list[str]:
    folder = base / name
    folder.mkdir()
    model = folder / "model.toml"
    if case.example is not None:
        text = (EXAMPLES / case.example).read_text(encoding="utf-8")
        if case.mutate is not None:
            data = tomllib.loads(text)
            case.mutate(data)
            text = dumps(data)
        if case.text is not None:
            text = case.text(text)
        model.write_text(text, encoding="utf-8")
    args = [case.command, str(model)]
    if case.command == "run":
        args += ["--out", str(folder / "out"), "--no-vtu", "--quiet"]
    return args


def _run_inprocess(args: list[str], out_dir: Path) -> Outcome:
    from typer.testing import CliRunner

    from layershell.cli import app

    cwd = os.getcwd()
    os.chdir(out_dir)
    try:
        res = CliRunner().invoke(app, args, env={"LAYERSHELL_TRACEBACK": None, "NO_COLOR": "1"})
    finally:
        os.chdir(cwd)
    stderr = res.stderr
    if res.exception is not None and not isinstance(res.exception, SystemExit):  # would be a traceback
        import traceback

        stderr += "Traceback:\n" + "".join(traceback.format_exception(res.exception))
    return Outcome(args, res.exit_code, res.stdout, stderr, out_dir)


def _run(args: list[str], out_dir: Path) -> Outcome:
    env = dict(os.environ, NO_COLOR="1", COLUMNS="100", PYTHONIOENCODING="utf-8")
    env.pop("LAYERSHELL_TRACEBACK", None)
    p = subprocess.run(_command() + args, capture_output=True, text=True, encoding="utf-8", env=env,
                       cwd=out_dir, timeout=300)
    return Outcome(args, p.returncode, p.stdout, p.stderr, out_dir)


@pytest.fixture(scope="module")
def outcomes(tmp_path_factory) -> dict[str, Outcome]:
    base = tmp_path_factory.mktemp("cli")
    jobs = {name: _prepare(name, case, base) for name, case in CASES.items() if not case.inprocess}
    jobs.update({f"check_{g}": ["check", str(EXAMPLES / g)] for g in GOOD})
    good_out = base / "good_run"
    jobs["run_good"] = ["run", str(EXAMPLES / "cantilever_thick.toml"), "--out", str(good_out), "--no-vtu"]
    with ThreadPoolExecutor(max_workers=max(2, min(8, os.cpu_count() or 2))) as pool:
        futures = {name: pool.submit(_run, args, base) for name, args in jobs.items()}
        results = {name: f.result() for name, f in futures.items()}
    for name, case in CASES.items():
        if case.inprocess:
            results[name] = _run_inprocess(_prepare(name, case, base), base)
    return results


def _describe(o: Outcome) -> str:
    return f"layershell {' '.join(o.args)}\nexit code {o.returncode}\nstdout:\n{o.stdout}\nstderr:\n{o.stderr}"


@pytest.mark.parametrize("name", list(CASES))
def test_bad_input_gives_one_paragraph(outcomes, name):
    case, o = CASES[name], outcomes[name]
    info = _describe(o)
    assert o.returncode in case.codes, info
    assert "Traceback" not in o.stderr and "Traceback" not in o.stdout, info
    msg = o.stderr.strip()
    assert msg.startswith("error:"), info
    assert msg.count("error:") == 1, info
    lines = msg.splitlines()
    assert all(line.strip() for line in lines), f"the message is not one paragraph\n{info}"
    for field in case.fields:
        assert field in msg, f"{field!r} is not named\n{info}"


def test_message_names_the_model_file(outcomes):
    o = outcomes["negative_thickness"]
    assert "model.toml" in o.stderr, _describe(o)


def test_unknown_key_suggests_the_spelling(outcomes):
    o = outcomes["unknown_key"]
    assert "did you mean 'thickness'" in o.stderr, _describe(o)


@pytest.mark.parametrize("example", GOOD)
def test_check_accepts_the_examples(outcomes, example):
    o = outcomes[f"check_{example}"]
    assert o.returncode == 0, _describe(o)
    assert "OK" in o.stdout, _describe(o)
    assert o.stderr.strip() == "", _describe(o)


def test_run_good_example_writes_summary(outcomes):
    o = outcomes["run_good"]
    assert o.returncode == 0, _describe(o)
    summary = json.loads((o.out_dir / "good_run" / "summary.json").read_text(encoding="utf-8"))
    assert summary["converged"] is True
    assert "w_tip" in summary["probes"]
    assert not list((o.out_dir / "good_run").glob("*.vtu"))


def test_a_run_stopped_after_its_peak_names_the_peak_instead_of_the_support_hint():
    """A path-following run that stops on the branch after a peak of its load factor (the TRC
    slab by arc length on 8 × 6 stopped at 266.28 kN/m² after its peak of 327.12) gets advice
    that names the peak and its step and says that the steps up to there are equilibrium states,
    not the generic hint about supports and step sizes (which a structure that carried the peak
    does not need). A run whose last load factor is within 1 % of its largest (a load-controlled
    run that failed on its way up) keeps the generic hint."""
    from layershell.cli import POST_PEAK, _post_peak_cause

    def summary(lams):
        return {"steps": [{"step": i + 1, "load_factor": x} for i, x in enumerate(lams)]}

    said = _post_peak_cause(summary([100.0, 250.0, 327.12, 300.0, 266.28]))
    assert said is not None
    assert "327.12 at step 3" in said and "18.6% below it" in said and "equilibrium states" in said
    assert "supports" not in said
    assert _post_peak_cause(summary([100.0, 250.0, 327.12])) is None  # stopped on its way up
    assert _post_peak_cause(summary([100.0, 327.12, 327.12 * (1 - 0.5 * POST_PEAK)])) is None  # at the peak
    assert _post_peak_cause(summary([])) is None and _post_peak_cause({}) is None
    assert _post_peak_cause(summary([0.0, -1.0])) is None  # no positive peak


def test_help_texts_keep_model_file_section_names():
    """Section names in square brackets reach the help text as written (no markup eats them)."""
    from typer.testing import CliRunner

    from layershell.cli import app

    res = CliRunner().invoke(app, ["buckle", "--help"], env={"NO_COLOR": "1", "COLUMNS": "200"})
    assert res.exit_code == 0
    text = " ".join(res.stdout.split())
    assert "initially debonded zones of [[interfaces]]" in text
    assert "buckling_modes.npz (for [imperfection])" in text
