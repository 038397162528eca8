"""Operator takeover: pause, any command, moving the ball, sending off and returning robots, automatic judging
on and off — on the Python API and on the bus (RefereeCommand on ``referee_command``), every request logged,
every bad request refused with a reason and without harm."""

from __future__ import annotations

import math

import pytest

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.msgs.game_commands import MatchMode
from simatch.scene.referee import OperatorError

OVERRIDES = {"teams.cyan.strategy": "none", "teams.magenta.strategy": "none", "judge.kind": "msl_referee"}


@pytest.fixture
def match():
    sims = []

    def make(**overrides):
        sim = simatch.Simulation("msl_5v5", overrides={**OVERRIDES, **overrides})
        sims.append(sim)
        heard = {"cyan": [], "magenta": []}
        for team, log in heard.items():
            sim.bus.subscribe(topics.team_topic(team, topics.RECEIVE_FROM_COACH), msgs.CoachInfo, log.append)
        sim.step()
        return sim, heard

    yield make
    for sim in sims:
        sim.close()


def types(sim, since=0):
    return [e["type"] for e in sim.events[since:]]


def test_pause_stops_robots_and_the_clock_and_resume_carries_on(match):
    sim, heard = match()
    ref = sim.judge
    sim.set_model_state("ball", x=3.0, y=2.0)
    ref.command("STARTROBOT")
    sim.run(seconds=1.0)
    clock = sim.game["clock"]
    ref.pause()
    assert heard["cyan"][-1].match_mode == MatchMode.STOPROBOT and sim.game["paused"]
    sim.run(seconds=3.0)
    assert sim.game["clock"] == pytest.approx(clock, abs=1e-9)  # the clock stood still
    assert sim.game["phase"] == "paused"
    ref.resume()
    sim.run(seconds=0.5)
    assert heard["magenta"][-1].match_mode == MatchMode.STARTROBOT
    assert sim.game["phase"] == "play" and sim.game["clock"] == pytest.approx(clock + 0.5, abs=0.006)
    ops = [e for e in sim.events if e["type"] == "operator"]
    assert [e["detail"].split(" (by")[0] for e in ops] == ["command STARTROBOT", "pause", "resume"]


def test_any_command_mirrored_per_team_and_the_ball_placed(match):
    sim, heard = match()
    ref = sim.judge
    ref.command("opp corner", team="magenta", spot=(-10.7, 6.7))  # a corner for cyan, said from magenta's side
    sim.step()
    assert heard["cyan"][-1].match_mode == MatchMode.OUR_CORNERKICK
    assert heard["magenta"][-1].match_mode == MatchMode.OPP_CORNERKICK
    ball = sim.model_states()["ball"]
    assert (ball.x, ball.y) == pytest.approx((-10.7, 6.7))
    c = heard["cyan"][-1]
    assert (c.ball_x, c.ball_y) == pytest.approx((-10.7, 6.7))  # cyan's team frame = world
    m = heard["magenta"][-1]
    assert (m.ball_x, m.ball_y) == pytest.approx((10.7, -6.7))  # magenta's is turned by pi
    ref.place_ball(-9.0, 5.0)
    sim.step()
    assert sim.game["restart"] == "corner kick for cyan at (-9.00, 5.00)"
    ball = sim.model_states()["ball"]
    assert (ball.x, ball.y) == pytest.approx((-9.0, 5.0))


def test_send_off_parks_and_disables_and_return_brings_back(match):
    sim, _ = match()
    ref = sim.judge
    ref.send_off("cyan/3")
    sim.step()
    s = sim.model_states()["cyan/3"]
    assert s.y < -7.0 and sim.game["sent_off"] == ["cyan/3"]
    sim.take_control("cyan/3")
    sim.send_vel("cyan/3", 2.0, 0.0, 0.0)  # a sent-off robot does not move
    sim.run(seconds=0.5)
    assert sim.model_states()["cyan/3"].x == pytest.approx(s.x, abs=1e-6)
    ref.return_robot("cyan/3")
    sim.run(seconds=0.5)
    back = sim.model_states()["cyan/3"]
    assert abs(back.y) < 7.0 and back.x < 0 and sim.game["sent_off"] == []  # own half, on the field
    assert back.x > s.x + 0.5 or back.y > s.y + 0.5  # and it moves again
    assert {"send_off", "robot_returned"} <= set(types(sim))


