"""The examples run as users run them."""

from __future__ import annotations

import runpy
import sys

from conftest import EXAMPLES


def load(name):
    sys.path.insert(0, str(EXAMPLES))
    try:
        return runpy.run_path(str(EXAMPLES / f"{name}.py"), run_name="example")
    finally:
        sys.path.pop(0)


def test_figure5_draws_the_paper_figure(tmp_path):
    out = tmp_path / "fig5.png"
    worst = load("figure5")["main"]([str(out)])
    assert out.stat().st_size > 20_000
    assert 0.0 < worst <= 0.6


def test_the_point_mass_swarm_keeps_the_paper_formation():
    ratio = load("point_mass")["main"]([])
    assert 0.0 < ratio <= 1.0


def test_the_point_mass_swarm_without_the_controller_leaves_its_formation():
    # The same loop with every input discarded: the noise and the navigator's manoeuvres take
    # the followers out of their allowable errors, so the example's check can fail.
    ratio = load("point_mass")["main"](["--no-adjust", "--duration-s", "40"])
    assert ratio > 1.0
