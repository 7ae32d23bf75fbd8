"""The state of a followed path that lasts from one increment to the next, and the reasons an
increment is refused or a path ends.

:class:`PathState` holds everything :func:`~layershell.solver.arclength.path_steps` carries
across increments; the checkpoint stores it whole (:meth:`PathState.to_arrays`, keys ``path.*``)
and a restart restores it (:meth:`PathState.from_arrays`), so that a restarted run takes the same
increments as an uninterrupted one. What follows from the restored model state alone (the
displacement u, λ, the debonded area and the probe values at the start of the next increment) is
not stored twice.

:class:`Reason` names why an increment is refused (its branches decide by it) and :class:`End`
why a path ends; the text for the log is kept apart (:attr:`Reason.message`, or the Newton
solver's own message where the reason is :attr:`Reason.NOT_CONVERGED`).
"""
from __future__ import annotations

import json
import math
from dataclasses import dataclass, field, replace
from enum import Enum

import numpy as np


class Reason(Enum):
    """Why an increment was refused (the human text: :attr:`message`)."""

    NOT_CONVERGED = "the constrained or Newton iterations did not converge"
    NO_DISSIPATION = "no dissipation in the predictor direction"
    ENERGY_BALANCE = "energy balance"
    DEBONDING_JUMP = "debonding jump"
    PROBE_JUMP = "probe jump"
    FRICTION_REFUSED = "the dissipation constraint was met by friction on unloading, not by damage"
    CLOSURE_REFUSED = "the dissipation constraint was met by closure, not damage"
    UNBOOKED = "the dissipation constraint was met while the materials booked no dissipation (unloading)"
    CROSSED_ZERO = "the dissipation constraint crossed λ = 0 (closure, not damage)"
    TURNED_BACK = "the increment turned back along the path"
    ELASTIC_UNLOADING = "the increment unloads elastically from a debonding state"
    STILL_CHANGING = "the state still changes after the allowed re-solutions"
    PASSES_END = "the increment passes λ_end, where load control finds no equilibrium"

    @property
    def message(self) -> str:
        return self.value

    @property
    def jump(self) -> bool:
        """A refusal for a jump of the path (accepted with a warning after ``max_jump_cuts``)."""
        return self in (Reason.DEBONDING_JUMP, Reason.PROBE_JUMP)


class End(str, Enum):
    """Why a path ends (summary.json ``path_end`` holds the value)."""

    LAMBDA_END = "lambda_end"
    COMPLETE_FAILURE = "complete failure"
    MAX_STEPS = "max_steps"


#: the float fields stored as one 0-d array each (with their defaults when a checkpoint lacks them)
_SCALARS = ("size", "arc_length", "lam_peak", "dissipated", "arc_length0", "lam_damaged", "dissipation_max",
            "reaction", "stretch_from", "stretch_block", "implex_size")
_FLAGS = ("finished", "changed")
_COUNTS = ("stretch_accepted", "end_cuts")
_TEXTS = ("mode", "recent_mode", "implex_mode", "rescue")
_PAIRS = ("recent", "recent_dissipation")  # lists of (size, Newton iterations)
_SERIES = ("recent_lams", "recent_dG")  # lists of floats


