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
