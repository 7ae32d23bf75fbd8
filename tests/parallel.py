"""How many pytest-xdist processes `make test` starts (``-n auto``; tests/conftest.py): one per
core this process may use, but no more than the CPU quota of its control group allows, and at
most one per 6 GiB of memory (a worker of the slow suite held 6.5 GB here).
A container on a large host can see all the host's cores in ``os.cpu_count()`` while its quota and
memory are those of a small machine; ``PYTEST_XDIST_AUTO_NUM_WORKERS`` overrides all of this."""
from __future__ import annotations

import os
from pathlib import Path

MEMORY_PER_WORKER = 6 * 1024**3


def auto_workers(cpus: int, cpu_quota: float | None = None, memory: float | None = None) -> int:
    """The processes for ``cpus`` usable cores, a CPU quota (cores; None: none) and ``memory``
    bytes (None: unknown)."""
    n = cpus
    if cpu_quota is not None:
        n = min(n, max(1, int(cpu_quota)))
    if memory is not None:
        n = min(n, max(1, int(memory // MEMORY_PER_WORKER)))
    return max(1, n)


def _read(path: str) -> str | None:
    try:
        return Path(path).read_text().strip()
    except OSError:
        return None


def this_machine() -> int:
    """:func:`auto_workers` for this process: its CPU affinity, the cgroup's ``cpu.max`` (v2) or
    ``cpu.cfs_quota_us`` (v1), and the smaller of the physical memory and the cgroup's limit."""
    cpus = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)
    quota = None
    v2 = _read("/sys/fs/cgroup/cpu.max")
    if v2 and not v2.startswith("max"):
        q, p = v2.split()[:2]
        quota = int(q) / int(p)
    else:
        q, p = _read("/sys/fs/cgroup/cpu/cpu.cfs_quota_us"), _read("/sys/fs/cgroup/cpu/cpu.cfs_period_us")
        if q and p and int(q) > 0:
            quota = int(q) / int(p)
    memory = None
    if hasattr(os, "sysconf") and "SC_PHYS_PAGES" in os.sysconf_names:
        memory = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    for limit in (_read("/sys/fs/cgroup/memory.max"), _read("/sys/fs/cgroup/memory/memory.limit_in_bytes")):
        if limit and limit.isdigit():
            memory = min(memory, int(limit)) if memory else int(limit)
    return auto_workers(cpus, quota, memory)
