"""The teams change ends at half time in a distributed run too: team processes learn their new side from the
game state (no restart), and the lockstep run still equals the embedded one bit for bit."""

from __future__ import annotations

import json
import subprocess

import pytest

from .cluster import ROOT, SIMATCH

AWARE = "tests.distributed.strategies:SideAware"
SETTINGS = [
    "--set",
    f"teams.cyan.strategy={AWARE}",
    "--set",
    f"teams.magenta.strategy={AWARE}",
    "--set",
    "match.half_duration=3.0",
    "--set",
    "match.half_time=0.5",
    "--seed",
    "2",
]


@pytest.mark.slow
def test_team_processes_learn_the_new_side_from_the_game_state(procs):
    from simatch.record import Recording

    mcap = procs.tmp / "ends.mcap"
    server = procs.server("msl_5v5", *SETTINGS, "--deadline", "120", "--record", str(mcap))
    teams = [procs.team("cyan"), procs.team("magenta")]
    dist = procs.result(server)
    for t in teams:
        assert procs.wait(t) == 0, procs.stderr(t)
    [change] = [e for e in dist["events"] if e["type"] == "ends_changed"]
    assert change["t"] == pytest.approx(3.0) and "cyan attacks -x, magenta attacks +x" in change["detail"]
    # each team's robot 5 drives to a world point through its team frame: it is there at the end only if its
    # process turned its frame with the game state (else it would drive to the mirror point)
    rec = Recording(mcap)
    *_, (_, _, last) = rec.messages(topics=["model_states"])
    names = list(last.name)
    pose = last.pose.reshape(len(names), -1)
    for robot, (wx, wy) in (("cyan/5", (2.0, 3.0)), ("magenta/5", (2.0, -3.0))):
        x, y = pose[names.index(robot), :2]
        assert abs(x - wx) < 0.5 and abs(y - wy) < 0.5, f"{robot} at ({x:.2f}, {y:.2f}): it missed the change of ends"
    # perception turned with it: cyan's goalkeeper, at +10.5 in the world after the change, sees itself at -10.5
    late = [m for _, t, m in rec.messages(topics=["cyan/1/OmniVisionInfo"]) if t / 1e9 > 3.1]
    me = next(r for r in late[0].robots if r.id == 1)
    assert me.x == pytest.approx(-10.5, abs=0.3) and pose[names.index("cyan/1"), 0] > 9.0
    emb = subprocess.run(
        [*SIMATCH, "run", "msl_5v5", *SETTINGS, "--json", "--quiet"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=procs.env,
        timeout=300,
    )
    assert emb.returncode == 0, emb.stderr
    assert json.loads(emb.stdout)["state_digest"] == dist["state_digest"]
