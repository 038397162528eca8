"""`LiveView`: the web UI attached to an embedded run (``simatch run SCENE --view``, ``simatch serve``).

It puts together the parts of the web subsystem around one `Simulation`: the observer on the run's bus,
the control node in its lockstep, the tokens and the server. While at least one live page (a coach page
or the referee console) is open, the run is paced at real time (``sim.pace = 1.0``); when the last one
closes, the run goes back to its own pace.
"""

from __future__ import annotations

from .access import Access
from .control import RunControl
from .hosting import Hosted, hello_of
from .observer import RunObserver
from .picture import Picture
from .server import ViewServer


class LiveView(Hosted):
    def __init__(self, sim, host: str = "127.0.0.1", port: int = 8765, fps: float = 40.0, access: Access | None = None):
        spec = sim.scene.spec
        self.sim = sim
        self._own_pace = sim.pace
        self.observer = RunObserver(
            sim.bus, {team: spec.teams[team].robot_ids() for team in spec.teams}, spec.control.period
        )
        self.control = RunControl(sim)
        self.access = access or Access(list(spec.teams))
        self.picture = Picture(self.observer, spec, sent_off=lambda: tuple(self.control.sent_off))
        self.server = ViewServer(
            self.observer,
            self.picture,
            self.access,
            hello_of(spec, self.picture, fps),
            control=self.control,
            host=host,
            port=port,
            fps=fps,
            on_viewers=self._on_viewers,
        )

    def _on_viewers(self, n: int) -> None:
        """Called in the server's thread; ``Simulation.run`` reads ``pace`` between its chunks."""
        self.sim.pace = 1.0 if n > 0 else self._own_pace

    def _ended(self) -> None:
        if not self.control.ended:
            self.control.close()

    def _closing(self) -> None:
        self.observer.close()
        self.sim.pace = self._own_pace
