"""Tournament throughput (``simatch bench --only tournament``): matches per hour with one Ray worker and with
every core, and what Ray costs against the same matches in a plain loop.

The same four matches (nubot against simple, seeds 1 and 2, both colours; ``--seconds`` of play each,
default 600: ten-minute matches of two halves with the 10 s break) are played three times, each time in a
fresh process: one after another in a plain loop (`PlainLoop`), on a local Ray instance with one worker, and
on one with a worker per core. Each time counts from the first match handed out to the last result back,
the processes' start-up (importing simatch, loading the compiled kernels: once per process, in the plain
loop's process as in each Ray worker) included; starting Ray itself is reported apart
(``tournament_ray_start_s``), as a tournament pays it once whatever its length. The state digests of the
three runs must be equal (``tournament_same_digests``).

On a machine shared with other work the wall-clock figures move with the load (reported before and after);
the CPU time of every process of the run — the plain loop's process, or the driver, Ray's own processes and
its workers together — moves much less: ``tournament_ray_cpu_overhead_pct`` is Ray's cost in CPU time
against the plain loop's for the same matches.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import time

MATCHES_SEEDS = (1, 2)
_TICK = os.sysconf("SC_CLK_TCK")


def session_cpu(sid: int) -> float:
    """CPU seconds used so far by the processes of session ``sid`` and the children they reaped."""
    total = 0
    for entry in os.scandir("/proc"):
        if not entry.name.isdigit():
            continue
        try:
            with open(f"/proc/{entry.name}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[3]) == sid:
            total += sum(int(v) for v in fields[11:15])  # utime stime cutime cstime
    return total / _TICK


def _play(mode: str, workers: int, half: float) -> dict:
    """One measurement, in this (fresh) process: {"wall", "start", "digests"}."""
    from ..tournament import PlainLoop, RayPool, Tournament, parse_entries

    with tempfile.TemporaryDirectory(prefix="simatch-bench-tournament-") as tmp:
        t = Tournament(
            parse_entries(["nubot,simple"]),
            seeds=MATCHES_SEEDS,
            out=tmp,
            overrides={"match.half_duration": half},
        )
        t0 = time.perf_counter()
        pool = PlainLoop() if mode == "plain" else RayPool(workers=workers)
        started = time.perf_counter() - t0
        try:
            sid = os.getsid(0)
            c1, t1 = session_cpu(sid), time.perf_counter()
            rows = [outcome["row"] for _, outcome in pool.map(t.job(m) for m in t.format.matches)]
            wall, cpu = time.perf_counter() - t1, session_cpu(sid) - c1
        finally:
            pool.close()
    bad = [r for r in rows if r["status"] != "ok"]
    if bad:
        raise RuntimeError(f"a benchmark match failed: {bad[0]['error']}")
    return {
        "wall": wall,
        "cpu": cpu,
        "start": started,
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
        "tournament_ray_start_s": round(max(one["start"], every["start"]), 2),
        "tournament_same_digests": plain["digests"] == one["digests"] == every["digests"],
        "tournament_load_before": round(load, 2),
        "tournament_load_after": round(os.getloadavg()[0], 2),
    }


if __name__ == "__main__":
    mode, workers, half = sys.argv[1], int(sys.argv[2]), float(sys.argv[3])
    print(json.dumps(_play(mode, workers, half)))
