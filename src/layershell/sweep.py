"""Parameter studies: model-file values addressed by dotted paths, variants run in parallel.

``layershell sweep MODEL.toml --set interfaces.0.tau_max=1.0,1.2 --set steps.n=10,20`` runs the
Cartesian product of the values, each variant into its own subfolder, and tabulates the final
probes in ``sweep.csv``. The paths address the parsed TOML document (tables by key, arrays of
tables by index), so every variant goes through the same schema validation and model build as
``layershell run``; a bad path or value is an :class:`~layershell.io.build.InputError` naming it.

This module imports only the standard library at the top: worker processes set their thread
limits before NumPy is loaded (see :func:`_init_worker`).
"""
from __future__ import annotations

import copy
import itertools
import math
import os
import tomllib
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

THREAD_VARS = ("OMP_NUM_THREADS", "MKL_NUM_THREADS", "OPENBLAS_NUM_THREADS", "NUMBA_NUM_THREADS")


def _input_error(msg: str) -> Exception:
    from .io.build import InputError

    return InputError(msg)


# ------------------------------------------------------------------ dotted paths and values
def split_top_level(text: str, sep: str = ",") -> list[str]:
    """Split ``text`` at ``sep`` outside brackets, braces and quotes: ``"[1,2],3"`` → ``["[1,2]", "3"]``."""
    parts, depth, quote, cur = [], 0, "", []
    for ch in text:
        if quote:
            quote = "" if ch == quote else quote
        elif ch in "\"'":
            quote = ch
        elif ch in "[{":
            depth += 1
        elif ch in "]}":
            depth -= 1
        elif ch == sep and depth == 0:
            parts.append("".join(cur))
            cur = []
            continue
        cur.append(ch)
    parts.append("".join(cur))
    return [p.strip() for p in parts]


def parse_value(text: str) -> Any:
    """A command-line value as a TOML value (number, bool, string, array, inline table, ``inf``);
    anything that is not valid TOML is taken as a bare string (``explicit`` → ``"explicit"``)."""
    text = text.strip()
    try:
        return tomllib.loads(f"v = {text}")["v"]
    except tomllib.TOMLDecodeError:
        return text


def parse_assignment(arg: str, option: str = "--set") -> tuple[str, list[Any]]:
    """``"key=v1,v2"`` → ``(key, [v1, v2])``."""
    key, eq, values = arg.partition("=")
    key = key.strip()
    if not eq or not key:
        raise _input_error(f"{option} '{arg}': write KEY=VALUE[,VALUE...] with a dotted model-file path as KEY, "
                           "e.g. --set interfaces.0.tau_max=1.0,1.2")
    items = split_top_level(values)
    if any(v == "" for v in items):
        raise _input_error(f"{option} '{arg}': empty value in the list; separate the values with single commas, "
                           "e.g. --set steps.n=10,20")
    return key, [parse_value(v) for v in items]


def _segments(key: str) -> list[str]:
    segs = key.split(".")
    if any(s == "" for s in segs):
        raise _input_error(f"'{key}': empty part in the dotted path; write e.g. interfaces.0.tau_max")
    return segs


def get_path(data: dict, key: str) -> Any:
    """The value at dotted ``key`` (list entries by index); InputError naming the key if absent."""
    cur: Any = data
    done: list[str] = []
    for s in _segments(key):
        cur = _child(cur, s, key, done)
        done.append(s)
    return cur


def _child(cur: Any, s: str, key: str, done: list[str]) -> Any:
    where = f"'{'.'.join(done)}'" if done else "the model file"
    if isinstance(cur, list):
        try:
            i = int(s)
        except ValueError:
            raise _input_error(f"'{key}': {where} is an array of {len(cur)} table(s); address an entry by its "
                               f"index 0..{len(cur) - 1}, e.g. {'.'.join(done + ['0'])}") from None
        if not -len(cur) <= i < len(cur):
            raise _input_error(f"'{key}': {where} has {len(cur)} entr{'y' if len(cur) == 1 else 'ies'} "
                               f"(indices 0..{len(cur) - 1}), so index {i} does not exist")
        return cur[i]
    if isinstance(cur, dict):
        if s not in cur:
            import difflib

            close = difflib.get_close_matches(s, list(cur), n=1, cutoff=0.6)
            hint = f"did you mean '{close[0]}'? " if close else ""
            raise _input_error(f"'{key}': {where} has no key '{s}'; {hint}keys there: {sorted(cur)}")
        return cur[s]
    raise _input_error(f"'{key}': {where} is a value ({cur!r}), not a table; shorten the path")


