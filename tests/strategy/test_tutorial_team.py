"""The tutorial's team (examples/striker.py) shows good practice: it scores, it slows down near opponents, and
it plays a whole refereed match (examples/striker_vs_simple.toml, as a user runs it) without a card.

The scene as shipped has exact perception, so every seed gives the same match; the second match sees the
world through noisy eyes (a seed of its own), so that the team is not one tuned to a single run."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

import simatch

ROOT = Path(__file__).resolve().parents[2]
SCENE = ROOT / "examples" / "striker_vs_simple.toml"
#: fouls of driving into opponents: the ones a team that slows down near them never commits
CONTACT_FOULS = {"charging", "pushing", "goalkeeper_contact"}


#: the matches played: as the tutorial runs it, and seen through noisy perception (2 cm, 5 cm/s, 0.02 rad)
MATCHES = {
    "as_shipped": [],
    "noisy_perception": [
        "--seed=1",
        "--set=perception.position_noise=0.02",
        "--set=perception.velocity_noise=0.05",
        "--set=perception.heading_noise=0.02",
    ],
}


@pytest.fixture(scope="module", params=list(MATCHES))
def match(request):
    """A whole embedded match as the tutorial runs it: PYTHONPATH=examples simatch run
    examples/striker_vs_simple.toml (and the same with noisy perception)."""
    proc = subprocess.run(
        [sys.executable, "-m", "simatch", "run", str(SCENE), "--json", "--quiet", *MATCHES[request.param]],
        capture_output=True,
        text=True,
        timeout=1200,
        env={"PYTHONPATH": str(ROOT / "examples"), "PATH": "/usr/bin:/bin"},
        cwd=ROOT,
    )
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


@pytest.mark.slow
def test_the_tutorial_team_plays_a_whole_match_without_a_card(match):
    result, events = match["result"], match["events"]
    assert result["ended"] and match["sim_seconds"] == pytest.approx(610.0, abs=0.1)  # 2 x 300 s and the break
    assert result["yellow_cards"]["cyan"] == 0 and result["red_cards"]["cyan"] == 0
    assert not [e for e in events if e["type"] in ("yellow_card", "red_card", "send_off") and e.get("team") == "cyan"]
    assert not [e for e in events if e["type"] == "strategy_error"]


@pytest.mark.slow
def test_the_tutorial_team_scores(match):
    # (the result's goals are the valid ones: a disallowed goal is counted apart)
    own = [g for g in match["result"]["goals"] if g["team"] == "cyan" and g["robot"].startswith("cyan/")]
    assert own, f"no goal scored by the team itself: {match['result']['goals']}"
    assert match["result"]["score"]["cyan"] > match["result"]["score"]["magenta"]


@pytest.mark.slow
def test_the_tutorial_team_never_drives_into_an_opponent(match):
    fouls = [e for e in match["events"] if e["type"] in CONTACT_FOULS and e.get("team") == "cyan"]
    assert not fouls, fouls
    # the baseline it plays against does: the referee judges contacts in this match
    assert [e for e in match["events"] if e["type"] == "charging" and e.get("team") == "magenta"]


def test_a_striker_slows_down_before_an_opponent_in_its_way(monkeypatch):
    """Two opponents stand between a striker and the ball: the striker goes round them to the ball, never
    driving at one of them as fast as the referee's charging limit (1.5 m/s), and the referee calls nothing."""
    monkeypatch.syspath_prepend(str(ROOT / "examples"))
    overrides = {
        "teams.magenta.strategy": "none",
        "teams.cyan.start": [
            [-10.5, 0.0, 0.0],
            [-6.0, 0.0, 0.0],
            [-6.0, 5.0, 0.0],
            [-8.0, -5.0, 0.0],
            [-9.0, 5.0, 0.0],
        ],
        "teams.magenta.start": [
            [10.5, 0.0, math.pi],
            [-3.5, 0.0, math.pi],
            [-3.0, 0.6, math.pi],
            [5, -2, math.pi],
            [5, 2, math.pi],
        ],
        "ball.position": [-1.0, 0.0],
        "match.kickoff": "magenta",
    }
    with simatch.Simulation(str(SCENE), overrides=overrides) as sim:
        sim.run(seconds=2.0)
        sim.judge.command("STARTROBOT")  # play on at once, the ball where it lies
        sim.set_model_state("ball", x=-1.0, y=0.0, vx=0.0, vy=0.0)
        fastest, reached = 0.0, math.inf
        for _ in range(160):
            sim.step(5)
            ms = sim.model_states()
            me, ball = ms["cyan/2"], ms["ball"]
            reached = min(reached, math.hypot(ball.x - me.x, ball.y - me.y))
            for opp in ("magenta/2", "magenta/3"):
                o = ms[opp]
                d = math.hypot(o.x - me.x, o.y - me.y)
                if d < 0.7:
                    fastest = max(fastest, (me.vx * (o.x - me.x) + me.vy * (o.y - me.y)) / d)
        assert reached < 0.45, "cyan/2 went round the opponents and took the ball"
        assert fastest < 1.0, f"cyan/2 drove at {fastest:.2f} m/s towards an opponent within 0.7 m"
        assert not [e for e in sim.events if e["type"] in CONTACT_FOULS]
