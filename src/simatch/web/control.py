"""Carrying out what the pages ask, inside the run's own thread and lockstep.

The pages' messages arrive in the server's thread; the simulation runs in the main thread. Nothing may
touch the run from the side: `RunControl` queues each validated request and a node of the run
(`ControlNode`, JUDGE phase, every physics step) carries it out between two steps, through the run's
public interfaces only — a team's `Coach` for game commands (as the coach machine of the paper does),
the Gazebo-like calls (`set_model_state`, and `set_enabled` of the judge's world interface) for the
referee's manual mode. The answer (done, or why not) goes back to the page that asked.

Without a referee, the referee console gives its commands to both teams' coaches, each mirrored to the
team's point of view, exactly as the original automatic referee did.
"""

from __future__ import annotations

import logging
import math
import queue
from typing import Any, Callable

from .. import frames, msgs
from ..bus import Node, Phase, topics
from ..scene.commands import MatchMode, TestMode, for_team
from . import protocol as P

log = logging.getLogger(__name__)

Reply = Callable[[str | None], None]


class ControlError(ValueError):
    """A request that is valid but cannot be carried out in this run (its text goes back to the page)."""


class ControlNode(Node):
    phase = Phase.JUDGE
    name = "web/control"

    def __init__(self, control: "RunControl", period: float):
        self.control = control
        self.period = period

    def tick(self, now: float) -> None:
        self.control.apply_pending()


