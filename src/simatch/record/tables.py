"""Dataset export (``simatch export FILE --format parquet|csv``): a recording as tidy tables.

One table per kind of observation, one row per observation, one column per variable, every table with
``t`` (simulated seconds) and, for robot and team topics, ``team`` and ``robot``:

* ``trajectories``: one row per model (robot or ball) per physics step: pose (x, y, z, yaw and the
  quaternion) and twist, world frame. (``link_trajectories`` likewise, only when link states were recorded.)
* ``events``: the event log (goals, fouls, game commands, kicks...): type, team, robot, where, value, limit.
* ``perception``: one row per robot per control tick: what it saw of the ball (team frame);
  ``perception_robots`` (its own team as it perceived it) and ``perception_obstacles`` (every other
  robot it perceived), one row per perceived robot.
* one table per other message type (``vel_cmd``, ``action_cmd``, ``strategy_info``, ``coach_info``,
  ``team_strategy``, ``game_state``, ``ball_contacts``, ``clock``, ``operator_command``,
  ``state_fingerprint``, ``component_fingerprints``, ``world_inputs``): scalar fields as columns, nested
  messages flattened (``pass_cmd_catch_x``); a variable-length field is a list column in Parquet (a list of
  structs for a list of messages, e.g. ``team_strategy.strategies``) and JSON text in CSV.

Every table in `ALWAYS` is written, with its columns, even when the recording holds none of its messages (a
run nobody intervened in has no ``operator_command`` rows). An empty value is null in every table: an empty
string, a NaN that stands for "none" (a robot with no target), and in ``events`` what ``simatch run --json``
leaves out of an event (robot 0, a place or a measurement that is all zero); an empty list stays an empty list.

``metadata.json`` holds the run's metadata (scene text, overrides, seed, version, command line).

The tables are written with pyarrow, in batches (a long match never has to fit in memory), a column at a time:
the values of each field are gathered for a whole batch of messages and turned into one Arrow array (numpy
where it can), which is what makes an export faster than the run it comes from. pyarrow writes Parquet and CSV
from the same columnar batches, and pandas (``read_parquet``) and polars (``read_parquet``, ``scan_parquet``)
read its files directly.
"""

from __future__ import annotations

import gc
import json
import operator
import re
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pyarrow as pa
import pyarrow.compute as pc
import pyarrow.csv as pacsv
import pyarrow.parquet as pq
from rosbags.interfaces import Nodetype

from .. import msgs
from ..bus import topics
from . import layout, rosbag2
from .reader import Recording

FORMATS = ("parquet", "csv")
BATCH_ROWS = 200_000  # rows of a table gathered before they are written
_NUMPY = {
    "bool": np.bool_,
    "byte": np.uint8,
    "char": np.uint8,
    "octet": np.uint8,
    "int8": np.int8,
    "uint8": np.uint8,
    "int16": np.int16,
    "uint16": np.uint16,
    "int32": np.int32,
    "uint32": np.uint32,
    "int64": np.int64,
    "uint64": np.uint64,
    "float32": np.float32,
    "float64": np.float64,
}
_ARROW = {name: pa.from_numpy_dtype(np.dtype(t)) for name, t in _NUMPY.items()} | {"string": pa.string()}
_ARROW["bool"] = pa.bool_()

