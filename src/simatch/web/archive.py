"""A recording as the replay pages go through it: its whole timeline, loaded from the file in the
background so that a page can seek anywhere in the match — not only up to where playback on the bus has
come.

The file is read by a `RunObserver` of its own, on a private in-process bus onto which the loader
publishes what the replay page draws: model states (only those the observer samples, about 66 a simulated
second, so that a long match loads in seconds), the event log and the game states. The observer's
timeline grows while the file loads; `complete` says when it is all there.
"""

from __future__ import annotations

import logging
import math
import threading
from collections.abc import Callable

from ..bus import InProcessBus, topics
from .observer import RunObserver

log = logging.getLogger(__name__)

NS = 1_000_000_000
#: what the replay page shows of a recording (each robot's perception and intentions are live-only)
TOPICS = (topics.MODEL_STATES, topics.EVENTS, topics.GAME_STATE)


class RecordingArchive:
    """``open_recording()`` gives a reader of the file of its own (`simatch.record.Recording`'s interface:
    ``topics()``, ``raw(topics)``, ``decode(type, data, topic)``), which the loader uses in its thread while the
    player reads the same file in another."""

    def __init__(
        self,
        open_recording: Callable[[], object],
        robots: dict[str, list[int]],
        control_period: float,
        name: str = "the recording",
    ):
        self.open_recording = open_recording
        self.name = name
        self.bus = InProcessBus("archive")
        self.observer = RunObserver(self.bus, robots, control_period, keep=math.inf)  # the file bounds it
        self.error: str | None = None
        self._done = threading.Event()
        self._stop = False
        self._thread = threading.Thread(target=self._load, name="simatch-web-archive", daemon=True)

    def start(self) -> RecordingArchive:
        self._thread.start()
        return self

    @property
    def complete(self) -> bool:
        return self._done.is_set()

    def wait(self, timeout: float | None = None) -> bool:
        return self._done.wait(timeout)

    def _load(self) -> None:
        try:
            rec = self.open_recording()
            types = rec.topics()
            wanted = [t for t in TOPICS if t in types]
            pubs = {t: self.bus.publisher(t, types[t]) for t in wanted}
            every = int(self.observer.SAMPLE_PERIOD * NS)
            due = -1
            skipped = None  # the last model states not sampled: the recording's end
            for topic, t_ns, data in rec.raw(topics=wanted):
                if self._stop:
                    return
                if topic == topics.MODEL_STATES:
                    if t_ns < due:
                        skipped = data  # the observer would skip it: do not even decode it
                        continue
                    due, skipped = t_ns + every - 1, None
                msg = rec.decode(types[topic], data, topic)
                if msg is not None:
                    pubs[topic].put(msg)
            last = rec.decode(types[topics.MODEL_STATES], skipped, topics.MODEL_STATES) if skipped else None
            if last is not None:
                self.observer.add_states(last)
        except Exception as exc:  # a damaged file must not bring the server down: the page shows less
            self.error = str(exc)
            log.warning("the replay page cannot load %s: %s", self.name, exc)
        finally:
            self._done.set()

    def close(self) -> None:
        self._stop = True
        self._thread.join(5.0)
        self.observer.close()
        self.bus.close()
