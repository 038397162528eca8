"""The ball-holding rule cannot fire on the shipped robots: their mouth lets the ball into the footprint by
less than the 1/3 of its diameter the MSL allows (RC-12.0.1), by construction and in the physics.

The rule itself is judged by the scenarios (ball_holding_*.toml): it fires on robot models with a deeper
mouth, and not on the squeezes and impacts that press the ball deeper than the mouth for a moment."""

from __future__ import annotations

import math

import pytest

import simatch
from simatch.robots.omni3 import Omni3
from simatch.robots.omni4 import Omni4
from simatch.scene.referee.params import RefereeParams

BALL_RADIUS = 0.11
LIMIT = RefereeParams().ball_holding_depth * 2 * BALL_RADIUS  # 0.0733 m


@pytest.mark.parametrize("model", [Omni4, Omni3], ids=["omni4", "omni3"])
def test_the_mouth_collider_keeps_the_ball_less_than_a_third_deep(model):
    robot = model()
    p = robot.params
    cx, cr = robot.ball_collider(BALL_RADIUS)
    # the ball's centre stays cr + r from the capsule's axis at (cx, 0): the deepest it gets into the footprint
    # circle is straight ahead, at cx + cr + r from the robot's centre
    deepest = p.radius + BALL_RADIUS - (cx + cr + BALL_RADIUS)
    held = p.radius + BALL_RADIUS - robot.mouth_x(BALL_RADIUS)
    assert deepest == pytest.approx(p.mouth_depth)
    assert held < deepest < LIMIT


def test_a_robot_dribbling_hard_keeps_the_ball_less_than_a_third_deep():
    """Every physics step of a robot taking the ball and dribbling it flat out, turning hard (until the grip
    gives): the ball's depth in the footprint never reaches 1/3 of its diameter."""
    sim = simatch.Simulation(
        "msl_5v5",
        seed=0,
        overrides={"teams.cyan.strategy": "none", "teams.magenta.strategy": "none", "judge.kind": "none"},
    )
    try:
        sim.step()
        sim.take_control("cyan/2")
        sim.set_model_state("cyan/2", x=-2.0, y=0.0, yaw=0.0)
        sim.set_model_state("ball", x=-1.7, y=0.0, z=BALL_RADIUS)
        sim.send_action("cyan/2", dribble=True)
        deepest, held_steps = 0.0, 0
        for vel in [(0.0, 0.0, 0.0), (3.0, 0.0, 0.0), (3.0, 0.0, 5.0), (-2.0, 2.0, -5.0), (0.0, -3.0, 5.0)]:
            sim.send_vel("cyan/2", *vel)
            for _ in range(round(0.8 / sim.dt)):
                sim.step()
                st = sim.model_states()
                r, b = st["cyan/2"], st["ball"]
                depth = 0.25 + BALL_RADIUS - math.hypot(b.x - r.x, b.y - r.y)
                deepest = max(deepest, depth)
                held_steps += depth > 0.06
        assert held_steps * sim.dt > 1.0  # it did hold the ball (0.066 m deep) for a while
        assert deepest < LIMIT
    finally:
        sim.close()
