"""Tournaments on a real local Ray instance: the standing, resumption after Ctrl-C, a killed worker and a killed
driver, failing plug-ins (one that does not build, one that hangs, one that ends its process, one that ignores
every interruption), an existing cluster with --address, and that the same tournament gives the same table."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time

import pytest

from simatch.tournament import PlainLoop, RayPool, Tournament, parse_entries
from simatch.tournament.runner import plugin_paths

from .conftest import (
    MATCHES,
    REPO,
    SHORT,
    cmdline,
    command,
    end_session,
    env,
    rows_done,
    session_pids,
    shm,
    start,
    table,
    wait_for,
)

pytestmark = pytest.mark.slow

PLUGINS = "tests.tournament.plugins"


def points(row: dict, side: str) -> int:
    mine, theirs = row[f"{side}_goals"], row["away_goals" if side == "home" else "home_goals"]
    return 3 if mine > theirs else 1 if mine == theirs else 0


def test_a_small_tournament_standing_rows_recordings_and_reports(reference):
    rows = reference["rows"]
    summary = reference["summary"]
    assert len(rows) == MATCHES and {r["status"] for r in rows.values()} == {"ok"}
    assert summary["complete"] and summary["matches"]["played"] == MATCHES
    # every pairing both ways, one seed
    pairs = {(r["home"], r["away"]) for r in rows.values()}
    assert len(pairs) == MATCHES and {r["home_colour"] for r in rows.values()} == {"cyan"}
    # the standing is the rows' arithmetic
    table_ = {t["team"]: t for t in summary["standing"]}
    for team, t in table_.items():
        mine = [(r, "home") for r in rows.values() if r["home"] == team]
        mine += [(r, "away") for r in rows.values() if r["away"] == team]
        assert t["played"] == len(mine) == 4
        assert t["points"] == sum(points(r, side) for r, side in mine)
        assert t["goals_for"] == sum(r[f"{side}_goals"] for r, side in mine)
        assert t["elo_low"] <= t["elo"] <= t["elo_high"]
    assert [t["rank"] for t in summary["standing"]] == [1, 2, 3]
    # every column is filled for a played match
    for r in rows.values():
        assert r["state_digest"] and len(r["state_digest"]) == 64
        assert r["sim_seconds"] == pytest.approx(11.0, abs=0.01)
        assert 0 <= (r["home_possession"] or 0) <= 1 and r["worker"]
        assert r["recording"] and os.path.exists(r["recording"])
    report = reference["root"] / "report"
    assert (report / "index.html").exists() and (report / "plotly.min.js").exists()
    assert len(list((report / "matches").glob("*.html"))) == MATCHES
    # the terminal shows simatch's lines only: a local instance's token authentication is chosen, not warned of
    assert "WARNING" not in reference["stderr"], reference["stderr"]


def test_a_match_of_the_tournament_is_the_match_simatch_run_plays(reference):
    row = next(r for r in reference["rows"].values() if (r["home"], r["away"]) == ("nubot", "simple"))
    run = subprocess.run(
        [
            sys.executable,
            "-m",
            "simatch",
            "run",
            "msl_5v5",
            "--json",
            "--quiet",
            "--seed",
            str(row["seed"]),
            *SHORT,
            "--set",
            "teams.cyan.strategy=nubot",
            "--set",
            "teams.magenta.strategy=simple",
        ],
        capture_output=True,
        text=True,
        env=env(),
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    out = json.loads(run.stdout)
    assert out["state_digest"] == row["state_digest"]
    assert [out["result"]["score"]["cyan"], out["result"]["score"]["magenta"]] == [row["home_goals"], row["away_goals"]]


def test_the_same_command_again_plays_nothing_and_prints_the_same_standing(reference):
    t0 = time.monotonic()
    again = subprocess.run(command(reference["out"], "--json"), capture_output=True, text=True, env=env(), timeout=300)
    assert again.returncode == 0, again.stderr
    assert "starting Ray" not in again.stderr  # nothing to play: no Ray
    assert json.loads(again.stdout)["standing"] == reference["summary"]["standing"]
    assert time.monotonic() - t0 < 120


def test_interrupted_killed_worker_killed_driver_then_resumed_gives_the_same_table(reference, tmp_path):
    out = tmp_path / "results"
    before = shm()
    # 1. Ctrl-C after two matches: exit 130, what was played is kept
    proc = start(out)
    try:
        wait_for(lambda: rows_done(out) >= 2, 600, "two matches", proc)
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=120)
    finally:
        end_session(proc)
    assert proc.returncode == 130, err
    assert "run the same command to play the rest" in err
    first = rows_done(out)
    assert 2 <= first < MATCHES
    assert len(table(out)) == first  # the whole table is written on the way out too

    # 2. the same command plays only what is missing; a worker is killed during a match (Ray plays it again),
    #    then the driver is killed outright
    proc = start(out, "--workers", "1")
    try:
        wait_for(
            lambda: any("ray::play_match" in cmdline(p) for p in session_pids(proc.pid)),
            600,
            "a match in a Ray worker",
            proc,
        )
        worker = next(p for p in session_pids(proc.pid) if "ray::play_match" in cmdline(p))
        os.kill(worker, signal.SIGKILL)
        wait_for(lambda: rows_done(out) >= first + 1, 600, "one more match", proc)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
        err = proc.stderr.read()
    finally:
        end_session(proc, wait=5)
    assert f"{MATCHES - first} match(es) to play ({first} of {MATCHES} played before)" in err
    second = rows_done(out)
    assert first < second <= MATCHES

    # 3. once more: the rest, and the table is the reference's, match for match
    proc = start(out)
    try:
        _, err = proc.communicate(timeout=600)
    finally:
        left = end_session(proc)
    assert proc.returncode == 0, err
    assert not left
    if second < MATCHES:
        assert f"{MATCHES - second} match(es) to play ({second} of {MATCHES} played before)" in err
    rows = table(out)
    ref = reference["rows"]
    assert set(rows) == set(ref)
    for mid, r in rows.items():
        assert r["status"] == "ok", r["error"]
        for key in (
            "state_digest",
            "home_goals",
            "away_goals",
            "home_fouls",
            "away_fouls",
            "home_shots",
            "away_possession",
            "home",
            "away",
            "seed",
        ):
            assert r[key] == ref[mid][key], (key, r, ref[mid])
    assert shm() <= before


def test_failing_plug_ins_are_recorded_and_the_tournament_goes_on(tmp_path):
    out = tmp_path / "results"
    teams = f"simple,{PLUGINS}:Crashing,{PLUGINS}:Hanging"
    proc = start(out, "--timeout", "20", "--json", "--report", str(tmp_path / "report"), teams=teams)
    try:
        stdout, stderr = proc.communicate(timeout=600)
    finally:
        left = end_session(proc)
    assert proc.returncode == 0, stderr
    assert not left
    rows = table(out)
    assert len(rows) == 6
    by_pair = {(r["home"], r["away"]): r for r in rows.values()}
    crash, hang = f"{PLUGINS}:Crashing", f"{PLUGINS}:Hanging"
    for pair in ((crash, "simple"), ("simple", crash), (crash, hang), (hang, crash)):
        r = by_pair[pair]
        assert r["status"] == "error"
        assert "RuntimeError: this team does not build" in r["error"] and "plugins.py" in r["error"]
    for pair in ((hang, "simple"), ("simple", hang)):
        r = by_pair[pair]
        assert r["status"] == "timeout"
        assert "limit of 20 s" in r["error"] and "plugins.py" in r["error"] and "decide" in r["error"]
        assert 19 < r["wall_seconds"] < 20 + 60
    summary = json.loads(stdout)
    assert summary["complete"] and summary["matches"]["failed"] == 6
    assert {t["failed"] for t in summary["standing"]} == {4}
    # the report lists them with their errors, and links no match report for them
    page = (tmp_path / "report" / "index.html").read_text()
    assert 'id="failed"' in page and "this team does not build" in page and "timeout" in page
    assert not list((tmp_path / "report" / "matches").glob("*.html"))
    # failed matches are not played again by the same command; --retry-failed plays them again
    again = subprocess.run(command(out, "--json", teams=teams), capture_output=True, text=True, env=env(), timeout=300)
    assert again.returncode == 0 and "starting Ray" not in again.stderr


def test_a_match_that_ends_its_process_or_ignores_its_time_limit(tmp_path):
    """Driven from this process: a RayPool whose grace before ending a stuck worker is short."""
    entries = parse_entries([f"simple,{PLUGINS}:Exiting,{PLUGINS}:Stubborn"])
    t = Tournament(
        entries,
        seeds=[0],
        out=tmp_path / "results",
        overrides={"match.half_duration": 5, "match.half_time": 1},
        timeout=8,
    )
    wanted = {(1, 0), (2, 0)}  # Exiting and Stubborn, each against simple
    jobs = [t.job(m) for m in t.format.matches if (m.home, m.away) in wanted]
    # Exiting's worker dies twice (Ray plays a task again once): a long limit, not to stop its second try
    jobs[0]["timeout"] = 600
    saved = os.environ.get("PYTHONPATH")
    before = shm()
    pool = RayPool(workers=2, paths=plugin_paths([PLUGINS]), kill_grace=5)
    try:
        outcomes = {job["match_id"]: outcome["row"] for job, outcome in pool.map(jobs)}
    finally:
        pool.close()
        if saved is None:
            os.environ.pop("PYTHONPATH", None)
        else:
            os.environ["PYTHONPATH"] = saved
    assert shm() <= before
    exiting, stubborn = (outcomes[j["match_id"]] for j in jobs)
    assert exiting["status"] == "crashed" and "Worker" in exiting["error"]
    assert stubborn["status"] == "timeout" and "its worker was ended" in stubborn["error"]
    assert 8 + 5 <= stubborn["wall_seconds"] < 8 + 5 + 30


def test_a_team_raising_in_every_decision_plays_on_standing_still(tmp_path):
    """The strategies' guard keeps such a match going: it is no failure, its errors are counted."""
    entries = parse_entries([f"simple,{PLUGINS}:Raising"])
    t = Tournament(
        entries, seeds=[0], out=tmp_path / "results", overrides={"match.half_duration": 3, "match.half_time": 1}
    )
    summary = t.play(PlainLoop())
    rows = table(tmp_path / "results")
    assert summary["complete"] and {r["status"] for r in rows.values()} == {"ok"}
    for r in rows.values():
        side = "home" if r["home"].endswith("Raising") else "away"
        assert r[f"{side}_strategy_errors"] >= 100


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_an_existing_ray_cluster_with_address(tmp_path):
    port = free_port()
    ray_bin = os.path.join(os.path.dirname(sys.executable), "ray")
    head = subprocess.Popen(
        [
            ray_bin,
            "start",
            "--head",
            "--block",
            "--node-ip-address",
            "127.0.0.1",
            "--port",
            str(port),
            "--num-cpus",
            "2",
            "--include-dashboard",
            "false",
            "--object-store-memory",
            str(128 * 1024 * 1024),
            "--disable-usage-stats",
        ],
        env=env(),
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        start_new_session=True,
    )
    out = tmp_path / "results"
    try:
        proc = None
        deadline = time.monotonic() + 180
        while True:  # the head takes a while to listen
            proc = subprocess.run(
                command(out, "--address", f"127.0.0.1:{port}", "--json", teams="nubot,simple"),
                capture_output=True,
                text=True,
                env=env(),
                timeout=600,
            )
            if proc.returncode == 0 or time.monotonic() > deadline or head.poll() is not None:
                break
            time.sleep(3)
        assert proc.returncode == 0, proc.stderr
        summary = json.loads(proc.stdout)
        assert summary["executor"].startswith(f"Ray cluster at 127.0.0.1:{port}")
        assert summary["matches"]["played"] == 2
        assert {r["status"] for r in table(out).values()} == {"ok"}
    finally:
        head.send_signal(signal.SIGTERM)
        try:
            head.wait(timeout=60)
        except subprocess.TimeoutExpired:
            head.kill()
        left = end_session(head)
    assert not left, [cmdline(p) for p in left]


def test_bad_input_is_refused_in_one_line(tmp_path):
    cases = [
        (["--teams", "nubot"], "at least two teams"),
        (["--teams", "nubot,simple", "--seeds", "0"], "--seeds must be at least 1"),
        (["--teams", "nubot,simple", "--scene", "encirclement_9v7"], "need the referee"),
        (["--teams", "nubot,simple", "--set", "judge.kind=none"], "need the referee"),
        (["--teams", "nubot,simple", "--set", "match.halfs=2"], "unknown key"),
        (["--teams", "nubot,simple", "--timeout", "-1"], "--timeout must be positive"),
    ]
    for args, message in cases:
        proc = subprocess.run(
            [sys.executable, "-m", "simatch", "tournament", "--out", str(tmp_path / "x"), *args],
            capture_output=True,
            text=True,
            env=env(),
            timeout=120,
        )
        assert proc.returncode == 2, (args, proc.stderr)
        lines = [line for line in proc.stderr.splitlines() if line.strip()]
        assert len(lines) == 1 and message in lines[0], (args, proc.stderr)
    assert not REPO.joinpath("tournament").exists()
