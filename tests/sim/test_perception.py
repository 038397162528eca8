"""Each robot's OmniVisionInfo: in its team frame (magenta mirrored), with optional noise, dropout and
latency set in the scene (off by default)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simatch import msgs
from simatch.bus import topics

R = 0.11


def _listen(sim, names):
    got = {}
    for name in names:
        team, rid = topics.split_robot_name(name)
        sim.bus.subscribe(
            topics.robot_topic(team, rid, topics.OMNI_VISION),
            msgs.OmniVisionInfo,
            lambda m, n=name: got.__setitem__(n, m),
        )
    return got


def test_magentas_perception_is_the_mirror_of_cyans(field_sim):
    sim = field_sim()
    # a symmetric situation: cyan/2 at (-2, 1) facing +x, magenta/2 at (2, -1) facing -x
    sim.set_model_state("cyan/2", x=-2.0, y=1.0, yaw=0.3)
    sim.set_model_state("magenta/2", x=2.0, y=-1.0, yaw=math.pi + 0.3)
    sim.set_model_state("ball", x=0.5, y=0.25, z=R, vx=1.0, vy=-0.5)
    got = _listen(sim, ["cyan/2", "magenta/2"])
    sim.step()
    c, m = got["cyan/2"], got["magenta/2"]
    me_c = next(r for r in c.robots if r.id == 2)
    me_m = next(r for r in m.robots if r.id == 2)
    assert (me_c.x, me_c.y) == pytest.approx((-2.0, 1.0)) and me_c.yaw == pytest.approx(0.3)
    assert (me_m.x, me_m.y) == pytest.approx((-2.0, 1.0)) and me_m.yaw == pytest.approx(0.3)
    # the ball: cyan sees it at (0.5, 0.25); magenta at the mirror (-0.5, -0.25), moving the mirror way
    assert (c.ball.x, c.ball.y, c.ball.vx, c.ball.vy) == pytest.approx((0.5, 0.25, 1.0, -0.5))
    assert (m.ball.x, m.ball.y, m.ball.vx, m.ball.vy) == pytest.approx((-0.5, -0.25, -1.0, 0.5))
    # relative polar position of the ball does not depend on the frame
    assert m.ball.distance == pytest.approx(math.hypot(0.5 - 2.0, 0.25 + 1.0))
    assert c.ball.distance == pytest.approx(math.hypot(0.5 + 2.0, 0.25 - 1.0))
    assert c.ball.angle == pytest.approx(math.atan2(-0.75, 2.5) - 0.3)
    # magenta/2 faces pi + 0.3 in the world: the ball at world bearing atan2(1.25, -1.5)
    assert m.ball.angle == pytest.approx(math.remainder(math.atan2(1.25, -1.5) - (math.pi + 0.3), 2 * math.pi))
    # obstacles: every other robot (9), in the team frame
    assert len(c.obstacles.x) == 9 and len(m.obstacles.x) == 9
    oc = set(zip(np.round(c.obstacles.x, 6), np.round(c.obstacles.y, 6)))
    assert (2.0, -1.0) in oc  # magenta/2 as cyan/2 sees it
    om = set(zip(np.round(m.obstacles.x, 6), np.round(m.obstacles.y, 6)))
    assert (2.0, -1.0) in om  # cyan/2 as magenta/2 sees it (mirrored)
    # own team, self included
    assert sorted(r.id for r in c.robots) == [1, 2, 3, 4, 5]
    assert len(me_c.wheel_speeds) == 4


def test_perception_is_exact_by_default_and_noisy_when_asked(field_sim):
    exact = field_sim()
    got = _listen(exact, ["cyan/3"])
    exact.step()
    b = exact.model_states()["ball"]
    assert got["cyan/3"].ball.x == b.x and got["cyan/3"].ball.state == msgs.BallInfo.SEEBALLBYOWN
    noisy = field_sim(**{"perception.position_noise": 0.05, "perception.ball_dropout": 0.5})
    got = _listen(noisy, ["cyan/3"])
    errors, unseen = [], 0
    for _ in range(400):
        noisy.step()
        if noisy.simulator.step_index % 5 == 1:
            ball = got["cyan/3"].ball
            if not ball.pos_known:
                unseen += 1
            else:
                errors.append(ball.x - noisy.model_states()["ball"].x)
    assert 0.05 * 0.7 < np.std(errors) < 0.05 * 1.3
    assert 0.3 < unseen / 80 < 0.7


def test_latency_shows_the_world_as_it_was(field_sim):
    sim = field_sim(**{"perception.latency": 0.1})
    got = _listen(sim, ["cyan/3"])
    sim.set_model_state("ball", x=0.0, y=0.0, z=R, vx=2.0, vy=0.0, vz=0.0, wy=2.0 / R)
    history = []
    for _ in range(100):
        history.append(sim.model_states()["ball"].x)
        sim.step()
    seen = got["cyan/3"].ball.x
    # the last observation (at step 95) shows the ball of step 75 (0.1 s earlier)
    assert seen == msgs.f32(history[75])  # at the perception's float32 precision


def test_the_perception_of_some_robots_alone_is_what_they_get_among_all(field_sim):
    """A real-time server takes each robot's perception at its own step: the messages of a few robots are
    those of the whole observation (same noise, same dropouts), and nobody else's are made."""
    sim = field_sim(
        **{"perception.position_noise": 0.05, "perception.ball_dropout": 0.3, "perception.obstacle_dropout": 0.3}
    )
    sim.step(3)
    perception = sim.simulator.perception
    snap = sim.simulator.snapshot()
    state = perception.rng.bit_generator.state
    every = perception.observe(snap, 1.0, 7)
    for only in ([2], [0, 7], list(range(10))):
        perception.rng.bit_generator.state = state
        some = perception.observe(snap, 1.0, 7, only)
        for i, msg in enumerate(some):
            if i in only:
                assert msgs.encode(msg) == msgs.encode(every[i])
            else:
                assert msg is None


