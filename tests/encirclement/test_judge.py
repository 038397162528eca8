"""The encirclement judge: a target whose centre is in the prison is captured and frozen, every capture is
logged and announced on game_state, the run ends when all are captured or at the time limit, the start is
scattered from the seed, and a scene with a mistake is refused with its file and key named."""

from __future__ import annotations

import json
import math

import pytest

import simatch
from simatch.config.loader import SceneError

from .conftest import IDLE, target_positions


def captures(sim) -> list[dict]:
    return [e for e in sim.events if e["type"] == "capture"]


def test_a_target_in_the_prison_is_captured_and_frozen(encirclement):
    sim = encirclement(idle=True)
    sim.set_model_state("magenta/3", x=6.5, y=0.5, yaw=0.0)
    sim.run(0.2)
    [ev] = captures(sim)
    assert ev["team"] == "magenta" and ev["robot"] == 3 and ev["value"] == 1.0 and ev["limit"] == 7.0
    assert (ev["x"], ev["y"]) == pytest.approx((6.5, 0.5), abs=1e-3)
    r = sim.result()["result"]
    assert r["captured"] == 1 and r["targets"] == 7 and r["capture_time_s"] is None
    assert r["captures"][0]["robot"] == "magenta/3"
    # frozen: its own commands do nothing, and a chaser driving into it at full traction does not move it
    sim.take_control("magenta/3")
    sim.send_vel("magenta/3", -2.0, 1.0, 1.0)
    sim.set_model_state("cyan/5", x=5.6, y=0.5, yaw=0.0)
    sim.take_control("cyan/5")
    sim.send_vel("cyan/5", 2.0, 0.0, 0.0)
    sim.run(2.0)
    x, y = target_positions(sim)["magenta/3"]
    assert (x, y) == pytest.approx((6.5, 0.5), abs=0.02)
    assert sim.model_states()["cyan/5"].x < 6.5 - 0.45  # the chaser stopped against it


def test_the_centre_decides_a_target_astride_the_line_is_free(encirclement):
    sim = encirclement(idle=True)
    sim.set_model_state("magenta/1", x=4.9, y=0.0)  # its body overlaps the prison, its centre does not
    sim.set_model_state("magenta/2", x=5.1, y=2.15)  # beside the prison's corner
    sim.run(0.5)
    assert captures(sim) == []


def test_all_captured_ends_the_run_at_the_last_capture(encirclement):
    sim = encirclement(idle=True)
    spots = [(5.5, -1.5), (5.5, 0.0), (5.5, 1.5), (6.5, -0.8), (6.5, 0.8), (7.5, -1.5), (7.5, 1.5)]
    names = sorted(target_positions(sim))
    for k, (name, (x, y)) in enumerate(zip(names, spots)):
        sim.set_model_state(name, x=x, y=y)
        sim.run(0.5)
        assert sim.done == (k == len(spots) - 1)
    last = sim.time - sim.dt
    sim.run(5.0)  # the run is over: nothing more happens
    r = sim.result()["result"]
    assert r["captured"] == 7 and r["end"] == "all_captured"
    assert r["capture_time_s"] == pytest.approx(max(c["t"] for c in r["captures"]))
    assert r["capture_time_s"] <= last + 1e-9 and sim.time == pytest.approx(last + sim.dt)
    assert [e["type"] for e in sim.events][-1] == "all_captured"


def test_the_time_limit_ends_the_run_with_nobody_captured(encirclement):
    sim = encirclement(idle=True, **{"judge.time_limit": 1.5})
    assert sim.duration == 1.5
    sim.run()
    assert sim.time == pytest.approx(1.5)
    r = sim.result()["result"]
    assert r["captured"] == 0 and r["capture_time_s"] is None and r["end"] == "time_limit"
    assert r["time_limit_s"] == 1.5


def test_the_judge_starts_both_teams_and_tells_them_every_capture(encirclement):
    sim = encirclement()
    sim.run(0.1)
    chaser = sim.robot_nodes["cyan/1"].world
    target = sim.robot_nodes["magenta/2"].world
    assert chaser.match_mode == target.match_mode == 15  # STARTROBOT
    sim.set_model_state("magenta/4", x=7.0, y=-1.0)
    sim.run(0.2)
    for world in (chaser, target):
        game = world.game
        assert game.stage == "encirclement"
        told = json.loads(game.result)
        assert [c["robot"] for c in told["captures"]] == ["magenta/4"]
    # each robot reads the capture in its own team frame (magenta's is turned by pi)
    assert json.loads(chaser.game.result)["captures"][0]["x"] == pytest.approx(7.0, abs=1e-3)


def test_the_start_is_scattered_from_the_seed(encirclement):
    a, b, c = encirclement(seed=4, idle=True), encirclement(seed=4, idle=True), encirclement(seed=5, idle=True)
    pa, pb, pc = target_positions(a), target_positions(b), target_positions(c)
    assert pa == pb and pa != pc
    spec = a.scene.spec
    x0, y0, x1, y1 = spec.judge.model_extra["scatter"]
    spacing = spec.judge.model_extra["scatter_spacing"]
    chasers = [(x, y) for x, y, _ in spec.teams["cyan"].start]
    spots = list(pa.values())
    for i, (x, y) in enumerate(spots):
        assert x0 <= x <= x1 and y0 <= y <= y1
        assert not (5.0 - spacing <= x and -2.0 - spacing <= y <= 2.0 + spacing)  # away from the prison
        others = spots[:i] + spots[i + 1 :] + chasers
        assert min(math.hypot(x - ox, y - oy) for ox, oy in others) >= spacing - 1e-9


def test_without_scatter_the_targets_start_at_their_start_poses(tmp_path):
    from simatch.config.loader import resolve

    _, text = resolve("encirclement_9v7")
    path = tmp_path / "fixed_start.toml"
    path.write_text("\n".join(line for line in text.splitlines() if not line.startswith("scatter")))
    with simatch.Simulation(str(path), seed=3, overrides=IDLE) as sim:
        starts = sorted(tuple(p[:2]) for p in sim.scene.spec.teams["magenta"].start)
        placed = sorted(target_positions(sim).values())
        assert max(math.dist(a, b) for a, b in zip(placed, starts)) < 1e-9


@pytest.mark.parametrize(
    "key, value, expected",
    [
        ("judge.prison", "jail", "judge.prison: the world has no area named 'jail' (world.areas: prison)"),
        ("judge.chasers", "blue", "judge.chasers: the scene has no team 'blue' (teams: cyan, magenta)"),
        ("judge.targets", "cyan", "chasers and targets must be different teams"),
        ("judge.scatter", [-9.0, -5.0, 0.0, 5.0], "judge.scatter: [-9.0, -5.0, 0.0, 5.0] is not inside the arena"),
        ("judge.scatter", [1.0, -5.0, 0.0, 5.0], "expected x0 < x1 and y0 < y1"),
        ("judge.time_limit", -1.0, "judge.time_limit: expected greater than 0"),
        ("judge.capture", 1, "judge.capture: unknown key"),
        ("judge.scatter_spacing", 5.0, "judge.scatter: no room for 7 targets 5 m apart"),
    ],
)
def test_mistakes_are_refused_with_file_and_key(key, value, expected):
    with pytest.raises(SceneError) as err:
        simatch.Simulation("encirclement_9v7", overrides={key: value})
    msg = str(err.value)
    assert "encirclement_9v7.toml" in msg and expected in msg, msg
