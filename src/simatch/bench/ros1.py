"""``simatch bench --only ros1``: ten ROS robot stacks through the bridge (docs/ros.md).

A roscore of its own (a free port), both teams played by the example ROS team (``roslaunch simatch_demo
team.launch`` twice: per robot a world model, a decision node and a low-level controller, plus each team's
strategy relay: 32 rospy processes), and ``msl_5v5`` embedded in this process with ``--ros1 cyan,magenta``:

* ``ros1_realtime_*``: the match paced at wall-clock speed: the real-time factor it holds, the steps that
  started late, and the command latency from a VelCmd published by a low-level controller (its monotonic
  clock, written by the node: ``SIMATCH_VELCMD_TRACE``) to the simulator taking it (the same clock, here),
  p50/p99/max over every VelCmd of every robot;
* ``ros1_lockstep_*``: the same match in lockstep: the real-time factor, and per control tick the bridge's
  wait from publishing the perception to the last robot's answer (the three nodes of each of the ten
  robots, one after another), p50/p99; and whether a second run gives the same state digest.

Every figure starts after a warm-up of a few simulated seconds (the kick-off), as the other benchmarks do.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import signal
import socket
import subprocess
import tempfile
import time
import xmlrpc.client
from argparse import Namespace
from pathlib import Path

import numpy as np

from .. import msgs
from ..config.loader import load_scene

SCENE = "msl_5v5"
WARM_UP = 3.0
TEAMS = {"cyan": "NuBot", "magenta": "rival"}


def _port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@contextlib.contextmanager
def _ros_master(folder: Path):
    """A roscore on a free port, ROS_MASTER_URI pointing at it for this process and its children."""
    from ..ros1.rosenv import RosUnavailable, environment

    if not shutil.which("roscore"):
        raise RosUnavailable("roscore is not installed: run scripts/install-system-deps.sh")
    port = _port()
    uri = f"http://127.0.0.1:{port}"
    env = environment(dict(os.environ, ROS_HOME=str(folder / "roshome"), ROS_IP="127.0.0.1"), master=uri)
    procs: list[subprocess.Popen] = []

    def start(*args: str, extra: dict | None = None) -> subprocess.Popen:
        p = subprocess.Popen(
            list(args),
            env={**env, **(extra or {})},
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            start_new_session=True,
        )
        procs.append(p)
        return p

    saved = os.environ.get("ROS_MASTER_URI")
    os.environ["ROS_MASTER_URI"] = uri
    try:
        start("roscore", "-p", str(port))
        deadline = time.monotonic() + 30
        while True:
            try:
                if xmlrpc.client.ServerProxy(uri).getPid("/bench")[0] == 1:
                    break
            except OSError:
                pass
            if time.monotonic() > deadline:
                raise RosUnavailable(f"roscore did not start at {uri}")
            time.sleep(0.2)
        yield start
    finally:
        for p in reversed(procs):
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGINT)
        for p in reversed(procs):
            try:
                p.wait(15)
            except subprocess.TimeoutExpired:
                with contextlib.suppress(ProcessLookupError):
                    os.killpg(p.pid, signal.SIGKILL)
                p.wait(10)
        if saved is None:
            os.environ.pop("ROS_MASTER_URI", None)
        else:
            os.environ["ROS_MASTER_URI"] = saved


def _match(realtime: bool, seconds: float) -> dict:
    """One bridged match of ``seconds`` after the warm-up; its figures."""
    from ..ros1.embedded import bridged
    from ..simulation import Simulation

    args = Namespace(ros_master=None, realtime=realtime, ros1_answer_timeout=2.0, ros1_wait=120.0)
    applied: dict[str, list] = {}
    with Simulation(load_scene(SCENE), seed=0) as sim, bridged(sim, args, ",".join(TEAMS)) as bridge:
        for link in bridge.links.values():
            r = link.robot
            got = applied.setdefault(r.ros, [])
            sim.bus.subscribe(
                f"{r.team}/{r.rid}/VelCmd",
                msgs.VelCmd,
                lambda m, got=got: got.append((time.monotonic(), m.vx, m.vy, m.w)),
            )
        sim.run(seconds=WARM_UP, realtime=realtime)
        cut = {robot: len(got) for robot, got in applied.items()}  # the figures count from here
        bridge.stats.waited.clear()
        t0 = time.perf_counter()
        sim.run(seconds=seconds, realtime=realtime)
        wall = time.perf_counter() - t0
        pacer = next((n for n in sim.clock.nodes if type(n).__name__ == "Pacer"), None)
        out = {"rtf": round(seconds / wall, 3), "digest": sim.state_digest(), "stats": bridge.stats}
        if pacer is not None:
            out["pacer"] = pacer.stats()
        out["applied"] = applied
        out["cut"] = cut
    return out


def _latencies(trace: Path, applied: dict[str, list], cut: dict[str, int]) -> tuple[list[float], int]:
    """Per robot, the k-th VelCmd the simulator took is the k-th its low-level controller published (one
    connection, in order, none lost: the bridge starts once every controller is connected); the values
    must agree. Latencies of those taken from ``cut[robot]`` on; and how many did not agree."""
    from ..ros1.convert import velcmd_in

    lat, unmatched = [], 0
    for robot, got in applied.items():
        path = trace / f"{robot}.velcmd"
        sent = []
        for line in path.read_text().splitlines() if path.exists() else ():
            t, vx, vy, w = (float(v) for v in line.split())
            vx, vy, w = msgs.f32s(vx, vy, w)  # as the wire carries them (float32)
            m = velcmd_in(Namespace(Vx=vx, Vy=vy, w=w), 0.0, 0)
            sent.append((t, m.vx, m.vy, m.w))
        for k in range(cut[robot], len(got)):
            if k < len(sent) and sent[k][1:] == got[k][1:] and sent[k][0] <= got[k][0]:
                lat.append(got[k][0] - sent[k][0])
            else:
                unmatched += 1
    return lat, unmatched


def _ms(values, q) -> float | None:
    return round(float(np.percentile(np.array(values) * 1e3, q)), 3) if len(values) else None


def _teams(start, trace: Path | None = None) -> list:
    """Both example teams (32 rospy processes), once every node is registered with the master."""
    import rosgraph

    extra = {"SIMATCH_VELCMD_TRACE": str(trace)} if trace is not None else None
    procs = [
        start("roslaunch", "simatch_demo", "team.launch", f"prefix:={prefix}", extra=extra) for prefix in TEAMS.values()
    ]
    master = rosgraph.Master("/bench")
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        _, subs, _ = master.getSystemState()
        listening = {t for t, nodes in subs if t.endswith("/nubotcontrol/actioncmd") and nodes}
        if len(listening) >= 10:
            break
        time.sleep(0.5)
    return procs


def _stop(procs) -> None:
    for p in procs:
        with contextlib.suppress(ProcessLookupError):
            os.killpg(p.pid, signal.SIGINT)
    for p in procs:
        try:
            p.wait(20)
        except subprocess.TimeoutExpired:
            with contextlib.suppress(ProcessLookupError):
                os.killpg(p.pid, signal.SIGKILL)
            p.wait(10)


def run(seconds: float | None = None) -> dict:
    from ..ros1.rosenv import use_rospy

    seconds = seconds or 30.0
    use_rospy()
    folder = Path(tempfile.mkdtemp(prefix="simatch-bench-ros1-"))
    trace = folder / "trace"
    trace.mkdir()
    out: dict = {}
    try:
        with _ros_master(folder) as start:
            teams = _teams(start, trace)
            rt = _match(True, seconds)
            lat, unmatched = _latencies(trace, rt["applied"], rt["cut"])
            _stop(teams)
            pacer = rt.get("pacer", {})
            out.update(
                {
                    "ros1_robot_stacks": 10,
                    "ros1_ros_processes": 32,
                    "ros1_realtime_rtf": rt["rtf"],
                    "ros1_realtime_late_steps": pacer.get("late_steps"),
                    "ros1_realtime_max_lag_ms": pacer.get("max_lag_ms"),
                    "ros1_realtime_latency_p50_ms": _ms(lat, 50),
                    "ros1_realtime_latency_p99_ms": _ms(lat, 99),
                    "ros1_realtime_latency_max_ms": _ms(lat, 100),
                    "ros1_realtime_commands": len(lat),
                    "ros1_realtime_unmatched": unmatched,
                    "ros1_realtime_late_robots": rt["stats"].late,
                }
            )
            digests = []
            for _ in range(2):  # lockstep, twice with fresh teams: the same match
                teams = _teams(start)
                ls = _match(False, seconds)
                _stop(teams)
                digests.append(ls["digest"])
            waited = ls["stats"].waited
            out.update(
                {
                    "ros1_lockstep_rtf": ls["rtf"],
                    "ros1_lockstep_answers_p50_ms": _ms(waited, 50),
                    "ros1_lockstep_answers_p99_ms": _ms(waited, 99),
                    "ros1_lockstep_late_robots": ls["stats"].late,
                    "ros1_lockstep_digest_equal": digests[0] == digests[1],
                    "ros1_load": round(os.getloadavg()[0], 2),
                }
            )
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    return out
