"""The referee keeps any match going (FIFA Law 12 as MSL keeps it, and a guard for what no rule covers):
whatever a team does at restarts, a whole refereed match reaches its end with the ball in play most of the
time. Teams in `teams`; each match is a short one (two halves of two minutes) of the real referee."""

from __future__ import annotations

from collections import Counter

import pytest

import simatch

TEAMS = "tests.referee.teams"
MATCH = {"match.half_duration": 120.0, "match.half_time": 5.0}


SAMPLE = 0.5  # [s] how often the game is looked at


def _play(cyan: str, magenta: str = "nubot", **overrides) -> tuple[float, dict, Counter]:
    """Play the match to its end; the share of the halves' time with the ball in play, the result, the events."""
    share, result, events, _, _ = _play_timed(cyan, magenta, **overrides)
    return share, result, events


def _play_timed(cyan: str, magenta: str = "nubot", **overrides) -> tuple[float, dict, Counter, float, object]:
    """`_play`, the longest stretch of the halves without the ball in play [s], and the referee's settings."""
    settings = {**MATCH, "teams.cyan.strategy": cyan, "teams.magenta.strategy": magenta, **overrides}
    in_play = samples = dead = longest = 0
    with simatch.Simulation("msl_5v5", seed=1, overrides=settings) as sim:
        while not sim.done:
            sim.run(SAMPLE, until_done=True)
            game = sim.game
            if game["stage"] in ("first_half", "second_half"):
                samples += 1
                in_play += bool(game["ball_in_play"])
                dead = 0 if game["ball_in_play"] else dead + 1
                longest = max(longest, dead)
        result = sim.judge.result()
        events = Counter(e["type"] for e in sim.events)
        judge = sim.judge.p
    return in_play / max(samples, 1), result, events, longest * SAMPLE, judge


def test_a_team_that_encroaches_at_every_restart_is_cautioned_and_the_match_goes_on():
    share, result, events = _play(f"{TEAMS}:EncroachingNubot")
    assert result["ended"]
    assert events["set_piece_distance"] >= 3, events
    assert result["yellow_cards"]["cyan"] >= 3 and events["send_off"] >= 1, (result, events)
    assert share > 0.5, (share, events)


def test_the_original_simatch_behaviour_plays_a_whole_match():
    """3.2 m from the ball at the opponents' set pieces, and for the ball at START whoever's restart it is:
    it stopped matches before cautions (30 retakes of one free kick, the ball in play once in 120 s)."""
    share, result, events = _play(f"{TEAMS}:OriginalSimple", f"{TEAMS}:OriginalSimple")
    assert result["ended"] and events["ball_in_play"] >= 3, events
    assert events["yellow_card"] >= 1 and events["restart_loop"] + events["send_off"] >= 1, events
    # the baseline team fouls often by itself (it dribbles too far, charges): against itself, with the
    # cautions off, the same match had the ball in play a fraction of this
    baseline, _, _ = _play(
        f"{TEAMS}:OriginalSimple",
        f"{TEAMS}:OriginalSimple",
        **{"judge.max_retakes": 100, "judge.caution_distance_at_restarts": False},
    )
    assert share > 1.5 * baseline, (share, baseline, events)


def test_a_team_that_never_takes_its_restarts_does_not_stop_the_match():
    share, result, events = _play(f"{TEAMS}:NeverTakesRestarts")
    assert result["ended"] and events["restart_timeout"] >= 1, events
    assert share > 0.5, (share, events)


def test_a_team_that_stands_still_does_not_stop_the_match():
    """Every restart of a team that never moves ends in the restart timeout, and the opponents score at will,
    each goal a kick-off of the still team: the ball is dead after each for the stop, the kick-off's
    preparation and the timeout, and never longer (how much of the match that is depends on the goals)."""
    share, result, events, longest, judge = _play_timed("none")
    assert result["ended"] and events["restart_timeout"] >= 3 and events["goal"] >= 3, events
    bound = judge.stop_time + judge.kickoff_prepare_time + judge.restart_timeout + 2.0
    assert longest <= bound, (longest, bound, events)
    assert share > 0.3, (share, events)


@pytest.mark.parametrize("max_retakes", [0, 2])
def test_no_restart_is_taken_again_more_than_max_retakes_times_in_a_row(max_retakes):
    """Without cautions (so that no robot is sent off) the guard alone ends every loop: never more than
    ``max_retakes`` retakes of one restart in a row, and each loop ended is logged with its reason."""
    settings = {**MATCH, "teams.cyan.strategy": f"{TEAMS}:EncroachingNubot", "teams.magenta.strategy": "nubot"}
    settings.update({"judge.caution_distance_at_restarts": False, "judge.max_retakes": max_retakes})
    with simatch.Simulation("msl_5v5", seed=1, overrides=settings) as sim:
        sim.run(None)
        events = sim.events
    assert not any(e["type"] == "yellow_card" and "respecting the distance" in e["detail"] for e in events)
    loops = [e for e in events if e["type"] == "restart_loop"]
    assert loops and all("ball is in play for everybody" in e["detail"] for e in loops)
    run = longest = 0
    for e in events:
        if e["type"] == "set_piece_distance" and "taken again" in e["detail"]:
            run += 1
            longest = max(longest, run)
        elif e["type"] in ("ball_in_play", "restart_timeout", "restart_loop"):
            run = 0
    assert longest <= max_retakes + 1  # the last infringement of a loop is logged, then the ball is in play