#: what a table's rows say besides the message: robot topics name the team and the robot, team topics the team
ROBOT_LEAD = ("team", "robot")
TEAM_LEAD = ("team",)
#: the tables every export writes (name -> message type, lead columns), with their columns even when empty
ALWAYS: dict[str, tuple[str, tuple[str, ...]]] = {
    "trajectories": ("ModelStates", ()),
    "events": ("GameEvent", ()),
    "perception": ("OmniVisionInfo", ROBOT_LEAD),
    "perception_robots": ("OmniVisionInfo", ROBOT_LEAD),
    "perception_obstacles": ("OmniVisionInfo", ROBOT_LEAD),
    "vel_cmd": ("VelCmd", ROBOT_LEAD),
    "action_cmd": ("ActionCmd", ROBOT_LEAD),
    "strategy_info": ("StrategyInfo", ROBOT_LEAD),
    "team_strategy": ("TeamStrategy", TEAM_LEAD),
    "coach_info": ("CoachInfo", TEAM_LEAD),
    "game_state": ("GameState", ()),
    "ball_contacts": ("BallContacts", ()),
    "clock": ("Clock", ()),
    "operator_command": ("OperatorCommand", ()),
    "state_fingerprint": ("StateFingerprint", ()),
    "component_fingerprints": ("ComponentFingerprints", ()),
    "world_inputs": ("WorldInputs", ()),
}
STATE_COLUMNS = ("x", "y", "z", "yaw", "qw", "qx", "qy", "qz", "vx", "vy", "vz", "wx", "wy", "wz")
OBSTACLE_FIELDS = ("x", "y", "vx", "vy", "angle", "distance", "radius")


class ExportError(Exception):
    """An export that cannot be carried out (bad format, unwritable folder)."""


def snake(name: str) -> str:
    return re.sub(r"(?<=[a-z0-9])([A-Z])", r"_\1", name).lower()


def _typename(kind: str) -> str:
    return f"simatch_msgs/msg/{kind}"


def _where(topic: str) -> dict:
    """team and robot of a robot or team topic (``cyan/2/VelCmd`` -> team cyan, robot 2)."""
    parts = topic.split("/")
    if len(parts) >= 3 and parts[1].isdigit():
        return {"team": parts[0], "robot": int(parts[1])}
    if len(parts) == 2:
        return {"team": parts[0]}
    return {}


# --- columns of a message type, built a whole batch at a time -------------------------------------------------
def _floats(values, dtype) -> pa.Array:
    """Floats with NaN ("no value") as null."""
    arr = np.asarray(values, dtype=dtype)
    nan = np.isnan(arr)
    return pa.array(arr, mask=nan if nan.any() else None)


def _list(seqs: list, values: pa.Array) -> pa.Array:
    lengths = np.fromiter((len(s) for s in seqs), dtype=np.int32, count=len(seqs))
    offsets = np.zeros(len(seqs) + 1, dtype=np.int32)
    np.cumsum(lengths, out=offsets[1:])
    return pa.ListArray.from_arrays(pa.array(offsets), values)


