"""Situations from nubot-against-nubot matches where nubot used to foul, rebuilt through the Python API
(no referee: the test gives the game commands and measures what the referee would)."""

from __future__ import annotations

import math

from simatch.scene.commands import MatchMode as M
from tests.strategy.helpers import command, scenario

PREPARE = 5.0           # the referee's preparation time before START


#: seed 5, t = 71.5 s: the ball is placed for magenta's throw-in at (5.92, -6.70) (world frame)
THROW_IN = {"cyan/2": (5.40, 2.72, -1.25), "cyan/3": (5.99, -7.23, -0.26), "cyan/4": (-1.16, -1.15, -0.70),
            "cyan/5": (-0.64, -2.64, -0.57), "magenta/2": (4.90, -5.15, -0.62), "magenta/3": (8.22, -3.92, -2.02),
            "magenta/4": (4.45, 2.21, -2.33), "magenta/5": (-0.62, 4.45, -0.92)}


def place(sim, poses: dict) -> None:
    for name, (x, y, yaw) in poses.items():
        sim.set_model_state(name, x=x, y=y, yaw=yaw, vx=0.0, vy=0.0, wz=0.0)


def test_a_robot_beyond_the_side_line_leaves_the_throw_in_circle_along_the_field():
    """The ball is placed for the opponents' throw-in half a metre from a robot that ran over the side line
    with it, the taker coming to the ball from inside the field. Leaving the 3 m circle straight away from
    the ball drove the robot into the boards, where it stayed (1.6 m from the ball at START: a set-piece
    distance foul); it must go round, along the line."""
    sim = scenario(cyan="nubot", magenta="nubot")
    bx, by = 5.92, -6.70
    place(sim, THROW_IN)
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    sim.step()
    command(sim, "magenta", M.OUR_THROWIN)
    sim.run(seconds=PREPARE)
    ms = sim.model_states()
    near = {n: round(math.hypot(ms[n].x - bx, ms[n].y - by), 2) for n in sim.simulator.robot_names
            if n.startswith("cyan")}
    assert min(near.values()) >= 3.0, near
    sim.close()
