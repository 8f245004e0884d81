"""A flight as a rerun recording (``.rrd``): :meth:`proxform.Result.to_rerun` for a result's
first run, ``python -m proxform.rrd OUT_DIR [FILE]`` for an output folder of ``proxform run``
(its ``trajectories.csv`` and ``summary.json``).

Needs ``rerun-sdk`` (``pip install 'proxform[rerun]'``), imported only when called. On the
recording's ``flight_time`` timeline (seconds since t = 0): each UAV's position (``swarm/uav/N``,
a point with its id as label, coloured by whether it is within its allowable errors) and
attitude (``swarm/uav/N/attitude``, the pitch α, yaw β and roll γ as a rotation, radians inside,
as the trajectories have them), each follower's six formation errors (``errors/uav/N/x_m``…
``gamma_deg``) with the allowable bands (``errors/allowable/…``, static), and events as text
(``events``: a UAV leaving or coming back within its allowable errors, its first and last
step). Everything is sent as columns (one call per UAV and series), so a long flight costs
little Python time.
"""

from __future__ import annotations

import csv
import json
import os
import sys
from typing import Any, Optional

import numpy as np

_AXES = ("x_m", "y_m", "z_m", "alpha_deg", "beta_deg", "gamma_deg")


def _rerun() -> Any:
    try:
        import rerun as rr
    except ImportError as e:
        raise ImportError(
            "to_rerun needs the rerun SDK: pip install 'proxform[rerun]' (or rerun-sdk)"
        ) from e
    return rr


def _quaternions(alpha: np.ndarray, beta: np.ndarray, gamma: np.ndarray) -> np.ndarray:
    """Rotations (x, y, z, w) of yaw β about z, then pitch α about y, then roll γ about x."""
    cy, sy = np.cos(beta / 2), np.sin(beta / 2)
    cp, sp = np.cos(alpha / 2), np.sin(alpha / 2)
    cr, sr = np.cos(gamma / 2), np.sin(gamma / 2)
    return np.stack(
        [
            sr * cp * cy - cr * sp * sy,
            cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy,
            cr * cp * cy + sr * sp * sy,
        ],
        axis=1,
    )


def to_rerun(result: Any, path: "os.PathLike[str] | str", *, recording_id: Optional[str] = None) -> str:
    """Writes ``result``'s first run (its trajectories) to the rerun recording ``path``."""
    if result.trajectories is None:
        raise ValueError("to_rerun: this result has no trajectories (run it with trajectories=True)")
    return write(result.trajectories, result.summary, path, recording_id=recording_id)


def _read_csv(path: str) -> dict:
    """``trajectories.csv`` as columns (numbers as floats, the outcome as text)."""
    with open(path, newline="", encoding="utf-8") as f:
        rows = list(csv.reader(f))
    if not rows:
        raise ValueError(f"{path}: empty")
    head, body = rows[0], rows[1:]
    cols: dict = {}
    for j, name in enumerate(head):
        values = [r[j] if j < len(r) else "" for r in body]
        try:
            cols[name] = np.asarray(values, dtype=str if name == "outcome" else np.float64)
        except ValueError as e:
            raise ValueError(f"{path}: column {name}: {e}") from None
    return cols


def from_folder(folder: "os.PathLike[str] | str", path: "os.PathLike[str] | str | None" = None) -> str:
    """Writes the first run of the output folder ``folder`` (``proxform run``'s
    ``trajectories.csv`` and ``summary.json``) to ``path`` (default ``folder/flight.rrd``)."""
    folder = os.fspath(folder)
    for name in ("trajectories.csv", "summary.json"):
        if not os.path.isfile(os.path.join(folder, name)):
            raise FileNotFoundError(f"{folder}: no {name} (give the output folder of `proxform run`)")
    summary_path = os.path.join(folder, "summary.json")
    with open(summary_path, encoding="utf-8") as f:
        try:
            summary = json.load(f)
        except json.JSONDecodeError as e:
            raise ValueError(f"{summary_path}: not a proxform summary ({e})") from None
    if not isinstance(summary, dict):
        raise ValueError(f"{summary_path}: not a proxform summary (not a JSON object)")
    traj = _read_csv(os.path.join(folder, "trajectories.csv"))
    return write(traj, summary, path if path is not None else os.path.join(folder, "flight.rrd"))


