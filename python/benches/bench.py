"""Benchmarks of the Python package, against the command line where both do the same work.

    .venv/bin/python python/benches/bench.py [--repeats 5] [--runs 1000] [--uavs 10000]

1. A batch of 6-UAV runs (the paper, no trajectories): per-run time from Python and from
   `proxform run --runs N` (the binary of this checkout), alternating, medians.
2. `Controller.step` for one UAV with 8 neighbours (a lattice's interior UAV, in its slot).
3. `Controllers.step` for every UAV of a lattice of --uavs UAVs, 8 nearest neighbours each:
   time per UAV.
Prints medians (and min/max) over the repeats. Run on an idle machine.
"""

from __future__ import annotations

import argparse
import pathlib
import statistics
import subprocess
import tempfile
import time

import numpy as np

import proxform

ROOT = pathlib.Path(__file__).resolve().parents[2]


def spread(xs: list[float]) -> str:
    return f"median {statistics.median(xs):.4g} (min {min(xs):.4g}, max {max(xs):.4g}, n {len(xs)})"


def nearest(states: np.ndarray, k: int) -> np.ndarray:
    """Indices of each UAV's k nearest others, by blocks of rows."""
    pos = states[:, :3]
    out = np.empty((len(pos), k), dtype=np.int64)
    for a in range(0, len(pos), 512):
        d = np.linalg.norm(pos[a : a + 512, None, :] - pos[None, :, :], axis=2)
        d[np.arange(d.shape[0]), np.arange(a, a + d.shape[0])] = np.inf
        out[a : a + 512] = np.argpartition(d, k, axis=1)[:, :k]
    return out


def steady_inputs(sc: proxform.Scenario, x: np.ndarray, nn: np.ndarray, i: int, steps: int, k0: int = 0) -> list:
    """Controller.step arguments of UAV i (0-based) for `steps` periods from period k0: the
    formation in steady flight, its 8 nearest as an (8, 10) array."""
    inputs = []
    for k in range(k0, k0 + steps):
        t = k * sc.dt_s
        own = x[i].copy()
        own[:3] += t * own[3:6]
        nb = np.column_stack([nn[i] + 1, x[nn[i]]])
        nb[:, 1:4] += t * nb[:, 4:7]
        inputs.append((t, own, nb))
    return inputs


def bench_runs(repeats: int, runs: int) -> None:
    cli = ROOT / "target" / "release" / "proxform"
    py, sh = [], []
    with tempfile.TemporaryDirectory() as out:
        for _ in range(repeats):
            t = time.perf_counter()
            proxform.run("paper", runs=runs, trajectories=False)
            py.append((time.perf_counter() - t) / runs * 1e3)
            t = time.perf_counter()
            subprocess.run(
                [cli, "run", "--runs", str(runs), "-q", "--no-figures", "--no-trajectories", "--out", out],
                check=True, stdout=subprocess.DEVNULL,
            )
            sh.append((time.perf_counter() - t) / runs * 1e3)
    print(f"paper run, batch of {runs}: Python {spread(py)} ms/run")
    print(f"paper run, batch of {runs}: CLI    {spread(sh)} ms/run")
    print(f"  ratio Python/CLI (medians): {statistics.median(py) / statistics.median(sh):.3f}")


def bench_controller(repeats: int) -> None:
    sc = proxform.load("swarm", uavs=100)
    x = sc.initial_states()
    nn = nearest(x, 8)
    # An interior UAV: the one whose 8 nearest are closest.
    i = int(np.argmin([np.linalg.norm(x[nn[j], :3] - x[j, :3], axis=1).max() for j in range(len(x))]))
    if i == sc.navigator - 1:
        i = (i + 1) % len(x)
    c = proxform.Controller(sc, i + 1)
    steps = 20_000
    per = []
    for r in range(repeats):
        # The inputs of every step built beforehand: only the calls are timed.
        inputs = steady_inputs(sc, x, nn, i, steps, r * steps)
        step = c.step
        start = time.perf_counter()
        for t, own, nb in inputs:
            step(t, own, nb)
        per.append((time.perf_counter() - start) / steps * 1e6)
    print(f"Controller.step, 8 neighbours (arrays): {spread(per)} µs/step")


def bench_controllers(repeats: int, uavs: int) -> None:
    sc = proxform.load("swarm", uavs=uavs)
    x = sc.initial_states()
    ctl = proxform.Controllers(sc)
    f = np.array(ctl.uavs) - 1
    nn = nearest(x, 8)[f]
    counts = np.full(len(f), 8, dtype=np.int64)
    ids = (nn + 1).reshape(-1)
    per = []
    for r in range(repeats + 1):
        t = r * sc.dt_s
        moved = x.copy()
        moved[:, :3] += t * moved[:, 3:6]
        own = moved[f]
        states = moved[nn.reshape(-1)]
        start = time.perf_counter()
        ctl.step(t, own, counts, ids, states)
        if r > 0:  # the first step builds the tracks
            per.append((time.perf_counter() - start) / len(f) * 1e6)
    print(f"Controllers.step, {len(f)} UAVs × 8 neighbours: {spread(per)} µs/UAV")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--uavs", type=int, default=10_000)
    args = ap.parse_args()
    bench_controller(args.repeats)
    bench_controllers(args.repeats, args.uavs)
    bench_runs(args.repeats, args.runs)


if __name__ == "__main__":
    main()
