"""ROS 2 benchmark (``simatch bench --only ros2``; needs the ``ros2`` extra).

* ``ros2_latency_*``: the command latency from ``cmd_vel`` published by an rclpy process to the server's
  process receiving it as a VelCmd (as the distributed benchmarks measure theirs), with ten robots driven over
  ROS 2 in real time: ``msl_5v5 --realtime`` served in this process, both teams played through a bridge each
  (``simatch ros2 --team``), and a probe (`simatch.ros2.probe`, plain rclpy) publishing a new speed for every
  robot at 40 Hz and noting when (the monotonic clock is one for every process of the machine). p50, p99 and
  max [ms]. ``ros2_applied_latency_*``: to the simulator applying it instead (a subscription beside the
  simulator's, delivered in the gate's order before the physics step that applies it: the above and the
  wait for the next physics step, up to one step of 5 ms in real time); ``ros2_latency_applied``: how many
  of the published commands were applied (a later one replaces one not applied yet).
* ``ros2_observer_*``: the real-time factor of an embedded ``msl_5v5`` (as shipped) without and with the
  observer bridge attached (``simatch run --ros2``), and what it costs (``ros2_observer_cost_pct``; goal
  < 10 %), alternated in pairs, after a warm-up past the kick-off; and, since on a shared machine the wall
  time moves with everybody's load, the CPU time of the run's process per simulated second without and with
  (``ros2_observer_cpu_cost_pct``).

The bridges, the probe and the run share the machine's cores: the figures say so with ``ros2_load``.
"""

from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from .. import msgs
from ..bus import topics
from ..config.loader import load_scene
from .distributed import WARM_UP, _port

SCENE = "msl_5v5"
LATENCY_SECONDS = 20.0  # wall seconds of probing
OBSERVER_SECONDS = 60.0  # simulated seconds of each embedded run


_DOMAIN_LOCK = None


def _ros_env() -> None:
    """The environment's ROS_DOMAIN_ID if set, else a domain nobody else on this machine uses, on this machine."""
    global _DOMAIN_LOCK
    if "ROS_DOMAIN_ID" not in os.environ and _DOMAIN_LOCK is None:
        from ..ros2 import domain

        _, _DOMAIN_LOCK = domain.claim()
    os.environ.setdefault("ROS_AUTOMATIC_DISCOVERY_RANGE", "LOCALHOST")


def run(seconds: float | None = None) -> dict:
    _ros_env()
    out = {"ros2_load": round(os.getloadavg()[0], 2), "ros2_domain_id": int(os.environ["ROS_DOMAIN_ID"])}
    out.update(observer(seconds or OBSERVER_SECONDS))
    out.update(latency(min(seconds or LATENCY_SECONDS, LATENCY_SECONDS)))
    return out


def _embedded(seconds: float, with_bridge: bool) -> tuple[float, float]:
    """(real-time factor, CPU seconds of this process per simulated second) of ``seconds`` of an embedded run."""
    from ..ros2.extension import attached
    from ..simulation import Simulation

    with Simulation(SCENE, seed=0) as sim:
        stack = contextlib.ExitStack()
        with stack:
            if with_bridge:
                stack.enter_context(attached(sim, say=lambda text: None))
            sim.run(seconds=WARM_UP)
            t0, c0 = time.perf_counter(), time.process_time()
            sim.run(seconds=seconds)
            return seconds / (time.perf_counter() - t0), (time.process_time() - c0) / seconds


def observer(seconds: float, pairs: int = 2) -> dict:
    """Embedded runs without and with the observer bridge, alternated (the machine's load moves during a
    benchmark): the real-time factors (medians) and the CPU time of the run's process per simulated second
    (what the bridge costs the simulation whatever else the machine runs; the bridge's own process not
    counted: it has a core's share of its own)."""
    runs = {False: [], True: []}
    for _ in range(pairs):
        for with_bridge in (False, True):
            runs[with_bridge].append(_embedded(seconds, with_bridge))
    rtf = {k: float(np.median([r for r, _ in v])) for k, v in runs.items()}
    cpu = {k: float(np.median([c for _, c in v])) for k, v in runs.items()}
    return {
        "ros2_observer_rtf_without": round(rtf[False], 2),
        "ros2_observer_rtf_with": round(rtf[True], 2),
        "ros2_observer_cost_pct": round(100.0 * (1.0 - rtf[True] / rtf[False]), 1),
        "ros2_observer_cpu_ms_per_sim_s_without": round(1e3 * cpu[False], 1),
        "ros2_observer_cpu_ms_per_sim_s_with": round(1e3 * cpu[True], 1),
        "ros2_observer_cpu_cost_pct": round(100.0 * (cpu[True] / cpu[False] - 1.0), 1),
    }


