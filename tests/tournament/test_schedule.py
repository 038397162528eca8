"""Teams, schedules (round robin, league, knockout), Elo and the standing: the tournament's logic without
playing (the matches' rows are made up here; test_ray.py plays real ones)."""

from __future__ import annotations

import itertools
from collections import Counter
from pathlib import Path

import numpy as np
import pytest

from simatch.config.loader import load_scene
from simatch.errors import UsageError
from simatch.tournament import elo
from simatch.tournament.entries import Entry, parse_entries, parse_entry
from simatch.tournament.schedule import MAX_DECIDERS, Knockout, League, MatchContext, RoundRobin, matchdays
from simatch.tournament.standing import standing

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def ctx(labels: list[str]) -> MatchContext:
    """Teams that differ only by a (made-up) parameter: enough for schedules that are never played."""
    entries = [Entry(label=name, strategy="simple", strategy_params={"variant": k}) for k, name in enumerate(labels)]
    scene = load_scene("msl_5v5")
    return MatchContext(scene.text, scene.source, {}, ("cyan", "magenta"), entries)


# --- teams -------------------------------------------------------------------------------------------------
def test_entries_of_every_kind(monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLES))
    scene = EXAMPLES / "striker_vs_simple.toml"
    a, b, c = parse_entries(["nubot,striker:StrikerTeam", f"{scene}:cyan"])
    (d,) = [parse_entry(f"slow={scene}:cyan")]
    assert (a.label, a.strategy) == ("nubot", "nubot")
    assert (b.label, b.strategy) == ("striker:StrikerTeam", "striker:StrikerTeam")
    assert c.label == "striker_vs_simple:cyan"
    assert c.strategy == "striker:StrikerTeam" and c.strategy_params == {"speed": 3.0, "shoot_from": 5.0}
    assert d.label == "slow" and d.identity() == c.identity()  # a name is not part of what plays
    assert c.overrides("magenta")["teams.magenta.strategy_params"] == {"speed": 3.0, "shoot_from": 5.0}
    # a plain name clears the scene's parameters of the colour it plays on
    assert a.overrides("cyan") == {"teams.cyan.strategy": "nubot", "teams.cyan.strategy_params": {}}


@pytest.mark.parametrize(
    "teams, message",
    [
        ("nubot", "at least two teams"),
        ("nubot,nubot", "two teams are named 'nubot'"),
        ("nubot,other=nubot", "the same strategy with the same parameters"),
        ("nubot,nubbot", "unknown strategy 'nubbot'"),
        ("nubot,nosuchmodule:Team", "cannot import module 'nosuchmodule'"),
        ("nubot,none", "must play"),
        ("nubot,=simple", "name before '=' is empty"),
        ("nubot,x=", "nothing to play"),
        ("nubot,missing.toml:cyan", "does not exist"),
        ("nubot,{scene}:blue", "has no team 'blue'"),
    ],
)
def test_bad_teams_are_refused_with_one_line(teams, message):
    teams = teams.format(scene=EXAMPLES / "striker_vs_simple.toml")
    with pytest.raises(UsageError, match=message) as info:
        parse_entries([teams])
    assert "\n" not in str(info.value)


def test_bad_strategy_params_of_a_scene_team(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(EXAMPLES))
    scene = tmp_path / "fast.toml"
    scene.write_text('[teams.cyan]\nstrategy = "striker:StrikerTeam"\nstrategy_params = { speed = 60.0 }\n')
    with pytest.raises(UsageError, match="speed"):
        parse_entries([f"nubot,{scene}:cyan"])


# --- formats -------------------------------------------------------------------------------------------------
def test_round_robin_plays_every_pairing_both_ways_for_every_seed():
    c = ctx(["a", "b", "c", "d"])
    rr = RoundRobin(c, [0, 1, 2])
    assert len(rr.matches) == 6 * 2 * 3
    seen = Counter((m.home, m.away) for m in rr.matches)
    assert set(seen) == {(i, j) for i, j in itertools.permutations(range(4), 2)}
    assert set(seen.values()) == {3}
    assert len({m.match_id for m in rr.matches}) == len(rr.matches)
    # seed after seed: after the first seed's matches every pairing has played once each way
    assert {m.seed for m in rr.matches[:12]} == {0}
    # the identity does not depend on the other teams or seeds of the tournament
    other = RoundRobin(ctx(["a", "b"]), [2])
    assert {m.match_id for m in other.matches} <= {m.match_id for m in rr.matches}


