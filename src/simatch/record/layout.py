"""How a simatch recording is laid out in its MCAP file (read by the writer, the reader and the docs).

* MCAP profile ``ros2``: every channel has a ``ros2msg`` schema (the ``.msg`` text with its dependencies,
  as rosbag2 writes it) and CDR messages, so ``rosbags``, the ``mcap`` readers, ROS 2 tools and Foxglove
  read it without simatch.
* One channel per bus topic, named ``/`` + the topic (``cyan/2/VelCmd`` -> ``/cyan/2/VelCmd``); the 3D
  scene channels ``/scene/field`` and ``/scene/game`` are not bus topics.
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
FORMAT_VERSION = "1"
PROFILE = "ros2"
SCHEMA_ENCODING = "ros2msg"
MESSAGE_ENCODING = "cdr"
META_START = "simatch"
META_END = "simatch_end"
NS = 1_000_000_000
CHUNK_NS = NS // 2  # simulated time per chunk


def channel_topic(bus_topic: str) -> str:
    """The MCAP channel (ROS-style, absolute) of a bus topic."""
    return "/" + bus_topic.lstrip("/")


def bus_topic(channel: str) -> str:
    return channel.lstrip("/")


def ns(seconds: float) -> int:
    """Simulated seconds as integer nanoseconds (exact for every physics step of a run)."""
    return int(round(seconds * NS))


def schema_text(typestore, typename: str) -> str:
    """The ``ros2msg`` schema of a type: its definition followed by those of the types it uses."""
    text, _ = typestore.generate_msgdef(typename, ros_version=2)
    return text
