"""Bad input everywhere (issue 5): property-based tests with hypothesis.

Mutated model files (deleted keys and tables, wrong types, negative / zero / NaN / infinite /
huge numbers, bad formulas, unknown keys, empty lists and strings, broken TOML) and corrupted
mesh files (through a ``type = "file"`` model) go through ``layershell check`` and a short
``layershell run`` (1 load step on a tiny mesh), in-process with typer's CliRunner. Every case
must end with exit code 0, 1 (the documented non-convergence: "the solution failed") or 2 with
a one-paragraph ``error:`` message — never an uncaught exception, a traceback, or the CLI's
last-line-of-defence messages for unexpected errors ("internal error", "could not be built").

The default runs are short and reproducible (``derandomize``); for a longer search set
``LAYERSHELL_FUZZ_EXAMPLES=1000`` (and ``LAYERSHELL_FUZZ_RANDOM=1`` for new random examples).
"""
from __future__ import annotations

import copy
import math
import os
import tomllib
import traceback
import warnings
from pathlib import Path

import meshio
import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from test_cli import dumps  # the small TOML writer of the CLI tests
from typer.testing import CliRunner

from layershell.cli import app
from layershell.mesh import rectangle

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = ROOT / "examples"
BASES = ("cantilever_thick.toml", "ring.toml", "curved_beam_1layer.toml", "cantilever_plate_slip.toml",
         "pulloff.toml")
MESH_FILE = "mesh.msh"

#: messages of the CLI's last line of defence: reaching them means an input was not checked
UNEXPECTED = ("internal error", "could not be built", "could not be set up", "Traceback")

NUMBERS = [-1, 0, -0.0, 1e-300, -1e-300, 1e300, -1e300, 1.7e308, math.nan, math.inf, -math.inf, 10**20,
           -(10**20), 2**63, 2**31, 0.5, 3]
WRONG_TYPES = ["abc", "", [], [1.0, 2.0], ["x"], [[1]], {"a": 1}, {}, True, False]
FORMULAS = ["x +* 2", "__import__('os')", "log(x - 1e9)", "1/0", "x/0", "sqrt(-1 - x)", "x.__class__", "near(x",
            "y ** 1e6", "exp(1000*x)", "a + b", "near(x, 0) and", "lambda: 0", "[1, 2]", "'text'",
            "x if y else z", "9**9**9", "near(x, 0, 1, 2)", "max()", "x[0]", "f(x)", "1e999", "-x", "0*x",
            "nan", "inf", "x > 1e300", "(" * 200 + "x" + ")" * 200, "x" * 5000]
EDIT = st.sampled_from(NUMBERS) | st.sampled_from(WRONG_TYPES) | st.sampled_from(FORMULAS) | st.text(max_size=6)


def _tiny_mesh_file(folder: Path) -> None:
    """A 2 × 1 quad9 rectangle in Gmsh 2.2 ASCII with physical groups 'plate' and 'clamp'."""
    from layershell.io.build import boundary_edges

    m = rectangle(10.0, 1.0, 2, 1, normal="-z")
    be = boundary_edges(m)
    clamp = be[np.isclose(m.nodes[be][..., 0], 0).all(1)]
    mm = meshio.Mesh(m.nodes, [("quad9", m.elements), ("line3", clamp)],
                     cell_data={"gmsh:physical": [np.full(m.n_elements, 1), np.full(len(clamp), 2)],
                                "gmsh:geometrical": [np.full(m.n_elements, 1), np.full(len(clamp), 2)]},
                     field_data={"plate": np.array([1, 2]), "clamp": np.array([2, 1])})
    meshio.write(folder / MESH_FILE, mm, file_format="gmsh22", binary=False)


def _base(name: str) -> dict:
    return tomllib.loads((EXAMPLES / name).read_text(encoding="utf-8"))


def _file_base() -> dict:
    """The thick cantilever on the Gmsh mesh file, clamped through the physical group."""
    d = _base("cantilever_thick.toml")
    d["mesh"] = {"type": "file", "path": MESH_FILE}
    d["supports"][0] = {"type": "symmetry", "set": "clamp", "normal": [1, 0, 0]}
    return d


