"""What a robot announces as its role when its strategy names none."""

from __future__ import annotations

from simatch import msgs
from simatch.bus import topics
from simatch.strategy.base import Command
from simatch.strategy.roles import Role
from tests.strategy.helpers import scenario


def test_a_robot_that_names_no_role_announces_none_not_the_goalkeepers():
    assert Command().role == Command.stop().role == Role.NOROLE
    sim = scenario(cyan="simple", magenta="simple")  # no referee: the robots stand at STOP, naming no role
    heard: dict[str, int] = {}
    for team in ("cyan", "magenta"):
        for rid in range(1, 6):
            topic = topics.robot_topic(team, rid, topics.STRATEGY_INFO)
            sim.bus.subscribe(topic, msgs.StrategyInfo, lambda m, k=f"{team}/{rid}": heard.__setitem__(k, m.role))
    sim.run(seconds=0.5)
    assert len(heard) == 10 and set(heard.values()) == {Role.NOROLE}, heard