def test_manual_mode_proposes_and_the_operator_decides(match):
    sim, heard = match()
    ref = sim.judge
    ref.command("STARTROBOT")
    ref.set_auto(False)
    assert sim.game["manual"]
    sim.take_control("cyan/2")
    sim.set_model_state("cyan/2", x=-9.5, y=1.0, yaw=0.0)
    sim.send_vel("cyan/2", -1.0, 0.0, 0.0)  # into its own goal area
    sim.run(seconds=1.5)
    proposals = [e for e in sim.events if e["type"] == "proposal"]
    assert proposals and proposals[0]["team"] == "cyan" and "goal_area" in proposals[0]["detail"]
    assert "goal_area" not in types(sim) and sim.game["fouls"]["cyan"] == 0  # not enforced
    assert heard["cyan"][-1].match_mode == MatchMode.STARTROBOT and sim.game["phase"] == "play"
    ref.command("OUR_FREEKICK", team="magenta")
    sim.run(seconds=3.0)  # no automatic START in manual mode
    assert sim.game["phase"] == "prepare"
    ref.command("STARTROBOT")
    assert sim.game["phase"] == "taking"
    ref.award_goal("magenta")
    assert sim.game["score"] == {"cyan": 0, "magenta": 1}


def test_operator_requests_on_the_bus(match):
    sim, heard = match()
    pub = sim.bus.publisher(topics.REFEREE_COMMAND, msgs.RefereeCommand)

    def send(**fields):
        pub.put(msgs.new(msgs.RefereeCommand, source="web", **fields))
        sim.step()

    send(op="command", team="cyan", command=int(MatchMode.OUR_FREEKICK), x=2.0, y=-3.0, has_position=True)
    assert heard["cyan"][-1].match_mode == MatchMode.OUR_FREEKICK
    assert sim.game["restart"] == "free kick for cyan at (2.00, -3.00)"
    send(op="pause")
    assert sim.game["paused"]
    send(op="resume")
    send(op="card", team="magenta", robot=4, card="yellow")
    assert sim.game["yellow_cards"]["magenta"] == 1
    send(op="send_off", team="magenta", robot=4, seconds=30.0)
    assert sim.game["sent_off"] == ["magenta/4"]
    send(op="auto", on=False)
    assert sim.game["manual"]
    ops = [e for e in sim.events if e["type"] == "operator"]
    assert len(ops) == 6 and all(e["detail"].endswith("(by web)") for e in ops)


@pytest.mark.parametrize(
    "fields, reason",
    [
        ({"op": "dance"}, "unknown operator request"),
        ({"op": "command", "command": 99}, "no game command numbered 99"),
        ({"op": "command", "command": int(MatchMode.OUR_FREEKICK)}, "needs the team"),
        ({"op": "command", "command": int(MatchMode.TEST)}, "TEST"),
        ({"op": "card", "team": "cyan", "robot": 9, "card": "yellow"}, "no robot named 'cyan/9'"),
        ({"op": "card", "team": "cyan", "robot": 2, "card": "green"}, "'yellow' or 'red'"),
        ({"op": "place_ball", "x": math.nan, "y": 0.0}, "finite"),
        ({"op": "place_ball", "x": 40.0, "y": 0.0}, "not on the floor"),
        ({"op": "send_off", "team": "blue", "robot": 2}, "no team named 'blue'"),
        ({"op": "send_off", "team": "cyan", "robot": 2, "seconds": -5.0}, "positive"),
        ({"op": "return", "team": "cyan", "robot": 2}, "not sent off"),
        ({"op": "goal"}, "needs the team"),
    ],
)
def test_bad_operator_requests_are_refused_with_a_reason(match, fields, reason):
    sim, _ = match()
    game = sim.game
    sim.bus.publisher(topics.REFEREE_COMMAND, msgs.RefereeCommand).put(msgs.new(msgs.RefereeCommand, **fields))
    sim.step()
    refused = [e for e in sim.events if e["type"] == "operator_refused"]
    assert len(refused) == 1 and reason in refused[0]["detail"], refused
    assert "operator" not in types(sim)
    after = sim.game
    assert {k: after[k] for k in ("score", "sent_off", "yellow_cards", "phase")} == {
        k: game[k] for k in ("score", "sent_off", "yellow_cards", "phase")
    }
    sim.run(seconds=0.1)  # the run goes on


def test_the_api_raises_for_a_bad_request(match):
    sim, _ = match()
    with pytest.raises(OperatorError, match="no robot named 'cyan/7'"):
        sim.judge.send_off("cyan/7")
    with pytest.raises(ValueError, match="unknown game command"):
        sim.judge.command("hop")


def test_no_request_after_the_match(match):
    sim, _ = match(**{"match.halves": 1, "match.half_duration": 1.0})
    sim.run()
    assert sim.done and sim.game["phase"] == "ended"
    with pytest.raises(OperatorError, match="the match is over"):
        sim.judge.command("STARTROBOT")