def _shrink(d: dict) -> dict:
    """Tiny mesh, d ≤ 1, one load step to λ = 0.5, no ParaView files or plots: a `run` of seconds at most."""
    mesh = d.get("mesh", {})
    for key in ("nx", "ny", "n_arc", "n_width", "n_meridian", "n_circ"):
        if isinstance(mesh.get(key), int):
            mesh[key] = min(mesh[key], 2)
    for layer in d.get("layers", []):
        layer["directors"] = min(layer.get("directors", 3), 1)
    for sup in d.get("supports", []):
        if isinstance(sup.get("directors"), list):
            sup["directors"] = [k for k in sup["directors"] if k <= 1]
    if d.get("interfaces"):
        d["delamination"] = {**d.get("delamination", {}), "max_resolves": 3}
    steps = d.setdefault("steps", {})
    steps.pop("factors", None)
    steps["n"] = 1
    steps["lambda_end"] = 0.5
    steps["max_iterations"] = min(int(steps.get("max_iterations", 25)), 12)
    steps["max_bisections"] = 1
    d["profiles"] = []
    d["output"] = {"vtu": False, "plots": False}
    return d


BASE_DATA = {**{n: _base(n) for n in BASES}, "file": _file_base()}
RUN_DATA = {n: _shrink(copy.deepcopy(d)) for n, d in BASE_DATA.items()}


def _locations(d, path=()) -> list[tuple]:
    """Every key path of the nested data (tables, arrays of tables and values)."""
    out = []
    items = d.items() if isinstance(d, dict) else enumerate(d) if isinstance(d, list) else ()
    for k, v in items:
        out.append(path + (k,))
        if isinstance(v, (dict, list)):
            out += _locations(v, path + (k,))
    return out


def _parent(d, path):
    for p in path[:-1]:
        d = d[p]
    return d


@st.composite
def model_texts(draw, bases: dict) -> tuple[str, str]:
    """(base name, model-file text) with 1-3 mutations of the data, or a broken text."""
    name = draw(st.sampled_from(sorted(bases)))
    data = copy.deepcopy(bases[name])
    for _ in range(draw(st.integers(1, 3))):
        locs = _locations(data)
        if not locs:
            break
        path = draw(st.sampled_from(locs))
        parent, key = _parent(data, path), path[-1]
        op = draw(st.sampled_from(["delete", "set", "typed", "typed", "typed", "unknown", "empty", "duplicate"]))
        value = parent[key]
        if op == "delete":
            del parent[key]
        elif op == "set":
            parent[key] = draw(EDIT)
        elif op == "typed":  # a value of the right type that may still be wrong: reaches the build and solver
            if isinstance(value, bool):
                parent[key] = not value
            elif isinstance(value, (int, float)):
                parent[key] = draw(st.sampled_from(NUMBERS) | st.floats(-1e3, 1e3) | st.integers(-3, 12))
            elif isinstance(value, str):
                parent[key] = draw(st.sampled_from(FORMULAS) | st.sampled_from(["x", "y", "z", "all", "none"]))
            elif isinstance(value, list) and value and all(isinstance(v, (int, float)) for v in value):
                parent[key] = [draw(st.sampled_from(NUMBERS) | st.floats(-10, 10)) for _ in value]
        elif op == "unknown" and isinstance(parent[key], dict):
            parent[key][draw(st.sampled_from(["bogus", "thicknes", "type", "nx", "E"]))] = draw(EDIT)
        elif op == "empty":
            v = parent[key]
            parent[key] = [] if isinstance(v, list) else {} if isinstance(v, dict) else ""
        elif op == "duplicate" and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[key]))
    text = dumps(data)
    edit = draw(st.sampled_from(["none"] * 8 + ["truncate", "garbage"]))
    if edit == "truncate":
        text = text[: draw(st.integers(0, len(text)))]
    elif edit == "garbage":
        i = draw(st.integers(0, len(text)))
        text = text[:i] + draw(st.text(min_size=1, max_size=5)) + text[i:]
    return name, text


def _invoke(args: list[str], cwd: Path):
    """The CLI in-process; Python warnings (which the console script prints to stderr before the
    message) are kept in ``result.warnings``."""
    cwd0 = os.getcwd()
    os.chdir(cwd)
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            res = CliRunner().invoke(app, args, env={"LAYERSHELL_TRACEBACK": None, "NO_COLOR": "1"})
    finally:
        os.chdir(cwd0)
    res.warnings = [f"{w.category.__name__}: {w.message} ({w.filename}:{w.lineno})" for w in caught
                    if not issubclass(w.category, ResourceWarning)]
    return res