@dataclass
class PathState:
    """What continues a path after a restart (stored in checkpoint.npz as ``path.*``)."""

    mode: str = ""  # "load" (under arc-length control: a stretch), "arc", "dissipation"; "" at first
    size: float = 0.0  # Δλ, Δl or Δτ of the next increment
    arc_length: float = 0.0  # the arc length (kept while the dissipation constraint acts)
    du_prev: np.ndarray | None = None  # full-space increment of the last step (predictor sign)
    lam_peak: float = 0.0  # largest |λ| so far
    dissipated: float = 0.0  # Σ ΔG of the increments so far
    finished: bool = False
    arc_length0: float = 0.0  # the first arc length (sets the default bounds)
    changed: bool = False  # the last increment changed the state (debonding): work criterion next
    lam_damaged: float = math.nan  # λ of the last increment in which damage grew (force paths; unloading())
    # (size, Newton iterations) of the last increments under the constraint ``recent_mode``
    # ("load": Δλ, "arc": Δl): the last one under load control, ARC_WINDOW under arc-length
    # control (size_insensitive)
    recent: list = field(default_factory=list)
    recent_mode: str = ""
    # where friction acts on a damaged share: the largest dissipation-controlled increment Δτ so
    # far and the last ARC_WINDOW (Δτ, iterations) under that constraint (size_insensitive)
    dissipation_max: float = 0.0
    recent_dissipation: list = field(default_factory=list)
    # λ and |ΔG| of the last stall_increments accepted increments (stalled(), crawling())
    recent_lams: list = field(default_factory=list)
    recent_dG: list = field(default_factory=list)
    scales: dict = field(default_factory=dict)  # largest |value| of each watched probe (probe_scales)
    reaction: float = math.nan  # R = gᵀ f_int at the committed state (displacement paths); NaN: not yet
    # a crawl's stop message while one load-controlled increment tries to pass it ("": none)
    rescue: str = ""
    # a stretch of load-controlled increments under arc-length control: the load factor where it
    # began, how many increments it accepted, and the load factor below which no new one starts
    stretch_from: float = math.nan
    stretch_accepted: int = 0
    stretch_block: float = -math.inf
    end_cuts: int = 0  # increments cut since they passed λ_end where load control could not reach it
    # IMPL-EX: the constraint and size of the last accepted increment ("": none yet)
    implex_mode: str = ""
    implex_size: float = 0.0

    def copy(self) -> "PathState":
        """A copy that later changes of this state do not reach."""
        return replace(self, du_prev=None if self.du_prev is None else self.du_prev.copy(),
                       **{k: list(getattr(self, k)) for k in _PAIRS + _SERIES}, scales=dict(self.scales))

    def to_arrays(self) -> dict[str, np.ndarray]:
        """The state as plain arrays (``path.<field>``) for checkpoint.npz."""
        out = {f"path.{k}": np.array(getattr(self, k), float) for k in _SCALARS}
        out.update({f"path.{k}": np.array(bool(getattr(self, k))) for k in _FLAGS})
        out.update({f"path.{k}": np.array(int(getattr(self, k))) for k in _COUNTS})
        out.update({f"path.{k}": np.array(str(getattr(self, k))) for k in _TEXTS})
        out.update({f"path.{k}": np.array(getattr(self, k), float).reshape(-1, 2) for k in _PAIRS})
        out.update({f"path.{k}": np.array(getattr(self, k), float).reshape(-1) for k in _SERIES})
        out["path.scales"] = np.array(json.dumps(self.scales))
        if self.du_prev is not None:
            out["path.du_prev"] = self.du_prev.copy()
        return out

    @classmethod
    def from_arrays(cls, a: dict[str, np.ndarray]) -> "PathState | None":
        """The state stored by :meth:`to_arrays` (None where ``a`` holds none); a field missing
        from ``a`` keeps its default."""
        if "path.mode" not in a:
            return None
        st = cls()
        for k in _SCALARS:
            setattr(st, k, float(a.get(f"path.{k}", getattr(st, k))))
        for k in _FLAGS:
            setattr(st, k, bool(a.get(f"path.{k}", getattr(st, k))))
        for k in _COUNTS:
            setattr(st, k, int(a.get(f"path.{k}", getattr(st, k))))
        for k in _TEXTS:
            setattr(st, k, str(a.get(f"path.{k}", getattr(st, k))))
        for k in _PAIRS:
            setattr(st, k, [(float(x), int(n)) for x, n in np.asarray(a.get(f"path.{k}", np.zeros((0, 2))))
                            .reshape(-1, 2)])
        for k in _SERIES:
            setattr(st, k, [float(x) for x in np.asarray(a.get(f"path.{k}", np.zeros(0))).reshape(-1)])
        st.scales = {str(k): float(v) for k, v in json.loads(str(a.get("path.scales", "{}"))).items()}
        st.du_prev = np.array(a["path.du_prev"], float) if "path.du_prev" in a else None
        if "path.recent" not in a and float(a.get("path.last_increment", 0.0)) > 0.0:
            # checkpoints written before `recent` kept the last load-controlled increment alone
            st.recent, st.recent_mode = [(float(a["path.last_increment"]), int(a["path.last_iterations"]))], "load"
        return st