def set_path(data: dict, key: str, value: Any) -> None:
    """Set the value at dotted ``key`` in place.

    Every part of the path but the last must exist; the last may be a key the file leaves at its
    default (``interfaces.0.gT_mu``), and a missing top-level section is created (``steps.n``).
    Keys unknown to the schema are rejected later by the validation."""
    segs = _segments(key)
    cur: Any = data
    for j, s in enumerate(segs[:-1]):
        if j == 0 and len(segs) == 2 and isinstance(cur, dict) and s not in cur:
            cur[s] = {}
        cur = _child(cur, s, key, segs[:j])
    last = segs[-1]
    if isinstance(cur, list):
        _child(cur, last, key, segs[:-1])  # index check
        cur[int(last)] = value
    elif isinstance(cur, dict):
        cur[last] = value
    else:
        raise _input_error(f"'{key}': '{'.'.join(segs[:-1])}' is a value ({cur!r}), not a table; shorten the path")


# ------------------------------------------------------------------ building variants
def read_model(path: str | Path) -> dict:
    """The model file as a TOML document (dict); InputError for a missing or malformed file."""
    path = Path(path)
    if not path.is_file():
        raise _input_error(f"model file '{path}' does not exist; check the path (examples are in examples/)")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8").removeprefix("\ufeff"))  # BOM: not TOML
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise _input_error(f"{path}: not valid TOML/UTF-8: {exc}; run `layershell check {path}`") from None


def build_spec(data: dict, base: Path, name: str):
    """Validate a TOML document with the model-file schema and build it (as ``layershell run`` does)."""
    from pydantic import ValidationError

    from .io import schema
    from .io.build import InputError, _validation_message, build

    try:
        mf = schema.ModelFile.model_validate(data)
    except ValidationError as exc:
        raise InputError(f"{name}: " + _validation_message(exc)) from None
    try:
        spec = build(mf, Path(base))
    except InputError as exc:
        raise InputError(f"{name}: {exc}") from None
    return spec


def with_values(data: dict, values: dict[str, Any]) -> dict:
    """A deep copy of ``data`` with the dotted-path ``values`` set."""
    d = copy.deepcopy(data)
    for k, v in values.items():
        set_path(d, k, v)
    return d


def _fmt(v: Any) -> str:
    return repr(v) if isinstance(v, float) else str(v)


def describe(values: dict[str, Any]) -> str:
    return ", ".join(f"{k}={_fmt(v)}" for k, v in values.items())


#: most variants of one sweep: every variant is validated and built before the first is solved
#: (about 2 ms each for a small model), and each writes its own results folder
MAX_VARIANTS = 10_000


def variants(data: dict, sets: list[tuple[str, list[Any]]]) -> list[dict[str, Any]]:
    """The Cartesian product of the ``--set`` lists as ``[{key: value}, ...]`` (paths checked)."""
    keys = [k for k, _ in sets]
    dup = {k for k in keys if keys.count(k) > 1}
    if dup:
        raise _input_error(f"--set: the key(s) {sorted(dup)} are given more than once; list all values of a key "
                           "in one --set KEY=V1,V2")
    count = math.prod(len(v) for _, v in sets)
    if count > MAX_VARIANTS:
        sizes = " × ".join(f"{len(v)} ({k})" for k, v in sets)
        raise _input_error(f"--set: the product of the value lists gives {count:,} variants ({sizes}), more than "
                           f"the {MAX_VARIANTS:,} one sweep runs (each is validated, solved and written to its own "
                           "folder); use fewer values per --set, or split the study into several sweeps with --out")
    probe = copy.deepcopy(data)
    for k, vals in sets:
        set_path(probe, k, vals[0])  # InputError naming the key when a parent does not exist
    return [dict(zip(keys, combo)) for combo in itertools.product(*[v for _, v in sets])]


# ------------------------------------------------------------------ running
@dataclass
class SweepResult:
    header: list[str]
    rows: list[list]
    keys: list[str]
    probes: list[str]
    out: Path
    failed: int = 0
    records: list[dict] = field(default_factory=list)


def _init_worker() -> None:
    """One BLAS/OpenMP thread per worker process: the parallelism is across variants."""
    for v in THREAD_VARS:
        os.environ[v] = "1"


