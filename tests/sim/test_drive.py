"""Omnidirectional locomotion (paper Eq. 2-3, Table II): wheel matrix, speed and acceleration limits in the
robot frame, direction kept, bounded force, and a second robot model."""

from __future__ import annotations

import math

import numpy as np
import pytest

from simatch.robots.drive import OmniDrive
from simatch.robots.omni3 import Omni3
from simatch.robots.omni4 import Omni4
from tests.conftest import park_everyone_but


def test_wheel_matrix_is_the_papers():
    m = Omni4()
    A = m.wheel_matrix()
    r, d = 0.0625, 0.203
    for i, a in enumerate((math.pi / 4, 3 * math.pi / 4, -3 * math.pi / 4, -math.pi / 4)):
        beta = math.pi / 2
        expect = np.array([-math.cos(a + beta) / math.sin(beta), -math.sin(a + beta) / math.sin(beta), -d]) / r
        assert np.allclose(A[i], expect)
    # pure rotation turns every wheel the same way, pure translation forward splits them in pairs
    assert np.allclose(A @ [0, 0, 1.0], -d / r)
    w = A @ [1.0, 0, 0]
    assert np.isclose(w[0], w[1]) and np.isclose(w[2], w[3]) and np.isclose(w[0], -w[2])


def ramp_step(U: np.ndarray, U_target: np.ndarray, up: float, down: float) -> np.ndarray:
    """The drive's per-step rule (`simatch.robots.drive`): rim speeds after one physics step, every wheel moved
    towards its target by the same fraction of its change, the largest such that no wheel changes by more than
    ``up`` when it speeds up and ``down`` when it slows down."""
    dU = U_target - U
    adU = np.abs(dU)
    if adU.max() == 0.0:
        return U_target.copy()
    bound = np.where(U * dU >= 0.0, up, down)
    frac = min(1.0, float(np.min(bound / np.maximum(adU, 1e-300))))
    return U + frac * dU


def _drive(model, dt=0.005):
    p = model.params
    return OmniDrive([model.rim_matrix()], p.max_wheel_speed, p.max_acceleration, p.max_deceleration, dt)


def _run_setpoints(drive, V0, command, steps, window=5):
    """Set points of one robot, integrated the way the engine does (rate, clamped at the target)."""
    V = np.array([V0], dtype=float)
    drive.command(0, *command)
    due = np.ones(1, dtype=bool)
    bounds, rate, bias = np.zeros((1, 3, 2)), np.zeros((1, 3)), np.zeros((1, 3))
    out = []
    for k in range(steps):
        if k % window == 0:
            drive.plan(due, V, window, bounds, rate, bias, np.ones((1, 3)))
        V = np.clip(V + rate * drive.dt, bounds[:, :, 0], bounds[:, :, 1])
        out.append(V[0].copy())
    return np.array(out)


@pytest.mark.parametrize("model", [Omni4(), Omni3()])
@pytest.mark.parametrize("command", [(3.0, 0.0, 0.0), (0.0, -2.0, 4.0), (5.0, 5.0, 10.0), (-7.0, 2.0, -3.0)])
def test_limits_bound_every_wheel_and_keep_the_direction(model, command):
    drive = _drive(model)
    p = model.params
    M = model.rim_matrix()
    V = _run_setpoints(drive, (0.0, 0.0, 0.0), command, 600)
    U = V @ M.T
    assert np.abs(U).max() <= p.max_wheel_speed + 1e-9
    dU = np.diff(np.vstack([np.zeros(M.shape[0]), U]), axis=0)
    # from rest every wheel speeds up: change per step at most a_up dt
    assert np.abs(dU).max() <= p.max_acceleration * drive.dt + 1e-9
    # direction of motion kept: every set point is a positive multiple of the (speed-limited) target
    final = V[-1]
    target_dir = final / np.linalg.norm(final)
    for v in V[::25]:
        if np.linalg.norm(v) > 1e-6:
            assert np.allclose(v / np.linalg.norm(v), target_dir, atol=1e-9)
    # an over-fast command is scaled as a whole: same direction as the command
    cmd = np.array(command)
    assert np.allclose(final / np.linalg.norm(final), cmd / np.linalg.norm(cmd), atol=1e-9)


def test_from_rest_the_plan_equals_the_per_step_rule():
    model = Omni4()
    drive = _drive(model)
    p = model.params
    M = model.rim_matrix()
    V = _run_setpoints(drive, (0.0, 0.0, 0.0), (2.0, 0.0, 2.0), 300)
    U_ref = np.zeros(4)
    target = M @ [2.0, 0.0, 2.0]
    for k in range(300):
        U_ref = ramp_step(U_ref, target, p.max_acceleration * drive.dt, p.max_deceleration * drive.dt)
        assert np.allclose(M @ V[k], U_ref, atol=1e-9)


