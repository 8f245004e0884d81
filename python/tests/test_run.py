"""Runs from Python: the same numbers as the command line, whatever the thread count, with
the GIL released, progress on the calling thread, and Ctrl-C that stops a run."""

from __future__ import annotations

import csv
import json
import subprocess
import threading
import time
import _thread

import numpy as np
import pytest

import proxform


def test_the_paper_passes():
    r = proxform.run("paper")
    assert r.summary["pass_fraction"] == 1.0 and r.pass_fraction == 1.0
    assert r.summary["runs"] == 1 and r.summary["seed"] == 1


def test_summary_runs_and_trajectories_equal_the_cli_files(cli, tmp_path):
    out = tmp_path / "cli"
    subprocess.run(
        [cli, "run", "--seed", "7", "--runs", "3", "--out", out, "--no-figures", "-q"],
        check=True, timeout=600, stdout=subprocess.DEVNULL,
    )
    r = proxform.run("paper", seed=7, runs=3)
    # summary.json, value for value (JSON round trips every float exactly).
    assert r.summary == json.loads((out / "summary.json").read_text())
    # runs.csv: the CLI rounds to its printed decimals.
    with open(out / "runs.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == len(r.runs) == 3
    assert set(rows[0]) == set(r.runs.columns)
    for name in r.runs.columns:
        cli_col = np.array([float(row[name]) for row in rows])
        np.testing.assert_allclose(r.runs[name].astype(float), cli_col, atol=1e-3, rtol=0, err_msg=name)
    # trajectories.csv: the first run, row for row, to the file's 6 decimals.
    with open(out / "trajectories.csv") as f:
        traj = list(csv.DictReader(f))
    tr = r.trajectories
    assert len(traj) == len(tr) == 6 * 1001
    for name in ["t_s", "uav", "x_m", "y_m", "err_y_m", "gamma_rad", "err_gamma_deg"]:
        np.testing.assert_allclose(tr[name], [float(row[name]) for row in traj], atol=1e-6, rtol=0, err_msg=name)
    assert list(tr["outcome"][6:12]) == [row["outcome"] for row in traj[6:12]]
    assert tr.to_pandas().shape == (6 * 1001, len(tr.columns))


def test_results_do_not_depend_on_the_thread_count():
    one = proxform.run("paper", seed=3, runs=4, threads=1, trajectories=False)
    two = proxform.run("paper", seed=3, runs=4, threads=2, trajectories=False)
    assert one.summary == two.summary
    for name in one.runs.columns:
        assert np.array_equal(one.runs[name], two.runs[name]), name
    assert one.trajectories is None


def test_no_adjustment_fails_the_check():
    sc = proxform.load("paper").with_values({"duration_s": 40})
    assert proxform.run(sc, adjust=False, trajectories=False).pass_fraction == 0.0


def test_progress_is_reported_on_the_calling_thread():
    seen = []
    caller = threading.get_ident()

    def progress(done, total):
        seen.append((done, total, threading.get_ident()))

    proxform.run("paper", runs=8, threads=2, trajectories=False, progress=progress)
    assert seen and seen[-1][:2] == (8, 8)
    assert all(t == caller for _, _, t in seen)
    assert [d for d, _, _ in seen] == sorted(d for d, _, _ in seen)


def test_the_gil_is_released_while_running():
    ticks = 0
    stop = False

    def count():
        nonlocal ticks
        while not stop:
            ticks += 1
            time.sleep(0.001)

    t = threading.Thread(target=count)
    t.start()
    try:
        proxform.run("paper", runs=6, threads=1, trajectories=False)
    finally:
        stop = True
        t.join(timeout=10)
    assert ticks > 20, ticks


def test_ctrl_c_stops_a_long_run_promptly():
    # A batch that would take minutes; Ctrl-C after 0.5 s.
    timer = threading.Timer(0.5, _thread.interrupt_main)
    started = time.monotonic()
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            proxform.run("paper", runs=100_000, threads=2, trajectories=False)
    finally:
        timer.cancel()
    assert time.monotonic() - started < 10


def test_an_error_in_the_progress_callback_stops_the_run():
    def progress(done, total):
        if done > 0:
            raise RuntimeError("enough")

    started = time.monotonic()
    with pytest.raises(RuntimeError, match="enough"):
        proxform.run("paper", runs=100_000, trajectories=False, progress=progress)
    assert time.monotonic() - started < 10


@pytest.mark.parametrize(
    "kwargs",
    [
        {"runs": 0},
        {"runs": 10**8},
        {"threads": 100_000},
        {"threads": -1},
        {"seed": -1},
        {"seed": 2**70},
        {"first_run": -3},
        {"runs": 1.9},
        {"seed": True},
    ],
)
def test_bad_arguments_raise_naming_the_argument(kwargs):
    # Never a bare OverflowError, never a float truncated.
    with pytest.raises((ValueError, TypeError)) as info:
        proxform.run("paper", trajectories=False, **kwargs)
    assert not isinstance(info.value, OverflowError)
    assert next(iter(kwargs)) in str(info.value), str(info.value)


def test_a_path_with_an_equals_sign_is_read_as_a_file(tmp_path):
    d = tmp_path / "lambda=0.5"
    d.mkdir()
    f = d / "x=y.toml"
    f.write_text(proxform.load("paper").to_toml().replace('name = "paper"', 'name = "from-file"'))
    assert proxform.load(str(f)).name == "from-file"
    with pytest.raises(proxform.ScenarioError, match="cannot read"):
        proxform.load(str(d / "missing=1.toml"))


def test_progress_true_without_tqdm_writes_a_line(capsys, monkeypatch):
    import builtins

    real_import = builtins.__import__

    def no_tqdm(name, *args, **kwargs):
        if name.startswith("tqdm"):
            raise ImportError(name)
        return real_import(name, *args, **kwargs)

    monkeypatch.setattr(builtins, "__import__", no_tqdm)
    proxform.run("paper", runs=3, threads=1, trajectories=False, progress=True)
    assert "3/3 runs" in capsys.readouterr().err


def test_the_columns_of_forming_and_robust_checks_equal_the_cli_file(cli, tmp_path):
    # The aggregate forms from scattered starts with the robust fusion on: runs.csv gains the
    # forming, flown and isolation columns, and Python's table has the same.
    out = tmp_path / "cli"
    subprocess.run(
        [cli, "run", "--scenario", "aggregate", "--runs", "2", "--out", out, "--no-figures", "--no-trajectories", "-q"],
        check=True, timeout=600, stdout=subprocess.DEVNULL,
    )
    r = proxform.run("aggregate", runs=2, trajectories=False)
    with open(out / "runs.csv") as f:
        rows = list(csv.DictReader(f))
    assert set(rows[0]) == set(r.runs.columns)
    for name in ["time_to_form_s", "transient_error_ratio", "isolating_s_per_uav"]:
        np.testing.assert_allclose(r.runs[name], [float(row[name]) for row in rows], atol=1e-3, rtol=0, err_msg=name)
    # The whole flight at ~70 m/s: metres to the CLI's one decimal.
    np.testing.assert_allclose(
        r.runs["path_length_m_per_uav"], [float(row["path_length_m_per_uav"]) for row in rows], atol=0.06, rtol=0
    )
    assert all(t <= 120.0 for t in r.runs["time_to_form_s"])
    # Every follower scattered: none was judged from the start.
    assert all(row["settled_error_ratio"] == "" for row in rows) and np.isnan(r.runs["settled_error_ratio"]).all()