def write(
    traj: Any, summary: dict, path: "os.PathLike[str] | str", *, recording_id: Optional[str] = None
) -> str:
    """Writes the trajectories ``traj`` (the columns of ``trajectories.csv``) of a flight whose
    summary is ``summary`` to the rerun recording ``path``; returns the path."""
    rr = _rerun()
    path = os.fspath(path)
    if os.path.isdir(path):
        raise IsADirectoryError(f"to_rerun: {path} is a folder (give a file name, e.g. flight.rrd)")
    # Written fresh, never through a link or into a FIFO or device (as the CLI's outputs).
    if os.path.lexists(path):
        if os.path.islink(path) or not os.path.isfile(path):
            raise FileExistsError(f"to_rerun: {path} exists and is not a regular file (a link, FIFO or device): not written")
        os.remove(path)
    parent = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(parent):
        raise FileNotFoundError(f"to_rerun: {parent} is not a folder (the recording goes into an existing one)")
    name = summary.get("scenario", "flight")
    seed = summary.get("seed")
    rec = rr.RecordingStream("proxform", recording_id=recording_id or f"{name}-seed-{seed}")
    rec.save(path)
    t = np.asarray(traj["t_s"], dtype=np.float64)
    uav = np.asarray(traj["uav"], dtype=np.int64)
    pos = np.stack([np.asarray(traj[k], dtype=np.float64) for k in ("x_m", "y_m", "z_m")], axis=1)
    att = [np.asarray(traj[k], dtype=np.float64) for k in ("alpha_rad", "beta_rad", "gamma_rad")]
    within = np.asarray(traj["within_allowable"]).astype(bool)
    outcome = np.asarray(traj["outcome"])
    allow = summary.get("allowable_error") or {}
    for axis in _AXES:
        if axis in allow:
            rec.log(f"errors/allowable/{axis}", rr.Scalars(float(allow[axis])), static=True)
    green, red, blue = (40, 160, 70, 255), (210, 40, 40, 255), (40, 90, 220, 255)
    events_t: list[float] = []
    events_text: list[str] = []
    for u in np.unique(uav):
        m = uav == u
        tu = t[m]
        time = [rr.TimeColumn("flight_time", duration=tu)]
        navigator = bool(np.all(outcome[m] == "navigator"))
        colors = np.where(within[m][:, None], np.array(green), np.array(red)).astype(np.uint32)
        if navigator:
            colors[:] = np.array(blue)
        rgba = (colors[:, 0] << 24) | (colors[:, 1] << 16) | (colors[:, 2] << 8) | colors[:, 3]
        rec.send_columns(
            f"swarm/uav/{u}",
            indexes=time,
            columns=rr.Points3D.columns(positions=pos[m], colors=rgba, labels=[f"UAV {u}"] * int(m.sum())).partition(
                np.ones(int(m.sum()), dtype=np.int32)
            ),
        )
        rec.send_columns(
            f"swarm/uav/{u}/attitude",
            indexes=time,
            columns=rr.Transform3D.columns(translation=pos[m], quaternion=_quaternions(att[0][m], att[1][m], att[2][m])),
        )
        if not navigator:
            for axis in _AXES:
                rec.send_columns(
                    f"errors/uav/{u}/{axis}",
                    indexes=time,
                    columns=rr.Scalars.columns(scalars=np.asarray(traj["err_" + axis], dtype=np.float64)[m]),
                )
            w = within[m]
            changes = np.flatnonzero(w[1:] != w[:-1]) + 1
            for k in changes:
                events_t.append(float(tu[k]))
                events_text.append(f"UAV {u} {'back within' if w[k] else 'outside'} its allowable errors")
        events_t += [float(tu[0]), float(tu[-1])]
        events_text += [f"UAV {u} first step", f"UAV {u} last step"]
    if events_t:
        order = np.argsort(np.asarray(events_t), kind="stable")
        rec.send_columns(
            "events",
            indexes=[rr.TimeColumn("flight_time", duration=np.asarray(events_t)[order])],
            columns=rr.TextLog.columns(text=[events_text[i] for i in order]),
        )
    rec.flush()
    return path


def main(argv: Optional[list] = None) -> int:
    args = sys.argv[1:] if argv is None else argv
    if not 1 <= len(args) <= 2 or args[0] in ("-h", "--help"):
        print("usage: python -m proxform.rrd OUT_DIR [FILE.rrd]   (an output folder of `proxform run`)")
        return 2
    try:
        print("wrote", from_folder(*args))
    except (OSError, ValueError, ImportError, RuntimeError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
