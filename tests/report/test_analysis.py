"""The match analysis on made-up feeds (each number known by construction), and on a real match: live and
read back from its recording it gives the same numbers, and attaching it changes nothing in the run."""

from __future__ import annotations

import numpy as np
import pytest

import simatch
from simatch.field import FieldGeometry
from simatch.record import Recorder
from simatch.report.analysis import MatchAnalysis, MatchMeta, TeamInfo
from simatch.report.live import LiveAnalysis
from simatch.report.recorded import analyse_recording

DT = 0.005
CONTROL = 0.025
STEPS = 5  # physics steps per control tick
NAMES = ["cyan/1", "cyan/2", "magenta/1", "magenta/2", "ball"]


def meta(refereed: bool = True) -> MatchMeta:
    return MatchMeta(
        scene="test",
        seed=0,
        teams=[TeamInfo("cyan", "cyan", "a", 1, 1), TeamInfo("magenta", "magenta", "b", 1, -1)],
        field=FieldGeometry(),
        dt=DT,
        control_period=CONTROL,
        refereed=refereed,
    )


class Feed:
    """Feeds a MatchAnalysis tick by tick with positions and velocities set per model."""

    def __init__(self, refereed: bool = True):
        self.a = MatchAnalysis(meta(refereed))
        self.pos = {n: np.array([0.0, 0.0]) for n in NAMES}
        self.vel = {n: np.array([0.0, 0.0]) for n in NAMES}
        self.pos.update({"cyan/1": np.array([-10.0, 0.0]), "magenta/1": np.array([10.0, 0.0])})
        self.step = 0

    def tick(self, n: int = 1) -> None:
        for _ in range(n):
            pose = np.zeros((len(NAMES), 7), np.float32)
            twist = np.zeros((len(NAMES), 6), np.float32)
            for k, name in enumerate(NAMES):
                pose[k, :2] = self.pos[name]
                twist[k, :2] = self.vel[name]
            self.a.states(self.step, NAMES, pose, twist)
            self.step += STEPS

    @property
    def t(self) -> float:
        return self.step * DT

    def touch(self, *robots: str, kicker: str = "", speed: float = 0.0) -> None:
        self.a.contacts(self.t, self.step, list(robots), "", kicker, speed, False)

    def event(self, kind: str, team: str = "", **extra) -> None:
        self.a.event({"t": self.t, "type": kind, **({"team": team} if team else {}), **extra})

    def state(self, phase: str, stage: str = "first_half", score=(0, 0)) -> None:
        self.a.game_state(self.t, stage, phase, score)


def test_possession_is_the_last_team_to_touch_alone_while_in_play():
    f = Feed()
    f.state("stopped")
    f.tick(10)  # 0.25 s
    f.state("play")
    f.tick(10)  # 0.5 s
    f.touch("cyan/2")
    f.tick(60)  # 2.0 s
    f.touch("magenta/2")
    f.tick(40)  # 3.0 s
    f.touch("cyan/2", "magenta/2")  # a duel: the ball stays with magenta
    f.tick(20)  # 3.5 s
    f.state("stopped")
    f.tick(20)  # 4.0 s: not in play, nobody's
    out = f.a.finish()
    assert out["possession"]["seconds"] == pytest.approx({"cyan": 1.5, "magenta": 1.5})
    assert out["possession"]["share"] == {"cyan": 0.5, "magenta": 0.5}
    assert out["play_seconds"] == pytest.approx(3.25)
    bins = out["possession"]["bins"]
    assert sum(b["seconds"]["cyan"] for b in bins) == pytest.approx(1.5)
    # stages and phases
    assert [p["phase"] for p in out["phases"]] == ["stopped", "play", "stopped"]
    assert out["phases"][1]["t0"] == pytest.approx(0.25) and out["phases"][1]["t1"] == pytest.approx(3.5)


