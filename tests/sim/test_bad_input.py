"""Bad input gets a clear refusal, never reaches the physics, and is counted in the run's events."""

from __future__ import annotations

import math

import pytest

from simatch import msgs
from simatch.bus import topics
from tests.conftest import park_everyone_but


@pytest.mark.parametrize(
    "vx, vy, w",
    [
        (float("nan"), 0.0, 0.0),
        (0.0, float("inf"), 0.0),
        (0.0, 0.0, -math.inf),
        (1e6, 0.0, 0.0),
        (0.0, 0.0, 500.0),
        ("fast", 0.0, 0.0),
    ],
)
def test_bad_velocity_commands_are_refused_and_counted(field_sim, vx, vy, w):
    sim = field_sim()
    park_everyone_but(sim, ["cyan/2"])
    sim.take_control("cyan/2")
    sim.send_vel("cyan/2", 1.0, 0.0, 0.0)  # a good command first
    sim.run(seconds=0.5)
    pub = sim.bus.publisher(topics.robot_topic("cyan", 2, topics.VEL_CMD), msgs.VelCmd)
    for _ in range(3):
        pub.put(msgs.VelCmd(stamp=0.0, tick=0, vx=vx, vy=vy, w=w))
    sim.release_control("cyan/2")
    sim.take_control("cyan/2")  # the manual driver keeps re-sending the good command
    sim.send_vel("cyan/2", 1.0, 0.0, 0.0)
    sim.run(seconds=0.5)
    st = sim.model_states()["cyan/2"]
    assert all(math.isfinite(v) for v in (st.x, st.y, st.vx, st.vy, st.wz))
    assert math.hypot(st.vx, st.vy) == pytest.approx(1.0, abs=1e-6)  # the good command still applies
    bad = [e for e in sim.events if e["type"] == "bad_command"]
    assert len(bad) == 1 and bad[0]["team"] == "cyan" and bad[0]["robot"] == 2
    assert sim.simulator.refused[sim.simulator.index_of("cyan/2")] == 3


def test_refusals_are_reported_once_a_second_with_their_count(field_sim):
    sim = field_sim()
    pub = sim.bus.publisher(topics.robot_topic("magenta", 3, topics.VEL_CMD), msgs.VelCmd)
    for _ in range(450):  # a broken node flooding NaN for 2.25 s
        pub.put(msgs.VelCmd(stamp=0.0, tick=0, vx=math.nan, vy=0.0, w=0.0))
        sim.step()
    bad = [e for e in sim.events if e["type"] == "bad_command"]
    assert 2 <= len(bad) <= 4
    assert sum(e["value"] for e in bad) <= 450 and sim.simulator.refused[sim.simulator.index_of("magenta/3")] == 450


def test_bad_kick_requests_are_refused(field_sim):
    sim = field_sim()
    sim.take_control("cyan/2")
    for speed in (float("nan"), -1.0, 1e9):
        sim.send_action("cyan/2", dribble=True, kick=speed)
    assert sim.simulator.refused[sim.simulator.index_of("cyan/2")] >= 3
    sim.step(3)
    assert sim.simulator.mechanics["kick"] == 0


def test_a_strategy_that_raises_does_not_stop_the_run(tmp_path, monkeypatch):
    import simatch

    (tmp_path / "buggy_team.py").write_text(
        "from simatch.strategy import RobotStrategy\n"
        "class Buggy(RobotStrategy):\n"
        "    def decide(self, world):\n"
        "        raise ZeroDivisionError('oops')\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    with simatch.Simulation(
        "msl_5v5", overrides={"teams.cyan.strategy": "buggy_team:Buggy", "teams.magenta.strategy": "startpose"}
    ) as sim:
        sim.run(seconds=1.0)
        errors = [e for e in sim.events if e["type"] == "strategy_error"]
        assert {e["robot"] for e in errors} == {1, 2, 3, 4, 5}
        assert "ZeroDivisionError: oops" in errors[0]["detail"]
        assert sim.time == pytest.approx(1.0)


@pytest.mark.parametrize(
    "name, state, why",
    [
        ("magenta/1", {"vx": -1e4}, "faster than anything in the world moves"),
        ("cyan/2", {"x": 20.0}, "outside the world"),
        ("ball", {"y": -9.0}, "outside the world"),
        ("ball", {"z": 60.0}, "outside the world"),
        ("ball", {"wx": 5000.0}, "faster than anything"),
        ("cyan/2", {"x": False}, "not a finite value"),
    ],
)
def test_placements_outside_the_world_or_too_fast_are_refused(field_sim, name, state, why):
    """Found by the fuzzing campaign (docs/reliability.md): a robot set moving at 10 km/s went through the
    boards in one step and left the world."""
    sim = field_sim()
    before = sim.model_states()[name]
    with pytest.raises(ValueError, match=why):
        sim.set_model_state(name, **state)
    assert sim.model_states()[name] == before  # nothing changed


def test_wrenches_that_would_throw_a_body_out_of_the_world_are_refused(field_sim):
    sim = field_sim()
    with pytest.raises(ValueError, match="more than anything in the world moves"):
        sim.apply_wrench("cyan/3", force=(1e5, 0.0, 0.0), duration=3.0)  # went through the boards
    with pytest.raises(ValueError, match="more than anything in the world moves"):
        sim.apply_wrench("ball", force=(1e3, 0.0, 0.0), duration=3.0)  # flew 10 km
    sim.apply_wrench("ball", force=(4.0, 0.0, 0.0), duration=0.05)  # a push is fine
    sim.run(seconds=0.2)
    assert all(math.isfinite(v) for s in sim.model_states().values() for v in (s.x, s.y, s.vx, s.vy))
