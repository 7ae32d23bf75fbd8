"""The CI time budget (tests/conftest.py, .ci/run): tests that would start after the budget are
skipped and listed, the others run."""
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _pytest(*args: str) -> str:
    r = subprocess.run([sys.executable, "-m", "pytest", "-p", "no:cacheprovider", "-q", "-o", "addopts=",
                        "tests/test_formula.py", *args], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def test_a_spent_time_budget_skips_and_lists_the_tests_it_did_not_run():
    out = _pytest("--time-budget", "0")
    assert "passed" not in out and "tests not run: --time-budget 0 s spent" in out
    assert "not run (time budget): tests/test_formula.py::" in out


def test_without_a_budget_or_within_it_every_test_runs():
    for args in ((), ("--time-budget", "3600")):
        out = _pytest(*args)
        assert "skipped" not in out and "not run (time budget)" not in out and "passed" in out
