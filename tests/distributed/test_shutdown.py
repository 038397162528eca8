"""Stopping a distributed run: Ctrl-C (SIGINT) or SIGTERM on any process ends it cleanly; stopping the server
ends every process; a server that dies leaves no client behind; nothing is left in /dev/shm."""

from __future__ import annotations

import json
import signal
import time

import pytest

from .cluster import chaser_overrides, shm_segments

LONG = [*chaser_overrides("cyan", "magenta"), "--realtime", "--duration", "60"]


def start_match(procs):
    server = procs.server("msl_5v5", *LONG)
    teams = [procs.team("cyan"), procs.team("magenta")]
    for team in teams:
        procs.wait_for_line(team, "joined run")
    procs.wait_for_line(server, "(magenta/1,2,3,4,5) joined")
    procs.wait_for_line(server, "(cyan/1,2,3,4,5) joined")
    return server, teams


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_stopping_the_server_ends_every_process(procs, sig):
    before = shm_segments()
    server, teams = start_match(procs)
    time.sleep(1.0)
    t0 = time.monotonic()
    server.send_signal(sig)
    out = procs.result(server, codes=(130,))  # the partial run is still reported
    for team in teams:
        assert procs.wait(team, timeout=30) == 0
        assert "the server ended the run (interrupted)" in procs.stderr(team)
    assert time.monotonic() - t0 < 20
    assert 0 < out["sim_seconds"] < 60 and out["state_digest"]
    assert shm_segments() <= before


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM])
def test_stopping_a_team_process_ends_it_and_the_match_goes_on(procs, sig):
    server = procs.server("msl_5v5", *chaser_overrides("cyan", "magenta"), "--realtime", "--duration", "4")
    teams = [procs.team("cyan"), procs.team("magenta")]
    procs.wait_for_line(server, "(cyan/1,2,3,4,5) joined")
    procs.wait_for_line(server, "(magenta/1,2,3,4,5) joined")  # the match is on
    time.sleep(1.0)
    teams[0].send_signal(sig)
    assert procs.wait(teams[0], timeout=30) == 130
    assert "interrupted" in procs.stderr(teams[0])
    out = procs.result(server)
    assert procs.wait(teams[1]) == 0
    assert out["sim_seconds"] == 4.0
    left = [e for e in out["events"] if e["type"] == "process_left"]
    assert [e["team"] for e in left] == ["cyan"]
    assert any(e["type"] == "watchdog_stop" and e["team"] == "cyan" for e in out["events"])


@pytest.mark.slow
def test_clients_of_a_dead_server_end_by_themselves(procs):
    server, teams = start_match(procs)
    server.send_signal(signal.SIGKILL)
    server.wait(10)
    for team in teams:
        assert procs.wait(team, timeout=60) != 0
        assert "lost the server" in procs.stderr(team)


@pytest.mark.slow
def test_a_server_waiting_for_teams_stops_on_ctrl_c(procs):
    server = procs.server("msl_5v5", *LONG)
    procs.wait_for_line(server, "waiting for")
    server.send_signal(signal.SIGINT)
    assert procs.wait(server, timeout=30) == 130
    assert json.loads(procs.stdout(server))["sim_seconds"] == 0.0
