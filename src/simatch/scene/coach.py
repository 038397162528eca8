"""The per-team coach: sends game commands to its own team only (paper section V-A).

It is what runs a match without a referee (the paper's first test: one team, one coach machine). A
`Coach` node publishes its team's CoachInfo on ``<team>/receive_from_coach`` every period (the original
coach re-published every 30 ms), so robots that join late or lose a message still hear the command.
Following the original coach: a set piece sets both MatchMode and MatchType; START sets only MatchMode
(MatchType keeps the set piece being taken); STOP and PARK set only MatchMode.
"""

from __future__ import annotations

from .. import msgs
from ..bus import Node, NodeContext, Phase, topics
from ..msgs.game_commands import SET_PIECES, MatchMode, parse


class Coach(Node):
    phase = Phase.JUDGE

    def __init__(
        self,
        team: str,
        period: float,
        max_vel: float = 4.5,
        max_w: float = 10.0,
        initial: MatchMode = MatchMode.STOPROBOT,
    ):
        self.team = team
        self.name = f"{team}/coach"
        self.period = period
        self.match_mode = MatchMode(initial)
        self.match_type = MatchMode(initial)
        self.max_vel = max_vel  # the original coach's default: 450 cm/s
        self.max_w = max_w  # and 10 rad/s
        self.extra: dict = {}
        self._dirty = True

    def start(self, ctx: NodeContext) -> None:
        super().start(ctx)
        self.pub = ctx.bus.publisher(topics.team_topic(self.team, topics.RECEIVE_FROM_COACH), msgs.CoachInfo)
        self.pub_events = ctx.bus.publisher(topics.EVENTS, msgs.GameEvent)

    # --- commands ---------------------------------------------------------------------------------------
    def send(self, cmd: int | str, **fields) -> None:
        """Give a command (from this team's point of view): a MatchMode, its number, or words such as
        ``"freekick"``, ``"opp corner"`` (see `commands.parse`); extra CoachInfo fields (points, ids, test
        mode, max_vel, max_w) may be given too. Takes effect at the coach's next tick."""
        cmd = parse(cmd) if isinstance(cmd, str) else MatchMode(cmd)
        if cmd in SET_PIECES:
            self.match_type = cmd
        elif cmd == MatchMode.TEST:
            self.match_type = cmd
        self.match_mode = cmd
        if "max_vel" in fields:
            self.max_vel = float(fields.pop("max_vel"))
        if "max_w" in fields:
            self.max_w = float(fields.pop("max_w"))
        unknown = set(fields) - set(msgs.new(msgs.CoachInfo).__dataclass_fields__)
        if unknown:
            raise ValueError(f"CoachInfo has no field(s) {', '.join(sorted(unknown))}")
        self.extra = fields
        self._dirty = True
        if hasattr(self, "pub_events"):
            self.pub_events.put(
                msgs.GameEvent(
                    stamp=self.ctx.now(),
                    type="coach_command",
                    team=self.team,
                    robot=0,
                    x=0.0,
                    y=0.0,
                    value=float(cmd),
                    limit=0.0,
                    detail=cmd.name,
                )
            )

    def start_play(self) -> None:
        self.send(MatchMode.STARTROBOT)

    def stop_play(self) -> None:
        self.send(MatchMode.STOPROBOT)

    def park(self) -> None:
        self.send(MatchMode.PARKINGROBOT)

    def info(self, now: float):
        if self.extra:
            return msgs.new(
                msgs.CoachInfo,
                stamp=now,
                match_mode=int(self.match_mode),
                match_type=int(self.match_type),
                max_vel=self.max_vel,
                max_w=self.max_w,
                **self.extra,
            )
        return msgs.CoachInfo(
            stamp=now,
            match_mode=int(self.match_mode),
            match_type=int(self.match_type),
            test_mode=0,
            point_a_x=0.0,
            point_a_y=0.0,
            point_b_x=0.0,
            point_b_y=0.0,
            angle_a=0.0,
            angle_b=0.0,
            id_a=0,
            id_b=0,
            kick_force=0.0,
            max_vel=self.max_vel,
            max_w=self.max_w,
            ball_x=0.0,
            ball_y=0.0,
        )

    def tick(self, now: float) -> None:
        self.pub.put(self.info(now))
        self._dirty = False
