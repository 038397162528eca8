"""What a robot announces as its role and action when its strategy names none."""

from __future__ import annotations

from simatch import msgs
from simatch.bus import topics
from simatch.strategy.base import Command
from simatch.strategy.roles import Action, Role
from tests.strategy.helpers import scenario


def test_a_robot_that_names_no_role_announces_none_not_the_goalkeepers():
    assert Command().role == Command.stop().role == Role.NOROLE
    assert Command().action == Action.NO_ACTION  # not STUCKED
    sim = scenario(cyan="simple", magenta="simple")  # no referee: the robots stand at STOP, naming no role
    heard: dict[str, int] = {}
    for team in ("cyan", "magenta"):
        for rid in range(1, 6):
            topic = topics.robot_topic(team, rid, topics.STRATEGY_INFO)
            sim.bus.subscribe(topic, msgs.StrategyInfo, lambda m, k=f"{team}/{rid}": heard.__setitem__(k, m.role))
    sim.run(seconds=0.5)
    assert len(heard) == 10 and set(heard.values()) == {Role.NOROLE}, heard


def test_robots_of_a_scene_beyond_soccer_announce_no_action_rather_than_stuck():
    import simatch

    sim = simatch.Simulation("encirclement_9v7", seed=0)
    heard: dict[str, int] = {}
    for name in sim.simulator.robot_names:
        team, rid = name.split("/")
        topic = topics.robot_topic(team, int(rid), topics.STRATEGY_INFO)
        sim.bus.subscribe(topic, msgs.StrategyInfo, lambda m, k=name: heard.__setitem__(k, m.action))
    sim.run(seconds=0.5)
    assert len(heard) == 16 and Action.STUCKED not in heard.values(), heard
