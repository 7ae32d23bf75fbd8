"""Restart files: the complete state after a converged load step.

``checkpoint.npz`` in the results folder is rewritten atomically (temporary file + rename) after
every converged step, so a run that is killed keeps a consistent restart point. It holds plain
NumPy arrays only (read with ``allow_pickle=False``):

* ``format_version``, ``model_hash`` (see :func:`model_hash`), ``load_factors`` (all targets);
* ``step``, ``load_factor`` and the full-space displacement ``u`` of the last converged step;
* ``itf/...``: the interface controller's state (bond flags, g_T^max, slip, gap, contact
  pressure, friction loads and return-mapping state, failure function, first failure), see
  :meth:`~layershell.solver.interface_state.InterfaceController.state`;
* ``summary`` (JSON text): the last probes, first delamination, restarts and wall time; the step
  records themselves are in ``steps.jsonl`` next to it (one line per converged step, appended by
  :class:`~layershell.recorder.Recorder`), so that the checkpoint's size does not grow with the
  number of steps. ``rows`` and ``pvd`` are empty (checkpoints written before steps.jsonl held
  the probes.csv rows and the ParaView series there, and the steps in ``summary``; they are
  still read);
* ``extra/...``: the debonded flags of the steps the zone maps may show (bounded, see
  :class:`~layershell.plots.ZoneHistory`) and, for path following, ``extra/path.*``: the whole
  :class:`~layershell.solver.path_state.PathState` (constraint, sizes, recent increments,
  stretches, rescue), so that a restarted run takes the same increments as an uninterrupted one.

A checkpoint holding NaN or infinite displacements is refused (:func:`load`).

``layershell run MODEL --restart DIR`` continues from it (:func:`layershell.runner.run`).
"""
from __future__ import annotations

import hashlib
import json
import os
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .io.output import atomic_write

# 2: the cohesive interfaces' fracture energy per point (CohesiveRun.fracture)
# 3: the stick anchors of a cohesive interface's friction belong to a stick penalty per point
#    (cohesive.stick_penalty)
FORMAT_VERSION = 3
FILENAME = "checkpoint.npz"


class CheckpointError(ValueError):
    """A restart file that is missing, unreadable or written for another model (exit code 2)."""


@dataclass
class Checkpoint:
    """State after converged step ``step`` (see the module docstring)."""

    step: int
    load_factor: float
    u: np.ndarray
    load_factors: np.ndarray
    model_hash: str
    interface_state: dict[str, np.ndarray] = field(default_factory=dict)
    summary: dict = field(default_factory=dict)
    rows: list = field(default_factory=list)
    pvd: dict[str, list] = field(default_factory=dict)
    extra: dict[str, np.ndarray] = field(default_factory=dict)  # e.g. the zone-map history of the figures
    format_version: int = FORMAT_VERSION


def model_hash(spec) -> str:
    """SHA-256 of what determines the solution: the validated model file without ``[output]``,
    ``model.title`` and ``model.units`` (comments and formatting do not matter either), and the
    mesh's node coordinates and connectivity (so an edited mesh file is detected too)."""
    src = spec.source.model_dump(mode="json", exclude={"output": True, "model": {"title", "units"}})
    for layer in src.get("layers", []):  # a layer without plies hashes as it did before plies existed
        if layer.get("plies") is None:
            layer.pop("plies", None)
    h = hashlib.sha256(json.dumps(src, sort_keys=True, default=str).encode())
    mesh = spec.model.mesh
    h.update(np.ascontiguousarray(mesh.nodes, dtype=np.float64).tobytes())
    h.update(np.ascontiguousarray(mesh.elements, dtype=np.int64).tobytes())
    return h.hexdigest()


