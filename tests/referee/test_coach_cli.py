"""The coaches: the programmatic per-team coach takes words as well as numbers, and `simatch coach` (the
command-line coach) commands one team only, or operates the referee, from typed or piped lines."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.msgs.game_commands import MatchMode, parse


def coach(*args, stdin: str, check: bool = True):
    proc = subprocess.run(
        [sys.executable, "-m", "simatch", "coach", *args], input=stdin, capture_output=True, text=True, timeout=120
    )
    if check:
        assert proc.returncode == 0, proc.stderr
    return proc


def test_command_words():
    assert parse("freekick") == MatchMode.OUR_FREEKICK
    assert parse("opp corner") == parse("corner opp") == MatchMode.OPP_CORNERKICK
    assert parse("OPP_GOALKICK") == MatchMode.OPP_GOALKICK and parse("13") == MatchMode.DROPBALL
    for bad, why in (
        ("opp stop", "belongs to no team"),
        ("kick it", "one command"),
        ("99", "no game command"),
        ("dance", "unknown game command"),
    ):
        with pytest.raises(ValueError, match=why):
            parse(bad)


def test_programmatic_coach_takes_words():
    with simatch.Simulation(
        "msl_5v5", overrides={"judge.kind": "none", "teams.cyan.strategy": "none", "teams.magenta.strategy": "none"}
    ) as sim:
        heard = []
        sim.bus.subscribe(topics.team_topic("magenta", topics.RECEIVE_FROM_COACH), msgs.CoachInfo, heard.append)
        sim.coaches["magenta"].send("opp throwin")
        sim.run(seconds=0.05)
        assert heard[-1].match_mode == MatchMode.OPP_THROWIN == heard[-1].match_type


def test_command_line_coach_commands_its_team_only():
    script = "kickoff\nrun 0.5\nstart\nrun 0.5\nmaxvel 2\nstatus\nmagenta stop\nnonsense\nrun 0.5\n"
    proc = coach("msl_5v5", "--team", "cyan", "--json", "--set", "teams.magenta.strategy=none", stdin=script)
    out = json.loads(proc.stdout)
    assert out["sim_seconds"] == pytest.approx(1.505)
    sent = [(e["t"], e["team"], e["detail"]) for e in out["events"] if e["type"] == "coach_command"]
    assert sent == [(0.005, "cyan", "OUR_KICKOFF"), (0.505, "cyan", "STARTROBOT"), (1.005, "cyan", "STARTROBOT")]
    assert "this console coaches cyan, not magenta" in proc.stderr
    assert "? unknown game command 'nonsense'" in proc.stderr
    assert "cyan: STARTROBOT" in proc.stderr and "magenta: STOPROBOT" in proc.stderr  # the status line
    assert out["result"] == {}  # no referee: coaches only


def test_command_line_coach_runs_a_script_file_the_same_way_twice(tmp_path):
    path = tmp_path / "plan.txt"
    path.write_text("# both teams\ncyan kickoff   # ours\nmagenta kickoff opp\nrun 1\nstart\nrun 1\n")
    runs = [
        json.loads(coach("msl_5v5", "--script", str(path), "--json", "--seed", "2", stdin="").stdout) for _ in range(2)
    ]
    assert runs[0]["state_digest"] == runs[1]["state_digest"]
    sent = [(e["team"], e["detail"]) for e in runs[0]["events"] if e["type"] == "coach_command"]
    assert sent == [
        ("cyan", "OUR_KICKOFF"),
        ("magenta", "OPP_KICKOFF"),
        ("cyan", "STARTROBOT"),
        ("magenta", "STARTROBOT"),
    ]


def test_command_line_referee_operator():
    script = (
        "run 3\npause\nrun 1\nresume\nyellow cyan/3\noff magenta/2 5\ncyan freekick at 2 3\nrun 1\n"
        "red cyan/9\nquit\nrun 5\n"
    )
    proc = coach("msl_5v5", "--referee", "--json", stdin=script)
    out = json.loads(proc.stdout)
    ops = [e["detail"] for e in out["events"] if e["type"] == "operator"]
    assert ops == [
        "pause (by cli)",
        "resume (by cli)",
        "yellow card for cyan/3 (by cli)",
        "send magenta/2 off for 5 s (by cli)",
        "command OUR_FREEKICK for cyan at (2.00, 3.00) (by cli)",
    ]
    assert "? refused: no robot named 'cyan/9'" in proc.stderr
    assert out["result"]["yellow_cards"] == {"cyan": 1, "magenta": 0}
    assert out["sim_seconds"] < 5.2  # 'quit' ended it


def test_live_console_applies_lines_while_the_run_goes_on():
    proc = coach(
        "msl_5v5", "--live", "--pace", "20", "--duration", "2", "--json", "--team", "magenta", stdin="freekick\n"
    )
    out = json.loads(proc.stdout)
    assert any(
        e["type"] == "coach_command" and e["team"] == "magenta" and e["detail"] == "OUR_FREEKICK" for e in out["events"]
    )


def test_command_line_mistakes():
    proc = coach("msl_5v5", "--team", "blue", stdin="", check=False)
    assert proc.returncode == 2 and "no team named 'blue'" in proc.stderr
    proc = coach("omni_circle", "--referee", stdin="", check=False)
    assert proc.returncode == 2 and "has no referee" in proc.stderr
