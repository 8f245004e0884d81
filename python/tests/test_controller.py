"""The controller alone: the agent step with the scenario's setup, checked inputs, and the
vectorised form equal to stepping each UAV by itself."""

from __future__ import annotations

import numpy as np
import pytest

import proxform


@pytest.fixture
def paper():
    return proxform.load("paper")


def slot_states(sc, t):
    """Every UAV exactly in its slot of a formation in steady flight (the paper's initial
    states, advanced by their velocity to time t)."""
    states = sc.initial_states()
    states[:, 0:3] += t * states[:, 3:6]
    return states


def neighbours_of(states, i):
    return np.array([[j + 1, *states[j]] for j in range(len(states)) if j != i])


def test_a_uav_in_its_slot_holds_and_one_off_it_adjusts_toward_it(paper):
    c = proxform.Controller(paper, 2)
    for k in range(5):
        x = slot_states(paper, 0.1 * k)
        d = c.step(0.1 * k, x[1], neighbours_of(x, 1))
        assert d.outcome == "held", (k, d)
    x = slot_states(paper, 0.5)
    off = x[1].copy()
    off[1] += 3.0  # 3 m to the left of its slot
    d = c.step(0.5, off, neighbours_of(x, 1))
    assert d.outcome == "adjusted" and d.normalised_sq > 1
    assert d.input[1] < 0, d.input  # it moves right, back toward its slot
    nxt = c.propagate(off, d.input)
    assert nxt[4] == pytest.approx(off[4] + d.input[1])


def test_lists_of_pairs_equal_arrays(paper):
    a, b = proxform.Controller(paper, 4), proxform.Controller(paper, 4)
    for k in range(20):
        x = slot_states(paper, 0.1 * k)
        x[3, 2] += 0.5 * np.sin(k)
        arr = neighbours_of(x, 3)
        pairs = [(int(r[0]), list(r[1:])) for r in arr]
        da, db = a.step(0.1 * k, x[3], arr), b.step(0.1 * k, list(x[3]), pairs)
        assert (da.outcome, da.input) == (db.outcome, db.input)


def test_bad_inputs_raise_value_errors(paper):
    c = proxform.Controller(paper, 2)
    x = slot_states(paper, 0.0)
    nb = neighbours_of(x, 1)
    bad_state = x[1].copy()
    bad_state[4] = np.nan
    bad_nb = nb.copy()
    bad_nb[0, 0] = 9
    self_nb = nb.copy()
    self_nb[0, 0] = 2
    frac = nb.copy()
    frac[0, 0] = 1.5
    cases = [
        lambda: c.step(0.0, bad_state, nb),
        lambda: c.step(0.0, x[1][:8], nb),
        lambda: c.step(0.0, x[1], bad_nb),
        lambda: c.step(0.0, x[1], self_nb),
        lambda: c.step(0.0, x[1], frac),
        lambda: c.step(0.0, x[1], nb[:, :9]),
        lambda: c.step(float("inf"), x[1], nb),
        lambda: c.step(0.0, x[1], nb, ages=[-1.0] * len(nb)),
        lambda: c.step(0.0, x[1], nb, ages=[0.0]),
        lambda: c.step(0.0, x[1], [(1, [0.0] * 9), (3, "abc")]),
        lambda: c.step(0.0, x[1], "nonsense"),
    ]
    for i, case in enumerate(cases):
        with pytest.raises(ValueError):
            case()
            pytest.fail(f"case {i} did not raise")
    c.step(1.0, x[1], nb)
    with pytest.raises(ValueError, match="does not go back|before"):
        c.step(0.5, x[1], nb)
    with pytest.raises(ValueError, match="navigator"):
        proxform.Controller(paper, 1)
    with pytest.raises(ValueError):
        proxform.Controller(paper, 7)
    with pytest.raises(ValueError, match="twice"):
        proxform.Controllers(paper, [2, 2])


def test_the_baselines_are_controllers_too(paper):
    sc = paper.with_values({"controller": {"method": "consensus"}})
    c = proxform.Controller(sc, 3)
    x = slot_states(sc, 0.0)
    x[2, 0] += 5.0
    d = c.step(0.0, x[2], neighbours_of(x, 2), radio=[True] * 5)
    assert d.outcome in ("held", "adjusted") and d.input[0] < 0, d


