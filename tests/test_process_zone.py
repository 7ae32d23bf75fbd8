"""Issue 13 item 4: the cohesive process-zone estimate (layershell.process_zone) against the
process zone measured in FE runs, and probes that are round-off (a reaction that equilibrium
makes zero) kept out of the jump warnings and step cuts."""
import warnings

import numpy as np
import pytest

from helpers import run_example
from layershell.solver.arclength import jump_warnings

# ---------------------------------------------------------------------- round-off probes
#: examples/dcb_cohesive.toml (force control: the two arms pulled apart by equal and opposite
#: forces) with the reactions of the clamp as probes: zero by equilibrium, so their values are
#: solver round-off (~1e-13 N against loads of 10-60 N)
ROUND_OFF = {
    "nonlinear = false": "nonlinear = true",  # Newton iterates: the round-off changes from step to step
    "nx = 150": "nx = 20",
    '[[probes]]\nname = "P"': '[[probes]]\nname = "Rx"\nquantity = "reaction"\nwhere = "near(x, 150)"\ncomponent = "x"\n\n'
    '[[probes]]\nname = "Rz"\nquantity = "reaction"\nwhere = "near(x, 150)"\ncomponent = "z"\n\n[[probes]]\nname = "P"',
}


def _probe_jumps(caught) -> list[str]:
    from layershell.runner import JumpWarning

    return [str(w.message) for w in caught if issubclass(w.category, JumpWarning) and "probe" in str(w.message)]


@pytest.mark.parametrize("steps", ["fixed", "adaptive"])
def test_reactions_that_equilibrium_makes_zero_are_no_jump(steps):
    """The clamp reactions of the self-equilibrated DCB are round-off whose ratio from step to
    step is arbitrary (measured: 2.8e-14 → -4.5e-13 N, 16× while λ doubled). Without a noise
    floor that is a 'jump' (three warnings on the fixed steps; on adaptive steps a cut and a
    warning). With the floor |scale| ‖ρ‖ tol_residual force_scale (runner._ProbeFloors): none.
    The check that the floor is needed: the recorded values give jump warnings when the floor
    is left out."""
    if steps == "fixed":
        repl = {**ROUND_OFF, "factors = [0.01, 0.02, 0.05,": "factors = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6] #"}
    else:
        repl = {**ROUND_OFF, "factors = [0.01, 0.02, 0.05,": "n = 6\nadaptive = true\nlambda_end = 0.6 #"}
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = run_example("dcb_cohesive", repl)
    assert r.converged and r.summary["steps"][-1]["load_factor"] == pytest.approx(0.6)
    assert not _probe_jumps(caught), _probe_jumps(caught)
    assert not [w for w in r.summary.get("warnings", []) if "probe" in w]
    st = r.summary["steps"]
    assert sum(s["bisections"] for s in st) == 0  # no step cut for round-off
    P = np.array([s["probes"]["P"] for s in st])
    R = np.array([[s["probes"]["Rx"], s["probes"]["Rz"]] for s in st])
    assert np.abs(R).max() < 1e-10 * P.max()  # round-off indeed
    # the same values without the floor: jumps (the largest |value| so far is round-off too)
    scales = {k: np.abs(R[:, i]).max() for i, k in enumerate(("Rx", "Rz"))}
    lams = [s["load_factor"] for s in st]
    raw = [m for i in range(1, len(st)) for m in jump_warnings(
        i, lams[i], lams[i - 1], None, None, st[i]["probes"], st[i - 1]["probes"], None, 3.0, scales)]
    assert raw and all("'Rx'" in m or "'Rz'" in m for m in raw)


def test_noise_floor_unit():
    """A probe whose two values are below its floor is no jump; above it the ratio counts."""
    assert jump_warnings(3, 0.75, 0.5, None, None, {"R": 5e-9}, {"R": 1e-10}, None, 3.0)
    assert not jump_warnings(3, 0.75, 0.5, None, None, {"R": 5e-9}, {"R": 1e-10}, None, 3.0, None, {"R": 1e-8})
    assert jump_warnings(3, 0.75, 0.5, None, None, {"R": 5e-7}, {"R": 1e-10}, None, 3.0, None, {"R": 1e-8})
    assert jump_warnings(3, 0.75, 0.5, None, None, {"R": 5e-9, "w": 5.0}, {"R": 1e-10, "w": 1.0}, None, 3.0, None,
                         {"R": 1e-8})  # other probes are unaffected
