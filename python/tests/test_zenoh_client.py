"""An outside Python client (eclipse-zenoh, same minor version as the Rust crate) receives every
UAV's state from a running distributed swarm (loopback only, multicast scouting off)."""

from __future__ import annotations

import runpy
import socket
import subprocess
import threading

from conftest import EXAMPLES


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_the_client_receives_every_uavs_state(cli_net, tmp_path):
    client = runpy.run_path(str(EXAMPLES / "zenoh_client.py"), run_name="example")
    endpoint = f"tcp/127.0.0.1:{free_port()}"
    swarm = "pytest-client"
    proc = subprocess.Popen(
        [cli_net, "run", "--distributed", "--listen", endpoint, "--swarm", swarm, "--start-delay-s", "3",
         "--duration-s", "10", "--no-figures", "-q", "--out", tmp_path],
        stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
    )
    try:
        ready = threading.Event()
        result: dict = {}
        t = threading.Thread(target=lambda: result.update(client["listen"](endpoint, swarm, 8.0, ready)))
        t.start()
        t.join(timeout=60)
        _, err = proc.communicate(timeout=60)
        assert proc.returncode == 0, err.decode()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert sorted(result) == [1, 2, 3, 4, 5, 6], sorted(result)
    for uav, states in result.items():
        assert len(states) >= 50, (uav, len(states))
        # In time order (warm-up first, at negative times), ending at the flight's end.
        times = [t for _, t, _ in states]
        assert times == sorted(times) and times[-1] >= 9.8, (uav, times[-3:])
