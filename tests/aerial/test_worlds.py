"""Worlds are plug-ins (``world.kind``): the MSL field, the arena with obstacles given or scattered from a
seed and zones, a world written outside simatch; one description that the physics builds, viewers draw and
judges read; mistakes refused with the file and the key."""

from __future__ import annotations

import math

import pytest

import simatch
from simatch.config.loader import SceneError, load_scene, scene_from_text

ARENA = """
name = "arena_test"
[world]
kind = "{kind}"
length = 12.0
width = 8.0
{world}
[ball]
position = [-5.5, -3.5]
[teams.cyan]
model = "omni4"
strategy = "none"
start = [[-4.0, 0.0, 0.0]]
"""


def arena(world: str = "", kind: str = "arena", **overrides):
    return scene_from_text(ARENA.format(kind=kind, world=world), "<arena>", overrides)


def test_the_default_world_is_still_the_msl_field():
    geo = load_scene("msl_5v5").spec.world.geometry()
    assert geo.kind == "msl_field" and geo.goals and geo.lines() and geo.obstacles == ()


def test_an_arena_has_walls_zones_and_obstacles_and_no_soccer():
    scene = arena(
        'areas = [{ name = "base", x0 = 3.0, y0 = -1.0, x1 = 5.0, y1 = 1.0 }]\n'
        'obstacles = [{ shape = "box", x = 0.0, y = 2.0, size = [1.0, 0.5], yaw = 0.3, height = 1.2 },'
        ' { shape = "cylinder", x = -1.0, y = -2.0, radius = 0.4, height = 2.0, name = "pillar" }]'
    )
    geo = scene.spec.world.geometry()
    assert (geo.kind, geo.margin, geo.goals, geo.markings, geo.lines()) == ("arena", 0.0, False, "none", [])
    assert geo.area("base").contains(4.0, 0.0)
    box, pillar = geo.obstacles
    assert box.name == "obstacle_1" and pillar.name == "pillar"
    assert box.contains(0.0, 2.0) and not box.contains(0.0, 2.6) and pillar.distance(-1.0, -1.0) == pytest.approx(0.6)
    d = geo.describe()
    assert d["kind"] == "arena" and [o["name"] for o in d["obstacles"]] == ["obstacle_1", "pillar"]
    assert d["obstacles"][1] == {
        "name": "pillar",
        "shape": "cylinder",
        "x": -1.0,
        "y": -2.0,
        "height": 2.0,
        "radius": 0.4,
    }


def test_scattered_obstacles_come_from_their_seed_and_keep_their_distances():
    clutter = (
        "clutter = {{ seed = {seed}, boxes = 3, cylinders = 3, gap = 1.0, keep_clear = [[-6.0, -4.0, -3.0, 4.0]] }}"
    )
    a = arena(clutter.format(seed=7)).spec.world.geometry().obstacles
    assert a == arena(clutter.format(seed=7)).spec.world.geometry().obstacles  # the same on every load
    assert a != arena(clutter.format(seed=8)).spec.world.geometry().obstacles
    assert sorted(o.name for o in a) == ["box_1", "box_2", "box_3", "cylinder_1", "cylinder_2", "cylinder_3"]
    for i, p in enumerate(a):
        assert p.x - p.bounding_radius >= -3.0 + 1.0 - 1e-9  # out of the kept-clear rectangle, with the gap
        for q in a[i + 1 :]:
            assert math.hypot(p.x - q.x, p.y - q.y) >= p.bounding_radius + q.bounding_radius + 1.0 - 1e-9


def test_a_ground_robot_is_stopped_by_an_obstacle():
    scene = arena('obstacles = [{ shape = "box", x = -1.0, y = 0.0, size = [1.0, 3.0], height = 1.0 }]')
    with simatch.Simulation(scene) as sim:
        sim.take_control("cyan/1")
        sim.send_vel("cyan/1", 2.0, 0.0, 0.0)
        sim.run(3.0)
        s = sim.model_states()["cyan/1"]
    assert s.x == pytest.approx(-1.5 - 0.25, abs=0.03)  # its hull against the box's face


def test_a_world_plug_in_from_outside_simatch():
    scene = arena("params = { spacing = 3.0 }", kind="tests.aerial.plugin_world:Corridor")
    geo = scene.spec.world.geometry()
    assert geo.kind == "corridor" and [o.name for o in geo.obstacles] == ["pillar_1", "pillar_2", "pillar_3"]
    with simatch.Simulation(scene) as sim:  # the simulator builds the pillars: a robot stops at one
        sim.take_control("cyan/1")
        sim.set_model_state("cyan/1", x=-1.5, y=0.0, yaw=0.0)  # between the pillars at x = -3 and 0
        sim.send_vel("cyan/1", 2.0, 0.0, 0.0)
        sim.run(2.0)
        assert sim.model_states()["cyan/1"].x == pytest.approx(0.0 - 0.2 - 0.25, abs=0.03)


@pytest.mark.parametrize(
    "world, kind, error",
    [
        ("goals = true", "arena", r"world.goals: not a setting of the arena world"),
        ("", "maze", r"world.kind: unknown world 'maze': expected one of arena, msl_field"),
        ('obstacles = [{ shape = "box", x = 0.0, y = 0.0 }]', "arena", r"world.obstacles\[0\]: a box needs size"),
        ('obstacles = [{ shape = "cylinder", x = 0.0, y = 0.0, radius = 0.3, yaw = 1.0 }]', "arena", "radius, not"),
        (
            'obstacles = [{ shape = "box", x = 5.9, y = 0.0, size = [1.0, 1.0] }]',
            "arena",
            r"does not stand on the floor",
        ),
        ('obstacles = [{ shape = "box", x = -4.0, y = 0.0, size = [1.0, 1.0] }]', "arena", r"robot 1 starts at"),
        ("clutter = { boxes = 40, gap = 2.0 }", "arena", r"world.clutter: no room for 40 obstacles"),
        ("clutter = { boxes = 1, size = [2.0, 1.0] }", "arena", r"size: expected 0 < low <= high"),
        ("params = { spacing = 0.1 }", "tests.aerial.plugin_world:Corridor", r"world.params.spacing"),
    ],
)
def test_mistakes_name_the_file_and_the_key(world, kind, error):
    with pytest.raises(SceneError, match=error):
        arena(world, kind=kind)
