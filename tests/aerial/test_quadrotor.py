"""The quadrotor against physics: hover hold, step responses, the climb that thrust-to-weight allows, a cut
rotor, collisions with walls, floor, obstacles and other drones, and the drift of a passive body. Real
MuJoCo through the Python API; numbers measured, not assumed (docs/aerial.md gives the same figures)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import simatch
from simatch.config.loader import SceneError
from simatch.robots.quadrotor import STANDARD_GRAVITY, Quadrotor

from .conftest import track

DRONE = "cyan/1"
HALF = Quadrotor().collision_half_sizes()  # (0.051, 0.051, 0.015) m


def reach(state, axis: int) -> float:
    """How far the frame's collision box reaches from its centre along world axis ``axis`` (turned as it is)."""
    R = np.empty(9)
    import mujoco

    mujoco.mju_quat2Mat(R, np.array((state.qw, state.qx, state.qy, state.qz)))
    return float(np.abs(R.reshape(3, 3)[axis]) @ np.array(HALF))


def no_teleport(states, dt: float, top_speed: float = 8.0) -> None:
    """Between two physics steps a drone moves at most as far as its top speed allows."""
    p = np.array([(s.x, s.y, s.z) for s in states])
    jumps = np.linalg.norm(np.diff(p, axis=0), axis=1)
    assert jumps.max() <= top_speed * dt, f"moved {jumps.max():.4f} m in one step"


@pytest.mark.slow
def test_the_flight_test_measures_hover_steps_climb_and_a_cut_rotor():
    with simatch.Simulation("quadrotor_flight") as sim:
        sim.run()
        r = sim.result()["result"]
    assert r["done"]
    hover = r["hover"]
    assert hover["seconds"] >= 57.9  # a minute of hover, measured from 2 s after reaching the height
    assert hover["height_error_max_m"] <= 0.05
    assert hover["drift_max_m"] <= 0.01
    for axis in "xyz":
        step = r["steps"][axis]
        assert abs(step["final_m_s"] - 1.0) <= 0.02, step
        assert 0.1 <= step["rise_time_s"] <= 0.6, step
        assert step["overshoot_pct"] <= (15.0 if axis != "z" else 5.0), step
        assert step["settling_time_s"] <= 2.0, step
    assert r["steps"]["x"]["tilt_max_deg"] > 10.0  # a horizontal step is flown by tilting
    climb = r["full_climb"]
    assert climb["climb_rate_m_s"] == pytest.approx(climb["expected_m_s"], rel=0.02)
    cut = r["cut_rotor"]
    assert cut["fall_time_s"] is not None and cut["fall_time_s"] < 1.5
    assert cut["lowest_m"] >= 0.0  # on the floor, not through it


@pytest.mark.slow
@pytest.mark.parametrize("ratio", [1.5, 3.0])
def test_thrust_to_weight_caps_the_climb(ratio):
    over = {
        "teams.cyan.model_params.thrust_to_weight": ratio,
        "judge.hover": 1.0,
        "judge.step_time": 1.0,
        "judge.fall_time": 1.0,
    }
    with simatch.Simulation("quadrotor_flight", overrides=over) as sim:
        sim.run()
        climb = sim.result()["result"]["full_climb"]
    m, drag = 0.027, 0.060
    expected = (ratio * m * STANDARD_GRAVITY - m * 9.8) / drag
    assert climb["expected_m_s"] == pytest.approx(expected, abs=1e-4)
    # commanded 20 m/s; the rotors at their limit hold a climb where drag takes the excess thrust
    assert climb["climb_rate_m_s"] == pytest.approx(expected, rel=0.03)
    assert climb["climb_rate_m_s"] < 0.5 * climb["command_m_s"]


def test_hover_holds_height_under_a_constant_push(drones):
    """A steady downward push of a tenth of the weight (say, a payload): the velocity loop's integral takes
    it up, and the height stays within 5 cm for 60 s."""
    sim = drones(params="start_altitude = 1.5")
    sim.send_vel(DRONE, 0.0, 0.0, 0.0, 0.0)
    push = (0.0, 0.0, -0.1 * 0.027 * 9.8)
    # renewed every 5 s (the simulator refuses a single push that could add more than 50 m/s to a body)
    sim.apply_wrench(DRONE, force=push, duration=5.0)
    sim.run(5.0)  # the integral builds up
    states = []
    for _ in range(12):
        sim.apply_wrench(DRONE, force=push, duration=5.0)
        states += track(sim, DRONE, 5.0)
    z = np.array([s.z for s in states])
    assert np.abs(z - 1.5).max() <= 0.05
    no_teleport(states, sim.dt)


