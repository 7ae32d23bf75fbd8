"""Arc-length runs stopped after any increment and restarted continue exactly.

The reference is the same model run without interruption: a run stopped as by Ctrl-C after
increment k and restarted from its checkpoint must give the uninterrupted run's load factors,
probes, Newton iterations and cuts for every later increment (to 1e-9 relative; a restart that
forgets part of the path's state - the last increments' sizes and iteration counts, a running
stretch of load-controlled increments, the probes' scales - takes other increments, which changes
the load factors by far more). The stop points are picked from the uninterrupted run itself: the
increment of the first cut, the first under the dissipation constraint and the one before it, the
first of a stretch of load-controlled increments under arc-length control and every one that ended
such a stretch (where the example has them).
"""
from __future__ import annotations

import pytest

from helpers import example_spec, stopped_and_restarted
from layershell.runner import run

#: relative bound on the load factors and probes of the restarted run (both are the same
#: computation when the state is complete; round-off only)
REL = 1e-9

#: the examples reduced to runs of a few seconds that still pass a cut, a switch to the
#: dissipation constraint and (the force-loaded DCB) load-controlled stretches
CASES = {
    "dcb_force": ("dcb_cohesive", {"nx = 150": "nx = 50",
                                   "factors = [0.01": 'control = "arc_length"\nn = 20\nmax_steps = 13 #'}),
    "dcb_displacement": ("dcb_displacement", {"nx = 150": "nx = 50", "max_steps = 3000": "max_steps = 15"}),
    "lapshear": ("lapshear_cohesive", {"max_steps = 300": "max_steps = 9"}),
}


def _stop_points(full) -> dict[str, int]:
    """The increments to stop after, by what happens at them: {what: k}."""
    steps = full.summary["steps"]
    n = len(steps)
    modes = {s["step"]: s["path"]["constraint"] for s in steps}  # the constraint after each increment
    points = {}
    cut = next((s["step"] for s in steps if s["bisections"] > 0), None)
    if cut is not None and cut < n:
        points["after a cut"] = cut
    diss = next((k for k in sorted(modes) if modes[k] == "dissipation"), None)
    if diss is not None and diss < n:
        points["first under the dissipation constraint"] = diss
        points["before the switch to dissipation"] = diss - 1
    stretch = next((k for k in sorted(modes) if modes[k] == "load"), None)
    if stretch is not None and stretch < n:
        points["in a load-controlled stretch"] = stretch
    # every increment that ended a stretch (the next may start only past the load it reached)
    ended = [k for k in sorted(modes) if k > 1 and modes[k - 1] == "load" and modes[k] != "load" and k < n]
    for i, k in enumerate(ended):
        points[f"where load-controlled stretch {i + 1} ended"] = k
    return points


def _series(result):
    steps = result.summary["steps"]
    return ([s["load_factor"] for s in steps], [s["probes"] for s in steps],
            [(s["iterations"], s["bisections"]) for s in steps])


@pytest.mark.parametrize("case", [pytest.param("dcb_force", marks=pytest.mark.slow),
                                  pytest.param("dcb_displacement", marks=pytest.mark.slow), "lapshear"])
def test_restart_after_any_increment_continues_the_path_exactly(case, tmp_path):
    name, replace = CASES[case]
    spec = example_spec(name, replace)
    full = run(spec, tmp_path / "full", write_vtu=False)
    assert full.converged
    points = _stop_points(full)
    assert "first under the dissipation constraint" in points, points
    lams, probes, counts = _series(full)
    scale = {p: max(abs(v[p]) for v in probes) for p in probes[0]}  # a probe near 0: judged on its range
    by_step: dict[int, str] = {}
    for what, k in points.items():
        by_step[k] = f"{by_step[k]}, {what}" if k in by_step else what
    failed = {}
    for k, what in sorted(by_step.items()):
        part, again = stopped_and_restarted(spec, tmp_path / f"part{k}", k)
        assert part.interrupted and len(part.summary["steps"]) == k
        got_lams, got_probes, got_counts = _series(again)
        ok = (len(got_lams) == len(lams) and got_lams == pytest.approx(lams, rel=REL)
              and all(g[p] == pytest.approx(v[p], rel=REL, abs=REL * scale[p])
                      for g, v in zip(got_probes, probes) for p in scale)
              and got_counts == counts)
        if not ok:
            first = next((i for i, (a, b) in enumerate(zip(got_lams, lams)) if a != pytest.approx(b, rel=REL)),
                         min(len(got_lams), len(lams)))
            failed[f"k={k} ({what})"] = f"increment {first + 1}: {got_lams[first:first + 1]} vs {lams[first:first + 1]}"
    assert not failed, failed
