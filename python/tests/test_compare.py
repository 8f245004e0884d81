"""Comparisons from Python: the CLI's rows, and located errors in a comparison's text."""

from __future__ import annotations

import csv
import subprocess

import numpy as np
import pytest

import proxform
from proxform import ScenarioError

TEXT = """
name = "py"
scenario = "paper"
seeds = 2
methods = ["proximity", "leader_follower"]
[[condition]]
name = "ideal"
[[condition]]
name = "lossy"
radio_loss = 0.3
"""


def test_a_comparison_gives_the_cli_rows(cli, tmp_path):
    path = tmp_path / "cmp.toml"
    path.write_text(TEXT)
    subprocess.run(
        [cli, "compare", path, "--duration-s", "20", "--out", tmp_path / "out", "--no-figures", "-q"],
        check=True, timeout=600, stdout=subprocess.DEVNULL,
    )
    c = proxform.compare(path, duration_s=20, threads=1)
    assert len(c.rows) == 2 * 2 * 2 and len(c.cells) == 4
    with open(tmp_path / "out" / "compare.csv") as f:
        rows = list(csv.DictReader(f))
    assert [r["method"] for r in rows] == list(c.rows["method"])
    np.testing.assert_allclose(c.rows["max_error_m"], [float(r["max_error_m"]) for r in rows], rtol=1e-12)
    assert set(c.cells["condition"]) == {"ideal", "lossy"}


def test_a_bad_comparison_names_key_and_line():
    with pytest.raises(ScenarioError) as e:
        proxform.compare(TEXT.replace("seeds = 2", "seeds = 0"))
    assert (e.value.key, e.value.line) == ("seeds", 4)
    with pytest.raises(ScenarioError, match="scenario"):
        proxform.compare(TEXT.replace('"paper"', '"missing.toml"'))


def test_a_comparison_stops_when_its_progress_callback_raises():
    def progress(done, total):
        if done > 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        proxform.compare(TEXT.replace("seeds = 2", "seeds = 5000"), progress=progress)
