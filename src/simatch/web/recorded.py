"""`RecordingView`: the web UI for a recording (``simatch replay FILE.mcap --view``, ``simatch serve
FILE.mcap``).

A `simatch.record.player.Player` publishes the recorded topics on its bus with their recorded timing; the
live pages — each team's coach page and the referee console — watch that bus exactly as they watch a
running match (perception, intentions, the referee's game state and event log), and the replay page goes
through the whole recording, loaded from the file (`RecordingArchive`), with its own timeline: play,
pause, speed, seek, and "Latest" to join the moment the live pages show. Nothing can be commanded: a
recording is shown as it was.
"""

from __future__ import annotations

from .access import Access
from .archive import RecordingArchive
from .hosting import Hosted, hello_of
from .observer import RunObserver
from .picture import Picture
from .server import Archive, ViewServer


class RecordingError(ValueError):
    """A recording the pages cannot show (e.g. an MCAP file that simatch did not write)."""


class RecordingView(Hosted):
    def __init__(
        self, player, host: str = "127.0.0.1", port: int = 8765, fps: float = 40.0, access: Access | None = None
    ):
        scene = player.scene
        if scene is None:
            raise RecordingError(
                f"{player.recording.path} holds no simatch scene (no simatch metadata): the pages cannot draw it"
            )
        spec = scene.spec
        self.player = player
        robots = {team: spec.teams[team].robot_ids() for team in spec.teams}
        self.observer = RunObserver(player.bus, robots, spec.control.period)
        self.picture = Picture(self.observer, spec)
        rec = player.recording
        self.archive = RecordingArchive(lambda: type(rec)(rec.path), robots, spec.control.period, name=str(rec.path))
        archive = Archive(self.archive.observer, Picture(self.archive.observer, spec), lambda: self.archive.complete)
        self.access = access or Access(list(spec.teams))
        name = player.recording.path.name
        hello = hello_of(
            spec, self.picture, fps, source="recording", recording=name, duration=round(player.duration, 3)
        )
        self.server = ViewServer(
            self.observer,
            self.picture,
            self.access,
            hello,
            host=host,
            port=port,
            fps=fps,
            archive=archive,
            read_only=f"this is a recording ({name}): it is shown as it was, nothing can be commanded",
        )

    def start(self) -> RecordingView:
        self.archive.start()
        return super().start()

    def _ended(self) -> None:
        if not self.player.done:
            self.player.stop()

    def _closing(self) -> None:
        self.observer.close()
        self.archive.close()
