"""Tournament throughput (``simatch bench --only tournament``): matches per hour with one Ray worker and with
every core, and what Ray costs against the same matches in a plain loop.

The same four matches (nubot against simple, seeds 1 and 2, both colours; ``--seconds`` of play each,
default 600: ten-minute matches of two halves with the 10 s break) are played three times, each time in a
fresh process (a session of its own): one after another in a plain loop (`PlainLoop`), on a local Ray
instance with one worker, and on one with a worker per core. Each time counts from the first match handed
out to the last result back; starting Ray itself is reported apart (``tournament_ray_start_s``), as a
tournament pays it once whatever its length.

CPU time counts every process of the session, each from its start, so that both sides pay their own
start-up: the plain loop's process with its imports and the loading of the compiled kernels; on Ray the
driver (its imports too), every worker (Python, Ray, simatch and the kernels once per worker) and Ray's own
processes (GCS, raylet, agents, log monitor, autoscaler monitor, API server), less what the driver and Ray's
own processes spent starting the instance (``tournament_ray_start_cpu_s``). ``tournament_ray1_cpu_by_process``
says where Ray's CPU went, per kind of process. On a machine shared with other work the wall-clock figures
move with the load (reported before and after, with the hypervisor's steal); the CPU time moves much less,
so ``tournament_ray_cpu_overhead_pct`` is the fairer figure there.
"""

from __future__ import annotations

import collections
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from .host import cpu_times, steal_pct

MATCHES_SEEDS = (1, 2)
_TICK = os.sysconf("SC_CLK_TCK")
AGENTS = ("ray::DashboardAgent", "ray::RuntimeEnvAgent")


def _kind(cmdline: list[str]) -> str:
    """What a process of the run is: "worker", "driver" (this process), or the name of Ray's process."""
    first = cmdline[0] if cmdline else "?"
    if first.startswith("ray::"):
        return "agents" if first in AGENTS else "worker"
    if "python" in Path(first).name:
        scripts = [Path(a).stem for a in cmdline[1:] if a.endswith(".py")]
        name = scripts[0] if scripts else "python"
        return "worker" if name == "default_worker" else name  # a worker not yet named ray::...
    return Path(first).name


def session_processes(sid: int) -> dict[int, tuple[str, float]]:
    """pid -> (kind, CPU seconds) of the processes of session ``sid``, each with the children it reaped."""
    out = {}
    me = os.getpid()
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
            if int(fields[3]) != sid:
                continue
            with open(f"/proc/{entry.name}/cmdline", "rb") as f:
                cmdline = f.read().decode(errors="replace").split("\0")
        except OSError:
            continue
        pid = int(entry.name)
        kind = "driver" if pid == me else _kind(cmdline)
        out[pid] = (kind, sum(int(v) for v in fields[11:15]) / _TICK)  # utime stime cutime cstime
    return out


def _play(mode: str, workers: int, half: float) -> dict:
    """One measurement, in this (fresh) process: wall and CPU time of the matches, Ray's start, digests."""
    from ..tournament import PlainLoop, RayPool, Tournament, parse_entries

    sid = os.getsid(0)
    with tempfile.TemporaryDirectory(prefix="simatch-bench-tournament-") as tmp:
        t = Tournament(
            parse_entries(["nubot,simple"]),
            seeds=MATCHES_SEEDS,
            out=tmp,
            overrides={"match.half_duration": half},
        )
        before_start = session_processes(sid)
        t0 = time.perf_counter()
        pool = PlainLoop() if mode == "plain" else RayPool(workers=workers)
        started = time.perf_counter() - t0
        at_start = session_processes(sid)
        try:
            t1 = time.perf_counter()
            rows = [outcome["row"] for _, outcome in pool.map(t.job(m) for m in t.format.matches)]
            wall = time.perf_counter() - t1
            at_end = session_processes(sid)
        finally:
            pool.close()
    bad = [r for r in rows if r["status"] != "ok"]
    if bad:
        raise RuntimeError(f"a benchmark match failed: {bad[0]['error']}")
    # starting Ray: what the driver and Ray's own processes used until the pool was ready; not the workers'
    # start-up (every worker pays it again, so it counts), nor the driver's imports before (the plain loop's
    # process pays them too)
    by_kind: dict[str, float] = collections.defaultdict(float)
    start_cpu = -sum(c for _, c in before_start.values())
    for pid, (kind, cpu) in at_end.items():
        base = 0.0 if kind == "worker" else at_start.get(pid, (kind, 0.0))[1]
        by_kind[kind] += cpu - base
        start_cpu += base
    by_kind["driver"] += sum(c for _, c in before_start.values())
    workers_seen = sum(1 for k, _ in at_end.values() if k == "worker")
    return {
        "wall": wall,
        "cpu": sum(by_kind.values()),
        "by_kind": {k: round(v, 2) for k, v in sorted(by_kind.items())},
        "start": started,
        "start_cpu": start_cpu,
        "workers_seen": workers_seen,
        "digests": {r["match_id"]: r["state_digest"] for r in rows},
        "sim": sum(r["sim_seconds"] for r in rows),
    }