def test_match_identity_follows_what_decides_the_match():
    scene = load_scene("msl_5v5")
    entries = parse_entries(["nubot,simple"])
    base = MatchContext(scene.text, scene.source, {}, ("cyan", "magenta"), entries).match_id(0, 1, 3)
    assert base == MatchContext(scene.text, scene.source, {}, ("cyan", "magenta"), entries).match_id(0, 1, 3)
    assert base != MatchContext(scene.text, scene.source, {}, ("cyan", "magenta"), entries).match_id(1, 0, 3)
    assert base != MatchContext(scene.text, scene.source, {}, ("cyan", "magenta"), entries).match_id(0, 1, 4)
    longer = {"match.half_duration": 60}
    assert base != MatchContext(scene.text, scene.source, longer, ("cyan", "magenta"), entries).match_id(0, 1, 3)


@pytest.mark.parametrize("n", [2, 3, 4, 5, 6, 7])
def test_matchdays_have_every_team_at_most_once(n):
    days = matchdays(n)
    assert len(days) == (n - 1 if n % 2 == 0 else n)
    for day in days:
        teams = [t for pair in day for t in pair]
        assert len(teams) == len(set(teams))
        assert len(day) == n // 2
    pairs = [p for day in days for p in day]
    assert sorted(pairs) == sorted(itertools.combinations(range(n), 2))


def test_league_is_the_round_robin_in_matchdays():
    c = ctx(["a", "b", "c", "d"])
    league = League(c, [0, 1])
    assert sorted(m.match_id for m in league.matches) == sorted(m.match_id for m in RoundRobin(c, [0, 1]).matches)
    assert league.matches[0].stage == "matchday 1" and league.matches[-1].stage == "matchday 6"
    assert league.describe({})["matchdays"] == 6


def ok(m, home_goals: int, away_goals: int) -> dict:
    return {"match_id": m.match_id, "status": "ok", "home_goals": home_goals, "away_goals": away_goals, "seed": m.seed}


def test_knockout_with_byes_rounds_and_a_champion():
    c = ctx(["a", "b", "c", "d", "e"])  # 5 teams: a bracket of 8, byes for the top three seeds
    ko = Knockout(c, [0, 1])
    rounds = ko.bracket({})
    assert [t.round for t in rounds[0]] == ["quarter-final"] * 4
    byes = [t for t in rounds[0] if t.how == "bye"]
    assert sorted(t.winner for t in byes) == [0, 1, 2]
    wave = ko.wave({})
    assert len(wave) == 4 and {(m.home, m.away) for m in wave} == {(3, 4), (4, 3)}
    results = {}
    # the lower seed (e) wins its tie: it meets the top seed (a) in a semi-final
    for m in wave:
        results[m.match_id] = ok(m, *((0, 2) if m.home == 3 else (2, 0)))
    semis = ko.wave(results)
    assert {frozenset((m.home, m.away)) for m in semis} == {frozenset((0, 4)), frozenset((1, 2))}
    for m in semis:  # the higher seed wins every semi-final match 1-0
        high = min(m.home, m.away)
        results[m.match_id] = ok(m, *((1, 0) if m.home == high else (0, 1)))
    final = ko.wave(results)
    assert {frozenset((m.home, m.away)) for m in final} == {frozenset((0, 1))}
    assert {m.stage for m in final} == {"final"}
    for m in final:
        results[m.match_id] = ok(m, *((3, 0) if m.home == 1 else (0, 3)))
    assert ko.wave(results) == []
    assert ko.describe(results)["champion"] == "b"


