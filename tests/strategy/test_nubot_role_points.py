"""The positional roles' points exist once, in `simatch.strategy.nubot.positions`: a team follows the one
that module holds, in open play as at set pieces, so a user who replaces one there changes both."""

from __future__ import annotations

import math

import pytest

from simatch.msgs.game_commands import MatchMode as M
from simatch.strategy.nubot import positions
from simatch.strategy.roles import Role
from tests.strategy.helpers import bench_all_but, command, run_until, scenario, start

#: a point no role of nubot's own would choose (team frame: cyan's is the world's)
POINT = (-6.0, -5.2)


@pytest.fixture
def own_passive_point(monkeypatch):
    asked = []

    def passive_point(pitch, bx, by, attacking):
        asked.append((bx, by, attacking))
        return POINT

    monkeypatch.setattr(positions, "passive_point", passive_point)
    return asked


def _passive_robot_at_point(sim) -> bool:
    states = sim.model_states()
    for name, node in sim.robot_nodes.items():
        if name.startswith("cyan") and node.strategy.role == Role.PASSIVE:
            s = states[name]
            if math.hypot(s.x - POINT[0], s.y - POINT[1]) < 0.4:
                return True
    return False


def test_open_play_follows_the_passive_point_of_positions(own_passive_point):
    sim = scenario()
    bench_all_but(sim, [f"cyan/{k}" for k in range(1, 6)])
    sim.set_model_state("cyan/2", x=1.5, y=1.0, yaw=0.0)
    sim.set_model_state("cyan/3", x=-1.0, y=3.0, yaw=0.0)
    sim.set_model_state("cyan/4", x=-2.0, y=-1.0, yaw=0.0)
    sim.set_model_state("cyan/5", x=-4.0, y=2.0, yaw=0.0)
    sim.set_model_state("ball", x=2.5, y=1.0, z=0.11)
    sim.step()
    start(sim)
    assert run_until(sim, lambda: _passive_robot_at_point(sim), 10.0), sim.model_states()
    assert any(not attacking or bx > -3.0 for bx, _, attacking in own_passive_point)
    sim.close()


@pytest.mark.parametrize("cmd", [M.OPP_FREEKICK, M.DROPBALL], ids=["their free kick", "dropped ball"])
def test_set_pieces_follow_the_passive_point_of_positions(own_passive_point, cmd):
    sim = scenario()
    bench_all_but(sim, [f"cyan/{k}" for k in range(1, 6)])
    sim.set_model_state("ball", x=3.0, y=2.0, z=0.11)
    sim.step()
    command(sim, "cyan", cmd)
    assert run_until(sim, lambda: _passive_robot_at_point(sim), 8.0), sim.model_states()
    assert own_passive_point
    sim.close()