class RunControl:
    """Requests from the pages to one embedded `Simulation` (coach commands, limits, tests, the referee's
    manual mode). ``submit`` may be called from any thread; ``apply_pending`` runs in the run's thread."""

    def __init__(self, sim):
        self.sim = sim
        spec = sim.scene.spec
        self.spec = spec
        self.teams = list(spec.teams)
        self.ids = {team: spec.teams[team].robot_ids() for team in self.teams}
        self.field = spec.world.geometry()
        self.sent_off: set[str] = set()
        self._queue: queue.SimpleQueue = queue.SimpleQueue()
        self.ended = False
        self.node = sim.clock.add(ControlNode(self, sim.dt))

    # --- any thread ----------------------------------------------------------------------------------------
    def submit(self, grant, message, reply: Reply) -> None:
        """Queue ``message`` (validated, from a page holding ``grant``); ``reply(error or None)`` follows."""
        if self.ended:
            reply("the run has ended: nothing can be commanded any more")
            return
        self._queue.put((grant, message, reply))

    @property
    def has_referee(self) -> bool:
        return bool(getattr(self.sim.judge, "gives_commands", False))

    def capabilities(self) -> dict:
        """What the referee console can do in this run (the page greys out the rest)."""
        return {"coaches": sorted(self.sim.coaches), "referee": self.has_referee, "auto_referee": False,
                "place_ball": True, "send_off": True}

    # --- the run's thread ------------------------------------------------------------------------------------
    def apply_pending(self) -> None:
        q = self._queue
        while not q.empty():
            grant, message, reply = q.get_nowait()
            try:
                self.apply(grant, message)
            except (ControlError, ValueError) as exc:
                reply(str(exc))
            except Exception as exc:        # a page must never bring the run down
                log.exception("web request %r failed", message)
                reply(f"internal error: {type(exc).__name__}: {exc}")
            else:
                reply(None)

    def close(self) -> None:
        """The run is over: refuse what comes, answer what waits."""
        self.ended = True
        while not self._queue.empty():
            _, _, reply = self._queue.get_nowait()
            reply("the run has ended")
        self.sim.clock.remove(self.node)

    def apply(self, grant, m) -> None:
        if isinstance(m, P.Command):
            if grant.role == "coach":
                if m.team is not None and m.team != grant.team:
                    raise ControlError(f"this page commands {grant.team} only, not {m.team}")
                self._coach(grant.team).send(m.cmd)
            else:
                self.referee_command(m.cmd, m.team or self.teams[0])
        elif isinstance(m, P.Limits):
            for team in ([grant.team] if grant.role == "coach" else self.teams):
                coach = self._coach(team)
                coach.max_vel, coach.max_w = m.max_vel, m.max_w
        elif isinstance(m, P.Test):
            self.test(grant.team, m)
        elif isinstance(m, P.Pause):
            self.referee_command(MatchMode.STOPROBOT, self.teams[0])
        elif isinstance(m, P.PlaceBall):
            self.place_ball(m.x, m.y)
        elif isinstance(m, P.SendOff):
            self.send_off(m.robot, m.off)
        elif isinstance(m, P.AutoReferee):
            raise ControlError("this run has no automatic referee to switch on or off")
        else:
            raise ControlError(f"'{m.type}' cannot be carried out on a live run")

    def _coach(self, team: str):
        coach = self.sim.coaches.get(team)
        if coach is None:
            raise ControlError(f"team {team} has no coach in this run (a referee gives the commands)"
                               if self.has_referee else f"team {team} has no coach in this run")
        return coach

    # --- what each request does ----------------------------------------------------------------------------------
    def referee_command(self, cmd: MatchMode, given_to: str) -> None:
        """``cmd`` from ``given_to``'s point of view, to every team (mirrored), through their coaches."""
        if given_to not in self.teams:
            raise ControlError(f"unknown team {given_to!r} (this run has {', '.join(self.teams)})")
        coaches = [self._coach(team) for team in self.teams]
        for team, coach in zip(self.teams, coaches):
            coach.send(for_team(cmd, given_to, team))

    def test(self, team: str, m: P.Test) -> None:
        ids = self.ids[team]
        if m.mode != "stop" and m.robot not in ids:
            raise ControlError(f"{team} has no robot {m.robot} (ids: {', '.join(map(str, ids))})")
        if m.mode == "pass" and m.receiver not in ids:
            raise ControlError(f"{team} has no robot {m.receiver} to pass to")
        sign = self.spec.team_sign(team)
        x, y = frames.point(sign, m.x, m.y)
        fields: dict[str, Any] = {"id_a": m.robot}
        if m.mode == "move":
            mode = {(False, False): TestMode.MOVE_NOBALL_NOAVOID, (False, True): TestMode.MOVE_NOBALL_AVOID,
                    (True, False): TestMode.MOVE_BALL_NOAVOID, (True, True): TestMode.MOVE_BALL_AVOID}[
                (m.dribble, m.avoid)]
            fields.update(point_a_x=x, point_a_y=y, angle_a=frames.yaw(sign, m.heading))
        elif m.mode == "pass":
            mode = TestMode.PASS_BALL
            fields.update(id_b=m.receiver, point_b_x=x, point_b_y=y, kick_force=m.kick)
        elif m.mode == "shoot":
            mode = TestMode.SHOOT_BALL
            fields.update(point_a_x=x, point_a_y=y, kick_force=m.kick)
        elif m.mode == "catch":
            mode = TestMode.CATCH_BALL
        else:
            mode, fields = TestMode.TEST_STOP, {}
        self._coach(team).send(MatchMode.TEST, test_mode=int(mode), **fields)

    def place_ball(self, x: float, y: float) -> None:
        f = self.field
        if not f.in_field(x, y, margin=f.margin - 0.2):
            raise ControlError(f"({x:.2f}, {y:.2f}) is off the floor: the ball stays where it is")
        self.sim.set_model_state("ball", x=x, y=y, z=self.spec.ball.radius, vx=0.0, vy=0.0, vz=0.0,
                                 wx=0.0, wy=0.0, wz=0.0)

    def send_off(self, name: str, off: bool) -> None:
        """Send a robot off (to the margin beside the side line, where it stands still) or return it (to
        the side line, where it plays again), as the original referee's keys did."""
        team, _, rid = name.partition("/")
        if team not in self.ids or not rid.isdigit() or int(rid) not in self.ids[team]:
            raise ControlError(f"no robot named {name!r}")
        if off == (name in self.sent_off):
            raise ControlError(f"{name} is already {'off' if off else 'on'} the field")
        f = self.field
        slot = self.ids[team].index(int(rid)) + 1
        x = -self.spec.team_sign(team) * (0.5 + 0.8 * slot)
        world = self.sim.simulator          # the judge's world interface (WorldControl)
        if off:
            world.set_enabled(name, False)
            self.sim.set_model_state(name, x=x, y=-(f.half_width + 0.5 * f.margin), yaw=math.pi / 2,
                                     vx=0.0, vy=0.0, wz=0.0)
            self.sent_off.add(name)
        else:
            self.sim.set_model_state(name, x=x, y=-(f.half_width - 0.4), vx=0.0, vy=0.0, wz=0.0)
            world.set_enabled(name, True)
            self.sent_off.discard(name)
        self.sim.bus.publisher(topics.EVENTS, msgs.GameEvent).put(msgs.GameEvent(
            stamp=self.sim.time, type="sent_off" if off else "returned", team=team, robot=int(rid), x=0.0, y=0.0,
            value=0.0, limit=0.0, detail="by the operator (referee console)"))