def test_braking_uses_the_deceleration_limit_and_reversal_never_exceeds_a_bound():
    model = Omni4()
    p = model.params
    drive = _drive(model)
    M = model.rim_matrix()
    start = np.linalg.pinv(M) @ (M @ [3.0, 0.0, 0.0])
    V = _run_setpoints(drive, start, (0.0, 0.0, 0.0), 200)
    U = np.vstack([M @ start, V @ M.T])
    dU = np.abs(np.diff(U, axis=0))
    # braking to rest is twice as quick as speeding up
    assert dU.max() == pytest.approx(p.max_deceleration * drive.dt, rel=1e-9)
    stop = np.argmax(np.abs(V).sum(axis=1) < 1e-12)
    assert stop * drive.dt == pytest.approx(np.abs(M @ [3.0, 0, 0]).max() / p.max_deceleration, abs=0.011)
    # a reversal: while slowing, at most a_down dt per step; while speeding up again, at most a_up dt
    V = _run_setpoints(drive, start, (-3.0, 0.0, 0.0), 400)
    U = np.vstack([M @ start, V @ M.T])
    for k in range(1, len(U)):
        for w in range(4):
            change = abs(U[k, w] - U[k - 1, w])
            speeding = abs(U[k, w]) > abs(U[k - 1, w]) or U[k - 1, w] == 0.0
            assert change <= (p.max_acceleration if speeding else p.max_deceleration) * drive.dt + 1e-9


def test_robot_follows_its_command_in_the_physics(field_sim):
    sim = field_sim()
    park_everyone_but(sim, ["cyan/2"])
    sim.set_model_state("cyan/2", x=-4.0, y=0.0, yaw=0.5)
    sim.take_control("cyan/2")
    sim.send_vel("cyan/2", 2.0, 0.0, 0.0)
    sim.run(seconds=1.5)
    st = sim.model_states()["cyan/2"]
    # moving along its heading at the commanded speed, in the robot frame
    assert math.hypot(st.vx, st.vy) == pytest.approx(2.0, abs=1e-6)
    assert math.atan2(st.vy, st.vx) == pytest.approx(0.5, abs=1e-6)
    sim.send_vel("cyan/2", 0.0, 1.0, 0.0)
    sim.run(seconds=1.5)
    st = sim.model_states()["cyan/2"]
    assert math.atan2(st.vy, st.vx) == pytest.approx(0.5 + math.pi / 2, abs=1e-6)
    assert math.hypot(st.vx, st.vy) == pytest.approx(1.0, abs=1e-6)


def test_three_wheel_robots_drive_too(field_sim):
    sim = field_sim(**{"teams.magenta.model": "omni3"})
    park_everyone_but(sim, ["magenta/2"])
    sim.set_model_state("magenta/2", x=3.0, y=0.0, yaw=0.0)
    sim.take_control("magenta/2")
    sim.send_vel("magenta/2", 1.0, 0.5, 1.0)
    sim.run(seconds=2.0)
    st = sim.model_states()["magenta/2"]
    assert st.wz == pytest.approx(1.0, abs=1e-6)
    assert math.hypot(st.vx, st.vy) == pytest.approx(math.hypot(1.0, 0.5), rel=1e-5)
    links = sim.link_states()
    assert {f"magenta/2/wheel_{k}" for k in (1, 2, 3)} <= set(links)
    assert "magenta/2/wheel_4" not in links and "cyan/2/wheel_4" in links


def test_pushing_is_force_bounded_and_robots_never_pass_through_each_other(field_sim):
    sim = field_sim()
    park_everyone_but(sim, ["cyan/2", "magenta/2"])
    sim.set_model_state("cyan/2", x=-1.0, y=0.0, yaw=0.0)
    sim.set_model_state("magenta/2", x=1.0, y=0.0, yaw=math.pi)
    for r in ("cyan/2", "magenta/2"):
        sim.take_control(r)
    # equal robots pushing head-on: a stalemate
    sim.send_vel("cyan/2", 3.0, 0.0, 0.0)
    sim.send_vel("magenta/2", 3.0, 0.0, 0.0)
    closest = 10.0
    for _ in range(400):
        sim.step()
        s = sim.model_states()
        closest = min(closest, math.hypot(s["cyan/2"].x - s["magenta/2"].x, s["cyan/2"].y - s["magenta/2"].y))
    s = sim.model_states()
    assert abs(s["cyan/2"].x + s["magenta/2"].x) < 0.05  # stalemate around the centre
    assert closest > 0.48  # footprints 0.5 m: never through
    # one pushes, the other only holds still: the pusher wins, slowly (force limited)
    sim.send_vel("magenta/2", 0.0, 0.0, 0.0)
    x0 = sim.model_states()["magenta/2"].x
    sim.run(seconds=1.0)
    moved = sim.model_states()["magenta/2"].x - x0
    assert 0.0 < moved < 3.0


def test_robots_do_not_pass_through_goal_posts(field_sim):
    sim = field_sim()
    park_everyone_but(sim, ["cyan/3"])
    post_y = 1.2 + 0.0625
    sim.set_model_state("cyan/3", x=10.0, y=post_y, yaw=0.0)
    sim.take_control("cyan/3")
    sim.send_vel("cyan/3", 3.0, 0.0, 0.0)
    sim.run(seconds=2.0)
    st = sim.model_states()["cyan/3"]
    assert st.x < 11.0 - 0.25 + 0.02  # stopped by the post (front face at the goal line)
