"""Hostile input from Python: random mutations of a valid scenario dict and random controller
inputs either work or raise the package's errors; no Rust panic ever reaches Python (a
pyo3 PanicException is a BaseException, which these tests would not catch)."""

from __future__ import annotations

import copy
import math
import random

import numpy as np
import pytest

import proxform
from proxform import ScenarioError

NASTY = [
    -1, 0, 1, 2**63 - 1, -(2**63), 1e308, -1e308, float("nan"), float("inf"), -float("inf"), 1e-320,
    "", "x" * 10_000, "∞", True, False, [], {}, [1e308] * 3, [float("nan")] * 3, [[]], [{}], {"a": 1},
    list(range(1000)), [-1.0, 0.0, 1.0],
]


def leaves(d, path=()):
    if isinstance(d, dict):
        for k, v in d.items():
            yield from leaves(v, path + (k,))
    elif isinstance(d, list) and d and all(isinstance(x, dict) for x in d):
        for i, v in enumerate(d):
            yield from leaves(v, path + (i,))
    else:
        yield path


def put(d, path, value):
    for k in path[:-1]:
        d = d[k]
    d[path[-1]] = value


def test_mutated_scenarios_load_or_raise_scenario_errors():
    base = proxform.load("paper").resolved()
    base["duration_s"] = 2.0
    paths = list(leaves(base))
    rng = random.Random(17)
    loaded = refused = 0
    for _ in range(400):
        spec = copy.deepcopy(base)
        for _ in range(rng.randint(1, 3)):
            put(spec, rng.choice(paths), copy.deepcopy(rng.choice(NASTY)))
        try:
            sc = proxform.load(spec)
        except ScenarioError as e:
            refused += 1
            assert e.key, f"an error without a key: {e}"
            continue
        loaded += 1
        # What loads also flies (briefly), without a panic.
        if sc.steps <= 200 and sc.uavs <= 50:
            r = proxform.run(sc, trajectories=False, threads=1)
            assert 0.0 <= r.pass_fraction <= 1.0
    assert refused > 200 and loaded > 0, (loaded, refused)


def test_random_controller_inputs_never_panic():
    sc = proxform.load("paper")
    rng = np.random.default_rng(3)
    values = np.array([0.0, 1.0, -1.0, 1e308, -1e308, np.nan, np.inf, 1e-300, 70.0, 500.0])
    c = proxform.Controller(sc, 3)
    many = proxform.Controllers(sc)
    t = 0.0
    for k in range(2000):
        t += rng.choice([0.0, 0.1, 1e-9, 5.0, -0.1])
        own = rng.choice(values, 9) if k % 3 == 0 else sc.initial_states()[2] + rng.normal(0, 1, 9)
        n = int(rng.integers(0, 12))
        ids = rng.integers(-1, 9, n)
        states = rng.normal(0, 100, (n, 9))
        if k % 5 == 0 and states.size:
            states.flat[rng.integers(0, states.size)] = rng.choice(values)
        try:
            d = c.step(t, own, np.column_stack([ids, states]) if n else np.zeros((0, 10)))
            assert d.outcome in ("held", "adjusted", "alone")
            assert all(math.isfinite(u) for u in d.input), d
        except ValueError:
            pass
        counts = rng.multinomial(n, [0.2] * 5) if k % 7 else rng.integers(-2, 4, 5)
        try:
            inputs, codes = many.step(t, np.tile(own, (5, 1)), counts, ids, states)
            assert np.isfinite(inputs).all()
        except ValueError:
            pass


@pytest.mark.parametrize("bad", [None, 3, 1.5, [1, 2], object()])
def test_dicts_of_the_wrong_shape_raise(bad):
    with pytest.raises((ScenarioError, TypeError)):
        proxform.load({"formation": bad})


def test_counts_that_overflow_are_refused():
    sc = proxform.load("paper")
    many = proxform.Controllers(sc)
    own = np.tile(sc.initial_states()[1], (5, 1))
    big = np.array([1, 2**63 - 1, 0, 0, 0], dtype=np.int64)
    with pytest.raises(ValueError, match="counts"):
        many.step(0.0, own, big, np.array([1]), np.zeros((1, 9)))


@pytest.mark.parametrize("bad", [42, "yes", 1.0, [True]])
def test_progress_that_is_neither_a_flag_nor_a_callable_is_refused(bad):
    # (It was accepted as true: 42 drew a bar.)
    sc = proxform.load("paper")
    with pytest.raises(TypeError, match="progress"):
        proxform.run(sc, runs=1, trajectories=False, progress=bad)


@pytest.mark.parametrize("bad", [2.0, True, "2", None])
def test_a_controller_for_a_uav_that_is_not_an_int_names_the_argument(bad):
    with pytest.raises(TypeError, match="uav: a UAV number"):
        proxform.Controller(proxform.load("paper"), bad)
    with pytest.raises(ValueError, match="uav"):
        proxform.Controller(proxform.load("paper"), 2**70)


def test_controllers_name_a_uav_number_that_is_not_whole():
    sc = proxform.load("paper")
    with pytest.raises(TypeError, match=r"uavs\[0\]: a UAV number \(an int\), not float 2.9"):
        proxform.Controllers(sc, [2.9, 3])
    with pytest.raises(ValueError, match="uavs: a sequence of UAV numbers"):
        proxform.Controllers(sc, 5)
    assert proxform.Controllers(sc, np.array([2, 3])).uavs == [2, 3]
