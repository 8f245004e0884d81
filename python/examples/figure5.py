"""The paper's Figure 5 from Python: the UAVs' lateral position y over time (a) and each
follower's y error relative to the navigator against the allowable error (b).

    python examples/figure5.py [OUT.png] [--seed S]

Runs the paper's experiment (one seed), takes the trajectories as numpy columns and draws them
with matplotlib. Prints the largest |y error| and whether every follower stayed within ±0.6 m.
"""

from __future__ import annotations

import argparse

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import proxform  # noqa: E402


def main(argv: list[str] | None = None) -> float:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", default="fig5_y.png")
    ap.add_argument("--seed", type=int, default=1)
    args = ap.parse_args(argv)

    result = proxform.run("paper", seed=args.seed)
    tr = result.trajectories
    assert tr is not None, "trajectories were asked for"
    allowable_y = result.summary["allowable_error"]["y_m"]
    navigator = result.scenario.navigator

    fig, (a, b) = plt.subplots(2, 1, figsize=(8, 7), sharex=True)
    worst = 0.0
    for uav in np.unique(tr["uav"]):
        rows = tr["uav"] == uav
        t, y, err = tr["t_s"][rows], tr["y_m"][rows], tr["err_y_m"][rows]
        a.plot(t, y, label=f"UAV{uav}", lw=1)
        if uav != navigator:
            b.plot(t, err, label=f"UAV{uav}", lw=0.8)
            worst = max(worst, float(np.abs(err).max()))
    for sign in (1, -1):
        b.axhline(sign * allowable_y, color="k", ls="--", lw=0.8)
    a.set_ylabel("y (m)")
    a.set_title("Figure 5 (a): lateral position")
    a.legend(ncol=3, fontsize=8)
    b.set_xlabel("t (s)")
    b.set_ylabel("y error (m)")
    b.set_title(f"Figure 5 (b): y error relative to the navigator, allowable ±{allowable_y} m")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"largest |y error| {worst:.3f} m (allowable {allowable_y} m): "
          f"{'within' if worst <= allowable_y else 'OUTSIDE'}; wrote {args.out}")
    return worst


if __name__ == "__main__":
    main()
