#!/usr/bin/env python3
"""Formation depth: does the error grow from the first rank to the last?

Runs a scenario with the proxform binary, groups the followers into ranks by their slot's
distance behind the navigator (slots within 1 m of each other share a rank), and prints, per
axis, the largest |error| of the first rank, of the last rank, and their ratio; the ratio of
the errors over the allowable errors (the largest over the axes) last.

    scripts/depth.py SCENARIO [--runs N] [--bin target/release/proxform]

Exits 1 when the last rank's largest error exceeds `--limit` (default 1.5) times the first's.
Needs only the Python standard library. Per-UAV detail covers the first 32 followers.
"""
import argparse
import json
import re
import subprocess
import sys
import tempfile
from pathlib import Path

AXES = ["x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"]


def slot_offsets(binary, scenario):
    """UAV number -> forward offset of its slot, from the resolved scenario."""
    text = subprocess.run([binary, "run", scenario, "--print-scenario"], check=True,
                          capture_output=True, text=True).stdout
    navigator = int(re.search(r"^navigator = (\d+)", text, re.M).group(1))
    forward = {}
    for block in text.split("[[formation.slot]]")[1:]:
        uav = int(re.search(r"^id = (\d+)", block, re.M).group(1))
        offset = re.search(r"^offset_m = \[([^\]]+)\]", block, re.M).group(1)
        forward[uav] = float(offset.split(",")[0])
    return navigator, forward


def ranks(navigator, forward):
    """Followers grouped by distance behind the navigator, nearest first."""
    behind = sorted((forward[navigator] - x, uav) for uav, x in forward.items() if uav != navigator)
    out = []
    for d, uav in behind:
        if out and d - out[-1][0] <= 1.0:
            out[-1][1].append(uav)
        else:
            out.append((d, [uav]))
    return [uavs for _, uavs in out]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenario")
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--limit", type=float, default=1.5)
    ap.add_argument("--bin", default="target/release/proxform")
    ap.add_argument("--threads", type=int, default=0, help="worker threads (0 = all cores)")
    a = ap.parse_args()
    navigator, forward = slot_offsets(a.bin, a.scenario)
    groups = ranks(navigator, forward)
    with tempfile.TemporaryDirectory() as out:
        # The binary exits 1 when some run fails its allowable errors: the summary is still written.
        run = subprocess.run([a.bin, "run", a.scenario, "--runs", str(a.runs), "--seed", str(a.seed),
                              "--threads", str(a.threads), "--out", out, "--no-figures", "--no-trajectories"],
                             capture_output=True, text=True)
        path = Path(out) / "summary.json"
        if not path.exists():
            sys.exit(run.stderr)
        summary = json.loads(path.read_text())
    worst = dict(zip(summary["per_uav"], summary["per_uav_worst"]))
    allowed = summary["allowable_error"]
    first, last = groups[0], groups[-1]
    if any(u not in worst for u in first + last):
        sys.exit("the first or last rank is beyond the per-UAV detail (first 32 followers)")

    def largest(rank, axis):
        return max(worst[u][axis] for u in rank)

    def normalised(rank):
        return max(largest(rank, ax) / allowed[ax] for ax in AXES)

    print(f"{a.scenario}: {len(groups)} ranks, first {first}, last {last}, {a.runs} runs")
    print(f"{'axis':<10}{'first':>10}{'last':>10}{'ratio':>8}")
    for ax in AXES:
        f, l = largest(first, ax), largest(last, ax)
        print(f"{ax:<10}{f:>10.3f}{l:>10.3f}{l / f:>8.2f}")
    f, l = normalised(first), normalised(last)
    print(f"{'/allowed':<10}{f:>10.3f}{l:>10.3f}{l / f:>8.2f}   (largest over the axes, each over its allowable error)")
    # Position alone: the largest over x, y, z in metres (an axis judged loosely, such as a
    # multirotor's pitch and roll, can dominate the line above).
    pf, pl = (max(largest(r, ax) for ax in AXES[:3]) for r in (first, last))
    print(f"{'position':<10}{pf:>10.3f}{pl:>10.3f}{pl / pf:>8.2f}   (largest over x, y, z, m)")
    print(f"pass fraction {summary['pass_fraction']:.3f}")
    sys.exit(0 if l <= a.limit * f else 1)


if __name__ == "__main__":
    main()
