"""Tournaments played for real: the ``simatch tournament`` command in a process of its own, on a local Ray
instance it starts (2 CPUs, a small object store, no dashboard) and stops.

Matches are short (two halves of 5 s and a 1 s break). The reference tournament — nubot, simple and the
tutorial's striker, one seed, both colours: six matches, recorded and reported — is played once per test
session; the other tests compare their tables with it.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pyarrow.parquet as pq
import pytest

REPO = Path(__file__).resolve().parents[2]
SHORT = ["--set", "match.half_duration=5", "--set", "match.half_time=1"]
TEAMS = "nubot,simple,striker:StrikerTeam"
MATCHES = 6  # three teams, one seed, both colours


def env() -> dict:
    out = dict(os.environ)
    out["PYTHONPATH"] = os.pathsep.join([str(REPO / "examples"), str(REPO)])
    out["PYTHONUNBUFFERED"] = "1"
    return out


def command(out: Path, *extra: str, teams: str = TEAMS) -> list[str]:
    return [
        sys.executable,
        "-m",
        "simatch",
        "tournament",
        "--teams",
        teams,
        "--seeds",
        "1",
        *SHORT,
        "--out",
        str(out),
        "--quiet",
        *extra,
    ]


def start(out: Path, *extra: str, teams: str = TEAMS) -> subprocess.Popen:
    """The command in a session of its own (so that everything it starts, Ray included, can be found)."""
    return subprocess.Popen(
        command(out, *extra, teams=teams),
        env=env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )


def session_pids(sid: int) -> list[int]:
    """The processes of session ``sid`` (the driver's and every process it started, Ray's own included)."""
    out = []
    for entry in Path("/proc").iterdir():
        if not entry.name.isdigit():
            continue
        try:
            stat = (entry / "stat").read_text()
        except OSError:
            continue
        fields = stat.rsplit(")", 1)[1].split()
        if int(fields[3]) == sid and fields[0] != "Z":
            out.append(int(entry.name))
    return out


def cmdline(pid: int) -> str:
    try:
        return (Path("/proc") / str(pid) / "cmdline").read_bytes().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def end_session(proc: subprocess.Popen, wait: float = 30.0) -> list[int]:
    """Wait for the session of ``proc`` to empty (``wait`` seconds), then end what is left of it, by pid.
    Returns the pids that had to be ended."""
    deadline = time.monotonic() + wait
    left = session_pids(proc.pid)
    while left and time.monotonic() < deadline:
        time.sleep(0.5)
        left = session_pids(proc.pid)
    for pid in left:
        try:
            os.kill(pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
    return left


def rows_done(out: Path) -> int:
    return len(list((out / "matches").glob("*.parquet"))) if (out / "matches").is_dir() else 0


def wait_for(condition, timeout: float, what: str, proc: subprocess.Popen | None = None) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"the tournament ended (exit {proc.returncode}) before {what}: {proc.stderr.read()}")
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        time.sleep(0.3)


def table(out: Path) -> dict[str, dict]:
    return {r["match_id"]: r for r in pq.read_table(out / "matches.parquet").to_pylist()}


#: /dev/shm files of other middleware (ROS 2's Fast DDS, LTTng) that other jobs on a shared machine make meanwhile
FOREIGN_SHM = ("fastdds_", "sem.fastdds_", "lttng-")


def shm() -> set[str]:
    """/dev/shm files (a Ray object store may use it: nothing of it must stay behind)."""
    names = os.listdir("/dev/shm") if os.path.isdir("/dev/shm") else []
    return {n for n in names if not n.startswith(FOREIGN_SHM)}


@pytest.fixture(scope="session")
def reference(tmp_path_factory):
    """The reference tournament, played to its end once: (folder, summary, rows by match id, stderr)."""
    root = tmp_path_factory.mktemp("reference")
    out = root / "results"
    before = shm()
    proc = start(out, "--record", str(root / "recordings"), "--report", str(root / "report"), "--json")
    try:
        stdout, stderr = proc.communicate(timeout=900)
    finally:
        if proc.poll() is None:
            proc.kill()
        left = end_session(proc)
    assert proc.returncode == 0, stderr
    assert not left, f"processes left running by the tournament: {[cmdline(p) for p in left]}"
    assert shm() <= before, f"files left in /dev/shm: {shm() - before}"
    return {"root": root, "out": out, "summary": json.loads(stdout), "rows": table(out), "stderr": stderr}
