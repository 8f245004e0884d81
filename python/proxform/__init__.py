"""proxform: distributed formation maintenance of UAV swarms, from Python.

Each UAV keeps its place in the formation from what it perceives of its neighbours (the
proximity method, see docs/METHOD.md in the repository). This package runs the same Rust code
as the ``proxform`` command line:

- ``proxform.load(...)``: a checked scenario from a built-in name, a TOML file, TOML text or a
  dict; a bad one raises :class:`ScenarioError` naming the key (and the line, for text).
- ``proxform.run(scenario, seed=1, runs=1, threads=0)``: seeded runs; the result's
  ``summary`` is the dict of ``summary.json``, ``runs`` and ``trajectories`` are tables of
  numpy columns (``.to_pandas()`` when pandas is installed).
- ``proxform.compare(...)``: methods side by side under the same conditions.
- ``proxform.Controller(scenario, uav)`` and ``proxform.Controllers(scenario)``: the controller
  alone, stepped by another simulator.

Units are SI and radians (errors in the tables: m and degrees, as in the CLI's files); world
frame x forward, y left, z up; UAVs are numbered from 1.
"""

from __future__ import annotations

import json
import os
import sys
from typing import Any, Callable, Mapping, Optional, Union

import numpy as np

from ._proxform import (
    Controller,
    Controllers,
    Decision,
    Scenario,
    ScenarioError,
    __version__,
    builtin_names,
)
from . import _proxform
from ._files import read_text
from ._table import Table

__all__ = [
    "Comparison",
    "Controller",
    "Controllers",
    "Decision",
    "Result",
    "Scenario",
    "ScenarioError",
    "Table",
    "builtin_names",
    "compare",
    "load",
    "run",
    "__version__",
]

ScenarioLike = Union[Scenario, str, "os.PathLike[str]", Mapping[str, Any]]
Progress = Union[None, bool, Callable[[int, int], Any]]


def load(source: ScenarioLike, *, uavs: Optional[int] = None) -> Scenario:
    """A checked scenario from a built-in name (``"paper"``, ``"swarm"`` with ``uavs``, …), a
    path to a TOML file, TOML text, or a dict with the keys of a scenario file.

    Raises :class:`ScenarioError` (a ``ValueError``) with ``.key``, ``.line`` and ``.source``.
    """
    if isinstance(source, Scenario):
        return source
    if isinstance(source, Mapping):
        return Scenario.from_dict(dict(source))
    if isinstance(source, os.PathLike):
        path = os.fspath(source)
        return Scenario.from_toml(read_text(path, "scenario file"), source=path)
    if isinstance(source, str):
        if source in builtin_names():
            return Scenario.builtin(source, uavs)
        if "\n" in source or "=" in source or "[" in source:
            return Scenario.from_toml(source)
        return Scenario.from_toml(read_text(source, "scenario file"), source=source)
    raise TypeError(
        f"a scenario is a built-in name, a path, TOML text, a dict or a Scenario, not {type(source).__name__}"
    )


class Result:
    """A batch of runs: ``summary`` (the dict of ``summary.json``), ``runs`` (one row per run,
    the columns of ``runs.csv``), ``trajectories`` (the first run, the columns of
    ``trajectories.csv``; None when not asked for) and the ``scenario``."""

    def __init__(self, scenario: Scenario, summary: dict, runs: Table, trajectories: Optional[Table]):
        self.scenario = scenario
        self.summary = summary
        self.runs = runs
        self.trajectories = trajectories

    @property
    def pass_fraction(self) -> float:
        """Fraction of runs in which every follower stayed within every allowable error."""
        return float(self.summary["pass_fraction"])

    def __repr__(self) -> str:
        return (
            f"Result(scenario={self.scenario.name!r}, runs={self.summary['runs']}, "
            f"pass_fraction={self.summary['pass_fraction']})"
        )


def _progress(progress: Progress, unit: str) -> tuple[Optional[Callable[[int, int], Any]], Callable[[], None]]:
    """A callback (done, total) for the extension, and what closes it."""
    if progress is None or progress is False:
        return None, lambda: None
    if callable(progress):
        return progress, lambda: None
    try:
        from tqdm.auto import tqdm
    except ImportError:
        tqdm = None
    if tqdm is not None:
        bar = None

        def tick(done: int, total: int) -> None:
            nonlocal bar
            if bar is None:
                bar = tqdm(total=total, unit=unit)
            bar.update(done - bar.n)

        def close() -> None:
            if bar is not None:
                bar.close()

        return tick, close

    def line(done: int, total: int) -> None:
        sys.stderr.write(f"\r{done}/{total} {unit}")
        sys.stderr.flush()

    def end() -> None:
        sys.stderr.write("\n")

    return line, end


def run(
    scenario: ScenarioLike = "paper",
    *,
    seed: int = 1,
    runs: int = 1,
    threads: int = 0,
    trajectories: bool = True,
    adjust: bool = True,
    progress: Progress = None,
) -> Result:
    """Runs ``runs`` seeded flights of ``scenario`` (run r uses random streams keyed by
    (seed, r), as ``proxform run --seed S --runs N``; the results do not depend on
    ``threads``, 0 meaning every core). The GIL is released while it runs; Ctrl-C stops it.

    ``progress``: True for a tqdm bar (a line on stderr without tqdm), or a callable
    ``(done, total)``, called on the calling thread. ``adjust=False`` discards every input
    (shows the pass criterion failing).
    """
    sc = load(scenario)
    cb, close = _progress(progress, "runs" if runs > 1 else "steps")
    try:
        summary, table, traj = _proxform.run(
            sc, seed=seed, runs=runs, threads=threads, trajectories=trajectories, adjust=adjust, progress=cb
        )
    finally:
        close()
    return Result(sc, json.loads(summary), Table(table), Table(traj) if traj is not None else None)


class Comparison:
    """A comparison's results: ``rows`` (every run: the columns of ``compare.csv``) and
    ``cells`` (one row per method and condition: the columns of ``compare_summary.csv``)."""

    def __init__(self, rows: Table, cells: Table):
        self.rows = rows
        self.cells = cells

    def __repr__(self) -> str:
        return f"Comparison(cells={len(self.cells)}, rows={len(self.rows)})"


def compare(
    source: Union[None, str, "os.PathLike[str]"] = None,
    *,
    seeds: Optional[int] = None,
    duration_s: Optional[float] = None,
    threads: int = 0,
    progress: Progress = None,
) -> Comparison:
    """Runs a comparison file (a path, TOML text, or None for the built-in comparison of the
    paper's experiment), as ``proxform compare``: its ``scenario`` is a built-in name or a file
    beside it. ``seeds`` and ``duration_s`` override the file's."""
    text: Optional[str] = None
    name = "compare-paper (built-in)"
    base = "."
    if source is not None:
        path = os.fspath(source)
        if "\n" in path or "=" in path:
            text, name = path, "<string>"
        else:
            text, name, base = read_text(path, "comparison file"), path, os.path.dirname(path) or "."
    cb, close = _progress(progress, "runs")
    try:
        rows, cells = _proxform.compare(
            text,
            name,
            lambda s: read_text(os.path.join(base, s), "scenario file"),
            seeds=seeds,
            duration_s=duration_s,
            threads=threads,
            progress=cb,
        )
    finally:
        close()
    return Comparison(Table(rows), Table(cells))
