"""A fixed amount of controller work, for instruction counts (python/benches/callgrind.sh):

    python steps.py single CALLS BUILT   CALLS of Controller.step, one UAV with 8 neighbours
    python steps.py many CALLS BUILT     CALLS of Controllers.step over a 1000-UAV lattice, 8 each

The arguments of BUILT calls are built beforehand (the formation in steady flight), the same
whatever CALLS is, so that the difference of two counts is the calls alone.
"""

from __future__ import annotations

import sys

import numpy as np

import proxform
from bench import nearest, steady_inputs


def main() -> None:
    mode, calls, built = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    sc = proxform.load("swarm", uavs=100 if mode == "single" else 1000)
    x = sc.initial_states()
    nn = nearest(x, 8)
    if mode == "single":
        i = 55 if sc.navigator != 56 else 56
        step = proxform.Controller(sc, i + 1).step
        for t, own, nb in steady_inputs(sc, x, nn, i, built)[:calls]:
            step(t, own, nb)
    else:
        ctl = proxform.Controllers(sc)
        f = np.array(ctl.uavs) - 1
        counts = np.full(len(f), 8, dtype=np.int64)
        ids = (nn[f] + 1).reshape(-1)
        inputs = []
        for k in range(built):
            t = k * sc.dt_s
            moved = x.copy()
            moved[:, :3] += t * moved[:, 3:6]
            inputs.append((t, moved[f], moved[nn[f].reshape(-1)]))
        for t, own, states in inputs[:calls]:
            ctl.step(t, own, counts, ids, states)


if __name__ == "__main__":
    main()