def kick(f: Feed, robot: str, at, velocity, speed: float = 8.0):
    f.pos["ball"] = np.array(at, float)
    f.vel["ball"] = np.array(velocity, float)
    f.touch(robot, kicker=robot, speed=speed)
    f.tick()
    f.vel["ball"] = np.array([0.0, 0.0])


def test_shots_their_outcomes_and_what_is_no_shot():
    f = Feed(refereed=False)
    f.tick(4)
    kick(f, "cyan/2", (7.0, 1.0), (8.0, -0.5))  # heads for magenta's goal (+x): a shot
    f.tick(10)
    f.event("goal", "cyan", detail="goal for cyan")
    f.tick(40)
    kick(f, "cyan/2", (6.0, 0.0), (8.0, 0.0))  # saved by magenta's goalkeeper (id 1)
    f.tick(8)
    f.touch("magenta/1")
    f.tick(40)
    kick(f, "magenta/2", (-5.0, 2.0), (-7.0, -1.0))  # magenta attacks -x: blocked by cyan/2
    f.tick(8)
    f.touch("cyan/2")
    f.tick(40)
    kick(f, "cyan/2", (5.0, 0.0), (8.0, 1.2))  # wide of the post but within a metre: off target, ball out
    f.tick(12)
    f.event("ball_out", "cyan")
    f.tick(40)
    kick(f, "cyan/2", (5.0, 0.0), (0.5, 8.0))  # across the field: no shot
    f.tick(10)
    kick(f, "cyan/2", (0.0, 0.0), (2.0, 0.0))  # towards the goal, but rolls 4 m of the 11: a pass
    f.tick(10)
    kick(f, "cyan/2", (-2.0, 0.0), (9.0, 0.0))  # 13 m from the goal line: too far
    f.tick(10)
    kick(f, "magenta/2", (5.0, 0.0), (8.0, 0.0))  # magenta kicking towards its own goal: no shot
    f.tick(10)
    out = f.a.finish()
    shots = out["shots"]
    assert [(s["robot"], s["outcome"]) for s in shots] == [
        ("cyan/2", "goal"),
        ("cyan/2", "saved"),
        ("magenta/2", "blocked"),
        ("cyan/2", "off target"),
    ]
    assert [s["on_target"] for s in shots] == [True, True, False, False]
    assert shots[0]["x"] == pytest.approx(7.0) and shots[0]["goal_x"] == pytest.approx(11.0)
    assert shots[0]["goal_y"] == pytest.approx(1.0 - 0.5 * 4.0 / 8.0)
    assert shots[2]["goal_x"] == pytest.approx(-11.0)  # magenta shoots at cyan's goal, on the left
    s = out["summary"]
    assert (s["cyan"]["shots"], s["cyan"]["on_target"], s["magenta"]["shots"]) == (3, 2, 1)


def test_after_the_change_of_ends_play_is_mirrored_onto_the_end_each_team_attacks():
    f = Feed(refereed=False)
    f.pos["cyan/2"] = np.array([5.0, 1.0])  # cyan attacks +x: in the attacking half
    f.tick(40)  # 1 s
    f.a.sides(f.t, {"cyan": -1, "magenta": 1})
    f.pos["cyan/2"] = np.array([-5.0, -1.0])  # after the change cyan attacks -x: the same place for cyan
    f.tick(40)
    kick(f, "cyan/2", (-6.0, 0.0), (-8.0, 0.0))  # a shot at the goal at -x, which cyan now attacks
    f.tick(10)
    out = f.a.finish()
    heat = np.array(out["heat"]["maps"]["cyan"])
    xe, ye = out["heat"]["x_edges"], out["heat"]["y_edges"]
    col = int(np.searchsorted(xe, 5.0, side="right") - 1)
    row = int(np.searchsorted(ye, 1.0, side="right") - 1)
    # all of cyan/2's play lands on one cell at (5, 1) in the view (cyan attacks to the right): the samples but
    # the last (the run's end is not in play)
    assert heat[row, col] == pytest.approx((len(f.a._t) - 1) * CONTROL)
    mirrored_col = int(np.searchsorted(xe, -5.0, side="right") - 1)
    mirrored_row = int(np.searchsorted(ye, -1.0, side="right") - 1)
    assert heat[mirrored_row, mirrored_col] == 0
    (shot,) = out["shots"]
    assert shot["x"] == pytest.approx(6.0) and shot["goal_x"] == pytest.approx(11.0)
    assert out["sides"][1] == {"t": pytest.approx(1.0), "signs": {"cyan": -1, "magenta": 1}}


