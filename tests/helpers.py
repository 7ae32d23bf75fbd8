"""Shared helpers for tests that run example files."""
from __future__ import annotations

from pathlib import Path

from layershell.io.build import build, parse
from layershell.runner import run

EXAMPLES = Path(__file__).resolve().parents[1] / "examples"


#: Equivalence of two nonlinear runs that iterate differently (another mesh numbering, another
#: contact algorithm) can only be claimed to the accuracy each is solved to. The examples use a
#: relative residual of 1e-8, which the plates' stiff bond and contact penalties amplify up to
#: ~30× into a probe (tests/test_plate_gmsh.py measured 3.3e-7 between two numberings, issue 16):
#: a bound below ~1e-6 on such runs tests round-off. Equivalence tests therefore solve both runs
#: with these [steps] lines (1e-12, with room for the extra contact iterations that takes) and
#: compare at TIGHT_BOUND: 30 × 1e-12 leaves a factor 30 for other machines' round-off, and a
#: wrong node, set or thickness changes the results by far more (test_plate_gmsh.py shows it).
TIGHT_STEPS = "tolerance = 1e-12\nmax_contact_iterations = 400"
TIGHT_BOUND = 1e-9


def stopped_and_restarted(spec, folder: Path, after: int):
    """Run ``spec`` into ``folder``, stopped as by Ctrl-C after step ``after``, then continue it
    there with ``restart``: ``(part, again)``, the two RunResults."""

    def stop(i, n, lam):
        if i == after:
            raise KeyboardInterrupt

    part = run(spec, folder, progress=stop, write_vtu=False)
    again = run(spec, folder, write_vtu=False, restart=folder)
    return part, again


def example_spec(name: str, replace: dict[str, str] | None = None):
    """The RunSpec of ``examples/<name>.toml`` with text replacements (each must occur)."""
    path = EXAMPLES / f"{name}.toml"
    text = path.read_text()
    for a, b in (replace or {}).items():
        assert a in text, f"{a!r} not in {name}.toml"
        text = text.replace(a, b)
    return build(parse(text, str(path)), path.parent)


def run_example(name: str, replace: dict[str, str] | None = None, out=None, newton: dict | None = None):
    """Run ``examples/<name>.toml`` (optionally with text replacements and Newton settings
    changed, e.g. ``newton={"semismooth_iterations": 0}``); return the RunResult."""
    spec = example_spec(name, replace)
    if newton:
        import dataclasses

        spec.newton = dataclasses.replace(spec.newton, **newton)
    return run(spec, out, write_vtu=False)


def fd_reduced_tangent(pb, ur, h=1e-6):
    """Reduced tangent Tᵀ K T of ``pb`` at ``T ur`` and its central finite difference."""
    import numpy as np

    T = pb.op.T
    _, K = pb.assembler.evaluate(T @ ur)
    Kr = (T.T @ K @ T).toarray()
    Kfd = np.zeros_like(Kr)
    for j in range(ur.size):
        e = np.zeros_like(ur)
        e[j] = h
        fp, _ = pb.assembler.evaluate(T @ (ur + e), tangent=False)
        fm, _ = pb.assembler.evaluate(T @ (ur - e), tangent=False)
        Kfd[:, j] = T.T @ (fp - fm) / (2 * h)
    return Kr, Kfd
