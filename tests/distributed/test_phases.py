"""Real time spreads the processes over the physics steps of a control period (their phases): the rule both
sides compute, the clock that ticks a process at its phase, the perception taken at it, and real robot
processes answering at their own steps, bundled or topic by topic (and a hung one: late, then back)."""

from __future__ import annotations

import math
import os
import signal

import pytest

from simatch import msgs
from simatch.bus import InProcessBus, LockstepClock, Node, topics
from simatch.config.loader import load_scene
from simatch.distributed import protocol
from simatch.distributed.registry import ProcState
from simatch.distributed.server import Server
from simatch.simulation import Simulation

from .cluster import CHASER

#: cyan: three chasing robots (ids 1, 2, 3: phases 0, 1, 3 of 5 in real time); magenta: nobody to wait for
THREE = {
    "teams.cyan.strategy": CHASER,
    "teams.cyan.ids": [1, 2, 3],
    "teams.cyan.start": [[-6.0, 0.0, 0.0], [-2.0, 1.0, 0.0], [-2.0, -1.0, 0.0]],
    "teams.magenta.strategy": "none",
}


def test_the_phase_rule_spreads_a_teams_robot_processes_and_treats_both_teams_alike():
    spec = load_scene("msl_5v5").spec
    assert protocol.phases(spec, protocol.LOCKSTEP) == 1 and protocol.phases(spec, protocol.REALTIME) == 5
    for team in ("cyan", "magenta"):
        ids = spec.teams[team].robot_ids()
        assert [protocol.phase_of(spec, team, [r], protocol.LOCKSTEP) for r in ids] == [0] * 5
        assert [protocol.phase_of(spec, team, [r], protocol.REALTIME) for r in ids] == [0, 1, 2, 3, 4]
        assert protocol.phase_of(spec, team, ids, protocol.REALTIME) == 0  # a whole-team process
        assert protocol.phase_of(spec, team, ids[2:], protocol.REALTIME) == 2  # its first robot's
    herd = load_scene("encirclement_9v7").spec
    for team in herd.teams:
        ids = herd.teams[team].robot_ids()
        steps = protocol.phases(herd, protocol.REALTIME)
        got = [protocol.phase_of(herd, team, [r], protocol.REALTIME) for r in ids]
        assert got == sorted(got) and got[0] == 0 and max(got) < steps
        assert len(set(got)) == min(len(ids), steps)  # every step used that can be


class Counter(Node):
    name = "counter"

    def __init__(self, period: float):
        self.period = period
        self.steps: list[int] = []

    def tick(self, now: float) -> None:
        self.steps.append(self.ctx.step())


def test_a_clock_with_an_offset_ticks_its_nodes_at_their_phase():
    clock = LockstepClock(InProcessBus(), 0.005, seed=0, offset=3)
    node = clock.add(Counter(0.025))
    for _ in range(16):
        clock.step()
    assert node.steps == [3, 8, 13]


def test_a_robots_perception_is_taken_at_its_phase():
    with Simulation(load_scene("msl_5v5"), seed=0) as sim:
        stamps: dict[str, list[float]] = {"cyan/2": [], "magenta/3": []}
        for name, got in stamps.items():
            team, rid = name.split("/")
            sim.bus.subscribe(
                topics.robot_topic(team, rid, topics.OMNI_VISION),
                msgs.OmniVisionInfo,
                lambda msg, got=got: got.append(round(msg.stamp / sim.dt)),
            )
        sim.set_perception_phase("magenta/3", 3)
        sim.step(12)
        assert stamps == {"cyan/2": [0, 5, 10], "magenta/3": [3, 8]}
        with pytest.raises(ValueError, match="phase 5"):
            sim.set_perception_phase("cyan/2", 5)
        with pytest.raises(Exception, match="no robot named"):
            sim.set_perception_phase("cyan/9", 1)


@pytest.fixture
def server(procs):
    srv = Server(
        load_scene("msl_5v5", THREE),
        seed=1,
        listen=[procs.endpoint],
        run=procs.run,
        realtime=True,
        team_timeout=60,
        credentials_dir=procs.creds,
        say=lambda text: None,
    )
    try:
        yield srv
    finally:
        srv.finish(linger=0.5)
        srv.close()


