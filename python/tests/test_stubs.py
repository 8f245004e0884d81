"""The type stubs describe the extension as built (mypy's stubtest), and the package
type-checks with them."""

from __future__ import annotations

import subprocess
import sys

from conftest import ROOT


def test_the_stubs_match_the_extension():
    r = subprocess.run(
        [sys.executable, "-m", "mypy.stubtest", "proxform._proxform", "--ignore-missing-stub", "--allowlist", "stubtest-allowlist.txt"],
        capture_output=True, text=True, timeout=600, cwd=ROOT / "python" / "tests",
    )
    assert r.returncode == 0, r.stdout + r.stderr


def test_the_examples_type_check_against_the_package():
    r = subprocess.run(
        [sys.executable, "-m", "mypy", "--no-incremental", "--cache-dir", "/dev/null", "examples"],
        capture_output=True, text=True, timeout=600, cwd=ROOT / "python",
    )
    assert r.returncode == 0, r.stdout + r.stderr
