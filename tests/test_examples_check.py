"""Every example model file validates (`layershell check`), without solving."""
import pytest
from helpers import EXAMPLES
from typer.testing import CliRunner

from layershell.cli import app

FILES = sorted(EXAMPLES.glob("*.toml"))


@pytest.mark.parametrize("path", FILES, ids=[p.stem for p in FILES])
def test_example_validates(path):
    res = CliRunner().invoke(app, ["check", str(path)])
    assert res.exit_code == 0, res.output
    assert "OK" in res.output


def test_check_names_how_the_steps_are_sized():
    """`layershell check` of a model whose steps are sized as it runs says so (arc length or
    adaptive load steps, the first increment and the largest number of increments) instead of
    counting fixed load steps."""
    res = CliRunner().invoke(app, ["check", str(EXAMPLES / "dcb_displacement.toml")])
    assert res.exit_code == 0, res.output
    assert "arc length to λ = 1 (first increment 0.01, at most 3000 increments)" in " ".join(res.output.split())
    res = CliRunner().invoke(app, ["check", str(EXAMPLES / "enf_cohesive.toml")])
    assert "adaptive load steps to λ = 1" in " ".join(res.output.split())
    res = CliRunner().invoke(app, ["check", str(EXAMPLES / "pulloff.toml")])
    assert "20 load step(s)" in " ".join(res.output.split())
