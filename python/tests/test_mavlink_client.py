"""pymavlink (pinned) listens where PX4 SITL's offboard programs listen, one UDP port per UAV,
while a distributed swarm runs with `--mavlink-port`: every UAV is a MAVLink 2 system that
pymavlink decodes without a checksum error, says its state, origin and mode, and answers a
mode command (OFFBOARD refused while no setpoints stream). Loopback only; the world is ended
by its id."""

from __future__ import annotations

import math
import os
import subprocess
import time

os.environ["MAVLINK20"] = "1"
from pymavlink import mavutil  # noqa: E402

R = 6_371_000.0


def ned_of(lat0: float, lon0: float, lat: float, lon: float) -> tuple[float, float]:
    """PX4's azimuthal equidistant projection about (lat0, lon0), degrees in, metres out."""
    la0, lo0, la, lo = map(math.radians, (lat0, lon0, lat, lon))
    cos_d = math.cos(lo - lo0)
    c = math.acos(max(-1.0, min(1.0, math.sin(la0) * math.sin(la) + math.cos(la0) * math.cos(la) * cos_d)))
    k = c / math.sin(c) if c > 0 else 1.0
    n = k * (math.cos(la0) * math.sin(la) - math.sin(la0) * math.cos(la) * cos_d) * R
    e = k * math.cos(la) * math.sin(lo - lo0) * R
    return n, e


def test_every_uav_is_a_mavlink_system_pymavlink_decodes(cli_net, tmp_path, free_udp_base):
    base = free_udp_base(6)
    conns = [mavutil.mavlink_connection(f"udpin:127.0.0.1:{base + i}", source_system=255) for i in range(6)]
    proc = subprocess.Popen(
        [cli_net, "run", "--distributed", "--clock", "realtime", "--mavlink-port", str(base), "--duration-s", "8",
         "--no-figures", "-q", "--out", tmp_path],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    seen: list[dict[str, object]] = [{} for _ in range(6)]
    local: list[dict[int, tuple[float, float]]] = [{} for _ in range(6)]
    globs: list[list] = [[] for _ in range(6)]
    bad = 0
    acks = []
    asked = False
    try:
        start = time.monotonic()
        while time.monotonic() - start < 90 and proc.poll() is None:
            idle = True
            for i, c in enumerate(conns):
                m = c.recv_match(blocking=False)
                if m is None:
                    continue
                idle = False
                t = m.get_type()
                if t == "BAD_DATA":
                    bad += 1
                    continue
                assert m.get_srcSystem() == i + 1 and m.get_srcComponent() == 1, (i, m)
                seen[i][t] = m
                if t == "LOCAL_POSITION_NED":
                    local[i][m.time_boot_ms] = (m.x, m.y)
                if t == "GLOBAL_POSITION_INT":
                    globs[i].append(m)
                if t == "COMMAND_ACK":
                    acks.append(m)
            if not asked and all("LOCAL_POSITION_NED" in s for s in seen):
                # OFFBOARD for UAV 3 without a setpoint stream: refused, as PX4 refuses it.
                conns[2].mav.command_long_send(3, 1, mavutil.mavlink.MAV_CMD_DO_SET_MODE, 0, 1, 6, 0, 0, 0, 0, 0)
                asked = True
            if idle:
                time.sleep(0.005)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err.decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for c in conns:
            c.close()
    assert bad == 0
    for i, s in enumerate(seen):
        for t in ["HEARTBEAT", "LOCAL_POSITION_NED", "ATTITUDE", "GLOBAL_POSITION_INT", "HOME_POSITION",
                  "GPS_GLOBAL_ORIGIN"]:
            assert t in s, (i + 1, t, sorted(s))
        hb = s["HEARTBEAT"]
        assert hb.autopilot == mavutil.mavlink.MAV_AUTOPILOT_PX4 and hb.custom_mode == (4 << 16) | (3 << 24), hb
        # The global position is the local one of the same instant, projected about the origin
        # (1e-7 degrees are ~1 cm).
        home = s["GPS_GLOBAL_ORIGIN"]
        pairs = [(g, local[i][g.time_boot_ms]) for g in globs[i] if g.time_boot_ms in local[i]]
        assert len(pairs) >= 20, (i + 1, len(pairs))
        for g, (x, y) in pairs:
            n, e = ned_of(home.latitude * 1e-7, home.longitude * 1e-7, g.lat * 1e-7, g.lon * 1e-7)
            assert math.hypot(n - x, e - y) < 0.02, (i + 1, n, e, x, y)
    assert [a.result for a in acks] == [mavutil.mavlink.MAV_RESULT_DENIED], acks
