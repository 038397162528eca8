"""The recorder's message log: every bus message it records, as MCAP Message records in one buffer.

The log is the bus callback itself (``log(topic, msg)``), so that recording adds no Python frame per message
on the thread that runs the simulation: it looks the topic up, appends the record header (opcode, length,
channel id, sequence 0, log time and publish time = ``log.now``) and the message's CDR bytes, and counts the
message. It is written in C (``Log``, record/_messagelog.c, compiled into the extension
``simatch.msgs._cdr_accel`` with the CDR encoder it calls); `new_log` makes one.

Interface:

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
  handed over without a copy (a read-only buffer whose memory the log takes again once it is dropped;
  ``bytes(data)`` copies it), or, after ``into``, a memoryview of the memory given there.
* ``log.into(buffer)``: the chunk's records go into ``buffer`` (a writable buffer: memory shared with the
  writer process, `simatch.record.writer`), if they fit; ``take`` then hands over ``memoryview(buffer)[:n]``
  (its ``obj`` is the buffer's exporter), and the log writes no more into it until it is given again. A chunk
  that outgrows it is handed over as without it. The log writes the records there as they come (no copy).
  ``into(None)``: no such memory.
* ``log.poses(topic, channel_id, every, fallback)`` and ``log.pose_template(names, template, slots, grid,
  turn_grid)``: a pose template (the recorder's 3D scene). After a message on ``topic`` (model states:
  ``name``, ``pose`` as rows of x y z qw qx qy qz) of a physics step that is a multiple of ``every``, a
  record on ``channel_id``: `fill_poses` of the template, if its names are the template's; anything else
  (no template yet, other names, a pose that is not a float buffer of enough rows) goes to
  ``fallback(msg)``, which may set a new template and records what it makes itself.
* ``log.ros_clock(topic, channel_id)``: after each message on ``topic`` (the clock), a record on ``channel_id``
  of ROS 2's clock at the log time (`simatch.record.layout.ros_clock`; none beyond int32 seconds).
* ``log.for_topic(topic)``: a callable ``f(msg)`` that logs as ``log(topic, msg)`` does; the in-process bus
  calls it for the topic's messages (`simatch.bus.inproc`): it finds the topic's channel once, not per
  message.
* ``log.forget()``: a new memo period; ``log.now``: the log time [ns]; ``log.size``: bytes held since the
  last take.
"""

from __future__ import annotations

import struct
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from .. import msgs
from ..msgs import cdr
from ..msgs._cdr_accel import Log
from ..msgs._cdr_accel import fill_poses as _fill_poses

#: a Message record up to its data: opcode, record length, channel id, sequence, log time, publish time
MESSAGE_HEADER = struct.Struct("<BQHIQQ")
MESSAGE_FIXED = 22  # bytes of a Message record's content before its data
OPCODE_MESSAGE = 0x05

Fallback = Callable[[str, Any], None]
CLOCK_STEP = 1  # the message's step sets the log time
CLOCK_TICK = 2  # ... and opens a new memo period


#: a slot of a pose template: (byte offset of a geometry_msgs/Pose in the template, row of the model in the
#: poses, height drawn or NaN for the row's own, whether the row's turn about z is drawn)
PoseSlot = tuple[int, int, float, bool]


def fill_poses(template: bytes, slots: Sequence[PoseSlot], pose, grid: float, turn_grid: float) -> bytes:
    """``template`` with a Pose written at each slot from ``pose`` (rows of x y z qw qx qy qz): the position
    snapped to multiples of 1/``grid``, the height the slot's (or the row's, snapped, if NaN), the
    orientation the row's turn about z snapped to 1/``turn_grid`` (or none); what the log's pose template
    writes, by the same C function."""
    return _fill_poses(template, list(slots), np.ascontiguousarray(pose, dtype=np.float64), grid, turn_grid)


def new_log(fallback: Fallback):
    """A message log (see the module's docstring) whose messages not taken go to ``fallback(topic, msg)``."""
    return Log(cdr.Codec(msgs.typestore, memo=True).program, fallback)