class Fields:
    """The columns of a message type: nested messages flattened (``pass_cmd_catch_x``), sequences as lists (of
    structs for sequences of messages). `arrays` turns a list of messages into one Arrow array per column."""

    _cache: dict[tuple[str, str], Fields] = {}

    def __init__(self, typename: str, prefix: str = ""):
        #: (column, arrow type, builder: list of messages -> pa.Array)
        self.columns: list[tuple[str, pa.DataType, Callable[[list], pa.Array]]] = []
        _, fields = msgs.typestore.fielddefs[typename]
        for name, (kind, info) in fields:
            col = f"{prefix}{name}"
            get = operator.attrgetter(name)
            if kind == Nodetype.BASE:
                self.columns.append((col, _ARROW[info[0]], self._base(get, info[0])))
            elif kind == Nodetype.NAME:
                nested = Fields.of(info, f"{col}_")
                for sub, typ, build in nested.columns:
                    self.columns.append((sub, typ, self._nested(get, build)))
            else:
                (sub_kind, sub_info), _ = info
                if sub_kind == Nodetype.BASE:
                    typ = pa.list_(_ARROW[sub_info[0]])
                    self.columns.append((col, typ, self._sequence(get, sub_info[0])))
                else:
                    inner = Fields.of(sub_info)
                    typ = pa.list_(inner.struct)
                    self.columns.append((col, typ, self._messages(get, inner)))

    @classmethod
    def of(cls, typename: str, prefix: str = "") -> Fields:
        found = cls._cache.get((typename, prefix))
        if found is None:
            found = cls._cache[(typename, prefix)] = cls(typename, prefix)
        return found

    @property
    def schema(self) -> list[pa.Field]:
        return [pa.field(c, t) for c, t, _ in self.columns]

    @property
    def struct(self) -> pa.StructType:
        return pa.struct(self.schema)

    def arrays(self, messages: list) -> dict[str, pa.Array]:
        return {c: build(messages) for c, _, build in self.columns}

    @staticmethod
    def _base(get, base: str) -> Callable[[list], pa.Array]:
        if base == "string":
            return lambda ms: pa.array([v or None for v in map(get, ms)], pa.string())
        dtype = _NUMPY[base]
        if base.startswith("float"):
            return lambda ms: _floats(np.fromiter(map(get, ms), dtype=dtype, count=len(ms)), dtype)
        typ = _ARROW[base]
        return lambda ms: pa.array(np.fromiter(map(get, ms), dtype=dtype, count=len(ms)), typ)

    @staticmethod
    def _nested(get, build) -> Callable[[list], pa.Array]:
        return lambda ms: build(list(map(get, ms)))

    @staticmethod
    def _sequence(get, base: str) -> Callable[[list], pa.Array]:
        def build(ms: list) -> pa.Array:
            seqs = list(map(get, ms))
            if base == "string":
                values = pa.array([v for s in seqs for v in s], pa.string())
            else:
                dtype = _NUMPY[base]
                flat = np.concatenate(seqs).astype(dtype, copy=False) if seqs else np.empty(0, dtype)
                values = _floats(flat, dtype) if base.startswith("float") else pa.array(flat, _ARROW[base])
            return _list(seqs, values)

        return build

    @staticmethod
    def _messages(get, inner: Fields) -> Callable[[list], pa.Array]:
        def build(ms: list) -> pa.Array:
            seqs = list(map(get, ms))
            flat = [x for s in seqs for x in s]
            arrays = inner.arrays(flat)
            struct = pa.StructArray.from_arrays([arrays[c] for c, _, _ in inner.columns], fields=inner.schema)
            return _list(seqs, struct)

        return build


# --- one output table ---------------------------------------------------------------------------------------------
class _Table:
    """The batches of one table, written to ``DIR/<name>.<format>`` as they come."""

    def __init__(self, folder: Path, name: str, fmt: str, schema: pa.Schema):
        self.path = folder / f"{name}.{fmt}"
        self.fmt = fmt
        self.schema = schema
        self.rows = 0
        self._writer = None

    def write(self, columns: dict[str, pa.Array | np.ndarray | list], n: int) -> None:
        arrays = []
        for f in self.schema:
            value = columns.get(f.name)
            if value is None:
                arrays.append(pa.nulls(n, f.type))
            elif isinstance(value, pa.Array):
                arrays.append(value if value.type == f.type else value.cast(f.type))
            else:
                arrays.append(pa.array(value, f.type))
        batch = pa.record_batch(arrays, schema=self.schema)
        self._open()
        self._writer.write_batch(_csv_batch(batch) if self.fmt == "csv" else batch)
        self.rows += n

    def _open(self) -> None:
        if self._writer is None:
            if self.fmt == "parquet":
                # dictionary encoding pays for names (team, model, type), not for measurements
                names = [f.name for f in self.schema if pa.types.is_string(f.type)]
                self._writer = pq.ParquetWriter(self.path, self.schema, use_dictionary=names)
            else:
                self._writer = pacsv.CSVWriter(self.path, _csv_schema(self.schema))

    def close(self) -> None:
        self._open()  # an empty table is written too: its columns, no rows
        self._writer.close()


def _csv_schema(schema: pa.Schema) -> pa.Schema:
    """Lists have no CSV form: they become JSON text."""
    return pa.schema([pa.field(f.name, pa.string() if pa.types.is_list(f.type) else f.type) for f in schema])


def _csv_batch(batch: pa.RecordBatch) -> pa.RecordBatch:
    arrays = [_json_text(col) if pa.types.is_list(col.type) else col for col in batch.columns]
    return pa.record_batch(arrays, schema=_csv_schema(batch.schema))


