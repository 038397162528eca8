"""The tunable numbers of the nubot team (``teams.<team>.strategy_params`` in a scene).

The defaults fit the shipped MSL world (omni4 robots, 0.5 m/s^2 rolling ball, 10 m/s kicker) and keep
safety margins under the MSL limits the referee judges (3 m dribbling, 3 m / 2 m / 1 m set-piece distances,
10 s in a penalty area).
"""

from __future__ import annotations

from types import SimpleNamespace

from pydantic import BaseModel, ConfigDict, Field


class NubotParams(BaseModel):
    model_config = ConfigDict(extra="forbid")

    # --- the robot as the strategy models it ------------------------------------------------------------
    max_speed: float = Field(4.5, gt=0.0, le=10.0, description="cruise speed without the ball [m/s]")
    dribble_speed: float = Field(3.0, gt=0.0, le=6.0, description="top speed while holding the ball [m/s]")
    acceleration: float = Field(2.4, gt=0.0, le=20.0, description="speeding up, for reach-time estimates [m/s^2]")
    braking: float = Field(3.5, gt=0.0, le=20.0, description="planned slowing down [m/s^2]")
    max_turn: float = Field(7.0, gt=0.0, le=30.0, description="turn-rate limit without the ball [rad/s]")
    dribble_turn: float = Field(5.0, gt=0.0, le=30.0, description="turn-rate limit while holding the ball [rad/s]")
    turn_acceleration: float = Field(10.0, gt=0.0, le=100.0, description="planned angular slowing down [rad/s^2]")
    robot_radius: float = Field(0.25, gt=0.05, le=1.0, description="footprint radius of every robot [m]")

    # --- the ball -------------------------------------------------------------------------------------
    ball_deceleration: float = Field(0.5, ge=0.0, le=20.0, description="rolling deceleration assumed [m/s^2]")
    catch_speed: float = Field(
        3.0, gt=0.0, le=20.0, description="fastest ball the dribbler is trusted to take (relative) [m/s]"
    )

    # --- rules, with margins -------------------------------------------------------------------------
    dribble_limit: float = Field(
        2.4,
        gt=0.0,
        le=10.0,
        description="distance from where the ball was taken at which a dribble ends (MSL: 3 m) [m]",
    )
    dribble_back_limit: float = Field(1.2, ge=0.0, le=10.0, description="backward dribbling allowed (MSL: 2 m) [m]")
    opponent_distance: float = Field(
        3.35, gt=0.0, le=10.0, description="distance kept from the ball at opponents' restarts (MSL: 3 m) [m]"
    )
    mate_distance: float = Field(
        2.4, gt=0.0, le=10.0, description="distance kept by team-mates of the kicker at our restarts (MSL: 2 m) [m]"
    )
    dropball_distance: float = Field(
        1.35, gt=0.0, le=10.0, description="distance kept at a dropped ball (MSL: 1 m) [m]"
    )
    area_time: float = Field(
        6.0, gt=0.0, le=60.0, description="longest stay of a field robot in a penalty area (MSL: 10 s) [s]"
    )
    restart_wait: float = Field(
        7.5,
        gt=0.0,
        le=60.0,
        description="after this long a restart that was not taken is in play for "
        "everybody: the defending team may play it, the kicking team's "
        "other robots may come closer (MSL: 7 s) [s]",
    )
    contact_speed: float = Field(
        0.8, gt=0.0, le=10.0, description="closing speed allowed when touching an opponent [m/s]"
    )

    # --- play -----------------------------------------------------------------------------------------
    shoot_range: float = Field(8.0, gt=0.0, le=30.0, description="longest shot at the goal [m]")
    shot_speed: float = Field(10.0, gt=0.0, le=30.0, description="kick speed of a shot [m/s]")
    pass_arrival_speed: float = Field(2.2, gt=0.0, le=10.0, description="ball speed wanted at the receiver [m/s]")
    max_pass: float = Field(9.0, gt=0.0, le=30.0, description="longest ground pass [m]")
    role_hysteresis: float = Field(
        1.5,
        ge=0.0,
        le=20.0,
        description="a robot keeps its role unless another assignment saves this much total distance [m]",
    )
    active_hysteresis: float = Field(
        0.35,
        ge=0.0,
        le=10.0,
        description="the active robot keeps its role unless another reaches the ball this much sooner [s]",
    )


def plain(params: NubotParams) -> SimpleNamespace:
    """The parameters' values as plain attributes (read them, never write them), for the code that reads
    them for every robot and tick."""
    return SimpleNamespace(**{name: getattr(params, name) for name in type(params).model_fields})
