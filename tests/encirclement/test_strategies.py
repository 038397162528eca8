"""The two teams' strategies through the Python API: targets flee fast, leave corners and keep apart;
chasers see captures through their topics only; the whole scene captures all seven, and nobody when the
chasers stand still."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simatch.strategy.encirclement.game import Captures
from simatch.strategy.encirclement.view import opponents

from .conftest import park_targets, target_positions

FLEEING = {"teams.cyan.strategy": "none"}  # targets flee, chasers are moved by the test


def speed(sim, name: str) -> float:
    s = sim.model_states()[name]
    return math.hypot(s.vx, s.vy)


def test_targets_flee_at_least_sixty_percent_of_the_chasers_speed(encirclement):
    sim = encirclement(**FLEEING)
    caps = {t: sim.scene.spec.teams[t].strategy_params["max_speed"] for t in ("cyan", "magenta")}
    assert caps["magenta"] >= 0.6 * caps["cyan"]  # the ratio the scene declares
    park_targets(sim, keep=("magenta/1",))
    for k in range(2, 10):
        sim.set_model_state(f"cyan/{k}", x=-7.5, y=-5.5 + 1.2 * k)
    sim.set_model_state("magenta/1", x=-3.0, y=0.0, yaw=0.0)
    sim.set_model_state("cyan/1", x=-5.0, y=0.0, yaw=0.0)
    sim.take_control("cyan/1")
    sim.send_vel("cyan/1", caps["cyan"], 0.0, 0.0)  # runs at the target at the chasers' cap
    top = 0.0
    for _ in range(40):
        sim.run(0.05)
        top = max(top, speed(sim, "magenta/1"))
        if sim.model_states()["cyan/1"].x > 4.0:
            break
    assert top >= 0.6 * caps["cyan"]
    t, c = sim.model_states()["magenta/1"], sim.model_states()["cyan/1"]
    assert math.hypot(t.x - c.x, t.y - c.y) > 0.6  # it got out of the way


def test_a_target_leaves_a_corner_and_targets_keep_apart(encirclement):
    sim = encirclement(**FLEEING)
    park_targets(sim, keep=("magenta/1", "magenta/2", "magenta/3"))
    sim.set_model_state("magenta/1", x=-7.6, y=-5.6)  # in a corner
    sim.set_model_state("magenta/2", x=1.0, y=0.0)  # two targets nearly touching
    sim.set_model_state("magenta/3", x=1.55, y=0.0)
    corner = (-7.75, -5.75)
    before = math.dist(target_positions(sim)["magenta/1"], corner)
    sim.run(3.0)
    pos = target_positions(sim)
    assert math.dist(pos["magenta/1"], corner) > before + 0.5
    assert math.dist(pos["magenta/2"], pos["magenta/3"]) >= 0.85  # from 0.55 m


def test_targets_come_to_rest_when_no_chaser_comes_near(encirclement):
    sim = encirclement(**FLEEING)
    sim.run(5.0)  # those that start near a chaser, a wall or a corner move off
    before = target_positions(sim)
    sim.run(5.0)
    after = target_positions(sim)
    assert max(math.dist(before[n], after[n]) for n in before) < 0.05


def test_opponents_are_told_from_team_mates_under_noise(encirclement):
    sim = encirclement(**{"perception.position_noise": 0.05, "perception.obstacle_dropout": 0.1})
    for _ in range(20):
        sim.run(0.05)
        world = sim.robot_nodes["cyan/4"].world
        seen = opponents(world)
        assert len(seen) <= 7
        truth = list(target_positions(sim).values())
        for x, y in seen:  # every one is a target
            assert min(math.dist((x, y), t) for t in truth) < 0.35


def test_chasers_learn_captures_from_the_game_state_only(encirclement):
    sim = encirclement()
    sim.run(0.2)
    world = sim.robot_nodes["cyan/2"].world
    caps = Captures().update(world)
    assert caps.names == frozenset()
    sim.set_model_state("magenta/5", x=6.0, y=1.0)
    sim.run(0.2)
    caps.update(world)
    assert caps.names == {"magenta/5"}
    x, y = caps.where[0]
    assert (x, y) == pytest.approx((6.0, 1.0), abs=0.01)
    free = caps.free(opponents(world))
    assert len(free) == 6 and all(math.dist(p, (x, y)) > 0.3 for p in free)
    # a garbled summary tells nothing rather than crashing a robot
    world.game.result = "{not json"
    assert Captures().update(world).names == frozenset()


def test_the_chasers_herd_all_seven_into_the_prison(encirclement):
    sim = encirclement(seed=0)
    sim.run()
    r = sim.result()["result"]
    assert r["captured"] == 7 and r["capture_time_s"] is not None and r["capture_time_s"] <= 300.0
    assert r["top_speed_m_s"]["magenta"] >= 0.6 * r["top_speed_m_s"]["cyan"]
    assert not [e for e in sim.events if e["type"] in ("strategy_error", "bad_command")]
    for c in r["captures"]:  # frozen where they were captured (give or take the shoves)
        p = target_positions(sim)[c["robot"]]
        assert math.dist(p, (c["x"], c["y"])) < 0.1
        assert 5.0 <= c["x"] <= 8.0 and -2.0 <= c["y"] <= 2.0


def test_the_chasers_still_win_with_noisy_perception(encirclement):
    sim = encirclement(
        seed=1,
        **{"perception.position_noise": 0.05, "perception.velocity_noise": 0.1, "perception.obstacle_dropout": 0.05},
    )
    sim.run()
    assert sim.result()["result"]["captured"] == 7


def test_nobody_is_captured_while_the_chasers_stand_still(encirclement):
    sim = encirclement(seed=2, **{"teams.cyan.strategy": "none", "judge.time_limit": 60.0})
    sim.run()
    r = sim.result()["result"]
    assert r["captured"] == 0 and r["end"] == "time_limit"
    assert r["top_speed_m_s"]["cyan"] < 0.01


def test_a_run_is_repeatable_bit_for_bit_and_seeds_differ(encirclement):
    a, b, c = (encirclement(seed=s) for s in (7, 7, 8))
    for sim in (a, b, c):
        sim.run(6.0)
    assert a.state_digest() == b.state_digest() != c.state_digest()
    assert np.allclose(list(target_positions(a).values()), list(target_positions(b).values()))


def test_a_chaser_without_its_prison_is_refused_with_the_key_named():
    import simatch
    from simatch.config.loader import SceneError

    with pytest.raises(
        SceneError,
        match=r"teams.cyan.strategy_params.prison: the world has no area named 'jail' "
        r"\(world.areas: prison\)",
    ):
        simatch.Simulation("encirclement_9v7", overrides={"teams.cyan.strategy_params.prison": "jail"})
    with pytest.raises(SceneError, match=r"teams.magenta.strategy_params.max_speed: expected greater than 0"):
        simatch.Simulation("encirclement_9v7", overrides={"teams.magenta.strategy_params.max_speed": 0})


def test_the_net_squeezes_when_nothing_gives_way():
    from simatch.config.loader import load_scene
    from simatch.strategy.base import RobotContext
    from simatch.strategy.encirclement import Chaser, ChaserParams

    field = load_scene("encirclement_9v7").spec.world.geometry()
    p = ChaserParams()
    chaser = Chaser(
        RobotContext(
            team="cyan",
            id=1,
            goalkeeper=None,
            ids=[1],
            field=field,
            start=(0.0, 0.0, 0.0),
            control_period=0.05,
            params=p,
        )
    )
    assert chaser._slack(0.0, 6.0, 0) == p.slack
    assert chaser._slack(p.squeeze_after, 6.0, 0) == p.slack  # patience
    assert chaser._slack(p.squeeze_after + 2.0, 6.0, 0) == pytest.approx(p.slack - 2.0 * p.squeeze_rate)
    assert chaser._slack(p.squeeze_after + 100.0, 6.0, 0) == p.min_slack  # down to the floor
    assert chaser._slack(200.0, 5.5, 0) == p.slack  # a target gave way
    assert chaser._slack(200.0 + p.squeeze_after + 1.0, 5.6, 0) < p.slack
    assert chaser._slack(200.0 + p.squeeze_after + 1.0, 5.6, 1) == p.slack  # a capture
