"""The point states of the inelastic layers: committed, trial and (IMPL-EX) extrapolated.

One :class:`~layershell.element.inelastic.LayerState` per inelastic block of the assembler. The
element evaluations write their trial states here (:meth:`MaterialStates.put`); a converged
solution's trial becomes the committed state (:meth:`MaterialStates.commit`), so that a rejected
iterate or increment leaves no trace. IMPL-EX (Oliver, Huespe & Cante 2008): the histories of
the next increment are extrapolated linearly in pseudo-time from the last two commits, r̃ = r_n +
ratio (r_n − r_(n−1)), ratio = the next increment over the last one.
"""
from __future__ import annotations

import numpy as np

from .element.inelastic import InelasticBlock, extrapolated_state, initial_state, put_trial

#: the largest IMPL-EX extrapolation ratio (next increment over the last): an increment grown
#: more than this would extrapolate the damage rate of a short one far beyond where it held
MAX_IMPLEX_RATIO = 4.0


class MaterialStates:
    """The states of the inelastic ``blocks`` (assembly.Block) of ``model``; ``model.integration``
    selects "implex" (extrapolated histories) or "implicit"."""

    def __init__(self, model, blocks: list):
        self.model, self.blocks = model, blocks
        self.committed = {i: initial_state(b.ref) for i, b in enumerate(blocks) if isinstance(b.ref, InelasticBlock)}
        self.trial = {i: st.copy() for i, st in self.committed.items()}
        self.previous = {i: st.copy() for i, st in self.committed.items()}
        self.integration = getattr(model, "integration", "implex")
        self.extrapolated: dict = {}
        self.times = (0.0, 0.0)  # the pseudo-time of the last two commits
        self.ratio = 1.0
        self._extrapolate()
        if not model.point_states:  # (a second assembler of the same model, e.g. for probes, keeps the first's)
            self._publish()

    @property
    def active(self) -> bool:
        return bool(self.committed)

    def put(self, i: int, sl: slice, part) -> None:
        """The trial state ``part`` of block ``i``'s elements ``sl`` from an evaluation."""
        put_trial(self.trial[i], self.blocks[i].ref, sl, part)

    def commit(self, time: float | None = None) -> None:
        """The trial states (of an evaluation at a converged solution) become the committed ones;
        ``time``: their pseudo-time (default: one more than the last)."""
        self.previous = self.committed
        self.committed = {i: st.copy() for i, st in self.trial.items()}
        self.times = (self.times[1], self.times[1] + 1.0 if time is None else float(time))
        self.ratio = 1.0
        self._extrapolate()
        self._publish()

    def next_increment(self, time: float | None = None, ratio: float | None = None) -> None:
        """Extrapolate to pseudo-time ``time``, or by ``ratio`` (the next increment's size over the
        last one's); neither: one unit."""
        if not self.extrapolated:
            return
        t0, t1 = self.times
        last = t1 - t0
        if ratio is None:
            ratio = 1.0 if time is None or last == 0.0 else (float(time) - t1) / last
        ratio = min(max(ratio, 0.0), MAX_IMPLEX_RATIO)
        if ratio != self.ratio:
            self.ratio = ratio
            self._extrapolate()

    def implex_error(self) -> float:
        """The largest difference between the damage the last evaluation acted with
        (extrapolated) and its implicit update (the trial state)."""
        err = 0.0
        for i, ex in self.extrapolated.items():
            e = self.blocks[i].ref.law.implex_error(self.trial[i].bulk, ex.bulk)
            err = max(err, float(e.max()) if e.size else 0.0)
        return err

    def _extrapolate(self) -> None:
        self.extrapolated = {}
        if self.integration != "implex":
            return
        for i, st in self.committed.items():
            ex = extrapolated_state(self.blocks[i].ref, self.previous[i], st, self.ratio)
            if ex is not None:
                self.extrapolated[i] = ex

    def _publish(self) -> None:
        """Hand the committed states to the model's outputs (``Model.point_states``)."""
        states: dict = {}
        for i, st in self.committed.items():
            b = self.blocks[i]
            states.setdefault(b.layer, []).append((b.elements, b.ref, st))
        self.model.point_states.clear()
        self.model.point_states.update(states)

    def dissipation(self, trial: bool = False) -> float:
        """Energy dissipated so far: Σ dissipation per volume × dV over the points (sheets: ×
        A_s dA), of the committed state, or (``trial``) of the last evaluation's trial state."""
        total = 0.0
        for i, st in (self.trial if trial else self.committed).items():
            ref = self.blocks[i].ref
            if ref.law is not None:
                total += float(ref.law.dissipation(st.bulk) @ ref.base.dV.ravel())
            for s, ss in zip(ref.sheets, st.sheets):
                total += float(s.law.dissipation(ss) @ s.w.ravel())
        return total

    def events(self) -> dict[str, bool]:
        """Which events the committed state has seen anywhere (``cracking``, ``crushing``,
        ``yielding``, ``rupture``), from each law's ``events``."""
        seen: dict[str, bool] = {}
        for i, st in self.committed.items():
            ref = self.blocks[i].ref
            pairs = ([(ref.law, st.bulk)] if ref.law is not None else []) + list(zip((s.law for s in ref.sheets),
                                                                                     st.sheets))
            for law, state in pairs:
                for name, flags in law.events(state).items():
                    seen[name] = seen.get(name, False) or bool(np.any(flags))
        return seen

    def arrays(self) -> dict[str, np.ndarray]:
        """The committed and previous states and the pseudo-times as plain arrays (snapshots,
        checkpoints)."""
        out: dict[str, np.ndarray] = {}
        for i, st in self.committed.items():
            out.update(st.to_dict(f"block{i}"))
            out.update(self.previous[i].to_dict(f"previous{i}"))
        if out:
            out["implex_times"] = np.array(self.times, float)
        return out

    def load(self, arrays: dict) -> None:
        """Restore :meth:`arrays` (KeyError if one is missing or of another shape)."""
        self.committed = {i: st.load(arrays, f"block{i}") for i, st in self.committed.items()}
        self.previous = {i: st.load(arrays, f"previous{i}") for i, st in self.previous.items()}
        if self.committed:
            if "implex_times" not in arrays:
                raise KeyError("implex_times")
            self.times = tuple(float(t) for t in np.asarray(arrays["implex_times"]))
            self.ratio = 1.0
        self.trial = {i: st.copy() for i, st in self.committed.items()}
        self._extrapolate()
        self._publish()
