"""Faults in a distributed run: a robot process that dies (its robot stops by the watchdog within 0.1 s of
simulated time, the match goes on, the event is logged, a restarted process rejoins), one that hangs (not
waited for until it answers again), and a team that never connects (the server says so and plays without it);
and how the server times the answers it waits for."""

from __future__ import annotations

import math
import os
import signal

import pytest

from simatch.config.loader import load_scene
from simatch.distributed.registry import ProcState
from simatch.distributed.server import Server

from .cluster import CHASER, chaser_overrides

#: cyan is one chasing robot (cyan/2); magenta has no strategy (nobody to wait for)
ONE_ROBOT = {
    "teams.cyan.strategy": CHASER,
    "teams.cyan.ids": [2],
    "teams.cyan.start": [[-2.0, 1.0, 0.0]],
    "teams.magenta.strategy": "none",
}


@pytest.fixture
def server(procs):
    srv = Server(
        load_scene("msl_5v5", ONE_ROBOT),
        seed=1,
        listen=[procs.endpoint],
        run=procs.run,
        deadline=1.0,
        team_timeout=60,
        credentials_dir=procs.creds,
        say=lambda text: None,
    )
    try:
        yield srv
    finally:
        srv.finish(linger=0.5)
        srv.close()


def events(srv, kind: str) -> list[dict]:
    return [e for e in srv.sim.events if e["type"] == kind]


def speed(srv, name: str) -> float:
    s = srv.sim.model_states()[name]
    return math.hypot(s.vx, s.vy)


def join(srv, procs) -> None:
    assert srv.wait_for_teams(timeout=60) == {}, "the robot process did not join"


@pytest.mark.slow
def test_a_dead_robot_process_stops_its_robot_and_a_restarted_one_rejoins(procs, server):
    sim = server.sim
    i = sim.simulator.index_of("cyan/2")
    first = procs.robot("cyan/2")
    join(server, procs)
    sim.run(seconds=1.0)
    assert speed(server, "cyan/2") > 0.3  # it chases the ball
    first.send_signal(signal.SIGKILL)
    first.wait(10)
    t_kill = sim.time
    sim.run(seconds=0.5)  # the match goes on without it
    assert sim.time == pytest.approx(t_kill + 0.5)
    lost = events(server, "process_lost") + events(server, "process_late")
    assert lost and lost[0]["team"] == "cyan"
    last_command = sim.simulator.last_command_step[i] * sim.dt
    stop = [e for e in events(server, "watchdog_stop") if e["t"] > last_command]
    assert len(stop) == 1 and stop[0]["team"] == "cyan" and stop[0]["robot"] == 2
    assert stop[0]["t"] <= last_command + 0.1 + 1e-9  # stopped within 0.1 s of simulated time
    assert not sim.simulator.drive.cmd[i].any() and not sim.simulator.ball.dribble_on[i]  # zero velocity, dribbler off
    sim.run(seconds=0.5)
    assert speed(server, "cyan/2") < 0.05  # and it comes to rest (wheels slow at 5 m/s^2)

    procs.robot("cyan/2")  # restarted: a new process takes the robot back
    join(server, procs)
    sim.run(seconds=1.0)
    assert len(events(server, "process_joined")) == 2
    assert events(server, "watchdog_resume")
    assert not sim.simulator.watchdog_tripped[i]
    assert sim.simulator.last_command_step[i] * sim.dt >= sim.time - 0.03  # commanded again, every tick


@pytest.mark.slow
def test_the_server_times_each_answer_and_its_parts(procs, server):
    """Each answer's round trip is the sum of its parts, read from the process's clock (same machine)."""
    procs.robot("cyan/2")
    join(server, procs)
    server.sim.run(seconds=0.5)
    server.reset_stats()
    server.sim.run(seconds=1.0)
    gate, st = server.gate, server.stats()
    assert st["ticks"] == 40 and st["answers"] == 40 - st["missed"] >= 35
    assert len(gate.feeds) == len(gate.thinking) == len(gate.transits) == len(gate.latencies)
    for whole, parts in zip(gate.latencies, zip(gate.feeds, gate.thinking, gate.transits)):
        assert min(parts) >= 0.0 and sum(parts) == pytest.approx(whole, abs=1e-6)
    assert len(gate.completions) == 40 - st["missed"]  # one process: the tick ends with its answer
    assert sorted(gate.completions) == sorted(gate.latencies)
    for name in ("latency", "tick", "feed", "processing", "transit"):
        assert 0.0 <= st[f"{name}_p50_ms"] <= st[f"{name}_p99_ms"] < 1000.0


@pytest.mark.slow
def test_a_hung_process_is_not_waited_for_until_it_answers_again(procs, server):
    sim = server.sim
    robot = procs.robot("cyan/2")
    join(server, procs)
    sim.run(seconds=0.2)
    for _ in range(50):  # answering in time (a loaded machine may delay it)
        if all(p.state is ProcState.ACTIVE for p in server.registry.procs.values()):
            break
        sim.run(seconds=0.1)
    os.kill(robot.pid, signal.SIGSTOP)
    try:
        missed = server.gate.missed
        sim.run(seconds=0.3)  # one deadline (1 s wall), then no more waiting
        late = events(server, "process_late")
        assert len(late) >= 1 and server.gate.missed == missed + 1
        assert events(server, "watchdog_stop")
    finally:
        os.kill(robot.pid, signal.SIGCONT)
    sim.run(seconds=1.0)
    assert events(server, "process_back")
    assert not sim.simulator.watchdog_tripped[sim.simulator.index_of("cyan/2")]


@pytest.mark.slow
def test_a_team_that_never_connects_is_reported_and_the_match_is_played_without_it(procs):
    server = procs.server("msl_5v5", *chaser_overrides("cyan"), "--duration", "1", "--team-timeout", "2")
    team = procs.team("cyan")
    out = procs.result(server)
    assert procs.wait(team) == 0
    absent = [e for e in out["events"] if e["type"] == "team_absent"]
    assert [e["team"] for e in absent] == ["magenta"]
    assert "team magenta did not connect" in procs.stderr(server)
    assert out["sim_seconds"] == 1.0