def test_knockout_tie_level_goes_to_deciders_then_to_the_higher_seed():
    c = ctx(["a", "b"])
    ko = Knockout(c, [0])
    results = {m.match_id: ok(m, 1, 1) for m in ko.wave({})}
    decider = ko.wave(results)
    assert len(decider) == 1 and decider[0].seed == 1 and decider[0].stage == "final decider"
    # deciders go on while they are drawn, colours alternating, up to MAX_DECIDERS
    for k in range(MAX_DECIDERS):
        (m,) = ko.wave(results)
        assert m.seed == 1 + k and (m.home, m.away) == ((0, 1) if k % 2 == 0 else (1, 0))
        results[m.match_id] = ok(m, 0, 0)
    assert ko.wave(results) == []
    final = ko.bracket(results)[-1][0]
    assert final.winner == 0 and "higher seed" in final.how
    # a decider won settles it
    results2 = {m.match_id: ok(m, 1, 1) for m in ko.wave({})}
    (m,) = ko.wave(results2)
    results2[m.match_id] = ok(m, 0, 2)  # the away side (b) wins the first decider
    assert ko.bracket(results2)[-1][0].winner == 1


# --- Elo and the standing -----------------------------------------------------------------------------------------
def test_elo_orders_teams_and_stays_finite_for_a_perfect_record():
    games = []
    for seed in range(10):
        games += [(0, 1, 1.0, seed), (0, 2, 1.0, seed), (1, 2, 1.0 if seed % 3 else 0.5, seed), (1, 0, 0.0, seed)]
    r = elo.ratings(3, games)
    assert r["rating"][0] > r["rating"][1] > r["rating"][2]
    assert np.all(np.isfinite(r["rating"])) and abs(r["rating"].mean() - 1500) < 1e-6
    assert np.all(r["low"] <= r["rating"] + 1e-9) and np.all(r["rating"] <= r["high"] + 1e-9)
    again = elo.ratings(3, games)
    assert np.array_equal(again["low"], r["low"]) and np.array_equal(again["high"], r["high"])


def test_elo_of_equal_teams_is_1500_and_the_interval_narrows_with_more_seeds():
    draws = [(0, 1, 0.5, s) for s in range(4)]
    assert np.allclose(elo.ratings(2, draws)["rating"], 1500)

    def width(seeds):
        games = [(0, 1, 1.0 if (s % 3) else 0.0, s) for s in range(seeds)]
        r = elo.ratings(2, games)
        return r["high"][0] - r["low"][0]

    assert width(60) < width(6)


def test_standing_points_goals_head_to_head_and_failed_matches():
    rows = [
        {"home": "a", "away": "b", "status": "ok", "home_goals": 2, "away_goals": 0, "seed": 0},
        {"home": "b", "away": "a", "status": "ok", "home_goals": 1, "away_goals": 1, "seed": 0},
        {"home": "a", "away": "c", "status": "ok", "home_goals": 0, "away_goals": 1, "seed": 0},
        {
            "home": "c",
            "away": "b",
            "status": "error",
            "home_goals": None,
            "away_goals": None,
            "seed": 0,
            "error": "RuntimeError: boom",
            "match_id": "x",
            "stage": "round robin",
        },
    ]
    s = standing(["a", "b", "c"], rows)
    table = {t["team"]: t for t in s["standing"]}
    assert (table["a"]["points"], table["a"]["goal_difference"], table["a"]["played"]) == (4, 1, 3)
    assert (table["c"]["points"], table["c"]["failed"]) == (3, 1)
    assert (table["b"]["points"], table["b"]["goals_for"], table["b"]["goals_against"]) == (1, 1, 3)
    assert [t["team"] for t in s["standing"]] == ["a", "c", "b"]
    assert s["head_to_head"]["a"]["b"] == dict(played=2, won=1, drawn=1, lost=0, goals_for=3, goals_against=1, points=4)
    assert s["scores"]["a vs b"] == {"1-1": 1, "2-0": 1}
    assert s["scores"]["a vs c"] == {"0-1": 1}
    assert [f["error"] for f in s["failed"]] == ["RuntimeError: boom"]