def latency(seconds: float) -> dict:
    """The ``ros2_latency_*`` figures: ``seconds`` of probing a real-time server through both teams' bridges."""
    from ..distributed.server import Server

    overrides = {"teams.cyan.strategy": "external", "teams.magenta.strategy": "external", "judge.kind": "none"}
    folder = tempfile.TemporaryDirectory(prefix="simatch-bench-ros2-")
    endpoint = f"tcp/127.0.0.1:{_port()}"
    run_name = f"benchros2{os.getpid()}"
    server = Server(
        load_scene(SCENE, overrides),
        listen=[endpoint],
        run=run_name,
        realtime=True,
        team_timeout=120,
        credentials_dir=folder.name,
        say=lambda text: None,
    )
    sim = server.sim
    names = sim.simulator.robot_names
    applied = _note_applied(server, names)
    arrived = _note_arrived(server, names)
    procs: list[subprocess.Popen] = []
    probe_out = os.path.join(folder.name, "sent.json")
    try:
        _start_bridges(procs, endpoint, run_name, folder.name)
        probe = subprocess.Popen(
            [sys.executable, "-m", "simatch.ros2.probe", probe_out, str(seconds), *names],
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        procs.append(probe)
        server.wait_for_teams(timeout=120)
        stats_at = None
        while probe.poll() is None:
            sim.run(seconds=0.5, until_done=False)
            if stats_at is None and sim.time > WARM_UP:
                server.reset_stats()
                stats_at = sim.time
        sim.run(seconds=0.5, until_done=False)  # the last commands arrive
        stats = server.stats()
    finally:
        server.finish()
        _stop(procs)
        server.close()
    with open(probe_out) as f:
        sent = json.load(f)
    folder.cleanup()
    ms = np.array(_latencies(sent, arrived, names)) * 1e3
    applied_ms = np.array(_latencies(sent, applied, names)) * 1e3
    return {
        "ros2_latency_robots": len(names),
        "ros2_latency_published": len(sent),
        "ros2_latency_applied": int(applied_ms.size),
        "ros2_latency_p50_ms": round(float(np.percentile(ms, 50)), 2) if ms.size else None,
        "ros2_latency_p99_ms": round(float(np.percentile(ms, 99)), 2) if ms.size else None,
        "ros2_latency_max_ms": round(float(ms.max()), 2) if ms.size else None,
        "ros2_applied_latency_p50_ms": round(float(np.percentile(applied_ms, 50)), 2) if applied_ms.size else None,
        "ros2_applied_latency_p99_ms": round(float(np.percentile(applied_ms, 99)), 2) if applied_ms.size else None,
        "ros2_realtime_missed": stats.get("missed"),
        "ros2_server_latency_p50_ms": stats.get("latency_p50_ms"),
    }


def _note_arrived(server, names: list[str]) -> list[tuple[float, int, float]]:
    """(when, robot, vx) of every velocity command as it reaches the server's process: the time Zenoh's
    receiving thread took it in (the definition of the distributed benchmarks' command latency)."""
    arrived: list[tuple[float, int, float]] = []

    def note(i: int):
        def on_sample(topic: str, payload: bytes, attachment, arrival: float) -> None:
            arrived.append((arrival, i, float(msgs.decode(msgs.VelCmd, payload).vx)))

        return on_sample

    for i, name in enumerate(names):
        team, rid = topics.split_robot_name(name)
        topic = topics.robot_topic(team, rid, topics.VEL_CMD)
        server.bus.subscribe_raw(topic, note(i), verify=False, wakes=lambda topic, payload: False)
    return arrived


def _note_applied(server, names: list[str]) -> list[tuple[float, int, float]]:
    """(when, robot, vx) of every velocity command as the simulator gets it: noted by a subscription of the
    server's bus, delivered in the gate's order just before the physics step that applies it."""
    applied: list[tuple[float, int, float]] = []
    for i, name in enumerate(names):
        team, rid = topics.split_robot_name(name)
        server.bus.subscribe(
            topics.robot_topic(team, rid, topics.VEL_CMD),
            msgs.VelCmd,
            lambda m, i=i: applied.append((time.monotonic(), i, float(m.vx))),
        )
    return applied


def _start_bridges(procs: list, endpoint: str, run_name: str, keys: str) -> None:
    """A ROS 2 bridge process per team (the second without a clock of its own), added to ``procs``."""
    for k, team in enumerate(("cyan", "magenta")):
        procs.append(
            subprocess.Popen(
                [sys.executable, "-m", "simatch", "ros2", "--team", team, "--connect", endpoint, "--run", run_name]
                + ["--key", os.path.join(keys, f"{team}.key"), "--wait", "120"]
                + (["--no-clock"] if k else []),
                stdout=subprocess.DEVNULL,
                stderr=subprocess.DEVNULL,
            )
        )


def _stop(procs: list) -> None:
    for p in procs:
        if p.poll() is None:
            p.terminate()
    for p in procs:
        try:
            p.wait(15)
        except subprocess.TimeoutExpired:
            p.kill()


def _latencies(sent: list, applied: list[tuple[float, int, float]], names: list[str]) -> list[float]:
    """Seconds from each published command to its first delivery to the simulator (the probe's sequence
    number is in the speed it sent: 0.5 m/s + sequence x 1e-4); commands never applied are left out."""
    first = {}
    for t, i, vx in applied:
        first.setdefault((names[i], round((vx - 0.5) / 1e-4)), t)
    return [first[(name, seq)] - t for name, seq, t in sent if (name, seq) in first and first[(name, seq)] >= t]
