"""Cost of an inelastic (concrete) layer against the elastic layer of the same geometry.

    python benchmarks/inelastic.py [--elements 2000] [--repeat 3] [--chunk 256] [--no-reference]
                                   [--element mitc full] [--d 1 2] [--points 3 6] [--cpu-time]

One tangent evaluation (internal forces + tangent, nonlinear kinematics) of one concrete layer
(C30/37, N and mm, 200 mm thick on a plate of 100 mm elements) over ``--elements`` elements in
chunks of ``--chunk`` as the assembly calls it, for d = 1, 2, the MITC9 and the fully integrated
element and 3 and 6 thickness points. The displacements are random with strains around cracking
and crushing, from a committed state with some damage (the state of 0.7 times them). Columns:

* ``cracked``: the share of the points with a crack in the committed state;
* ``elastic s``: :func:`layershell.element.kernel.layer_response` of the layer's elastic block;
* ``inelastic s``: :func:`layershell.element.inelastic.inelastic_response` (compiled point work);
* ``IMPL-EX s``: the same with the histories extrapolated from the virgin to the committed state
  (``implex``, the default integration of runs): the implicit update and the frozen-damage
  response;
* ``plain s``: the same through the kernels' plain NumPy forms (``fast=False``, the check);
* ``law s``: ``ConcreteLaw.response`` alone at the same points (its share of ``inelastic s``);
* ``with bars s``: the same concrete layer with two steel bar sheets (x and y, Ø12 at 200 mm,
  40 mm above the bottom face), the ratio to the elastic layer;
* ``ratio``: inelastic / elastic (and plain / elastic).

Best of ``--repeat``, the variants interleaved so that load changes on a shared machine hit all
alike; the load average is printed. ``--cpu-time``: the process's CPU time instead of the wall
time (on a shared machine the waits for a core are left out; meaningful with one kernel thread).
Threads: ``LAYERSHELL_THREADS`` as for the kernels.
"""
from __future__ import annotations

import argparse
import dataclasses
import os
import time

import numpy as np

from layershell.element.inelastic import (extrapolated_state, initial_state, inelastic_block, inelastic_response,
                                          put_trial)
from layershell.element.kernel import kernel_threads, layer_response
from layershell.laws import ConcreteLaw, SteelLaw
from layershell.material import Orthotropic
from layershell.mesh import rectangle
from layershell.threads import blas_single_thread

SIZE = 100.0  # element size, mm
THICK = 200.0  # layer thickness, mm
STRAIN = 1.5e-3  # scale of the random nodal displacements over the element size: strains ~ 1e-3
COVER, BARS = 40.0, 0.57  # bar sheets: height above the bottom face (mm), area per width (Ø12 @ 200 mm: mm²/mm)


_CLOCK = [time.perf_counter]  # the clock of _timed (--cpu-time: time.process_time)


def _timed(fn) -> float:
    t0 = _CLOCK[0]()
    fn()
    return _CLOCK[0]() - t0