def _fresh(mode: str, workers: int, half: float) -> dict:
    cmd = [sys.executable, "-m", "simatch.bench.tournament", mode, str(workers), repr(half)]
    out = subprocess.run(cmd, capture_output=True, text=True, start_new_session=True)
    if out.returncode != 0:
        raise RuntimeError(f"{' '.join(cmd)} failed:\n{out.stderr[-2000:]}")
    return json.loads(out.stdout.strip().splitlines()[-1])


def run(seconds: float | None = None) -> dict:
    half = (seconds or 600.0) / 2.0
    cores = os.cpu_count() or 1
    load = os.getloadavg()[0]
    host = cpu_times()
    plain = _fresh("plain", 1, half)
    one = _fresh("ray", 1, half)
    every = _fresh("ray", cores, half)
    n = len(plain["digests"])

    def per_hour(m: dict) -> float:
        return round(n / m["wall"] * 3600.0, 1)

    return {
        "tournament_matches": n,
        "tournament_match_sim_seconds": round(plain["sim"] / n, 3),
        "tournament_cores": cores,
        "tournament_plain_wall_s": round(plain["wall"], 2),
        "tournament_ray1_wall_s": round(one["wall"], 2),
        "tournament_ray_all_wall_s": round(every["wall"], 2),
        "tournament_plain_matches_per_hour": per_hour(plain),
        "tournament_ray1_matches_per_hour": per_hour(one),
        "tournament_ray_all_matches_per_hour": per_hour(every),
        "tournament_speedup_all_cores": round(one["wall"] / every["wall"], 3),
        "tournament_ray_overhead_pct": round((one["wall"] / plain["wall"] - 1.0) * 100.0, 2),
        "tournament_plain_cpu_s": round(plain["cpu"], 2),
        "tournament_ray1_cpu_s": round(one["cpu"], 2),
        "tournament_ray_all_cpu_s": round(every["cpu"], 2),
        "tournament_ray_cpu_overhead_pct": round((one["cpu"] / plain["cpu"] - 1.0) * 100.0, 2),
        "tournament_ray1_cpu_by_process": one["by_kind"],
        "tournament_ray_all_cpu_by_process": every["by_kind"],
        "tournament_ray1_workers": one["workers_seen"],
        "tournament_ray_all_workers": every["workers_seen"],
        "tournament_ray_start_s": round(max(one["start"], every["start"]), 2),
        "tournament_ray_start_cpu_s": round(max(one["start_cpu"], every["start_cpu"]), 2),
        "tournament_same_digests": plain["digests"] == one["digests"] == every["digests"],
        "tournament_load_before": round(load, 2),
        "tournament_load_after": round(os.getloadavg()[0], 2),
        "tournament_steal_pct": steal_pct(host, cpu_times()),
    }


if __name__ == "__main__":
    mode, workers, half = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    print(json.dumps(_play(mode, workers, half)))
