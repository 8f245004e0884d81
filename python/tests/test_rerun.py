"""A flight as a rerun recording: written by Result.to_rerun and python -m proxform.rrd, read
back by rerun's own reader with every UAV and every step."""

import json
import subprocess
import sys
from collections import Counter

import numpy as np
import pytest

import proxform

rr_chunk = pytest.importorskip("rerun.chunk")


def rows_by_entity(path):
    """Rows on the flight's timeline per entity path, as rerun reads the file back."""
    reader = rr_chunk.RrdReader(str(path))
    (recording,) = reader.recordings()
    rows = Counter()
    for chunk in reader.stream(store=recording):
        if "flight_time" in chunk.timeline_names:
            rows[chunk.entity_path] += chunk.num_rows
    return recording, rows


def test_the_papers_flight_reads_back_with_every_uav_and_step(tmp_path):
    result = proxform.run("paper", seed=3)
    path = result.to_rerun(tmp_path / "paper.rrd")
    recording, rows = rows_by_entity(path)
    assert recording.application_id == "proxform"
    traj = result.trajectories
    steps = len(np.unique(traj["t_s"]))
    assert steps == 1001
    uavs = sorted(set(int(u) for u in traj["uav"]))
    assert uavs == [1, 2, 3, 4, 5, 6]
    for u in uavs:
        assert rows[f"/swarm/uav/{u}"] == steps, (u, rows)
        assert rows[f"/swarm/uav/{u}/attitude"] == steps
    for u in uavs[1:]:
        for axis in ("x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg"):
            assert rows[f"/errors/uav/{u}/{axis}"] == steps
    # The navigator has no formation error; each UAV's first and last step are events.
    assert "/errors/uav/1/x_m" not in rows
    assert rows["/events"] >= 2 * len(uavs)


def test_an_output_folder_converts_and_bad_uses_say_what_is_wrong(tmp_path):
    result = proxform.run("paper", seed=2, trajectories=False)
    with pytest.raises(ValueError, match="trajectories=True"):
        result.to_rerun(tmp_path / "x.rrd")
    with pytest.raises(IsADirectoryError, match="folder"):
        proxform.run("paper", seed=2).to_rerun(tmp_path)
    # An output folder as `proxform run` writes it (trajectories.csv, summary.json), through
    # python -m proxform.rrd.
    folder = tmp_path / "out"
    folder.mkdir()
    r = proxform.run("paper", seed=2)
    (folder / "summary.json").write_text(json.dumps(r.summary))
    cols = list(r.trajectories)

    def cell(v):
        return str(int(v)) if isinstance(v, (bool, np.bool_)) else str(v)

    lines = [",".join(cols)] + [
        ",".join(cell(r.trajectories[c][i]) for c in cols) for i in range(len(r.trajectories))
    ]
    (folder / "trajectories.csv").write_text("\n".join(lines) + "\n")
    done = subprocess.run([sys.executable, "-m", "proxform.rrd", str(folder)], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    _, rows = rows_by_entity(folder / "flight.rrd")
    assert all(rows[f"/swarm/uav/{u}"] == 1001 for u in range(1, 7)), rows
    bad = subprocess.run([sys.executable, "-m", "proxform.rrd", str(tmp_path / "nowhere")], capture_output=True, text=True)
    assert bad.returncode == 2 and "no trajectories.csv" in bad.stderr, bad.stderr


def test_a_recording_is_written_fresh_never_through_a_link(tmp_path):
    result = proxform.run("paper", seed=2, runs=1)
    victim = tmp_path / "victim.txt"
    victim.write_text("keep")
    (tmp_path / "link.rrd").symlink_to(victim)
    with pytest.raises(FileExistsError, match="not a regular file"):
        result.to_rerun(tmp_path / "link.rrd")
    assert victim.read_text() == "keep"
    with pytest.raises(FileNotFoundError, match="is not a folder"):
        result.to_rerun(tmp_path / "nowhere" / "x.rrd")
