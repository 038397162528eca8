"""The PPO example trains (briefly: the full 20 minutes is a documented command, docs/learning.md), its reward
signal is wired, and the saved policy plays in an ordinary run as a strategy plug-in."""

from __future__ import annotations

import csv
import json
import subprocess
import sys
from pathlib import Path

import pytest

from ..lockfile import skip_unless_locked

ROOT = Path(__file__).resolve().parents[2]


@pytest.mark.slow
@pytest.mark.timeout(1800)  # a few CPU seconds of training, but a shared machine may give it little wall time
def test_the_striker_example_trains_saves_and_its_policy_plays_in_a_run(tmp_path):
    skip_unless_locked("stable-baselines3")
    out = tmp_path / "ppo"
    cmd = [
        sys.executable,
        str(ROOT / "examples/learn/train_striker.py"),
        "--minutes",
        "0.1",
        "--clock",
        "cpu",
        "--envs",
        "2",
    ]
    proc = subprocess.run(
        [*cmd, "--eval-episodes", "2", "--out", str(out), "--json"], capture_output=True, text=True, timeout=600
    )
    assert proc.returncode == 0, proc.stderr[-2000:]
    summary = json.loads(proc.stdout.strip().splitlines()[-1])
    assert summary["train_steps"] >= 512 and summary["eval_episodes"] == 2
    for name in ("striker.zip", "striker.json", "curve.png", "curve.csv", "summary.json"):
        assert (out / name).stat().st_size > 0, name
    assert (out / "curve.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    meta = json.loads((out / "striker.json").read_text())
    assert meta["format"] == "simatch-policy-1" and meta["algorithm"] == "PPO" and meta["action"]["max_vel_x"] == 3.5
    rows = list(csv.DictReader(open(out / "curve.csv")))
    assert rows and all(r["end"] in ("goal", "ball_out", "time_limit") for r in rows)
    assert len({float(r["return"]) for r in rows}) > 1  # the reward signal reaches the learner

    play = [
        sys.executable,
        "-m",
        "simatch",
        "run",
        "striker_1v0",
        "--seed",
        "3",
        "--json",
        "--set",
        "teams.cyan.strategy=simatch.envs.policy:Policy",
        "--set",
        f"teams.cyan.strategy_params.file={out / 'striker.zip'}",
    ]
    run = subprocess.run(play, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    result = json.loads(run.stdout)
    assert result["result"]["end"] in ("goal", "ball_out", "time_limit")
    assert not [e for e in result["events"] if e["type"] == "strategy_error"]
    again = subprocess.run(play, capture_output=True, text=True, timeout=600)
    assert json.loads(again.stdout)["state_digest"] == result["state_digest"]  # deterministic
    idle = subprocess.run(play[:8], capture_output=True, text=True, timeout=600)
    assert json.loads(idle.stdout)["state_digest"] != result["state_digest"]  # the policy drove the robot

    # and in a refereed match, as a whole team: it sees there what its observation slots hold
    match = [*play[:4], "msl_5v5", "--duration", "4", "--json", *play[8:]]
    run = subprocess.run(match, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr[-2000:]
    events = json.loads(run.stdout)["events"]
    assert not [e for e in events if e["type"] == "strategy_error"]
    assert [e for e in events if e["type"] == "command" and "kick-off for cyan" in e.get("detail", "")]


def test_a_missing_policy_file_is_a_clear_error(tmp_path):
    proc = subprocess.run(
        [
            sys.executable,
            "-m",
            "simatch",
            "run",
            "striker_1v0",
            "--set",
            "teams.cyan.strategy=simatch.envs.policy:Policy",
            "--set",
            f"teams.cyan.strategy_params.file={tmp_path / 'nothing.zip'}",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert proc.returncode == 2 and "nothing.zip" in proc.stderr and "save_policy" in proc.stderr
    assert "Traceback" not in proc.stderr
