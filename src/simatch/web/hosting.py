"""What every way of showing a run in the pages shares: the first message a page gets (`hello_of`) and the
life of the server around the run (`Hosted`: start, the addresses, waiting for a first page, keeping the
pages up after the end, closing).

`LiveView` (a `Simulation` in this process) and `RecordingView` (a recording played back on a bus) are the
two kinds; each builds its observer, pictures and server, then relies on this.
"""

from __future__ import annotations

import time

from ..config.loader import SceneError
from ..msgs.game_commands import MatchMode
from ..scene.judges import judge_class
from .picture import Picture


def hello_of(spec, picture: Picture, fps: float, **extra) -> dict:
    """What every page gets first: the scene, the field to scale, the teams and robots, the commands."""
    return {
        "scene": spec.name,
        "description": spec.description,
        "fps": fps,
        "field": spec.world.geometry().describe(),
        "ball_radius": spec.ball.radius,
        "teams": [
            {
                "name": team,
                "color": spec.team_color(team),
                "sign": spec.team_sign(team),
                "ids": spec.teams[team].robot_ids(),
                "goalkeeper": spec.teams[team].goalkeeper,
            }
            for team in spec.teams
        ],
        "robots": picture.robots_meta(),
        "commands": [m.name for m in MatchMode],
        "set_pieces": _has_set_pieces(spec),
        "source": "run",
        **extra,
    }


def _has_set_pieces(spec) -> bool:
    """The scene's game has soccer's set pieces (its judge says so): the pages offer their commands only then;
    a judge that cannot be loaded here (a recording of somebody's plug-in) leaves them offered."""
    try:
        return judge_class(spec.judge.kind).set_pieces
    except SceneError:
        return True


class Hosted:
    """The server's life around a run; subclasses set ``self.server`` and may override `_closing`."""

    server = None
    _closed = False

    def start(self):
        self.server.start()
        return self

    @property
    def urls(self) -> dict[str, str]:
        return self.server.urls()

    def wait_for_viewer(self, timeout: float | None = None, any_page: bool = False) -> bool:
        """Block until a live page is open (``any_page``: any page, the replay page too) — at most ``timeout``
        seconds (None: as long as it takes)."""
        self.server.status = "waiting"
        deadline = None if timeout is None else time.monotonic() + timeout
        count = (lambda: len(self.server.clients)) if any_page else (lambda: self.server.live_viewers)
        try:
            while count() == 0:
                if deadline is not None and time.monotonic() >= deadline:
                    return False
                time.sleep(0.05)  # short sleeps: Ctrl-C works
            return True
        finally:
            self.server.status = "running"

    def finish(self, linger: float | None = None, grace: float = 3.0) -> None:
        """The run is over: the pages say so and can still replay it. Keep serving while a page (of any kind)
        is open (for at most ``linger`` seconds; None: until they are all closed for ``grace`` seconds)."""
        self.server.status = "ended"
        self._ended()
        deadline = None if linger is None else time.monotonic() + linger
        quiet_since = None
        while deadline is None or time.monotonic() < deadline:
            if not self.server.clients:
                quiet_since = quiet_since or time.monotonic()
                if time.monotonic() - quiet_since >= grace:
                    return
            else:
                quiet_since = None
            time.sleep(0.1)

    def _ended(self) -> None:
        """What the run's end changes besides the pages' status (e.g. no more commands)."""

    def _closing(self) -> None:
        """Release what the subclass holds (after the server stopped)."""

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._ended()
        self.server.stop()
        self._closing()

    def __enter__(self):
        return self if self.server._thread is not None else self.start()

    def __exit__(self, *exc) -> None:
        self.close()
