"""Cost of the material laws per integration point (layershell.laws).

    python benchmarks/laws.py [--points 100000] [--repeat 3]

Random strain states around cracking and crushing of C30/37 (N, mm) from a committed state with
some damage; prints µs per point of ``ConcreteLaw.response`` with and without the tangent, of the
elastic stress ``eps @ C0`` for scale, and of the steel and textile laws. Timings on a shared
machine are noisy: compare runs at similar load (the load average is printed).
"""
from __future__ import annotations

import argparse
import os
import time

import numpy as np

from layershell.laws import ConcreteLaw, SteelLaw, TextileLaw


def best_of(fn, repeat):
    t = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        t.append(time.perf_counter() - t0)
    return min(t)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--points", type=int, default=100_000)
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args(argv)
    n, rng = a.points, np.random.default_rng(0)
    law = ConcreteLaw.from_class(30.0, length_unit=1e-3)
    eps = rng.uniform(-3e-3, 6e-4, (n, 6)) * rng.choice([0.05, 1.0], (n, 6))
    h_in, h_z, normal = np.full(n, 100.0), np.full(n, 20.0), np.tile([0.0, 0.0, 1.0], (n, 1))
    _, _, committed = law.response(0.7 * eps, law.state(n), h_in, h_z, normal, tangent=False)
    C0 = law.stiffness()
    rows = {
        "concrete response + tangent": lambda: law.response(eps, committed, h_in, h_z, normal),
        "concrete response, no tangent": lambda: law.response(eps, committed, h_in, h_z, normal, tangent=False),
        "elastic eps @ C0 (scale)": lambda: eps @ C0,
    }
    steel, textile = SteelLaw.from_grade("B500B"), TextileLaw.from_fibre("carbon")
    e1 = eps[:, 0] * 10
    s_state, t_state = steel.state(n), textile.state(n)
    rows["steel response + tangent"] = lambda: steel.response(e1, s_state)
    rows["textile response + tangent"] = lambda: textile.response(e1, t_state)
    print(f"points={n} repeat={a.repeat} load_average={os.getloadavg()[0]:.2f} "
          f"threads(OMP_NUM_THREADS)={os.environ.get('OMP_NUM_THREADS', 'unset')}")
    for name, fn in rows.items():
        print(f"{name:32s} {best_of(fn, a.repeat) / n * 1e6:8.3f} us/point")


if __name__ == "__main__":
    main()
