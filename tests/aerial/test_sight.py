"""What robots see, switchable in the scene: sight lines blocked by obstacles (ground robots), a drone
camera's cone below it, a ground robot's range; heights in the messages. Perception taken from the real
bus, as a robot gets it."""

from __future__ import annotations

import math

import numpy as np
import pytest

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.config.loader import scene_from_text

SCENE = """
name = "sight"
[world]
kind = "arena"
length = 20.0
width = 14.0
obstacles = [{{ shape = "box", x = 0.0, y = 0.0, size = [1.0, 2.0], height = {box_height}, name = "wall_box" }}]
[perception]
line_of_sight = {los}
camera_footprint = {footprint}
{extra}
[ball]
position = [3.0, 0.0]
[teams.cyan]
model = "omni4"
strategy = "none"
start = [[-3.0, 0.0, 0.0], [-3.0, 5.0, 0.0]]
[[teams.cyan.squads]]
model = "quadrotor"
model_params = {{ start_altitude = 4.0 }}
start = [[3.0, 5.0, 0.0]]
[teams.magenta]
model = "omni4"
strategy = "none"
start = [[3.0, 1.0, 0.0], [8.0, 5.0, 0.0]]
"""


def look(box_height=1.5, los=True, footprint=True, extra="") -> dict[str, object]:
    """Every robot's OmniVisionInfo after one control tick (from the bus)."""
    text = SCENE.format(
        box_height=box_height, los="true" if los else "false", footprint="true" if footprint else "false", extra=extra
    )
    got = {}
    with simatch.Simulation(scene_from_text(text, "<sight>")) as sim:
        subs = []
        for name in sim.simulator.robot_names:
            team, rid = topics.split_robot_name(name)
            subs.append(
                sim.bus.subscribe(
                    topics.robot_topic(team, rid, topics.OMNI_VISION),
                    msgs.OmniVisionInfo,
                    lambda m, name=name: got.__setitem__(name, m),
                )
            )
        sim.step()
        for sub in subs:
            sub.close()
    return got


def seen_at(info, sign=1) -> set[tuple[float, float]]:
    o = info.obstacles
    return {(round(sign * float(x), 1), round(sign * float(y), 1)) for x, y in zip(o.x, o.y)}


def test_an_obstacle_hides_what_is_behind_it_from_a_ground_robot():
    got = look()
    assert (3.0, 1.0) not in seen_at(got["cyan/1"])  # behind the 1.5 m box: the robot's eye is at 0.8 m
    assert not got["cyan/1"].ball.pos_known  # the ball too
    assert (3.0, 1.0) in seen_at(got["cyan/2"])  # from y = 5 the line passes by the box
    assert got["cyan/2"].ball.pos_known


def test_over_a_low_obstacle_and_with_the_rule_off_everything_is_seen():
    assert (3.0, 1.0) in seen_at(look(box_height=0.5)["cyan/1"])  # below the eye and the other's top
    assert (3.0, 1.0) in seen_at(look(los=False)["cyan/1"])


def test_a_drone_sees_what_lies_in_its_cone_below_it():
    got = look()
    drone = got["cyan/3"]
    seen = seen_at(drone)
    cone = (4.0 - 0.8) * math.tan(math.radians(55.0))  # 4.57 m out for a robot's top 3.2 m below
    assert (3.0, 1.0) in seen and cone > 4.0  # 4 m away horizontally
    assert (-3.0, 5.0) not in seen and (8.0, 5.0) not in seen  # 6 and 5 m out: outside the cone
    everything = seen_at(look(footprint=False)["cyan/3"])
    assert {(-3.0, 5.0), (8.0, 5.0)} <= everything


def test_a_ground_robot_sees_no_farther_than_its_range():
    got = look(los=False, extra="ground_range = 5.5")
    assert (-3.0, 5.0) in seen_at(got["cyan/1"])  # 5 m away
    assert (3.0, 1.0) not in seen_at(got["cyan/1"])  # 6.1 m
    mine = seen_at(got["magenta/1"], sign=-1)  # magenta's team frame is turned
    assert (3.0, 5.0) in mine  # the drone, 5.1 m from its eye
    assert (8.0, 5.0) not in mine  # 6.4 m
    assert (8.0, 5.0) in seen_at(look(los=False)["magenta/1"], sign=-1)  # no range: seen


def test_heights_are_in_the_messages():
    got = look(los=False, footprint=False)
    drone = next(r for r in got["cyan/1"].robots if r.id == 3)
    assert drone.z == pytest.approx(4.0, abs=1e-3) and drone.vz == pytest.approx(0.0, abs=1e-3)
    assert len(drone.wheel_speeds) == 0
    ground = next(r for r in got["cyan/1"].robots if r.id == 1)
    assert ground.z == 0.0
    o = got["magenta/1"].obstacles
    z = {(round(-float(x), 1), round(-float(y), 1)): float(h) for x, y, h in zip(o.x, o.y, o.z)}  # magenta: turned
    assert z[(3.0, 5.0)] == pytest.approx(4.0, abs=1e-3) and z[(-3.0, 0.0)] == 0.0
    assert np.asarray(o.z).dtype == np.float32