def test_a_cut_rotor_makes_it_fall_to_the_floor(drones):
    sim = drones(params="start_altitude = 2.0")
    sim.send_vel(DRONE, 0.0, 0.0, 0.0, 0.0)
    sim.run(1.0)
    sim.simulator.set_rotor(DRONE, 3, False)
    states = track(sim, DRONE, 3.0)
    z = np.array([s.z for s in states])
    low = np.array([s.z - reach(s, 2) for s in states])
    assert z[-1] < 0.2  # down on the floor
    assert low.min() >= -0.02  # never through it (soft contact: 1.3 cm at a 4.5 m/s impact)
    assert np.argmax(z < 1.0) * sim.dt < 1.2  # fell a metre within 1.2 s
    no_teleport(states, sim.dt)
    assert any(e["type"] == "rotor_cut" for e in sim.events)


def test_a_restored_rotor_flies_again(drones):
    sim = drones(params="start_altitude = 3.0")
    sim.simulator.set_rotor(DRONE, 2, False)
    sim.run(0.3)
    sim.simulator.set_rotor(DRONE, 2, True)
    sim.send_vel(DRONE, 0.0, 0.0, 0.0, 0.0)
    sim.run(6.0)
    s = sim.model_states()[DRONE]
    assert s.z > 1.0 and abs(s.vz) < 0.02 and abs(s.qx) + abs(s.qy) < 0.01  # it caught itself, hovers level


def test_a_drone_flown_into_a_wall_stops_at_it_and_comes_off(drones):
    sim = drones(start=((7.0, 0.0, 0.0),))
    sim.send_vel(DRONE, 2.5, 0.0, 0.0)
    states = track(sim, DRONE, 3.0)
    x = np.array([s.x for s in states])
    vx = np.array([s.vx for s in states])
    front = np.array([s.x + reach(s, 0) for s in states])
    wall = 10.0  # the arena's inner face
    assert front.max() <= wall + 0.01  # touches it, does not pass it (a centimetre of soft contact at most)
    hit = int(np.argmax(front >= wall - 0.005))
    assert hit > 0 and vx[hit - 5] > 1.5  # it arrived fast
    assert vx[hit:].min() < 0.0  # and was thrown back (it bounces)
    assert x.max() < wall
    no_teleport(states, sim.dt)


def test_a_drone_flown_into_the_floor_lands_on_it(drones):
    sim = drones(params="start_altitude = 1.0")
    sim.send_vel(DRONE, 0.0, 0.0, 0.0, -1.5)
    states = track(sim, DRONE, 3.0)
    z = np.array([s.z - reach(s, 2) for s in states])  # the frame's lowest point
    assert z.min() >= -0.01  # stands on its frame, a few millimetres of contact at most
    assert z[-1] == pytest.approx(0.0, abs=0.005)
    no_teleport(states, sim.dt)


def test_a_drone_flown_into_an_obstacle_stops_at_its_face(drones):
    box = '{ shape = "box", x = 3.0, y = 0.0, size = [1.0, 1.0], height = 2.5 }'
    sim = drones(obstacles=box)
    sim.send_vel(DRONE, 2.0, 0.0, 0.0)
    states = track(sim, DRONE, 3.0)
    front = np.array([s.x + reach(s, 0) for s in states])
    assert front.max() <= 2.5 + 0.01
    assert front.max() >= 2.5 - 0.01  # it got there
    no_teleport(states, sim.dt)
    # over a low obstacle it flies on
    sim2 = drones(obstacles='{ shape = "cylinder", x = 3.0, y = 0.0, radius = 0.5, height = 0.5 }')
    sim2.send_vel(DRONE, 2.0, 0.0, 0.0)
    sim2.run(3.0)
    assert sim2.model_states()[DRONE].x > 4.0


