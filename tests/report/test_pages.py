"""The match report in the real headless Chromium: every plot drawn, nothing fetched from a network, and its
numbers checked against the recording's own tables (``simatch export``), computed here another way."""

from __future__ import annotations

import math
from collections import defaultdict

import numpy as np
import pytest

from simatch.scene.referee.log import FOUL_TYPES

from .conftest import plot, report_data, shot, simatch

pytestmark = pytest.mark.slow

PLOTS = ["timeline", "possession", "shots", "heat-ball", "heat-cyan", "heat-magenta", "robots", "roles", "stages"]
CONTROL_STEPS = 5
PERIOD = 0.025


def play_intervals(tables) -> list[tuple[float, float]]:
    out, start = [], None
    for row in sorted(tables["game_state"], key=lambda r: r["t"]):
        if row["phase"] == "play" and start is None:
            start = row["t"]
        elif row["phase"] != "play" and start is not None:
            out.append((start, row["t"]))
            start = None
    return out


def test_the_match_report_draws_every_plot_offline_and_its_numbers_are_the_recordings(recorded, open_file):
    page = open_file(recorded["recorded"])
    assert page.network == [] and page.errors == []
    ids = page.evaluate("Array.from(document.querySelectorAll('.js-plotly-plot')).map(d => d.id)")
    assert ids == [f"plot-{p}" for p in PLOTS]
    data = report_data(page)
    tables = recorded["tables"]
    result = recorded["run"]["result"]

    # goals, fouls: the referee's, as the run printed them and as the event table has them
    events = tables["events"]
    for team in ("cyan", "magenta"):
        goals = sum(1 for e in events if e["type"] == "goal" and e["team"] == team)
        fouls = sum(1 for e in events if e["type"] in FOUL_TYPES and e["team"] == team)
        assert goals == result["score"][team]
        assert page.inner_text(f'[data-key="{team}.goals"]') == str(goals)
        assert page.inner_text(f'[data-key="{team}.fouls"]') == str(fouls)
    assert page.inner_text("#final-score").replace(" ", "") == f"{result['score']['cyan']}:{result['score']['magenta']}"

    # distance run and top speed per robot: from the trajectories at every control tick
    traj = defaultdict(list)
    for r in tables["trajectories"]:
        if r["step"] % CONTROL_STEPS == 0 and r["team"]:
            traj[r["model"]].append((r["step"], r["x"], r["y"], r["vx"], r["vy"]))
    robots = plot(page, "robots")
    distance = dict(zip(robots[0]["x"], robots[0]["y"]))
    top = dict(zip(robots[1]["x"], robots[1]["y"]))
    assert set(distance) == set(traj) and len(distance) == 10
    for name, samples in traj.items():
        samples.sort()
        steps = [math.hypot(b[1] - a[1], b[2] - a[2]) for a, b in zip(samples, samples[1:])]
        assert distance[name] == pytest.approx(sum(s for s in steps if s <= 0.5), abs=0.011), name
        assert top[name] == pytest.approx(max(math.hypot(s[3], s[4]) for s in samples), abs=0.001), name
    assert sum(distance.values()) > 100

    # the ball's heat map holds every control tick of play: the play time of the referee's game states
    play = play_intervals(tables)
    ticks = sum(
        1
        for r in tables["trajectories"]
        if r["model"] == "ball" and r["step"] % CONTROL_STEPS == 0 and any(a <= r["t"] < b for a, b in play)
    )
    (heat,) = plot(page, "heat-ball")
    z = np.array([[v or 0.0 for v in row] for row in heat["z"]])
    assert z.sum() == pytest.approx(ticks * PERIOD, abs=1e-6)
    assert data["play_seconds"] == pytest.approx(sum(b - a for a, b in play), abs=1e-3)

    # every shot on the map is a kick of the recording by that robot at that time
    kicks = {(round(r["t"], 3), r["kicker"]) for r in tables["ball_contacts"] if r["kicker"]}
    markers = [t for t in plot(page, "shots") if t["meta"]]
    assert sum(t["meta"]["shots"] for t in markers) == len(data["shots"])
    for s in data["shots"]:
        assert any(abs(t - s["t"]) < 0.006 and k == s["robot"] for t, k in kicks), s
    assert len(data["shots"]) >= 1  # nubot shoots in a minute against simple

    # role time: the StrategyInfo messages of each robot, one control period each
    roles = plot(page, "roles")
    count = defaultdict(float)
    for r in tables["strategy_info"]:
        count[f"{r['team']}/{r['robot']}"] += PERIOD
    for name, seconds in count.items():
        shown = sum(t["x"][t["y"].index(name)] for t in roles if name in t["y"])
        assert shown == pytest.approx(seconds, abs=2 * PERIOD), name

    # the timeline: one goal marker per goal, whose hover text is the referee's reason
    goals = next(t for t in plot(page, "timeline") if t["name"] == "goals") if result["goals"] else None
    if goals:
        assert len(goals["x"]) == len(result["goals"]) + sum(1 for e in events if e["type"] == "goal_disallowed")
        reasons = [e["detail"] for e in events if e["type"] == "goal"]
        assert all(any(r[:60] in text for text in goals["text"]) for r in reasons)
    shot(page, "match-report")


def test_the_report_written_live_is_the_report_of_the_recording(recorded, open_file):
    live = report_data(open_file(recorded["live"]))
    again = report_data(open_file(recorded["recorded"]))
    skip = {"sim_seconds", "wall_seconds", "recording"}
    assert {k: v for k, v in live.items() if k not in skip} == {k: v for k, v in again.items() if k not in skip}
    assert live["state_digest"] == recorded["run"]["state_digest"]


def test_report_command_refuses_bad_input_in_one_line(recorded, tmp_path):
    not_mcap = tmp_path / "notes.mcap"
    not_mcap.write_text("hello")
    cases = [
        (["report", str(tmp_path / "missing.mcap")], "no such recording"),
        (["report", str(not_mcap)], "not an MCAP recording"),
        (["report", str(recorded["mcap"]), "-o", str(tmp_path / "r.png")], "an HTML file"),
        (["report", str(recorded["mcap"]), "-o", str(recorded["recorded"])], "exists"),
        (["run", "msl_5v5", "--duration", "1", "--report", str(tmp_path / "r.txt")], "an HTML file"),
        (["run", "msl_5v5", "--duration", "1", "--report", str(tmp_path / "no" / "r.html")], "does not exist"),
    ]
    for args, message in cases:
        out = simatch(*args, timeout=300)
        assert out.returncode == 2, (args, out.stderr)
        lines = [line for line in out.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and message in lines[0], (args, out.stderr)


def test_a_recording_cut_short_still_gets_its_report(recorded, tmp_path, open_file):
    data = recorded["mcap"].read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(len(data) * 0.6)])
    out = simatch("report", str(cut), "-o", str(tmp_path / "cut.html"), timeout=300)
    assert out.returncode == 0, out.stderr
    assert "warning" in out.stderr and "not finalised" in out.stderr
    page = open_file(tmp_path / "cut.html")
    full = report_data(open_file(recorded["recorded"]))
    part = report_data(page)
    assert 0 < part["duration"] < full["duration"]
    assert "not finalised" in page.inner_text("#numbers")
