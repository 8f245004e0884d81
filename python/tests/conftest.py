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