@pytest.mark.slow
def test_real_time_robot_processes_answer_at_their_own_steps(procs, server):
    robots = {2: procs.robot("cyan/2"), 3: procs.plain("cyan/3")}  # cyan/3 topic by topic
    procs.robot("cyan/1")
    assert server.wait_for_teams(timeout=60) == {}
    assert sorted(p.phase for p in server.registry.procs.values()) == [0, 1, 3]
    server.sim.run(seconds=1.0)
    server.reset_stats()
    server.sim.run(seconds=1.0)
    st = server.stats()
    assert st["ticks"] == 40
    assert st["answers"] >= 3 * 40 - 6 and st["missed"] <= 3  # (a loaded machine may miss a few)
    assert 0.0 < st["latency_p50_ms"] <= st["latency_p99_ms"]
    # each step waits for that step's process only: one completion per answer in time
    assert len(server.gate.completions) == st["answers"] - st["late"]
    start = {1: (-6.0, 0.0), 2: (-2.0, 1.0), 3: (-2.0, -1.0)}
    states = server.sim.model_states()
    assert all(math.dist((states[f"cyan/{r}"].x, states[f"cyan/{r}"].y), xy) > 0.3 for r, xy in start.items())
    simulator = server.sim.simulator
    applied = [simulator.last_command_step[simulator.index_of(f"cyan/{r}")] % 5 for r in (1, 2, 3)]
    for got, phase in zip(applied, (0, 1, 3)):  # each robot's commands came at its step (or, late, the next)
        assert got in (phase, phase + 1)
    assert "step 3 of each control period" in procs.stderr(robots[3])

    # a process that hangs misses its ticks (late after four in a row), then answers again
    os.kill(robots[2].pid, signal.SIGSTOP)
    try:
        server.sim.run(seconds=0.3)
        late = [e for e in server.sim.events if e["type"] == "process_late"]
        assert len(late) == 1 and "cyan/2" in late[0]["detail"]
        hung = [p for p in server.registry.procs.values() if 2 in p.robots][0]
        assert hung.state is ProcState.LATE and hung.missed >= 4
    finally:
        os.kill(robots[2].pid, signal.SIGCONT)
    server.sim.run(seconds=0.5)
    kinds = [e["type"] for e in server.sim.events if e["type"] in ("process_late", "process_back")]
    assert kinds == ["process_late", "process_back"]  # back, once, and in step from then on
    assert hung.state is ProcState.ACTIVE and hung.streak == 0


@pytest.mark.slow
def test_a_real_time_process_that_falls_behind_for_good_stays_late_and_its_commands_still_apply(procs):
    """A robot whose every decision takes longer than a control period answers each tick after the next
    one opened: it is late once (not flapping between late and back), and its commands still move it."""
    spec = {
        **THREE,
        "teams.cyan.ids": [2],
        "teams.cyan.start": [[-2.0, 1.0, 0.0]],
        "teams.cyan.strategy": "tests.distributed.strategies:SlowChaser",
    }
    srv = Server(
        load_scene("msl_5v5", spec),
        seed=1,
        listen=[procs.endpoint],
        run=procs.run,
        realtime=True,
        team_timeout=60,
        credentials_dir=procs.creds,
        say=lambda text: None,
    )
    try:
        procs.robot("cyan/2")
        assert srv.wait_for_teams(timeout=60) == {}
        srv.sim.run(seconds=2.0)
        kinds = [e["type"] for e in srv.sim.events if e["type"] in ("process_late", "process_back")]
        assert kinds == ["process_late"]
        assert srv.stats()["missed"] >= 4
        state = srv.sim.model_states()["cyan/2"]
        assert math.dist((state.x, state.y), (-2.0, 1.0)) > 0.3  # its (late) commands were applied
    finally:
        srv.finish(linger=0.5)
        srv.close()


@pytest.mark.slow
def test_a_team_process_replaced_by_robot_processes_spreads_them_out(procs, server):
    """The whole team plays at step 0; once its process dies, robot processes take the robots over, each
    at its own step, with their perception taken there."""
    team = procs.team("cyan")
    assert server.wait_for_teams(timeout=60) == {}
    server.sim.run(seconds=0.5)
    simulator = server.sim.simulator
    index = {r: simulator.index_of(f"cyan/{r}") for r in (1, 2, 3)}
    assert {simulator.last_command_step[i] % 5 for i in index.values()} <= {0, 1}
    team.send_signal(signal.SIGKILL)
    team.wait(10)
    for rid in (1, 2, 3):
        procs.robot(f"cyan/{rid}")
    for _ in range(300):  # the dead process is noticed, the robots are taken over
        server.sim.run(seconds=0.1)
        joined = [p for p in server.registry.active() if p.kind == "robot"]
        if len(joined) == 3:
            break
    assert sorted(p.phase for p in joined) == [0, 1, 3]
    server.sim.run(seconds=1.0)
    for rid, phase in ((1, 0), (2, 1), (3, 3)):
        assert simulator.last_command_step[index[rid]] % 5 in (phase, phase + 1)
    stamps: dict[int, int] = {}
    for rid in (2, 3):
        server.bus.subscribe(
            topics.robot_topic("cyan", rid, topics.OMNI_VISION),
            msgs.OmniVisionInfo,
            lambda msg, rid=rid: stamps.__setitem__(rid, round(msg.stamp / server.sim.dt)),
        )
    server.sim.run(seconds=0.1)
    assert stamps[2] % 5 == 1 and stamps[3] % 5 == 3  # their perception is taken at their steps
