"""proxform: distributed formation maintenance of UAV swarms, from Python.

Each UAV keeps its place in the formation from what it perceives of its neighbours (the
proximity method, see docs/METHOD.md in the repository). This package runs the same Rust code
as the ``proxform`` command line:

- ``proxform.load(...)``: a checked scenario from a built-in name, a TOML file, TOML text or a
  dict; a bad one raises :class:`ScenarioError` naming the key (and the line, for text).
- ``proxform.run(scenario, seed=1, runs=1, threads=0)``: seeded runs; the result's
  ``summary`` is the dict of ``summary.json``, ``runs`` and ``trajectories`` are tables of
  numpy columns (``.to_pandas()`` when pandas is installed).
- ``proxform.run(..., first_run=K)`` and ``proxform.merge(results)``: shards of one batch
  (on Dask, Ray or a Slurm array) merged into the summary one batch would have had; results
  and scenarios pickle exactly.
- ``proxform.sweep(scenario, {"controller.lambda": [0.5, 0.8]}, runs=50)``: a grid over
  scenario keys, one row per cell (a pandas DataFrame), as ``proxform sweep``.
- ``proxform.compare(...)``: methods side by side under the same conditions.
- ``proxform.Controller(scenario, uav)`` and ``proxform.Controllers(scenario)``: the controller
  alone, stepped by another simulator.

Units are SI and radians (errors in the tables: m and degrees, as in the CLI's files); world
frame x forward, y left, z up; UAVs are numbered from 1.
"""

from __future__ import annotations

import itertools
import json
import os
import sys
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np

from ._proxform import (
    Controller,
    Controllers,
    Decision,
    Runs,
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
    "Runs",
    "Scenario",
    "ScenarioError",
    "Table",
    "builtin_names",
    "compare",
    "load",
    "merge",
    "run",
    "sweep",
    "__version__",
]

ScenarioLike = Union[Scenario, str, "os.PathLike[str]", Mapping[str, Any]]
Progress = Union[None, bool, Callable[[int, int], Any]]


_U64 = 2**64 - 1


def _whole(name: str, value: Any, lo: int = 0, hi: int = _U64) -> int:
    """``value`` as an int in [lo, hi], or a ValueError (TypeError for a non-integer) naming
    the argument: a float, a bool or an out-of-range number is never truncated or wrapped."""
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)):
        raise TypeError(f"{name}: expected a whole number, not {type(value).__name__} {value!r}")
    v = int(value)
    if v < lo:
        raise ValueError(f"{name}: {v} is below {lo}")
    if v > hi:
        raise ValueError(f"{name}: {v} is beyond any count this package takes (at most {hi})")
    return v


def _is_path(source: str) -> bool:
    """A one-line string that names a file (or ends in .toml) is a path, never TOML text."""
    return "\n" not in source and (source.endswith(".toml") or os.path.exists(source))


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
        if uavs is not None:
            uavs = _whole("uavs", uavs, 2)
        if source in builtin_names():
            return Scenario.builtin(source, uavs)
        if not _is_path(source) and ("\n" in source or "=" in source or "[" in source):
            return Scenario.from_toml(source)
        return Scenario.from_toml(read_text(source, "scenario file"), source=source)
    raise TypeError(
        f"a scenario is a built-in name, a path, TOML text, a dict or a Scenario, not {type(source).__name__}"
    )


class Result:
    """A batch of runs: ``summary`` (the dict of ``summary.json``), ``runs`` (one row per run,
    the columns of ``runs.csv``), ``trajectories`` (the first run, the columns of
    ``trajectories.csv``; None when not asked for), the ``scenario`` and ``shard`` (the runs'
    exact results, which :func:`merge` merges with other shards of the same batch). A result
    pickles (for Dask, Ray, multiprocessing) and unpickles to equal values."""

    def __init__(
        self,
        scenario: Scenario,
        summary: dict,
        runs: Table,
        trajectories: Optional[Table],
        shard: Optional[Runs] = None,
    ):
        self.scenario = scenario
        self.summary = summary
        self.runs = runs
        self.trajectories = trajectories
        self.shard = shard

    @property
    def pass_fraction(self) -> float:
        """Fraction of runs in which every follower stayed within every allowable error."""
        return float(self.summary["pass_fraction"])

    def to_rerun(self, path: "os.PathLike[str] | str", *, recording_id: Optional[str] = None) -> str:
        """Writes the first run (``trajectories``) to the rerun recording ``path`` (``.rrd``):
        positions, attitudes, errors with their allowable bands and events on the
        ``flight_time`` timeline (see :mod:`proxform.rrd`; needs ``rerun-sdk``:
        ``pip install 'proxform[rerun]'``). Returns the path."""
        from .rrd import to_rerun

        return to_rerun(self, path, recording_id=recording_id)

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
    if progress is not True:
        raise TypeError(
            f"progress: True (a bar), False or None (none) or a callable(done, total), not {type(progress).__name__} {progress!r}"
        )
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
    first_run: int = 0,
) -> Result:
    """Runs ``runs`` seeded flights of ``scenario`` (run r uses random streams keyed by
    (seed, r), as ``proxform run --seed S --runs N``; the results do not depend on
    ``threads``, 0 meaning every core). The GIL is released while it runs; Ctrl-C stops it.
    ``first_run=K`` runs K to K+runs-1 (a shard, as ``--first-run K``; see :func:`merge`).

    ``progress``: True for a tqdm bar (a line on stderr without tqdm), or a callable
    ``(done, total)``, called on the calling thread. ``adjust=False`` discards every input
    (shows the pass criterion failing).
    """
    seed, runs = _whole("seed", seed), _whole("runs", runs, 1)
    threads, first_run = _whole("threads", threads), _whole("first_run", first_run)
    sc = load(scenario)
    cb, close = _progress(progress, "runs" if runs > 1 else "steps")
    try:
        summary, table, traj, shard = _proxform.run(
            sc,
            seed=seed,
            runs=runs,
            threads=threads,
            trajectories=trajectories,
            adjust=adjust,
            progress=cb,
            first_run=first_run,
        )
    finally:
        close()
    return Result(sc, json.loads(summary), Table(table), Table(traj) if traj is not None else None, shard)


