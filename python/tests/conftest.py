"""Shared fixtures: the repository's paths and the `proxform` binary built by the test command."""

from __future__ import annotations

import os
import pathlib
import socket
import subprocess
from typing import Callable

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENARIOS = ROOT / "crates" / "proxform-scenario" / "scenarios"
EXAMPLES = ROOT / "python" / "examples"


@pytest.fixture(scope="session")
def cli() -> pathlib.Path:
    """The command-line tool of this checkout (target/release/proxform, built if missing)."""
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary = target / "release" / "proxform"
    if not binary.exists():
        subprocess.run(["cargo", "build", "--release", "-q", "-p", "proxform-cli"], cwd=ROOT, check=True, timeout=1800)
    return binary


@pytest.fixture(scope="session")
def cli_net(tmp_path_factory) -> pathlib.Path:
    """The command-line tool with the network agent, and proxform-agent beside it: as the test
    command's `cargo test --all-features` built them, or built here when missing or built
    without the network agent."""
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    binary, agent = target / "release" / "proxform", target / "release" / "proxform-agent"

    def works() -> bool:
        if not (binary.exists() and agent.exists()):
            return False
        probe = subprocess.run(
            [binary, "run", "--distributed", "--duration-s", "0.2", "--no-figures", "-q", "--out",
             tmp_path_factory.mktemp("probe")],
            capture_output=True, timeout=120,
        )
        return probe.returncode == 0

    if not works():
        subprocess.run(
            ["cargo", "build", "--release", "-q", "--features", "net", "-p", "proxform-cli", "-p", "proxform-net"],
            cwd=ROOT, check=True, timeout=3600,
        )
    return binary


def _free_udp_base(n: int) -> int:
    """A loopback UDP port p with p .. p + n - 1 all free (one per MAVLink vehicle)."""
    for _ in range(50):
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
            s.bind(("127.0.0.1", 0))
            base = s.getsockname()[1]
        if base > 60000:
            continue
        socks = []
        try:
            for i in range(n):
                t = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
                socks.append(t)
                t.bind(("127.0.0.1", base + i))
            return base
        except OSError:
            continue
        finally:
            for t in socks:
                t.close()
    raise RuntimeError("no free UDP ports")


@pytest.fixture
def free_udp_base() -> Callable[[int], int]:
    """Finds `n` consecutive free loopback UDP ports: `free_udp_base(n)` is the first."""
    return _free_udp_base
