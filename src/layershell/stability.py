"""Stability of the equilibrium path from the inertia of the tangent stiffness.

The number of negative eigenvalues of the (reduced, symmetric) tangent K_T at converged states
tells stable from unstable equilibria: it is zero on a stable branch, and it changes only where
K_T is singular - at a limit point of the load (a maximum or minimum of λ along the path) or at
a bifurcation point, where another branch (e.g. a buckled one) crosses the path. PARDISO's
symmetric indefinite factorisation reports it for free (solver/linear.py ``FactorInfo``); each
step records the count of the last tangent it factorised, near its converged state
(:func:`layershell.solver.newton.step_inertia`; None where unknown).

:class:`StabilityWatch` classifies every change of the count between two recorded states:

- **limit point**: the count changes where the load factor passes a maximum or minimum (the
  signs of its increments turn within one increment of the change) - expected past the peak of
  a softening or snapping path traced by arc length;
- **bifurcation**: the count grows without such a turn - the path went through a bifurcation
  point between the two states and goes on along a branch that is now unstable (a perfect
  column or plate compressed beyond its buckling load stays straight in the computation, not in
  reality);
- **restabilised**: the count falls without a turn (back through a bifurcation, or the structure
  changed: contact, debonding);
- **undecided**: the path ended before the increment after the change showed whether λ turned.

A state whose tangent has a negative eigenvalue already at the first recorded step is reported
as ``unstable``. The physics-free logic works on (step, λ, count) triples only.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass


@dataclass
class StabilityEvent:
    """A change of the tangent's negative eigenvalues between two recorded states."""

    kind: str  # "limit point", "bifurcation", "restabilised", "undecided" or "unstable"
    step: int  # the first state with the new count
    load_factor: float
    negative_eigenvalues: int
    step_before: int | None  # the last state with the old count (None: ``unstable`` at the start)
    load_factor_before: float | None
    negative_eigenvalues_before: int
    # a bifurcation located by bisection (solver/newton.py locate_inertia_change): (λ_lo, λ_hi)
    located: tuple[float, float] | None = None
    mode_file: str | None = None  # its buckling mode (runner: buckling_mode_<step>.vtu)

    def as_dict(self) -> dict:
        d = asdict(self)
        if self.located is None:
            d.pop("located")
        else:
            d["located"] = [float(v) for v in self.located]
        if self.mode_file is None:
            d.pop("mode_file")
        return d

    @property
    def warns(self) -> bool:
        """Bifurcations and an unstable start are warned; limit points and restabilisation are
        expected on the paths that arc length traces."""
        return self.kind in ("bifurcation", "unstable")

    def message(self) -> str:
        n, lam = self.negative_eigenvalues, self.load_factor
        if self.kind == "unstable":
            return (f"step {self.step}: the tangent stiffness has {n} negative eigenvalue(s) at load factor {lam:.6g}, "
                    "the first state recorded: the equilibrium is unstable from the start (a structure loaded "
                    "beyond its buckling load in one step, or a mechanism held by a penalty only); use smaller "
                    "steps to see where the eigenvalue(s) turn negative")
        where = ("; bisection locates the change between load factors "
                 f"{self.located[0]:.7g} and {self.located[1]:.7g}" if self.located is not None
                 else "; smaller steps locate it")
        if self.mode_file is not None:
            where += f" (its mode: {self.mode_file})"
        return (f"step {self.step}: the tangent stiffness has {n} negative eigenvalue(s) at load factor {lam:.6g} "
                f"against {self.negative_eigenvalues_before} at {self.load_factor_before:.6g} (step "
                f"{self.step_before}), and the load factor did not pass a maximum in between: the equilibria from "
                "here on are unstable. The path went through a bifurcation point (e.g. buckling), on which a "
                "perfect model can stay, or a load step jumped onto an unstable branch. Smaller steps or "
                "control = 'arc_length' follow a path without jumps, and a small imperfection in the buckling "
                f"mode (a load or a geometric deviation) makes the model take the stable branch{where}")


def _turns(lams: list[float]) -> int:
    """How often the increments of ``lams`` change their sign (zero increments skipped)."""
    signs = [1 if b > a else -1 for a, b in zip(lams, lams[1:]) if b != a]
    return sum(1 for a, b in zip(signs, signs[1:]) if a != b)


class StabilityWatch:
    """Classifies the changes of the negative-eigenvalue count along a path (module docstring).
    :meth:`add` takes each converged state in order and returns the events that became decidable
    (a change is decided one state later, when the next increment shows whether λ turned);
    :meth:`finish` returns the rest at the end of the run. ``monotone``: the load factor only grows
    (load control), so every change is decided at once."""

    def __init__(self, monotone: bool = False) -> None:
        self.monotone = monotone
        self._lams: list[float] = []  # λ of every state added
        self._steps: list[int] = []
        self._known: int | None = None  # index of the last state with a known count
        self._count: int | None = None  # its count
        self._pending: tuple[int, int] | None = None  # (index of the change, index of the state before)
        self._counts: list[int | None] = []

    def add(self, step: int, load_factor: float, negative: int | None) -> list[StabilityEvent]:
        out: list[StabilityEvent] = []
        self._lams.append(float(load_factor))
        self._steps.append(int(step))
        self._counts.append(negative)
        i = len(self._lams) - 1
        if self._pending is not None and i >= self._pending[0] + 1:
            out.append(self._decide(*self._pending))
            self._pending = None
        if negative is None:
            return out
        if self._known is None:
            if negative > 0:
                out.append(StabilityEvent("unstable", step, float(load_factor), negative, None, None, 0))
        elif negative != self._count:
            if self._pending is not None:  # a second change before the first was decided
                out.append(self._decide(*self._pending))
            self._pending = (i, self._known)
        self._known, self._count = i, negative
        if self.monotone and self._pending is not None:
            out.append(self._decide(*self._pending))
            self._pending = None
        return out

    def finish(self) -> list[StabilityEvent]:
        if self._pending is None:
            return []
        ev = self._decide(*self._pending)
        self._pending = None
        return [ev]

    def _decide(self, i: int, k: int) -> StabilityEvent:
        """The change between state k (old count) and state i (new count): a limit point where λ
        turns among the increments from the state before k to the state after i."""
        lo, hi = max(k - 1, 0), min(i + 1, len(self._lams) - 1)
        before, now = self._counts[k], self._counts[i]
        if _turns(self._lams[lo:hi + 1]) >= abs(now - before):
            kind = "limit point"
        elif hi == i and not self.monotone:  # no increment after the change yet: a turn may follow
            kind = "undecided"
        else:
            kind = "bifurcation" if now > before else "restabilised"
        return StabilityEvent(kind, self._steps[i], self._lams[i], now, self._steps[k], self._lams[k], before)
