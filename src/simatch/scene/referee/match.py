"""What the rules read: the observation, the game state, the ball's touches, the robots' contacts, the
restart spots and the referee's settings, made once per match and shared by the referee and every rule."""

from __future__ import annotations

from .contacts import RobotContacts
from .observation import Observation
from .params import RefereeParams
from .restarts import NAMES, Spots
from .state import Game, schedule
from .touches import Touches


class Match:
    def __init__(self, scene, params: RefereeParams):
        spec = scene.spec
        self.params = params
        self.dt = spec.physics.timestep
        self.control_steps = max(1, round(spec.control.period / self.dt))
        self.control_dt = self.control_steps * self.dt
        self.obs = Observation(scene, params.robot_radius)
        self.game = Game(teams=list(spec.teams), stages=schedule(spec.match), dt=self.dt)
        self.touches = Touches(
            self.obs, params.dribble_release_distance, round(params.double_touch_gap / self.dt), params.regain_pass_roll
        )
        self.contacts = RobotContacts(self.obs, params.contact_margin)
        self.gravity = spec.physics.gravity
        self.spots = Spots(self.obs.field, params, spec.ball.radius)

    def restart_name(self) -> str:
        r = self.game.restart
        return NAMES[r.kind] if r is not None else "restart"
