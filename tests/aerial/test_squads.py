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