def _json_text(arr: pa.Array) -> pa.Array:
    """Each value of ``arr`` as JSON text, built with Arrow's string kernels (a Python object per number made the
    CSV export slower than the run): numbers as the CSV writer writes them (the shortest text that reads back
    to the same number of the column's type), null (and a non-finite number) as ``null``."""
    typ = arr.type
    if pa.types.is_list(typ):
        items = _json_text(arr.values)
        joined = pc.binary_join(pa.ListArray.from_arrays(arr.offsets, items), ",")
        text = pc.binary_join_element_wise("[", joined, "]", "")
    elif pa.types.is_struct(typ):
        parts = [
            pc.binary_join_element_wise(json.dumps(f.name) + ":", _json_text(arr.field(i)), "")
            for i, f in enumerate(typ)
        ]
        text = pc.binary_join_element_wise("{", pc.binary_join_element_wise(*parts, ","), "}", "")
    elif pa.types.is_string(typ):
        text = pa.array([json.dumps(v) for v in arr.to_pylist()], pa.string())
    else:
        text = pc.cast(arr, pa.string())
        if pa.types.is_floating(typ):
            text = pc.if_else(pc.is_finite(arr), text, None)
    text = pc.fill_null(text, "null")
    return pc.if_else(arr.is_null(), None, text) if arr.null_count and pa.types.is_nested(typ) else text


