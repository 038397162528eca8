"""Determinism across modes: a lockstep server with one process per team, or one per robot, reproduces the
embedded run bit for bit (equal state digests), with noisy perception, the ball in play and strategies that
read their team picture (so the StrategyPub's timing matters)."""

from __future__ import annotations

import json
import subprocess

import pytest

from .cluster import ROOT, SIMATCH, chaser_overrides

SCENE = "msl_5v5"
DURATION = "2"
SETTINGS = [
    *chaser_overrides("cyan", "magenta"),
    "--set",
    "perception.position_noise=0.05",
    "--set",
    "perception.ball_dropout=0.1",
    "--seed",
    "3",
    "--duration",
    DURATION,
]
#: events only a distributed run has (who joined, who left)
PROCESS_EVENTS = {"process_joined", "process_left", "process_lost"}


def embedded(procs) -> dict:
    out = subprocess.run(
        [*SIMATCH, "run", SCENE, *SETTINGS, "--json", "--quiet"],
        capture_output=True,
        text=True,
        cwd=ROOT,
        env=procs.env,
        timeout=300,
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout)


def game_events(result: dict) -> list:
    return [e for e in result["events"] if e["type"] not in PROCESS_EVENTS]


@pytest.mark.slow
def test_one_process_per_team_equals_embedded(procs):
    server = procs.server(SCENE, *SETTINGS, "--deadline", "120")  # never give up on a slow process here
    teams = [procs.team("cyan"), procs.team("magenta")]
    dist = procs.result(server)
    for t in teams:
        assert procs.wait(t) == 0, procs.stderr(t)
        assert "the server ended the run (finished)" in procs.stderr(t)
    emb = embedded(procs)
    assert dist["state_digest"] == emb["state_digest"]
    assert dist["sim_seconds"] == emb["sim_seconds"] == float(DURATION)
    assert game_events(dist) == game_events(emb)
    joined = [e for e in dist["events"] if e["type"] == "process_joined"]
    assert sorted(e["team"] for e in joined) == ["cyan", "magenta"]
    assert set(dist) == set(emb)  # the same JSON object as `simatch run`


@pytest.mark.slow
def test_one_process_per_robot_equals_embedded(procs):
    server = procs.server(SCENE, *SETTINGS, "--deadline", "120")
    robots = [procs.robot(f"{team}/{rid}") for team in ("cyan", "magenta") for rid in range(1, 6)]
    dist = procs.result(server)
    for r in robots:
        assert procs.wait(r) == 0, procs.stderr(r)
    assert dist["state_digest"] == embedded(procs)["state_digest"]
    # one process per robot: each team's StrategyPub runs on the server, and the robots are told so
    assert all("StrategyPub runs on the server" in procs.stderr(r) for r in robots)
    assert sum(e["type"] == "process_joined" for e in dist["events"]) == 10


@pytest.mark.slow
def test_processes_that_speak_topic_by_topic_play_beside_bundled_ones_and_equal_embedded(procs):
    """A client that declines bundles (as one in another language may) gets the same data in the same order."""
    server = procs.server(SCENE, *SETTINGS, "--deadline", "120")
    plain = [procs.plain(f"cyan/{rid}") for rid in range(1, 6)] + [procs.plain("magenta")]
    dist = procs.result(server)
    for p in plain:
        assert procs.wait(p) == 0, procs.stderr(p)
        assert "(topic by topic): the server ended the run (finished) after 80 ticks" in procs.stderr(p)
    assert dist["state_digest"] == embedded(procs)["state_digest"]


@pytest.mark.slow
def test_a_server_takes_the_options_of_run_such_as_recording(procs):
    from simatch.record import Recording

    mcap = procs.tmp / "match.mcap"
    server = procs.server(
        SCENE,
        *chaser_overrides("cyan"),
        "--set",
        "teams.magenta.strategy=none",
        "--duration",
        "1",
        "--record",
        str(mcap),
    )
    team = procs.team("cyan")
    out = procs.result(server)
    assert procs.wait(team) == 0
    rec = Recording(mcap)
    topics = rec.topics()
    assert "cyan/2/VelCmd" in topics and "cyan/2/OmniVisionInfo" in topics  # what the team sent, recorded
    assert not any("lockstep" in t for t in topics)  # the protocol is not data
    assert sum(1 for _ in rec.raw(topics=["cyan/2/VelCmd"])) == 40  # every tick of 1 s
    assert out["sim_seconds"] == 1.0
