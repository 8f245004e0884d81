"""pymavlink (pinned) decodes every MAVLink frame that proxform's agents send their autopilots, and
every frame the world's simulated vehicles send back, without a checksum error: a relay in this
test sits between each follower's `proxform-agent --mavlink` and its simulated vehicle
(`proxform world --mavlink-port`), parses every datagram both ways with pymavlink, and forwards
it unchanged. The agents fly their UAVs through the relays (the run passes: the world waits for
each step's setpoints within its allowance). Loopback only; every
process is ended by its id."""

from __future__ import annotations

import os
import pathlib
import select
import socket
import subprocess
import time

import pytest

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402
from pymavlink.dialects.v20 import common  # noqa: E402


def free_tcp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Relay:
    """World vehicle <-> agent, for one UAV: every datagram parsed by pymavlink, then forwarded."""

    def __init__(self, vehicle_port: int, agent_port: int) -> None:
        self.to_world = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.to_world.bind(("127.0.0.1", vehicle_port))  # where the world's vehicle sends
        self.to_agent = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
        self.to_agent.bind(("127.0.0.1", 0))
        self.agent = ("127.0.0.1", agent_port)
        self.world: tuple[str, int] | None = None
        self.parsers = {"world": common.MAVLink(None), "agent": common.MAVLink(None)}
        for p in self.parsers.values():
            p.robust_parsing = True
        self.seen: dict[str, dict[str, list]] = {"world": {}, "agent": {}}
        self.bad = {"world": 0, "agent": 0}

    def parse(self, side: str, data: bytes) -> None:
        for m in self.parsers[side].parse_buffer(data) or []:
            if m.get_type() == "BAD_DATA":
                self.bad[side] += 1
            else:
                self.seen[side].setdefault(m.get_type(), []).append(m)

    def pump(self, sock: socket.socket) -> None:
        data, addr = sock.recvfrom(65535)
        if sock is self.to_world:
            self.world = addr
            self.parse("world", data)
            self.to_agent.sendto(data, self.agent)
        else:
            self.parse("agent", data)
            if self.world is not None:
                self.to_world.sendto(data, self.world)

    def close(self) -> None:
        self.to_world.close()
        self.to_agent.close()


V6 = """
name = "multirotor-v6"
duration_s = 12.0
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
points_m = [[100.0, 0.0, 0.0], [100.0, 100.0, 0.0]]
turn_radius_m = 20.0
"""


@pytest.mark.parametrize("vehicle", ["multirotor", "paper"])
def test_pymavlink_decodes_every_frame_the_agents_and_the_vehicles_exchange(cli_net, tmp_path, vehicle, free_udp_base):
    # The multirotor's agents send velocity and yaw setpoints, the paper's kinematic vehicle's
    # attitude targets too. Both flights pass through the relays: the world waits for a step's
    # setpoints within its allowance (before, the relayed setpoints arrived just after the
    # agents' answers over Zenoh and each step was flown on the previous step's targets: the
    # paper's roll fell behind, 6.4 deg after 12 s).
    scenario = tmp_path / "v6.toml"
    scenario.write_text(V6)
    if vehicle == "paper":
        scenario = pathlib.Path(__file__).resolve().parents[2] / "scenarios" / "paper.toml"
    agent_bin = cli_net.parent / "proxform-agent"
    followers = [2, 3, 4, 5, 6]
    base, agents_base = free_udp_base(6), None
    for _ in range(20):
        agents_base = free_udp_base(5)
        if abs(agents_base - base) >= 6:
            break
    endpoint, swarm = f"tcp/127.0.0.1:{free_tcp_port()}", f"pymavlink-{os.getpid()}"
    relays = {u: Relay(base + u - 1, agents_base + u - 2) for u in followers}
    world = subprocess.Popen(
        [cli_net, "world", scenario, "--clock", "realtime", "--duration-s", "12", "--listen", endpoint, "--swarm", swarm,
         "--wait-agents-s", "30", "--mavlink-port", str(base), "--no-figures", "-q", "--out", tmp_path / "out"],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    procs = []
    try:
        time.sleep(0.5)
        for u in followers:
            procs.append(subprocess.Popen(
                [agent_bin, "--scenario", scenario, "--uav", str(u), "--swarm", swarm, "--connect", endpoint,
                 "--idle-exit-s", "5", "--mavlink", f"udpin:127.0.0.1:{agents_base + u - 2}"],
                stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
            ))
        socks = {r.to_world: r for r in relays.values()} | {r.to_agent: r for r in relays.values()}
        start = time.monotonic()
        while time.monotonic() - start < 90 and world.poll() is None:
            ready, _, _ = select.select(list(socks), [], [], 0.05)
            for s in ready:
                socks[s].pump(s)
        _, err = world.communicate(timeout=60)
        rc_err = (world.returncode, err.decode())
    finally:
        for p in [world, *procs]:
            if p.poll() is None:
                p.kill()
            p.wait()
        for r in relays.values():
            r.close()
    assert rc_err[0] == 0, rc_err[1]
    for u, r in relays.items():
        assert r.bad == {"world": 0, "agent": 0}, (u, r.bad)
        agent = r.seen["agent"]
        # The companion's heartbeat, its mode request (OFFBOARD), velocity and yaw setpoints and,
        # for the paper's kinematic vehicle, attitude targets: all from system u, component 191.
        sent = ["HEARTBEAT", "COMMAND_LONG", "SET_POSITION_TARGET_LOCAL_NED"]
        for t in sent + (["SET_ATTITUDE_TARGET"] if vehicle == "paper" else []):
            assert t in agent, (u, t, sorted(agent))
        for t, ms in agent.items():
            for m in ms:
                assert (m.get_srcSystem(), m.get_srcComponent()) == (u, 191), (u, t, m)
        assert len(agent["SET_POSITION_TARGET_LOCAL_NED"]) >= 80, (u, len(agent["SET_POSITION_TARGET_LOCAL_NED"]))
        for m in agent["SET_POSITION_TARGET_LOCAL_NED"]:
            assert m.target_system == u and m.coordinate_frame == mavutil.mavlink.MAV_FRAME_LOCAL_NED, m
        modes = {(m.command, int(m.param2)) for m in agent["COMMAND_LONG"]}
        assert (mavutil.mavlink.MAV_CMD_DO_SET_MODE, 6) in modes, modes  # PX4's OFFBOARD
        for t in ["HEARTBEAT", "LOCAL_POSITION_NED", "ATTITUDE", "GLOBAL_POSITION_INT", "COMMAND_ACK"]:
            assert t in r.seen["world"], (u, t, sorted(r.seen["world"]))