def merge(results: Sequence[Union[Result, Runs]], *, names: Optional[Sequence[str]] = None) -> Result:
    """Shards of one batch (results of :func:`run` with the same scenario, seed and options,
    from ``first_run`` values that tile consecutive runs, in any order) merged into the result
    one batch of all their runs would have had: the same ``summary`` and ``runs``, to the bit
    (``trajectories`` None). Raises ValueError naming the shards that do not fit (``names``,
    by default "shard 1", "shard 2", ...)."""
    shards: list[Runs] = []
    scenario: Optional[Scenario] = None
    for k, r in enumerate(results):
        if isinstance(r, Result):
            if r.shard is None:
                raise ValueError(f"results[{k}] holds no exact runs (it was not made by proxform.run)")
            scenario = scenario or r.scenario
            shards.append(r.shard)
        elif isinstance(r, Runs):
            shards.append(r)
        else:
            raise TypeError(f"results[{k}]: expected a proxform.Result or proxform.Runs, not {type(r).__name__}")
    merged = _proxform.merge_runs(shards, list(names) if names is not None else None)
    summary = json.loads(merged.summary_json())
    if scenario is None:
        scenario = merged.scenario()
    return Result(scenario, summary, Table(merged.columns()), None, merged)


def _nested(cell: Mapping[str, Any]) -> dict:
    """Dotted keys (``controller.lambda``) as the nested dict :meth:`Scenario.with_values` takes."""
    out: dict = {}
    for key, value in cell.items():
        parts = key.split(".")
        if not all(parts):
            raise ValueError(f"grid: {key!r} is not a key (names joined by dots, e.g. 'controller.lambda')")
        d = out
        for p in parts[:-1]:
            d = d.setdefault(p, {})
            if not isinstance(d, dict):
                raise ValueError(f"grid: {key!r} sets a key inside a value given by another key")
        d[parts[-1]] = value
    return out


def sweep(
    scenario: ScenarioLike,
    grid: Mapping[str, Sequence[Any]],
    *,
    seed: int = 1,
    runs: int = 1,
    threads: int = 0,
    progress: Progress = None,
) -> Any:
    """A grid over scenario keys, as ``proxform sweep``: every combination of ``grid``'s
    values (``{"controller.lambda": [0.5, 0.8], "sensing.dropout": [0, 0.3]}``; the first key
    varying slowest), each cell checked like a file before anything runs, then ``runs`` seeded
    runs of each from ``seed``. Returns a pandas DataFrame, one row per cell: ``cell`` (from
    1), the keys, and the columns of ``sweep.csv``."""
    import pandas as pd

    seed, runs, threads = _whole("seed", seed), _whole("runs", runs, 1), _whole("threads", threads)
    sc = load(scenario)
    keys = list(grid)
    for k in keys:
        if isinstance(grid[k], (str, bytes)) or not isinstance(grid[k], Sequence) or len(grid[k]) == 0:
            raise ValueError(f"grid[{k!r}]: give a non-empty list of values")
    count = 1
    for k in keys:
        count *= len(grid[k])
    if count > _proxform.MAX_SWEEP_CELLS:
        raise ValueError(f"grid: {count} cells, more than the {_proxform.MAX_SWEEP_CELLS} a sweep may have")
    combos = list(itertools.product(*(grid[k] for k in keys)))
    cells = []
    for combo in combos:
        cell = dict(zip(keys, combo))
        try:
            cells.append((cell, sc.with_values(_nested(cell))))
        except ScenarioError as e:
            label = " ".join(f"{k}={v}" for k, v in cell.items())
            raise ScenarioError(f"cell {label}: {e}") from e
    cb, close = _progress(progress, "runs")
    rows = []
    try:
        for n, (cell, cs) in enumerate(cells):
            done = n * runs
            tick = (lambda d, t, done=done: cb(done + (d if runs > 1 else 0), runs * len(cells))) if cb else None
            _, _, _, shard = _proxform.run(cs, seed=seed, runs=runs, threads=threads, trajectories=False, progress=tick)
            rows.append({"cell": n + 1, **cell, **shard.row()})
    finally:
        close()
    return pd.DataFrame(rows)


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
    threads = _whole("threads", threads)
    if seeds is not None:
        seeds = _whole("seeds", seeds, 1)
    text: Optional[str] = None
    name = "compare-paper (built-in)"
    base = "."
    if source is not None:
        path = os.fspath(source)
        if not _is_path(path) and ("\n" in path or "=" in path):
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