def test_the_vectorised_step_equals_single_steps(paper):
    many = proxform.Controllers(paper)
    assert many.uavs == [2, 3, 4, 5, 6]
    singles = [proxform.Controller(paper, u) for u in many.uavs]
    rng = np.random.default_rng(5)
    for k in range(30):
        t = 0.1 * k
        x = slot_states(paper, t) + rng.normal(0, 0.3, (6, 9)) * [1, 1, 1, 0.1, 0.1, 0.1, 0.001, 0.001, 0.001]
        counts, ids, states = [], [], []
        for u in many.uavs:
            nb = neighbours_of(x, u - 1)[: 3 + k % 3]
            counts.append(len(nb))
            ids.extend(nb[:, 0].astype(np.int64))
            states.extend(nb[:, 1:])
        inputs, codes = many.step(t, x[1:], np.array(counts), np.array(ids), np.array(states))
        start = 0
        for i, (u, single) in enumerate(zip(many.uavs, singles)):
            nb = np.column_stack([ids[start : start + counts[i]], states[start : start + counts[i]]])
            start += counts[i]
            d = single.step(t, x[u - 1], nb)
            assert proxform.Controllers.outcomes[codes[i]] == d.outcome
            assert list(inputs[i]) == d.input
    with pytest.raises(ValueError, match="add up"):
        many.step(10.0, x[1:], np.array([1, 1, 1, 1, 1]), np.array([1]), np.zeros((1, 9)))


def test_the_robust_checks_report_what_they_did(paper):
    """A stuck own sensor is refused (own_suspect) with controller.own_gate_m; a neighbour far
    from the others is left out (isolated) with controller.isolation_gate."""
    sc = paper.with_values({"controller": {"own_gate_m": 3.0, "isolation_gate": 1.0}})
    c = proxform.Controller(sc, 5)
    stuck = slot_states(sc, 1.0)[4]
    for k in range(30):
        x = slot_states(sc, 0.1 * k)
        own = stuck if 10 <= k < 20 else x[4]
        d = c.step(0.1 * k, own, neighbours_of(x, 4))
        assert d.own_suspect == (11 <= k < 20), (k, d)
        assert d.isolated == 0
    # UAV2, one of UAV5's references, 10 m off to the left: left out.
    x = slot_states(sc, 3.0)
    nb = neighbours_of(x, 4)
    nb[nb[:, 0] == 2, 2] += 10.0
    assert c.step(3.0, x[4], nb).isolated == 1
    # Without the checks neither is reported.
    plain = proxform.Controller(paper, 5)
    assert plain.step(0.0, x[4], nb).isolated == 0


def test_the_vectorised_step_refuses_ids_and_counts_that_are_not_whole(paper):
    many = proxform.Controllers(paper)
    x = slot_states(paper, 0.0)
    ok_counts = np.array([1, 0, 0, 0, 0])
    # 1.9 was read as UAV 1; a float count of 1.5 as 1.
    with pytest.raises(ValueError, match="ids: expected whole numbers, found 1.9"):
        many.step(0.0, x[1:], ok_counts, np.array([1.9]), x[:1])
    with pytest.raises(ValueError, match="counts: expected whole numbers, found 1.5"):
        many.step(0.0, x[1:], np.array([1.5, 0, 0, 0, 0]), np.array([1]), x[:1])
    with pytest.raises(ValueError, match="booleans"):
        many.step(0.0, x[1:], ok_counts, np.array([True]), x[:1])
    with pytest.raises(ValueError, match="beyond"):
        many.step(0.0, x[1:], ok_counts, np.array([1e300]), x[:1])
    # Whole floats are whole numbers: the same decision as integers.
    a, _ = many.step(0.0, x[1:], ok_counts.astype(float), np.array([1.0]), x[:1])
    b, _ = proxform.Controllers(paper).step(0.0, x[1:], ok_counts, np.array([1]), x[:1])
    assert np.array_equal(a, b)


def test_propagate_refuses_commands_far_beyond_the_vehicle(paper):
    c = proxform.Controller(paper, 2)
    x = slot_states(paper, 0.0)[1]
    with pytest.raises(ValueError, match=r"input\[1\] = 1e300: far beyond"):
        c.propagate(x, [0.0, 1e300, 0.0, 0.0, 0.0, 0.0])
    assert np.all(np.isfinite(c.propagate(x, [0.0] * 6)))
