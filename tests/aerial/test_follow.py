"""Everything else follows the drones and the new worlds: recordings re-simulate bit for bit (interventions on
drones included), the recording's 3D scene shows obstacles and drones at their heights, the Python API's
states and set/apply interface work on drones."""

from __future__ import annotations

import json
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import simatch
from simatch.record import Recorder, Recording, verify

SIMATCH = [str(Path(sys.executable).with_name("simatch"))]


def intervene(sim) -> None:
    """A chase with every kind of intervention on drones."""
    sim.run(seconds=0.5)
    sim.set_model_state("magenta/1", x=2.0, y=1.0, z=2.5, yaw=0.5, vx=1.0)  # the evader put elsewhere
    sim.apply_wrench("cyan/2", force=(0.0, 0.3, 0.2), torque=(0.0, 0.0, 1e-4), duration=0.2)
    sim.run(seconds=0.5)
    sim.take_control("cyan/3")
    sim.send_vel("cyan/3", 1.0, 0.5, 0.3, 0.8)  # with a climb
    sim.run(seconds=0.5)
    sim.set_rotor("cyan/1", 2, False)
    sim.run(seconds=0.5)
    sim.release_control("cyan/3")
    sim.run(seconds=0.5)


def test_a_recorded_chase_with_interventions_on_drones_reproduces_bit_for_bit(tmp_path):
    path = tmp_path / "chase.mcap"
    with simatch.Simulation("pursuit_evasion_3d", seed=3) as sim:
        with Recorder.for_run(sim, path, command_line=["pytest"]):
            intervene(sim)
        digest = sim.state_digest()
    # from the world's inputs alone (the drones' commands, with their climb rates, are among them) ...
    verdict = verify(path, mode="inputs")
    assert verdict.identical and verdict.complete, verdict.describe()
    calls = [c for _, _, m in Recording(path).messages(topics={"world_inputs"}) for c in m.calls]
    climbs = [json.loads(c) for c in calls if c.startswith('["command_velocity"')]
    assert climbs and all(len(args) == 5 for _, args, _ in climbs)  # (robot, vx, vy, w, vz)
    assert any('"set_rotor"' in c for c in calls)
    # ... and by running the strategies and the judge again, the interventions re-applied
    verdict = verify(path, mode="strategies")
    assert verdict.identical and verdict.operator_commands == 6, verdict.describe()
    with simatch.Simulation("pursuit_evasion_3d", seed=3) as again:  # the same calls, the same run
        intervene(again)
        assert again.state_digest() == digest


