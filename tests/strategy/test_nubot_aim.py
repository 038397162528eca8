"""Aiming a kick: the kicker adds its speed to the velocity the mouth already has, so the heading leans
against the robot's drift across the line to the target. Before, a robot drifting 1 m/s sideways put a
10 m/s shot 0.6 m wide of its aim at 6 m."""

from __future__ import annotations

import math
from types import SimpleNamespace

import pytest

from simatch.field import FieldGeometry
from simatch.strategy.nubot.active import MOUTH, BallPlayer
from simatch.strategy.nubot.motion import Motion
from simatch.strategy.nubot.params import NubotParams
from simatch.strategy.nubot.positions import Areas


@pytest.mark.parametrize("vx,vy,speed", [(0.0, 0.0, 10.0), (0.0, 1.0, 10.0), (1.5, -1.2, 10.0), (0.3, 0.8, 10.0),
                                         (0.0, -0.7, 3.0)])
def test_the_kicked_ball_heads_for_the_target(vx, vy, speed):
    field = FieldGeometry()
    p = NubotParams()
    areas = Areas(field, p.robot_radius + 0.15)
    player = BallPlayer(p, Motion(p, 0.025, field, areas), areas, 0.5 * field.goal_width)
    yaw = 0.3
    me = SimpleNamespace(x=5.0, y=-1.0, yaw=yaw, vx=vx, vy=vy, w=0.0)
    obs = SimpleNamespace(me=me, bx=me.x + MOUTH * math.cos(yaw), by=me.y + MOUTH * math.sin(yaw))
    tx, ty = 11.3, 0.6
    h = player.kick_heading(obs, tx, ty, speed)
    # the ball leaves with the robot's velocity plus the kick along the heading
    bvx, bvy = vx + speed * math.cos(h), vy + speed * math.sin(h)
    miss = abs(math.atan2(bvy, bvx) - math.atan2(ty - obs.by, tx - obs.bx))
    assert miss < 1e-9, (h, miss)
