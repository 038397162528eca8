"""Playback (``simatch replay FILE``): the recorded topics published on a bus again, with their timing.

A `Player` reads a recording and publishes every recorded message on its bus, under its bus topic and
type, at the recorded simulated time scaled by ``pace`` (simulated seconds per wall second; None: as fast
as possible). Anything that can subscribe to a bus sees the game again: a viewer, a strategy under test, a
second recorder. The 3D-scene channels are not bus topics and are not published.

``start`` skips to a simulated time: before playing from there, the player publishes the latest message
of every topic recorded before it (the current game command, game state, positions...), so that a viewer
joining at ``start`` has the full picture.

Hook for viewers: a `Player` offers ``bus``, ``scene`` (the recorded `LoadedScene`), ``time``, ``duration``,
``pace`` (may change while playing), ``done`` and ``stop()``; see `simatch.cli.replay.EXTENSIONS`.
"""

from __future__ import annotations

import time as _time
from collections.abc import Callable
from pathlib import Path

from .. import msgs
from ..bus import InProcessBus
from ..config.loader import LoadedScene
from . import layout
from .reader import Recording


class Player:
    def __init__(self, path: str | Path | Recording, bus=None, pace: float | None = 1.0, start: float = 0.0):
        self.recording = path if isinstance(path, Recording) else Recording(path)
        rec = self.recording
        self.bus = bus or InProcessBus(rec.metadata.get("run") or "replay")
        self.pace = pace
        self.start = max(0.0, float(start))
        self.time = self.start
        self.done = False
        self.published = 0
        self._stop = False
        self._pubs: dict[str, object] = {}
        self._scene: LoadedScene | None = None
        self.topics = {
            t: ty
            for t, ty in rec.topics().items()
            if ty in msgs.typestore.fielddefs and not t.startswith(layout.ROS_ONLY)  # /clock: for ROS 2 tools
        }

    @property
    def duration(self) -> float:
        """Simulated time of the last recorded message [s]."""
        return self.recording.end_ns / layout.NS

    @property
    def scene(self) -> LoadedScene | None:
        """The recorded scene (None for a recording without simatch metadata)."""
        if self._scene is None and self.recording.is_simatch:
            self._scene = self.recording.scene()
        return self._scene

    def stop(self) -> None:
        """Ask a running `play` to return (e.g. from a viewer's thread)."""
        self._stop = True

    def _publish(self, topic: str, msg) -> None:
        pub = self._pubs.get(topic)
        if pub is None:
            pub = self._pubs[topic] = self.bus.publisher(topic, self.topics[topic])
        pub.put(msg)
        self.published += 1

    def play(self, progress: Callable[[float], None] | None = None) -> int:
        """Publish everything from ``start`` to the end; returns the number of messages published."""
        rec = self.recording
        start_ns = layout.ns(self.start)
        if start_ns > 0:
            self._catch_up(start_ns)
        anchor: tuple[float, float, float | None] | None = None  # (wall, sim, pace) when pacing began
        last_progress = -1.0
        for topic, t_ns, data in rec.raw(topics=self.topics, start_ns=start_ns):
            if self._stop:
                break
            t = t_ns / layout.NS
            if t > self.time:
                self.time = t
                pace = self.pace
                if pace:
                    now = _time.perf_counter()
                    if anchor is None or anchor[2] != pace:
                        anchor = (now, t, pace)
                    ahead = (t - anchor[1]) / pace - (now - anchor[0])
                    if ahead > 0:
                        _time.sleep(ahead)
                else:
                    anchor = None
                if progress is not None and t - last_progress >= 0.1:
                    last_progress = t
                    progress(t)
            msg = rec.decode(self.topics[topic], data, topic)
            if msg is not None:
                self._publish(topic, msg)
        self.done = True
        return self.published

    def _catch_up(self, start_ns: int) -> None:
        """Publish the last message of every topic recorded before ``start_ns``."""
        rec = self.recording
        last: dict[str, tuple[int, bytes]] = {}
        for topic, t_ns, data in rec.raw(topics=self.topics):
            if t_ns >= start_ns:
                break
            last[topic] = (t_ns, data)
        for topic, (_t_ns, data) in sorted(last.items(), key=lambda item: item[1][0]):
            msg = rec.decode(self.topics[topic], data, topic)
            if msg is not None:
                self._publish(topic, msg)