def test_the_3d_scene_shows_obstacles_and_drones_at_their_heights(tmp_path):
    path = tmp_path / "encircle.mcap"
    with simatch.Simulation("aerial_encirclement", seed=1) as sim:
        with Recorder.for_run(sim, path, command_line=["pytest"]):
            sim.run(seconds=3.0)
        field = sim.simulator.field
    rec = Recording(path)
    ((_, _, scene),) = list(rec.messages(topics={"scene/field"}))
    entity = scene.entities[0]
    boxes = [o for o in field.obstacles if o.shape == "box"]
    pillars = [o for o in field.obstacles if o.shape == "cylinder"]
    tall = {round(c.size.z, 6) for c in entity.cubes}
    assert {round(o.height, 6) for o in boxes} <= tall  # each box, at its height
    assert len([c for c in entity.cylinders if c.size.z > 0.1]) == len(pillars)
    games = list(rec.messages(topics={"scene/game"}))
    states = {m.step: m for _, _, m in rec.messages(topics={"model_states"})}
    _, t, last = games[-1]
    state = states[t // 5_000_000]
    pose = np.asarray(state.pose).reshape(-1, 7)
    names = list(state.name)
    for drone in ("cyan/10", "cyan/11", "cyan/12"):
        e = next(e for e in last.entities if e.id == drone)
        p = e.cylinders[0].pose.position
        k = names.index(drone)
        assert pose[k, 2] > 2.0  # they took off
        assert p.z == pytest.approx(pose[k, 2], abs=1e-3)  # drawn at their height
        assert e.texts[0].text == drone.split("/")[1]


@pytest.mark.slow
def test_replay_verify_on_the_aerial_encirclement(tmp_path):
    path = tmp_path / "ae.mcap"
    run = subprocess.run(
        SIMATCH + ["run", "aerial_encirclement", "--seed", "2", "--record", str(path), "--quiet", "--json"],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert run.returncode == 0, run.stderr
    proc = subprocess.run(SIMATCH + ["replay", str(path), "--verify"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "reproduced bit for bit" in proc.stdout + proc.stderr


def test_model_and_link_states_of_a_drone(drones):
    sim = drones(params="start_altitude = 1.5")
    tilt = 0.2
    q = (math.cos(tilt / 2), math.sin(tilt / 2), 0.0, 0.0)  # rolled by 0.2 rad
    sim.set_model_state("cyan/1", x=1.0, y=2.0, z=3.0, qw=q[0], qx=q[1], qy=q[2], qz=q[3], wz=0.5)
    s = sim.model_states()["cyan/1"]
    assert (s.x, s.y, s.z) == (1.0, 2.0, 3.0) and (s.qw, s.qx) == pytest.approx(q[:2]) and s.wz == pytest.approx(0.5)
    links = sim.link_states()
    pose, twist = links["cyan/1/base"]
    assert tuple(pose[:3]) == (1.0, 2.0, 3.0)
    arm = 0.0397
    for k in range(1, 5):
        p, v = links[f"cyan/1/rotor_{k}"]
        assert math.dist(p[:3], pose[:3]) == pytest.approx(arm)
        assert math.hypot(v[0], v[1]) == pytest.approx(0.5 * arm * abs(math.cos(tilt)) ** 0 * 1.0, rel=0.05)
    sim.run(3.0)  # it rights itself and holds where it was put
    s = sim.model_states()["cyan/1"]
    assert math.dist((s.x, s.y, s.z), (1.0, 2.0, 3.0)) < 0.1 and abs(s.qx) < 0.01
    with pytest.raises(simatch.sim.simulator.CommandError, match="a rotor follows its robot's base"):
        sim.set_link_state("cyan/1/rotor_2", z=1.0)
    sim.set_link_state("cyan/1/base", z=2.0)
    assert sim.model_states()["cyan/1"].z == 2.0


def test_a_push_moves_a_drone_and_it_comes_back_to_its_point(drones):
    sim = drones(params="start_altitude = 1.5")
    sim.apply_wrench("cyan/1", force=(0.2, 0.0, 0.0), duration=0.3)
    sim.run(0.5)
    pushed = sim.model_states()["cyan/1"].x
    assert pushed > 0.1
    sim.run(5.0)
    s = sim.model_states()["cyan/1"]
    assert abs(s.x) < 0.02 and abs(s.z - 1.5) < 0.02


def test_a_frozen_drone_stays_where_it_flies(drones):
    sim = drones(params="start_altitude = 2.0")
    sim.send_vel("cyan/1", 1.0, 0.0, 0.0)
    sim.run(1.0)
    s0 = sim.model_states()["cyan/1"]
    sim.simulator.set_frozen("cyan/1", True)
    sim.run(2.0)
    s1 = sim.model_states()["cyan/1"]
    assert math.dist((s0.x, s0.y, s0.z), (s1.x, s1.y, s1.z)) < 0.02


def test_a_landed_drone_takes_off_when_told_to_climb(drones):
    sim = drones(params="start_altitude = 0.0")
    sim.send_vel("cyan/1", 0.0, 0.0, 0.0, 0.0)
    sim.run(1.0)
    assert sim.model_states()["cyan/1"].z < 0.02  # motors off on the floor
    sim.send_vel("cyan/1", 0.0, 0.0, 0.0, 1.0)
    sim.run(2.0)
    assert sim.model_states()["cyan/1"].z > 1.0


@pytest.mark.parametrize("vz, why", [(math.nan, "non-finite"), (1e6, "absurd velocity command"), ("up", "non-numeric")])
def test_a_bad_climb_command_is_refused(drones, vz, why):
    sim = drones(params="start_altitude = 1.0")
    sim.send_vel("cyan/1", 0.0, 0.0, 0.0, vz)
    sim.run(0.2)
    bad = [e for e in sim.events if e["type"] == "bad_command"]
    assert bad and why in bad[0]["detail"]
    assert abs(sim.model_states()["cyan/1"].z - 1.0) < 0.01  # it kept hovering


def test_rotor_requests_are_checked(drones, field_sim):
    sim = drones()
    with pytest.raises(simatch.sim.simulator.CommandError, match="rotor 5 is not one of 1, 2, 3, 4"):
        sim.set_rotor("cyan/1", 5)
    ground = field_sim()
    with pytest.raises(simatch.sim.simulator.CommandError, match="cyan/1 is a ground robot"):
        ground.set_rotor("cyan/1", 1)