def test_two_drones_that_fly_into_each_other_bounce_apart(drones):
    sim = drones(start=((-1.5, 0.0, 0.0), (1.5, 0.0, math.pi)), params="start_altitude = 1.0")
    a, b = "cyan/1", "cyan/2"
    sim.send_vel(a, 2.0, 0.0, 0.0)
    sim.send_vel(b, 2.0, 0.0, 0.0)  # facing the other way: towards a
    frames = {int(g) for g in sim.simulator.ix.aerial.geom}
    gaps, closing, met = [], [], None
    for k in range(round(2.0 / sim.dt)):
        sim.step()
        st = sim.model_states()
        gaps.append(math.dist((st[a].x, st[a].y, st[a].z), (st[b].x, st[b].y, st[b].z)))
        closing.append(st[a].vx - st[b].vx)
        d = sim.simulator.d
        if met is None and any({int(g) for g in pair} == frames for pair in d.contact.geom[: d.ncon]):
            met = k
            sim.send_vel(a, 0.0, 0.0, 0.0)  # after the hit nobody pushes on
            sim.send_vel(b, 0.0, 0.0, 0.0)
    assert met is not None  # the frames touched (a contact between the two)
    gaps, closing = np.array(gaps), np.array(closing)
    assert closing[met - 1] > 3.0  # they met at speed
    assert gaps.min() >= 2 * HALF[0] - 0.02  # frames touch, never pass into each other
    assert closing[met + 10 :].min() < 0.0  # and bounced apart
    assert gaps[-1] > gaps[met] + 0.05


def test_a_passive_body_keeps_its_energy(drones):
    """No gravity, no drag, motors off: a tumbling drone's kinetic energy drifts by under 1.5 % in 10 s
    (explicit integration of the gyroscopic terms) and it moves in a straight line at constant speed."""
    sim = drones(gravity=0.0, params="start_altitude = 0.0, drag_xy = 0.0, drag_z = 0.0", walls=False, size=60.0)
    sim.release_control(DRONE)  # nobody commands it: the motors stay off
    sim.set_model_state(DRONE, z=5.0, vx=0.5, vy=0.2, vz=0.1, wx=3.0, wy=-2.0, wz=5.0)
    model = sim.simulator.robot_models[0]
    inertia = np.array(model.inertia())
    va = int(sim.simulator.ix.aerial.qvel[0])

    def energy() -> float:
        v = sim.simulator.d.qvel[va : va + 6]
        return 0.5 * model.mass * float(v[:3] @ v[:3]) + 0.5 * float(inertia @ (v[3:] ** 2))

    e0 = energy()
    sim.run(10.0)
    s = sim.model_states()[DRONE]
    assert abs(energy() - e0) / e0 < 0.015
    assert (s.x, s.y, s.z) == pytest.approx((5.0, 2.0, 6.0), abs=1e-9)


def test_hover_does_not_wander(drones):
    """Told to stand still, a drone holds its point: the drift bound of docs/aerial.md."""
    sim = drones(params="start_altitude = 1.2")
    sim.send_vel(DRONE, 0.0, 0.0, 0.0, 0.0)
    sim.run(120.0)
    s = sim.model_states()[DRONE]
    assert math.hypot(s.x, s.y) < 1e-6 and abs(s.z - 1.2) < 1e-6


def test_a_quadrotor_written_outside_simatch_flies():
    """A plug-in airframe (a "+" layout, its own parameters) takes off and holds its height as the shipped one."""
    overrides = {"teams.cyan.model": "tests.aerial.plugin_drone:PlusQuad", "judge.hover": 30.0}
    with simatch.Simulation("quadrotor_flight", overrides=overrides) as sim:
        sim.run(seconds=4.0)  # took off (to 1.5 m, overshooting as the shipped airframe does), hovering
        held = sim.model_states()[DRONE].z
        sim.run(seconds=4.0)
        s = sim.model_states()[DRONE]
        assert sim.simulator.m.body(DRONE).mass[0] == pytest.approx(0.05)
        assert 1.5 < held < 1.8 and s.z == pytest.approx(held, abs=0.005) and math.hypot(s.vx, s.vy) < 1e-3


@pytest.mark.parametrize(
    "model, error",
    [
        ("tests.aerial.plugin_drone:Hexarotor", r"teams.cyan.model: .*6 rotor angle\(s\).*exactly 4 rotors"),
        ("tests.aerial.plugin_drone:Hovercraft", r"teams.cyan.model: .*locomotion 'floating' is neither"),
    ],
)
def test_aerial_models_the_simulator_cannot_fly_are_refused(model, error):
    with pytest.raises(SceneError, match=error):
        simatch.Simulation("quadrotor_flight", overrides={"teams.cyan.model": model})