# --- the export ---------------------------------------------------------------------------------------------------
class Exporter:
    """Reads the recording once; each table gathers its messages and writes them a batch at a time."""

    def __init__(self, rec: Recording, folder: Path, fmt: str):
        self.rec, self.folder, self.fmt = rec, folder, fmt
        self.tables: dict[str, _Table] = {}
        self._pending: dict[str, list] = {}  # table -> [(t, topic, msg)] not yet written
        self._rows: dict[str, int] = {}  # table -> rows pending (estimated)
        self._kinds: dict[str, tuple[str, str]] = {}  # topic -> (table, message kind)
        self._wheres: dict[str, dict] = {}  # topic -> its team and robot

    def run(self) -> dict[str, int]:
        # the batches hold a great many small objects, none in a cycle: the cyclic garbage collector would walk
        # them again and again for nothing (a sixth of the export's time)
        collecting = gc.isenabled()
        gc.disable()
        try:
            return self._run()
        finally:
            if collecting:
                gc.enable()

    def _run(self) -> dict[str, int]:
        types = self.rec.topics()
        # simatch's own types (the tables are named after them); ROS 2's /clock repeats /simatch/clock
        wanted = [t for t, ty in types.items() if ty.startswith("simatch_msgs/") and ty in msgs.typestore.fielddefs]
        route: dict[str, tuple[list, int, str, str]] = {}  # topic -> (its table's pending batch, its size, ...)
        for topic, t_ns, msg in self.rec.messages(topics=wanted):
            found = route.get(topic)
            if found is None:
                name, kind = self._kind(topic, msg)
                found = route[topic] = (
                    self._pending.setdefault(name, []),
                    max(1, BATCH_ROWS // self._rows_per(kind, msg)),
                    name,
                    kind,
                )
            pending, size, name, kind = found
            pending.append((t_ns / layout.NS, topic, msg))
            if len(pending) >= size:
                self._flush(name, kind)
        for name, pending in self._pending.items():
            if pending:
                self._flush(name, self._kind(pending[0][1], pending[0][2])[1])
        for name, (typename, lead) in ALWAYS.items():
            if name not in self.tables:
                self._table(name, self._schema(name, typename, lead))
        for table in self.tables.values():
            table.close()
        return {name: table.rows for name, table in self.tables.items()}

    def _kind(self, topic: str, msg) -> tuple[str, str]:
        kind = msg.__msgtype__.rsplit("/", 1)[1]
        if kind == "ModelStates":
            name = "trajectories"
        elif kind == "LinkStates":
            name = "link_trajectories"
        elif kind == "OmniVisionInfo":
            name = "perception"
        elif topic == topics.EVENTS:
            name = "events"
        else:
            name = snake(kind)
        self._kinds[topic] = (name, kind)
        return name, kind

    @staticmethod
    def _rows_per(kind: str, msg) -> int:
        if kind in ("ModelStates", "LinkStates"):
            return len(msg.name)
        if kind == "OmniVisionInfo":
            return 1 + len(msg.robots) + len(msg.obstacles.x)
        return 1

    def _table(self, name: str, schema: pa.Schema) -> _Table:
        found = self.tables.get(name)
        if found is None:
            found = self.tables[name] = _Table(self.folder, name, self.fmt, schema)
        return found

    # --- schemas -----------------------------------------------------------------------------------------------
    @staticmethod
    def _lead(lead: tuple[str, ...]) -> list[pa.Field]:
        return [pa.field("t", pa.float64())] + [pa.field(k, pa.string() if k == "team" else pa.int32()) for k in lead]

    def _schema(self, name: str, typename_or_kind: str, lead: tuple[str, ...]) -> pa.Schema:
        kind = typename_or_kind
        if kind in ("ModelStates", "LinkStates"):
            return pa.schema(
                [("t", pa.float64()), ("step", pa.uint64()), ("model", pa.string())]
                + [("team", pa.string()), ("robot", pa.int32())]
                + [(c, pa.float64()) for c in STATE_COLUMNS]
            )
        head = self._lead(lead)
        if kind == "OmniVisionInfo":
            head += [pa.field("stamp", pa.float64()), pa.field("tick", pa.uint64())]
            if name == "perception":
                return pa.schema(head + Fields.of(_typename("BallInfo"), "ball_").schema)
            if name == "perception_robots":
                return pa.schema(head + Fields.of(_typename("RobotInfo"), "seen_").schema)
            return pa.schema(
                head + [pa.field("index", pa.int32())] + [pa.field(c, pa.float64()) for c in OBSTACLE_FIELDS]
            )
        return pa.schema(head + Fields.of(_typename(kind)).schema)

    # --- batches ------------------------------------------------------------------------------------------------
    def _flush(self, name: str, kind: str) -> None:
        pending = self._pending[name]
        batch = pending[:]
        pending.clear()
        if not batch:
            return
        if kind in ("ModelStates", "LinkStates"):
            self._states(name, batch)
        elif kind == "OmniVisionInfo":
            self._perception(batch)
        else:
            self._messages(name, kind, batch)

    def _lead_columns(self, batch: list, lead: tuple[str, ...]) -> dict:
        """``t`` and the lead columns (team, robot) of a batch, one value per message."""
        cols: dict = {"t": np.fromiter((t for t, _, _ in batch), dtype=np.float64, count=len(batch))}
        if lead:
            wheres = [self._where(topic) for _, topic, _ in batch]
            for k in lead:
                cols[k] = pa.array([w.get(k) for w in wheres], pa.string() if k == "team" else pa.int32())
        return cols

    def _where(self, topic: str) -> dict:
        found = self._wheres.get(topic)
        if found is None:
            found = self._wheres[topic] = _where(topic)
        return found

    def _messages(self, name: str, kind: str, batch: list) -> None:
        lead = ALWAYS[name][1] if name in ALWAYS else tuple(_where(batch[0][1]))
        table = self._table(name, self._schema(name, kind, lead))
        ms = [m for _, _, m in batch]
        cols = self._lead_columns(batch, lead)
        cols.update(Fields.of(_typename(kind)).arrays(ms))
        if name == "events":
            _as_in_the_event_log(cols, ms)
        table.write(cols, len(batch))

    def _states(self, name: str, batch: list) -> None:
        table = self._table(name, self._schema(name, "ModelStates", ()))
        counts = np.fromiter((len(m.name) for _, _, m in batch), dtype=np.int64, count=len(batch))
        pose = np.concatenate([m.pose for _, _, m in batch]).astype(np.float64).reshape(-1, 7)
        twist = np.concatenate([m.twist for _, _, m in batch]).astype(np.float64).reshape(-1, 6)
        names = [n for _, _, m in batch for n in m.name]
        owners = {n: _owner(n) for n in set(names)}
        cols = {
            "t": np.repeat(np.fromiter((t for t, _, _ in batch), dtype=np.float64, count=len(batch)), counts),
            "step": np.repeat(np.fromiter((m.step for _, _, m in batch), dtype=np.uint64, count=len(batch)), counts),
            "model": names,
            "team": [owners[n][0] for n in names],
            "robot": pa.array([owners[n][1] for n in names], pa.int32()),
            "yaw": _yaw(pose[:, 3], pose[:, 4], pose[:, 5], pose[:, 6]),
        }
        for k, c in enumerate(("x", "y", "z", "qw", "qx", "qy", "qz")):
            cols[c] = pose[:, k]
        for k, c in enumerate(("vx", "vy", "vz", "wx", "wy", "wz")):
            cols[c] = twist[:, k]
        table.write(cols, len(names))

    def _perception(self, batch: list) -> None:
        ms = [m for _, _, m in batch]
        cols = self._lead_columns(batch, ROBOT_LEAD)
        cols["stamp"] = np.fromiter((m.stamp for m in ms), dtype=np.float64, count=len(ms))
        cols["tick"] = np.fromiter((m.tick for m in ms), dtype=np.uint64, count=len(ms))
        lead = dict(cols)
        # what each robot saw of the ball: one row per message
        cols.update(Fields.of(_typename("BallInfo"), "ball_").arrays([m.ball for m in ms]))
        self._table("perception", self._schema("perception", "OmniVisionInfo", ROBOT_LEAD)).write(cols, len(ms))
        # its team-mates as it perceived them, and the obstacles: one row per perceived robot
        for name, counts in (
            ("perception_robots", np.fromiter((len(m.robots) for m in ms), dtype=np.int64, count=len(ms))),
            ("perception_obstacles", np.fromiter((len(m.obstacles.x) for m in ms), dtype=np.int64, count=len(ms))),
        ):
            table = self._table(name, self._schema(name, "OmniVisionInfo", ROBOT_LEAD))
            n = int(counts.sum())
            if n == 0:
                continue
            rows = np.repeat(np.arange(len(ms)), counts)  # the message of each row
            cols = {k: v.take(pa.array(rows)) if isinstance(v, pa.Array) else v[rows] for k, v in lead.items()}
            if name == "perception_robots":
                cols.update(Fields.of(_typename("RobotInfo"), "seen_").arrays([r for m in ms for r in m.robots]))
            else:
                cols["index"] = (np.arange(n) - np.repeat(np.cumsum(counts) - counts, counts)).astype(np.int32)
                obstacles = [m.obstacles for m in ms]
                for c in OBSTACLE_FIELDS:
                    cols[c] = _floats(np.concatenate([getattr(o, c) for o in obstacles]), np.float64)
            table.write(cols, n)


def _owner(model: str) -> tuple[str | None, int | None]:
    parts = model.split("/")
    if len(parts) >= 2 and parts[1].isdigit():
        return parts[0], int(parts[1])
    return None, None


def _as_in_the_event_log(cols: dict, events: list) -> None:
    """Null where ``simatch run --json`` leaves a field out of an event: robot 0, a place or a measurement that is
    all zero (the message has no null of its own)."""
    robot = np.fromiter((e.robot for e in events), dtype=np.int32, count=len(events))
    cols["robot"] = pa.array(robot, mask=robot == 0)
    for a, b in (("x", "y"), ("value", "limit")):
        va = np.fromiter((getattr(e, a) for e in events), dtype=np.float64, count=len(events))
        vb = np.fromiter((getattr(e, b) for e in events), dtype=np.float64, count=len(events))
        none = (va == 0) & (vb == 0)
        cols[a], cols[b] = pa.array(va, mask=none), pa.array(vb, mask=none)


def _yaw(qw, qx, qy, qz):
    return np.arctan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


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
