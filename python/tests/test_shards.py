"""Shards, merges, pickles and sweeps: a batch split across processes or machines gives the
summary of the batch run whole, to the bit."""

import pickle

import numpy as np
import pytest

import proxform


def same_result(a: proxform.Result, b: proxform.Result) -> None:
    assert a.summary == b.summary
    assert a.runs.columns == b.runs.columns
    for c in a.runs.columns:
        np.testing.assert_array_equal(a.runs[c], b.runs[c], err_msg=c)


def test_scenarios_pickle_to_the_same_scenario_without_freezing_derived_values():
    sc = proxform.Scenario.builtin("paper").with_values({"controller": {"lambda": 0.4}, "duration_s": 20})
    back = pickle.loads(pickle.dumps(sc))
    assert back.to_toml() == sc.to_toml()
    # The spec travels, not the resolved values: a derived default still follows a change.
    wide = back.with_values({"allowable": {"y_m": 2.0}})
    assert wide.resolved()["allowable"]["y_m"] == 2.0
    same_result(proxform.run(sc, runs=3, trajectories=False), proxform.run(back, runs=3, trajectories=False))


def test_results_and_errors_pickle_exactly():
    r = proxform.run("paper", runs=4, seed=5, trajectories=False)
    back = pickle.loads(pickle.dumps(r))
    same_result(r, back)
    assert back.shard.to_bytes() == r.shard.to_bytes()
    with pytest.raises(proxform.ScenarioError) as info:
        proxform.load("duration_s = -1\n")
    e = pickle.loads(pickle.dumps(info.value))
    assert isinstance(e, proxform.ScenarioError)
    assert (e.key, e.line, e.source, str(e)) == (info.value.key, info.value.line, info.value.source, str(info.value))


def test_shards_in_any_order_merge_to_the_batch():
    sc = proxform.load("paper").with_values({"sensing": {"dropout": 0.2}})
    whole = proxform.run(sc, runs=60, trajectories=False)
    shards = [proxform.run(sc, runs=15, first_run=k * 15, trajectories=False, threads=1) for k in (2, 0, 3, 1)]
    merged = proxform.merge(shards)
    same_result(whole, merged)
    # Runs alone (their scenario travels with them) merge too.
    same_result(whole, proxform.merge([s.shard for s in shards]))
    # One run of a big batch, reproduced alone.
    alone = proxform.run(sc, runs=1, first_run=37, trajectories=False)
    row = int(np.flatnonzero(whole.runs["run"] == 37)[0])
    assert alone.runs["max_err_y_m"][0] == whole.runs["max_err_y_m"][row]


def test_merges_refuse_shards_of_other_batches_naming_them():
    a = proxform.run("paper", runs=3, trajectories=False)
    b = proxform.run("paper", runs=3, first_run=2, trajectories=False)
    with pytest.raises(ValueError, match="run 2 is in both left and right"):
        proxform.merge([a, b], names=["left", "right"])
    c = proxform.run("paper", runs=3, first_run=3, seed=2, trajectories=False)
    with pytest.raises(ValueError, match="seeds 1 and 2"):
        proxform.merge([a, c])
    d = proxform.run("paper", runs=3, first_run=5, trajectories=False)
    with pytest.raises(ValueError, match="runs 3..=4 are in none"):
        proxform.merge([a, d])
    with pytest.raises(ValueError, match="not a batch's runs"):
        proxform.Runs.from_bytes(b"PXFJRNL1 garbage")
    with pytest.raises(TypeError, match="results\\[1\\]"):
        proxform.merge([a, "b"])


def test_a_sweep_is_its_cells_single_batches():
    grid = {"controller.lambda": [0.5, 0.8], "sensing.dropout": [0.0, 0.1, 0.3]}
    table = proxform.sweep("paper", grid, runs=10)
    assert list(table["cell"]) == [1, 2, 3, 4, 5, 6]
    assert list(table["controller.lambda"]) == [0.5, 0.5, 0.5, 0.8, 0.8, 0.8]
    for _, row in table.iterrows():
        sc = proxform.load("paper").with_values(
            {"controller": {"lambda": row["controller.lambda"]}, "sensing": {"dropout": row["sensing.dropout"]}}
        )
        single = proxform.run(sc, runs=10, trajectories=False)
        assert row["pass_fraction"] == single.summary["pass_fraction"]
        assert row["worst_err_y_m"] == single.summary["worst_abs_error"]["y_m"]
    with pytest.raises(proxform.ScenarioError, match="cell controller.lambda=2"):
        proxform.sweep("paper", {"controller.lambda": [0.5, 2]}, runs=1)


def test_dask_workers_run_shards_that_merge_to_the_one_machine_summary():
    distributed = pytest.importorskip("distributed")
    sc = proxform.load("paper")
    whole = proxform.run(sc, runs=400, trajectories=False)
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, host="127.0.0.1", dashboard_address=None
    ) as cluster, distributed.Client(cluster) as client:
        futures = [
            client.submit(proxform.run, sc, runs=100, first_run=100 * k, trajectories=False, threads=1, pure=False)
            for k in range(4)
        ]
        shards = client.gather(futures)
        workers = {f.key for f in futures}
    assert len(workers) == 4
    same_result(whole, proxform.merge(shards))


def test_a_sweep_larger_than_the_cell_limit_is_refused_before_anything_runs():
    import time

    started = time.monotonic()
    with pytest.raises(ValueError, match="more than the 10000"):
        proxform.sweep("paper", {"controller.lambda": [0.5] * 1000, "controller.rho": [0.1] * 1000}, runs=1)
    assert time.monotonic() - started < 5
