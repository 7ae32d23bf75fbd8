import os
import time

import numpy as np
import pytest

from layershell.element.shape import NODE_XI


@pytest.fixture
def rng():
    return np.random.default_rng(1234)


def curved_element(rng, R=3.0, distort=0.1):
    """One distorted 9-node element on a cylinder of radius R (nodes moved inside the element)."""
    xi = NODE_XI + distort * rng.standard_normal((9, 2)) * (np.abs(NODE_XI) < 1)
    phi = 0.3 * xi[:, 0]
    y = 0.5 * xi[:, 1] + 0.1 * xi[:, 0]
    return np.stack([R * np.sin(phi), y, R * np.cos(phi)], -1)[None]


def flat_distorted_element(rng, distort=0.15):
    xi = NODE_XI + distort * rng.standard_normal((9, 2)) * (np.abs(NODE_XI) < 1)
    X = np.stack([2.0 * xi[:, 0] + 0.3 * xi[:, 1], 1.5 * xi[:, 1], 0 * xi[:, 0]], -1)
    return X[None]


# --- parallel processes (`make test`: pytest-xdist's -n auto) ----------------------------------------

@pytest.hookimpl(tryfirst=True, optionalhook=True)  # optional: without pytest-xdist
def pytest_xdist_auto_num_workers(config):
    """One process per usable core, within the CPU quota and one per 6 GiB (tests/parallel.py)."""
    if os.environ.get("PYTEST_XDIST_AUTO_NUM_WORKERS"):
        return None  # xdist's own hook reads it
    from parallel import this_machine

    return this_machine()


# --- a time budget for CI -------------------------------------------------------------------------
# CI stops a job after 90 minutes, and the time of the slow suite on its 2-core machines has varied
# from 40 to 79 minutes (fast and slow suites together) with the same code. `--time-budget S`: a test
# that would start more than S seconds after the session started is skipped, named as such in the
# summary - the tests that ran are not lost with a killed job (.ci/run).

_BUDGET_REASON = "the session's --time-budget was spent before this test started"
_START = pytest.StashKey[float]()


def pytest_addoption(parser):
    parser.addoption("--time-budget", type=float, default=None, metavar="SECONDS",
                     help="skip the tests that would start more than SECONDS after the session started "
                          "(each is reported as skipped, with the budget named)")


def pytest_configure(config):
    config.stash[_START] = time.monotonic()


def pytest_runtest_setup(item):
    budget = item.config.getoption("--time-budget")
    if budget is not None and time.monotonic() - item.config.stash[_START] > budget:
        pytest.skip(f"{_BUDGET_REASON} ({budget:.0f} s)")


def pytest_terminal_summary(terminalreporter, config):
    # from the skip reports, so that the list is complete when pytest-xdist's worker processes ran the
    # tests (`make test`): each worker measures the budget from its own start
    skipped = [r.nodeid for r in terminalreporter.stats.get("skipped", [])
               if isinstance(r.longrepr, tuple) and _BUDGET_REASON in str(r.longrepr[-1])]
    if skipped:
        terminalreporter.write_sep("=", f"{len(skipped)} tests not run: --time-budget "
                                        f"{config.getoption('--time-budget'):.0f} s spent", yellow=True)
        for nodeid in skipped:
            terminalreporter.write_line(f"not run (time budget): {nodeid}")
