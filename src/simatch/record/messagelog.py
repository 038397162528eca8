"""The recorder's message log: every bus message it records, as MCAP Message records in one buffer.

A recording encodes some two thousand messages per simulated second on the thread that runs the simulation,
so the log is the bus callback itself (``log(topic, msg)``): it looks the topic up, appends the record header
(opcode, length, channel id, sequence 0, log time and publish time = ``log.now``) and the message's CDR bytes,
and counts the message. Where the C extension is built, `new_log` returns its ``Log`` (`simatch.msgs.cdr`),
which does all of that in one C call; `MessageLog` is the same in Python, byte for byte, for machines without a
C compiler (and for the tests that compare the two).

Interface of both:

* ``log.add(topic, channel_id, typename, clock=0)``: record ``topic`` on that channel. ``clock``:
  `CLOCK_STEP`, the message's ``step`` (a physics step) sets the log time first; `CLOCK_STEP | CLOCK_TICK`,
  it also opens a new memo period (see `simatch.msgs.cdr.Codec`): model states and the clock.
* ``log.timing(step_ns, chunk_ns, on_chunk)``: the physics step and the chunk length [ns]; when a clock
  message moves the time into a new chunk, ``on_chunk()`` is called (the recorder takes the chunk then)
  before that message is logged.
* ``log(topic, msg)``: a topic not added, or a message the encoder does not take as it is, goes to
  ``fallback(topic, msg)`` instead, with nothing of it left in the buffer (the recorder then opens the
  channel, or encodes the message with the pure-Python encoder, or counts it as malformed).
* ``log.record(channel_id, data)``: a message already encoded (the 3D scene); ``log.append(data)``: raw
  records (schemas and channels, which must precede their first message in the chunk).
* ``log.take() -> (data, {channel_id: messages}, first, last)``: everything since the last take (one chunk)
  and the log times of its first and last message (-1 if it holds none). ``data`` is the log's buffer itself,
  handed over without a copy (a bytes-like object: a bytearray here, a read-only buffer of the C log whose
  memory the log takes again once it is dropped; ``bytes(data)`` copies it), or, after ``into``, a memoryview
  of the memory given there.
* ``log.into(buffer)``: the chunk's records go into ``buffer`` (a writable buffer: memory shared with the
  writer process, `simatch.record.writer`), if they fit; ``take`` then hands over ``memoryview(buffer)[:n]``
  (its ``obj`` is the buffer's exporter), and the log writes no more into it until it is given again. A chunk
  that outgrows it is handed over as without it. The C log writes the records there as they come (no copy);
  this one copies them there at ``take``. ``into(None)``: no such memory.
* ``log.poses(topic, channel_id, every, fallback)`` and ``log.pose_template(names, template, slots, grid,
  turn_grid)``: a pose template (the recorder's 3D scene). After a message on ``topic`` (model states:
  ``name``, ``pose`` as rows of x y z qw qx qy qz) of a physics step that is a multiple of ``every``, a
  record on ``channel_id``: `fill_poses` of the template, if its names are the template's; anything else
  (no template yet, other names, a pose that is not a float buffer of enough rows) goes to
  ``fallback(msg)``, which may set a new template and records what it makes itself.
* ``log.ros_clock(topic, channel_id)``: after each message on ``topic`` (the clock), a record on ``channel_id``
  of ROS 2's clock at the log time (`simatch.record.layout.ros_clock`; none beyond int32 seconds).
* ``log.for_topic(topic)``: a callable ``f(msg)`` that logs as ``log(topic, msg)`` does; the in-process bus
  calls it for the topic's messages (`simatch.bus.inproc`): the C log's finds the topic's channel once, not
  per message, and is called without a partial.
* ``log.forget()``: a new memo period; ``log.now``: the log time [ns]; ``log.size``: bytes held since the
  last take.
"""

from __future__ import annotations

import functools
import math
import operator
import struct
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .. import msgs
from ..msgs import cdr
from .layout import ros_clock

#: a Message record up to its data: opcode, record length, channel id, sequence, log time, publish time
MESSAGE_HEADER = struct.Struct("<BQHIQQ")
MESSAGE_FIXED = 22  # bytes of a Message record's content before its data
OPCODE_MESSAGE = 0x05
_GAP = bytes(MESSAGE_HEADER.size)
_pack_header = MESSAGE_HEADER.pack_into
_MAX_NS = 2**63 - 1  # log times are signed 64-bit in the C log

