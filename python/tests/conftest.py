"""Shared fixtures: the repository's paths and the `proxform` binary built by the test command."""

from __future__ import annotations

import os
import pathlib
import subprocess

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
def cli_net() -> pathlib.Path:
    """The command-line tool with the network agent, and proxform-agent beside it (cargo finds
    them up to date after the test command's `cargo test --all-features`)."""
    target = pathlib.Path(os.environ.get("CARGO_TARGET_DIR", ROOT / "target"))
    subprocess.run(
        ["cargo", "build", "--release", "-q", "--features", "net", "-p", "proxform-cli", "-p", "proxform-net"],
        cwd=ROOT, check=True, timeout=3600,
    )
    return target / "release" / "proxform"
