"""A verdict no one else can fake: the agent of UAV 3 is killed before a sealed lockstep
flight starts, and a process without the flight's key holds UAV 3's liveliness token and
replays UAV 3's own sealed membership messages throughout. The UAV is flown by nobody, so the
run fails and says it flew uncontrolled (before: PASS on a straight path, where holding its
course kept it in place)."""

import os
import pathlib
import signal
import socket
import subprocess
import threading
import time

import pytest

zenoh = pytest.importorskip("zenoh")

DATA = pathlib.Path(__file__).parent / "data"


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def children(pid: int) -> list:
    """The processes whose parent is `pid`, with their command lines."""
    out = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            stat = pathlib.Path(f"/proc/{entry}/stat").read_text()
            ppid = int(stat.rsplit(")", 1)[1].split()[1])
            cmd = pathlib.Path(f"/proc/{entry}/cmdline").read_bytes().split(b"\0")
        except (OSError, ValueError, IndexError):
            continue
        if ppid == pid:
            out.append((int(entry), [c.decode(errors="replace") for c in cmd]))
    return out


def test_a_replayed_membership_cannot_make_an_unflown_uav_pass(cli_net, tmp_path):
    port, swarm = free_port(), f"replay{os.getpid()}"
    endpoint = f"tcp/127.0.0.1:{port}"
    world = subprocess.Popen(
        [cli_net, "run", str(DATA / "straight20.toml"), "--distributed", "--seed", "3", "--no-figures", "-q",
         "--listen", endpoint, "--swarm", swarm, "--start-delay-s", "6", "--step-deadline-s", "0.05",
         "--agent-restarts", "0", "--out", str(tmp_path / "out")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )
    session = None
    try:
        conf = zenoh.Config()
        conf.insert_json5("mode", '"client"')
        conf.insert_json5("connect/endpoints", f'["{endpoint}"]')
        conf.insert_json5("scouting/multicast/enabled", "false")
        conf.insert_json5("connect/timeout_ms", "10000")
        prefix = f"proxform/v1/{swarm}"
        deadline = time.monotonic() + 20
        while session is None and time.monotonic() < deadline:
            try:
                session = zenoh.open(conf)
            except Exception:
                time.sleep(0.3)
        assert session is not None, "the rogue reaches the router"
        last = {}

        def overheard(sample):
            last["member"] = sample.payload.to_bytes()

        session.declare_subscriber(f"{prefix}/member/3", overheard)
        token = session.liveliness().declare_token(f"{prefix}/alive/3")
        # UAV 3's agent, killed before the flight starts (by its id).
        agent = None
        while agent is None and time.monotonic() < deadline:
            time.sleep(0.2)
            for pid, cmd in children(world.pid):
                if "--uavs" in cmd and cmd[cmd.index("--uavs") + 1] == "3" and "member" in last:
                    agent = pid
        assert agent is not None, "UAV 3's agent started and announced itself"
        os.kill(agent, signal.SIGKILL)
        stop = threading.Event()

        def replay():
            while not stop.is_set():
                session.put(f"{prefix}/member/3", last["member"])
                stop.wait(0.2)

        thread = threading.Thread(target=replay, daemon=True)
        thread.start()
        try:
            out, err = world.communicate(timeout=120)
        finally:
            stop.set()
            thread.join(5)
            token.undeclare()
    finally:
        if world.poll() is None:
            world.kill()
            world.wait()
        if session is not None:
            session.close()
    assert world.returncode == 1, out + err
    assert "uncontrolled followers: UAV3" in err, err
    assert "0 of 1 runs" in out, out