Fallback = Callable[[str, Any], None]
CLOCK_STEP = 1  # the message's step sets the log time
CLOCK_TICK = 2  # ... and opens a new memo period


#: a slot of a pose template: (byte offset of a geometry_msgs/Pose in the template, row of the model in the
#: poses, height drawn or NaN for the row's own, whether the row's turn about z is drawn)
PoseSlot = tuple[int, int, float, bool]
_POSE = struct.Struct("<7d")


def fill_poses(template: bytes, slots: Sequence[PoseSlot], pose, grid: float, turn_grid: float) -> bytes:
    """``template`` with a Pose written at each slot from ``pose`` (rows of x y z qw qx qy qz): the position
    snapped to multiples of 1/``grid``, the height the slot's (or the row's, snapped, if NaN), the
    orientation the row's turn about z snapped to 1/``turn_grid`` (or none). The C log writes the same
    bytes."""
    rows = np.asarray(pose, dtype=np.float64).reshape(-1, 7)
    needed = 1 + max((slot[1] for slot in slots), default=-1)
    if len(rows) < needed:
        raise ValueError(f"{len(rows)} poses where the template shows {needed} models")
    steps = np.array([grid, grid, grid, turn_grid, turn_grid, turn_grid, turn_grid])
    snapped = (np.round(rows * steps) / steps).tolist()
    buf = bytearray(template)
    for offset, row, z, turn in slots:
        x, y, pz, qw, _, _, qz = snapped[row]
        if not turn:
            qz, qw = 0.0, 1.0
        _POSE.pack_into(buf, offset, x, y, pz if math.isnan(z) else z, 0.0, 0.0, qz, qw)
    return bytes(buf)


def new_log(fallback: Fallback, *, accelerate: bool = True):
    """The C ``Log`` where it is built (and ``accelerate``), else a `MessageLog`."""
    if accelerate and cdr.Log is not None:
        return cdr.Log(cdr.Codec(msgs.typestore, memo=True).program, fallback)
    return MessageLog(cdr.Codec(msgs.typestore, memo=True, accelerate=False), fallback)


