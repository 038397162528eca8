"""Distributed benchmarks (``simatch bench``): the server runs in this process, teams and robots in their own
processes, over Zenoh on loopback.

* ``distributed_rtt``: the command round trip between the server and one robot process (lockstep): from
  the server opening a tick (perception and game command sent) to the robot's commands and answer being
  back, p50/p99; and the transit of the commands alone (answer sent -> received). The load is the plumbing
  strategy (``startpose``) on one robot thrown across the field every 4 s: the figure is the bus's, not a
  strategy's.
* ``distributed_lockstep``: the real-time factor of ``msl_5v5`` as shipped (both teams' default strategy,
  the automatic referee) in lockstep with two team processes, against the same run embedded (same scene
  and seed: the digests must be equal), with the CPU time per control tick of the embedded run, of the
  server's simulation thread, of its other (Zenoh's) threads and of the busier team process, and their ratio
  (``cpu_ratio``: all three processes against the embedded run): figures a busy machine does not distort.
* ``distributed_realtime``: the same match ``--realtime`` with one process per robot (11 processes): the
  real-time factor it holds and the command latency (tick opened -> commands back), p50/p99/max over
  every answer (``late``: how many came after the server stopped waiting, ``missed``: ticks not answered
  before the next), and its parts (see `Server.stats`): until the tick reached the robot process, until
  its answer was ready, and the answer's transit; ``tick``: until the last answer of a step's processes
  arrived (in real time the robot processes are spread over the physics steps of a control period, two
  at a time: see `simatch.distributed.protocol`).
* ``distributed_realtime_bus``: the same eleven processes in real time with the plumbing strategy
  (``startpose``) for every robot, thrown across the field every 4 s: what the bus and the processes cost
  without the shipped strategy's decisions (the difference to ``distributed_realtime`` is theirs).

Every figure starts after a warm-up of a few simulated seconds, past the kick-off (processes start, the
default team's compiled kernels load), as ``match_rtf`` does. The lockstep match runs a simulated minute by
default: its real-time factor changes with the phase of play (set pieces cost the strategy more), and a
shorter run is over in two seconds of wall time, too short for a steady figure on a shared machine.
"""

from __future__ import annotations

import contextlib
import math
import os
import socket
import subprocess
import sys
import tempfile
import threading
import time

import numpy as np

from ..config.loader import load_scene
from .distributed_cpu import Sample, per_tick_ms

SCENE = "msl_5v5"
#: the round trip's load: one robot driving back to its start pose (the bus's figure, not a strategy's)
RTT_OVERRIDES = {
    "teams.cyan.strategy": "startpose",
    "teams.magenta.strategy": "none",
    "teams.cyan.ids": [2],
    "teams.cyan.start": [[-2.0, 1.0, 0.0]],
    "perception.position_noise": 0.02,
}
#: the eleven processes' load without the shipped strategy: every robot drives back to its start pose
BUS_OVERRIDES = {
    "teams.cyan.strategy": "startpose",
    "teams.magenta.strategy": "startpose",
    "perception.position_noise": 0.02,
}
SCATTER_EVERY = 4.0
WARM_UP = 3.0  # simulated seconds before the figures start: past the kick-off at 2 s


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _scatter(sim, k: int) -> None:
    """Throw every robot somewhere else (deterministic), so that they all drive back."""
    rng = np.random.default_rng(k)
    for name in sim.simulator.robot_names:
        sim.set_model_state(
            name,
            x=float(rng.uniform(-9, 9)),
            y=float(rng.uniform(-6, 6)),
            yaw=float(rng.uniform(-math.pi, math.pi)),
            vx=0.0,
            vy=0.0,
            wz=0.0,
        )


def _play(sim, seconds: float) -> float:
    """Start the coaches and run ``seconds`` more, scattering the robots every few seconds; returns wall
    seconds."""
    for coach in sim.coaches.values():
        coach.start_play()
    wall = 0.0
    k = 0
    end = sim.time + seconds
    while sim.time < end - 1e-9:
        _scatter(sim, k)
        t0 = time.perf_counter()
        sim.run(seconds=min(SCATTER_EVERY, end - sim.time))
        wall += time.perf_counter() - t0
        k += 1
    return wall


