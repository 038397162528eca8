"""Dataset export (``simatch export FILE --format parquet|csv``): a recording as tidy tables.

One table per kind of observation, one row per observation, one column per variable, every table with
``t`` (simulated seconds) and, for robot and team topics, ``team`` and ``robot``:

* ``trajectories``: one row per model (robot or ball) per physics step: pose (x, y, z, yaw and the
  quaternion) and twist, world frame. (``link_trajectories`` likewise when link states were recorded.)
* ``events``: the event log (goals, fouls, game commands, kicks...): type, team, robot, where, value, limit.
* ``perception``: one row per robot per control tick: what it saw of the ball (team frame);
  ``perception_robots`` (its own team as it perceived it) and ``perception_obstacles`` (every other
  robot it perceived), one row per perceived robot.
* one table per other message type (``vel_cmd``, ``action_cmd``, ``strategy_info``, ``coach_info``,
  ``game_state``, ``ball_contacts``, ``clock``, ``operator_command``, ``team_strategy``...): scalar fields
  as columns, nested messages flattened (``pass_cmd_catch_x``); a variable-length field is a list column in
  Parquet and JSON text in CSV.

``metadata.json`` holds the run's metadata (scene text, overrides, seed, version, command line).

The tables are written with pyarrow, in batches (a long match never has to fit in memory): it writes
Parquet and CSV from the same columnar batches, and pandas (``read_parquet``) and polars (``read_parquet``,
``scan_parquet``) read its files directly.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
import pyarrow as pa
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
from rosbags.interfaces import Nodetype

from .. import msgs
from ..bus import topics
from . import layout, rosbag2
from .reader import Recording

FORMATS = ("parquet", "csv")
BATCH_ROWS = 200_000
_ARROW = {
    "bool": pa.bool_(),
    "byte": pa.uint8(),
    "char": pa.uint8(),
    "octet": pa.uint8(),
    "int8": pa.int8(),
    "uint8": pa.uint8(),
    "int16": pa.int16(),
    "uint16": pa.uint16(),
    "int32": pa.int32(),
    "uint32": pa.uint32(),
    "int64": pa.int64(),
    "uint64": pa.uint64(),
    "float32": pa.float32(),
    "float64": pa.float64(),
    "string": pa.string(),
}


class ExportError(Exception):
    """An export that cannot be carried out (bad format, unwritable folder)."""


def snake(name: str) -> str:
    return re.sub(r"(?<=[a-z0-9])([A-Z])", r"_\1", name).lower()


def _where(topic: str) -> dict:
    """team and robot of a robot or team topic (``cyan/2/VelCmd`` -> team cyan, robot 2)."""
    parts = topic.split("/")
    if len(parts) >= 3 and parts[1].isdigit():
        return {"team": parts[0], "robot": int(parts[1])}
    if len(parts) == 2:
        return {"team": parts[0]}
    return {}


class _Table:
    """Rows of one table, written out in batches to ``DIR/<name>.<format>``."""

    def __init__(self, folder: Path, name: str, fmt: str, schema: pa.Schema):
        self.path = folder / f"{name}.{fmt}"
        self.fmt = fmt
        self.schema = schema if fmt == "parquet" else _csv_schema(schema)
        self.columns: dict[str, list] = {f.name: [] for f in schema}
        self.rows = 0
        self._pending = 0
        self._writer = None

    def add(self, row: dict) -> None:
        for name, col in self.columns.items():
            col.append(row.get(name))
        self._pending += 1
        if self._pending >= BATCH_ROWS:
            self.flush()

    def add_columns(self, cols: dict[str, Any], n: int) -> None:
        for name, col in self.columns.items():
            value = cols.get(name)
            if isinstance(value, np.ndarray):
                col.extend(value.tolist())
            elif isinstance(value, list):
                col.extend(value)
            else:
                col.extend([value] * n)
        self._pending += n
        if self._pending >= BATCH_ROWS:
            self.flush()

    def flush(self) -> None:
        if self._pending == 0 and self._writer is not None:
            return
        data = {}
        for f in self.schema:
            values = self.columns[f.name]
            if self.fmt == "csv" and pa.types.is_string(f.type):
                values = [v if v is None or isinstance(v, str) else json.dumps(_jsonable(v)) for v in values]
            data[f.name] = pa.array(values, type=f.type)
        batch = pa.record_batch(data, schema=self.schema)
        if self._writer is None:
            self._writer = (
                pq.ParquetWriter(self.path, self.schema)
                if self.fmt == "parquet"
                else pacsv.CSVWriter(self.path, self.schema)
            )
        self._writer.write_batch(batch)
        self.rows += self._pending
        self._pending = 0
        for col in self.columns.values():
            col.clear()

    def close(self) -> None:
        self.flush()
        if self._writer is not None:
            self._writer.close()


def _csv_schema(schema: pa.Schema) -> pa.Schema:
    """Lists have no CSV form: they become JSON text."""
    return pa.schema([pa.field(f.name, pa.string() if pa.types.is_list(f.type) else f.type) for f in schema])


def _jsonable(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if hasattr(value, "__msgtype__"):
        return {k: _jsonable(getattr(value, k)) for k in value.__dataclass_fields__ if k != "__msgtype__"}
    return value


# --- generic flattening of a message type into columns ---------------------------------------------------------
def _columns(typename: str, prefix: str = "") -> list[tuple[str, pa.DataType, Callable]]:
    """(column, arrow type, getter) for every field of ``typename``, nested messages flattened."""
    out = []
    _, fields = msgs.typestore.fielddefs[typename]
    for name, (kind, info) in fields:
        col = f"{prefix}{name}"
        getter = _getter(name)
        if kind == Nodetype.BASE:
            out.append((col, _ARROW[info[0]], getter))
        elif kind == Nodetype.NAME:
            for sub, typ, get in _columns(info, f"{col}_"):
                out.append((sub, typ, _chain(getter, get)))
        else:
            (sub_kind, sub_info), _ = info
            if sub_kind == Nodetype.BASE:
                out.append((col, pa.list_(_ARROW[sub_info[0]]), _chain(getter, _as_list)))
            else:
                out.append((col, pa.string(), _chain(getter, lambda v: json.dumps(_jsonable(v)))))
    return out


def _getter(name: str) -> Callable:
    return lambda m: getattr(m, name)


def _chain(first: Callable, then: Callable) -> Callable:
    return lambda m: then(first(m))


def _as_list(v):
    return v.tolist() if isinstance(v, np.ndarray) else list(v)


def _yaw(qw, qx, qy, qz):
    return np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


class Exporter:
    def __init__(self, rec: Recording, folder: Path, fmt: str):
        self.rec, self.folder, self.fmt = rec, folder, fmt
        self.tables: dict[str, _Table] = {}
        self._generic: dict[str, list] = {}

    def table(self, name: str, schema: pa.Schema) -> _Table:
        found = self.tables.get(name)
        if found is None:
            found = self.tables[name] = _Table(self.folder, name, self.fmt, schema)
        return found

    def run(self) -> dict[str, int]:
        types = self.rec.topics()
        for topic, t_ns, msg in self.rec.messages(
            topics=[t for t, ty in types.items() if ty in msgs.typestore.fielddefs]
        ):
            t = t_ns / layout.NS
            kind = msg.__msgtype__.rsplit("/", 1)[1]
            if kind in ("ModelStates", "LinkStates"):
                self._states("trajectories" if kind == "ModelStates" else "link_trajectories", t, msg)
            elif kind == "OmniVisionInfo":
                self._perception(t, topic, msg)
            else:
                self._row(snake(kind) if topic != topics.EVENTS else "events", t, topic, msg)
        for table in self.tables.values():
            table.close()
        return {name: table.rows for name, table in self.tables.items()}

    def _states(self, name: str, t: float, msg) -> None:
        names = list(msg.name)
        n = len(names)
        pose = np.asarray(msg.pose, dtype=float).reshape(n, 7)
        twist = np.asarray(msg.twist, dtype=float).reshape(n, 6)
        table = self.table(
            name,
            pa.schema(
                [
                    ("t", pa.float64()),
                    ("step", pa.uint64()),
                    ("model", pa.string()),
                    ("team", pa.string()),
                    ("robot", pa.int32()),
                ]
                + [
                    (c, pa.float64())
                    for c in ("x", "y", "z", "yaw", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")
                ]
            ),
        )
        teams, robots = [], []
        for model in names:
            parts = model.split("/")
            ok = len(parts) >= 2 and parts[1].isdigit()
            teams.append(parts[0] if ok else None)
            robots.append(int(parts[1]) if ok else None)
        cols = {
            "t": t,
            "step": int(msg.step),
            "model": names,
            "team": teams,
            "robot": robots,
            "yaw": _yaw(pose[:, 3], pose[:, 4], pose[:, 5], pose[:, 6]),
        }
        for k, c in enumerate(("x", "y", "z", "qw", "qx", "qy", "qz")):
            cols[c] = pose[:, k]
        for k, c in enumerate(("vx", "vy", "vz", "wx", "wy", "wz")):
            cols[c] = twist[:, k]
        table.add_columns(cols, n)

    def _perception(self, t: float, topic: str, msg) -> None:
        where = _where(topic)
        base = {
            "t": t,
            "team": where.get("team"),
            "robot": where.get("robot"),
            "stamp": msg.stamp,
            "tick": int(msg.tick),
        }
        lead = [
            ("t", pa.float64()),
            ("team", pa.string()),
            ("robot", pa.int32()),
            ("stamp", pa.float64()),
            ("tick", pa.uint64()),
        ]
        ball = self._cols("simatch_msgs/msg/BallInfo", "ball_")
        row = dict(base)
        for c, _, get in ball:
            row[c] = get(msg.ball)
        self.table("perception", pa.schema(lead + [(c, typ) for c, typ, _ in ball])).add(row)
        seen = self._cols("simatch_msgs/msg/RobotInfo", "seen_")
        robots = self.table("perception_robots", pa.schema(lead + [(c, typ) for c, typ, _ in seen]))
        for info in msg.robots:
            row = dict(base)
            for c, _, get in seen:
                row[c] = get(info)
            robots.add(row)
        ob = msg.obstacles
        fields = ("x", "y", "vx", "vy", "angle", "distance", "radius")
        n = len(ob.x)
        if n:
            table = self.table(
                "perception_obstacles", pa.schema(lead + [("index", pa.int32())] + [(c, pa.float64()) for c in fields])
            )
            cols = dict(base)
            cols["index"] = list(range(n))
            for c in fields:
                cols[c] = np.asarray(getattr(ob, c), dtype=float)
            table.add_columns(cols, n)

    def _cols(self, typename: str, prefix: str = "") -> list:
        key = prefix + typename
        found = self._generic.get(key)
        if found is None:
            found = self._generic[key] = _columns(typename, prefix)
        return found

    def _row(self, name: str, t: float, topic: str, msg) -> None:
        cols = self._cols(msg.__msgtype__)
        where = _where(topic)
        lead = [("t", pa.float64())] + [(k, pa.string() if k == "team" else pa.int32()) for k in where]
        table = self.tables.get(name) or self.table(name, pa.schema(lead + [(c, typ) for c, typ, _ in cols]))
        row = {"t": t, **where}
        for c, _, get in cols:
            row[c] = get(msg)
        table.add(row)


def export(
    path: str | Path, fmt: str = "parquet", out: str | Path | None = None
) -> tuple[Path, dict[str, int], Recording]:
    """Write the tables of the recording at ``path`` into folder ``out`` (default: next to the recording,
    ``<name>_tables``; a rosbag2 folder's beside the folder, which then holds the bag alone); returns the
    folder, the row count of each table, and the recording (its ``problems`` say what was damaged)."""
    if fmt not in FORMATS:
        raise ExportError(f"unknown format {fmt!r}: choose one of {', '.join(FORMATS)}")
    rec = Recording(path)
    folder = Path(out) if out is not None else rosbag2.beside(path, "_tables")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ExportError(f"cannot create the folder {folder}: {exc}") from None
    clash = [p.name for p in folder.glob(f"*.{fmt}")]
    if clash:
        raise ExportError(
            f"{folder} already holds {fmt} tables ({', '.join(sorted(clash)[:3])}...): "
            f"export into an empty folder (--out DIR); nothing was overwritten"
        )
    counts = Exporter(rec, folder, fmt).run()
    meta = dict(rec.metadata)
    for key in ("overrides", "command_line"):
        if key in meta:
            meta[key] = json.loads(meta[key])
    info = {"recording": str(rec.path), "metadata": meta, "end": rec.end, "tables": counts, "problems": rec.problems}
    (folder / "metadata.json").write_text(json.dumps(info, indent=2, default=str), encoding="utf-8")
    return folder, counts, rec