def test_distance_top_speed_and_role_time():
    f = Feed(refereed=False)
    for _ in range(40):  # 1 m/s along x for one second
        f.pos["cyan/2"] = f.pos["cyan/2"] + np.array([CONTROL, 0.0])
        f.vel["cyan/2"] = np.array([1.0, 0.0])
        f.tick()
    f.pos["cyan/2"] = np.array([-11.0, -8.0])  # placed off the field (sent off): no distance run
    f.vel["cyan/2"] = np.array([3.0, 4.0])
    f.tick(2)
    for k in range(41):
        f.a.strategy(k * CONTROL, "cyan/2", 1 if k < 20 else 2)  # each message holds until the next
    out = f.a.finish()
    robot = next(r for r in out["robots"] if r["name"] == "cyan/2")
    assert robot["distance"] == pytest.approx(39 * CONTROL, abs=0.01)  # rounded to the centimetre
    assert robot["top_speed"] == pytest.approx(5.0)
    assert out["roles"]["cyan/2"] == pytest.approx({"ACTIVE": 0.5, "PASSIVE": 0.5})


@pytest.mark.slow
def test_live_and_recorded_analyses_agree_and_the_run_is_unchanged(tmp_path):
    overrides = {"match.half_duration": 12, "match.half_time": 2, "teams.magenta.strategy": "simple"}
    with simatch.Simulation("msl_5v5", seed=4, overrides=overrides) as plain:
        plain.run()
        digest = plain.state_digest()
    path = tmp_path / "m.mcap"
    with simatch.Simulation("msl_5v5", seed=4, overrides=overrides) as sim, Recorder.for_run(sim, path):
        live = LiveAnalysis.attach(sim)
        sim.run()
        out = sim.result()
    assert out["state_digest"] == digest  # the analysis only reads
    a = live.finish(out)
    b, rec = analyse_recording(path)
    assert not rec.problems
    for key in a:
        if key in ("sim_seconds", "wall_seconds"):
            continue
        assert a[key] == b[key], key
    assert b["state_digest"] == digest
    assert a["play_seconds"] > 5 and a["possession"]["share"]["cyan"] is not None
    assert sum(r["distance"] for r in a["robots"] if r["team"] == "cyan") > 10


def test_the_side_each_team_attacks_comes_from_the_referees_game_state():
    """GameState.attacks ("+x"/"-x" per team) moves the analysis to the other end after the change of ends; a
    GameState without it (a producer that predates the field) leaves the scene's sides."""
    from types import SimpleNamespace

    f = Feed()
    state = {"stage": "first_half", "phase": "play", "teams": ["cyan", "magenta"], "score": [0, 0]}
    f.a.game_state_message(SimpleNamespace(stamp=0.0, **state))  # no attacks field at all
    f.a.game_state_message(SimpleNamespace(stamp=0.5, attacks=["+x", "-x"], **state))
    f.tick(40)
    f.a.game_state_message(SimpleNamespace(stamp=f.t, attacks=["-x", "+x"], **{**state, "stage": "second_half"}))
    f.tick(10)
    out = f.a.finish()
    assert [s["signs"] for s in out["sides"]] == [{"cyan": 1, "magenta": -1}, {"cyan": -1, "magenta": 1}]
    assert out["sides"][1]["t"] == pytest.approx(1.0)
    assert [s["stage"] for s in out["stages"]] == ["first_half", "second_half"]
