"""The referee in a whole run: msl_5v5 is refereed by default and ends by itself; `simatch run --json` carries
score, fouls and every event; the GameState topic explains the game; settings are checked; runs repeat."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import simatch
from simatch import msgs
from simatch.bus import topics
from simatch.config.loader import SceneError
from simatch.scene.referee.log import FOUL_TYPES

SHORT = {"match.half_duration": 6.0, "match.half_time": 1.0, "judge.stop_time": 0.5, "judge.kickoff_prepare_time": 3.0}


def test_msl_5v5_is_refereed_and_lasts_a_full_match():
    with simatch.Simulation("msl_5v5") as sim:
        assert sim.judge.name == "msl_referee" and sim.coaches == {}
        assert sim.scene.spec.duration is None
        assert sim.duration == pytest.approx(2 * 900 + 10, abs=0.1)  # 2 x 15 min and the break


def test_run_json_carries_score_fouls_and_every_event():
    # robots that stay at their start poses (the default teams would take legal positions): both halves begin
    # without a foul (the start poses keep the kick-off distances for the kicking and the defending team alike,
    # docs/referee.md "Kick-off positions"), and the teams change ends at half time
    still = {"teams.cyan.strategy": "startpose", "teams.magenta.strategy": "startpose"}
    args = ["run", "msl_5v5", "--json", "--seed", "3"] + [f"--set={k}={v}" for k, v in {**SHORT, **still}.items()]
    proc = subprocess.run([sys.executable, "-m", "simatch", *args], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    out = json.loads(proc.stdout)
    r = out["result"]
    assert r["score"] == {"cyan": 0, "magenta": 0}
    assert set(r["fouls"]) == {"cyan", "magenta"} and all(isinstance(v, int) for v in r["fouls"].values())
    assert r["ended"] and r["stage"] == "ended" and r["winner"] is None
    assert out["sim_seconds"] == pytest.approx(13.0, abs=0.01)  # 6 + 1 + 6: the referee ended it
    kinds = [e["type"] for e in out["events"]]
    assert kinds[0] == "stage" and kinds[-1] == "match_end"
    assert {"command", "ball_placed", "ends_changed"} <= set(kinds)
    assert r["fouls"] == {"cyan": 0, "magenta": 0}
    assert not [e for e in out["events"] if e["type"] in FOUL_TYPES]
    kickoffs = [e for e in out["events"] if e["type"] == "command" and e.get("value") == 1.0]
    assert [e["team"] for e in kickoffs] == ["cyan", "magenta"]  # the second half: the other team kicks off
    first = out["events"][0]
    assert first == {"t": 0.0, "type": "stage", "value": 6.0, "limit": 0.0, "detail": "first_half begins"}


def test_same_seed_same_match():
    def play():
        with simatch.Simulation("msl_5v5", seed=4, overrides=SHORT) as sim:
            sim.run()
            return sim.state_digest(), sim.events, sim.result()["result"]

    assert play() == play()


def test_game_state_topic_explains_the_game():
    with simatch.Simulation("msl_5v5", overrides=SHORT) as sim:
        states = []
        sim.bus.subscribe(topics.GAME_STATE, msgs.GameState, states.append)
        sim.run(seconds=4.0)
        assert states, "no GameState published"
        gaps = [b.stamp - a.stamp for a, b in zip(states, states[1:])]
        assert max(gaps) <= 1.0 + 1e-9  # at least once a second
        last = states[-1]
        assert list(last.teams) == ["cyan", "magenta"] and list(last.score) == [0, 0]
        assert last.stage == "first_half" and last.phase in ("prepare", "taking", "play")
        kickoff = [s for s in states if s.phase == "prepare"][0]
        assert kickoff.command == 1 and kickoff.command_team == "cyan"  # OUR_KICKOFF, cyan's view
        assert (kickoff.ball_x, kickoff.ball_y) == (0.0, 0.0)
        stopped = states[0]
        assert stopped.phase == "stopped" and stopped.next_command == 1 and "kick-off" in stopped.reason
        assert json.loads(last.result)["score"] == {"cyan": 0, "magenta": 0}
        game = sim.game
        assert game["commands"]["magenta"]["name"] in ("OPP_KICKOFF", "STARTROBOT")
        assert game["stage"] == "first_half" and game["time_left"] == pytest.approx(2.0, abs=0.01)


@pytest.mark.parametrize(
    "overrides, message",
    [
        ({"judge.stop_tme": 1.0}, "judge.stop_tme: unknown key"),
        ({"judge.charging_speed": -1.0}, "judge.charging_speed: expected greater than 0"),
        ({"judge.disabled_rules": ["offside"]}, "unknown rule(s) offside"),
        ({"judge.charging_card": "blue"}, "judge.charging_card"),
        ({"match.kickoff": "yellow"}, "match.kickoff names team 'yellow'"),
    ],
)
def test_referee_settings_are_checked(overrides, message):
    with pytest.raises(SceneError) as err:
        simatch.Simulation("msl_5v5", overrides=overrides)
    assert message in str(err.value) and "msl_5v5.toml" in str(err.value)


def test_the_referee_needs_two_teams(tmp_path):
    path = tmp_path / "solo.toml"
    path.write_text('name = "solo"\n[teams.cyan]\nstart = [[0.0, 0.0, 0.0]]\n[judge]\nkind = "msl_referee"\n')
    with pytest.raises(SceneError, match="msl_referee judges two teams"):
        simatch.Simulation(str(path))


def test_the_teams_must_attack_opposite_goals(tmp_path):
    path = tmp_path / "same_way.toml"
    path.write_text(
        'name = "same_way"\n[teams.blue]\nstart = [[-1.0, 0.0, 0.0]]\n'
        '[teams.yellow]\nstart = [[1.0, 0.0, 0.0]]\n[match]\nkickoff = "blue"\n'
        '[judge]\nkind = "msl_referee"\n'
    )
    with pytest.raises(SceneError, match="teams.yellow.attacks: blue and yellow both attack"):
        simatch.Simulation(str(path))
    text = path.read_text().replace("[teams.yellow]\n", '[teams.yellow]\nattacks = "-x"\n')
    path.write_text(text)
    with simatch.Simulation(str(path), overrides=SHORT) as sim:  # any team names, once they face each other
        sim.run()
        assert sim.done and set(sim.game["score"]) == {"blue", "yellow"}


def test_referee_benchmark_reports_its_figures():
    from simatch.bench.referee import run

    out = run(1.0)
    assert set(out) >= {"referee_us_per_step", "referee_overhead_us_per_step", "referee_decisions"}
    assert out["referee_us_per_step"] > 0 and out["referee_sim_seconds"] == 1.0


def test_a_match_may_begin_in_play_or_with_a_restart():
    """match.start sets up a situation (the audit's sample scenes use it): the ball in play from the first step,
    or a restart for a team at a spot; a team that the scene does not have is refused."""
    with simatch.Simulation("msl_5v5", overrides={**SHORT, "match.start": "play"}) as sim:
        sim.step()
        assert sim.game["phase"] == "play" and sim.game["commands"]["cyan"]["name"] == "STARTROBOT"
    settings = {**SHORT, "match.start": "corner_kick", "match.start_team": "magenta", "match.start_spot": [-10.7, 6.7]}
    with simatch.Simulation("msl_5v5", overrides=settings) as sim:
        sim.run(seconds=1.0)
        assert sim.game["next_restart"] is None and sim.game["restart"] == "corner kick for magenta at (-10.70, 6.70)"
        assert sim.game["commands"]["magenta"]["name"] == "OUR_CORNERKICK"
        b = sim.model_states()["ball"]
        assert (b.x, b.y) == pytest.approx((-10.7, 6.7))
    with pytest.raises(SceneError, match="match.start_team names team 'yellow'"):
        simatch.Simulation("msl_5v5", overrides={"match.start": "free_kick", "match.start_team": "yellow"})
