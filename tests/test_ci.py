"""The CI time budget (tests/conftest.py, .ci/run): tests that would start after the budget are
skipped and listed, the others run; `make` runs the test files in parallel processes on one thread."""
import os
import subprocess
import sys
from pathlib import Path

import pytest

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


def test_the_list_of_tests_not_run_is_complete_from_parallel_workers():
    """`make test` runs the tests in pytest-xdist's worker processes: the budget is spent in the
    workers, the list is written by the main process, from their skip reports."""
    serial = _pytest("--time-budget", "0")
    parallel = _pytest("--time-budget", "0", "-n", "2", "--dist", "loadfile")
    names = [sorted(line for line in out.splitlines() if line.startswith("not run (time budget): "))
             for out in (serial, parallel)]
    assert names[0] and names[0] == names[1]


def test_without_a_budget_or_within_it_every_test_runs():
    for args in ((), ("--time-budget", "3600")):
        out = _pytest(*args)
        assert "skipped" not in out and "not run (time budget)" not in out and "passed" in out


def test_make_runs_the_test_files_in_parallel_processes_on_one_thread_each():
    """The slow tests are validated on one thread (README, Development): `make test` and
    `make test-slow` run pytest-xdist's processes with the thread variables at 1; `JOBS=0` runs
    in one process on the environment's threads."""
    import shutil

    from layershell.sweep import THREAD_VARS  # the variables a sweep's worker holds at one thread

    if not shutil.which("make"):
        pytest.skip("make is not installed")
    for target in ("test", "test-slow"):
        for jobs, parallel in (("auto", True), ("0", False)):
            dry = subprocess.run(["make", "-n", target, f"JOBS={jobs}"], cwd=ROOT,
                                 capture_output=True, text=True, timeout=60)
            line = [s for s in dry.stdout.splitlines() if "-m pytest" in s][-1]
            threads = all(f"{v}=1" in line for v in THREAD_VARS)
            assert threads == parallel and ("--dist loadfile" in line) == parallel, (target, jobs, line)
            assert (f"-n {jobs}" in line) == parallel, line


def test_the_parallel_processes_follow_the_cores_the_quota_and_the_memory():
    from parallel import MEMORY_PER_WORKER, auto_workers, this_machine

    assert auto_workers(2) == 2 and auto_workers(2, None, 24 * 1024**3) == 2
    assert auto_workers(64, 2.0, 24 * 1024**3) == 2  # a container's quota on a large host
    assert auto_workers(64, 1.5) == 1 and auto_workers(64, 0.5) == 1
    assert auto_workers(16, None, 3 * MEMORY_PER_WORKER + 1) == 3  # memory binds
    assert auto_workers(4, None, 1024**3) == 1
    assert 1 <= this_machine() <= (os.cpu_count() or 1)


def test_the_suite_runs_without_pytest_xdist():
    """tests/conftest.py implements an xdist hook; without the plugin pytest must not refuse it
    (it did, "no tests ran", before the hook was marked optional)."""
    out = _pytest("-p", "no:xdist")
    assert "passed" in out and "error" not in out.lower()
