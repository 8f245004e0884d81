"""Scenarios from Python: every source gives the same checked scenario, and every bad input
raises ScenarioError naming its key (and its line, for text)."""

from __future__ import annotations

import os

import numpy as np
import pytest

import proxform
from proxform import ScenarioError

from conftest import SCENARIOS


def test_every_source_gives_the_same_scenario():
    text = (SCENARIOS / "paper.toml").read_text()
    by_name = proxform.load("paper")
    by_path = proxform.load(SCENARIOS / "paper.toml")
    by_str_path = proxform.load(str(SCENARIOS / "paper.toml"))
    by_text = proxform.load(text)
    resolved = by_name.resolved()
    for other in (by_path, by_str_path, by_text):
        got = other.resolved()
        got["name"] = resolved["name"]
        assert got == resolved
    # A dict: the resolved values of one scenario build the same scenario again.
    assert proxform.load(resolved).resolved() == resolved
    # to_toml() loads again to the same scenario.
    assert proxform.load(by_name.to_toml()).resolved() == resolved


def test_resolved_values_are_attributes():
    sc = proxform.load("paper")
    assert (sc.name, sc.uavs, sc.dt_s, sc.duration_s, sc.steps, sc.navigator) == ("paper", 6, 0.1, 100.0, 1000, 1)
    assert sc.controller["lambda"] == 0.8
    assert sc.allowable["y_m"] == 0.6
    assert np.allclose(sc.allowable_errors(), [0.5, 0.6, 0.2, *np.radians([0.4, 0.3, 1.0])])
    assert sc.initial_states().shape == (6, 9)
    with pytest.raises(AttributeError, match="no key"):
        sc.no_such_key
    assert proxform.load("swarm", uavs=50).uavs == 50


def test_with_values_changes_a_value_and_checks_it():
    sc = proxform.load("paper")
    short = sc.with_values({"duration_s": 20, "controller": {"lambda": 0.5}})
    assert (short.duration_s, short.controller["lambda"], short.controller["rho"]) == (20.0, 0.5, sc.controller["rho"])
    with pytest.raises(ScenarioError) as e:
        sc.with_values({"controller": {"lambda": 2.0}})
    assert e.value.key == "controller.lambda"


@pytest.mark.parametrize(
    "changes, key, words",
    [
        ({"controller": {"lambda": "high"}}, "controller.lambda", "expected a number"),
        ({"controller": {"lambda": 1.5}}, "controller.lambda", ""),
        ({"controller": {"lamda": 0.5}}, "controller.lamda", "unknown key"),
        ({"dt_s": -0.1}, "dt_s", ""),
        ({"duration_s": float("nan")}, "duration_s", ""),
        ({"duration_s": None}, "duration_s", "None"),
        ({"controller": {"areas": 2**70}}, "controller.areas", "out of range"),
        ({"fault": [{"kind": "remove", "uav": 2, "at_s": 10}, {"kind": "remove", "uav": 99, "at_s": 5}]}, "fault[2]", ""),
        ({"formation": {1: 2}}, "formation", ""),
        ({"controller": {"lambda": object()}}, "controller.lambda", "not object"),
        ({"engine": "warp"}, "engine", "unknown engine"),
        ({"engine": "fast", "controller": {"method": "consensus"}}, "engine", "does not run a baseline method"),
    ],
)
def test_a_bad_dict_names_its_key(changes, key, words):
    spec = proxform.load("paper").resolved()
    for k, v in changes.items():
        if isinstance(v, dict) and isinstance(spec.get(k), dict):
            spec[k].update(v)
        else:
            spec[k] = v
    with pytest.raises(ScenarioError) as e:
        proxform.load(spec)
    assert e.value.key is not None and e.value.key.startswith(key), (e.value.key, str(e.value))
    assert words in str(e.value)
    assert e.value.line is None and e.value.source == "<dict>"
    assert isinstance(e.value, ValueError)


def test_errors_in_text_name_the_line():
    text = "name = 'x'\n[controller]\nareas = 8\nlambda = 7.0\n"
    with pytest.raises(ScenarioError) as e:
        proxform.load(text)
    assert (e.value.key, e.value.line, e.value.source) == ("controller.lambda", 4, "<string>")
    assert "<string>:4" in str(e.value)


def test_files_that_are_not_scenarios_are_refused_before_reading(tmp_path):
    with pytest.raises(ScenarioError, match="cannot read"):
        proxform.load(tmp_path / "missing.toml")
    with pytest.raises(ScenarioError, match="not a regular file"):
        proxform.load(tmp_path)
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    with pytest.raises(ScenarioError, match="not a regular file"):
        proxform.load(fifo)
    binary = tmp_path / "bin.toml"
    binary.write_bytes(b"name = '\xff\xfe'\n")
    with pytest.raises(ScenarioError, match="UTF-8"):
        proxform.load(binary)
    big = tmp_path / "big.toml"
    with open(big, "wb") as f:
        f.truncate((16 << 20) + 1)
    with pytest.raises(ScenarioError, match="MiB"):
        proxform.load(big)


def test_other_types_are_refused():
    with pytest.raises(TypeError):
        proxform.load(42)
    with pytest.raises(ScenarioError, match="keys must be text"):
        proxform.load({("a",): 1})
    with pytest.raises(ScenarioError):
        proxform.Scenario.builtin("no-such-scenario")


def test_values_that_contain_themselves_or_nest_without_end_are_refused_at_once():
    import time

    loop: dict = {"controller": {}}
    loop["controller"]["lambda"] = loop
    items: list = []
    items.append(items)
    deep: dict = {}
    d = deep
    for _ in range(30_000):
        d["x"] = {}
        d = d["x"]
    for value in ({"name": "x", "formation": loop}, {"fault": items}, {"wind": deep}):
        started = time.monotonic()
        # It killed the interpreter (a stack overflow), or took seconds and gigabytes.
        with pytest.raises(ScenarioError, match="nested more than"):
            proxform.load(value)
        assert time.monotonic() - started < 2
