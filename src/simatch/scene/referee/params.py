"""The referee's settings: every threshold and time it judges with, under the scene's ``[judge]`` table.

The defaults are the RoboCup MSL values (2016 rulebook, the 2020 Simatch competition rules and the MSL
RefBox configuration, see docs/referee.md); where the rules give no number (charging speed, no progress)
the default follows the SSL game controller or the original Simatch referee, and the documentation says
so. Halves, their length, the half-time break, the first kick-off and the shoot-out are in ``[match]``.
"""

from __future__ import annotations

from typing import Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

#: the rules a scene may switch off with ``judge.disabled_rules`` (names are the rule files and event types)
RULE_NAMES = (
    "goal",
    "ball_out",
    "dribbling",
    "goal_area",
    "penalty_area",
    "set_piece_distance",
    "kickoff_half",
    "dropped_ball_distance",
    "restart_timeout",
    "double_touch",
    "charging",
    "no_progress",
    "own_half_regain",
    "lob",
    "ball_holding",
    "ball_rotation",
    "pushing",
    "goalkeeper_contact",
)

Card = Literal["yellow", "red"] | None


class RefereeParams(BaseModel):
    model_config = ConfigDict(extra="forbid")

    # --- the flow of a stoppage ------------------------------------------------------------------------
    stop_time: float = Field(
        2.0,
        ge=0.0,
        le=60.0,
        description="dead ball: robots hold STOP this long before the ball is placed and "
        "the restart called [s] (original referee: 2 s)",
    )
    prepare_time: float = Field(
        5.0,
        gt=0.0,
        le=120.0,
        description="longest wait for robots to take their set-piece positions before "
        "START [s] (with stop_time: the MSL 7 s to restart)",
    )
    kickoff_prepare_time: float = Field(
        10.0, gt=0.0, le=120.0, description="the same for kick-offs, when every robot must reach its own half [s]"
    )
    prepare_min_time: float = Field(
        1.0,
        ge=0.0,
        le=60.0,
        description="START comes no sooner than this after the set-piece command, "
        "and then as soon as every position is legal [s]",
    )
    restart_timeout: float = Field(
        7.0,
        gt=0.0,
        le=120.0,
        description="the set piece must be kicked within this after START; then the "
        "ball is in play for everybody [s] (MSL: 7 s)",
    )
    caution_distance_at_restarts: bool = Field(
        True,
        description="a robot that breaks the distance at a restart after START, so that the restart is taken "
        "again, is cautioned (yellow card; FIFA Law 12, kept by MSL): a team that encroaches at every "
        "restart loses its robots to send-offs instead of stopping the match",
    )
    max_retakes: int = Field(
        3,
        ge=0,
        le=100,
        description="a restart is taken again at most this many times in a row; at the next infringement "
        "that would retake it, the ball is in play for everybody instead (logged as restart_loop)",
    )
    in_play_distance: float = Field(
        0.5, gt=0.0, le=5.0, description="after a set piece the ball is in play once it moved this far [m] (MSL: 0.5 m)"
    )
    replace_distance: float = Field(
        0.1,
        gt=0.0,
        le=5.0,
        description="while robots prepare, a ball moved off its spot by more than "
        "this is put back [m] (original referee: 10 cm)",
    )

    # --- restart spots ------------------------------------------------------------------------------------
    throw_in_inset: float = Field(0.3, ge=0.0, le=3.0, description="throw-in spot inside the side line [m]")
    corner_inset: float = Field(
        0.3, ge=0.0, le=3.0, description="corner spot inside the goal line and the side line [m]"
    )
    restart_spot: tuple[float, float] = Field(
        (3.6, 3.5),
        description="goal-kick spot, and where a free kick or dropped ball that would be in a penalty "
        "area goes: [distance from the goal line, |y|] [m] (original referee: 3.6, 3.5)",
    )
    restart_border: float = Field(
        0.3,
        ge=0.0,
        le=3.0,
        description="free kicks and dropped balls are placed at least this far inside the lines [m]",
    )

    # --- set-piece positions --------------------------------------------------------------------------------
    opponent_distance: float = Field(
        3.0, ge=0.0, le=20.0, description="opponents keep this far from the ball until it is in play [m]"
    )
    teammate_distance: float = Field(
        2.0, ge=0.0, le=20.0, description="the kicker's team-mates keep this far from the ball [m]"
    )
    dropped_ball_distance: float = Field(
        1.0, ge=0.0, le=20.0, description="everybody keeps this far from a dropped ball [m]"
    )

    # --- ball holding -----------------------------------------------------------------------------------------
    dribble_distance: float = Field(
        3.0,
        gt=0.0,
        le=100.0,
        description="a robot may keep the ball within this radius of where it took it [m] (MSL: 3 m)",
    )
    dribble_backward_distance: float = Field(
        2.0, gt=0.0, le=100.0, description="of which at most this much driving backwards [m] (MSL: 2 m)"
    )
    dribble_release_distance: float = Field(
        0.6,
        gt=0.0,
        le=5.0,
        description="a robot has released the ball once the ball's centre is this far from the robot's centre [m]",
    )
    ball_holding_depth: float = Field(
        1 / 3,
        gt=0.0,
        le=1.0,
        description="the ball may enter a robot's convex hull (its footprint) by at "
        "most this fraction of its diameter (MSL: 1/3)",
    )
    ball_holding_brief_depth: float = Field(
        0.5,
        gt=0.0,
        le=1.0,
        description="... and by at most this fraction for less than "
        "ball_holding_brief_time (MSL: 1/2, when stopping the ball)",
    )
    ball_holding_brief_time: float = Field(
        1.0,
        gt=0.0,
        le=60.0,
        description="longest time the ball may be deeper than ball_holding_depth [s] (MSL: less than 1 s)",
    )

    ball_rotation_ratio: float = Field(
        0.5,
        ge=-5.0,
        le=5.0,
        description="a held ball moving over the floor keeps its natural rotation while it turns at least this "
        "fraction of rolling with its motion (1: rolling, 0: sliding unturned); below it the robot holds "
        "it against its rotation (MSL RC-12.3.1)",
    )
    ball_rotation_time: float = Field(
        1.0, gt=0.0, le=60.0, description="longest time a ball may be held against its rotation [s] (MSL: 1 s)"
    )
    ball_rotation_distance: float = Field(
        0.3, gt=0.0, le=20.0, description="longest way a ball may travel held against its rotation [m] (MSL: 30 cm)"
    )
    ball_rotation_rest: float = Field(
        4.0,
        ge=0.0,
        le=600.0,
        description="holding the ball against its rotation may begin anew only after this long without, or once "
        "the ball was released [s] (MSL: 4 s)",
    )
    ball_rotation_min_speed: float = Field(
        0.2,
        gt=0.0,
        le=20.0,
        description="a held ball's rotation is judged while it moves over the floor at least this fast [m/s]",
    )

    # --- scoring and lobs -----------------------------------------------------------------------------------
    regain_pass_roll: float = Field(
        1.0,
        ge=0.0,
        le=20.0,
        description="a team that won the ball in its own half scores only after a "
        "team-mate received it in the opponent half after it rolled freely "
        "this far [m] (MSL RC-10.1.2: 1 m)",
    )
    lob_height: float = Field(
        0.6,
        ge=0.0,
        le=20.0,
        description="a lob from the own half flying higher than this (the ball's underside at "
        "the apex) needs a team-mate near where it lands [m] (MSL: 60 cm)",
    )
    lob_mate_distance: float = Field(
        3.0, ge=0.0, le=30.0, description="... a team-mate within this of the landing point [m] (MSL: 3 m)"
    )
    lob_min_robots: int = Field(
        3,
        ge=0,
        le=20,
        description="the lob rule applies to a team with at least this many robots on the field (MSL: 3)",
    )

    # --- areas ----------------------------------------------------------------------------------------------
    penalty_area_robots: int = Field(
        1,
        ge=0,
        le=10,
        description="robots of one team allowed in a penalty area at once, besides the defending goalkeeper (MSL: 1)",
    )
    penalty_area_time: float = Field(
        10.0,
        gt=0.0,
        le=600.0,
        description="longest stay of such a robot in a penalty area while the ball is in play [s] (MSL: 10 s)",
    )

    # --- contact --------------------------------------------------------------------------------------------
    robot_radius: float = Field(
        0.25,
        gt=0.05,
        le=2.0,
        description="footprint radius used to see robots touch each other [m] (a team's "
        "model_params.radius overrides it)",
    )
    contact_margin: float = Field(
        0.05, ge=0.0, le=1.0, description="robots closer than their radii plus this are in contact [m]"
    )
    charging_speed: float = Field(
        1.5,
        gt=0.0,
        le=50.0,
        description="a robot that drives into an opponent faster than this (towards it) "
        "charges [m/s] (SSL crash threshold; MSL gives no number)",
    )
    charging_margin: float = Field(
        0.3, ge=0.0, le=50.0, description="... and faster than the opponent drives into it by this much [m/s]"
    )
    charging_card: Card = Field("yellow", description="card for charging (null: none)")
    charging_red_speed: float | None = Field(
        3.0, gt=0.0, le=50.0, description="charging faster than this is ramming: red card [m/s] (null: never)"
    )
    penalty_for_fouls_in_area: bool = Field(
        True, description="a charge or push by a defender in its own penalty area gives a penalty kick"
    )
    pushing_speed: float = Field(
        0.1,
        gt=0.0,
        le=20.0,
        description="a robot in contact with an opponent drives into it while it moves "
        "towards it at least this fast, and the opponent is moved away at least "
        "this fast [m/s]",
    )
    pushing_distance: float = Field(
        1.0,
        gt=0.0,
        le=20.0,
        description="a robot that keeps driving into an opponent and moves it this far "
        "in one contact pushes it [m] (MSL gives no number)",
    )
    pushing_time: float = Field(
        3.0, gt=0.0, le=120.0, description="... or keeps driving into it, moving it, this long [s]"
    )
    pushing_card: Card = Field(
        None, description="card for pushing (null: none, as in MSL; the 2020 Simatch rules gave a yellow card)"
    )

    # --- no progress ------------------------------------------------------------------------------------------
    no_progress_time: float = Field(
        10.0,
        gt=0.0,
        le=600.0,
        description="a ball in play that stays within no_progress_radius this long becomes a dropped ball [s]",
    )
    no_progress_radius: float = Field(0.5, gt=0.0, le=20.0, description="[m]")

    # --- double touch ---------------------------------------------------------------------------------------
    double_touch_gap: float = Field(
        0.1,
        gt=0.0,
        le=5.0,
        description="the kicker has let go of the ball after this long out of "
        "contact; touching it again before another robot did is a foul [s]",
    )

    # --- cards and sending off ---------------------------------------------------------------------------------
    yellow_cards_for_send_off: int = Field(
        2, ge=1, le=100, description="every this many yellow cards send the robot off (MSL: the second yellow)"
    )
    yellow_send_off_time: float = Field(
        90.0,
        gt=0.0,
        le=86400.0,
        description="how long a robot sent off by yellow cards stays off [s] (MSL RefBox: 90 s)",
    )
    red_send_off_time: float | None = Field(
        None,
        gt=0.0,
        le=86400.0,
        description="how long a red card sends a robot off [s] (null: the rest of the match, as in MSL)",
    )

    # --- penalties ----------------------------------------------------------------------------------------------
    penalty_kick_time: float = Field(
        10.0, gt=0.0, le=120.0, description="the penalty taker must kick within this after START [s]"
    )
    shootout_kicks: int = Field(5, ge=1, le=50, description="penalty kicks per team in a shoot-out (MSL: 5)")
    shootout_max_rounds: int = Field(
        10,
        ge=1,
        le=100,
        description="rounds of sudden death at most after the regular kicks; a shoot-out still level then ends drawn",
    )
    shootout_shot_time: float = Field(
        10.0, gt=0.0, le=120.0, description="a shoot-out kick that is no goal this long after START is missed [s]"
    )

    # --- coach fields and switches ---------------------------------------------------------------------------
    max_vel: float = Field(
        4.5, ge=0.0, le=50.0, description="speed limit sent in CoachInfo [m/s] (original referee: 450 cm/s; 0: none)"
    )
    max_w: float = Field(10.0, ge=0.0, le=100.0, description="turn-rate limit sent in CoachInfo [rad/s] (0: none)")
    disabled_rules: list[str] = Field(
        default_factory=list, description=f"rules not judged, among: {', '.join(RULE_NAMES)}"
    )
    game_state_period: float = Field(
        1.0, gt=0.0, le=60.0, description="GameState is published on every change and at least this often [s]"
    )

    @model_validator(mode="after")
    def _consistent(self):
        unknown = sorted(set(self.disabled_rules) - set(RULE_NAMES))
        if unknown:
            raise ValueError(f"disabled_rules: unknown rule(s) {', '.join(unknown)}; rules are {', '.join(RULE_NAMES)}")
        if self.prepare_min_time > min(self.prepare_time, self.kickoff_prepare_time):
            raise ValueError("prepare_min_time must not exceed prepare_time and kickoff_prepare_time")
        if self.ball_holding_brief_depth < self.ball_holding_depth:
            raise ValueError("ball_holding_brief_depth must not be below ball_holding_depth")
        if self.restart_spot[0] < 0 or self.restart_spot[1] < 0:
            raise ValueError("restart_spot: both numbers must be >= 0")
        return self
