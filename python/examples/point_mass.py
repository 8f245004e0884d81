"""A swarm simulated in Python, kept in formation by proxform's controller.

    python examples/point_mass.py [--seed S] [--duration-s T]

The paper's six UAVs are point masses integrated here in numpy: each step, every follower
measures its own state and its neighbours within the sensing range (with the scenario's
measurement noise), asks its `proxform.Controllers` entry for an input (velocity and attitude
changes), and this script applies it with an actuation error, as a simulator of your own would.
The navigator flies the scenario's path. Prints the largest error of each axis over the
flight against the allowable errors; returns the largest ratio (≤ 1: within them).
"""

from __future__ import annotations

import argparse

import numpy as np

import proxform


def simulate(seed: int = 1, duration_s: float | None = None, adjust: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """Flies the swarm; returns (largest |error| per axis x, y, z (m), α, β, γ (rad), allowable).
    ``adjust=False`` discards every input (as ``proxform run --no-adjust``)."""
    sc = proxform.load("paper")
    rng = np.random.default_rng(seed)
    dt, steps = sc.dt_s, sc.steps if duration_s is None else int(round(duration_s / sc.dt_s))
    nav = sc.navigator - 1
    sensing_range = sc.controller["sensing_range_m"]
    noise = sc.noise
    # Measurement noise per state component: position (m), velocity (m/s), attitude (rad).
    sigma = np.array([noise["position_m"]] * 3 + [noise["velocity_kmh"] / 3.6] * 3 + [np.radians(noise["attitude_deg"])] * 3)
    actuation = noise["actuation_error"]

    x = sc.initial_states()  # (6, 9) true states
    ctl = proxform.Controllers(sc)  # every follower
    followers = np.array(ctl.uavs) - 1
    warmup_s = sc.resolved()["warmup_s"]  # errors are judged after the warm-up, as in a run
    worst = np.zeros(6)
    for k in range(steps):
        t = k * dt
        # What each follower perceives: every other UAV within range, measured with noise.
        own = x[followers] + rng.normal(0.0, sigma, (len(followers), 9))
        counts: list[int] = []
        ids: list[int] = []
        states: list[np.ndarray] = []
        for i in followers:
            d = np.linalg.norm(x[:, :3] - x[i, :3], axis=1)
            seen = [j for j in range(len(x)) if j != i and d[j] <= sensing_range]
            counts.append(len(seen))
            ids.extend(j + 1 for j in seen)
            states.extend(x[j] + rng.normal(0.0, sigma) for j in seen)
        inputs, _ = ctl.step(
            t, own, np.array(counts, dtype=np.int64), np.array(ids, dtype=np.int64), np.array(states).reshape(-1, 9)
        )
        # The plant: a point mass whose velocity and attitude change by the input (with a
        # relative actuation error), position advancing with the mean velocity of the period.
        du = inputs * (1.0 + rng.uniform(-actuation, actuation, inputs.shape)) * adjust
        xf = x[followers]
        xf[:, 0:3] += dt * (xf[:, 3:6] + 0.5 * du[:, 0:3])
        xf[:, 3:6] += du[:, 0:3]
        xf[:, 6:9] += du[:, 3:6]
        x[followers] = xf
        x[nav] = sc.navigator_state(t + dt)
        if t + dt >= warmup_s:
            worst = np.maximum(worst, np.abs(sc.formation_errors(x)).max(axis=0))
    return worst, sc.allowable_errors()


def main(argv: list[str] | None = None) -> float:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--duration-s", type=float, default=None)
    ap.add_argument("--no-adjust", action="store_true", help="discard every input: shows the check failing")
    args = ap.parse_args(argv)
    worst, allowable = simulate(args.seed, args.duration_s, adjust=not args.no_adjust)
    names = ["x (m)", "y (m)", "z (m)", "α (deg)", "β (deg)", "γ (deg)"]
    scale = np.array([1, 1, 1, 180 / np.pi, 180 / np.pi, 180 / np.pi])
    for n, w, a, s in zip(names, worst, allowable, scale):
        print(f"{n:8} largest |error| {w * s:8.3f}   allowable {a * s:6.2f}")
    ratio = float((worst / allowable).max())
    print(f"largest error / allowable: {ratio:.3f} ({'within' if ratio <= 1 else 'OUTSIDE'} the allowable errors)")
    return ratio


if __name__ == "__main__":
    main()
