"""The one writer of a results folder: the runner hands it each converged step.

:class:`Recorder` alone writes into the folder of ``layershell run``: summary.json, probes.csv,
delamination.csv, steps.jsonl, run.log, the ParaView files, checkpoint.npz and the figures. It

* **locks the folder** (``.layershell.lock``, an OS file lock released when the process ends,
  even by SIGKILL): a second run into the same folder is refused with the first run's PID;
* **clears an earlier run's files**: a rerun of the same model file (edited or not) or of the
  same model replaces them; results of *another* model are kept and the run is refused unless
  ``overwrite`` (``--overwrite``). Removed are the files listed in ``.layershell-files`` (every
  file a run writes) and files with layershell's result names (summary.json, probes.csv, *.vtu
  of its series, *.pvd, *.png, profile_*.csv, ...); other files (model files, meshes, notes)
  are kept;
* writes whole files **atomically** (temporary file in the folder, then :func:`os.replace`) with
  the **mode from the umask** (:mod:`layershell.io.output`);
* **appends** per-step results (a line of probes.csv, delamination.csv and steps.jsonl, entries
  of the .pvd files), so that a step costs the same however long the history; summary.json (the
  whole history) is rewritten at a bounded rate (at most ~5 % of the run time) and at the end.
  steps.jsonl, probes.csv and checkpoint.npz are complete after every converged step, so a killed
  run keeps its finished steps and ``--restart`` continues from them.
"""
from __future__ import annotations

import datetime as dt
import json
import os
import socket
import sys
import time
from pathlib import Path
from typing import Callable

from .io.output import FILE_MODE, AppendCsv, atomic_write, write_csv, write_json

LOCK = ".layershell.lock"
MANIFEST = ".layershell-files"
STEPS = "steps.jsonl"
RUN_LOG = "run.log"
SUMMARY = "summary.json"
#: files of a run that are always layershell's (removed with the run even without a manifest)
OWN_NAMES = ("summary.json", "probes.csv", "delamination.csv", STEPS, RUN_LOG, "checkpoint.npz", "report.html")
#: the names layershell gives its other result files (removed with an earlier run's files, also
#: when a kill kept them from the manifest)
RESULT_GLOBS = ("*.pvd", "surface_*.vtu", "solid_*.vtu", "interface_*.vtu", "*.png", "profile_*.csv")


class ResultsFolderError(ValueError):
    """The results folder cannot be used: in use by another run, or holding another model's
    results (exit code 2)."""


