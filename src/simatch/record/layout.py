"""How a simatch recording is laid out in its MCAP file (read by the writer, the reader and the docs).

* MCAP profile ``ros2``: every channel has a ``ros2msg`` schema (the ``.msg`` text with its dependencies,
  as rosbag2 writes it) and CDR messages, so ``rosbags``, the ``mcap`` readers, ROS 2 tools and Foxglove
  read it without simatch.
* One channel per bus topic, named ``/`` + the topic (``cyan/2/VelCmd`` -> ``/cyan/2/VelCmd``), except the
  run's clock (``simatch_msgs/msg/Clock``: time, step, tick), on ``/simatch/clock``: ``/clock`` is the
  simulated time as ROS 2's standard ``rosgraph_msgs/msg/Clock``, which ROS 2 tools play back for nodes on
  ``use_sim_time`` (recordings made before had the simatch clock on ``/clock``; a reader tells them apart by
  the type). The 3D scene channels ``/scene/field`` and ``/scene/game`` and ``/clock`` are not bus topics.
* Message log time = simulated time of the physics step during which the message was published, in
  nanoseconds (a recording starts at 0, not at the Unix epoch).
* Metadata records: ``simatch`` (written first: format, version, scene text, overrides, seed, command
  line, run name, timestep) and ``simatch_end`` (written when the file is finalised: how the run ended,
  simulated seconds, state digest, message counts, topics that could not be recorded).
* Chunks hold half a simulated second each (zstd, level 3; no message or chunk indexes, which would add
  16 bytes per message outside the compression: readers read the file from start to end). A chunk is
  handed to the writer process as soon as its half second ends, and the writer process writes whatever it
  was handed even when the run's process is killed, so a kill loses at most the half second being filled
  (`simatch.record.writer`).
"""

from __future__ import annotations

FORMAT = "simatch-recording"
#: 3: with the per-component fingerprints of every physics step (``/component_fingerprints``,
#: `simatch.sim.components`); 2: the exact states' fingerprints by `simatch.sim.kernels.mix64` (metadata
#: ``fingerprint``); 1: by SHA-256
FORMAT_VERSION = "3"
#: the first format version whose recordings hold the component fingerprints
COMPONENTS_SINCE = 3
PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
META_START = "simatch"
META_END = "simatch_end"
NS = 1_000_000_000
CHUNK_NS = NS // 2  # simulated time per chunk


#: the channel of the bus's clock, and ROS 2's standard clock channel and type
SIMATCH_CLOCK = "/simatch/clock"
ROS_CLOCK = "/clock"
ROS_CLOCK_TYPE = "rosgraph_msgs/msg/Clock"
#: what a channel that is for ROS 2 tools only is called among the bus topics (no node publishes there)
ROS_ONLY = "ros/"


def channel_topic(bus_topic: str) -> str:
    """The MCAP channel (ROS-style, absolute) of a bus topic."""
    topic = bus_topic.lstrip("/")
    return SIMATCH_CLOCK if topic == "clock" else "/" + topic


def bus_topic(channel: str, schema: str = "") -> str:
    """The bus topic of a channel (its type tells ROS 2's ``/clock`` from the simatch clock of older files)."""
    if channel == SIMATCH_CLOCK:
        return "clock"
    if channel == ROS_CLOCK and schema == ROS_CLOCK_TYPE:
        return ROS_ONLY + "clock"
    return channel.lstrip("/")


def ros_clock(seconds_ns: int) -> bytes:
    """A rosgraph_msgs/msg/Clock in CDR (little-endian encapsulation, then builtin_interfaces/Time)."""
    sec, nsec = divmod(int(seconds_ns), NS)
    return b"\x00\x01\x00\x00" + sec.to_bytes(4, "little", signed=True) + nsec.to_bytes(4, "little")


def ns(seconds: float) -> int:
    """Simulated seconds as integer nanoseconds (exact for every physics step of a run)."""
    return int(round(seconds * NS))


def schema_text(typestore, typename: str) -> str:
    """The ``ros2msg`` schema of a type: its definition followed by those of the types it uses."""
    text, _ = typestore.generate_msgdef(typename, ros_version=2)
    return text
