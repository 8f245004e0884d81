"""MAVSDK (the MAVLink project's own SDK; PyPI `mavsdk`, pinned, a native binding with no server
process) connects to a distributed swarm's simulated vehicles (`--mavlink-port`) as it would to
PX4 SITL: it reads the navigator's position, equal to trajectories.csv in local NED, and flies
the navigator in OFFBOARD by velocity setpoints while the followers' proxform agents keep the
formation around it. Loopback only; the world is ended by its id."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import time

import pytest

mavsdk = pytest.importorskip("mavsdk")
from mavsdk import ComponentType, Configuration, Mavsdk  # noqa: E402
from mavsdk.plugins.offboard import Offboard, VelocityNedYaw  # noqa: E402
from mavsdk.plugins.telemetry import Telemetry  # noqa: E402

V6 = """
name = "multirotor-v6"
duration_s = 24.0
[vehicle]
model = "multirotor"
[formation.shape]
kind = "v"
uavs = 6
spacing_m = 8.0
angle_deg = 30.0
[path]
kind = "waypoints"
speed_kmh = 18.0
points_m = [[200.0, 0.0, 0.0]]
turn_radius_m = 20.0
"""


def test_mavsdk_reads_the_navigator_and_flies_it_in_offboard_while_the_followers_keep_formation(cli_net, tmp_path, free_udp_base):
    scenario = tmp_path / "v6.toml"
    scenario.write_text(V6)
    out = tmp_path / "out"
    base = free_udp_base(6)
    proc = subprocess.Popen(
        [cli_net, "run", scenario, "--distributed", "--clock", "realtime", "--mavlink-port", str(base),
         "--start-delay-s", "2", "--no-figures", "-q", "--out", out],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    drone = Mavsdk(Configuration.create_with_component_type(ComponentType.GROUND_STATION))
    seen: list[tuple[float, float, float]] = []
    try:
        # UAV 1, the navigator, sends to base + 0, as PX4 SITL's first instance to 14540.
        assert int(drone.add_any_connection(f"udpin://127.0.0.1:{base}")) == 0
        system = drone.first_autopilot(30.0)
        assert system is not None, f"no autopilot heard: {proc.poll()}"
        telemetry, offboard = Telemetry(system), Offboard(system)
        start = time.monotonic()
        flown = False
        while time.monotonic() - start < 60 and proc.poll() is None:
            pv = telemetry.position_velocity_ned()
            p = pv.position
            if not math.isnan(p.north_m):
                seen.append((p.north_m, p.east_m, p.down_m))
            # From about 5 s of flight, 8 s of 5 m/s north and 1.5 m/s east, at 10 Hz.
            elapsed = time.monotonic() - start
            if 7.0 < elapsed < 15.0:
                # A setpoint first (PX4 refuses OFFBOARD without a stream), then the mode.
                offboard.set_velocity_ned(VelocityNedYaw(5.0, 1.5, 0.0, 0.0))
                if not flown:
                    offboard.start()
                    flown = True
            time.sleep(0.1)
        _, err = proc.communicate(timeout=60)
        assert flown, err.decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        drone.destroy()
    err = err.decode()
    # Every position MAVSDK read is one of the navigator's rows of trajectories.csv, in local
    # NED (north = x, east = -y, down = -z), to a centimetre.
    with open(out / "trajectories.csv") as f:
        rows = [(float(r["x_m"]), -float(r["y_m"]), -float(r["z_m"])) for r in csv.DictReader(f) if r["uav"] == "1"]
    assert len(seen) > 100, len(seen)
    for p in seen:
        nearest = min(math.dist(p, q) for q in rows)
        assert nearest < 0.01, (p, nearest)
    # The navigator flew the setpoints: about 1.5 m/s × 7 s east of its path (which runs north).
    east = max(q[1] for q in rows)
    assert east > 8.0, east
    assert "flown by outside setpoints: UAV1 " in err, err
    # The followers kept their places around it (their allowable errors).
    summary = json.loads((out / "summary.json").read_text())
    allowed = summary["allowable_error"]
    for uav, worst in enumerate(summary["per_uav_worst"], start=1):
        if uav == 1:
            continue
        for axis in ("x_m", "y_m", "z_m"):
            assert worst[axis] <= allowed[axis], (uav, axis, worst[axis], err)
