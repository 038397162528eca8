"""The nubot team's skills, each in a small scene through the Python API: scoring, passing, goalkeeping."""

from __future__ import annotations

import math

import pytest

from tests.strategy.helpers import BallWatch, bench_all_but, goal_side, run_until, scenario, start


@pytest.mark.parametrize("team", ["cyan", "magenta"])
def test_a_lone_attacker_scores_against_an_empty_goal(team):
    """Both colours: the same strategy attacks +x in its team frame, i.e. magenta scores at cyan's goal."""
    other = "magenta" if team == "cyan" else "cyan"
    sim = scenario(**{team: "nubot", other: "none"})
    s = 1 if team == "cyan" else -1
    bench_all_but(sim, [f"{team}/2"])
    sim.set_model_state(f"{team}/2", x=-2.0 * s, y=1.0, yaw=0.0 if s > 0 else math.pi)
    sim.set_model_state("ball", x=0.0, y=0.0, z=0.11)
    watch = BallWatch(sim)
    sim.step()
    start(sim)
    assert run_until(sim, lambda: goal_side(sim) == s, 15.0), sim.model_states()["ball"]
    assert watch.held_by(f"{team}/2") and watch.kicks and watch.kicks[-1][1] == f"{team}/2"
    # the shot came from the opponents' half, so the goal counts
    sim.close()


def test_a_pass_arrives():
    """A robot in its own half (no shot can count from there) passes to a free team-mate up the field,
    who takes the ball."""
    sim = scenario()
    bench_all_but(sim, ["cyan/2", "cyan/3"])
    sim.set_model_state("cyan/2", x=-3.0, y=0.0, yaw=0.0)
    sim.set_model_state("ball", x=-2.7, y=0.0, z=0.11)
    sim.set_model_state("cyan/3", x=2.0, y=3.0, yaw=math.pi)
    watch = BallWatch(sim)
    announced = []
    node = sim.robot_nodes["cyan/2"]
    original = node.publish

    def spy(now, tick, cmd, vx, vy, w):
        if cmd.pass_intent is not None:
            announced.append(cmd.pass_intent.catch_id)
        original(now, tick, cmd, vx, vy, w)

    node.publish = spy
    sim.step()
    start(sim)
    assert run_until(sim, lambda: watch.held_by("cyan/3"), 8.0)
    assert [k for k in watch.kicks if k[1] == "cyan/2"], "the ball reached the receiver by a kick"
    assert 3 in announced, "the passer told its team who receives"
    sim.close()


@pytest.mark.parametrize(
    "shooter,aim_y", [((5.0, 0.0), -0.6), ((5.0, 0.0), 0.0), ((5.0, 0.0), 0.6), ((4.0, 3.0), -0.95), ((4.0, 3.0), 0.95)]
)
def test_the_goalkeeper_stops_a_straight_shot(shooter, aim_y):
    sim = scenario(cyan="none", magenta="nubot")
    bench_all_but(sim, ["magenta/1"])
    bx, by = shooter
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    sim.step()
    start(sim)
    sim.run(seconds=1.5)  # the keeper takes its place for a ball there
    d = math.hypot(11.0 - bx, aim_y - by)
    v = 10.0  # the kicker's full speed
    sim.set_model_state("ball", x=bx, y=by, z=0.11, vx=v * (11.0 - bx) / d, vy=v * (aim_y - by) / d, vz=0.0)
    assert not run_until(sim, lambda: goal_side(sim) != 0, 2.5, step=0.01)
    sim.close()


def test_the_goalkeeper_stops_a_lob():
    sim = scenario(cyan="none", magenta="nubot")
    bench_all_but(sim, ["magenta/1"])
    bx, by = 3.0, 1.0
    sim.set_model_state("ball", x=bx, y=by, z=0.11)
    sim.step()
    start(sim)
    sim.run(seconds=1.5)
    a, v = math.radians(37.0), 8.5  # the kicker's lob, landing just in front of the goal
    d = math.hypot(11.0 - bx, -0.5 - by)
    h = v * math.cos(a)
    sim.set_model_state("ball", x=bx, y=by, z=0.11, vx=h * (11.0 - bx) / d, vy=h * (-0.5 - by) / d, vz=v * math.sin(a))
    assert not run_until(sim, lambda: goal_side(sim) != 0, 3.0, step=0.01)
    sim.close()
