"""The command line contract: `simatch run SCENE --json` prints exactly one JSON object with the documented
keys; mistakes exit with status 2 and a one-line message; the paper's locomotion test meets its bounds."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

SIMATCH = [sys.executable, "-m", "simatch"]


def run(*args, check=True):
    proc = subprocess.run(SIMATCH + list(args), capture_output=True, text=True, timeout=300)
    if check and proc.returncode != 0:
        raise AssertionError(f"simatch {' '.join(args)} failed ({proc.returncode}):\n{proc.stderr}")
    return proc


def test_locomotion_test_meets_the_issue_bounds():
    out = json.loads(run("run", "omni_circle", "--json").stdout)
    assert set(out) == {"scene", "seed", "sim_seconds", "wall_seconds", "rtf", "state_digest", "result", "events"}
    r = out["result"]
    assert r["samples"] == 5112  # 25.56 s sampled every physics step
    assert r["position_error_cm"] <= 0.5
    assert abs(r["orientation_error_rad"] - r["orientation_error_expected_rad"]) <= 0.01
    # a robot speeding up from rest at 2.5 m/s^2 lags w t by a constant (here ~0.72 rad)
    assert 0.6 < r["orientation_error_expected_rad"] < 0.8
    assert out["sim_seconds"] == pytest.approx(25.56)
    assert len(out["state_digest"]) == 64


def test_run_json_is_one_object_and_repeatable():
    a = run("run", "msl_5v5", "--duration", "2", "--seed", "5", "--json").stdout
    b = run("run", "msl_5v5", "--duration", "2", "--seed", "5", "--json").stdout
    assert a.count("\n") == 1
    ja, jb = json.loads(a), json.loads(b)
    assert ja["state_digest"] == jb["state_digest"] and ja["seed"] == 5 and ja["sim_seconds"] == 2.0


def test_overrides_on_the_command_line():
    out = json.loads(
        run(
            "run",
            "omni_circle",
            "--set",
            "judge.duration=2.0",
            "--set",
            "teams.cyan.strategy_params.w=1.0",
            "--set",
            "judge.w=1.0",
            "--json",
        ).stdout
    )
    assert out["result"]["samples"] == 400 and out["result"]["command"]["w"] == 1.0


@pytest.mark.parametrize(
    "args, message",
    [
        (["run", "nosuchscene"], "no scene named 'nosuchscene'"),
        (["run", "msl_5v5", "--set", "ball.mass=-2"], "ball.mass: expected greater than 0"),
        (["run", "msl_5v5", "--set", "ball.mas=2"], "ball.mas: unknown key"),
        (["run", "msl_5v5", "--duration", "-1"], "--duration must be positive"),
        (["bench", "--only", "physics", "--seconds", "-1"], "--seconds must be positive"),
        (["bench", "--only", "physics", "--seconds", "nan"], "--seconds must be positive"),
    ],
)
def test_mistakes_exit_2_with_a_clear_message(args, message):
    proc = run(*args, check=False)
    assert proc.returncode == 2, proc.stderr
    assert message in proc.stderr and "Traceback" not in proc.stderr


def test_scenes_lists_the_shipped_scenes():
    out = run("scenes").stdout
    assert "omni_circle" in out and "msl_5v5" in out
    detail = json.loads(run("scenes", "omni_circle").stdout)
    assert detail["judge"]["kind"] == "locomotion_test"


def test_a_match_summary_prints_the_event_log_it_is_asked_for():
    """The main job (`make run`) prints the whole event log; by default the summary keeps the last 30."""
    short = ["run", "msl_5v5", "--quiet", "--set", "match.half_duration=4", "--set", "match.half_time=2"]
    every = json.loads(run(*short, "--json").stdout)["events"]
    full = run(*short, "--events", "all").stdout
    listed = [line for line in full.splitlines() if line.startswith("  ") and line.strip()[:1].isdigit()]
    assert len(listed) == len(every) > 10 and "earlier events" not in full
    assert listed[-1].split()[1] == "match_end" and "final score" in listed[-1]
    # the result comes last, so that however long the event log, the final screen of a terminal shows it
    lines = full.splitlines()
    result = json.loads(run(*short, "--json").stdout)["result"]
    assert lines[-len(result) - 1] == "result:"
    assert [line.split(":")[0].strip() for line in lines[-len(result) :]] == list(result)
    assert lines.index("result:") > lines.index(listed[-1])
    two = run(*short, "--events", "2").stdout
    assert f"({len(every) - 2} earlier events" in two
    assert len([line for line in two.splitlines() if line.strip()[:1].isdigit() and "  " in line[:4]]) == 2
    bad = run(*short, "--events", "some", check=False)
    assert bad.returncode == 2 and "expected a number of events or 'all'" in bad.stderr


@pytest.mark.slow
def test_bench_runs_each_benchmark_in_its_own_process_and_prints_one_object():
    proc = run("bench", "--only", "referee", "--only", "distributed_rtt", "--seconds", "1", "--json")
    out = json.loads(proc.stdout)
    assert proc.stdout.count("\n") == 1
    assert out["referee_sim_seconds"] == 1.0 and out["distributed_rtt_samples"] == 40
    for name in ("referee", "distributed_rtt"):  # what the host took meanwhile, beside each figure
        assert 0.0 <= out[f"{name}_host_steal_pct"] <= 100.0
    bad = run("bench", "--only", "nosuchbench", check=False)
    assert bad.returncode == 2 and "unknown benchmark(s) nosuchbench" in bad.stderr


def test_the_hosts_steal_is_read_from_proc_stat():
    from simatch.bench import host

    now = host.cpu_times()
    assert now is not None and 0 <= now[0] <= now[1]  # this machine is Linux
    assert host.steal_pct((10, 1000), (35, 1100)) == 25.0
    assert host.steal_pct((10, 1000), (10, 1000)) is None and host.steal_pct(None, now) is None


def test_a_benchmark_that_fails_alone_is_reported_with_what_it_said(monkeypatch):
    from simatch.cli import UsageError, bench

    def failing(cmd, **kwargs):
        return subprocess.CompletedProcess(cmd, 1, stdout="", stderr="Traceback ...\nRuntimeError: no cores")

    monkeypatch.setattr(bench.subprocess, "run", failing)
    with pytest.raises(
        UsageError, match="benchmark physics failed \\(exit 1\\):\nTraceback ...\nRuntimeError: no cores"
    ):
        bench.run_alone("physics", 1.0)