def _jsonable(obj):
    """NumPy scalars and arrays inside nested dicts/lists as plain Python values."""
    if isinstance(obj, dict):
        return {str(k): _jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return obj.tolist()
    if isinstance(obj, np.generic):
        return obj.item()
    return obj


#: the summary entries a checkpoint carries to the restarted run: what the run found up to it
#: (the stabilisation, the relaxed jumps, the stability events and the solver's counters included -
#: a restart once dropped them). The step history lives in steps.jsonl (older checkpoints held it as "steps").
SUMMARY_KEYS = ("probes", "first_delamination_load_factor", "restarts", "wall_seconds", "warnings", "path_end",
                "stabilized", "relaxations", "active_set", "linear_solves", "energy_balance_warned",
                "peak_load_factor", "contact_moved_to_nodes", "stability", "settlements",
                "first_cracking_load_factor", "first_cracking_step", "first_yield_load_factor", "first_yield_step",
                "first_crushing_load_factor", "first_crushing_step", "first_rupture_load_factor",
                "first_rupture_step")


def capture(step: int, load_factor: float, u: np.ndarray, load_factors: np.ndarray, hash_: str,
            interface_state: dict[str, np.ndarray] | None, summary: dict, rows: list, pvd: dict,
            extra: dict[str, np.ndarray] | None = None) -> Checkpoint:
    """A :class:`Checkpoint` holding copies (later changes of the live state do not reach it)."""
    keep = {k: summary[k] for k in SUMMARY_KEYS if k in summary}
    return Checkpoint(int(step), float(load_factor), np.array(u, float, copy=True),
                      np.array(load_factors, float, copy=True), hash_,
                      {k: np.array(v, copy=True) for k, v in (interface_state or {}).items()},
                      json.loads(json.dumps(_jsonable(keep))), json.loads(json.dumps(_jsonable(rows))),
                      {k: [list(e) for e in v] for k, v in pvd.items()},
                      {k: np.array(v, copy=True) for k, v in (extra or {}).items()})


def save(path: Path, ck: Checkpoint, fsync: bool = True) -> None:
    """Write ``ck`` to ``path`` atomically (a reader or a killed writer never leaves a partial file).
    ``fsync``: also force it onto the disk before the rename (survives a power failure, not only
    a killed process; costs milliseconds, so the recorder asks for it at a bounded rate)."""
    arrays = {
        "format_version": np.array(ck.format_version),
        "model_hash": np.array(ck.model_hash),
        "step": np.array(ck.step),
        "load_factor": np.array(ck.load_factor),
        "u": ck.u,
        "load_factors": ck.load_factors,
        "summary": np.array(json.dumps(ck.summary)),
        "rows": np.array(json.dumps(ck.rows)),
        "pvd": np.array(json.dumps(ck.pvd)),
    }
    arrays.update({f"itf/{k}": v for k, v in ck.interface_state.items()})
    arrays.update({f"extra/{k}": v for k, v in ck.extra.items()})

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as f:
            np.savez(f, **arrays)
            f.flush()
            if fsync:
                os.fsync(f.fileno())

    atomic_write(Path(path), write)


def locate(where: str | Path) -> Path:
    """The checkpoint file of a results folder (or ``where`` itself when it is a file)."""
    p = Path(where)
    if p.is_dir():
        p = p / FILENAME
        if not p.is_file():
            raise CheckpointError(f"--restart '{where}': the folder has no {FILENAME} (it is written after every "
                                  "converged load step); give the results folder of a run that converged at "
                                  "least one step")
        return p
    if not p.exists():
        raise CheckpointError(f"--restart '{where}': no such folder; give the results folder (--out) of the run "
                              "to continue")
    return p


def load(where: str | Path) -> Checkpoint:
    """Read the checkpoint of a results folder (or file); CheckpointError with the fix otherwise."""
    path = locate(where)
    try:
        with np.load(path, allow_pickle=False) as z:
            files = set(z.files)
            version = int(z["format_version"]) if "format_version" in files else None
            if version != FORMAT_VERSION:
                raise CheckpointError(f"--restart '{where}': {path.name} has format version {version}, this "
                                      f"layershell reads version {FORMAT_VERSION}; rerun the model from the start")
            ck = Checkpoint(int(z["step"]), float(z["load_factor"]), np.array(z["u"], float),
                            np.array(z["load_factors"], float), str(z["model_hash"]),
                            {k[4:]: np.array(z[k]) for k in z.files if k.startswith("itf/")},
                            json.loads(str(z["summary"])), json.loads(str(z["rows"])), json.loads(str(z["pvd"])),
                            {k[6:]: np.array(z[k]) for k in z.files if k.startswith("extra/")}, version)
        bad = [name for name, v in (("u", ck.u), ("load_factor", ck.load_factor), ("load_factors", ck.load_factors))
               if not np.all(np.isfinite(v))]
        bad += [f"itf/{k}" for k, v in ck.interface_state.items()
                if v.dtype.kind == "f" and np.isinf(v).any()]  # NaN marks "not yet" in some histories
        if bad:
            raise CheckpointError(f"--restart '{where}': {path.name} holds NaN or infinite values ({', '.join(bad)}), "
                                  "so it is no state to continue from (damaged, or written by a diverged run); rerun "
                                  "the model from the start without --restart")
    except CheckpointError:
        raise
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, json.JSONDecodeError) as exc:
        raise CheckpointError(f"--restart '{where}': {path.name} cannot be read ({type(exc).__name__}: {exc}); "
                              "it is damaged or not a layershell checkpoint, rerun the model from the start") from None
    return ck


def check_compatible(ck: Checkpoint, spec, n_full: int, where: str | Path) -> None:
    """Raise CheckpointError unless ``ck`` was written by a run of this model."""
    if ck.model_hash != model_hash(spec):
        try:  # the run's model file as summary.json next to the checkpoint holds it
            text = json.loads((locate(where).parent / "summary.json").read_text(encoding="utf-8")).get("model_text")
        except (OSError, UnicodeDecodeError, ValueError, AttributeError):
            text = None
        same_text = text is not None and spec.model_text() == text
        if same_text:  # the hash covers the validated model with its defaults
            raise CheckpointError(f"--restart '{where}': the model file is the one of that run, but this layershell "
                                  "version fills in other defaults for what the file leaves out (the checkpoint "
                                  "would continue a different model); rerun without --restart, or finish the run "
                                  "with the version that wrote the checkpoint")
        raise CheckpointError(f"--restart '{where}': the checkpoint was written for a different model (the model "
                              "file or its mesh changed since: only [output], title and units may change); "
                              "restart with the model file of that run, or rerun without --restart")
    lf = np.asarray(spec.load_factors, float)
    if ck.load_factors.shape != lf.shape or not np.array_equal(ck.load_factors, lf):
        raise CheckpointError(f"--restart '{where}': the checkpoint's load factors differ from the model's [steps]; "
                              "rerun without --restart")
    n_max = lf.size if getattr(spec, "path_following", None) is None else spec.path_following.max_steps
    if ck.u.shape != (n_full,) or not 0 <= ck.step <= n_max:
        raise CheckpointError(f"--restart '{where}': the checkpoint does not fit this model ({ck.u.size} "
                              f"displacements for {n_full} DOFs, step {ck.step} of {lf.size}); rerun without --restart")