def test_a_team_frame_turns_when_the_teams_change_ends(field_sim):
    """The referee turns the team frames at half time (`set_team_sign`): from the next observation on, cyan
    sees the world turned by pi (it attacks -x), magenta as it is; each still attacks +x in its own frame."""
    sim = field_sim()
    sim.set_model_state("cyan/2", x=3.5, y=-1.0, yaw=math.pi)
    sim.set_model_state("magenta/2", x=-3.5, y=1.0, yaw=0.0)
    sim.set_model_state("ball", x=0.5, y=0.25, z=R, vx=1.0, vy=-0.5)
    world = sim.simulator
    world.set_team_sign("cyan", -1)
    world.set_team_sign("magenta", 1)
    got = _listen(sim, ["cyan/2", "magenta/2"])
    sim.step()
    c, m = got["cyan/2"], got["magenta/2"]
    me_c = next(r for r in c.robots if r.id == 2)
    me_m = next(r for r in m.robots if r.id == 2)
    # both forwards stand in their own half facing the other goal: at (-3.5, +-1) facing +x in their frames
    assert (me_c.x, me_c.y, me_c.yaw) == pytest.approx((-3.5, 1.0, 0.0), abs=1e-6)
    assert (me_m.x, me_m.y, me_m.yaw) == pytest.approx((-3.5, 1.0, 0.0), abs=1e-6)
    assert (c.ball.x, c.ball.y, c.ball.vx, c.ball.vy) == pytest.approx((-0.5, -0.25, -1.0, 0.5))
    assert (m.ball.x, m.ball.y, m.ball.vx, m.ball.vy) == pytest.approx((0.5, 0.25, 1.0, -0.5))
    with pytest.raises(Exception, match="sign must be"):
        world.set_team_sign("cyan", 0)
    with pytest.raises(Exception, match="no team named 'yellow'"):
        world.set_team_sign("yellow", 1)