def case(X, d: int, element: str, nz: int, law, chunk: int, repeat: int, reference: bool) -> dict:
    ne = X.shape[0]
    H = np.full((ne, 9), THICK)
    blk = inelastic_block(X, np.zeros((ne, 9)), H, d, _mat(law), law, (), nz, element)
    steel = SteelLaw.from_grade("B500B")
    rc = inelastic_block(X, np.zeros((ne, 9)), H, d, _mat(law), law,
                         tuple((f"bars {k}", steel, COVER, BARS, 0.0, v) for k, v in (("x", (1, 0, 0)), ("y", (0, 1, 0)))),
                         nz, element)
    rng = np.random.default_rng(1)
    U = np.zeros((ne, 9 * (d + 1), 3))
    U[:, :: d + 1] = STRAIN * SIZE * rng.standard_normal((ne, 9, 3))  # director 0: displacement
    U[:, 1:: d + 1] = STRAIN * rng.standard_normal((ne, 9, 3)) * (THICK / SIZE)  # director 1: rotation
    c0 = initial_state(blk)
    committed = c0.copy()
    for s in range(0, ne, chunk):
        sl = slice(s, min(s + chunk, ne))
        put_trial(committed, blk, sl, inelastic_response(blk, 0.7 * U[sl], True, False, sl, c0)[2])

    ex = extrapolated_state(blk, c0, committed, 1.0)

    def run(fast=True, b=blk, c=committed, implex=None):
        for s in range(0, ne, chunk):
            sl = slice(s, min(s + chunk, ne))
            inelastic_response(b, U[sl], True, True, sl, c, implex, fast=fast)

    c_rc = initial_state(rc)
    c_rc.bulk, c_rc.strain = committed.bulk, committed.strain  # the bulk's damage, virgin bars

    def run_elastic():
        for s in range(0, ne, chunk):
            sl = slice(s, min(s + chunk, ne))
            layer_response(blk.base, U[sl], True, True, sl)

    strain = np.concatenate([inelastic_response(blk, U[sl], True, False, sl, committed)[2].strain
                             for sl in (slice(s, min(s + chunk, ne)) for s in range(0, ne, chunk))])
    P = blk.n_points
    hin, hz, nrm = blk.h_in.ravel(), blk.h_z.ravel(), blk.normal.reshape(-1, 3)

    def run_law():
        for s in range(0, ne, chunk):
            p = slice(s * P, min(s + chunk, ne) * P)
            law.response(strain[p], _slice_state(committed.bulk, p), hin[p], hz[p], nrm[p], True)

    run(), run_elastic(), run_law(), run(b=rc, c=c_rc)
    t = {"elastic": [], "inelastic": [], "implex": [], "plain": [], "law": [], "rc": []}
    for _ in range(repeat):
        t["elastic"].append(_timed(run_elastic))
        t["inelastic"].append(_timed(run))
        t["implex"].append(_timed(lambda: run(implex=ex)))
        t["rc"].append(_timed(lambda: run(b=rc, c=c_rc)))
        t["law"].append(_timed(run_law))
        if reference:  # BLAS single-threaded as in the compiled path (threaded BLAS on its small products
            with blas_single_thread():  # only waits on a busy machine)
                t["plain"].append(_timed(lambda: run(False)))
    out = {k: min(v) for k, v in t.items() if v}
    cracked = float(np.mean(committed.bulk.h_t > 0))
    return dict(d=d, element=element, points=nz if element == "full" else max(nz, d + 1), cracked=cracked, **out)


def _slice_state(state, p):
    return dataclasses.replace(state, **{f.name: getattr(state, f.name)[p] for f in dataclasses.fields(state)})


def _mat(law):
    """The law's undamaged elasticity (the elastic layer compared against, and the block's stand-in)."""
    return Orthotropic.isotropic(law.E, law.nu)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--elements", type=int, default=2000)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--chunk", type=int, default=256)
    ap.add_argument("--no-reference", action="store_true", help="leave out the plain NumPy forms")
    ap.add_argument("--element", nargs="+", default=["mitc", "full"], choices=["mitc", "full"])
    ap.add_argument("--d", nargs="+", type=int, default=[1, 2])
    ap.add_argument("--points", nargs="+", type=int, default=[3, 6], help="thickness points")
    ap.add_argument("--cpu-time", action="store_true", help="process CPU time instead of wall time")
    a = ap.parse_args(argv)
    if a.cpu_time:
        _CLOCK[0] = time.process_time
    side = int(np.ceil(np.sqrt(a.elements)))
    mesh = rectangle(SIZE * side, SIZE * side, side, side)
    X = mesh.nodes[mesh.elements][: a.elements]
    law = ConcreteLaw.from_class(30.0, length_unit=1e-3)
    print(f"elements={len(X)} chunk={a.chunk} repeat={a.repeat} threads={kernel_threads()} "
          f"clock={'cpu' if a.cpu_time else 'wall'} load_average={os.getloadavg()[0]:.2f}")
    head = ("| d | element | points | cracked | elastic s | inelastic s | ratio | IMPL-EX s (ratio) | law s (share) | "
            "with bars s (ratio) |")
    if not a.no_reference:
        head += " plain s | plain ratio |"
    print(head)
    print("|" + "---|" * (head.count("|") - 1))
    for element in a.element:
        for d in a.d:
            for nz in a.points:
                r = case(X, d, element, nz, law, a.chunk, a.repeat, not a.no_reference)
                row = (f"| {r['d']} | {r['element']} | {r['points']} | {r['cracked']:.2f} | {r['elastic']:.3f} | "
                       f"{r['inelastic']:.3f} | {r['inelastic'] / r['elastic']:.2f} | "
                       f"{r['implex']:.3f} ({r['implex'] / r['elastic']:.2f}) | "
                       f"{r['law']:.3f} ({r['law'] / r['inelastic']:.2f}) | {r['rc']:.3f} ({r['rc'] / r['elastic']:.2f}) |")
                if "plain" in r:
                    row += f" {r['plain']:.3f} | {r['plain'] / r['elastic']:.2f} |"
                print(row, flush=True)


if __name__ == "__main__":
    main()