class MessageLog:
    """The message log in Python (see the module docstring)."""

    def __init__(self, codec: cdr.Codec, fallback: Fallback):
        self.now = 0
        self._codec = codec
        self._fallback = fallback
        self._channels: dict[str, tuple[int, Callable, int]] = {}
        self._buf = bytearray()
        self._counts: dict[int, int] = {}
        self._first = self._last = -1
        self._step_ns = self._chunk_ns = self._next_chunk = 0
        self._on_chunk: Callable[[], None] | None = None
        self._step = -1
        self._poses: tuple[str, int, int, Callable[[Any], None]] | None = None
        self._ros: tuple[str, int] | None = None
        self._template: tuple[Any, bytes, list[PoseSlot], float, float] | None = None
        self._target: memoryview | None = None

    @property
    def size(self) -> int:
        return len(self._buf)

    def add(self, topic: str, channel_id: int, typename: str, clock: int = 0) -> None:
        self._channels[topic] = (
            _channel(channel_id),
            self._codec.appender(typename),
            clock & (CLOCK_STEP | CLOCK_TICK),
        )

    def timing(self, step_ns: int, chunk_ns: int, on_chunk: Callable[[], None]) -> None:
        if step_ns <= 0 or chunk_ns <= 0 or not callable(on_chunk):
            raise ValueError("timing(step_ns > 0, chunk_ns > 0, on_chunk callable)")
        self._step_ns, self._chunk_ns, self._on_chunk = step_ns, chunk_ns, on_chunk
        self._next_chunk = (self.now // chunk_ns + 1) * chunk_ns

    def __call__(self, topic: str, msg) -> None:
        entry = self._channels.get(topic)
        if entry is None:
            return self._fallback(topic, msg)
        cid, append, clock = entry
        if clock:
            self._clock(msg, clock)
        buf = self._buf
        start = len(buf)
        buf += _GAP  # the record header, written once the message's size is known
        try:
            n = append(msg, buf)
        except Exception:  # the fallback encodes it again and reports what is wrong
            del buf[start:]
            self._fallback(topic, msg)
        else:
            now = self.now
            _pack_header(buf, start, OPCODE_MESSAGE, MESSAGE_FIXED + n, cid, 0, now, now)
            self._counted(cid)
        if self._poses is not None and clock and topic == self._poses[0]:
            self._poses_after(msg)
        if self._ros is not None and topic == self._ros[0]:
            sec, nsec = divmod(self.now, 1_000_000_000)
            if -(2**31) <= sec < 2**31:
                self.record(self._ros[1], ros_clock(self.now))

    def ros_clock(self, topic: str, channel_id: int) -> None:
        self._ros = (topic, _channel(channel_id))

    def poses(self, topic: str, channel_id: int, every: int, fallback: Callable[[Any], None]) -> None:
        if every <= 0 or not callable(fallback):
            raise ValueError("poses(topic, channel_id, every > 0, fallback callable)")
        self._poses = (topic, _channel(channel_id), every, fallback)
        self._template = None

    def pose_template(self, names, template: bytes, slots: Sequence[PoseSlot], grid: float, turn_grid: float) -> None:
        if self._poses is None:
            raise ValueError("pose_template: call poses() first")
        if not (grid > 0.0 and turn_grid > 0.0):
            raise ValueError("pose_template: grids must be positive")
        checked = []
        for offset, row, z, turn in slots:
            if offset < 4 or offset + _POSE.size > len(template) or row < 0:
                raise ValueError("pose_template: a slot outside the template")
            checked.append((operator.index(offset), operator.index(row), float(z), bool(turn)))
        self._template = (names, bytes(template), checked, float(grid), float(turn_grid))

    def _poses_after(self, msg) -> None:
        _, cid, every, fallback = self._poses
        if self._step < 0 or self._step % every:
            return
        data = None
        if self._template is not None:
            names, template, slots, grid, turn_grid = self._template
            try:
                if msg.name == names:
                    data = fill_poses(template, slots, _float_buffer(msg.pose), grid, turn_grid)
            except Exception:  # not as the template expects: the fallback says what is wrong
                data = None
        if data is None:
            return fallback(msg)
        self.record(cid, data)

    def _clock(self, msg, clock: int) -> None:
        try:
            step = operator.index(msg.step)
        except (AttributeError, TypeError, ValueError):
            step = -1
        self._step = step
        if self._step_ns > 0 and 0 <= step <= _MAX_NS // self._step_ns:  # else ignored, as by the C log
            now = step * self._step_ns
            if now != self.now:
                self.now = now
                if self._on_chunk is not None and now >= self._next_chunk:
                    self._next_chunk = (now // self._chunk_ns + 1) * self._chunk_ns
                    self._on_chunk()
        if clock & CLOCK_TICK:
            self.forget()

    def _counted(self, cid: int) -> None:
        self._counts[cid] = self._counts.get(cid, 0) + 1
        if self._first < 0:
            self._first = self.now
        self._last = self.now

    def record(self, channel_id: int, data) -> None:
        cid = _channel(channel_id)
        now = self.now
        self._buf += MESSAGE_HEADER.pack(OPCODE_MESSAGE, MESSAGE_FIXED + len(data), cid, 0, now, now)
        self._buf += data
        self._counted(cid)

    def append(self, data) -> None:
        self._buf += data

    def for_topic(self, topic: str) -> Callable[[Any], None]:
        return functools.partial(self, topic)

    def into(self, buffer) -> None:
        self._target = None if buffer is None else _writable(buffer)

    def take(self) -> tuple[bytearray | memoryview, dict[int, int], int, int]:
        data, target = self._buf, self._target
        if target is not None and len(data) <= len(target):
            target[: len(data)] = data
            data = target[: len(data)]
        self._target = None
        out = (data, self._counts, self._first, self._last)
        self._buf = bytearray()
        self._counts = {}
        self._first = self._last = -1
        return out

    def forget(self) -> None:
        self._codec.forget()


def _float_buffer(pose):
    """``pose`` as the C log takes it: a float32 or float64 buffer (else ValueError)."""
    view = memoryview(pose)
    if view.format not in ("f", "d", "<f", "<d", "=f", "=d", "@f", "@d"):
        raise ValueError(f"poses of format {view.format!r}")
    return np.frombuffer(view.cast("B"), dtype=np.float32 if view.format[-1] == "f" else np.float64)


def _writable(buffer) -> memoryview:
    """``buffer`` as the C log takes it: a writable contiguous buffer (else BufferError)."""
    view = memoryview(buffer)
    if view.readonly:
        raise BufferError("into: a writable buffer")
    if not view.c_contiguous:
        raise BufferError("into: a contiguous buffer")
    return view.cast("B")


def _channel(channel_id: int) -> int:
    if not 0 <= channel_id <= 0xFFFF:
        raise ValueError("channel id: 0 to 65535")
    return channel_id