@contextlib.contextmanager
def _server(realtime: bool = False, overrides: dict | None = None):
    from ..distributed.server import Server

    folder = tempfile.TemporaryDirectory(prefix="simatch-bench-")
    endpoint = f"tcp/127.0.0.1:{_port()}"
    run = f"bench{os.getpid()}"
    server = Server(
        load_scene(SCENE, overrides or {}),
        seed=0,
        listen=[endpoint],
        run=run,
        realtime=realtime,
        team_timeout=120,
        credentials_dir=folder.name,
        say=lambda text: None,
    )
    procs: list[subprocess.Popen] = []

    def launch(kind: str, who: str) -> subprocess.Popen:
        team = who.split("/")[0]
        procs.append(
            subprocess.Popen(
                [
                    sys.executable,
                    "-m",
                    "simatch",
                    kind,
                    who,
                    "--connect",
                    endpoint,
                    "--run",
                    run,
                    "--key",
                    os.path.join(folder.name, f"{team}.key"),
                ],
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )
        return procs[-1]

    try:
        yield server, launch
    finally:
        server.finish(linger=2.0)
        server.close()
        for p in procs:
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(10)
        folder.cleanup()


def rtt(seconds: float | None = None) -> dict:
    seconds = seconds or 20.0
    with _server(overrides=RTT_OVERRIDES) as (server, launch):
        launch("robot", "cyan/2")
        server.wait_for_teams()
        _play(server.sim, seconds)
        st = server.stats()
    return {
        "distributed_rtt_p50_ms": st["latency_p50_ms"],
        "distributed_rtt_p99_ms": st["latency_p99_ms"],
        **_parts("distributed_rtt", st, ("feed", "processing", "transit")),
        "distributed_rtt_samples": st["answers"],
    }


def _parts(prefix: str, st: dict, names) -> dict:
    """The p50/p99 of parts of the round trip (`Server.stats`), under ``prefix``."""
    return {f"{prefix}_{name}_{q}_ms": st[f"{name}_{q}_ms"] for name in names for q in ("p50", "p99")}


def _match(sim, seconds: float, server=None, play=None, cpu: dict | None = None) -> float:
    """Run the warm-up, then ``seconds`` more of the match (or of ``play(sim, seconds)``); returns the wall
    seconds of the latter. ``cpu``: process name -> pid, replaced by the CPU seconds each of their threads
    used meanwhile (`distributed_cpu`)."""
    sim.run(seconds=WARM_UP, until_done=False)
    if server is not None:
        server.reset_stats()
    if play is not None:
        return play(sim, seconds)
    before = Sample.take(cpu) if cpu is not None else None
    t0 = time.perf_counter()
    sim.run(seconds=seconds, until_done=False)
    wall = time.perf_counter() - t0
    if before is not None:
        cpu.clear()
        cpu.update(Sample.take(before.pids).minus(before))
    return wall


def lockstep(seconds: float | None = None) -> dict:
    from ..simulation import Simulation

    seconds = seconds or 60.0
    me, main = os.getpid(), threading.get_native_id()
    with Simulation(load_scene(SCENE), seed=0) as sim:
        embedded_cpu = {"embedded": me}
        embedded_wall = _match(sim, seconds, cpu=embedded_cpu)
        embedded_digest = sim.state_digest()
    with _server() as (server, launch):
        cpu = {"server": me, "cyan": launch("team", "cyan").pid, "magenta": launch("team", "magenta").pid}
        server.wait_for_teams()
        wall = _match(server.sim, seconds, server, cpu=cpu)
        digest = server.sim.state_digest()
        st = server.stats()
    rtf, emb = seconds / wall, seconds / embedded_wall
    ticks = round(seconds / load_scene(SCENE).spec.control.period)
    teams = [per_tick_ms(cpu[team], ticks) for team in ("cyan", "magenta")]
    return {
        "distributed_lockstep_rtf": round(rtf, 2),
        "distributed_lockstep_embedded_rtf": round(emb, 2),
        "distributed_lockstep_ratio": round(rtf / emb, 3),
        "distributed_lockstep_digest_equal": digest == embedded_digest,
        **_parts("distributed_lockstep", st, ("latency", "tick", "feed", "processing", "transit")),
        "distributed_lockstep_missed": st["missed"],
        # CPU time per control tick (what the wall clock hides on a busy machine): the embedded run's thread,
        # the server's simulation thread, its other threads (Zenoh's), each team process (the slower one)
        "distributed_lockstep_embedded_cpu_ms_per_tick": per_tick_ms(embedded_cpu["embedded"], ticks, only=main),
        "distributed_lockstep_server_main_cpu_ms_per_tick": per_tick_ms(cpu["server"], ticks, only=main),
        "distributed_lockstep_server_zenoh_cpu_ms_per_tick": per_tick_ms(cpu["server"], ticks, but=main),
        "distributed_lockstep_team_cpu_ms_per_tick": max(teams),
        "distributed_lockstep_cpu_ratio": round(
            (per_tick_ms(cpu["server"], ticks) + sum(teams)) / per_tick_ms(embedded_cpu["embedded"], ticks, only=main),
            3,
        ),
        "distributed_lockstep_load": round(os.getloadavg()[0], 2),
    }


def realtime(seconds: float | None = None) -> dict:
    return _realtime("distributed_realtime", seconds or 30.0)


def realtime_bus(seconds: float | None = None) -> dict:
    return _realtime("distributed_realtime_bus", seconds or 30.0, BUS_OVERRIDES)


def _realtime(prefix: str, seconds: float, overrides: dict | None = None) -> dict:
    """One process per robot in real time: the shipped match, or (``overrides``) robots thrown about."""
    with _server(realtime=True, overrides=overrides) as (server, launch):
        for team in ("cyan", "magenta"):
            for rid in range(1, 6):
                launch("robot", f"{team}/{rid}")
        server.wait_for_teams()
        wall = _match(server.sim, seconds, server, play=None if overrides is None else _play)
        st = server.stats()
    return {
        f"{prefix}_processes": 1 + st["processes"],
        f"{prefix}_rtf": round(seconds / wall, 4),
        **_parts(prefix, st, ("latency", "tick", "feed", "processing", "transit")),
        f"{prefix}_latency_max_ms": st["latency_max_ms"],
        f"{prefix}_answers": st["answers"],
        f"{prefix}_late": st["late"],
        f"{prefix}_missed": st["missed"],
        f"{prefix}_late_steps": st["realtime_late_steps"],
        f"{prefix}_max_lag_ms": st["realtime_max_lag_ms"],
        f"{prefix}_load": round(os.getloadavg()[0], 2),
    }
