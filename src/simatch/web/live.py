"""`LiveView`: the web UI attached to an embedded run (``simatch run SCENE --view``, ``simatch serve``).

It puts together the parts of the web subsystem around one `Simulation`: the observer on the run's bus,
the control node in its lockstep, the tokens and the server. While at least one live page (a coach page
or the referee console) is open, the run is paced at real time (``sim.pace = 1.0``); when the last one
closes, the run goes back to its own pace.
"""

from __future__ import annotations

import time

from .access import Access
from .control import RunControl
from .observer import RunObserver
from .picture import Picture
from .server import ViewServer


def hello_of(spec, picture: Picture, fps: float) -> dict:
    """What every page gets first: the scene, the field to scale, the teams and robots, the commands."""
    from ..scene.commands import MatchMode

    return {
        "scene": spec.name, "description": spec.description, "fps": fps,
        "field": spec.world.geometry().describe(), "ball_radius": spec.ball.radius,
        "teams": [{"name": team, "color": spec.team_color(team), "sign": spec.team_sign(team),
                   "ids": spec.teams[team].robot_ids(), "goalkeeper": spec.teams[team].goalkeeper}
                  for team in spec.teams],
        "robots": picture.robots_meta(),
        "commands": [m.name for m in MatchMode],
    }


class LiveView:
    def __init__(self, sim, host: str = "127.0.0.1", port: int = 8765, fps: float = 40.0,
                 access: Access | None = None):
        spec = sim.scene.spec
        self.sim = sim
        self._own_pace = sim.pace
        self.observer = RunObserver(sim.bus, {team: spec.teams[team].robot_ids() for team in spec.teams},
                                    spec.control.period)
        self.control = RunControl(sim)
        self.access = access or Access(list(spec.teams))
        self.picture = Picture(self.observer, spec, sent_off=lambda: tuple(self.control.sent_off))
        self.server = ViewServer(self.observer, self.picture, self.access, hello_of(spec, self.picture, fps),
                                 control=self.control, host=host, port=port, fps=fps,
                                 on_viewers=self._on_viewers)
        self._closed = False

    def start(self) -> "LiveView":
        self.server.start()
        return self

    @property
    def urls(self) -> dict[str, str]:
        return self.server.urls()

    def _on_viewers(self, n: int) -> None:
        """Called in the server's thread; ``Simulation.run`` reads ``pace`` between its chunks."""
        self.sim.pace = 1.0 if n > 0 else self._own_pace

    def wait_for_viewer(self, timeout: float | None = None) -> bool:
        """Block until a live page is open (at most ``timeout`` seconds; None: as long as it takes)."""
        self.server.status = "waiting"
        deadline = None if timeout is None else time.monotonic() + timeout
        try:
            while self.server.live_viewers == 0:
                if deadline is not None and time.monotonic() >= deadline:
                    return False
                time.sleep(0.05)           # short sleeps: Ctrl-C works
            return True
        finally:
            self.server.status = "running"

    def finish(self, linger: float | None = None, grace: float = 3.0) -> None:
        """The run is over: the pages say so and can still replay it. Keep serving while a live page is
        open (for at most ``linger`` seconds; None: until they are all closed for ``grace`` seconds)."""
        self.server.status = "ended"
        self.control.close()
        deadline = None if linger is None else time.monotonic() + linger
        quiet_since = None
        while deadline is None or time.monotonic() < deadline:
            if self.server.live_viewers == 0:
                quiet_since = quiet_since or time.monotonic()
                if time.monotonic() - quiet_since >= grace:
                    return
            else:
                quiet_since = None
            time.sleep(0.1)

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        if not self.control.ended:
            self.control.close()
        self.server.stop()
        self.observer.close()
        self.sim.pace = self._own_pace

    def __enter__(self) -> "LiveView":
        return self if self.server._thread is not None else self.start()

    def __exit__(self, *exc) -> None:
        self.close()
