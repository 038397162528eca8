"""A team of several kinds of robot (squads): ids, models, strategies that tell them apart, mistakes named."""

from __future__ import annotations

import pytest

import simatch
from simatch.config.loader import SceneError


def test_a_team_with_a_squad_of_drones():
    with simatch.Simulation("aerial_encirclement") as sim:
        spec = sim.scene.spec.teams["cyan"]
        assert spec.robot_ids() == list(range(1, 13))  # the squad's ids follow the team's own
        assert [m.model for m in spec.members()][-4:] == ["omni4", "quadrotor", "quadrotor", "quadrotor"]
        names = sim.simulator.robot_names
        assert names[:9] == [f"cyan/{i}" for i in range(1, 10)] and names[-3:] == ["cyan/10", "cyan/11", "cyan/12"]
        kinds = {n: type(node.strategy).__name__ for n, node in sim.robot_nodes.items() if n.startswith("cyan/")}
        assert kinds["cyan/1"] == "GroundChaser" and kinds["cyan/11"] == "Scout"
        sim.run(seconds=2.0)
        assert sim.model_states()["cyan/11"].z > 1.0  # the drones took off


@pytest.mark.parametrize(
    "overrides, error",
    [
        ({"teams.cyan.squads.0.model": "blimp"}, r"teams.cyan.squads\[0\].model: .*unknown robot model 'blimp'"),
        ({"teams.cyan.squads.0.model_params.mass": -1.0}, r"teams.cyan.squads\[0\].model_params.mass"),
        ({"teams.cyan.squads.0.ids": [3, 13, 14]}, r"ids must be distinct positive integers"),
        ({"teams.cyan.squads.0.ids": [13]}, r"ids has 1 entries but start has 3"),
        ({"teams.cyan.squads.0.wings": 2}, r"teams.cyan.squads\[0\].wings: unknown key"),
    ],
)
def test_squad_mistakes_are_named(overrides, error):
    with pytest.raises(SceneError, match=error):
        simatch.Simulation("aerial_encirclement", overrides=overrides)


@pytest.mark.parametrize(
    "overrides, error",
    [
        ({"teams.cyan.model_params.start_altitude": 3.99}, r"teams.cyan.model_params.start_altitude: 3.99 m puts"),
        ({"teams.magenta.model_params.start_altitude": 4.2}, r"teams.magenta.model_params.start_altitude: 4.2 m"),
        ({"judge.scatter": [-2.0, -4.0, 1.0, 6.0, 4.0, 4.5]}, r"judge.scatter: its top z1 = 4.5 m puts the evader"),
        ({"judge.scatter": [-2.0, -4.0, 1.0, 6.0, 4.0, 3.99]}, r"judge.scatter: its top z1 = 3.99 m .* ceiling"),
        ({"judge.scatter": [-2.0, -4.0, 0.01, 6.0, 4.0, 3.0]}, r"judge.scatter: its bottom z0 = 0.01 m .* floor"),
    ],
)
def test_drones_start_under_the_ceiling(overrides, error):
    with pytest.raises(SceneError, match=error):
        simatch.Simulation("pursuit_evasion_3d", overrides=overrides)


def test_drones_just_under_the_ceiling_fly():
    """The bounds are the body's, not its centre's: a frame that fits starts and the evader scatters in the box."""
    overrides = {"teams.cyan.model_params.start_altitude": 3.98, "judge.scatter": [-2.0, -4.0, 0.02, 6.0, 4.0, 3.98]}
    with simatch.Simulation("pursuit_evasion_3d", overrides=overrides) as sim:
        sim.run(seconds=0.1)
        states = sim.model_states()
        assert all(3.9 < states[f"cyan/{i}"].z < 4.0 for i in (1, 2, 3))
        assert 0.0 < states["magenta/1"].z < 4.0


def test_a_ground_evader_is_scattered_over_the_floor():
    """The pursuit judge scatters a wheeled evader over the box's floor, upright, and says nothing about heights."""
    overrides = {"teams.magenta.model": "omni4", "teams.magenta.model_params": {}, "teams.magenta.strategy": "none"}
    with simatch.Simulation("pursuit_evasion_3d", overrides=overrides) as sim:
        sim.run(seconds=0.2)
        e = sim.model_states()["magenta/1"]
        assert -2.0 <= e.x <= 6.0 and -4.0 <= e.y <= 4.0 and abs(e.z) < 0.5
        assert "robot_upright" not in [ev["type"] for ev in sim.events]


@pytest.mark.parametrize("height, altitude, fits", [(1.0, 1.5, True), (1.49, 1.5, False), (0.5, 0.0, False)])
def test_a_drone_may_start_in_the_air_above_a_low_obstacle(height, altitude, fits):
    """Over a box lower than its frame's bottom a drone starts where the scene says; into it, it is refused."""
    box = {"shape": "box", "x": -6.2, "y": -3.0, "size": [0.6, 0.6], "height": height}
    overrides = {"world.obstacles": [box], "teams.cyan.model_params.start_altitude": altitude}
    if not fits:
        with pytest.raises(SceneError, match=r"teams.cyan.start: robot 1 starts at \(-6.2, -3\), inside obstacle"):
            simatch.Simulation("pursuit_evasion_3d", overrides=overrides)
        return
    with simatch.Simulation("pursuit_evasion_3d", overrides=overrides) as sim:
        s = sim.model_states()["cyan/1"]
        assert (s.x, s.y) == pytest.approx((-6.2, -3.0)) and s.z == pytest.approx(altitude)
        sim.run(seconds=0.5)
        assert sim.model_states()["cyan/1"].z > height  # it flies off above the box, not through it


@pytest.mark.parametrize("scene", ["pursuit_evasion_3d", "msl_5v5"])
@pytest.mark.parametrize("call", ["stop_robot", "command_velocity", "command_action"])
def test_a_robot_index_out_of_range_is_an_index_error(scene, call):
    """With or without drones, past the last robot or negative: an IndexError, no other robot commanded."""
    with simatch.Simulation(scene) as sim:
        w = sim.simulator
        args = {"stop_robot": (), "command_velocity": (0.5, 0.0, 0.0), "command_action": (True,)}[call]
        for i in (w.n, w.n + 5, -1):
            with pytest.raises(IndexError, match=rf"robot index {i} out of range: the world has robots 0..{w.n - 1}"):
                getattr(w, call)(i, *args)
        assert not w.commanded.any()
