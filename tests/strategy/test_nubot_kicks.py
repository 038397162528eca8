"""Kicks with the ball. Aiming: the kicker adds its speed to the velocity the mouth already has, so the
heading leans against the robot's drift across the line to the target (before, a robot drifting 1 m/s
sideways put a 10 m/s shot 0.6 m wide of its aim at 6 m). First-time clearances (an opponent on the
ball): before, they went at 4 m/s wherever the robot faced, so most rolled out over a line or into the
opponent in front and bounced back."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from simatch.field import FieldGeometry
from simatch.strategy.nubot.active import MOUTH, BallPlayer
from simatch.strategy.nubot.motion import Motion
from simatch.strategy.nubot.params import NubotParams
from simatch.strategy.nubot.positions import Areas


def player() -> BallPlayer:
    field = FieldGeometry()
    p = NubotParams()
    areas = Areas(field, p.robot_radius + 0.15)
    return BallPlayer(p, Motion(p, 0.025, field, areas), areas, 0.5 * field.goal_width)


def holding(x: float, y: float, yaw: float, opps: list) -> SimpleNamespace:
    """What a robot holding the ball sees (team frame): itself, the ball in its mouth, opponents."""
    me = SimpleNamespace(id=2, x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, w=0.0, holding=True)
    return SimpleNamespace(
        me=me,
        mates=[me],
        opps=opps,
        opp_array=np.array(opps, dtype=np.float64).reshape(-1, 4),  # as Observation gives them to kernels
        bx=x + MOUTH * math.cos(yaw),
        by=y + MOUTH * math.sin(yaw),
    )


def test_a_clearance_stays_on_the_field():
    """Facing the side line 4.7 m away (a 4 m/s kick would roll 16 m), the kick stops before the line."""
    p = player()
    obs = holding(-2.0, 2.3, math.pi / 2, [(-2.9, 2.1, 0.0, 0.0)])
    plan = p.first_time(obs, can_score=False)
    assert plan is not None and plan[0] == "clear"
    roll = plan[3] ** 2 / (2.0 * p.p.ball_deceleration)
    assert obs.by + roll < p.areas.W2, plan


def test_no_clearance_into_an_opponent_in_front():
    p = player()
    assert p.first_time(holding(2.0, 0.0, 0.0, [(2.75, 0.05, 0.0, 0.0)]), can_score=False) is None
    plan = p.first_time(holding(2.0, 0.0, 0.0, [(2.3, 1.0, 0.0, 0.0)]), can_score=False)
    assert plan is not None and plan[0] == "clear"


@pytest.mark.parametrize(
    "vx,vy,speed", [(0.0, 0.0, 10.0), (0.0, 1.0, 10.0), (1.5, -1.2, 10.0), (0.3, 0.8, 10.0), (0.0, -0.7, 3.0)]
)
def test_the_kicked_ball_heads_for_the_target(vx, vy, speed):
    yaw = 0.3
    me = SimpleNamespace(x=5.0, y=-1.0, yaw=yaw, vx=vx, vy=vy, w=0.0)
    obs = SimpleNamespace(me=me, bx=me.x + MOUTH * math.cos(yaw), by=me.y + MOUTH * math.sin(yaw))
    tx, ty = 11.3, 0.6
    h = player().kick_heading(obs, tx, ty, speed)
    # the ball leaves with the robot's velocity plus the kick along the heading
    bvx, bvy = vx + speed * math.cos(h), vy + speed * math.sin(h)
    miss = abs(math.atan2(bvy, bvx) - math.atan2(ty - obs.by, tx - obs.bx))
    assert miss < 1e-9, (h, miss)