def run_variant(index: int, values: dict[str, Any], data: dict, base: str, out: str, vtu: bool,
                model_file: str = "") -> dict:
    """Build and run one variant into ``out``; never raises (a failure is a record with ``error``)."""
    import time
    import traceback

    t0 = time.perf_counter()
    rec: dict[str, Any] = {"index": index, "values": values, "folder": out, "converged": False, "probes": {},
                           "load_factor": None, "steps": 0, "first_delamination_load_factor": None, "error": ""}
    try:
        from .io.output import write_json
        from .runner import run

        Path(out).mkdir(parents=True, exist_ok=True)
        write_json(Path(out) / "variant.json", {"model_file": model_file, "variant": index, "values": values,
                                                "model": data})
        spec = build_spec(data, Path(base), f"variant {index} ({describe(values)})")
        res = run(spec, Path(out), write_vtu=vtu, overwrite=True)
        s = res.summary
        rec.update(converged=bool(res.converged), probes=dict(s.get("probes", {})), steps=len(s.get("steps", [])),
                   load_factor=s["steps"][-1]["load_factor"] if s.get("steps") else None,
                   first_delamination_load_factor=s.get("first_delamination_load_factor"),
                   error="" if res.converged else res.message)
    except Exception as exc:  # a failed variant is a row, not a crash
        rec["error"] = f"{type(exc).__name__}: {exc}"
        if os.environ.get("LAYERSHELL_TRACEBACK", "") not in ("", "0"):
            rec["error"] += "\n" + traceback.format_exc()
    rec["wall_seconds"] = round(time.perf_counter() - t0, 3)
    return rec


def sweep(model: str | Path, sets: list[tuple[str, list[Any]]], out: str | Path, jobs: int | None = None,
          vtu: bool = False, progress: Callable[[dict], None] | None = None,
          checking: Callable[[int, int], None] | None = None) -> SweepResult:
    """Run every combination of ``sets`` (``[(dotted key, [values])]``) and write ``out/sweep.csv``.

    All variants are validated and built before any is solved, so bad input fails fast
    (InputError naming the key and the variant). Variants run in ``jobs`` processes (default:
    the number of CPU cores); each writes its results into ``out/vNNN/``. ``checking(i, n)`` is
    called after each of the n variants is validated (progress of a long validation)."""
    from .io.output import write_csv, write_json

    model = Path(model)
    data = read_model(model)
    if not sets:
        raise _input_error("give at least one --set KEY=V1,V2 (a dotted model-file path and its values)")
    combos = variants(data, sets)
    docs = []
    for i, vals in enumerate(combos):
        d = with_values(data, vals)
        build_spec(d, model.parent, f"{model}: variant {i} (--set {describe(vals)})")
        docs.append(d)
        if checking:
            checking(i + 1, len(combos))
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    keys = [k for k, _ in sets]
    width = max(3, len(str(len(combos) - 1)))
    folders = [out / f"v{i:0{width}d}" for i in range(len(combos))]
    jobs = max(1, min(jobs or os.cpu_count() or 1, len(combos)))
    records: list[dict] = [{}] * len(combos)
    args = [(i, combos[i], docs[i], str(model.parent.resolve()), str(folders[i]), vtu, str(model))
            for i in range(len(combos))]
    if jobs == 1:
        for a in args:
            records[a[0]] = run_variant(*a)
            if progress:
                progress(records[a[0]])
    else:
        import multiprocessing

        with ProcessPoolExecutor(max_workers=jobs, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=_init_worker) as pool:
            futures = {pool.submit(run_variant, *a): a for a in args}
            from concurrent.futures import as_completed

            for fut in as_completed(futures):
                a = futures[fut]
                try:
                    rec = fut.result()
                except Exception as exc:  # the worker process died (memory, signal)
                    rec = {"index": a[0], "values": a[1], "folder": a[4], "converged": False, "probes": {},
                           "load_factor": None, "steps": 0, "first_delamination_load_factor": None,
                           "error": f"worker process failed: {type(exc).__name__}: {exc}", "wall_seconds": None}
                records[a[0]] = rec
                if progress:
                    progress(rec)
    probes = list(dict.fromkeys(p for r in records for p in r["probes"]))
    header = (["variant"] + keys + ["converged", "steps", "load_factor", "first_delamination_load_factor"]
              + probes + ["wall_seconds", "folder", "error"])
    rows = []
    for r, f in zip(records, folders):
        rows.append([f.name] + [_csv_value(r["values"][k]) for k in keys]
                    + [r["converged"], r["steps"], _csv_value(r["load_factor"]),
                       _csv_value(r["first_delamination_load_factor"])]
                    + [_csv_value(r["probes"].get(p)) for p in probes]
                    + [_csv_value(r.get("wall_seconds")), f.name, " ".join(str(r["error"]).split())])
    write_csv(out / "sweep.csv", header, rows)
    write_json(out / "sweep.json", {"model": str(model), "sets": [{"key": k, "values": v} for k, v in sets],
                                    "variants": records})
    return SweepResult(header, rows, keys, probes, out, sum(not r["converged"] for r in records), records)


def _csv_value(v: Any) -> Any:
    if v is None:
        return ""
    if isinstance(v, (list, dict)):
        import json

        return json.dumps(v)
    return v