def _assert_clean(res, allowed: tuple[int, ...], text: str) -> None:
    """Exit code in ``allowed``; a failure is one ``error:`` paragraph that is no crash report."""
    info = f"--- model file:\n{text}\n--- exit code {res.exit_code}\n--- stderr:\n{res.stderr}"
    if res.exception is not None and not isinstance(res.exception, SystemExit):
        info += "\n--- uncaught:\n" + "".join(traceback.format_exception(res.exception))
        raise AssertionError(f"uncaught exception\n{info}")
    assert res.exit_code in allowed, info
    if res.exit_code == 0:
        return
    msg = res.stderr.strip()
    assert not res.warnings, f"warnings would precede the message: {res.warnings}\n{info}"
    assert msg.startswith("error:") and msg.count("error:") == 1, info
    assert all(line.strip() for line in msg.splitlines()), f"not one paragraph\n{info}"
    assert not any(u in msg for u in UNEXPECTED), f"an unexpected error reached the last line of defence\n{info}"
    if res.exit_code == 1:
        assert "the solution failed" in msg, info


def _fuzz_settings(default: int):
    return settings(max_examples=int(os.environ.get("LAYERSHELL_FUZZ_EXAMPLES", default)), deadline=None,
                    derandomize=not os.environ.get("LAYERSHELL_FUZZ_RANDOM"), database=None,
                    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                           HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def folder(tmp_path_factory) -> Path:
    d = tmp_path_factory.mktemp("fuzz")
    _tiny_mesh_file(d)
    return d


@_fuzz_settings(80)
@given(case=model_texts(BASE_DATA))
def test_check_never_crashes(folder, case):
    """`layershell check` on mutated model files: exit code 0 or 2, never a crash."""
    name, text = case
    (folder / "model.toml").write_text(text, encoding="utf-8")
    _assert_clean(_invoke(["check", "model.toml"], folder), (0, 2), text)


@_fuzz_settings(25)
@given(case=model_texts(RUN_DATA))
def test_short_run_never_crashes(folder, case):
    """`layershell run` (1 step, tiny mesh) on mutated model files: exit code 0, 1 or 2."""
    name, text = case
    (folder / "model.toml").write_text(text, encoding="utf-8")
    _assert_clean(_invoke(["run", "model.toml", "--out", "out", "--no-vtu", "--quiet"], folder), (0, 1, 2), text)


@_fuzz_settings(40)
@given(data=st.data())
def test_corrupted_mesh_files(folder, data):
    """A Gmsh mesh file truncated, with bytes replaced or lines dropped: `check` and `run` end
    with 0, 1 or 2 and a clear message."""
    good = (folder / MESH_FILE).read_bytes()
    lines = good.split(b"\n")
    kind = data.draw(st.sampled_from(["truncate", "replace", "drop_line", "swap_number"]))
    if kind == "truncate":
        bad = good[: data.draw(st.integers(0, len(good) - 1))]
    elif kind == "replace":
        i = data.draw(st.integers(0, len(good) - 1))
        bad = good[:i] + data.draw(st.binary(min_size=1, max_size=4)) + good[i + 1:]
    elif kind == "drop_line":
        i = data.draw(st.integers(0, len(lines) - 1))
        bad = b"\n".join(lines[:i] + lines[i + 1:])
    else:
        i = data.draw(st.integers(0, len(lines) - 1))
        words = lines[i].split(b" ")
        j = data.draw(st.integers(0, len(words) - 1))
        words[j] = data.draw(st.sampled_from([b"-1", b"0", b"999999", b"nan", b"1e308", b"x", b""]))
        lines = lines[:i] + [b" ".join(words)] + lines[i + 1:]
        bad = b"\n".join(lines)
    sub = folder / "corrupt"
    sub.mkdir(exist_ok=True)
    (sub / MESH_FILE).write_bytes(bad)
    text = dumps(RUN_DATA["file"])
    (sub / "model.toml").write_text(text, encoding="utf-8")
    info = f"{kind} mesh file:\n{bad[:3000]!r}\n{text}"
    _assert_clean(_invoke(["check", "model.toml"], sub), (0, 2), info)
    _assert_clean(_invoke(["run", "model.toml", "--out", "out", "--no-vtu", "--quiet"], sub), (0, 1, 2), info)


def test_unmutated_bases_pass(folder):
    """The bases themselves are good input (so the mutations above are what fails)."""
    for name, data in RUN_DATA.items():
        text = dumps(data)
        (folder / "model.toml").write_text(text, encoding="utf-8")
        res = _invoke(["check", "model.toml"], folder)
        assert res.exit_code == 0, (name, res.stderr)
    text = dumps(RUN_DATA["file"])
    (folder / "model.toml").write_text(text, encoding="utf-8")
    res = _invoke(["run", "model.toml", "--out", "out", "--no-vtu", "--quiet"], folder)
    assert res.exit_code == 0, res.stderr


# ------------------------------------------------------------------ cases the fuzzing found
def _edit(base: str, path: tuple, value):
    data = copy.deepcopy(BASE_DATA[base])
    target = data
    for p in path[:-1]:
        target = target[p]
    target[path[-1]] = value
    return data


FOUND = {  # (base, key path, value, text the message must contain)
    "huge_mesh": ("cantilever_thick.toml", ("mesh", "nx"), 10**20, "'mesh': nx × ny"),
    "mesh_too_big_for_memory": ("cantilever_thick.toml", ("mesh", "nx"), 2**31, "at most"),
    "huge_step_count": ("cantilever_thick.toml", ("steps", "n"), 2**31, "'steps.n'"),
    "huge_iterations": ("cantilever_thick.toml", ("steps", "max_iterations"), 10**20, "'steps.max_iterations'"),
    "infinite_probe_samples": ("ring.toml", ("probes", 2, "theta3"), [0.0, 1.0, math.inf], "'probes[2].theta3'"),
    "nan_probe_height": ("cantilever_thick.toml", ("probes", 0, "theta3"), math.nan, "'probes[0].theta3'"),
    "far_support_point": ("file", ("supports", 2, "point"), [2.4, -1e300, 0.0], None),  # ok: nearest node, no warning
    "infinite_support_point": ("cantilever_thick.toml", ("supports", 2, "point"), [0.0, -math.inf, 0.0],
                               "'supports[2]': point[1] must be a finite number"),
    "huge_direction": ("curved_beam_1layer.toml", ("loads", 0, "direction"), [-1e300, 1e-300, 0.0], None),
    "infinite_direction": ("cantilever_thick.toml", ("loads", 0, "direction"), [0.0, 0.0, -math.inf],
                           "'loads[0]': direction[2] must be a finite number"),
    "nan_probe_point": ("ring.toml", ("probes", 1, "point"), [-1.0, -1.0, math.nan], "'probes[1]': point[2] must be a finite number"),
    "nan_lambda_end": ("cantilever_thick.toml", ("steps", "lambda_end"), math.nan, "'steps.lambda_end'"),
    "vanishing_thickness": ("cantilever_plate_slip.toml", ("layers", 1, "thickness"), 1e-300,
                            "'layers[1].thickness'"),
    "infinite_thickness_formula": ("cantilever_thick.toml", ("layers", 0, "thickness"), "1e999 + x",
                                   "'layers[0].thickness'"),
}


@pytest.mark.parametrize("name", list(FOUND))
def test_cases_found_by_fuzzing(folder, name):
    """Inputs that used to end in a crash report (MemoryError, OverflowError, meshio's sys.exit),
    a misleading message or numpy warnings: now 0 with no warnings, or 2 naming the field."""
    base, path, value, expect = FOUND[name]
    text = dumps(_edit(base, path, value))
    (folder / "model.toml").write_text(text, encoding="utf-8")
    res = _invoke(["check", "model.toml"], folder)
    _assert_clean(res, (0,) if expect is None else (2,), text)
    assert not res.warnings, res.warnings
    if expect is not None:
        assert expect in " ".join(res.stderr.split()), res.stderr


def test_unreadable_mesh_file_is_bad_input(folder):
    """meshio prints its read errors and calls sys.exit(1) on a file it cannot parse: the message
    is one paragraph naming 'mesh.path' (with meshio's reason), exit code 2."""
    sub = folder / "unreadable"
    sub.mkdir(exist_ok=True)
    (sub / MESH_FILE).write_bytes((folder / MESH_FILE).read_bytes()[:1])
    text = dumps(RUN_DATA["file"])
    (sub / "model.toml").write_text(text, encoding="utf-8")
    res = _invoke(["check", "model.toml"], sub)
    _assert_clean(res, (2,), text)
    msg = " ".join(res.stderr.split())
    assert "'mesh.path'" in msg and "Couldn't read" in msg and res.stdout == "", msg