def _lock(folder: Path) -> int:
    """Open and lock ``folder/.layershell.lock``; ResultsFolderError naming the holder if taken."""
    path = folder / LOCK
    fd = os.open(path, os.O_RDWR | os.O_CREAT, FILE_MODE)
    try:
        try:
            import fcntl

            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except ImportError:  # Windows
            import msvcrt

            msvcrt.locking(fd, msvcrt.LK_NBLCK, 1)
    except OSError:
        try:
            os.lseek(fd, 0, os.SEEK_SET)
            holder = json.loads(os.read(fd, 65536).decode("utf-8") or "{}")
        except (OSError, ValueError):
            holder = {}
        os.close(fd)
        who = (f"PID {holder.get('pid')} on {holder.get('host')}, started {holder.get('started')}"
               if holder.get("pid") else "another process")
        raise ResultsFolderError(
            f"the results folder '{folder}' is in use by another layershell run ({who}); two runs into one "
            "folder would overwrite each other's files: wait until that run ends (or stop it), or give this "
            "run another folder with --out") from None
    info = {"pid": os.getpid(), "host": socket.gethostname(),
            "started": dt.datetime.now(dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
            "command": " ".join(sys.argv)}
    os.ftruncate(fd, 0)
    os.lseek(fd, 0, os.SEEK_SET)
    os.write(fd, json.dumps(info).encode("utf-8"))
    return fd


def _unlock(fd: int) -> None:
    try:
        os.ftruncate(fd, 0)
    except OSError:
        pass
    os.close(fd)  # releases the lock


def earlier_files(folder: Path) -> list[Path]:
    """The files of an earlier layershell run in ``folder``: those in its manifest, the fixed
    names, the result name patterns (:data:`RESULT_GLOBS`) and temporary leftovers of a kill."""
    names: set[str] = set(OWN_NAMES)
    man = folder / MANIFEST
    if man.is_file():
        names |= {ln.strip() for ln in man.read_text(encoding="utf-8", errors="replace").splitlines() if ln.strip()}
    if man.is_file() or (folder / SUMMARY).is_file() or (folder / "checkpoint.npz").is_file():
        for g in RESULT_GLOBS:
            names |= {p.name for p in folder.glob(g)}
    names |= {p.name for p in folder.glob(".*.tmp")}
    out = []
    for n in sorted(names):
        p = folder / n
        if "/" not in n and "\\" not in n and n not in (LOCK, "..", ".") and p.is_file():
            out.append(p)
    if man.is_file():
        out.append(man)
    return out


def _earlier_model(folder: Path) -> dict | None:
    """model_file / model_hash / title of the run that wrote ``folder`` (None: no earlier run)."""
    p = folder / SUMMARY
    if not p.is_file():
        return {} if (folder / "checkpoint.npz").is_file() or (folder / MANIFEST).is_file() else None
    try:
        s = json.loads(p.read_text(encoding="utf-8"))
        return s if isinstance(s, dict) else {}
    except (OSError, ValueError):
        return {}


def _same_file(a, b) -> bool:
    if not a or not b:
        return False
    try:
        return Path(a).resolve() == Path(b).resolve()
    except OSError:
        return False


class Recorder:
    """Owner of one results folder for one run (use as a context manager).

    ``model_file``/``model_hash``/``title``: what this run solves (to recognise an earlier run of
    the same model); ``overwrite``: delete another model's results instead of refusing; ``resume``:
    a restart into this folder (its files are continued, not removed); ``echo``: called with every
    run.log line (``--verbose``).
    """

    def __init__(self, folder: str | Path, *, model_file: str | None = None, model_hash: str = "",
                 title: str = "", overwrite: bool = False, resume: bool = False,
                 echo: Callable[[str], None] | None = None, summary_budget: float = 0.05):
        self.folder = Path(folder)
        self.model_file, self.model_hash, self.title = model_file, model_hash, title
        self.overwrite, self.resume, self.echo = overwrite, resume, echo
        self.summary_budget = summary_budget
        self._lock_fd: int | None = None
        self._doomed: list[Path] = []
        self._known: set[str] = set()
        self._manifest = None
        self._log = None
        self._steps = None
        self._probes: AppendCsv | None = None
        self._delam: AppendCsv | None = None
        self._delam_names: list[str] | None = None
        self.energy_names: list[str] = []
        self._summary_t = -1e300  # time of the last summary.json write
        self._summary_cost = 0.0
        self._sync_t = -1e300  # time of the last fsync of the checkpoint

    # ----------------------------------------------------------------- folder ownership

    def __enter__(self) -> "Recorder":
        self.open()
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def open(self) -> None:
        """Create and lock the folder and check an earlier run's files (refused: another model
        without ``overwrite``). They are removed only by :meth:`begin`, when the new run has been
        set up (so that a model that fails to build leaves the earlier results alone)."""
        self.folder.mkdir(parents=True, exist_ok=True)
        self._lock_fd = _lock(self.folder)
        try:
            self._doomed = [] if self.resume else self._earlier()
        except BaseException:
            self.close()
            raise

    def _earlier(self) -> list[Path]:
        """The earlier run's files to remove; ResultsFolderError if they are another model's."""
        prev = _earlier_model(self.folder)
        if prev is None:
            return []
        files = earlier_files(self.folder)
        if not files:
            return []
        same = (_same_file(prev.get("model_file"), self.model_file)
                or (self.model_hash and prev.get("model_hash") == self.model_hash))
        if not same and not self.overwrite:
            what = (f"of the model file '{prev['model_file']}'" if prev.get("model_file")
                    else f"of '{prev['title']}'" if prev.get("title") else "of another model")
            raise ResultsFolderError(
                f"the results folder '{self.folder}' holds the results {what} ({len(files)} file(s)); a run of "
                f"'{self.model_file}' there would mix two models' files: give this run another folder with "
                "--out, or add --overwrite to delete those results first")
        return files

    def _start(self) -> None:
        """Remove the earlier run's files, open the manifest and run.log."""
        if self._manifest is not None:
            return
        for p in self._doomed:
            try:
                p.unlink()
            except FileNotFoundError:
                pass
        self._doomed = []
        man = self.folder / MANIFEST
        if man.is_file():
            self._known = {ln.strip() for ln in man.read_text(encoding="utf-8", errors="replace").splitlines()}
        self._manifest = open(man, "a", encoding="utf-8")
        os.chmod(man, FILE_MODE)
        self._log = open(self.folder / RUN_LOG, "a" if self.resume else "w", encoding="utf-8")
        self._register(RUN_LOG)

    def close(self) -> None:
        for f in (self._probes, self._delam):
            if f is not None:
                f.close()
        for f in (self._steps, self._manifest, self._log):
            if f is not None and not f.closed:
                f.close()
        self._probes = self._delam = None
        if self._lock_fd is not None:
            _unlock(self._lock_fd)
            self._lock_fd = None

    def _register(self, *names) -> None:
        """List files as written by this run (removed with it by a later run)."""
        new = []
        for n in names:
            n = Path(n).name if Path(n).parent in (Path("."), self.folder) else os.path.relpath(n, self.folder)
            if n not in self._known:
                self._known.add(n)
                new.append(n)
        if new and self._manifest is not None:
            self._manifest.write("".join(f"{n}\n" for n in new))
            self._manifest.flush()

    def path(self, name: str) -> Path:
        """``folder/name``, registered as a file of this run (for writers elsewhere, e.g. VTU)."""
        self._register(name)
        return self.folder / name

    def register(self, paths) -> None:
        """Register files written by others into the folder (paths or names)."""
        self._register(*[Path(p) for p in paths])

    # ----------------------------------------------------------------- whole files

    def write_json(self, name: str, data) -> None:
        write_json(self.path(name), data)

    def write_csv(self, name: str, header: list[str], rows: list[list]) -> None:
        write_csv(self.path(name), header, rows)

    def write(self, name: str, write: Callable[[Path], None]) -> None:
        atomic_write(self.path(name), write)

    # ----------------------------------------------------------------- run.log

    def log(self, line: str) -> None:
        """One line of run.log (flushed at once; echoed with --verbose)."""
        if self._log is not None and not self._log.closed:
            self._log.write(line + "\n")
            self._log.flush()
        if self.echo is not None:
            self.echo(line)

    # ----------------------------------------------------------------- per-step results

    def begin(self, probe_names: list[str], history: list[dict], energy_names: list[str] = ()) -> None:
        """Take over the folder (the earlier run's files go now) and start the per-step files
        with ``history`` (the steps before a restart, else empty). ``energy_names``: columns of
        probes.csv after the probes, taken from each step's ``energy`` (cohesive interfaces)."""
        self._start()
        self.probe_names = list(probe_names)
        self.energy_names = list(energy_names)
        lines = "".join(json.dumps(r) + "\n" for r in history)
        atomic_write(self.path(STEPS), lambda tmp: tmp.write_text(lines, encoding="utf-8"))
        self._steps = open(self.folder / STEPS, "a", encoding="utf-8")
        self._register("probes.csv")
        self._probes = AppendCsv(self.folder / "probes.csv",
                                 ["step", "load_factor", "iterations"] + self.probe_names + self.energy_names,
                                 [self._row(r) for r in history])
        recs = [r for r in history if "debonded_extent" in r]
        if recs:
            self._start_delam(recs)

    def _row(self, rec: dict) -> list:
        energy = rec.get("energy") or {}
        return ([rec["step"], rec["load_factor"], rec["iterations"]] + [rec["probes"][n] for n in self.probe_names]
                + [energy.get(n, "") for n in self.energy_names])

    _DELAM_KEYS = ("area", "x_min", "x_max", "y_min", "y_max")

    def _delam_row(self, rec: dict) -> list:
        ext = rec["debonded_extent"]
        return [rec["step"], float(rec["load_factor"])] + [
            ("" if ext[n][k] is None else float(ext[n][k])) for n in self._delam_names for k in self._DELAM_KEYS]

    def _start_delam(self, recs: list[dict]) -> None:
        self._delam_names = list(recs[0]["debonded_extent"])
        header = ["step", "load_factor"] + [f"{n}:{k}" for n in self._delam_names for k in self._DELAM_KEYS]
        self._register("delamination.csv")
        self._delam = AppendCsv(self.folder / "delamination.csv", header, [self._delam_row(r) for r in recs])

    def step(self, rec: dict, files: dict[str, str] | None = None) -> None:
        """Append one converged step: a line of steps.jsonl (``rec`` and the ParaView ``files`` of
        the step), probes.csv and delamination.csv."""
        line = dict(rec, files=files) if files else rec
        self._steps.write(json.dumps(line) + "\n")
        self._steps.flush()
        self._probes.append(self._row(rec))
        if "debonded_extent" in rec:
            if self._delam is None:
                self._start_delam([rec])
            else:
                self._delam.append(self._delam_row(rec))

    def sync_due(self, every: float = 5.0) -> bool:
        """Whether the checkpoint written now should be forced onto the disk (fsync): at most every
        ``every`` seconds (a killed process loses nothing either way; this bounds what a power
        failure can cost without paying an fsync per step)."""
        now = time.monotonic()
        if now - self._sync_t >= every:
            self._sync_t = now
            return True
        return False

    def summary(self, summary: dict, force: bool = False) -> bool:
        """Rewrite summary.json: always with ``force``, otherwise only when the time since the last
        write is at least 1/``summary_budget`` times what that write cost (its cost grows with the
        history; this keeps it below ~5 % of the run time). Returns whether it was written."""
        now = time.perf_counter()
        if not force and now - self._summary_t < self._summary_cost / self.summary_budget:
            return False
        self.write_json(SUMMARY, summary)
        self._summary_t = time.perf_counter()
        self._summary_cost = self._summary_t - now
        return True


def read_history(folder: str | Path, upto_step: int) -> list[dict]:
    """The step records of steps.jsonl in ``folder`` up to step ``upto_step`` (a line cut short
    by a kill is ignored)."""
    p = Path(folder) / STEPS
    out: list[dict] = []
    if not p.is_file():
        return out
    with p.open(encoding="utf-8") as f:
        for ln in f:
            try:
                rec = json.loads(ln)
            except ValueError:
                break
            if not isinstance(rec, dict) or int(rec.get("step", 10**12)) > upto_step:
                break
            out.append(rec)
    return out
